//! Recordings as rigs and loggers write them (docs/src/recordings.md):
//! a logger's preamble before the header is found, recorded and its
//! stated sample rate used or cross-checked; `--header-line` names the
//! header; `--rate-hz` is optional wherever `time_s` gives the times.

use crate::common;
use common::*;
use serde_json::Value;

/// A 60 s, 100 Hz gyro record without `time_s`, and the same record
/// after an MPU-6050 logger's preamble.
fn logger_pair(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let sim = dir.join("sim.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--arw-deg-rth",
        "0.1",
        "--duration-s",
        "60",
        "--rate-hz",
        "100",
        "--seed",
        "7",
        "-o",
        p(&sim),
    ]));
    let text = std::fs::read_to_string(&sim).unwrap();
    let mut plain = String::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        plain.push_str(line.split_once(',').unwrap().1);
        plain.push('\n');
    }
    let bare = dir.join("bare.csv");
    std::fs::write(&bare, &plain).unwrap();
    let log = dir.join("log.csv");
    std::fs::write(
        &log,
        format!("Device,MPU6050\nFs,100\nLogging Type,0\n{plain}"),
    )
    .unwrap();
    (bare, log)
}

#[test]
fn a_logger_preamble_is_read_past_recorded_and_its_rate_used() {
    let dir = workdir("rig_logs_preamble");
    let (bare, log) = logger_pair(&dir);
    let want = json_of(&run(&[
        "noise",
        "--input",
        p(&bare),
        "--rate-hz",
        "100",
        "--json",
    ]));
    let got = json_of(&run(&["noise", "--input", p(&log), "--json"]));
    assert_eq!(coefficient_values(&got), coefficient_values(&want));
    assert_eq!(got["options"]["rate_hz"], 100.0);
    let pre = got["preamble"].as_array().unwrap();
    let lines: Vec<(u64, &str, &str)> = pre
        .iter()
        .map(|l| {
            (
                l["line"].as_u64().unwrap(),
                l["key"].as_str().unwrap(),
                l["value"].as_str().unwrap(),
            )
        })
        .collect();
    assert_eq!(
        lines,
        [
            (1, "Device", "MPU6050"),
            (2, "Fs", "100"),
            (3, "Logging Type", "0")
        ]
    );
    // Given anyway, the rate is cross-checked with the preamble's.
    let same = json_of(&run(&[
        "noise",
        "--input",
        p(&log),
        "--rate-hz",
        "100.5",
        "--json",
    ]));
    assert_eq!(same["options"]["rate_hz"], 100.5);
    refused(
        &run(&["noise", "--input", p(&log), "--rate-hz", "200"]),
        &[
            "log.csv:2:",
            "preamble states a sample rate of 100 Hz",
            "rate_hz is 200 Hz",
        ],
    );
    // The header line named; a wrong one is what the file has there.
    let named = json_of(&run(&[
        "noise",
        "--input",
        p(&log),
        "--header-line",
        "4",
        "--json",
    ]));
    assert_eq!(coefficient_values(&named), coefficient_values(&want));
    refused(
        &run(&["noise", "--input", p(&log), "--header-line", "9"]),
        &["log.csv:9: --header-line 9: this line holds '"],
    );
    refused(
        &run(&["noise", "--input", p(&log), "--header-line", "7000"]),
        &[
            "log.csv",
            "--header-line 7000: no record starts on line 7000",
        ],
    );
    refused(
        &run(&["noise", "--input", p(&log), "--header-line", "0"]),
        &["--header-line"],
    );
}

/// The document without what names the run (inputs' paths, the software
/// block's time): coefficients, options, warnings and tables.
fn numbers(doc: &Value) -> Value {
    serde_json::json!({
        "coefficients": doc["coefficients"],
        "options": doc["options"],
        "warnings": doc["warnings"],
        "tables": doc["tables"],
    })
}

