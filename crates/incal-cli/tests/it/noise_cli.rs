//! `incal noise` and `incal simulate noise` from outside: the interface
//! contract (options, JSON keys, coefficient names and units), parallel =
//! sequential bit for bit, CSV = binary, and bad input → exit 2, one line.

use crate::common;
use common::*;

use std::path::PathBuf;
use std::process::Output;

use serde_json::Value;

fn bad(o: &Output, needle: &str) {
    refused(o, &[needle]);
}

fn simulate(name: &str, format: &str, extra: &[&str]) -> PathBuf {
    let p = dir().join(name);
    let mut args = vec![
        "simulate",
        "noise",
        "--quantity",
        "gyro",
        "--arw-deg-rth",
        "0.1",
        "--bias-instability-deg-h",
        "2",
        "--rrw-deg-h-rth",
        "0",
        "--rate-hz",
        "10",
        "--duration-s",
        "2000",
        "--seed",
        "5",
        "--format",
        format,
        "--output",
        p.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    ok(&run(&args));
    p
}

#[test]
fn contract_keys_units_and_truth() {
    let p = simulate("g.csv", "csv", &["--channels", "2"]);
    let out = ok(&run(&[
        "noise",
        "--input",
        p.to_str().unwrap(),
        "--rate-hz",
        "10",
        "--quantity",
        "gyro",
        "--unit",
        "deg/s",
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["procedure"], "noise");
    for ch in ["ch1", "ch2"] {
        let c = &v["channels"][ch];
        let taus = c["taus_s"].as_array().unwrap();
        assert_eq!(taus[0].as_f64(), Some(0.1));
        for d in ["oadev", "mdev", "ohdev", "tdev", "totdev"] {
            for k in ["value", "lo", "hi", "edf", "n"] {
                assert_eq!(
                    c[d][k].as_array().unwrap().len(),
                    taus.len(),
                    "{ch}.{d}.{k}"
                );
            }
            let (lo, val, hi) = (
                c[d]["lo"][3].as_f64().unwrap(),
                c[d]["value"][3].as_f64().unwrap(),
                c[d]["hi"][3].as_f64().unwrap(),
            );
            assert!(lo < val && val < hi, "{d}");
        }
        assert_eq!(c["alpha"].as_array().unwrap().len(), taus.len());
        let arw = &v["coefficients"][format!("{ch}.ARW")];
        assert_eq!(arw["unit"], "deg/sqrt(h)");
        let (val, u95) = (arw["value"].as_f64().unwrap(), arw["U95"].as_f64().unwrap());
        assert!((val - 0.1).abs() < u95.max(0.003), "ARW {val} ± {u95}");
        let b = &v["coefficients"][format!("{ch}.bias_instability")];
        assert_eq!(b["unit"], "deg/h");
        assert!(
            (b["value"].as_f64().unwrap() - 2.0).abs() < 3.0 * b["U95"].as_f64().unwrap(),
            "B {b}"
        );
        for s in ["bias_stability_10s", "bias_stability_100s"] {
            assert_eq!(v["coefficients"][format!("{ch}.{s}")]["unit"], "deg/h");
        }
        // RRW is zero: never a confident number.
        assert!(v["coefficients"].get(format!("{ch}.RRW")).is_none());
    }
    assert!(!warnings_with(&v, "noise-term-not-identified").is_empty());
}

#[test]
fn parallel_equals_sequential_and_binary_equals_csv() {
    let csv = simulate("p.csv", "csv", &["--channels", "3"]);
    let bin = simulate("p.f64", "f64le", &["--channels", "3"]);
    // A mapped binary record is not drawn again: the Monte Carlo is
    // refused, never ignored.
    refused(
        &common::run(&[
            "noise",
            "--input",
            bin.to_str().unwrap(),
            "--format",
            "f64le",
            "--channels",
            "3",
            "--rate-hz",
            "10",
            "--monte-carlo",
            "100",
        ]),
        &["--monte-carlo", "binary record"],
    );
    let run = |extra: &[&str], input: &PathBuf| {
        let mut a = vec![
            "noise",
            "--input",
            input.to_str().unwrap(),
            "--rate-hz",
            "10",
            "--json",
            "--quiet",
        ];
        a.extend_from_slice(extra);
        let v: Value = serde_json::from_str(&ok(&run(&a))).unwrap();
        v
    };
    let par = run(&[], &csv);
    let seq = run(&["--sequential"], &csv);
    assert_eq!(par["channels"], seq["channels"]);
    assert_eq!(par["coefficients"], seq["coefficients"]);
    let b = run(&["--format", "f64le", "--channels", "3"], &bin);
    assert_eq!(par["channels"], b["channels"]);
    assert_eq!(par["coefficients"], b["coefficients"]);
    // f32 data, one selected channel.
    let b32 = simulate("p.f32", "f32le", &["--channels", "2"]);
    let one = run(
        &["--format", "f32le", "--channels", "2", "--columns", "ch2"],
        &b32,
    );
    assert_eq!(one["channels"].as_object().unwrap().len(), 1);
    assert!(
        one["channels"]["ch2"]["oadev"]["value"][0]
            .as_f64()
            .unwrap()
            > 0.0
    );
}

#[test]
fn angle_data_gives_the_rate_deviations() {
    // The running sum of rate samples, given as angle, gives the same OADEV.
    let d = dir();
    let rate: Vec<f64> = (0..400)
        .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
        .collect();
    let mut r = String::from("time_s,w\n");
    let mut a = String::from("theta\n");
    let mut acc = 0.0;
    a.push_str("0\n");
    for (i, v) in rate.iter().enumerate() {
        r.push_str(&format!("{},{v}\n", i as f64));
        acc += v;
        a.push_str(&format!("{acc}\n"));
    }
    std::fs::write(d.join("r.csv"), r).unwrap();
    std::fs::write(d.join("a.csv"), a).unwrap();
    let get = |f: &str, data: &str, col: &str| -> Vec<f64> {
        let v: Value = serde_json::from_str(&ok(&run(&[
            "noise",
            "--input",
            d.join(f).to_str().unwrap(),
            "--rate-hz",
            "1",
            "--data",
            data,
            "--json",
        ])))
        .unwrap();
        v["channels"][col]["oadev"]["value"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (x, y) = (get("r.csv", "rate", "w"), get("a.csv", "angle", "theta"));
    assert_eq!(x.len(), y.len());
    for (p, q) in x.iter().zip(&y) {
        assert!(((p - q) / q).abs() < 1e-9, "{p} vs {q}");
    }
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let d = dir();
    let w = |n: &str, s: &str| {
        let p = d.join(n);
        std::fs::write(&p, s).unwrap();
        p.to_str().unwrap().to_string()
    };
    let text = w("t.csv", "time_s,gx\n0,1\n1,abc\n2,3\n3,4\n4,5\n");
    bad(
        &run(&["noise", "--input", &text, "--rate-hz", "1"]),
        "t.csv:3",
    );
    let inf = w("inf.csv", "gx\n1\ninf\n2\n3\n4\n");
    bad(
        &run(&["noise", "--input", &inf, "--rate-hz", "1"]),
        "inf.csv:3",
    );
    // A NaN cell is a missing sample (a gap): here no stretch is long
    // enough for one averaging time.
    let nan = w("nan.csv", "gx\n1\nNaN\n2\n3\n4\n");
    bad(
        &run(&["noise", "--input", &nan, "--rate-hz", "1"]),
        "longest stretch between gaps and missing samples has 3 samples",
    );
    let no_rate = w("norate.csv", "gx\n1\n2\n3\n4\n5\n6\n");
    bad(&run(&["noise", "--input", &no_rate]), "--rate-hz");
    let empty = w("e.csv", "");
    bad(
        &run(&["noise", "--input", &empty, "--rate-hz", "1"]),
        "e.csv",
    );
    let short = w("s.csv", "gx\n1\n2\n");
    bad(
        &run(&["noise", "--input", &short, "--rate-hz", "1"]),
        "s.csv",
    );
    let good = w("g.csv", "gx\n1\n2\n3\n4\n5\n6\n");
    bad(
        &run(&[
            "noise",
            "--input",
            &good,
            "--rate-hz",
            "1",
            "--columns",
            "gy",
        ]),
        "gy",
    );
    bad(
        &run(&["noise", "--input", &good, "--rate-hz", "0"]),
        "--rate-hz",
    );
    bad(
        &run(&[
            "noise",
            "--input",
            &good,
            "--rate-hz",
            "1",
            "--quantity",
            "gyro",
            "--unit",
            "furlong/s",
        ]),
        "--unit: 'furlong/s'",
    );
    bad(
        &run(&[
            "noise",
            "--input",
            &good,
            "--rate-hz",
            "1",
            "--taus",
            "weekly",
        ]),
        "--taus",
    );
    bad(
        &run(&[
            "noise",
            "--input",
            &good,
            "--rate-hz",
            "1",
            "--confidence",
            "1.5",
        ]),
        "--confidence",
    );
    bad(
        &run(&[
            "noise",
            "--input",
            &good,
            "--rate-hz",
            "1",
            "--format",
            "f64le",
        ]),
        "channels",
    );
    let odd = w("o.bin", "12345");
    bad(
        &run(&[
            "noise",
            "--input",
            &odd,
            "--rate-hz",
            "1",
            "--format",
            "f32le",
            "--channels",
            "1",
        ]),
        "o.bin",
    );
    bad(
        &run(&["noise", "--input", "/nonexistent/x.csv", "--rate-hz", "1"]),
        "x.csv",
    );
    bad(
        &run(&[
            "simulate",
            "noise",
            "--arw-deg-rth",
            "-1",
            "--rate-hz",
            "1",
            "--duration-s",
            "10",
            "--seed",
            "1",
            "-o",
            "-",
        ]),
        "--arw-deg-rth",
    );
}

#[test]
fn the_report_draws_the_allan_plot() {
    let p = simulate("rep.csv", "csv", &[]);
    let json = dir().join("rep.json");
    ok(&run(&[
        "noise",
        "--input",
        p.to_str().unwrap(),
        "--rate-hz",
        "10",
        "--quantity",
        "gyro",
        "--json",
        "-o",
        json.to_str().unwrap(),
    ]));
    let html = ok(&run(&["report", json.to_str().unwrap()]));
    let fig = html.find("data-plot=\"allan\"").expect("an Allan figure");
    let svg = &html[fig..html[fig..].find("</svg>").unwrap() + fig];
    // Dots for the deviations, lines for the bounds and the fitted terms.
    assert!(svg.matches("<circle").count() >= 8, "dots");
    assert!(svg.matches("<polyline").count() >= 8, "bars and lines");
    assert!(html.contains("OADEV with 68.3 % bounds"));
}

/// `simulate noise --quantity accel`: terms in accelerometer units (g
/// samples), recovered by `noise --quantity accel --unit g` within their
/// U95; a gyro term option with accel (and the reverse) is refused.
#[test]
fn accelerometer_records_round_trip() {
    let p = dir().join("accel.bin");
    ok(&run(&[
        "simulate",
        "noise",
        "--quantity",
        "accel",
        "--vrw-ug-rthz",
        "50",
        "--bias-instability-ug",
        "20",
        "--rate-hz",
        "100",
        "--duration-s",
        "20000",
        "--seed",
        "3",
        "--format",
        "f64le",
        "--output",
        p.to_str().unwrap(),
    ]));
    let out = ok(&run(&[
        "noise",
        "--input",
        p.to_str().unwrap(),
        "--format",
        "f64le",
        "--channels",
        "1",
        "--rate-hz",
        "100",
        "--quantity",
        "accel",
        "--unit",
        "g",
        "--json",
    ]));
    let v: Value = serde_json::from_str(&out).unwrap();
    let c = &v["coefficients"];
    assert_eq!(c["ch1.VRW"]["unit"], "ug/sqrt(Hz)");
    for (name, truth) in [("ch1.VRW", 50.0), ("ch1.bias_instability", 20.0)] {
        let (x, u95) = (
            c[name]["value"].as_f64().unwrap(),
            c[name]["U95"].as_f64().unwrap(),
        );
        assert!(
            (x - truth).abs() <= u95,
            "{name}: {x} vs {truth} (U95 {u95})"
        );
    }
    let q = dir().join("x.csv");
    bad(
        &run(&[
            "simulate",
            "noise",
            "--quantity",
            "accel",
            "--arw-deg-rth",
            "1",
            "--rate-hz",
            "10",
            "--duration-s",
            "10",
            "--seed",
            "1",
            "--output",
            q.to_str().unwrap(),
        ]),
        "--arw-deg-rth: not a term of quantity accel",
    );
    bad(
        &run(&[
            "simulate",
            "noise",
            "--vrw-ug-rthz",
            "1",
            "--rate-hz",
            "10",
            "--duration-s",
            "10",
            "--seed",
            "1",
            "--output",
            q.to_str().unwrap(),
        ]),
        "--vrw-ug-rthz: not a term of quantity gyro",
    );
}

#[test]
fn binary_samples_that_are_not_finite_or_overflow_are_named() {
    let d = dir();
    // Interleaved little-endian frames of `ch` channels, value(row, channel).
    let write = |n: &str, rows: usize, ch: usize, f64le: bool, v: &dyn Fn(usize, usize) -> f64| {
        let mut b = Vec::new();
        for r in 0..rows {
            for c in 0..ch {
                let x = v(r, c);
                if f64le {
                    b.extend_from_slice(&x.to_le_bytes());
                } else {
                    b.extend_from_slice(&(x as f32).to_le_bytes());
                }
            }
        }
        let p = d.join(n);
        std::fs::write(&p, b).unwrap();
        p.to_str().unwrap().to_string()
    };
    let wiggle = |r: usize, c: usize| ((r * 7919 + c * 31) % 101) as f64 / 50.0 - 1.0;
    // The wiggle with one sample, at (row, channel), replaced by `v`.
    let spiked = |at: (usize, usize), v: f64| {
        move |r: usize, c: usize| if (r, c) == at { v } else { wiggle(r, c) }
    };
    let run = |p: &str, fmt: &str, ch: &str, extra: &[&str]| {
        let mut a = vec![
            "noise",
            "--input",
            p,
            "--rate-hz",
            "1",
            "--format",
            fmt,
            "--channels",
            ch,
        ];
        a.extend_from_slice(extra);
        run(&a)
    };
    // f64, every channel: the arrays are built in the reading pass.
    let nan = write("nan.f64", 200, 3, true, &spiked((7, 1), f64::NAN));
    bad(
        &run(&nan, "f64le", "3", &[]),
        "sample 8 of ch2: not a finite number",
    );
    bad(
        &run(&nan, "f64le", "3", &["--data", "angle", "--sequential"]),
        "sample 8 of ch2: not a finite number",
    );
    // The other channels alone are fine.
    ok(&run(
        &nan,
        "f64le",
        "3",
        &["--columns", "ch1,ch3", "--json"],
    ));
    // f32, four channels: the arrays (f64) would outgrow the file, so they
    // are built per channel after the checks.
    let inf = write("inf.f32", 300, 4, false, &spiked((250, 2), f64::INFINITY));
    bad(
        &run(&inf, "f32le", "4", &[]),
        "sample 251 of ch3: not a finite number",
    );
    // Finite samples whose running sum (the phase) would overflow: beyond
    // the input layer's range, so refused at the first one.
    let huge = write("huge.f64", 100, 1, true, &|r, _| {
        if r < 50 {
            1.7e308
        } else {
            -1.7e308
        }
    });
    let o = run(&huge, "f64le", "1", &[]);
    bad(&o, "huge.f64");
    bad(&o, "sample 1 of ch1: 1.7e308 is beyond the readable range");
    // As angle data too (there the differences overflowed and every
    // deviation came out null with exit 0).
    bad(
        &run(&huge, "f64le", "1", &["--data", "angle", "--json"]),
        "beyond the readable range",
    );
}

/// `incal export kalibr`: the gyro's and the accelerometer's noise
/// results as Kalibr's imu.yaml, every value the largest axis's term
/// converted to SI continuous time (checked here from the results' own
/// coefficients), read back as numbers; a term not identified on an axis,
/// a result of the wrong quantity or rate are refused by name.
#[test]
fn kalibr_export_converts_the_terms_and_refuses_what_is_missing() {
    let sim = |name: &str, args: &[&str]| {
        let p = unique(name);
        let mut a = vec![
            "simulate",
            "noise",
            "--rate-hz",
            "100",
            "--duration-s",
            "3600",
            "--channels",
            "3",
            "--seed",
            "11",
            "-o",
            p.to_str().unwrap(),
        ];
        a.extend_from_slice(args);
        ok(&run(&a));
        p
    };
    let reduce = |input: &PathBuf, q: &str, name: &str| {
        let out = unique(name);
        ok(&run(&[
            "noise",
            "--input",
            p(input),
            "--rate-hz",
            "100",
            "--quantity",
            q,
            "--json",
            "-o",
            p(&out),
        ]));
        out
    };
    let (gj, aj) = noise_pair(&workdir("kalibr"), "kal-");
    let yaml = ok(&run(&[
        "export",
        "kalibr",
        "--gyro",
        p(&gj),
        "--accel",
        p(&aj),
    ]));
    let read: std::collections::BTreeMap<String, f64> = yaml
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let (k, v) = l.split_once(':').unwrap();
            let v = v.split('#').next().unwrap().trim();
            (k.to_string(), v.parse::<f64>().unwrap())
        })
        .collect();
    let doc = |f: &PathBuf| -> Value {
        serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap()
    };
    let largest = |d: &Value, term: &str| {
        ["ch1", "ch2", "ch3"]
            .iter()
            .map(|c| {
                d["coefficients"][format!("{c}.{term}")]["value"]
                    .as_f64()
                    .unwrap_or_else(|| panic!("{c}.{term} identified"))
            })
            .fold(f64::MIN, f64::max)
    };
    let (gd, ad) = (doc(&gj), doc(&aj));
    let rad = std::f64::consts::PI / 180.0;
    let g0 = 9.80665;
    let want = [
        ("gyroscope_noise_density", largest(&gd, "ARW") * rad / 60.0),
        (
            "gyroscope_random_walk",
            largest(&gd, "RRW") * rad / 216_000.0,
        ),
        (
            "accelerometer_noise_density",
            largest(&ad, "VRW") * 1e-6 * g0,
        ),
        (
            "accelerometer_random_walk",
            largest(&ad, "acceleration_random_walk") * 1e-6 * g0,
        ),
        ("update_rate", 100.0),
    ];
    assert_eq!(read.len(), want.len(), "{yaml}");
    for (k, v) in want {
        let got = read[k];
        assert!((got - v).abs() <= 1e-12 * v.abs(), "{k}: {got} vs {v}");
    }
    // Near the truth: ARW 0.2 deg/sqrt(h) is 5.8e-5 rad/s/sqrt(Hz).
    assert!(
        (read["gyroscope_noise_density"] / (0.2 * rad / 60.0) - 1.0).abs() < 0.05,
        "{yaml}"
    );
    // Each source path has a comment line of its own; every other line
    // stays short whatever the paths' length.
    assert!(
        yaml.lines()
            .filter(|l| !l.starts_with("# gyro: ") && !l.starts_with("# accelerometer: "))
            .all(|l| l.len() < 200),
        "{yaml}"
    );

    // The same terms in SI continuous time in each result (si_terms).
    for (d, term, key, k) in [
        (&gd, "ARW", "noise_density", rad / 60.0),
        (&gd, "RRW", "random_walk", rad / 216_000.0),
        (&ad, "VRW", "noise_density", 1e-6 * g0),
        (&ad, "acceleration_random_walk", "random_walk", 1e-6 * g0),
    ] {
        for c in ["ch1", "ch2", "ch3"] {
            let want = d["coefficients"][format!("{c}.{term}")]["value"]
                .as_f64()
                .unwrap()
                * k;
            let got = d["channels"][c]["si_terms"][key]["value"].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 1e-12 * want,
                "{c}.{key}: {got} vs {want}"
            );
        }
    }
    assert_eq!(
        gd["channels"]["ch1"]["si_terms"]["noise_density"]["unit"],
        "rad/s/sqrt(Hz)"
    );

    // PX4: each Kalibr density times √(EKF rate), in QGC's parameter file.
    let params = ok(&run(&[
        "export",
        "px4",
        "--gyro",
        p(&gj),
        "--accel",
        p(&aj),
        "--ekf-rate-hz",
        "250",
    ]));
    let px4: std::collections::BTreeMap<String, f64> = params
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!((f.len(), f[0], f[1], f[4]), (5, "1", "1", "9"), "{l}");
            (f[2].to_string(), f[3].parse::<f64>().unwrap())
        })
        .collect();
    let s = 250f64.sqrt();
    for (name, key) in [
        ("EKF2_GYR_NOISE", "gyroscope_noise_density"),
        ("EKF2_ACC_NOISE", "accelerometer_noise_density"),
        ("EKF2_GYR_B_NOISE", "gyroscope_random_walk"),
        ("EKF2_ACC_B_NOISE", "accelerometer_random_walk"),
    ] {
        let (got, v) = (px4[name], read[key] * s);
        assert!(
            (got - v).abs() <= 1e-12 * v,
            "{name}: {got} vs {v}\n{params}"
        );
    }
    assert_eq!(px4.len(), 4, "{params}");
    bad(
        &run(&[
            "export",
            "px4",
            "--gyro",
            p(&gj),
            "--accel",
            p(&aj),
            "--ekf-rate-hz",
            "0",
        ]),
        "--ekf-rate-hz",
    );

    // Refusals, one line each, exit 2.
    let e = run(&["export", "kalibr", "--gyro", p(&aj), "--accel", p(&aj)]);
    refused(
        &e,
        &["kal-accel", "$.options.quantity is \"accel\", not \"gyro\""],
    );
    let white = sim(
        "kal-white.csv",
        &["--quantity", "gyro", "--arw-deg-rth", "0.2"],
    );
    let wj = reduce(&white, "gyro", "kal-white.json");
    let e = run(&["export", "kalibr", "--gyro", p(&wj), "--accel", p(&aj)]);
    refused(
        &e,
        &[
            "ch1: RRW was not identified",
            "gyroscope_random_walk is not written as zero",
        ],
    );
    let tumble = unique("kal-tumble.json");
    let csv = unique("kal-tumble.csv");
    ok(&run(&["simulate", "tumble", "-o", p(&csv)]));
    ok(&run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        p(&csv),
        "--json",
        "-o",
        p(&tumble),
    ]));
    let e = run(&["export", "kalibr", "--gyro", p(&tumble), "--accel", p(&aj)]);
    refused(&e, &["a tumble result, not a noise result"]);
}

