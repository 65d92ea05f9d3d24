//! `incal centrifuge` and `incal simulate centrifuge` through the real
//! binary: the JSON contract, bad input (exit 2, one line naming file and
//! line), and reproducible simulation.

use crate::common;
use common::*;

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

fn simulate(extra: &[&str]) -> PathBuf {
    let path = unique("sim.csv");
    let p = path.to_str().unwrap();
    let mut args = vec!["simulate", "centrifuge", "--seed", "3", "--output", p];
    args.extend_from_slice(extra);
    let out = run(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    path
}

fn calibrate_args(path: &str) -> Vec<&str> {
    vec![
        "centrifuge",
        "--input",
        path,
        "--k0",
        "1.2e-4",
        "--k1",
        "1.3",
        "--u-k0",
        "2e-6",
        "--u-k1",
        "1e-6",
        "--radius-m",
        "0.71",
        "--latitude-deg",
        "39.9",
    ]
}

fn assert_value_u(v: &Value) {
    assert_eq!(keys(v), ["u", "value"], "{v}");
    assert!(v["value"].is_f64() && v["u"].is_f64(), "{v}");
}

#[test]
fn good_input_gives_the_contract_json() {
    let path = simulate(&[]);
    let p = path.to_str().unwrap();
    let mut args = calibrate_args(p);
    args.push("--json");
    let out = run(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let radius = &doc["radius"];
    assert_eq!(keys(radius), ["regression", "static"]);
    for kind in ["static", "regression"] {
        assert_eq!(keys(&radius[kind]), ["R_minus_m", "R_plus_m"]);
        for pol in ["R_plus_m", "R_minus_m"] {
            assert_value_u(&radius[kind][pol]);
        }
    }
    let r_plus = radius["regression"]["R_plus_m"]["value"].as_f64().unwrap();
    assert!((r_plus - 0.714775).abs() < 1e-5, "{r_plus}");
    let coef = &doc["coefficients"];
    let mut expect = vec![
        "K2",
        "K3",
        "K_oq",
        "K_pp",
        "K_oo",
        "K_ip",
        "K_io",
        "K_po",
        "R_plus_m",
        "R_minus_m",
        "R_plus_static_m",
        "R_minus_static_m",
        "R_centre_m",
        "ecm_offset_m",
        "tilt_rad",
    ];
    expect.sort();
    assert_eq!(keys(coef), expect);
    // The radii of the "radius" object are the coefficients of the same name.
    assert_eq!(
        coef["R_plus_m"]["value"],
        radius["regression"]["R_plus_m"]["value"]
    );
    assert_eq!(
        coef["R_minus_static_m"]["value"],
        radius["static"]["R_minus_m"]["value"]
    );
    assert_eq!(coef["R_plus_m"]["unit"], "m");
    for name in &expect {
        assert_eq!(
            keys(&coef[name]),
            ["U95", "dof", "k95", "u", "unit", "value"]
        );
    }
    assert_eq!(coef["K2"]["unit"], "g/g^2");
    assert_eq!(coef["K3"]["unit"], "g/g^3");
    let k_ip = coef["K_ip"]["value"].as_f64().unwrap();
    assert!((k_ip - 7e-6).abs() < 5.0 * coef["K_ip"]["u"].as_f64().unwrap());
    assert_eq!(keys(&doc["alignment"]), ["ecm_offset_m"]);
    assert_value_u(&doc["alignment"]["ecm_offset_m"]);
    let r = doc["alignment"]["ecm_offset_m"]["value"].as_f64().unwrap();
    assert!((r - 4.49e-3).abs() < 1e-5, "{r}");
    // The readable report runs too.
    let out = run(&calibrate_args(p));
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("Uncertainty budget of K_ip"));
    let _ = std::fs::remove_file(&path);
}

#[test]
fn simulate_is_reproducible() {
    let a = run(&["simulate", "centrifuge", "--seed", "9"]);
    let b = run(&["simulate", "centrifuge", "--seed", "9"]);
    let c = run(&["simulate", "centrifuge", "--seed", "10"]);
    assert!(a.status.success());
    assert_eq!(a.stdout, b.stdout);
    assert_ne!(a.stdout, c.stdout);
    assert!(String::from_utf8_lossy(&a.stdout)
        .starts_with("plane,phi_deg,polarity,omega_rad_s,output\n"));
}

/// Run the calibration on `text`; expect exit 2 and one stderr line that
/// contains every needle.
fn refused(text: &str, extra: &[&str], needles: &[&str]) {
    let path = unique("bad.csv");
    std::fs::write(&path, text).unwrap();
    let p = path.to_str().unwrap();
    let mut args = calibrate_args(p);
    args.extend_from_slice(extra);
    let out = run(&args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(out.stdout.is_empty());
    for n in needles {
        let n = n.replace("FILE", p);
        assert!(err.contains(&n), "expected '{n}' in: {err}");
    }
    let _ = std::fs::remove_file(&path);
}

const HEADER: &str = "plane,phi_deg,polarity,omega_rad_s,output\n";

#[test]
fn bad_inputs_exit_2_with_one_line() {
    refused(
        "plane,phi_deg,polarity,output\nip,0,1,1.0\n",
        &[],
        &["FILE", "missing column 'omega_rad_s'"],
    );
    refused(
        &format!("{HEADER}ip,0,1,0,1.0\nip,0,1,3.7,NaN\n"),
        &[],
        &["FILE:3:", "not a finite number"],
    );
    refused(
        &format!("{HEADER}ip,0,1,0,1.0\nip,0,1,3.7,1.3\nip,0,1,abc,1.3\n"),
        &[],
        &["FILE:4:", "omega_rad_s", "'abc' is not a number"],
    );
    refused("", &[], &["FILE", "empty file"]);
    refused(
        &format!("{HEADER}ip,0,2,0,1.0\n"),
        &[],
        &["FILE:2:", "polarity"],
    );
    refused(
        &format!("{HEADER}xy,0,1,0,1.0\n"),
        &[],
        &["FILE:2:", "unknown plane 'xy'"],
    );
}

#[test]
fn unseparable_plan_is_refused_by_name() {
    // IA radial, polarity + only: no cross position and no polarity reversal.
    let path = simulate(&["--positions", "ip:0", "--single-polarity"]);
    let text = std::fs::read_to_string(&path).unwrap();
    refused(&text, &["--terms", "K_ip"], &["FILE", "K_ip", "ip,45"]);
    refused(&text, &["--terms", "K2,K_oq"], &["FILE", "K_oq", "polarit"]);
    let _ = std::fs::remove_file(&path);
}

#[test]
fn unknown_option_exits_2() {
    let out = run(&["centrifuge", "--frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("--frobnicate"), "{err}");
}

/// `incal plan centrifuge`: predicted u of every coefficient and radius,
/// and u that shrink as 1/sqrt(samples).
#[test]
fn plan_centrifuge_predicts_u_that_scale_with_samples() {
    let u = |samples: &str| -> serde_json::Value {
        let o = Command::new(env!("CARGO_BIN_EXE_incal"))
            .args(["plan", "centrifuge", "--samples", samples, "--json"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["plan"], "centrifuge");
        v["predicted_u"].clone()
    };
    let (a, b) = (u("4"), u("16"));
    for k in [
        "K2",
        "K3",
        "K_ip",
        "K_oq",
        "R_plus_m",
        "R_minus_static_m",
        "tilt_rad",
    ] {
        let (ua, ub) = (a[k].as_f64().unwrap(), b[k].as_f64().unwrap());
        assert!(ua > 0.0, "{k}");
        assert!((ua / ub - 2.0).abs() < 0.02, "{k}: {ua} / {ub}");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["plan", "centrifuge", "--samples", "1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--samples"));
}
