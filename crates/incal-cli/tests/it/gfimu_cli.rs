//! Integration tests of `incal gfimu ...` and `incal simulate gfimu`,
//! running the real binary on temporary files.

use crate::common;
use common::*;

use std::path::PathBuf;

use serde_json::Value;

fn simulate(extra: &[&str]) -> String {
    let mut args = vec!["simulate", "gfimu"];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o)
}

/// Bad input: exit code 2 and exactly one stderr line containing `parts`.
fn refuses(args: &[&str], parts: &[&str]) {
    refused(&run(args), parts);
}

fn calibrate_json(path: &str) -> Value {
    let o = run(&["gfimu", "calibrate", "--input", path, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

/// Simulate a static test with `seed` (20 samples per position) on the
/// built-in `layout`, calibrate it, and keep the calibration JSON in a
/// temporary file: `(path, JSON text)`.
fn calibration(layout: &str, seed: &str) -> (PathBuf, String) {
    let st = write_unique(
        "static.csv",
        &simulate(&["--layout", layout, "--seed", seed, "--samples", "20"]),
    );
    let o = run(&[
        "gfimu",
        "calibrate",
        "--layout",
        layout,
        "--input",
        st.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    (write_unique("cal.json", &text), text)
}

#[test]
fn calibrate_gives_contract_json() {
    let csv = write_unique("static.csv", &simulate(&["--seed", "5"]));
    let doc = calibrate_json(csv.to_str().unwrap());
    let accs = doc["accelerometers"].as_object().unwrap();
    let mut names: Vec<&String> = accs.keys().collect();
    names.sort();
    assert_eq!(names, ["a", "b", "c", "d", "e", "f"]);
    for (n, a) in accs {
        let k0 = &a["K0"];
        assert!(
            k0["value"].is_f64() && k0["u"].as_f64().unwrap() > 0.0,
            "{n}"
        );
        let ks = &a["Ks"];
        assert_eq!(ks["value"].as_array().unwrap().len(), 3, "{n}");
        assert_eq!(ks["u"].as_array().unwrap().len(), 3, "{n}");
        assert!(ks["u"]
            .as_array()
            .unwrap()
            .iter()
            .all(|u| u.as_f64().unwrap() > 0.0));
    }
    // Accelerometer a senses z with K1 ≈ 1 output/g (default truth).
    let ksz = doc["accelerometers"]["a"]["Ks"]["value"][2]
        .as_f64()
        .unwrap();
    assert!((ksz - 0.997).abs() < 1e-3, "{ksz}");
}

#[test]
fn arbitrary_orientations_by_force_columns() {
    // fx_g, fy_g, fz_g instead of position: the six axes and two diagonals.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let forces = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [h, 0.0, h],
        [0.0, h, -h],
    ];
    let mut text = String::from("fx_g,fy_g,fz_g,a,b,c,d,e,f\n");
    for (i, f) in forces.iter().enumerate() {
        // Accelerometer j: K0 = 0.01 j, Ks = (1 + 0.01 j) l_j, tiny ripple.
        let l = [
            [0, 0, 1],
            [0, 0, 1],
            [1, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 1, 0],
        ];
        let e: Vec<String> = (0..6)
            .map(|j| {
                let s: f64 = (0..3).map(|k| l[j][k] as f64 * f[k]).sum();
                let ripple = 1e-7 * ((i * 7 + j * 3) % 5) as f64;
                (0.01 * j as f64 + (1.0 + 0.01 * j as f64) * s + ripple).to_string()
            })
            .collect();
        text.push_str(&format!("{},{},{},{}\n", f[0], f[1], f[2], e.join(",")));
    }
    let csv = write_unique("forces.csv", &text);
    let doc = calibrate_json(csv.to_str().unwrap());
    let c = &doc["accelerometers"]["c"];
    assert!((c["K0"]["value"].as_f64().unwrap() - 0.02).abs() < 1e-6);
    assert!((c["Ks"]["value"][0].as_f64().unwrap() - 1.02).abs() < 1e-6);
}

#[test]
fn solve_gives_contract_json_and_recovers_motion() {
    let (cal, _) = calibration("paper", "6");
    let mo = write_unique(
        "motion.csv",
        &simulate(&["--kind", "motion", "--seed", "7", "--duration-s", "1.5"]),
    );
    let o = run(&[
        "gfimu",
        "solve",
        "--calibration",
        cal.to_str().unwrap(),
        "--input",
        mo.to_str().unwrap(),
        "--lever-arm-m",
        "0.1",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let samples = doc["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 151);
    for s in samples {
        let mut keys: Vec<&String> = s.as_object().unwrap().keys().collect();
        keys.sort();
        assert_eq!(keys, ["f0_g", "omega_dot_rad_s2", "omega_rad_s", "time_s"]);
    }
    // Defaults: f0 = (0.05, 0, 1) g, 2 rad/s² about z until 1.005 s.
    let s = &samples[100]; // t = 1.0 s
    assert!((s["time_s"].as_f64().unwrap() - 1.0).abs() < 1e-12);
    assert!((s["f0_g"][2].as_f64().unwrap() - 1.0).abs() < 1e-3);
    assert!((s["f0_g"][0].as_f64().unwrap() - 0.05).abs() < 1e-3);
    assert!((s["omega_dot_rad_s2"][2].as_f64().unwrap() - 2.0).abs() < 0.05);
    assert!((s["omega_rad_s"][2].as_f64().unwrap() - 2.0).abs() < 0.01);
}

#[test]
fn simulate_is_reproducible() {
    for kind in ["static", "motion"] {
        let a = simulate(&["--kind", kind, "--seed", "42"]);
        let b = simulate(&["--kind", kind, "--seed", "42"]);
        let c = simulate(&["--kind", kind, "--seed", "43"]);
        assert_eq!(a.as_bytes(), b.as_bytes());
        assert_ne!(a, c);
    }
}

#[test]
fn bad_calibration_inputs_are_refused() {
    let good = simulate(&["--seed", "8", "--samples", "2"]);
    // Missing accelerometer column.
    let no_c = good
        .lines()
        .map(|l| {
            if l.starts_with('#') {
                return l.to_string();
            }
            let f: Vec<&str> = l.split(',').collect();
            [&f[..3], &f[4..]].concat().join(",")
        })
        .collect::<Vec<_>>()
        .join("\n");
    let p = write_unique("noc.csv", &no_c);
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[ps, "missing column 'c'"],
    );

    // NaN and text in a number: file and line named.
    let p = write_unique(
        "nan.csv",
        "position,a,b,c,d,e,f\n+x,0,0,1,1,0,0\n-x,0,NaN,1,1,0,0\n",
    );
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[&format!("{ps}:3"), "'b'"],
    );
    let p = write_unique(
        "text.csv",
        "position,a,b,c,d,e,f\n+x,0,0,1,1,0,0\n-x,0,0,abc,1,0,0\n",
    );
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[&format!("{ps}:3"), "not a number"],
    );
    let p = write_unique("pos.csv", "position,a,b,c,d,e,f\n+q,0,0,1,1,0,0\n");
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[&format!("{ps}:2"), "'+q'"],
    );

    // Empty file.
    let p = write_unique("empty.csv", "");
    let ps = p.to_str().unwrap();
    refuses(&["gfimu", "calibrate", "--input", ps], &[ps, "empty"]);

    // Fewer than six positions (only ±x, ±y, +z).
    let five: String = good
        .lines()
        .filter(|l| !l.starts_with("-z"))
        .map(|l| format!("{l}\n"))
        .collect();
    let p = write_unique("five.csv", &five);
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[ps, "need at least 6, got 5"],
    );

    // Unseparable plan: six orientations, all horizontal in x–y.
    let mut text = String::from("fx_g,fy_g,fz_g,a,b,c,d,e,f\n");
    for (fx, fy) in [
        (1.0, 0.0),
        (-1.0, 0.0),
        (0.0, 1.0),
        (0.0, -1.0),
        (0.6, 0.8),
        (-0.8, 0.6),
    ] {
        text.push_str(&format!("{fx},{fy},0,0.1,0.2,{fx},{fx},{fy},{fy}\n"));
    }
    let p = write_unique("flat.csv", &text);
    let ps = p.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", ps],
        &[ps, "cannot separate", "Ks_z"],
    );

    // Unknown option.
    refuses(
        &["gfimu", "calibrate", "--input", ps, "--frobnicate"],
        &["--frobnicate"],
    );
}

#[test]
fn bad_geometry_and_solve_inputs_are_refused() {
    // Singular geometry: c and d at the same place.
    let geo = write_unique(
        "geo.toml",
        r#"
[[accelerometer]]
name = "a"
position_m = [0.1, 0.0, 0.0]
direction = [0.0, 0.0, 1.0]
[[accelerometer]]
name = "b"
position_m = [-0.1, 0.0, 0.0]
direction = [0.0, 0.0, 1.0]
[[accelerometer]]
name = "c"
position_m = [0.0, 0.1, 0.0]
direction = [1.0, 0.0, 0.0]
[[accelerometer]]
name = "d"
position_m = [0.0, 0.1, 0.0]
direction = [1.0, 0.0, 0.0]
[[accelerometer]]
name = "e"
position_m = [0.0, 0.0, 0.1]
direction = [0.0, 1.0, 0.0]
[[accelerometer]]
name = "f"
position_m = [0.0, 0.0, -0.1]
direction = [0.0, 1.0, 0.0]
"#,
    );
    let gs = geo.to_str().unwrap();
    let csv = write_unique("st.csv", &simulate(&["--seed", "9"]));
    let cs = csv.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", cs, "--geometry", gs],
        &[gs, "cannot", "omega_dot_z"],
    );
    // Malformed TOML names file and line.
    let bad = write_unique(
        "bad.toml",
        "[[accelerometer]]\nname = \"a\"\nposition_m = [0.1, x]\n",
    );
    let bs = bad.to_str().unwrap();
    refuses(
        &["gfimu", "calibrate", "--input", cs, "--geometry", bs],
        &[&format!("{bs}:3")],
    );

    // Solve: calibration missing an accelerometer; series with bad time.
    let cal = write_unique(
        "cal.json",
        "{\"accelerometers\": {\"a\": {\"K0\": {\"value\": 0}, \"Ks\": {\"value\": [0,0,1]}}}}",
    );
    let cals = cal.to_str().unwrap();
    let series = write_unique("series.csv", "time_s,a,b,c,d,e,f\n0,0,0,0,0,0,0\n");
    let ss = series.to_str().unwrap();
    refuses(
        &["gfimu", "solve", "--calibration", cals, "--input", ss],
        &[cals, "'b'"],
    );
    let o = run(&["gfimu", "calibrate", "--input", cs, "--json"]);
    let cal = write_unique("cal2.json", &stdout(&o));
    let cals = cal.to_str().unwrap();
    let series = write_unique(
        "series2.csv",
        "time_s,a,b,c,d,e,f\n0,0,0,0,0,0,1\n0,0,0,0,0,0,1\n",
    );
    let ss = series.to_str().unwrap();
    refuses(
        &["gfimu", "solve", "--calibration", cals, "--input", ss],
        &[&format!("{ss}:3"), "time_s"],
    );
    let series = write_unique("series3.csv", "time_s,a,b,c,d,e\n0,0,0,0,0,0\n");
    let ss = series.to_str().unwrap();
    refuses(
        &["gfimu", "solve", "--calibration", cals, "--input", ss],
        &[ss, "missing column 'f'"],
    );
    let notjson = write_unique("not.json", "{\n \"accelerometers\": [1,\n");
    let ns = notjson.to_str().unwrap();
    refuses(
        &["gfimu", "solve", "--calibration", ns, "--input", ss],
        &[ns, "not valid JSON"],
    );
}

