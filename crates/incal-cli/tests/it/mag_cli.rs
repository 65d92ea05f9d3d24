//! `incal mag`, `mag apply`, `mag export`, `plan mag`, `simulate mag` from
//! the command line: the document, the refusals (exit 2, one line naming
//! the problem), the apply and export outputs, and the report's plots.

use crate::common::{ok, refused, run_in, stdout, workdir};

fn session(dir: &std::path::Path, out: &str, extra: &[&str]) {
    let mut args = vec![
        "simulate",
        "mag",
        "--seed",
        "5",
        "--orientations",
        "24",
        "--dwell-s",
        "1",
        "--rate-hz",
        "20",
        "-o",
        out,
    ];
    args.extend_from_slice(extra);
    ok(&run_in(dir, &args));
}

#[test]
fn mag_reduces_applies_and_exports() {
    let d = workdir("mag_cli_main");
    session(&d, "s.csv", &["--truth-out", "truth.json"]);
    let out = run_in(
        &d,
        &[
            "mag",
            "--input",
            "s.csv",
            "--field-ut",
            "50",
            "--json",
            "-o",
            "r.json",
        ],
    );
    ok(&out);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("r.json")).unwrap()).unwrap();
    assert_eq!(doc["procedure"], "mag");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("truth.json")).unwrap()).unwrap();
    for name in [
        "hard_iron_x",
        "soft_iron_xy",
        "alignment_z_deg",
        "inclination_deg",
    ] {
        let c = &doc["coefficients"][name];
        let (v, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
        let t = truth[name].as_f64().unwrap();
        assert!(
            (v - t).abs() < 3.0 * u95,
            "{name}: {v} against {t} (U95 {u95})"
        );
    }
    assert_eq!(doc["mag"]["output_unit"], "uT");
    let applied = run_in(
        &d,
        &[
            "mag",
            "apply",
            "--calibration",
            "r.json",
            "--input",
            "s.csv",
        ],
    );
    ok(&applied);
    let text = stdout(&applied);
    assert!(
        text.starts_with("time_s,mag_x,mag_y,mag_z,acc_x"),
        "{}",
        &text[..80]
    );
    let px4 = run_in(
        &d,
        &["mag", "export", "--calibration", "r.json", "--to", "px4"],
    );
    ok(&px4);
    assert!(stdout(&px4).contains("\tCAL_MAG0_XODIAG\t"));
    let ap = run_in(
        &d,
        &[
            "mag",
            "export",
            "--calibration",
            "r.json",
            "--to",
            "ardupilot",
            "--instance",
            "2",
        ],
    );
    ok(&ap);
    assert!(stdout(&ap).contains("COMPASS3_OFS_X,"));
    ok(&run_in(&d, &["report", "r.json", "-o", "r.html"]));
    let html = std::fs::read_to_string(d.join("r.html")).unwrap();
    assert_eq!(html.matches("data-plot=\"mag\"").count(), 4);
}

#[test]
fn mag_refusals_name_the_problem() {
    let d = workdir("mag_cli_refusals");
    session(&d, "s.csv", &["--motion", "planar"]);
    refused(
        &run_in(&d, &["mag", "--input", "s.csv", "--field-ut", "50"]),
        &["s.csv", "cannot separate hard_iron_z, soft_iron_zz"],
    );
    refused(
        &run_in(&d, &["plan", "mag", "--motion", "planar"]),
        &["cannot separate"],
    );
    session(&d, "g.csv", &[]);
    refused(
        &run_in(&d, &["mag", "--input", "g.csv", "--full-scale", "30"]),
        &["g.csv", "full scale", "line "],
    );
    refused(
        &run_in(&d, &["mag", "--input", "g.csv", "--axes", "x,x,z"]),
        &["--axes"],
    );
    std::fs::write(d.join("few.csv"), "mag_x,mag_y,mag_z\n1,2,3\n4,5,6\n").unwrap();
    refused(
        &run_in(&d, &["mag", "--input", "few.csv"]),
        &["few.csv", "unknowns"],
    );
    ok(&run_in(
        &d,
        &[
            "mag", "--input", "g.csv", "--unit", "counts", "--json", "-o", "c.json",
        ],
    ));
    refused(
        &run_in(
            &d,
            &["mag", "export", "--calibration", "c.json", "--to", "px4"],
        ),
        &["c.json", "counts"],
    );
    refused(
        &run_in(
            &d,
            &["mag", "apply", "--calibration", "g.csv", "--input", "g.csv"],
        ),
        &["g.csv"],
    );
}
