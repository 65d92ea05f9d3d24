//! `incal gyro rate|positions`, `incal plan gyro-rate|gyro-positions`,
//! `incal simulate gyro-rate|gyro-positions`: the real binary on temp
//! files. Contract JSON keys and units; bad input exits 2 with one line.

use crate::common;
use common::*;

use std::path::PathBuf;

fn unit(v: &serde_json::Value, name: &str) -> String {
    v["coefficients"][name]["unit"]
        .as_str()
        .unwrap()
        .to_string()
}

fn simulate_rate(name: &str, extra: &[&str]) -> PathBuf {
    let p = tmp(name);
    let mut args = vec!["simulate", "gyro-rate", "-o", p.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    p
}

#[test]
fn rate_json_has_contract_keys_units_and_recovers_truth() {
    let p = simulate_rate(
        "r1.csv",
        &[
            "--k2",
            "2e-5",
            "--k3",
            "-1e-7",
            "--b-deg-h",
            "5",
            "--seed",
            "3",
        ],
    );
    let v = json_of(&run(&[
        "gyro",
        "rate",
        "--input",
        p.to_str().unwrap(),
        "--latitude-deg",
        "45",
        "--terms",
        "K1,B,K2,K3",
        "--json",
    ]));
    assert_eq!(v["procedure"], "gyro-rate");
    assert_eq!(unit(&v, "K1"), "output/(deg/s)");
    assert_eq!(unit(&v, "B"), "deg/h");
    assert_eq!(unit(&v, "K2"), "1/(deg/s)");
    assert_eq!(unit(&v, "K3"), "1/(deg/s)^2");
    assert_eq!(unit(&v, "asymmetry"), "ppm");
    assert!(v["nonlinearity_ppm_fs"].as_f64().unwrap() > 0.0);
    for (n, t) in [
        ("K1", 0.02),
        ("B", 5.0),
        ("K2", 2e-5),
        ("K3", -1e-7),
        ("asymmetry", 0.0),
    ] {
        let c = &v["coefficients"][n];
        let (val, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
        assert!(
            (val - t).abs() <= 1.5 * u95,
            "{n}: {val} vs {t} (U95 {u95})"
        );
    }
    // Default terms: K1 and B only.
    let v = json_of(&run(&[
        "gyro",
        "rate",
        "--input",
        p.to_str().unwrap(),
        "--latitude-deg",
        "45",
        "--json",
    ]));
    assert!(v["coefficients"].get("K2").is_none() && v["coefficients"].get("K1").is_some());
}

#[test]
fn rate_runs_and_type_b() {
    let p = simulate_rate("r2.csv", &["--runs", "3", "--run-scatter-ppm", "50"]);
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.starts_with("rate_deg_s,output,run\n"));
    let args = |ppm: &'static str| {
        vec![
            "gyro".to_string(),
            "rate".into(),
            "--input".into(),
            p.to_str().unwrap().into(),
            "--latitude-deg".into(),
            "45".into(),
            "--json".into(),
            "--rate-uncertainty-ppm".into(),
            ppm.into(),
        ]
    };
    let a: Vec<String> = args("0");
    let v0 = json_of(&bin().args(&a).output().unwrap());
    let rep = &v0["scale_factor_repeatability"];
    assert_eq!(rep["unit"], "ppm");
    assert_eq!(rep["dof"], 2.0);
    assert_eq!(rep["runs"], 3);
    let b: Vec<String> = args("100");
    let v1 = json_of(&bin().args(&b).output().unwrap());
    let (u0, u1) = (
        v0["coefficients"]["K1"]["u"].as_f64().unwrap(),
        v1["coefficients"]["K1"]["u"].as_f64().unwrap(),
    );
    let k1 = v0["coefficients"]["K1"]["value"].as_f64().unwrap();
    // u²(K1) grows by (K1 · 100 ppm)², exactly.
    let expect = (u0 * u0 + (k1 * 100e-6).powi(2)).sqrt();
    assert!((u1 - expect).abs() < 1e-9 * expect, "{u1} vs {expect}");
}

