//! Recordings as they come (docs/src/recordings.md): quantised time
//! stamps are accepted and give the clean run's numbers within their
//! stated U95, a `--rate-hz` that contradicts the stamps is refused naming
//! both rates, a decreasing stamp is refused at its line, gaps are
//! reported.

use crate::common;
use common::*;

/// A copy of `text` whose `time_s` (first column) is floored to
/// `resolution_s`, as a coarse acquisition clock prints it.
fn quantised(text: &str, resolution_s: f64) -> String {
    let mut out = String::new();
    let mut header = true;
    for line in text.lines() {
        if line.starts_with('#') || std::mem::replace(&mut header, false) {
            out.push_str(line);
        } else {
            let (t, rest) = line.split_once(',').unwrap();
            let t: f64 = t.parse().unwrap();
            let q = (t / resolution_s + 1e-9).floor() * resolution_s;
            out.push_str(&format!("{q:.3},{rest}"));
        }
        out.push('\n');
    }
    out
}

/// A 30 s, 100 Hz gyro noise record with `time_s` (seeded).
fn noise_record(name: &str, seed: &str) -> std::path::PathBuf {
    let f = unique(name);
    ok(&run(&[
        "simulate",
        "noise",
        "--arw-deg-rth",
        "0.1",
        "--duration-s",
        "30",
        "--rate-hz",
        "100",
        "--seed",
        seed,
        "-o",
        p(&f),
    ]));
    f
}

/// A short autocalibration session: 14 random orientations after a 3 s
/// still start (options of `simulate imu --sequence random`).
const RANDOM_SESSION: [&str; 8] = [
    "--orientations",
    "14",
    "--init-static-s",
    "3",
    "--static-s",
    "2",
    "--move-s",
    "1.5",
];

/// `simulate imu --sequence SEQUENCE EXTRA… -o NAME`, the file written.
fn simulate_imu(sequence: &str, extra: &[&str], name: &str) -> std::path::PathBuf {
    let f = unique(name);
    let mut args = vec!["simulate", "imu", "--sequence", sequence];
    args.extend_from_slice(extra);
    args.extend(["-o", p(&f)]);
    ok(&run(&args));
    f
}

fn autocal_session() -> String {
    let f = simulate_imu(
        "random",
        &[&RANDOM_SESSION[..], &["--seed", "11"]].concat(),
        "session.csv",
    );
    std::fs::read_to_string(&f).unwrap()
}

fn autocal(file: &std::path::Path, method: &str) -> serde_json::Value {
    json_of(&run(&[
        "imu",
        "autocal",
        "--input",
        p(file),
        "--rate-hz",
        "100",
        "--init-static-s",
        "3",
        "--method",
        method,
        "--json",
    ]))
}

#[test]
fn quantised_stamps_give_the_clean_result_within_u95() {
    let text = autocal_session();
    let header = text.lines().find(|l| !l.starts_with('#')).unwrap();
    assert!(header.starts_with("time_s,"), "a stamped session: {header}");
    let clean = write("clean.csv", &text);
    let coarse = write("coarse.csv", &quantised(&text, 0.02));
    let a = autocal(&clean, "incal");
    let b = autocal(&coarse, "incal");
    assert!(warnings_with(&a, "time-repeats").is_empty());
    let w = warnings_with(&b, "time-repeats");
    assert!(w.iter().any(|m| m.contains("sample index")), "{w:?}");
    let coefficients = a["coefficients"].as_object().unwrap();
    assert!(coefficients.len() >= 18);
    for (name, c) in coefficients {
        let (x, y) = (
            c["value"].as_f64().unwrap(),
            b["coefficients"][name]["value"].as_f64().unwrap(),
        );
        let u95 = c["U95"].as_f64().unwrap();
        assert!((x - y).abs() <= u95, "{name}: {x} vs {y} (U95 {u95})");
    }
    // imu_tk's steps take the stamps as read (zero steps and all): it runs.
    let t = autocal(&coarse, "tedaldi");
    assert_eq!(t["options"]["method"], "tedaldi");
}

