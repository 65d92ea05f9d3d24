//! `incal noise --temperature-bin-c W`: a gyro whose ARW grows with
//! temperature, recorded over a ramp with a `temperature_c` column, gives
//! ARW as a polynomial in temperature (coefficients `ch1.ARW.c0`, `c1`),
//! drawn by `incal report`; the temperature is not analysed as a channel;
//! a record without the column, or a binary one, is refused in one line.

use crate::common;
use common::*;
use serde_json::Value;

/// ARW 1 deg/sqrt(h) simulated at 10 Hz for 8000 s, rescaled sample by
/// sample to 0.5·(1 + 0.005·(T − 25)) over a ramp from −20 to 60 °C.
fn ramp(dir: &std::path::Path) {
    ok(&run_in(
        dir,
        &[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "8000",
            "--arw-deg-rth",
            "1",
            "--seed",
            "7",
            "-o",
            "unit.csv",
        ],
    ));
    let unit = std::fs::read_to_string(dir.join("unit.csv")).unwrap();
    let rows = unit.lines().count() - 1;
    let mut s = String::from("time_s,ch1,temperature_c\n");
    for (i, line) in unit.lines().skip(1).enumerate() {
        let (t, v) = line.split_once(',').unwrap();
        let temp = -20.0 + 80.0 * i as f64 / rows as f64;
        let arw = 0.5 * (1.0 + 0.005 * (temp - 25.0));
        let v: f64 = v.parse().unwrap();
        s.push_str(&format!("{t},{:e},{temp:.3}\n", v * arw));
    }
    std::fs::write(dir.join("ramp.csv"), s).unwrap();
}

#[test]
fn arw_against_temperature_from_one_ramp() {
    let dir = workdir("noise-temperature");
    ramp(&dir);
    ok(&run_in(
        &dir,
        &[
            "noise",
            "--input",
            "ramp.csv",
            "--quantity",
            "gyro",
            "--temperature-bin-c",
            "10",
            "--json",
            "-o",
            "ramp.json",
        ],
    ));
    let doc: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("ramp.json")).unwrap()).unwrap();
    let chans: Vec<&String> = doc["channels"].as_object().unwrap().keys().collect();
    assert_eq!(chans, ["ch1"], "temperature_c is not a channel");
    let c = &doc["coefficients"];
    for (name, want) in [("ch1.ARW.c0", 0.5), ("ch1.ARW.c1", 0.0025)] {
        let (v, u95) = (
            c[name]["value"].as_f64().unwrap(),
            c[name]["U95"].as_f64().unwrap(),
        );
        assert!(
            (v - want).abs() <= u95,
            "{name} = {v} +- {u95}, truth {want}"
        );
    }
    assert_eq!(c["ch1.ARW.c1"]["unit"], "deg/sqrt(h)/degC");
    assert_eq!(
        doc["channels"]["ch1"]["temperature"]["bins"]
            .as_array()
            .unwrap()
            .len(),
        8
    );
    ok(&run_in(&dir, &["report", "ramp.json", "-o", "ramp.html"]));
    let html = std::fs::read_to_string(dir.join("ramp.html")).unwrap();
    assert!(
        html.contains("data-source=\"ch1.ARW\""),
        "ARW against temperature drawn"
    );
}

#[test]
fn bins_need_a_temperature_column_and_a_csv_record() {
    let dir = workdir("noise-temperature-refused");
    ok(&run_in(
        &dir,
        &[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "100",
            "--arw-deg-rth",
            "1",
            "--seed",
            "7",
            "-o",
            "plain.csv",
        ],
    ));
    refused(
        &run_in(
            &dir,
            &["noise", "--input", "plain.csv", "--temperature-bin-c", "5"],
        ),
        &["plain.csv", "no temperature_c column"],
    );
    refused(
        &run_in(
            &dir,
            &["noise", "--input", "plain.csv", "--temperature-bin-c", "0"],
        ),
        &["--temperature-bin-c", "0.01..500"],
    );
    std::fs::write(dir.join("rec.f64"), vec![0u8; 8 * 1000]).unwrap();
    refused(
        &run_in(
            &dir,
            &[
                "noise",
                "--input",
                "rec.f64",
                "--format",
                "f64le",
                "--channels",
                "1",
                "--rate-hz",
                "10",
                "--temperature-bin-c",
                "5",
            ],
        ),
        &["rec.f64", "temperature_c"],
    );
}
