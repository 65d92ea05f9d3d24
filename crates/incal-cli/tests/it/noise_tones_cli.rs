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