#[test]
fn a_rate_that_contradicts_the_stamps_is_refused_naming_both() {
    let f = simulate_imu(
        "ferraris",
        &["--static-s", "0.5", "--rotation-s", "1"],
        "ferraris.csv",
    );
    refused(
        &run(&["imu", "ferraris", "--input", p(&f), "--rate-hz", "200"]),
        &["ferraris.csv", "--rate-hz 200 Hz", "100.0000 Hz"],
    );
    refused(
        &run(&["imu", "multipos", "--input", p(&f), "--rate-hz", "50"]),
        &["ferraris.csv"],
    );
    let n = noise_record("noise.csv", "2");
    refused(
        &run(&["noise", "--input", p(&n), "--rate-hz", "200", "--quiet"]),
        &["noise.csv", "--rate-hz 200 Hz", "100.0000 Hz"],
    );
    // Within 2 %: accepted.
    ok(&run(&[
        "noise",
        "--input",
        p(&n),
        "--rate-hz",
        "101",
        "--quiet",
    ]));
}

#[test]
fn a_decreasing_stamp_is_refused_at_its_line_and_gaps_are_reported() {
    let text = autocal_session();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header = lines.iter().position(|l| l.starts_with("time_s")).unwrap();
    // Row header+10 gets a stamp before its predecessor's.
    let bad = header + 10;
    let rest = lines[bad].split_once(',').unwrap().1.to_string();
    lines[bad] = format!("0,{rest}");
    let f = write("decreasing.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&["imu", "autocal", "--input", p(&f), "--rate-hz", "100"]),
        &[&format!("decreasing.csv:{}", bad + 1), "must not decrease"],
    );
    // 100 samples lost from a noise record: reported, with what it means.
    let n = noise_record("gappy.csv", "3");
    let text = std::fs::read_to_string(&n).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(1000..1100).contains(i))
        .map(|(_, l)| l)
        .collect();
    let g = write("gappy2.csv", &(kept.join("\n") + "\n"));
    let v = json_of(&run(&[
        "noise",
        "--input",
        p(&g),
        "--rate-hz",
        "100",
        "--quiet",
        "--json",
    ]));
    let m = warnings_with(&v, "time-gaps")[0];
    assert!(
        m.starts_with("1 gap(s)") && m.contains("1.0000 s missing"),
        "{m}"
    );
}

/// `text` in offset counts: every acc_/gyr_ column times `gain` plus 32768
/// (a 16-bit converter's offset), as a raw-count recording gives it.
fn in_counts(text: &str, gain: f64) -> String {
    let mut out = String::new();
    let mut cols: Option<Vec<bool>> = None;
    for line in text.lines() {
        if line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').collect();
        match &cols {
            None => {
                cols = Some(
                    fields
                        .iter()
                        .map(|f| f.starts_with("acc_") || f.starts_with("gyr_"))
                        .collect(),
                );
                out.push_str(line);
            }
            Some(c) => {
                let row: Vec<String> = fields
                    .iter()
                    .zip(c)
                    .map(|(f, &raw)| match (raw, f.parse::<f64>()) {
                        (true, Ok(x)) => format!("{}", x * gain + 32768.0),
                        _ => f.to_string(),
                    })
                    .collect();
                out.push_str(&row.join(","));
            }
        }
        out.push('\n');
    }
    out
}