/// The twelve-accelerometer layout solves each sample directly; the three
/// outputs (CSV, JSON, JSON lines) carry the same numbers, and u covers
/// the simulated truth of f0.
#[test]
fn twelve_layout_outputs_agree() {
    let (cal, _) = calibration("twelve", "11");
    let mo = write_unique(
        "m12.csv",
        &simulate(&["--layout", "twelve", "--kind", "motion", "--seed", "12"]),
    );
    let run = |extra: &str| {
        let mut args = vec![
            "gfimu",
            "solve",
            "--layout",
            "twelve",
            "--calibration",
            cal.to_str().unwrap(),
            "--input",
            mo.to_str().unwrap(),
        ];
        if !extra.is_empty() {
            args.push(extra);
        }
        let o = run(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        stdout(&o)
    };
    // serde_json parses floats to within an ulp, not exactly.
    let same =
        |a: f64, b: f64| assert!((a - b).abs() <= 1e-15 * a.abs().max(b.abs()), "{a} vs {b}");
    let doc: Value = serde_json::from_str(&run("--json")).unwrap();
    assert_eq!(doc["mode"], "direct");
    let samples = doc["samples"].as_array().unwrap();
    let us = doc["uncertainty"].as_array().unwrap();
    assert_eq!(samples.len(), 201);
    assert_eq!(us.len(), 201);
    let lines: Vec<Value> = run("--jsonl")
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 202);
    assert_eq!(lines[201]["summary"]["mode"], "direct");
    let csv = run("");
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("time_s"))
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 201);
    for (k, ((s, u), (l, r))) in samples
        .iter()
        .zip(us)
        .zip(lines.iter().zip(&rows))
        .enumerate()
    {
        let keys = ["f0_g", "omega_dot_rad_s2", "omega_rad_s"];
        for (i, key) in keys.iter().enumerate() {
            for a in 0..3 {
                let v = s[key][a].as_f64().unwrap();
                same(v, l[key][a].as_f64().unwrap());
                same(v, r[1 + 3 * i + a]);
                let uk = format!("u_{key}");
                let uv = u[&uk][a].as_f64().unwrap();
                same(uv, l[&uk][a].as_f64().unwrap());
                same(uv, r[10 + 3 * i + a]);
                // u(ω) is 0 at the first sample: ω0 is given.
                assert!(uv.is_finite() && (uv > 0.0 || (i == 2 && k == 0)));
            }
        }
        // f0 truth (0.05, 0, 1) g within 4 u on every axis.
        let truth = [0.05, 0.0, 1.0];
        for a in 0..3 {
            let e = s["f0_g"][a].as_f64().unwrap() - truth[a];
            assert!(
                e.abs() < 4.0 * u["u_f0_g"][a].as_f64().unwrap(),
                "sample {k} axis {a}: {e}"
            );
        }
    }
}