#[test]
fn the_psd_carries_its_bounds_the_white_level_and_the_allan_terms_as_a_psd() {
    let dir = workdir("noise_psd");
    let csv = dir.join("n.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--rate-hz",
        "100",
        "--duration-s",
        "7200",
        "--arw-deg-rth",
        "0.15",
        "--bias-instability-deg-h",
        "3",
        "--rrw-deg-h-rth",
        "20",
        "--seed",
        "3",
        "--output",
        p(&csv),
    ]));
    let v = json_of(&run(&[
        "noise",
        "--input",
        p(&csv),
        "--quantity",
        "gyro",
        "--psd",
        "--json",
    ]));
    let psd = &v["channels"]["ch1"]["psd"];
    let arr = |k: &str| -> Vec<f64> {
        psd[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (lo, hi) = (arr("lo"), arr("hi"));
    let m = &psd["model"];
    let total: Vec<f64> = m["total"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(total.len(), lo.len() - 1, "every bin above 0 Hz");
    // The Allan fit's terms as a PSD lie within the measured PSD's 95 %
    // bounds in about 95 % of the bins: the two analyses agree.
    let inside = total
        .iter()
        .zip(lo.iter().zip(&hi).skip(1))
        .filter(|(t, (a, b))| *a <= *t && *t <= *b)
        .count() as f64
        / total.len() as f64;
    assert!(inside > 0.9, "{inside}");
    assert!(m["terms"]["N"].is_array() && m["terms"]["B"].is_array());
    let w = &v["coefficients"]["ch1.white_asd"];
    assert_eq!(w["unit"], "deg/s/sqrt(Hz)");
    let asd = std::f64::consts::SQRT_2 * 0.15 / 60.0;
    assert!((w["value"].as_f64().unwrap() - asd).abs() <= w["U95"].as_f64().unwrap());
    // Bad settings are named.
    refused(
        &run(&[
            "noise",
            "--input",
            p(&csv),
            "--psd",
            "--psd-white-band-hz",
            "20,5",
        ]),
        &["--psd-white-band-hz"],
    );
    refused(
        &run(&[
            "noise",
            "--input",
            p(&csv),
            "--psd",
            "--psd-segment-samples",
            "4",
        ]),
        &["--psd-segment-samples"],
    );
}