/// Raw counts need no option and no initial value: Ferraris, multipos and
/// the autocalibration (both methods) give, on a session rewritten in
/// offset counts (× 7 + 32768), the clean run's coefficients carried into
/// counts (biases × 7 + 32768, output-per-input terms × 7, the
/// autocalibration's input-per-output scales ÷ 7, misalignments as they
/// were) and their U95 likewise.
#[test]
fn raw_counts_give_the_same_calibration_in_counts() {
    let gain = 7.0;
    let sim = |sequence: &str, name: &str| {
        let extra: &[&str] = if sequence == "random" {
            &RANDOM_SESSION
        } else {
            &[]
        };
        let f = simulate_imu(sequence, &[extra, &["--seed", "5"]].concat(), name);
        let counts = write(
            &format!("counts_{name}"),
            &in_counts(&std::fs::read_to_string(&f).unwrap(), gain),
        );
        (f, counts)
    };
    let reduce = |cmd: &str, f: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["imu", cmd, "--input", p(f), "--rate-hz", "100", "--json"];
        args.extend_from_slice(extra);
        json_of(&run(&args))
    };
    let ferraris = sim("ferraris", "ferraris.csv");
    let positions = sim("positions", "positions.csv");
    let random = sim("random", "random.csv");
    let autocal_opts = ["--init-static-s", "3"];
    let cases = [
        ("ferraris", &ferraris, vec![]),
        ("multipos", &positions, vec![]),
        ("autocal", &random, autocal_opts.to_vec()),
        (
            "autocal",
            &random,
            [&autocal_opts[..], &["--method", "tedaldi"]].concat(),
        ),
    ];
    for (cmd, (clean, counts), extra) in cases {
        let a = reduce(cmd, clean, &extra);
        let b = reduce(cmd, counts, &extra);
        let ca = a["coefficients"].as_object().unwrap();
        assert!(ca.len() >= 18, "{cmd}");
        for (name, c) in ca {
            let short = name.split('.').nth(1).unwrap();
            let (factor, offset) = if short.starts_with("b_") || name.starts_with("b_") {
                (gain, 32768.0)
            } else if name.starts_with("R_") || short.starts_with("M_") || short.starts_with("m_") {
                (1.0, 0.0)
            } else if cmd == "autocal" && short.starts_with("s_") {
                (1.0 / gain, 0.0)
            } else {
                (gain, 0.0)
            };
            let want = c["value"].as_f64().unwrap() * factor + offset;
            let want_u95 = c["U95"].as_f64().unwrap() * factor;
            let got = &b["coefficients"][name];
            let (v, u95) = (got["value"].as_f64().unwrap(), got["U95"].as_f64().unwrap());
            assert!(
                (v - want).abs() <= 0.01 * u95 + 1e-9 * want.abs(),
                "{cmd} {name}: {v} in counts, {want} carried from the clean run (U95 {u95})"
            );
            assert!(
                (u95 - want_u95).abs() <= 0.01 * want_u95 + 1e-12,
                "{cmd} {name}: U95 {u95} in counts, {want_u95} carried"
            );
        }
    }
}

/// A simulated session's rows (`time_s` first) to edit.
#[derive(Clone)]
struct Session {
    header: String,
    rows: Vec<Vec<String>>,
}

impl Session {
    fn of(text: &str) -> Session {
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let header = lines.next().unwrap().to_string();
        let rows = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        Session { header, rows }
    }

    fn column(&self, name: &str) -> usize {
        self.header.split(',').position(|h| h == name).unwrap()
    }

    fn label(&self, i: usize) -> &str {
        &self.rows[i][1]
    }

    fn write(&self, name: &str) -> std::path::PathBuf {
        let mut out = self.header.clone() + "\n";
        for r in &self.rows {
            out.push_str(&r.join(","));
            out.push('\n');
        }
        write(name, &out)
    }
}