#[test]
fn the_stamps_give_the_rate_wherever_time_s_is_there() {
    let dir = workdir("rig_logs_rate");
    let sim = |args: &[&str], name: &str| {
        let f = dir.join(name);
        let mut a = args.to_vec();
        a.extend(["--seed", "5", "-o", p(&f)]);
        ok(&run(&a));
        f
    };
    let random = [
        "--orientations",
        "14",
        "--init-static-s",
        "3",
        "--static-s",
        "2",
        "--move-s",
        "1.5",
    ];
    let cases: Vec<(Vec<&str>, std::path::PathBuf, &str)> = vec![
        (
            vec!["imu", "ferraris"],
            sim(
                &["simulate", "imu", "--sequence", "ferraris"],
                "ferraris.csv",
            ),
            "100",
        ),
        (
            vec!["imu", "multipos"],
            sim(
                &["simulate", "imu", "--sequence", "positions"],
                "positions.csv",
            ),
            "100",
        ),
        (
            vec!["imu", "autocal", "--init-static-s", "3"],
            sim(
                &[&["simulate", "imu", "--sequence", "random"][..], &random].concat(),
                "random.csv",
            ),
            "100",
        ),
        (
            vec!["thermal", "ramp", "--quantity", "gyro"],
            sim(
                &[
                    "simulate",
                    "thermal",
                    "--rate-hz",
                    "1",
                    "--hold-s",
                    "600",
                    "--ramp-c-per-min",
                    "2",
                ],
                "ramp.csv",
            ),
            "1",
        ),
    ];
    for (cmd, file, rate) in &cases {
        let with = |extra: &[&str]| {
            let mut a = cmd.clone();
            a.extend(["--input", p(file), "--json"]);
            a.extend_from_slice(extra);
            json_of(&run(&a))
        };
        let given = with(&["--rate-hz", rate]);
        let stamped = with(&[]);
        let r: f64 = rate.parse().unwrap();
        if cmd[0] == "thermal" {
            // Blocks cut by time: the rate is recorded as given, none.
            assert_eq!(stamped["options"]["rate_hz"], Value::Null);
        } else {
            let settled = stamped["options"]["rate_hz"].as_f64().unwrap();
            assert!((settled / r - 1.0).abs() < 1e-9, "{cmd:?}: {settled}");
        }
        // The same reduction, but for the rate recorded (the stamps' to
        // rounding instead of the round number given).
        let mut a = numbers(&given);
        let mut b = numbers(&stamped);
        a["options"]["rate_hz"] = Value::Null;
        b["options"]["rate_hz"] = Value::Null;
        if a != b {
            for (name, c) in a["coefficients"].as_object().unwrap() {
                let d = &b["coefficients"][name];
                let (x, y) = (c["value"].as_f64().unwrap(), d["value"].as_f64().unwrap());
                let u = c["U95"].as_f64().unwrap_or(0.0);
                assert!(
                    (x - y).abs() <= 1e-6 * u.max(x.abs()),
                    "{cmd:?} {name}: {x} vs {y}"
                );
            }
        }
        // Without time_s the rate is still needed, and said so.
        let text = std::fs::read_to_string(file).unwrap();
        let mut bare = String::new();
        for line in text.lines().filter(|l| !l.starts_with('#')) {
            let cells: Vec<&str> = line.split(',').collect();
            let keep: Vec<&str> = cells[1..].to_vec();
            bare.push_str(&keep.join(","));
            bare.push('\n');
        }
        assert!(text
            .lines()
            .find(|l| !l.starts_with('#'))
            .unwrap()
            .starts_with("time_s,"));
        let nostamps = dir.join(format!(
            "bare_{}",
            file.file_name().unwrap().to_str().unwrap()
        ));
        std::fs::write(&nostamps, bare).unwrap();
        let mut a = cmd.clone();
        a.extend(["--input", p(&nostamps)]);
        if cmd[1] == "multipos" {
            // Positions without rotations: nothing is timed, nothing needed.
            a.push("--json");
            let v = json_of(&run(&a));
            assert_eq!(v["coefficients"], given["coefficients"]);
            assert_eq!(v["options"]["rate_hz"], Value::Null);
        } else {
            refused(&run(&a), &["no time_s column and no rate_hz", "--rate-hz"]);
        }
    }
}

#[test]
fn samples_at_a_rail_are_named_with_their_lines() {
    let dir = workdir("rig_logs_clipped");
    // A 16-bit gyro record pinned at -32768 for 16 samples (lines 102-117)
    // and at 32767 for one sample (not a run).
    // gy: an unsigned 16-bit channel near mid-scale, at 32767 twice in a
    // row but with values above it: not a rail.
    let mut text = String::from("time_s,gx,gy\n");
    for k in 0..2000 {
        let v = match k {
            100..=115 => -32768.0,
            500 => 32767.0,
            800..=803 => 30.0,
            _ => (((k * 7919) % 61) as f64) - 30.0,
        };
        let gy = if (300..302).contains(&k) {
            32767
        } else {
            32760 + (k * 13) % 17
        };
        text.push_str(&format!("{},{v},{gy}\n", k as f64 / 100.0));
    }
    let f = dir.join("counts.csv");
    std::fs::write(&f, &text).unwrap();
    let v = json_of(&run(&["noise", "--input", p(&f), "--json"]));
    let clipped = warnings_with(&v, "clipped");
    assert_eq!(clipped.len(), 1, "{}", v["warnings"]);
    assert!(
        clipped[0].contains("gx sits at the rail -32768 in 16 samples (1 run: lines 102-117)"),
        "{}",
        clipped[0]
    );
    // A full scale given: 4 samples at or beyond 29.5 in a row are clipped
    // too; angles of 255 deg (an 8-bit end) are not.
    let v = json_of(&run(&[
        "noise",
        "--input",
        p(&f),
        "--full-scale",
        "29.5",
        "--json",
    ]));
    assert!(warnings_with(&v, "clipped").len() >= 2, "{}", v["warnings"]);
    let t = dir.join("tumble.csv");
    let mut tt = String::from("angle_deg,output\n");
    for a in [0, 45, 90, 135, 180, 225, 255, 270, 315] {
        for k in 0..4 {
            let x = (a as f64).to_radians();
            tt.push_str(&format!("{a},{}\n", 0.1 + x.sin() + 1e-6 * k as f64));
        }
    }
    std::fs::write(&t, tt).unwrap();
    let v = json_of(&run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        p(&t),
        "--json",
    ]));
    assert!(warnings_with(&v, "clipped").is_empty(), "{}", v["warnings"]);
    refused(
        &run(&["noise", "--input", p(&f), "--full-scale", "0"]),
        &["--full-scale: 0 is not a positive full scale"],
    );
}

