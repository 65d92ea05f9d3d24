//! `incal sensitivity`, `plan sensitivity`, `simulate sensitivity` from the
//! command line: the documents of the three kinds against the simulator's
//! truth, the refusals (exit 2, one line naming the file, line or term),
//! the plan, and the rig on the certificate.

use crate::common::{json_of, ok, refused, run_in, workdir};

fn within(doc: &serde_json::Value, truth: &serde_json::Value, factor: f64) {
    for (name, t) in truth.as_object().unwrap() {
        let c = &doc["coefficients"][name];
        let (v, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
        let t = t.as_f64().unwrap();
        assert!(
            (v - t).abs() < factor * u95,
            "{name}: {v} against {t} (U95 {u95})"
        );
    }
}

fn read(d: &std::path::Path, f: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(d.join(f)).unwrap()).unwrap()
}

#[test]
fn the_three_kinds_reduce_to_their_truth() {
    let d = workdir("sensitivity_cli_kinds");
    let cases: [(&[&str], &[&str]); 3] = [
        (
            &[
                "--angles-deg",
                "0,45,-45",
                "--interleave",
                "--run-s",
                "10",
                "--rate-hz",
                "20",
            ],
            &[],
        ),
        (
            &[
                "--kind",
                "magnetic",
                "--sensor",
                "gyro",
                "--interleave",
                "--run-s",
                "20",
                "--rate-hz",
                "20",
                "--levels=-2,0,2",
            ],
            &[
                "--sensor",
                "gyro",
                "--output-columns",
                "output_x,output_y,output_z",
            ],
        ),
        (
            &[
                "--kind",
                "shock",
                "--inputs=-1,1",
                "--sf-shifts-ppm",
                "150,-80",
                "--run-s",
                "10",
                "--rate-hz",
                "20",
            ],
            &[],
        ),
    ];
    for (k, (sim, red)) in cases.iter().enumerate() {
        let csv = format!("s{k}.csv");
        let truth = format!("t{k}.json");
        let mut args = vec![
            "simulate",
            "sensitivity",
            "--seed",
            "7",
            "-o",
            &csv,
            "--truth-out",
            &truth,
        ];
        args.extend_from_slice(sim);
        ok(&run_in(&d, &args));
        let mut args = vec!["sensitivity", "--input", &csv, "--json"];
        args.extend_from_slice(red);
        let doc = json_of(&run_in(&d, &args));
        assert_eq!(doc["procedure"], "sensitivity");
        within(&doc, &read(&d, &truth), 2.0);
    }
    let doc = json_of(&run_in(&d, &["sensitivity", "--input", "s2.csv", "--json"]));
    assert_eq!(doc["options"]["rig"], "shock-machine");
    let shock = doc["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == "shock")
        .expect("shock table");
    assert_eq!(shock["rows"].as_array().unwrap().len(), 4);
}

#[test]
fn runs_without_a_label_or_at_one_level_are_refused_in_one_line() {
    let d = workdir("sensitivity_cli_refusals");
    std::fs::write(
        d.join("nolabel.csv"),
        "time_s,run,vib_g,output\n0,a,0,1\n0.1,a,0,1.1\n0.2,b,,1.2\n",
    )
    .unwrap();
    refused(
        &run_in(
            &d,
            &["sensitivity", "--input", "nolabel.csv", "--rate-hz", "10"],
        ),
        &[
            "nolabel.csv:4",
            "vib_g",
            "run 'b' without its stimulus label",
        ],
    );
    std::fs::write(
        d.join("again.csv"),
        "time_s,run,shock_g,output\n0,a,0,1\n0.1,b,50,1\n0.2,a,0,1\n",
    )
    .unwrap();
    refused(
        &run_in(&d, &["sensitivity", "--input", "again.csv"]),
        &["again.csv:4", "run 'a' again"],
    );
    std::fs::write(d.join("none.csv"), "time_s,run,output\n0,a,1\n").unwrap();
    refused(
        &run_in(&d, &["sensitivity", "--input", "none.csv"]),
        &["none.csv", "no stimulus column"],
    );
    ok(&run_in(
        &d,
        &[
            "simulate",
            "sensitivity",
            "--levels",
            "3",
            "--run-s",
            "2",
            "--rate-hz",
            "20",
            "-o",
            "one.csv",
        ],
    ));
    refused(
        &run_in(&d, &["sensitivity", "--input", "one.csv"]),
        &["one.csv", "single stimulus level", "vib_g = 3"],
    );
    refused(
        &run_in(
            &d,
            &["sensitivity", "--input", "one.csv", "--unit", "furlong"],
        ),
        &["unit", "furlong"],
    );
}

#[test]
fn the_plan_names_what_the_runs_cannot_separate() {
    let d = workdir("sensitivity_cli_plan");
    let doc = json_of(&run_in(
        &d,
        &["plan", "sensitivity", "--angles-deg", "0,45,-45", "--json"],
    ));
    for t in ["vrc", "vibropendulous", "vrc_pendulous"] {
        assert!(doc["predicted_u"][t].as_f64().unwrap() > 0.0, "{t}");
    }
    refused(
        &run_in(&d, &["plan", "sensitivity", "--angles-deg", "45,-45"]),
        &["vrc", "vrc_pendulous"],
    );
}

#[test]
fn the_certificate_traces_the_rig_of_the_kind() {
    let d = workdir("sensitivity_cli_rig");
    std::fs::write(
        d.join("lab.toml"),
        "[lab]\nname = \"L\"\naddress = \"A\"\naccreditation = \"C\"\ncertificate_prefix = \"X-\"\n\n[[signatory]]\nname = \"S\"\nrole = \"R\"\n\n[[standard]]\nrig = \"helmholtz-coil\"\nid = \"Coil HC-3 and magnetometer FG-1\"\ncertificate = \"NIM-7\"\ndue = \"2030-01-01\"\n\n[[standard]]\nrig = \"shaker\"\nid = \"Reference accelerometer RA-9\"\ncertificate = \"NIM-1\"\ndue = \"2030-01-01\"\n",
    )
    .unwrap();
    ok(&run_in(
        &d,
        &[
            "simulate",
            "sensitivity",
            "--kind",
            "magnetic",
            "--outputs",
            "1",
            "--run-s",
            "5",
            "--rate-hz",
            "20",
            "-o",
            "m.csv",
        ],
    ));
    ok(&run_in(
        &d,
        &[
            "sensitivity",
            "--input",
            "m.csv",
            "--json",
            "-o",
            "m.json",
            "--serial",
            "SN-1",
        ],
    ));
    assert_eq!(read(&d, "m.json")["options"]["rig"], "helmholtz-coil");
    ok(&run_in(
        &d,
        &["report", "m.json", "--lab", "lab.toml", "-o", "c.html"],
    ));
    let h = std::fs::read_to_string(d.join("c.html")).unwrap();
    assert!(h.contains("HC-3") && !h.contains("RA-9"), "the coil traced");
}

#[test]
fn unusual_sessions_are_reduced_or_refused_by_name() {
    let d = workdir("sensitivity_cli_unusual");
    // Runs along the input and the pendulous axes only: no vibropendulous
    // term (cos 90° is not zero in floating point, but no term).
    ok(&run_in(
        &d,
        &[
            "simulate",
            "sensitivity",
            "--angles-deg",
            "0,90",
            "--run-s",
            "5",
            "--rate-hz",
            "20",
            "-o",
            "a.csv",
            "--truth-out",
            "t.json",
        ],
    ));
    let doc = json_of(&run_in(&d, &["sensitivity", "--input", "a.csv", "--json"]));
    assert!(doc["coefficients"]["vrc"].is_object());
    assert!(doc["coefficients"]["vrc_pendulous"].is_object());
    assert!(doc["coefficients"]["vibropendulous"].is_null());
    // A negative level, a rate that disagrees with time_s, a run sampled
    // at another rate.
    std::fs::write(
        d.join("neg.csv"),
        "time_s,run,vib_g,output\n0,a,0,1\n0.1,a,0,1.1\n0.2,b,-2,1.2\n",
    )
    .unwrap();
    refused(
        &run_in(&d, &["sensitivity", "--input", "neg.csv"]),
        &["neg.csv:4", "vib_g = -2"],
    );
    refused(
        &run_in(&d, &["sensitivity", "--input", "a.csv", "--rate-hz", "50"]),
        &["rate-hz", "50 Hz disagrees with time_s"],
    );
    let mut text = String::from("time_s,run,vib_g,output\n");
    for k in 0..60 {
        text.push_str(&format!(
            "{},a,0,{}\n",
            k as f64 * 0.1,
            1.0 + 0.01 * (k % 3) as f64
        ));
    }
    for k in 0..40 {
        text.push_str(&format!(
            "{},b,4,{}\n",
            10.0 + k as f64 * 0.2,
            1.0 + 0.01 * (k % 3) as f64
        ));
    }
    std::fs::write(d.join("rates.csv"), text).unwrap();
    refused(
        &run_in(&d, &["sensitivity", "--input", "rates.csv"]),
        &["rates.csv", "run 'b'", "one rate for every run"],
    );
    // A plan without noise, two shocks in a row at one level.
    refused(
        &run_in(
            &d,
            &["plan", "sensitivity", "--noise", "0", "--flicker", "0"],
        ),
        &["noise", "all 0"],
    );
    refused(
        &run_in(
            &d,
            &[
                "simulate",
                "sensitivity",
                "--kind",
                "shock",
                "--levels",
                "100,100",
                "--shifts",
                "1,2",
            ],
        ),
        &["levels", "two shocks in a row"],
    );
}
