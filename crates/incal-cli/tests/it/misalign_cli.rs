//! `incal misalign`, `incal simulate misalign`, `incal plan misalign`: the
//! real binary on temp files. Good input gives the contract JSON; bad input
//! gives exit code 2 and one stderr line naming the file and the line.

use crate::common;
use common::*;

const TABLE1_20: &str = "alpha_deg,beta_deg,rate,output
0,0,20,-0.0614
0,0,-20,0.0654
0,180,20,-0.0576
0,180,-20,0.0606
180,180,20,0.0350
180,180,-20,-0.0306
90,180,20,-0.0290
90,180,-20,0.0287
0,90,20,-0.0600
0,90,-20,0.0638
";

#[test]
fn gyro_json_has_contract_keys_and_paper_numbers() {
    let f = write("t1.csv", TABLE1_20);
    let v = json_of(&run(&[
        "misalign",
        "gyro",
        "--input",
        f.to_str().unwrap(),
        "--scale-factor",
        "-2.9222",
        "--json",
    ]));
    let angles = &v["angles"];
    assert_eq!(
        keys(angles),
        [
            "dtheta_x0",
            "dtheta_y0",
            "dtheta_y1",
            "dtheta_y2",
            "dtheta_z2",
            "gamma"
        ]
    );
    for (name, printed) in [("dtheta_y2", -162.2), ("dtheta_z2", 55.4), ("gamma", 171.4)] {
        let a = &angles[name];
        assert_eq!(keys(a), ["u", "unit", "value"]);
        assert_eq!(a["unit"], "rad");
        let arcsec = a["value"].as_f64().unwrap() * 206_264.806;
        assert!((arcsec - printed).abs() <= 0.05, "{name}: {arcsec}");
        assert!(a["u"].as_f64().unwrap() > 0.0);
    }
    // Readable output shows arcseconds, to the digits the uncertainty
    // supports (u ≈ 2.4″: the paper's −162.17″ and 171.37″ read −162.2″
    // and 171.4″; the JSON above keeps them whole).
    let o = run(&[
        "misalign",
        "gyro",
        "--input",
        f.to_str().unwrap(),
        "--scale-factor",
        "-2.9222",
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("arcsec") && text.contains(" -162.2 ") && text.contains(" 171.4 "),
        "{text}"
    );
}

#[test]
fn accel_json_has_contract_keys() {
    let f = write(
        "t2.csv",
        "beta_deg,output\n0,-0.001845\n180,-0.001911\n90,-0.001912\n270,-0.002175\n",
    );
    let v = json_of(&run(&[
        "misalign",
        "accel",
        "--input",
        f.to_str().unwrap(),
        "--scale-factor",
        "1.299",
        "--json",
    ]));
    assert_eq!(keys(&v["angles"]), ["dtheta_y2", "dtheta_z2", "gamma"]);
    let z2 = v["angles"]["dtheta_z2"]["value"].as_f64().unwrap() * 206_264.806;
    assert!((z2 - 20.9).abs() <= 0.05, "{z2}");
}

#[test]
fn simulate_is_reproducible_and_round_trips() {
    for kind in ["gyro", "accel"] {
        let a = run(&["simulate", "misalign", kind, "--seed", "7"]);
        let b = run(&["simulate", "misalign", kind, "--seed", "7"]);
        let c = run(&["simulate", "misalign", kind, "--seed", "8"]);
        assert!(a.status.success());
        assert_eq!(a.stdout, b.stdout, "{kind}: same seed, same bytes");
        assert_ne!(a.stdout, c.stdout);
        let f = write(
            &format!("sim_{kind}.csv"),
            &String::from_utf8(a.stdout).unwrap(),
        );
        let k = if kind == "gyro" { "-2.9222" } else { "1.299" };
        let v = json_of(&run(&[
            "misalign",
            kind,
            "--input",
            f.to_str().unwrap(),
            "--scale-factor",
            k,
            "--json",
        ]));
        let (g, u) = (
            v["angles"]["gamma"]["value"].as_f64().unwrap(),
            v["angles"]["gamma"]["u"].as_f64().unwrap(),
        );
        let truth = if kind == "gyro" {
            162.2f64.hypot(55.8)
        } else {
            5.3f64.hypot(20.5)
        };
        let k95 = v["coefficients"]["gamma"]["k95"].as_f64().unwrap();
        assert!(
            (g * 206_264.806 - truth).abs() <= k95 * u * 206_264.806 + 1e-9,
            "{kind}"
        );
    }
}

#[test]
fn raw_time_series_is_averaged_and_partial_turns_warned() {
    let o = run(&[
        "simulate",
        "misalign",
        "gyro",
        "--time-series",
        "--turns",
        "2.5",
        "--records",
        "1",
        "--seed",
        "3",
    ]);
    let f = write("raw.csv", &String::from_utf8(o.stdout).unwrap());
    let v = json_of(&run(&[
        "misalign",
        "gyro",
        "--input",
        f.to_str().unwrap(),
        "--scale-factor",
        "-2.9222",
        "--json",
    ]));
    let recs = v["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == "records")
        .expect("records table");
    let cols: Vec<&str> = recs["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["name"].as_str().unwrap())
        .collect();
    let used = cols.iter().position(|c| *c == "turns_used").unwrap();
    let rows = recs["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 30);
    assert_eq!(rows[0][used].as_f64().unwrap().round(), 2.0);
    let w = warnings_with(&v, "partial-turns");
    assert!(w.iter().any(|m| m.contains("not a whole number")), "{w:?}");
}

#[test]
fn bad_inputs_exit_2_with_file_and_line() {
    let k = ["--scale-factor", "-2.9222"];
    let check = |name: &str, text: &str, needles: &[&str]| {
        let f = write(name, text);
        let p = f.to_str().unwrap().to_string();
        let o = run(&["misalign", "gyro", "--input", &p, k[0], k[1]]);
        let mut n: Vec<&str> = needles.to_vec();
        n.push(&p);
        refused(&o, &n);
    };
    check(
        "missing.csv",
        "alpha_deg,beta_deg,output\n0,0,1\n",
        &["missing column 'rate'"],
    );
    check(
        "nan.csv",
        "alpha_deg,beta_deg,rate,output\n0,0,20,1\n0,0,-20,NaN\n",
        &[":3:", "not a finite"],
    );
    check(
        "text.csv",
        "alpha_deg,beta_deg,rate,output\n0,abc,20,1\n",
        &[":2:", "'abc' is not a number"],
    );
    check("empty.csv", "", &["empty file"]);
    // The paper's data without β = 90°: Δθx0 cannot be separated.
    let no_b90: String = TABLE1_20
        .lines()
        .take(9)
        .map(|l| format!("{l}\n"))
        .collect();
    check("unsep.csv", &no_b90, &["cannot separate", "dtheta_x0"]);
    // Accelerometer at two angles only.
    let f = write("acc2.csv", "beta_deg,output\n0,1\n180,2\n");
    refused(
        &run(&[
            "misalign",
            "accel",
            "--input",
            f.to_str().unwrap(),
            "--scale-factor",
            "1.3",
        ]),
        &[f.to_str().unwrap(), "distinct angles beta"],
    );
    // Unknown option.
    refused(&run(&["misalign", "gyro", "--bogus"]), &["--bogus"]);
    // Unseparable plan.
    refused(
        &run(&[
            "plan",
            "misalign",
            "--configs",
            "0:0,0:180,180:180,90:180",
            "--scale-factor",
            "-2.9",
            "--noise",
            "1e-4",
        ]),
        &["dtheta_x0"],
    );
}

#[test]
fn plan_predicts_each_angle() {
    let v = json_of(&run(&[
        "plan",
        "misalign",
        "--scale-factor",
        "-2.9222",
        "--noise",
        "1e-4",
        "--json",
    ]));
    let u = &v["predicted_u"];
    for n in [
        "dtheta_y0",
        "dtheta_x0",
        "dtheta_y1",
        "dtheta_y2",
        "dtheta_z2",
        "gamma",
    ] {
        assert!(u[n].as_f64().unwrap() > 0.0, "{n}");
        assert_eq!(v["units"][n], "rad", "{n}");
    }
    assert_eq!(v["schema"], "incal.plan/1");
    assert_eq!(v["procedure"], "misalign-gyro");
    assert_eq!(v["observations"], 30);
}