#[test]
fn positions_json_contract_from_rate_result_and_fit_k1() {
    let r = simulate_rate("r3.csv", &[]);
    let rj = tmp("r3.json");
    let o = run(&[
        "gyro",
        "rate",
        "--input",
        r.to_str().unwrap(),
        "--latitude-deg",
        "45",
        "--json",
        "-o",
        rj.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let p = tmp("p1.csv");
    assert!(run(&[
        "simulate",
        "gyro-positions",
        "--latitude-deg",
        "30",
        "--azimuths-deg",
        "60",
        "--axial",
        "oa",
        "-o",
        p.to_str().unwrap(),
    ])
    .status
    .success());
    let v = json_of(&run(&[
        "gyro",
        "positions",
        "--input",
        p.to_str().unwrap(),
        "--latitude-deg",
        "30",
        "--azimuth-deg",
        "60",
        "--axial",
        "oa",
        "--from",
        rj.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(v["procedure"], "gyro-positions");
    assert_eq!(unit(&v, "B"), "deg/h");
    assert_eq!(unit(&v, "D_I"), "deg/h/g");
    assert_eq!(unit(&v, "D_S"), "deg/h/g");
    assert!(v["coefficients"].get("D_O").is_none());
    assert_eq!(v["inputs"][1]["role"], "from");
    // Second-order terms have their unit.
    let v = json_of(&run(&[
        "gyro",
        "positions",
        "--input",
        p.to_str().unwrap(),
        "--latitude-deg",
        "30",
        "--azimuth-deg",
        "60",
        "--axial",
        "oa",
        "--k1",
        "0.02",
        "--u-k1",
        "1e-6",
        "--terms",
        "B,D_I,D_S,D_IS",
        "--json",
    ]));
    assert_eq!(unit(&v, "D_IS"), "deg/h/g^2");
    // K1 fitted from two azimuths in one file (azimuth_deg column).
    let p2 = tmp("p2.csv");
    assert!(run(&[
        "simulate",
        "gyro-positions",
        "--latitude-deg",
        "45",
        "--azimuths-deg",
        "90,270",
        "--samples",
        "50",
        "--noise",
        "2e-6",
        "-o",
        p2.to_str().unwrap(),
    ])
    .status
    .success());
    let v = json_of(&run(&[
        "gyro",
        "positions",
        "--input",
        p2.to_str().unwrap(),
        "--latitude-deg",
        "45",
        "--axial",
        "sa",
        "--fit-k1",
        "--json",
    ]));
    let k1 = &v["coefficients"]["K1"];
    assert!((k1["value"].as_f64().unwrap() - 0.02).abs() <= k1["U95"].as_f64().unwrap());
}

#[test]
fn positions_refusals_name_the_terms() {
    let p = tmp("p3.csv");
    assert!(
        run(&["simulate", "gyro-positions", "-o", p.to_str().unwrap()])
            .status
            .success()
    );
    let f = p.to_str().unwrap();
    refused(
        &run(&[
            "gyro",
            "positions",
            "--input",
            f,
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "0",
            "--axial",
            "sa",
            "--k1",
            "0.02",
            "--terms",
            "B,D_I,D_O,D_II,D_OO",
        ]),
        &["p3.csv", "cannot separate", "B", "D_II", "D_OO"],
    );
    refused(
        &run(&[
            "gyro",
            "positions",
            "--input",
            f,
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "0",
            "--axial",
            "sa",
            "--fit-k1",
        ]),
        // Azimuth 0: the Earth-rate projection is Ω_e sin φ sin θ, the D_I regressor.
        &["cannot separate", "K1", "D_I"],
    );
    refused(
        &run(&[
            "gyro",
            "positions",
            "--input",
            f,
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "0",
            "--axial",
            "sa",
        ]),
        &["--k1", "--from", "--fit-k1"],
    );
    refused(
        &run(&[
            "gyro",
            "positions",
            "--input",
            f,
            "--latitude-deg",
            "95",
            "--azimuth-deg",
            "0",
            "--axial",
            "sa",
            "--k1",
            "1",
        ]),
        &["--latitude-deg", "95"],
    );
    // --from needs a gyro-rate result.
    let t = tmp("tumble.csv");
    assert!(run(&["simulate", "tumble", "-o", t.to_str().unwrap()])
        .status
        .success());
    let tj = tmp("tumble.json");
    assert!(run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        t.to_str().unwrap(),
        "--json",
        "-o",
        tj.to_str().unwrap(),
    ])
    .status
    .success());
    refused(
        &run(&[
            "gyro",
            "positions",
            "--input",
            f,
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "0",
            "--axial",
            "sa",
            "--from",
            tj.to_str().unwrap(),
        ]),
        &["tumble.json", "gyro-rate"],
    );
}

#[test]
fn bad_rate_input_is_refused_with_file_and_line() {
    let f = write("bad1.csv", "rate_deg_s,output\n10,0.2\n-10,nan\n");
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
        ]),
        &["bad1.csv", ":3"],
    );
    let f = write("bad2.csv", "rate,output\n10,0.2\n");
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
        ]),
        &["bad2.csv", "rate_deg_s"],
    );
    let f = write("bad3.csv", "rate_deg_s,output\n10,0.2\n10,0.2001\n");
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
        ]),
        &["bad3.csv", "distinct table rates"],
    );
    let f = write("bad4.csv", "rate_deg_s,output,run\n10,0.2,a\n-10,-0.2,\n");
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
        ]),
        &["bad4.csv", ":3", "run"],
    );
    let f = write("bad5.csv", "rate_deg_s,output\n10,0.2\n-10,-0.2\n");
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
            "--terms",
            "K1,K7",
        ]),
        &["--terms", "K7"],
    );
    // Constant output: the scale factor is not observable.
    let f = write(
        "bad6.csv",
        "rate_deg_s,output\n10,0.2\n10,0.2\n-10,0.2\n-10,0.2\n",
    );
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            f.to_str().unwrap(),
            "--latitude-deg",
            "0",
        ]),
        &["bad6.csv", "every row", "scale factor is not observable"],
    );
}

