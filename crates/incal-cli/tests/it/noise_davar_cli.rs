//! `incal noise --davar WINDOW_S,STEP_S`: the dynamic Allan variance of a
//! gyro whose white noise doubles half-way is written as a table and a
//! surface, warned about (`non-stationary`) and drawn as a heat map by
//! `incal report`; a steady record is not warned about; windows the record
//! cannot hold are refused in one line.

use crate::common;
use common::*;
use serde_json::Value;

/// Two simulated records, ARW 0.5 then 1 deg/sqrt(h), one after the other
/// (`stepped.csv`), and the first alone (`steady.csv`), 10 Hz, 2000 s each.
fn records(dir: &std::path::Path) {
    for (arw, seed, out) in [("0.5", "1", "a.csv"), ("1.0", "2", "b.csv")] {
        ok(&run_in(
            dir,
            &[
                "simulate",
                "noise",
                "--rate-hz",
                "10",
                "--duration-s",
                "2000",
                "--arw-deg-rth",
                arw,
                "--seed",
                seed,
                "-o",
                out,
            ],
        ));
    }
    let a = std::fs::read_to_string(dir.join("a.csv")).unwrap();
    let b = std::fs::read_to_string(dir.join("b.csv")).unwrap();
    let rows_a = a.lines().count() - 1;
    let mut s = a.clone();
    for line in b.lines().skip(1) {
        let (t, v) = line.split_once(',').unwrap();
        let t: f64 = t.parse().unwrap();
        s.push_str(&format!("{:.1},{v}\n", t + rows_a as f64 / 10.0));
    }
    std::fs::write(dir.join("stepped.csv"), s).unwrap();
    std::fs::write(dir.join("steady.csv"), a).unwrap();
}

fn reduce(dir: &std::path::Path, input: &str, out: &str) -> Value {
    ok(&run_in(
        dir,
        &[
            "noise",
            "--input",
            input,
            "--quantity",
            "gyro",
            "--davar",
            "400,200",
            "--json",
            "-o",
            out,
        ],
    ));
    serde_json::from_str(&std::fs::read_to_string(dir.join(out)).unwrap()).unwrap()
}

#[test]
fn a_noise_that_doubles_is_warned_about_tabled_and_drawn() {
    let dir = workdir("davar");
    records(&dir);
    let doc = reduce(&dir, "stepped.csv", "stepped.json");
    let ch = doc["channels"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    let d = &doc["channels"][&ch]["davar"];
    assert_eq!(d["window_samples"], 4000);
    assert_eq!(d["step_samples"], 2000);
    assert_eq!(d["windows"], 19);
    assert_eq!(d["test"]["non_stationary"], true);
    let w = warnings_with(&doc, "non-stationary");
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with(&format!("{ch}: the noise changes")),
        "{}",
        w[0]
    );
    let table = doc["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == format!("davar.{ch}"))
        .expect("the davar table");
    let taus = d["taus_s"].as_array().unwrap().len();
    assert_eq!(table["rows"].as_array().unwrap().len(), 19 * taus);
    // The first window's ADEV at 0.1 s is the first ARW's, the last the
    // second's: 0.5 and 1 deg/sqrt(h) over sqrt(0.1 s).
    let at = |k: usize| d["adev"][k][0].as_f64().unwrap();
    let want = |arw: f64| arw / 60.0 / 0.1f64.sqrt();
    assert!((at(0) / want(0.5) - 1.0).abs() < 0.1, "{}", at(0));
    assert!((at(18) / want(1.0) - 1.0).abs() < 0.1, "{}", at(18));
    ok(&run_in(
        &dir,
        &["report", "stepped.json", "-o", "stepped.html"],
    ));
    let html = std::fs::read_to_string(dir.join("stepped.html")).unwrap();
    assert!(
        html.contains("data-plot=\"davar\""),
        "a heat map in the report"
    );
    assert!(html.contains("dynamic Allan deviation"));

    let calm = reduce(&dir, "steady.csv", "steady.json");
    assert!(warnings_with(&calm, "non-stationary").is_empty());
    assert_eq!(
        calm["channels"][&ch]["davar"]["test"]["non_stationary"],
        false
    );
}

#[test]
fn windows_the_record_cannot_hold_are_refused() {
    let dir = workdir("davar-refused");
    records(&dir);
    for (spec, says) in [
        ("400", "WINDOW_S,STEP_S"),
        ("0,10", "two positive numbers"),
        ("5000,100", "longer than the record"),
        ("100,0.1", "take a longer step"),
    ] {
        refused(
            &run_in(
                &dir,
                &["noise", "--input", "steady.csv", "--davar", spec, "--json"],
            ),
            &["davar", says],
        );
    }
}