/// The motion simulator turns gravity through the unit (`--f0-frame
/// table`) and oscillates the rate; bad values of those options are
/// refused by name.
#[test]
fn simulate_motion_turning_gravity_and_oscillation() {
    let base = ["--kind", "motion", "--seed", "5", "--axis", "1,0,0"];
    let plain = simulate(&base);
    let mut args = base.to_vec();
    args.extend(["--f0-g", "0,0,1", "--f0-frame", "table"]);
    args.extend([
        "--oscillation-amplitude-rad-s",
        "0.3",
        "--oscillation-hz",
        "2",
    ]);
    let turned = simulate(&args);
    assert_ne!(plain, turned);
    // How it was simulated is in the truth file beside the CSV.
    let t = write_unique("turned_truth.json", "");
    args.extend(["--truth-out", t.to_str().unwrap()]);
    simulate(&args);
    assert!(std::fs::read_to_string(&t)
        .unwrap()
        .contains("f0 frame: table"));
    refuses(
        &[
            "simulate",
            "gfimu",
            "--kind",
            "motion",
            "--oscillation-amplitude-rad-s",
            "0.3",
            "--oscillation-hz",
            "50",
        ],
        &["--oscillation-hz", "half of --rate-hz"],
    );
    refuses(
        &[
            "simulate",
            "gfimu",
            "--kind",
            "motion",
            "--oscillation-amplitude-rad-s",
            "0.3",
        ],
        &["--oscillation-hz > 0"],
    );
    refuses(
        &[
            "simulate",
            "gfimu",
            "--kind",
            "motion",
            "--f0-frame",
            "table",
            "--omega0-rad-s",
            "1,0,0",
        ],
        &["--omega0-rad-s must lie along axis"],
    );
}