/// An autocalibration session whose gyro is scaled by `gain` and, when
/// `clip`, held within a 16-bit converter's range.
fn gyro_counts(text: &str, gain: f64, clip: bool) -> String {
    gyro_counts_at(text, 4, gain, clip)
}

/// As [`gyro_counts`], the gyro from column `first` (0-based).
fn gyro_counts_at(text: &str, first: usize, gain: f64, clip: bool) -> String {
    let mut out = String::new();
    for (i, line) in text.lines().filter(|l| !l.starts_with('#')).enumerate() {
        if i == 0 {
            out.push_str(line);
        } else {
            let mut cells: Vec<String> = line.split(',').map(str::to_string).collect();
            for c in &mut cells[first..first + 3] {
                let v = c.parse::<f64>().unwrap() * gain;
                *c = if clip {
                    format!("{}", v.round().clamp(-32768.0, 32767.0))
                } else {
                    format!("{v}")
                };
            }
            out.push_str(&cells.join(","));
        }
        out.push('\n');
    }
    out
}

/// The gyro gain: peaks of about 50 000 counts, clipped at 32 767.
const GAIN: f64 = 24.0;

#[test]
fn clipped_rotations_are_left_out_of_the_autocalibration() {
    let dir = workdir("rig_logs_clipped_autocal");
    let sim = dir.join("session.csv");
    ok(&run(&[
        "simulate",
        "imu",
        "--sequence",
        "random",
        "--orientations",
        "14",
        "--init-static-s",
        "3",
        "--static-s",
        "2",
        "--move-s",
        "1.5",
        "--seed",
        "5",
        "-o",
        p(&sim),
    ]));
    let text = std::fs::read_to_string(&sim).unwrap();
    let (clean, clipped) = (dir.join("clean.csv"), dir.join("clipped.csv"));
    std::fs::write(&clean, gyro_counts(&text, GAIN, false)).unwrap();
    std::fs::write(&clipped, gyro_counts(&text, GAIN, true)).unwrap();
    let reduce = |f: &std::path::Path| {
        json_of(&run(&[
            "imu",
            "autocal",
            "--input",
            p(f),
            "--init-static-s",
            "3",
            "--json",
        ]))
    };
    let (a, b) = (reduce(&clean), reduce(&clipped));
    assert!(warnings_with(&a, "clipped").is_empty(), "{}", a["warnings"]);
    let named = warnings_with(&b, "clipped");
    assert!(
        named.iter().any(|w| w.contains("sits at the rail")),
        "{named:?}"
    );
    let left_out = named
        .iter()
        .find(|w| w.contains("motions between still intervals hold gyro samples"))
        .unwrap_or_else(|| panic!("{named:?}"));
    println!("{left_out}");
    // Integrated, the clipped rotations would fail the fit (the real
    // MPU-6050 session's chi-square p = 0, blamed on motion or the model).
    assert!(
        warnings_with(&b, "lack-of-fit").is_empty(),
        "{}",
        b["warnings"]
    );
    // Fewer rotations, the same gyro calibration within its U95.
    for (name, x, _) in coefficient_values(&a)
        .into_iter()
        .filter(|c| c.0.starts_with("gyr."))
    {
        let c = &b["coefficients"][&name];
        let (y, u) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
        assert!((x - y).abs() <= u, "{name}: {x} vs {y} (U95 {u})");
    }
}

