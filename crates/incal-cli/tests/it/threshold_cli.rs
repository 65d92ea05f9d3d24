//! `incal threshold`, `incal plan threshold` and `incal simulate
//! threshold` from outside: the contract keys and units, limits by name,
//! an accelerometer's tilt file, and bad input refused in one line naming
//! the file, the line or the option.

use crate::common;

use common::*;

fn small(dir: &std::path::Path, extra: &[&str]) -> std::path::PathBuf {
    let csv = dir.join("threshold.csv");
    let mut args = vec![
        "simulate",
        "threshold",
        "--dwell-s",
        "10",
        "--seed",
        "5",
        "-o",
        p(&csv),
    ];
    args.extend_from_slice(extra);
    ok(&run(&args));
    csv
}

#[test]
fn a_simulated_threshold_test_reduces_to_the_contract() {
    let dir = workdir("threshold_contract");
    let csv = small(&dir, &[]);
    let limits = dir.join("limits.toml");
    std::fs::write(
        &limits,
        "[threshold]\nthreshold_deg_s = { max = 0.005 }\nresolution_deg_s = { max = 0.01 }\n",
    )
    .unwrap();
    let v = json_of(&run(&[
        "threshold",
        "--input",
        p(&csv),
        "--json",
        "--limits",
        p(&limits),
    ]));
    assert_eq!(v["procedure"], "threshold");
    for (name, unit) in [
        ("threshold_deg_s", "deg/s"),
        ("resolution_deg_s", "deg/s"),
        ("K1", "output/(deg/s)"),
    ] {
        assert_eq!(v["coefficients"][name]["unit"], unit, "{name}");
    }
    let t = v["coefficients"]["threshold_deg_s"]["value"]
        .as_f64()
        .unwrap();
    assert!((0.006..=0.010).contains(&t), "threshold {t}");
    assert_eq!(v["threshold"]["sensor"], "gyro");
    assert_eq!(v["threshold"]["base_input"], 10.0);
    assert_eq!(v["threshold"]["scale_factor"]["source"], "measured");
    assert_eq!(
        v["verdict"], "fail",
        "threshold over its limit of 0.005 deg/s"
    );
    let s = serde_json::to_string(&v["verdicts"]).unwrap();
    assert!(s.contains("threshold_deg_s"), "{s}");
    let plan = json_of(&run(&["plan", "threshold", "--dwell-s", "10", "--json"]));
    assert!(plan["predicted_u"]["threshold_deg_s"].as_f64().unwrap() > 0.0);
}

#[test]
fn an_accelerometer_on_a_dividing_head_reports_in_g() {
    let dir = workdir("threshold_accel");
    let csv = small(&dir, &["--sensor", "accel"]);
    let head = std::fs::read_to_string(&csv).unwrap();
    assert!(
        head.starts_with("time_s,tilt_deg,output"),
        "{}",
        &head[..40]
    );
    let v = json_of(&run(&["threshold", "--input", p(&csv), "--json"]));
    assert_eq!(v["coefficients"]["threshold_g"]["unit"], "g");
    assert_eq!(v["coefficients"]["resolution_g"]["unit"], "g");
    assert_eq!(v["threshold"]["base_input"], 30.0);
    let t = v["coefficients"]["threshold_g"]["value"].as_f64().unwrap();
    assert!((1e-5..=4e-5).contains(&t), "threshold {t} g");
}

#[test]
fn bad_input_is_refused_in_one_line() {
    let dir = workdir("threshold_bad");
    let f = |name: &str, text: &str| {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    let none = f("none.csv", "time_s,output\n0,1\n");
    refused(
        &run(&["threshold", "--input", p(&none)]),
        &["none.csv", "rate_deg_s", "tilt_deg"],
    );
    let text = f(
        "text.csv",
        "rate_deg_s,output\n0,1\n0,abc\n0,1\n0,1\n0,1\n0,1\n0,1\n0,1\n0,1\n",
    );
    refused(
        &run(&["threshold", "--input", p(&text)]),
        &["text.csv:3", "output", "not a number"],
    );
    let csv = small(&dir, &[]);
    refused(
        &run(&["threshold", "--input", p(&csv), "--base-input", "7"]),
        &["base-input", "no plateau"],
    );
    refused(
        &run(&["threshold", "--input", p(&csv), "--test-level", "0.9"]),
        &["test-level"],
    );
    let wide = small(&dir, &["--dead-band", "1e-5"]);
    refused(
        &run(&["threshold", "--input", p(&wide)]),
        &["every step at zero passes", "smaller steps"],
    );
    let one = small(&dir, &["--steps", "0.01"]);
    refused(&run(&["threshold", "--input", p(&one)]), &["one size"]);
    let zero = small(&dir, &["--base-input", "0"]);
    refused(&run(&["threshold", "--input", p(&zero)]), &["scale-factor"]);
    refused(
        &run(&["plan", "threshold", "--steps", "0.01,0.02,0.05"]),
        &["steps", "bracket"],
    );
    refused(
        &run(&["simulate", "threshold", "--dwell-s", "0.1"]),
        &["dwell-s"],
    );
}
