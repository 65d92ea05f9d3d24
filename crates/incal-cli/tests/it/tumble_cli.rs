//! The real `incal` binary on good and bad tumble input.

use crate::common;
use common::*;

use std::process::Output;

use serde_json::Value;

fn stderr_line(o: &Output) -> String {
    let s = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(s.trim_end().lines().count(), 1, "one stderr line, got: {s}");
    s.trim_end().to_string()
}

/// `incal tumble --mount MOUNT --input <csv written to NAME> --json`, parsed.
fn calibrate_json(name: &str, csv: &str, mount: &str) -> Value {
    let f = write(name, csv);
    let o = run(&[
        "tumble",
        "--mount",
        mount,
        "--input",
        f.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn simulate(args: &[&str]) -> String {
    let mut all = vec!["simulate", "tumble"];
    all.extend_from_slice(args);
    let o = run(&all);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

#[test]
fn simulate_is_reproducible_and_calibrates_to_contract_json() {
    let a = simulate(&["--mount", "pendulum", "--seed", "5"]);
    let b = simulate(&["--mount", "pendulum", "--seed", "5"]);
    let c = simulate(&["--mount", "pendulum", "--seed", "6"]);
    assert_eq!(a, b, "same seed, same file");
    assert_ne!(a, c);
    assert!(a.starts_with("angle_deg,output\n"));
    let v = calibrate_json("pendulum.csv", &a, "pendulum");
    let coefs = v["coefficients"].as_object().unwrap();
    let names: Vec<&str> = coefs.keys().map(String::as_str).collect();
    for (name, unit) in [
        ("K0", "g"),
        ("K1", "output/g"),
        ("K2", "g/g^2"),
        ("K3", "g/g^3"),
        ("delta_o", "rad"),
        ("K_ip", "g/g^2"),
    ] {
        let c = &coefs[name];
        assert!(c["value"].is_f64() && c["u"].is_f64(), "{name}: {c}");
        assert_eq!(c["unit"], unit, "{name}");
    }
    assert_eq!(names.len(), 6, "{names:?}");
    // Default truth of simulate: K1 = 10, K0 = 8e-3 g.
    let k1 = coefs["K1"]["value"].as_f64().unwrap();
    assert!((k1 - 10.0).abs() < 1e-4);
    let k0 = coefs["K0"]["value"].as_f64().unwrap();
    assert!((k0 - 8e-3).abs() < 1e-5);
}

/// Negative option values (biases, misalignments), including negative
/// exponents that clap's own number detection rejects.
#[test]
fn negative_option_values_are_values() {
    let a = simulate(&[
        "--k0-g",
        "-1.5e-3",
        "--delta-o-arcsec",
        "-300",
        "--seed",
        "4",
    ]);
    let v = calibrate_json("negative.csv", &a, "pendulum");
    let k0 = v["coefficients"]["K0"]["value"].as_f64().unwrap();
    assert!((k0 + 1.5e-3).abs() < 1e-5, "{k0}");
    let d = v["coefficients"]["delta_o"]["value"].as_f64().unwrap();
    assert!((d + incal_arcsec(300.0)).abs() < 1e-6, "{d}");
    // A flag is still not swallowed silently as a value.
    let o = run(&["simulate", "tumble", "--noise", "--json"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr_line(&o).contains("--noise"));
}

fn incal_arcsec(x: f64) -> f64 {
    x / (180.0 * 3600.0 / std::f64::consts::PI)
}

#[test]
fn gate_mount_reports_delta_p_and_k_io() {
    let a = simulate(&["--mount", "gate", "--seed", "3", "--passes", "2"]);
    assert!(a.starts_with("angle_deg,output,pass\n"));
    let v = calibrate_json("gate.csv", &a, "gate");
    assert!(v["coefficients"]["delta_p"]["u"].as_f64().unwrap() > 0.0);
    assert!(v["coefficients"]["K_io"]["u"].as_f64().unwrap() > 0.0);
    assert!(v["coefficients"].get("delta_o").is_none());
    let tables = v["tables"].as_array().unwrap();
    assert!(tables.iter().any(|t| t["id"] == "pass-difference.ccw-cw"));
    assert!(tables.iter().any(|t| t["id"] == "pass-positions.ccw-cw"));
    // Readable report shows arcseconds and the pass difference.
    let f = write("gate.csv", &a);
    let o = run(&["tumble", "--mount", "gate", "--input", f.to_str().unwrap()]);
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("arcsec") && text.contains("Pass difference: ccw minus cw"),
        "{text}"
    );
}

#[test]
fn plan_tumble_json_contract() {
    let o = run(&[
        "plan",
        "tumble",
        "--range-g",
        "0.5",
        "--k1",
        "10",
        "--noise",
        "1e-7",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["step_deg"], 6.0);
    let angles: Vec<f64> = v["angles_deg"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(
        angles,
        vec![0.0, 6.0, 12.0, 18.0, 24.0, 30.0, 180.0, 330.0, 336.0, 342.0, 348.0, 354.0]
    );
    let u = v["predicted_u"].as_object().unwrap();
    // docs/src/tumble.md: σ(K3) ≈ 6.8e-6 at a = 6°.
    let k3 = u["K3"].as_f64().unwrap();
    assert!((k3 - 6.8e-6).abs() < 0.05e-6, "{k3}");
    assert_eq!(u.len(), 6);
}

#[test]
fn compare_reports_difference_per_mille_and_en() {
    let mut files = Vec::new();
    for seed in ["1", "2"] {
        let csv = simulate(&["--seed", seed]);
        let v = calibrate_json(&format!("cmp{seed}.csv"), &csv, "pendulum");
        files.push(write(&format!("cmp{seed}.json"), &v.to_string()));
    }
    let o = run(&[
        "compare",
        files[0].to_str().unwrap(),
        files[1].to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let k1 = &v["comparisons"]["K1"];
    let (a, b) = (k1["a"].as_f64().unwrap(), k1["b"].as_f64().unwrap());
    let d = k1["difference"].as_f64().unwrap();
    assert!((d - (a - b)).abs() <= 1e-15 * a.abs());
    assert!((k1["relative_per_mille"].as_f64().unwrap() - 1e3 * d / b.abs()).abs() < 1e-12);
    // En with each side's own U95 = k95 u (not 2u).
    let (ua, ub) = (k1["U95_a"].as_f64().unwrap(), k1["U95_b"].as_f64().unwrap());
    assert!(
        ua > 2.0 * k1["u_a"].as_f64().unwrap(),
        "k95 > 2 with few dof"
    );
    let en = d / (ua * ua + ub * ub).sqrt();
    assert!((k1["En"].as_f64().unwrap() - en).abs() < 1e-12);
}

#[test]
fn demo_runs_without_input() {
    let o = run(&["demo"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(
        text.contains("pendulum mount")
            && text.contains("gate mount")
            && text.contains("small-angle")
    );
    assert_eq!(
        text,
        String::from_utf8(run(&["demo"]).stdout).unwrap(),
        "deterministic"
    );
}

/// Bad input: exit 2 and one line naming the file, the line and the problem.
#[test]
fn bad_input_exits_2_with_one_line() {
    let cases: Vec<(&str, &str, Vec<&str>, &str)> = vec![
        (
            "missing.csv",
            "angle_deg,volts\n0,1\n",
            vec![],
            "missing column 'output'",
        ),
        (
            "nan.csv",
            "angle_deg,output\n0,1\n30,NaN\n",
            vec![],
            ":3: column 'output'",
        ),
        (
            "text.csv",
            "angle_deg,output\n0,1\nthirty,2\n",
            vec![],
            ":3: column 'angle_deg': 'thirty' is not a number",
        ),
        ("empty.csv", "", vec![], "empty file"),
        (
            "few.csv",
            "angle_deg,output\n0,1\n90,2\n180,3\n",
            vec![],
            "distinct angles for 6 terms",
        ),
        (
            "alias.csv",
            "angle_deg,output\n0,1\n30,2\n60,3\n90,4\n120,5\n150,6\n180,7\n210,8\n",
            vec!["--terms", "K0,K1,K2,K_pp"],
            "plan cannot separate",
        ),
        (
            "kip.csv",
            "angle_deg,output\n0,1\n90,2\n180,3\n270,4\n0,1.1\n90,2.1\n180,3.1\n270,4.1\n",
            vec!["--terms", "K0,K1,K_ip"],
            "K_ip",
        ),
    ];
    for (name, content, extra, expect) in cases {
        let f = write(name, content);
        let mut args = vec![
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            f.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let line = stderr_line(&o);
        assert!(line.contains(name), "{name}: {line}");
        assert!(line.contains(expect), "{name}: {line}");
    }
    // Unknown mount and unknown option: usage errors, exit 2, one line.
    let f = write("ok.csv", "angle_deg,output\n0,1\n");
    for args in [
        vec![
            "tumble",
            "--mount",
            "sideways",
            "--input",
            f.to_str().unwrap(),
        ],
        vec![
            "tumble",
            "--mount",
            "gate",
            "--input",
            f.to_str().unwrap(),
            "--frobnicate",
        ],
        vec!["plan", "tumble", "--step-deg", "25"],
    ] {
        let o = run(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        stderr_line(&o);
    }
    // A file that does not exist.
    let o = run(&["tumble", "--mount", "gate", "--input", "/nonexistent/x.csv"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr_line(&o).contains("/nonexistent/x.csv"));
}

#[test]
fn a_declared_output_unit_names_k1_and_its_limits() {
    let csv = simulate(&["--mount", "pendulum", "--seed", "12"]);
    let f = write("output_unit.csv", &csv);
    let o = run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        f.to_str().unwrap(),
        "--output-unit",
        "V",
        "--json",
    ]);
    let v = json_of(&o);
    assert_eq!(v["coefficients"]["K1"]["unit"], "V/g");
    assert_eq!(v["coefficients"]["K0"]["unit"], "g", "not an output unit");
    assert_eq!(v["options"]["output_unit"], "V");
    let cols = v["tables"][0]["columns"].as_array().unwrap();
    assert!(cols.iter().any(|c| c["unit"] == "V"), "{cols:?}");
    assert!(!v.to_string().contains("\"output/g\""));
    // Limits in V/g and in mV/g judge it; one in output/g no longer fits.
    let k1 = v["coefficients"]["K1"]["value"].as_f64().unwrap();
    for (unit, scale) in [("V/g", 1.0), ("mV/g", 1e3)] {
        let l = write(
            &format!("ou_{}.toml", unit.replace('/', "_")),
            &format!(
                "[tumble]\nK1 = {{ min = {}, max = {}, unit = \"{unit}\" }}\n",
                (k1 - 0.01) * scale,
                (k1 + 0.01) * scale
            ),
        );
        let o = run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            f.to_str().unwrap(),
            "--output-unit",
            "V",
            "--limits",
            l.to_str().unwrap(),
            "--json",
        ]);
        let v = json_of(&o);
        assert_eq!(v["verdicts"]["K1"]["verdict"], "pass", "{unit}");
    }
    let l = write(
        "ou_output.toml",
        "[tumble]\nK1 = { min = 0, max = 100, unit = \"output/g\" }\n",
    );
    refused(
        &run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            f.to_str().unwrap(),
            "--output-unit",
            "V",
            "--limits",
            l.to_str().unwrap(),
        ]),
        &["output/g", "V/g"],
    );
    refused(
        &run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            f.to_str().unwrap(),
            "--output-unit",
            "two words",
        ]),
        &["--output-unit"],
    );
}