#[test]
fn a_clipped_ferraris_rotation_is_refused_and_a_multipos_one_too_when_none_is_left() {
    let dir = workdir("rig_logs_clipped_ferraris");
    for (sequence, extra, reduce) in [
        ("ferraris", vec![], vec!["imu", "ferraris"]),
        ("positions", vec!["--rotations"], vec!["imu", "multipos"]),
    ] {
        let sim = dir.join(format!("{sequence}.csv"));
        let mut args = vec![
            "simulate",
            "imu",
            "--sequence",
            sequence,
            "--seed",
            "3",
            "-o",
            p(&sim),
        ];
        args.extend(&extra);
        ok(&run(&args));
        let text = std::fs::read_to_string(&sim).unwrap();
        let first = text
            .lines()
            .next()
            .unwrap()
            .split(',')
            .position(|h| h == "gyr_x")
            .unwrap();
        let peak = text
            .lines()
            .skip(1)
            .flat_map(|l| {
                l.split(',')
                    .skip(first)
                    .map(|c| c.parse::<f64>().unwrap().abs())
            })
            .fold(0.0, f64::max);
        let (clean, clipped) = (
            dir.join(format!("{sequence}_clean.csv")),
            dir.join(format!("{sequence}_clipped.csv")),
        );
        // Counts: peaks at 0.75 and at 1.5 times the 16-bit range.
        std::fs::write(
            &clean,
            gyro_counts_at(&text, first, 0.75 * 32767.0 / peak, false),
        )
        .unwrap();
        std::fs::write(
            &clipped,
            gyro_counts_at(&text, first, 1.5 * 32767.0 / peak, true),
        )
        .unwrap();
        let with = |f: &std::path::Path| {
            let mut a = reduce.clone();
            a.extend(["--input", p(f), "--json"]);
            run(&a)
        };
        let doc = json_of(&with(&clean));
        assert!(
            warnings_with(&doc, "clipped").is_empty(),
            "{}",
            doc["warnings"]
        );
        let o = with(&clipped);
        if sequence == "ferraris" {
            refused(
                &o,
                &[
                    "gyro samples at a converter's rail in x_rot (gyr_x at",
                    "y_rot (gyr_y at",
                    "z_rot (gyr_z at",
                    "the Ferraris method has no other rotation about that axis",
                ],
            );
        } else {
            refused(
                &o,
                &[
                    "gyro samples at a converter's rail in every rotation about x (x_rot;",
                    "none about that axis is left",
                ],
            );
        }
    }
}

#[test]
fn a_clipped_dwell_is_left_out_of_the_response() {
    let dir = workdir("rig_logs_clipped_response");
    let sim = dir.join("sine.csv");
    ok(&run(&[
        "simulate",
        "response-sine",
        "--order",
        "second",
        "--zeta",
        "0.2",
        "--seed",
        "4",
        "-o",
        p(&sim),
    ]));
    let text = std::fs::read_to_string(&sim).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let o = header.iter().position(|h| *h == "output").unwrap();
    let peak = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(o).unwrap().parse::<f64>().unwrap().abs())
        .fold(0.0, f64::max);
    // Output counts: the resonance's peak at 0.75 and at 1.3 times the 16-bit range.
    let counts = |gain: f64| {
        let mut out = String::from(text.lines().next().unwrap());
        out.push('\n');
        for l in text.lines().skip(1) {
            let mut c: Vec<String> = l.split(',').map(String::from).collect();
            let v = (c[o].parse::<f64>().unwrap() * gain * 32767.0 / peak).round();
            c[o] = v.clamp(-32768.0, 32767.0).to_string();
            out.push_str(&c.join(","));
            out.push('\n');
        }
        out
    };
    let (clean, clipped) = (dir.join("clean.csv"), dir.join("clipped.csv"));
    std::fs::write(&clean, counts(0.75)).unwrap();
    std::fs::write(&clipped, counts(1.3)).unwrap();
    let reduce = |f: &std::path::Path| {
        json_of(&run(&[
            "response",
            "sine",
            "--input",
            p(f),
            "--order",
            "second",
            "--json",
        ]))
    };
    let (a, b) = (reduce(&clean), reduce(&clipped));
    assert!(warnings_with(&a, "clipped").is_empty(), "{}", a["warnings"]);
    let named = warnings_with(&b, "clipped");
    assert!(
        named.iter().any(|w| w.contains("of 12 dwells hold samples at a converter's rail and are left out")),
        "{named:?}"
    );
    // Without the clipped dwell the model fits (kept in, p = 0).
    assert!(
        warnings_with(&b, "lack-of-fit").is_empty(),
        "{}",
        b["warnings"]
    );
    // The same sensor (its gain aside) within the two results' U95.
    for name in ["fn_hz", "zeta", "delay_s", "bandwidth_hz"] {
        let (x, y) = (&a["coefficients"][name], &b["coefficients"][name]);
        let v = |c: &serde_json::Value, k: &str| c[k].as_f64().unwrap();
        let u = v(x, "U95").hypot(v(y, "U95"));
        let (x, y) = (v(x, "value"), v(y, "value"));
        assert!((x - y).abs() <= u, "{name}: {x} vs {y} (U95 {u})");
    }
}