#[test]
fn plans_predict_and_refuse() {
    let o = run(&[
        "plan",
        "gyro-rate",
        "--rates-deg-s",
        "-100,-50,-10,10,50,100",
        "--samples",
        "20",
        "--noise",
        "2e-5",
        "--k1",
        "0.02",
        "--terms",
        "K1,B,K2",
        "--json",
    ]);
    let v = json_of(&o);
    for n in ["K1", "B", "K2", "asymmetry"] {
        assert!(v["predicted_u"][n].as_f64().unwrap() > 0.0, "{n}");
    }
    assert_eq!(v["units"]["B"], "deg/h");
    let v = json_of(&run(&[
        "plan",
        "gyro-positions",
        "--latitude-deg",
        "45",
        "--k1",
        "0.02",
        "--noise",
        "2e-5",
        "--samples",
        "10",
        "--json",
    ]));
    for n in ["B", "D_I", "D_O"] {
        assert!(v["predicted_u"][n].as_f64().unwrap() > 0.0, "{n}");
    }
    refused(
        &run(&[
            "plan",
            "gyro-positions",
            "--latitude-deg",
            "45",
            "--k1",
            "0.02",
            "--noise",
            "2e-5",
            "--terms",
            "B,D_II,D_OO",
        ]),
        &["cannot separate", "B", "D_II", "D_OO"],
    );
    refused(
        &run(&[
            "plan",
            "gyro-rate",
            "--rates-deg-s",
            "10",
            "--noise",
            "1e-5",
            "--k1",
            "1",
        ]),
        &["distinct table rates"],
    );
}

#[test]
fn simulators_refuse_sizes_and_nonsense() {
    refused(
        &run(&["simulate", "gyro-rate", "--samples", "1000000000"]),
        &["10000000"],
    );
    refused(&run(&["simulate", "gyro-rate", "--k1", "0"]), &["k1"]);
    refused(
        &run(&["simulate", "gyro-positions", "--latitude-deg", "-91"]),
        &["--latitude-deg"],
    );
    refused(
        &run(&["simulate", "gyro-positions", "--b-deg-h", "1e300"]),
        &["B"],
    );
}

#[test]
fn the_input_range_and_clipped_rates_reach_the_document() {
    let csv = simulate_rate(
        "gyro_range",
        &[
            "--rates-deg-s=-500,-400,-300,-200,-100,-50,-10,10,50,100,200,300,400,500",
            "--k3",
            "1e-8",
            "--clip",
            "9",
        ],
    );
    let v = json_of(&run(&[
        "gyro",
        "rate",
        "--input",
        p(&csv),
        "--latitude-deg",
        "45",
        "--linearity-ppm",
        "300",
        "--json",
    ]));
    assert_eq!(v["coefficients"]["input_range_deg_s"]["value"], 300.0);
    assert_eq!(unit(&v, "input_range_deg_s"), "deg/s");
    assert_eq!(
        v["input_range"]["clipped_deg_s"],
        serde_json::json!([-500.0, 500.0])
    );
    assert_eq!(
        v["input_range"]["beyond_deg_s"],
        serde_json::json!([-400.0, 400.0])
    );
    assert_eq!(v["options"]["linearity_ppm"], 300.0);
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            p(&csv),
            "--latitude-deg",
            "45",
            "--linearity-ppm",
            "-1",
        ]),
        &["linearity-ppm"],
    );
    refused(
        &run(&[
            "gyro",
            "rate",
            "--input",
            p(&csv),
            "--latitude-deg",
            "45",
            "--output-limit",
            "0",
        ]),
        &["output-limit"],
    );
}
