//! `incal noise --psd` lines from outside: `simulate noise --tone` adds
//! one, the document lists it (`psd.tones`, table `tones.ch1`, warning
//! `tones`) with its frequency and rms amplitude within U95, the report
//! marks it, and bad settings exit 2 naming the option.

use crate::common;
use common::*;

#[test]
fn a_simulated_line_is_listed_warned_and_marked() {
    let dir = workdir("noise_tones");
    let csv = dir.join("n.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--rate-hz",
        "200",
        "--duration-s",
        "600",
        "--arw-deg-rth",
        "0.3",
        "--bias-instability-deg-h",
        "10",
        "--tone",
        "37:0.01",
        "--seed",
        "5",
        "--output",
        p(&csv),
    ]));
    let json = dir.join("n.json");
    ok(&run(&[
        "noise",
        "--input",
        p(&csv),
        "--quantity",
        "gyro",
        "--psd",
        "--json",
        "--output",
        p(&json),
    ]));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let psd = &v["channels"]["ch1"]["psd"];
    assert_eq!(psd["tone_search"]["false_alarm"], 0.01);
    let tones = psd["tones"].as_array().unwrap();
    assert_eq!(tones.len(), 1, "{tones:?}");
    let t = &tones[0];
    let k = t["k95"].as_f64().unwrap();
    let f = t["frequency_hz"].as_f64().unwrap();
    assert!(
        (f - 37.0).abs() <= k * t["u_frequency_hz"].as_f64().unwrap(),
        "{t}"
    );
    let a = t["amplitude_rms"].as_f64().unwrap();
    assert!(
        (a - 0.01).abs() <= k * t["u_amplitude_rms"].as_f64().unwrap(),
        "{t}"
    );
    let table = v["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == "tones.ch1")
        .expect("table tones.ch1");
    assert_eq!(table["rows"].as_array().unwrap().len(), 1);
    assert!(v["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w["code"] == "tones"));
    let html = dir.join("n.html");
    ok(&run(&["report", p(&json), "--output", p(&html)]));
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("lines above the noise floor (1)"));
    // Bad settings are named.
    refused(
        &run(&[
            "noise",
            "--input",
            p(&csv),
            "--psd",
            "--psd-false-alarm",
            "0",
        ]),
        &["--psd-false-alarm"],
    );
    for bad in ["37", "x:1", "150:0.01"] {
        refused(
            &run(&[
                "simulate",
                "noise",
                "--rate-hz",
                "200",
                "--duration-s",
                "10",
                "--tone",
                bad,
                "--seed",
                "1",
                "--output",
                p(&dir.join("bad.csv")),
            ]),
            &["tone"],
        );
    }
}

#[test]
fn a_gauss_markov_bias_is_fitted_with_its_discrete_form() {
    let dir = workdir("noise_gm");
    let csv = dir.join("gm.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--arw-deg-rth",
        "0.6",
        "--gm-sigma",
        "0.01",
        "--gm-tau-s",
        "100",
        "--rate-hz",
        "100",
        "--duration-s",
        "7200",
        "--seed",
        "4",
        "--output",
        p(&csv),
    ]));
    let json = dir.join("gm.json");
    ok(&run(&[
        "noise",
        "--input",
        p(&csv),
        "--quantity",
        "gyro",
        "--gauss-markov",
        "--gm-filter-rate-hz",
        "200",
        "--json",
        "--output",
        p(&json),
    ]));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let g = &v["channels"]["ch1"]["gauss_markov"];
    assert_eq!(g["supported"], true, "{g}");
    let c = &v["coefficients"];
    for (name, truth) in [("ch1.gm_sigma", 0.01), ("ch1.gm_tau_c_s", 100.0)] {
        let (val, u95) = (
            c[name]["value"].as_f64().unwrap(),
            c[name]["U95"].as_f64().unwrap(),
        );
        assert!((val - truth).abs() <= u95, "{name}: {val} +- {u95}");
    }
    assert_eq!(c["ch1.gm_tau_c_s"]["unit"], "s");
    // The discrete form at 200 Hz: phi = exp(-1/(200 T)), q_d = sigma sqrt(1 - phi^2).
    let (s, t) = (g["sigma"].as_f64().unwrap(), g["tau_c_s"].as_f64().unwrap());
    let phi = (-1.0 / (200.0 * t)).exp();
    assert!((g["phi"].as_f64().unwrap() - phi).abs() < 1e-12);
    let qd = s * (1.0 - phi * phi).sqrt();
    assert!((g["q_d"].as_f64().unwrap() / qd - 1.0).abs() < 1e-9);
    assert!((g["q_c"].as_f64().unwrap() / (s * (2.0 / t).sqrt()) - 1.0).abs() < 1e-9);
    // White noise alone: no bias claimed, and the warning says why.
    let white = dir.join("w.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--arw-deg-rth",
        "0.6",
        "--rate-hz",
        "100",
        "--duration-s",
        "600",
        "--seed",
        "4",
        "--output",
        p(&white),
    ]));
    let w = ok(&run(&[
        "noise",
        "--input",
        p(&white),
        "--quantity",
        "gyro",
        "--gauss-markov",
    ]));
    assert!(!w.contains("gm_sigma"), "{w}");
    assert!(w.contains("no Gauss-Markov bias reported"), "{w}");
    refused(
        &run(&[
            "noise",
            "--input",
            p(&white),
            "--gauss-markov",
            "--gm-filter-rate-hz",
            "0",
        ]),
        &["--gm-filter-rate-hz"],
    );
    refused(
        &run(&[
            "simulate",
            "noise",
            "--gm-sigma",
            "0.01",
            "--rate-hz",
            "100",
            "--duration-s",
            "10",
            "--seed",
            "1",
            "--output",
            p(&dir.join("bad.csv")),
        ]),
        &["gm"],
    );
}
