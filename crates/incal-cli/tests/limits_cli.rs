//! `--limits FILE` on a reducing command: every limited coefficient gets a
//! verdict under the file's decision rule (ILAC-G8), the worst is the
//! overall verdict, the document still validates against the schema, and a
//! limit that does not fit the result is refused with one line.

mod common;
use common::*;

use std::path::PathBuf;

use serde_json::Value;

#[test]
fn guard_band_and_simple_verdicts_through_the_binary() {
    let d = dir();
    assert!(run_in(
        &d,
        &["simulate", "misalign", "accel", "--seed", "4", "-o", "a.csv"]
    )
    .status
    .success());
    let base = [
        "misalign",
        "accel",
        "--input",
        "a.csv",
        "--scale-factor",
        "1.299",
        "--json",
    ];
    let plain: Value = serde_json::from_slice(&run_in(&d, &base).stdout).unwrap();
    assert!(plain.get("verdicts").is_none() && plain.get("verdict").is_none());
    let c = &plain["coefficients"]["dtheta_z2"];
    let (x, u) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
    // One limit per verdict, placed around x with its U95 (rad).
    let cases = [
        ("pass", x - 2.0 * u, x + 2.0 * u),
        ("conditional-pass", x - 0.5 * u, x + 2.0 * u),
        ("conditional-fail", x + 0.5 * u, x + 3.0 * u),
        ("fail", x + 2.0 * u, x + 3.0 * u),
    ];
    for (want, lo, hi) in cases {
        let toml = format!("rule = \"guard-band\"\n[misalign-accel]\ndtheta_z2 = {{ min = {lo:e}, max = {hi:e} }}\n");
        std::fs::write(d.join("l.toml"), toml).unwrap();
        let mut args = base.to_vec();
        args.extend_from_slice(&["--limits", "l.toml"]);
        let o = run_in(&d, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).unwrap();
        let got = &v["verdicts"]["dtheta_z2"];
        assert_eq!(got["verdict"], want);
        assert_eq!(v["verdict"], want, "one limit: overall = its verdict");
        assert_eq!(v["decision_rule"], "guard-band");
        assert!((got["min"].as_f64().unwrap() - lo).abs() <= 1e-12 * lo.abs());
        assert!(v["inputs"]
            .as_array()
            .unwrap()
            .iter()
            .any(|i| i["role"] == "limits" && i["path"] == "l.toml"));
    }
    // Simple acceptance ignores U95; the worst verdict wins overall; an
    // explicit unit converts (arcsec to rad).
    let arcsec = x * 206_264.806_247;
    let toml = format!(
        "rule = \"simple\"\n[misalign-accel]\ndtheta_z2 = {{ min = {:e}, max = {:e}, unit = \"arcsec\" }}\ngamma = {{ max = 0 }}\n",
        arcsec - 1e-6,
        arcsec + 1e-6
    );
    std::fs::write(d.join("s.toml"), toml).unwrap();
    let mut args = base.to_vec();
    args.extend_from_slice(&["--limits", "s.toml"]);
    let v: Value = serde_json::from_slice(&run_in(&d, &args).stdout).unwrap();
    assert_eq!(v["verdicts"]["dtheta_z2"]["verdict"], "pass");
    assert_eq!(v["verdicts"]["gamma"]["verdict"], "fail");
    assert_eq!(v["verdict"], "fail");
    // The document with verdicts still validates against the schema.
    let schema: Value = serde_json::from_str(
        &std::fs::read_to_string(
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../schema/result.schema.json"),
        )
        .unwrap(),
    )
    .unwrap();
    assert!(jsonschema::validator_for(&schema).unwrap().is_valid(&v));
    // Limits that do not fit: one line, exit 2, naming the key.
    for (toml, needle) in [
        ("[misalign-accel]\nK9 = { max = 1 }\n", "K9"),
        (
            "[tumble]\nK0 = { max = 1 }\n",
            "no [misalign-accel] section",
        ),
        (
            "[misalign-accel]\ngamma = { max = 1, unit = \"ug\" }\n",
            "unit 'ug'",
        ),
        ("rule = \"lenient\"\n", "l.toml: line 1"),
        // An empty table gave a result without any verdict.
        ("[misalign-accel]\n", "[misalign-accel] is empty"),
    ] {
        std::fs::write(d.join("l.toml"), toml).unwrap();
        let mut args = base.to_vec();
        args.extend_from_slice(&["--limits", "l.toml"]);
        let o = run_in(&d, &args);
        assert_eq!(o.status.code(), Some(2), "{toml}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
