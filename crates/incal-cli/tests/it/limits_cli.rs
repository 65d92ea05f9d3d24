//! `--limits FILE` on a reducing command: every limited coefficient gets a
//! verdict under the file's decision rule (ILAC-G8), the worst is the
//! overall verdict, the document still validates against the schema, and a
//! limit that does not fit the result is refused with one line.

use crate::common;
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

/// Limits for a production line: one wildcard serves every channel; a
/// term a channel did not identify is `not-determined`, not a refusal; a
/// misspelled name is still refused; `--fail-on` turns a verdict into
/// exit 3 after the result is written; `compare --fail-on differs` stops
/// on |En| > 1; `report --fail-on` as the reduction.
#[test]
fn wildcards_not_determined_and_fail_on() {
    let csv = unique("prod-noise.csv");
    ok(&run(&[
        "simulate",
        "noise",
        "--quantity",
        "gyro",
        "--rate-hz",
        "100",
        "--duration-s",
        "3600",
        "--arw-deg-rth",
        "0.15",
        // RRW at the edge of what an hour shows: with this seed ch1 and
        // ch2 identify it, ch3 does not.
        "--rrw-deg-h-rth",
        "2",
        "--channels",
        "3",
        "--seed",
        "3",
        "-o",
        p(&csv),
    ]));
    let limits = write_unique(
        "prod.toml",
        "[noise]\n\"*.ARW\" = { max = 0.3, unit = \"deg/sqrt(h)\" }\n\"*.RRW\" = { max = 100 }\n",
    );
    let base = [
        "noise",
        "--input",
        p(&csv),
        "--rate-hz",
        "100",
        "--quantity",
        "gyro",
        "--json",
        "--limits",
        p(&limits),
    ];
    let o = run(&base);
    let v = json_of(&o);
    assert!(
        v["coefficients"].get("ch3.RRW").is_none(),
        "this seed leaves ch3's RRW unidentified"
    );
    let verdicts = &v["verdicts"];
    for ch in ["ch1", "ch2", "ch3"] {
        assert_eq!(
            verdicts[format!("{ch}.ARW")]["verdict"],
            "pass",
            "{verdicts}"
        );
    }
    assert_eq!(verdicts["ch1.RRW"]["verdict"], "pass");
    assert_eq!(verdicts["ch3.RRW"]["verdict"], "not-determined");
    assert_eq!(verdicts["ch3.RRW"]["max"], 100.0);
    assert_eq!(v["verdict"], "not-determined");
    // Exit 3 with --fail-on fail, the result written first.
    let mut stop = base.to_vec();
    stop.extend(["--fail-on", "fail"]);
    let o = run(&stop);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let written: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(written["verdict"], "not-determined");
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("verdict not-determined (ch3.RRW not-determined): stopped by --fail-on fail"),
        "{err}"
    );
    // The text report names it too.
    let text = stdout(&run(&[
        "noise",
        "--input",
        p(&csv),
        "--rate-hz",
        "100",
        "--quantity",
        "gyro",
        "--limits",
        p(&limits),
    ]));
    assert!(
        text.contains("ch3.RRW: not-determined (limited, but not reported by this result)"),
        "{text}"
    );
    // A misspelled term, a wildcard that matches nothing: refused.
    for (body, want) in [
        (
            "[noise]\n\"ch1.ARV\" = { max = 1 }\n",
            "ch1.ARV: not a coefficient of this result",
        ),
        (
            "[noise]\n\"*.VRW\" = { max = 1 }\n",
            "the wildcard matches no coefficient",
        ),
    ] {
        let l = write_unique("prod-bad.toml", body);
        let mut a = base[..base.len() - 1].to_vec();
        a.push(p(&l));
        refused(&run(&a), &[want]);
    }
    // --fail-on needs --limits.
    let e = run(&[
        "noise",
        "--input",
        p(&csv),
        "--rate-hz",
        "100",
        "--fail-on",
        "fail",
    ]);
    assert_eq!(e.status.code(), Some(2));

    // A tumble: conditional-pass stops only with --fail-on conditional.
    let t = unique("prod-t.csv");
    ok(&run(&["simulate", "tumble", "--seed", "2", "-o", p(&t)]));
    let plain: Value = json_of(&run(&[
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        p(&t),
        "--json",
    ]));
    let c = &plain["coefficients"]["K0"];
    let (x, u) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
    let l = write_unique(
        "prod-t.toml",
        &format!(
            "rule = \"guard-band\"\n[tumble]\nK0 = {{ min = {}, max = {} }}\n",
            x - 0.5 * u,
            x + 2.0 * u
        ),
    );
    let reduce = |extra: &[&str]| {
        let mut a = vec![
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            p(&t),
            "--json",
            "--limits",
            p(&l),
        ];
        a.extend_from_slice(extra);
        run(&a)
    };
    assert_eq!(reduce(&[]).status.code(), Some(0));
    assert_eq!(reduce(&["--fail-on", "fail"]).status.code(), Some(0));
    let o = reduce(&["--fail-on", "conditional"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(stderr(&o).contains(
        "verdict conditional-pass (K0 conditional-pass): stopped by --fail-on conditional"
    ));
    let doc = write_unique("prod-t.json", &stdout(&reduce(&[])));
    let o = run(&[
        "report",
        p(&doc),
        "--limits",
        p(&l),
        "--fail-on",
        "conditional",
        "-o",
        p(&unique("prod.html")),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));

    // compare --fail-on differs: En beyond 1 stops, agreement does not.
    let t2 = unique("prod-t2.csv");
    ok(&run(&[
        "simulate",
        "tumble",
        "--seed",
        "3",
        "--k0",
        "0.01",
        "-o",
        p(&t2),
    ]));
    let other = write_unique(
        "prod-t2.json",
        &stdout(&run(&[
            "tumble",
            "--mount",
            "pendulum",
            "--input",
            p(&t2),
            "--json",
        ])),
    );
    assert_eq!(
        run(&["compare", p(&doc), p(&doc), "--fail-on", "differs"])
            .status
            .code(),
        Some(0)
    );
    let o = run(&["compare", p(&doc), p(&other), "--fail-on", "differs"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("differ beyond their U95 (K0 En"),
        "{}",
        stderr(&o)
    );
    assert!(
        !stdout(&o).is_empty(),
        "the comparison is written before the stop"
    );
}