/// A seeded xorshift stream in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// Injected faults in real-recording sessions: each faulty session gives
/// every coefficient within its stated u of the clean run (or, where the
/// fault took samples away, within 4 standard deviations of a subset's
/// difference from the whole), or is refused naming the problem, or (for
/// a fault the data cannot undo) carries the warning that names it. Never
/// a silent change.
#[test]
fn injected_faults_are_undone_refused_or_named() {
    let sim = |sequence: &str, name: &str| {
        let f = simulate_imu(sequence, &["--static-s", "12", "--seed", "5"], name);
        Session::of(&std::fs::read_to_string(&f).unwrap())
    };
    let reduce = |cmd: &str, f: &std::path::Path| {
        run(&["imu", cmd, "--input", p(f), "--rate-hz", "100", "--json"])
    };
    let within_u = |clean: &serde_json::Value, faulty: &serde_json::Value, what: &str| {
        for (name, c) in clean["coefficients"].as_object().unwrap() {
            let f = &faulty["coefficients"][name];
            let d = (c["value"].as_f64().unwrap() - f["value"].as_f64().unwrap()).abs();
            let (u, uc) = (f["u"].as_f64().unwrap(), c["u"].as_f64().unwrap());
            // Within u, or, where the fault took samples away, within 4
            // standard deviations of a subset's difference from the whole
            // (√(u_f² − u_c²)).
            let allowed = u.max(4.0 * (u * u - uc * uc).abs().sqrt());
            assert!(
                d <= allowed,
                "{what}: {name} moved {d} (u {u}, clean u {uc})"
            );
        }
    };
    let has = |v: &serde_json::Value, code: &str| !warnings_with(v, code).is_empty();
    let mut rng = 0x9E37_79B9_7F4A_7C15u64;
    // The autocalibration: accelerometer spikes anywhere are undone, gyro
    // spikes in motion are named (not changed), gaps cut intervals and
    // motions (within u here), jitter as given is within u or named.
    {
        let s = Session::of(&autocal_session());
        let cal = |f: &std::path::Path| autocal(f, "incal");
        let clean = cal(&s.write("autocal_clean.csv"));
        let acc = s.column("acc_x");
        for (what, first) in [("acc", acc), ("gyr", s.column("gyr_x"))] {
            let mut f = s.clone();
            for r in &mut f.rows[400..] {
                if uniform(&mut rng) < 0.01 {
                    let k = first + (uniform(&mut rng) * 3.0) as usize;
                    let x: f64 = r[k].parse().unwrap();
                    r[k] = format!("{}", x + 500.0);
                }
            }
            let v = cal(&f.write(&format!("autocal_{what}_spikes.csv")));
            assert!(has(&v, "spikes"), "{what}");
            if what == "acc" {
                within_u(&clean, &v, "autocal acc spikes");
            }
        }
        for gap in [1usize, 10, 100] {
            let mut f = s.clone();
            let at = 400 + (uniform(&mut rng) * (s.rows.len() - 600) as f64) as usize;
            f.rows.drain(at..at + gap);
            let v = cal(&f.write(&format!("autocal_gap{gap}.csv")));
            within_u(&clean, &v, &format!("autocal gap {gap}"));
            assert!(has(&v, "time-gaps"));
        }
        let mut f = s.clone();
        for r in &mut f.rows {
            let t: f64 = r[0].parse().unwrap();
            r[0] = format!("{}", t + 0.002 * (2.0 * uniform(&mut rng) - 1.0));
        }
        let v = cal(&f.write("autocal_jitter.csv"));
        if !has(&v, "lack-of-fit") {
            within_u(&clean, &v, "autocal jitter");
        }
    }
    for (cmd, sequence) in [("ferraris", "ferraris"), ("multipos", "positions")] {
        let s = sim(sequence, &format!("{cmd}.csv"));
        let clean = json_of(&reduce(cmd, &s.write(&format!("{cmd}_clean.csv"))));
        let still = |i: usize| !s.label(i).is_empty() && !s.label(i).ends_with("_rot");
        // 1 % spikes of ±50 σ on every channel of the still rows: left
        // out of the means.
        let mut f = s.clone();
        let first = s.column("acc_x");
        let mut spikes = 0;
        for i in 0..f.rows.len() {
            if still(i) && uniform(&mut rng) < 0.01 {
                let k = first + (uniform(&mut rng) * 6.0) as usize;
                let x: f64 = f.rows[i][k].parse().unwrap();
                let sign = if uniform(&mut rng) < 0.5 { -1.0 } else { 1.0 };
                f.rows[i][k] = format!("{}", x + sign * 500.0);
                spikes += 1;
            }
        }
        assert!(spikes > 20, "{cmd}: {spikes} spikes");
        let v = json_of(&reduce(cmd, &f.write(&format!("{cmd}_spikes.csv"))));
        within_u(&clean, &v, &format!("{cmd} with {spikes} spikes"));
        assert!(has(&v, "spikes"), "{cmd}");
        // Time stamps jittered by up to ±0.2 periods: the rotation
        // integrals take 1/rate, the result is the clean one.
        let mut f = s.clone();
        for r in &mut f.rows {
            let t: f64 = r[0].parse().unwrap();
            r[0] = format!("{}", t + 0.002 * (2.0 * uniform(&mut rng) - 1.0));
        }
        within_u(
            &clean,
            &json_of(&reduce(cmd, &f.write(&format!("{cmd}_jitter.csv")))),
            &format!("{cmd} jitter"),
        );
        // Gaps of 1, 10, 100 and 1000 samples: inside a still section the
        // mean loses those samples (within u); beside or inside a rotation
        // the section is refused naming it.
        for gap in [1usize, 10, 100, 1000] {
            let mut f = s.clone();
            // A still row with `gap` rows after it in the same section.
            let at = (0..s.rows.len() - gap)
                .find(|&i| {
                    i > 10
                        && still(i)
                        && s.label(i + gap) == s.label(i)
                        && s.label(i - 1) == s.label(i)
                })
                .unwrap_or_else(|| panic!("{cmd}: no still stretch of {gap} rows"));
            f.rows.drain(at..at + gap);
            let v = json_of(&reduce(cmd, &f.write(&format!("{cmd}_gap{gap}.csv"))));
            within_u(&clean, &v, &format!("{cmd} gap {gap}"));
            assert!(has(&v, "time-gaps"), "{cmd} gap {gap}");
        }
        if cmd == "ferraris" {
            let mut f = s.clone();
            let at = (0..s.rows.len()).find(|&i| s.label(i) == "y_rot").unwrap() + 50;
            f.rows.drain(at..at + 10);
            refused(
                &reduce(cmd, &f.write("ferraris_rotgap.csv")),
                &["ferraris_rotgap.csv", "rotation section y_rot", "time gap"],
            );
            // A gyro saturated through part of a rotation: named.
            let mut f = s.clone();
            let k = s.column("gyr_z");
            let rot: Vec<usize> = (0..s.rows.len())
                .filter(|&i| s.label(i) == "z_rot")
                .collect();
            let peak = rot
                .iter()
                .map(|&i| s.rows[i][k].parse::<f64>().unwrap().abs())
                .fold(0.0, f64::max);
            for &i in &rot {
                let x: f64 = f.rows[i][k].parse().unwrap();
                f.rows[i][k] = format!("{}", x.clamp(-0.8 * peak, 0.8 * peak));
            }
            let v = json_of(&reduce(cmd, &f.write("ferraris_clipped.csv")));
            assert!(has(&v, "saturated"), "{}", v["warnings"]);
            // A dead channel: refused naming its column.
            let mut f = s.clone();
            let k = s.column("acc_y");
            for r in &mut f.rows {
                r[k] = "2048".into();
            }
            refused(
                &reduce(cmd, &f.write("ferraris_dead.csv")),
                &["ferraris_dead.csv", "column acc_y is 2048 in every row"],
            );
        }
    }
}

