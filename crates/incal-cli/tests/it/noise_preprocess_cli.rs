//! `incal noise --outliers mad:K --fill gaps --detrend MODEL`: every step
//! recorded (`preprocessing`, its table, the certificate's statement),
//! the numbers those of the clean record, and bad rules refused in one
//! line; a binary record is preprocessed as a CSV one.

use crate::common;
use common::*;
use serde_json::Value;

/// A white record with a linear drift, three spikes and two empty cells:
/// preprocessed, it gives the ARW of the clean record; the audit lists the
/// spikes' and the cells' rows, the drift's slope, and the certificate
/// states it.
#[test]
fn outliers_gaps_and_drift_are_removed_and_recorded() {
    let dir = workdir("preprocess");
    ok(&run_in(
        &dir,
        &[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "4000",
            "--arw-deg-rth",
            "0.5",
            "--seed",
            "5",
            "-o",
            "clean.csv",
        ],
    ));
    let clean = std::fs::read_to_string(dir.join("clean.csv")).unwrap();
    // Drift 1e-4 deg/s per s, spikes at samples 100, 101, 20000, cells
    // 3000 and 3001 empty.
    let mut dirty = String::new();
    for (i, line) in clean.lines().enumerate() {
        if i == 0 {
            dirty.push_str(line);
            dirty.push('\n');
            continue;
        }
        let k = i - 1;
        let (t, v) = line.split_once(',').unwrap();
        let v: f64 = v.parse().unwrap();
        let t_s: f64 = t.parse().unwrap();
        let cell = match k {
            100 | 101 | 20000 => format!("{}", v + 5.0),
            3000 | 3001 => String::new(),
            _ => format!("{}", v + 1e-4 * t_s),
        };
        dirty.push_str(&format!("{t},{cell}\n"));
    }
    std::fs::write(dir.join("dirty.csv"), dirty).unwrap();
    let reduce = |input: &str, extra: &[&str], out: &str| -> Value {
        let mut a = vec![
            "noise",
            "--input",
            input,
            "--quantity",
            "gyro",
            "--json",
            "-o",
            out,
        ];
        a.extend_from_slice(extra);
        ok(&run_in(&dir, &a));
        serde_json::from_str(&std::fs::read_to_string(dir.join(out)).unwrap()).unwrap()
    };
    let c = reduce("clean.csv", &[], "clean.json");
    let d = reduce(
        "dirty.csv",
        &[
            "--outliers",
            "mad:8",
            "--fill",
            "gaps",
            "--detrend",
            "linear",
        ],
        "dirty.json",
    );
    let pre = d["preprocessing"].as_array().expect("preprocessing");
    let steps: Vec<&str> = pre.iter().map(|s| s["step"].as_str().unwrap()).collect();
    assert_eq!(steps, ["outliers", "fill", "detrend"]);
    let ch = c["channels"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    assert_eq!(
        pre[0]["channels"][&ch]["samples"],
        serde_json::json!([[100, 101], [20000, 20000]])
    );
    assert_eq!(
        pre[1]["channels"][&ch]["samples"],
        serde_json::json!([[100, 101], [3000, 3001], [20000, 20000]])
    );
    let slope = pre[2]["channels"][&ch]["coefficients"]["slope_per_s"]
        .as_f64()
        .unwrap();
    assert!((slope - 1e-4).abs() < 1e-5, "slope {slope}");
    assert!(d["tables"]
        .as_array()
        .unwrap()
        .iter()
        .any(|t| t["id"] == "preprocessing"));
    assert_eq!(d["options"]["outliers"], "mad:8");
    assert_eq!(d["options"]["detrend"], "linear");
    // The ARW of the preprocessed record is the clean one's within u.
    let arw = |doc: &Value| {
        let k = format!("{ch}.ARW");
        (
            doc["coefficients"][&k]["value"].as_f64().unwrap(),
            doc["coefficients"][&k]["u"].as_f64().unwrap(),
        )
    };
    let ((a, ua), (b, _)) = (arw(&c), arw(&d));
    assert!(
        (a - b).abs() < 2.0 * ua,
        "ARW {a} clean, {b} preprocessed (u {ua})"
    );
    // Unpreprocessed, the spikes and the drift spoil it.
    let raw = reduce("dirty.csv", &[], "raw.json");
    assert!(raw.get("preprocessing").is_none());
    let (r, _) = arw(&raw);
    assert!(
        r > a + 10.0 * ua,
        "ARW {r} with the spikes against {a} (u {ua})"
    );
    // The certificate says what was done.
    std::fs::write(
        dir.join("lab.toml"),
        "[lab]\nname = \"L\"\naddress = \"A\"\n\n[[signatory]]\nname = \"S\"\nrole = \"R\"\n",
    )
    .unwrap();
    ok(&run_in(
        &dir,
        &["report", "dirty.json", "--lab", "lab.toml", "-o", "c.html"],
    ));
    let html = std::fs::read_to_string(dir.join("c.html")).unwrap();
    assert!(html.contains("Data preprocessing"), "no statement");
    assert!(
        html.contains("3 samples") && html.contains("linear drift"),
        "statement"
    );
}

/// A malformed rule is refused in one line naming the option; a binary
/// record is preprocessed.
#[test]
fn bad_preprocessing_is_refused_in_one_line() {
    let dir = workdir("preprocess-bad");
    ok(&run_in(
        &dir,
        &[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "100",
            "--seed",
            "1",
            "-o",
            "r.csv",
        ],
    ));
    for (rule, needle) in [
        ("mad", "mad:K"),
        ("mad:1", "outliers"),
        ("sigma:3", "mad:K"),
    ] {
        refused(
            &run_in(&dir, &["noise", "--input", "r.csv", "--outliers", rule]),
            &["outliers", needle],
        );
    }
    refused(
        &run_in(&dir, &["noise", "--input", "r.csv", "--detrend", "cubic"]),
        &["cubic"],
    );
    ok(&run_in(
        &dir,
        &[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "100",
            "--seed",
            "1",
            "--format",
            "f32le",
            "-o",
            "r.bin",
        ],
    ));
    // A binary record is read into memory and preprocessed as a CSV one.
    let out = ok(&run_in(
        &dir,
        &[
            "noise",
            "--input",
            "r.bin",
            "--format",
            "f32le",
            "--rate-hz",
            "10",
            "--channels",
            "1",
            "--detrend",
            "linear",
            "--json",
        ],
    ));
    let doc: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(doc["preprocessing"][0]["step"], "detrend");
    assert_eq!(doc["inputs"][0]["rows"], 1000);
}