/// The calibration JSON read by `gfimu solve` is strict: a wrong type, an
/// extra array element, an unknown field or an accelerometer the geometry
/// lacks is refused at its JSON path; a UTF-8 BOM is read.
#[test]
fn solve_calibration_is_read_strictly() {
    let (_, text) = calibration("paper", "9");
    let good: Value = serde_json::from_str(&text).unwrap();
    let mo = write_unique(
        "motion.csv",
        &simulate(&["--kind", "motion", "--seed", "9"]),
    );
    let solve = |cal: &PathBuf| {
        vec![
            "gfimu".to_string(),
            "solve".into(),
            "--calibration".into(),
            cal.to_str().unwrap().into(),
            "--input".into(),
            mo.to_str().unwrap().into(),
        ]
    };
    type Edit<'a> = &'a dyn Fn(&mut Value);
    let cases: [(Edit, &str); 6] = [
        (
            &|d| d["accelerometers"]["a"]["Ks"]["value"] = serde_json::json!([1, 0, 0, 99]),
            "$.accelerometers.a.Ks.value: must be an array of exactly three numbers",
        ),
        (
            &|d| d["accelerometers"]["b"]["K0"]["value"] = Value::from("x"),
            "$.accelerometers.b.K0.value: missing or not a number",
        ),
        (
            &|d| d["accelerometers"]["c"]["bogus"] = Value::from(1),
            "$.accelerometers.c.bogus: unknown field",
        ),
        (
            &|d| d["accelerometers"]["zz"] = d["accelerometers"]["a"].clone(),
            "$.accelerometers.zz: not an accelerometer of the geometry",
        ),
        (
            &|d| d["accelerometers"]["d"]["noise_output"] = Value::from(0),
            "$.accelerometers.d.noise_output: must be a positive number or null",
        ),
        (
            &|d| {
                d["accelerometers"].as_object_mut().unwrap().remove("e");
            },
            "$.accelerometers.e: missing",
        ),
    ];
    for (edit, msg) in cases {
        let mut d = good.clone();
        edit(&mut d);
        let cal = write_unique("cal.json", &d.to_string());
        let args = solve(&cal);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refuses(&args, &[cal.to_str().unwrap(), msg]);
    }
    let cal = write_unique("bom.json", &format!("\u{feff}{good}"));
    let args = solve(&cal);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A run stopped by a bad row keeps the rows before it and closes its
/// output with the reason: the JSON document stays valid, the exit code
/// is still 2 with one stderr line naming the line.
#[test]
fn solve_stopped_midway_closes_its_output() {
    let (cal, _) = calibration("paper", "6");
    let mut text = String::new();
    let mut data_rows = 0;
    for l in simulate(&["--kind", "motion", "--seed", "7"]).lines() {
        if !l.starts_with('#') && !l.starts_with("time_s") {
            data_rows += 1;
            if data_rows == 51 {
                let mut f: Vec<&str> = l.split(',').collect();
                f[2] = "abc";
                text.push_str(&f.join(","));
                text.push('\n');
                continue;
            }
        }
        text.push_str(l);
        text.push('\n');
    }
    let bad_line = text.lines().position(|l| l.contains("abc")).unwrap() + 1;
    let mo = write_unique("motion_bad.csv", &text);
    for out in ["--json", "--jsonl", ""] {
        let mut args = vec![
            "gfimu",
            "solve",
            "--calibration",
            cal.to_str().unwrap(),
            "--input",
            mo.to_str().unwrap(),
        ];
        if !out.is_empty() {
            args.push(out);
        }
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{out}");
        let err = stderr(&o);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        let at = format!("{}:{bad_line}:", mo.display());
        assert!(err.contains(&at), "{err}");
        let text = stdout(&o);
        match out {
            "--json" => {
                let d: Value = serde_json::from_str(&text).unwrap();
                assert_eq!(d["samples"].as_array().unwrap().len(), 50);
                assert!(d["error"].as_str().unwrap().contains(&at));
            }
            "--jsonl" => {
                let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
                assert!(last["summary"]["error"].as_str().unwrap().contains(&at));
                assert_eq!(text.lines().count(), 51);
            }
            // The CSV stays rows only (the reason is on stderr, above).
            _ => assert!(text.lines().all(|l| !l.starts_with('#')), "{text}"),
        }
    }
}

/// `gfimu solve` under the streaming time-stamp policy: stamps floored to
/// twice the period repeat (zero steps, warning `time-repeats`) and a gap
/// of up to four lost samples is bridged (warning `time-gaps`), each with
/// the final ω within 4 u of the clean run (the trapezoid error over the
/// bridged step is below the noise); a longer gap and a decreasing stamp
/// are refused at their line.
#[test]
fn solve_takes_repeats_and_short_gaps_and_refuses_long_ones() {
    let (cal, _) = calibration("twelve", "11");
    let text = simulate(&["--layout", "twelve", "--kind", "motion", "--seed", "12"]);
    let lines: Vec<&str> = text.lines().collect();
    let first = lines.iter().position(|l| l.starts_with("time_s")).unwrap() + 1;
    let solve = |name: &str, body: &[String]| {
        let mut t: String = lines[..first].iter().map(|l| format!("{l}\n")).collect();
        for l in body {
            t.push_str(l);
            t.push('\n');
        }
        let f = write_unique(name, &t);
        let o = run(&[
            "gfimu",
            "solve",
            "--layout",
            "twelve",
            "--calibration",
            p(&cal),
            "--input",
            p(&f),
            "--json",
        ]);
        (f, o)
    };
    let rows: Vec<String> = lines[first..].iter().map(|l| l.to_string()).collect();
    let last_omega = |o: &std::process::Output| -> (Vec<f64>, Vec<f64>, Value) {
        let d = json_of(o);
        let s = d["samples"].as_array().unwrap().last().unwrap().clone();
        let u = d["uncertainty"].as_array().unwrap().last().unwrap().clone();
        let v = |x: &Value| {
            x.as_array()
                .unwrap()
                .iter()
                .map(|a| a.as_f64().unwrap())
                .collect()
        };
        (v(&s["omega_rad_s"]), v(&u["u_omega_rad_s"]), d)
    };
    let (_, o) = solve("clean.csv", &rows);
    let (w0, u0, d) = last_omega(&o);
    assert!(
        warnings_with(&d, "time-repeats").is_empty() && warnings_with(&d, "time-gaps").is_empty()
    );
    let period: f64 = {
        let t = |k: usize| rows[k].split(',').next().unwrap().parse::<f64>().unwrap();
        t(1) - t(0)
    };
    let close = |w: &[f64], what: &str| {
        for a in 0..3 {
            assert!(
                (w[a] - w0[a]).abs() < 4.0 * u0[a],
                "{what}: axis {a}: {} vs {} ± {}",
                w[a],
                w0[a],
                u0[a]
            );
        }
    };
    // Floored to two periods: every other stamp repeats.
    let floored: Vec<String> = rows
        .iter()
        .map(|l| {
            let (t, rest) = l.split_once(',').unwrap();
            let t: f64 = t.parse().unwrap();
            let q = (t / (2.0 * period) + 1e-9).floor() * 2.0 * period;
            format!("{q},{rest}")
        })
        .collect();
    let (_, o) = solve("floored.csv", &floored);
    let (w, _, d) = last_omega(&o);
    assert_eq!(
        warnings_with(&d, "time-repeats").len(),
        1,
        "{}",
        d["warnings"]
    );
    close(&w, "floored stamps");
    // Four samples lost: bridged.
    let mut lost = rows.clone();
    lost.drain(100..104);
    let (_, o) = solve("lost4.csv", &lost);
    let (w, _, d) = last_omega(&o);
    let g = warnings_with(&d, "time-gaps");
    assert!(g.len() == 1 && g[0].starts_with("1 gap(s)"), "{g:?}");
    close(&w, "four samples lost");
    // Ten lost: refused at the row after the gap.
    let mut lost = rows.clone();
    lost.drain(100..110);
    let (f, o) = solve("lost10.csv", &lost);
    refused(
        &o,
        &[
            &format!("{}:{}:", p(&f), first + 101),
            "time_s",
            "gap of 11",
        ],
    );
    // A stamp going back: refused at its line.
    let mut back = rows.clone();
    back.swap(50, 51);
    let (f, o) = solve("back.csv", &back);
    refused(
        &o,
        &[
            &format!("{}:{}:", p(&f), first + 52),
            "below the stamp before",
        ],
    );
}