/// `--sort-time`: rows out of time order are refused at their line
/// without it; with it they are put in order (the clean result, to the
/// bit) and a `time-sorted` warning counts the rows moved. The same for
/// `noise`.
#[test]
fn sort_time_puts_rows_in_order_and_says_how_many() {
    let text = autocal_session();
    let clean = write("inorder.csv", &text);
    let mut lines: Vec<&str> = text.lines().collect();
    let header = lines.iter().position(|l| l.starts_with("time_s")).unwrap();
    lines.swap(header + 500, header + 501);
    lines.swap(header + 900, header + 903);
    let f = write("swapped.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&[
            "imu",
            "autocal",
            "--input",
            p(&f),
            "--rate-hz",
            "100",
            "--init-static-s",
            "3",
        ]),
        &[
            &format!("swapped.csv:{}", header + 502),
            "must not decrease",
        ],
    );
    let args = |file: &std::path::Path, sort: bool| {
        let mut a = vec![
            "imu",
            "autocal",
            "--input",
            p(file),
            "--rate-hz",
            "100",
            "--init-static-s",
            "3",
            "--json",
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
        if sort {
            a.push("--sort-time".into());
        }
        a
    };
    let go = |a: Vec<String>| json_of(&run(&a.iter().map(String::as_str).collect::<Vec<_>>()));
    let a = go(args(&clean, false));
    let b = go(args(&f, true));
    assert_eq!(a["coefficients"], b["coefficients"]);
    assert_eq!(b["options"]["sort_time"], true);
    let w = warnings_with(&b, "time-sorted");
    assert!(w.iter().any(|m| m.starts_with("4 of ")), "{w:?}");
    let n = std::fs::read_to_string(noise_record("sortnoise.csv", "4")).unwrap();
    let mut lines: Vec<&str> = n.lines().collect();
    lines.swap(10, 11);
    let g = write("sortnoise2.csv", &(lines.join("\n") + "\n"));
    refused(
        &run(&["noise", "--input", p(&g), "--rate-hz", "100", "--quiet"]),
        &["sortnoise2.csv:", "must not decrease"],
    );
    let v = json_of(&run(&[
        "noise",
        "--input",
        p(&g),
        "--rate-hz",
        "100",
        "--quiet",
        "--sort-time",
        "--json",
    ]));
    assert!(!warnings_with(&v, "time-sorted").is_empty());
}

/// An accelerometer record at rest in m/s² analysed as g (a channel mean
/// of 9.8 "g") carries `unit-suspect`; the same record at 1 g does not.
#[test]
fn an_accelerometer_record_in_the_wrong_unit_is_named() {
    let f = unique("accel.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--quantity",
        "accel",
        "--vrw-ug-rthz",
        "50",
        "--duration-s",
        "20",
        "--rate-hz",
        "100",
        "--seed",
        "6",
        "-o",
        p(&f),
    ]));
    let text = std::fs::read_to_string(&f).unwrap();
    let offset = |g: f64, name: &str| {
        let mut out = String::new();
        for (i, l) in text.lines().enumerate() {
            if l.starts_with('#') || i == 0 || !l.contains(',') {
                out.push_str(l);
            } else {
                let (a, b) = l.rsplit_once(',').unwrap();
                let x: f64 = b.parse().unwrap();
                out.push_str(&format!("{a},{}", x + g));
            }
            out.push('\n');
        }
        write(name, &out)
    };
    let analyse = |file: &std::path::Path| {
        json_of(&run(&[
            "noise",
            "--input",
            p(file),
            "--rate-hz",
            "100",
            "--quantity",
            "accel",
            "--unit",
            "g",
            "--quiet",
            "--json",
        ]))
    };
    let suspect = |v: &serde_json::Value| !warnings_with(v, "unit-suspect").is_empty();
    let wrong = analyse(&offset(9.80665, "accel_ms2.csv"));
    assert!(suspect(&wrong), "{}", wrong["warnings"]);
    assert!(!suspect(&analyse(&offset(1.0, "accel_g.csv"))));
}

/// The coefficients of a result as name → (value, u).
fn coefficients(v: &serde_json::Value) -> Vec<(String, f64, f64)> {
    v["coefficients"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(name, c)| {
            (
                name.clone(),
                c["value"].as_f64().unwrap(),
                c["u"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// Misalignment raw records under the time-stamp policy: stamps from a
/// clock coarser than the sampling repeat and change nothing (time gives
/// only the measured table rate); a few samples lost in a record are
/// counted by table angle and warned with their Earth-rate bound, within
/// u of the clean run; more than 1 % of a record lost is refused naming
/// the record's line.
#[test]
fn misalign_raw_records_take_repeats_and_count_lost_samples() {
    let o = run(&[
        "simulate",
        "misalign",
        "gyro",
        "--time-series",
        "--records",
        "1",
        "--samples-per-turn",
        "400",
        "--seed",
        "5",
    ]);
    let clean = ok(&o);
    // The file written and the run on it.
    let solve = |name: &str, text: &str| {
        let f = write(name, text);
        let o = run(&[
            "misalign",
            "gyro",
            "--input",
            p(&f),
            "--scale-factor",
            "-2.9222",
            "--json",
        ]);
        (f, o)
    };
    let base = json_of(&solve("clean.csv", &clean).1);
    assert!(warnings_with(&base, "time-repeats").is_empty());
    let c0 = coefficients(&base);
    // time_s is the fourth column: floor it to 0.1 s (samples every 0.045 s).
    let lines: Vec<&str> = clean.lines().collect();
    let floor = |l: &str| -> String {
        let mut f: Vec<String> = l.split(',').map(String::from).collect();
        let t: f64 = f[3].parse().unwrap();
        f[3] = format!("{:.1}", (t / 0.1 + 1e-9).floor() * 0.1);
        f.join(",")
    };
    let q: String = std::iter::once(lines[0].to_string())
        .chain(lines[1..].iter().map(|l| floor(l)))
        .map(|l| l + "\n")
        .collect();
    let v = json_of(&solve("quantised.csv", &q).1);
    assert!(!warnings_with(&v, "time-repeats").is_empty());
    for (a, b) in c0.iter().zip(coefficients(&v)) {
        assert_eq!(a.1, b.1, "{}: only the measured rate uses time", a.0);
    }
    // Two samples lost in the first record (0.5 %), then ten (2.5 %).
    let drop = |k: std::ops::Range<usize>| -> String {
        lines
            .iter()
            .enumerate()
            .filter(|(i, _)| !k.contains(i))
            .map(|(_, l)| format!("{l}\n"))
            .collect()
    };
    let v = json_of(&solve("lost2.csv", &drop(150..152)).1);
    let w = warnings_with(&v, "time-gaps");
    assert!(
        w.len() == 1 && w[0].starts_with("line 2") && w[0].contains("lose 2 samples"),
        "{w:?}"
    );
    for (a, b) in c0.iter().zip(coefficients(&v)) {
        assert!(
            (a.1 - b.1).abs() < a.2,
            "{}: {} against {} ± {}",
            a.0,
            b.1,
            a.1,
            a.2
        );
    }
    let (f, o) = solve("lost10.csv", &drop(150..160));
    refused(&o, &[p(&f), ":2:", "lose 10 samples", "more than 1 %"]);
}

/// `imu apply` under the streaming time-stamp policy: repeated stamps are
/// copied and reported on standard error, a decreasing stamp is refused
/// at its line, `--sort-time` puts the rows in order and says how many
/// moved; the calibrated values of every row are those of the clean file.
#[test]
fn imu_apply_copies_stamps_under_the_policy() {
    let text = autocal_session();
    let session = write_unique("apply_session.csv", &text);
    let cal = unique("apply_cal.json");
    std::fs::write(
        &cal,
        ok(&run(&[
            "imu",
            "autocal",
            "--input",
            p(&session),
            "--rate-hz",
            "100",
            "--init-static-s",
            "3",
            "--json",
        ])),
    )
    .unwrap();
    let apply = |f: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["imu", "apply", "--calibration", p(&cal), "--input", p(f)];
        args.extend_from_slice(extra);
        run(&args)
    };
    let clean = apply(&session, &[]);
    assert!(stderr(&clean).is_empty(), "{}", stderr(&clean));
    let clean = ok(&clean);
    // Stamps floored to 20 ms: copied as floored, warned, values unchanged.
    let q = write("apply_quantised.csv", &quantised(&text, 0.02));
    let o = apply(&q, &[]);
    let out = ok(&o);
    assert!(
        stderr(&o).contains("warning [time-repeats]"),
        "{}",
        stderr(&o)
    );
    let after_time = |s: &str| -> Vec<String> {
        s.lines()
            .map(|l| l.split_once(',').unwrap().1.to_string())
            .collect()
    };
    assert_eq!(after_time(&out), after_time(&clean));
    // Two data rows swapped: refused at the second one's line, unless
    // --sort-time, which gives the clean output back.
    let mut lines: Vec<&str> = text.lines().collect();
    let first = lines
        .iter()
        .position(|l| l.starts_with(|c: char| c.is_ascii_digit()))
        .unwrap();
    lines.swap(first + 10, first + 11);
    let swapped = write("apply_swapped.csv", &(lines.join("\n") + "\n"));
    refused(
        &apply(&swapped, &[]),
        &[
            p(&swapped),
            &format!(":{}:", first + 12),
            "below the stamp before",
        ],
    );
    let o = apply(&swapped, &["--sort-time"]);
    assert_eq!(ok(&o), clean);
    assert!(
        stderr(&o).contains("warning [time-sorted]: 2 of"),
        "{}",
        stderr(&o)
    );
}
