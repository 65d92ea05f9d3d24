//! The third hardening round (the issue "Third hardening round"): one
//! regression test per class of failure found by the generated cases,
//! each on the class, not only its first example.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;

use crate::common::{self, p, stderr};

/// A tumble result with a serial, as a file in `dir`.
fn result_in(dir: &Path) -> std::path::PathBuf {
    tumble_result(dir, 3, "r")
}

/// The tumble result of the simulation with `seed`, serial SN-1, as
/// `dir/STEM.json` (its recording `dir/STEM.csv`).
fn tumble_result(dir: &Path, seed: u64, stem: &str) -> std::path::PathBuf {
    let csv = dir.join(format!("{stem}.csv"));
    let seed = seed.to_string();
    common::ok(&common::run(&[
        "simulate",
        "tumble",
        "--seed",
        &seed,
        "-o",
        p(&csv),
    ]));
    let json = dir.join(format!("{stem}.json"));
    common::ok(&common::run(&[
        "tumble",
        "--input",
        p(&csv),
        "--mount",
        "pendulum",
        "--serial",
        "SN-1",
        "--json",
        "-o",
        p(&json),
    ]));
    json
}

/// An executable script `name` in `dir` with `body` (a fake browser).
fn script(dir: &Path, name: &str, body: &str) {
    let f = dir.join(name);
    std::fs::write(&f, format!("#!/bin/sh\n{body}\n")).unwrap();
    std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
}

/// Class 9: `--pdf` tells a missing browser, one that cannot start and one
/// that printed nothing apart, each exit 1 with the HTML kept; a PDF left
/// from an earlier run is never taken for this one.
#[test]
fn a_pdf_that_was_not_printed_is_a_failure_naming_why() {
    let dir = common::workdir("pdf");
    let json = result_in(&dir);
    let html = dir.join("r.html");
    let stale = dir.join("r.pdf");
    let report = |path: &Path| {
        common::bin()
            .env("PATH", path)
            .args(["report", p(&json), "-o", p(&html), "--pdf"])
            .output()
            .unwrap()
    };
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let o = report(&empty);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("not installed"), "{}", stderr(&o));
    assert!(html.exists(), "the HTML is written");

    let broken = dir.join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    script(
        &broken,
        "chromium",
        "echo 'error while loading shared libraries: libnss3.so' >&2; exit 127",
    );
    let o = report(&broken);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("cannot start") && err.contains("libnss3"),
        "{err}"
    );
    assert!(!err.contains("not installed"), "{err}");

    let silent = dir.join("silent");
    std::fs::create_dir_all(&silent).unwrap();
    script(
        &silent,
        "chromium",
        "[ \"$1\" = --version ] && { echo Chromium 1; exit 0; }; echo 'crashed' >&2; exit 0",
    );
    std::fs::write(&stale, b"%PDF-1.4 an old one").unwrap();
    let o = report(&silent);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("printed no") && stderr(&o).contains("crashed"),
        "{}",
        stderr(&o)
    );
    assert!(!stale.exists(), "the old PDF is not left as if printed now");
}

/// Class 12: control characters in a file name (ESC, a bell, a carriage
/// return) never reach the terminal raw: the one line shows them as `?`.
#[test]
fn control_characters_in_names_never_reach_the_terminal() {
    let dir = common::workdir("control");
    let name = dir.join("\u{1b}[31mred\u{7}\r.csv");
    let o = common::run(&["tumble", "--input", p(&name), "--mount", "pendulum"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(!err.chars().any(|c| c.is_control() && c != '\n'), "{err:?}");
    assert!(err.contains("?[31mred??.csv"), "{err:?}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err:?}");
}

/// The files of `dir` with their sizes and modification times.
fn listing(dir: &Path) -> Vec<(String, u64, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let m = e.metadata().unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                m.len(),
                m.modified().unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// `incal args…` as another user when the tests run as root (uid 65534,
/// to whom the read-only store belongs to no one), else as this one.
fn as_other_user(args: &[&str]) -> std::process::Output {
    use std::os::unix::process::CommandExt;
    let mut c = common::bin();
    c.args(args);
    // Root owns what it creates: a file just made tells who runs.
    let probe = common::write_unique("whoami", "");
    if std::os::unix::fs::MetadataExt::uid(&std::fs::metadata(&probe).unwrap()) == 0 {
        c.uid(65534).gid(65534);
    }
    c.output().unwrap()
}

/// Class 2: a store copied into a read-only directory, owned by another
/// user (an auditor's copy), with its chain wholly in the file or with
/// records still in its `-wal`: every reading command succeeds and nothing
/// is written beside it.
#[test]
fn a_read_only_store_of_another_user_is_read_and_never_written() {
    let dir = common::workdir("readonly");
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o755)).unwrap();
    let json = result_in(&dir);
    std::fs::set_permissions(&json, std::fs::Permissions::from_mode(0o644)).unwrap();
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o777)).unwrap();
    for pending in [false, true] {
        let src = dir.join(format!("src{pending}"));
        std::fs::create_dir_all(&src).unwrap();
        let db = src.join("lab.db");
        common::ok(&common::run(&[
            "record",
            "add",
            p(&json),
            "--db",
            p(&db),
            "--operator",
            "lee",
        ]));
        let ro = dir.join(format!("ro{pending}"));
        std::fs::create_dir_all(&ro).unwrap();
        if pending {
            // A copy taken while a writer holds the store: the second
            // record is only in the -wal file.
            let mut store = incal_records::Store::open(&db).unwrap();
            let text = std::fs::read_to_string(&json)
                .unwrap()
                .replace("SN-1", "SN-2");
            store
                .add(&incal_records::NewRecord {
                    document: &text,
                    serial: None,
                    operator: Some("kim"),
                    station: None,
                    created_utc: None,
                })
                .unwrap();
            let wal = src.join("lab.db-wal");
            assert!(
                wal.metadata().unwrap().len() > 0,
                "the writer's records are in the -wal"
            );
            std::fs::copy(&db, ro.join("lab.db")).unwrap();
            std::fs::copy(&wal, ro.join("lab.db-wal")).unwrap();
            drop(store);
        } else {
            std::fs::copy(&db, ro.join("lab.db")).unwrap();
        }
        for f in std::fs::read_dir(&ro).unwrap() {
            let f = f.unwrap().path();
            std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o444)).unwrap();
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        let before = listing(&ro);
        let store = ro.join("lab.db");
        let s = p(&store);
        let records = if pending { 2 } else { 1 };
        let o = as_other_user(&["record", "verify", "--db", s]);
        assert!(o.status.success(), "verify ({pending}): {}", stderr(&o));
        let o = as_other_user(&["record", "list", "--db", s, "--json"]);
        assert!(o.status.success(), "list ({pending}): {}", stderr(&o));
        let listed: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            listed["records"].as_array().unwrap().len(),
            records,
            "({pending})"
        );
        for args in [
            vec!["record", "show", "1", "--db", s],
            vec![
                "record",
                "history",
                "--serial",
                "SN-1",
                "--coefficient",
                "K1",
                "--db",
                s,
            ],
        ] {
            let o = as_other_user(&args);
            assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        }
        let export = out.join(format!("export{pending}.jsonl"));
        let o = as_other_user(&["record", "export", "--db", s, "-o", p(&export)]);
        assert!(o.status.success(), "export ({pending}): {}", stderr(&o));
        assert_eq!(
            std::fs::read_to_string(&export).unwrap().lines().count(),
            records
        );
        let html = out.join(format!("r{pending}.html"));
        let o = as_other_user(&["report", p(&json), "--db", s, "-o", p(&html)]);
        assert!(o.status.success(), "report ({pending}): {}", stderr(&o));
        assert_eq!(
            listing(&ro),
            before,
            "nothing written beside the store ({pending})"
        );
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
}

/// Tumble results at three temperatures in `dir` (by `--meta
/// temperature_c`), as JSON values.
fn plateaus(dir: &Path) -> Vec<serde_json::Value> {
    [-10, 25, 60]
        .iter()
        .map(|t| {
            let csv = dir.join(format!("t{t}.csv"));
            let seed = (t + 100).to_string();
            common::ok(&common::run(&[
                "simulate",
                "tumble",
                "--seed",
                &seed,
                "-o",
                p(&csv),
            ]));
            let meta = format!("temperature_c={t}");
            common::json_of(&common::run(&[
                "tumble",
                "--input",
                p(&csv),
                "--mount",
                "pendulum",
                "--meta",
                &meta,
                "--json",
            ]))
        })
        .collect()
}

/// Class 3: every malformed plateau document is exit 2 naming its JSON
/// path, never a panic or a silent number: a correlation matrix of the
/// wrong size, |r| > 1, an asymmetric one, an environment with min > max,
/// a value no recording gives, a temperature below absolute zero.
#[test]
fn thermal_fit_refuses_every_malformed_plateau_naming_the_json_path() {
    let dir = common::workdir("soak");
    let docs = plateaus(&dir);
    type Edit = fn(&mut serde_json::Value);
    let cases: [(&str, Edit, &str); 7] = [
        (
            "short",
            |d| {
                d["correlation"]["matrix"].as_array_mut().unwrap().pop();
            },
            "$.correlation.matrix: 5 rows for 6 names",
        ),
        (
            "narrow",
            |d| {
                d["correlation"]["matrix"][2].as_array_mut().unwrap().pop();
            },
            "$.correlation.matrix[2]: 5 entries",
        ),
        (
            "r2",
            |d| {
                d["correlation"]["matrix"][0][1] = 2.into();
                d["correlation"]["matrix"][1][0] = 2.into();
            },
            "$.correlation.matrix[0][1]: 2 is not a correlation",
        ),
        (
            "asym",
            |d| {
                d["correlation"]["matrix"][0][1] = 0.3.into();
                d["correlation"]["matrix"][1][0] = (-0.3).into();
            },
            "symmetric",
        ),
        (
            "env",
            |d| {
                d["environment"] = serde_json::json!({"temperature_c": {"mean": 25, "min": 30, "max": 20, "count": 5}});
            },
            "$.environment.temperature_c: min 30 is above max 20",
        ),
        (
            "big",
            |d| {
                d["coefficients"]["K0"]["value"] = 1e200.into();
            },
            "$.coefficients.K0: value 1e200",
        ),
        (
            "cold",
            |d| {
                d["instrument"]["temperature_c"] = "-300".into();
            },
            "$.instrument.temperature_c: '-300' is not a temperature",
        ),
    ];
    let good: Vec<std::path::PathBuf> = docs
        .iter()
        .enumerate()
        .map(|(i, d)| common::write(&format!("soak{i}.json"), &d.to_string()))
        .collect();
    common::ok(&common::run(&[
        "thermal",
        "fit",
        p(&good[0]),
        p(&good[1]),
        p(&good[2]),
        "--json",
    ]));
    for (name, edit, needle) in cases {
        let mut bad = docs[1].clone();
        edit(&mut bad);
        let f = common::write(&format!("bad_{name}.json"), &bad.to_string());
        let o = common::run(&["thermal", "fit", p(&good[0]), p(&f), p(&good[2]), "--json"]);
        common::refused(&o, &[&format!("bad_{name}.json"), needle]);
    }
}

/// Class 4: `thermal ramp` warns of the cells it takes as missing samples,
/// refuses a `--rate-hz` its `time_s` stamps contradict, and a block that
/// holds fewer than two samples.
#[test]
fn thermal_ramp_says_what_it_left_out_and_checks_its_time_base() {
    let dir = common::workdir("ramp");
    let csv = dir.join("ramp.csv");
    common::ok(&common::run(&[
        "simulate",
        "thermal",
        "--seed",
        "5",
        "--rate-hz",
        "1",
        "--hold-s",
        "300",
        "-o",
        p(&csv),
    ]));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let k = header.iter().position(|h| *h == "gx").unwrap();
    for (i, line) in lines.iter_mut().enumerate().skip(100).take(11) {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        cells[k] = if i == 110 {
            "NaN".into()
        } else {
            String::new()
        };
        *line = cells.join(",");
    }
    let holed = common::write("holed.csv", &(lines.join("\n") + "\n"));
    let v = common::json_of(&common::run(&[
        "thermal",
        "ramp",
        "--input",
        p(&holed),
        "--rate-hz",
        "1",
        "--quantity",
        "gyro",
        "--json",
    ]));
    let w = common::warnings_with(&v, "missing-samples");
    assert!(w.len() == 1 && w[0].contains("gx 11"), "{w:?}");
    let o = common::run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "100",
        "--quantity",
        "gyro",
    ]);
    common::refused(&o, &["--rate-hz", "disagrees with the time_s stamps"]);
    let o = common::run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "1",
        "--block-s",
        "1e-320",
        "--quantity",
        "gyro",
    ]);
    common::refused(&o, &["--block-s", "fewer than two samples"]);
}

/// Class 5: physical bounds in the thermal plan and simulator: no
/// temperature below absolute zero, low below high, no absurd lag, ramp or
/// hold.
#[test]
fn thermal_plans_and_simulations_keep_to_physics() {
    let out = common::tmp("x.csv");
    let o = p(&out);
    for (args, needle) in [
        (
            vec![
                "simulate",
                "thermal",
                "--seed",
                "1",
                "--t-low-c",
                "50",
                "--t-high-c",
                "10",
                "-o",
                o,
            ],
            "--t-low-c",
        ),
        (
            vec![
                "simulate",
                "thermal",
                "--seed",
                "1",
                "--t-low-c",
                "-300",
                "-o",
                o,
            ],
            "--t-low-c",
        ),
        (
            vec![
                "simulate", "thermal", "--seed", "1", "--lag-s", "1e300", "-o", o,
            ],
            "--lag-s",
        ),
        (
            vec![
                "simulate",
                "thermal",
                "--seed",
                "1",
                "--ramp-c-per-min",
                "1e9",
                "-o",
                o,
            ],
            "--ramp-c-per-min",
        ),
        (
            vec![
                "simulate",
                "thermal",
                "--seed",
                "1",
                "--t-ref-c",
                "-280",
                "-o",
                o,
            ],
            "--t-ref-c",
        ),
        (
            vec![
                "plan",
                "thermal",
                "--plateaus-c",
                "-300,20",
                "--u",
                "1e-3",
                "--degree",
                "1",
            ],
            "--plateaus-c",
        ),
        (
            vec![
                "plan",
                "thermal",
                "--t-low-c",
                "30",
                "--t-high-c",
                "10",
                "--noise",
                "1e-3",
                "--ramp-c-per-min",
                "1",
                "--degree",
                "1",
            ],
            "--t-low-c",
        ),
        (
            vec![
                "plan",
                "thermal",
                "--t-ref-c",
                "-274",
                "--plateaus-c",
                "0,20",
                "--u",
                "1e-3",
                "--degree",
                "1",
            ],
            "--t-ref-c",
        ),
    ] {
        common::refused(&common::run(&args), &[needle]);
    }
}

/// Class 8: `record import` compares every line the store already holds
/// and refuses one changed after the export; a new line with an empty
/// serial or one its document contradicts is refused; a refused import
/// leaves no store behind; `supersede` never stores a document the
/// instrument already holds.
#[test]
fn record_import_and_supersede_never_take_a_changed_or_repeated_record() {
    let dir = common::workdir("import");
    let json = result_in(&dir);
    let db = dir.join("lab.db");
    common::ok(&common::run(&[
        "record",
        "add",
        p(&json),
        "--db",
        p(&db),
        "--operator",
        "lee",
    ]));
    let export = dir.join("lab.jsonl");
    common::ok(&common::run(&[
        "record",
        "export",
        "--db",
        p(&db),
        "-o",
        p(&export),
    ]));
    let line: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(&export).unwrap().trim()).unwrap();
    // The same export again: every line present, nothing added.
    common::ok(&common::run(&[
        "record",
        "import",
        p(&export),
        "--db",
        p(&db),
    ]));
    type Edit = fn(&mut serde_json::Value);
    let changed: [(Edit, &str); 3] = [
        (
            |l| l["operator"] = "eve".into(),
            "its fields do not match its record_hash",
        ),
        (
            |l| {
                l["document"] = l["document"]
                    .as_str()
                    .unwrap()
                    .replace("SN-1", "SN-1 ")
                    .into()
            },
            "its document does not match its sha256",
        ),
        (
            |l| l["model"] = "other".into(),
            "its model is not the store's",
        ),
    ];
    for (edit, needle) in changed {
        let mut l = line.clone();
        edit(&mut l);
        let f = common::write_unique("changed.jsonl", &format!("{l}\n"));
        let o = common::run(&["record", "import", p(&f), "--db", p(&db)]);
        common::refused(&o, &["line 1", "record 1", needle]);
    }
    let fresh = dir.join("fresh.db");
    let new_lines: [(Edit, &str); 2] = [
        (|l| l["serial"] = " ".into(), "an empty serial"),
        (
            |l| l["serial"] = "SN-X".into(),
            "is not its document's instrument.serial 'SN-1'",
        ),
    ];
    for (edit, needle) in new_lines {
        let mut l = line.clone();
        edit(&mut l);
        let f = common::write_unique("new.jsonl", &format!("{l}\n"));
        let o = common::run(&["record", "import", p(&f), "--db", p(&fresh)]);
        common::refused(&o, &[needle]);
        assert!(!fresh.exists(), "a refused import leaves no store behind");
    }
    let o = common::run(&[
        "record",
        "supersede",
        "1",
        p(&json),
        "--reason",
        "again",
        "--db",
        p(&db),
    ]);
    common::refused(&o, &["record 1 already holds this document"]);
    let listed = common::json_of(&common::run(&["record", "list", "--db", p(&db), "--json"]));
    assert_eq!(
        listed["records"].as_array().unwrap().len(),
        1,
        "stored once"
    );
}

/// Class 12: `record add -o` on a full disk says once what happened to
/// the record (held already, or stored now), not "nothing stored" and
/// then "stored".
#[test]
fn record_add_says_once_whether_it_stored() {
    let dir = common::workdir("addfull");
    let json = result_in(&dir);
    let db = dir.join("lab.db");
    let o = common::run(&["record", "add", p(&json), "--db", p(&db), "-o", "/dev/full"]);
    assert_eq!(o.status.code(), Some(3));
    assert_eq!(stderr(&o).trim_end().lines().count(), 1, "{}", stderr(&o));
    assert!(stderr(&o).contains("record 1 stored; writing the output failed"));
    let o = common::run(&["record", "add", p(&json), "--db", p(&db), "-o", "/dev/full"]);
    assert_eq!(o.status.code(), Some(3));
    let err = stderr(&o);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("record 1 already holds this document; writing the output failed"),
        "{err}"
    );
    assert!(!err.contains("nothing stored"), "{err}");
}

/// A thermal model of the ramp simulated in `dir`, as JSON, and the ramp.
fn thermal_model(dir: &Path) -> (serde_json::Value, std::path::PathBuf) {
    let csv = dir.join("ramp.csv");
    common::ok(&common::run(&[
        "simulate",
        "thermal",
        "--seed",
        "5",
        "--rate-hz",
        "1",
        "--hold-s",
        "300",
        "-o",
        p(&csv),
    ]));
    let model = common::json_of(&common::run(&[
        "thermal",
        "ramp",
        "--input",
        p(&csv),
        "--rate-hz",
        "1",
        "--quantity",
        "gyro",
        "--json",
    ]));
    (model, csv)
}

/// Rename every `from.` coefficient and the `from` entry of a thermal
/// model to `to`.
fn rename_channel(m: &mut serde_json::Value, from: &str, to: &str) {
    let entry = m["thermal"].as_object_mut().unwrap().remove(from).unwrap();
    m["thermal"][to] = entry;
    let coefficients = m["coefficients"].as_object_mut().unwrap();
    let keys: Vec<String> = coefficients
        .keys()
        .filter(|k| k.starts_with(&format!("{from}.")))
        .cloned()
        .collect();
    for k in keys {
        let v = coefficients.remove(&k).unwrap();
        coefficients.insert(k.replacen(from, to, 1), v);
    }
    for n in m["correlation"]["names"].as_array_mut().unwrap() {
        if let Some(s) = n.as_str().and_then(|s| s.strip_prefix(&format!("{from}."))) {
            *n = format!("{to}.{s}").into();
        }
    }
}

/// Class 6: `thermal apply` refuses a model that would correct the
/// temperature column or whose degree contradicts its coefficients.
#[test]
fn thermal_apply_refuses_a_model_read_wrong() {
    let dir = common::workdir("apply");
    let (model, csv) = thermal_model(&dir);
    let mut temp = model.clone();
    rename_channel(&mut temp, "gx", "temperature_c");
    let f = common::write("m_temp.json", &temp.to_string());
    let o = common::run(&["thermal", "apply", p(&f), "--input", p(&csv)]);
    common::refused(
        &o,
        &["$.thermal.temperature_c", "not a channel a model corrects"],
    );
    let mut degree = model.clone();
    let d = degree["thermal"]["gx"]["degree"].as_u64().unwrap();
    degree["thermal"]["gx"]["degree"] = (d - 1).into();
    let f = common::write("m_deg.json", &degree.to_string());
    let o = common::run(&["thermal", "apply", p(&f), "--input", p(&csv)]);
    common::refused(&o, &["$.thermal.gx.degree", &format!("has gx.c{d}")]);
}

/// Class 7: exports refuse repeated axes, a parameter a float32 cannot
/// hold, an absurd EKF rate and a negative noise density.
#[test]
fn exports_write_only_what_a_flight_stack_reads_back() {
    let dir = common::workdir("exports");
    let (model, _) = thermal_model(&dir);
    let f = common::write("model.json", &model.to_string());
    let o = common::run(&["export", "px4", p(&f), "--axes", "gx,gx,gx"]);
    common::refused(&o, &["--axes", "three different channels"]);
    let mut tiny = model.clone();
    let mut c2 = tiny["coefficients"]["gx.c2"].clone();
    for k in ["value", "u", "U95"] {
        c2[k] = 1e-320.into();
    }
    c2["u"] = 0.into();
    c2["U95"] = 0.into();
    tiny["coefficients"]["gx.c2"] = c2;
    let f = common::write("tiny.json", &tiny.to_string());
    for fmt in ["px4", "ardupilot"] {
        let o = common::run(&["export", fmt, p(&f)]);
        common::refused(&o, &["does not fit the flight stack's float32 parameter"]);
    }
    let sim = |q: &str, args: &[&str]| {
        let csv = dir.join(format!("{q}.csv"));
        let mut a = vec![
            "simulate",
            "noise",
            "--rate-hz",
            "100",
            "--duration-s",
            "3600",
            "--seed",
            "11",
            "--quantity",
            q,
            "-o",
            p(&csv),
        ];
        a.extend_from_slice(args);
        common::ok(&common::run(&a));
        common::json_of(&common::run(&[
            "noise",
            "--input",
            p(&csv),
            "--rate-hz",
            "100",
            "--quantity",
            q,
            "--json",
        ]))
    };
    let g = sim("gyro", &["--arw-deg-rth", "0.2", "--rrw-deg-h-rth", "40"]);
    let a = sim("accel", &["--vrw-ug-rthz", "60", "--accel-rw-ug-rts", "30"]);
    let gj = common::write("g.json", &g.to_string());
    let aj = common::write("a.json", &a.to_string());
    let o = common::run(&[
        "export",
        "px4",
        "--gyro",
        p(&gj),
        "--accel",
        p(&aj),
        "--ekf-rate-hz",
        "1e300",
    ]);
    common::refused(&o, &["--ekf-rate-hz"]);
    let mut neg = g.clone();
    let arw = neg["coefficients"]
        .as_object()
        .unwrap()
        .keys()
        .find(|k| k.ends_with(".ARW"))
        .cloned()
        .unwrap();
    let v = neg["coefficients"][&arw]["value"].as_f64().unwrap();
    neg["coefficients"][&arw]["value"] = (-v).into();
    let nj = common::write("neg.json", &neg.to_string());
    for fmt in ["kalibr", "px4"] {
        let o = common::run(&["export", fmt, "--gyro", p(&nj), "--accel", p(&aj)]);
        common::refused(&o, &[&arw, "is positive"]);
    }
}

/// Class 9: a superseded record's certificate says it is withdrawn and by
/// which certificate; a date of year 0 is refused as `record add` refuses
/// it.
#[test]
fn a_withdrawn_certificate_says_so_and_year_zero_is_no_date() {
    let dir = common::workdir("withdrawn");
    let json = result_in(&dir);
    let db = dir.join("lab.db");
    common::ok(&common::run(&[
        "record",
        "add",
        p(&json),
        "--db",
        p(&db),
        "--operator",
        "lee",
    ]));
    let second = tumble_result(&dir, 4, "r2");
    common::ok(&common::run(&[
        "record",
        "supersede",
        "1",
        p(&second),
        "--reason",
        "wrong mount",
        "--db",
        p(&db),
    ]));
    let lab = common::write(
        "lab.toml",
        "[lab]\nname = \"Lab\"\naddress = \"1 Road\"\ncertificate_prefix = \"C-\"\n[[signatory]]\nname = \"Ann\"\nrole = \"Head\"\n",
    );
    let html = dir.join("old.html");
    common::ok(&common::run(&[
        "report",
        p(&json),
        "--db",
        p(&db),
        "--lab",
        p(&lab),
        "-o",
        p(&html),
    ]));
    let old = std::fs::read_to_string(&html).unwrap();
    assert!(old.contains("Withdrawn:") && old.contains("replaced by certificate C-000002"));
    let html = dir.join("new.html");
    common::ok(&common::run(&[
        "report",
        p(&second),
        "--db",
        p(&db),
        "--lab",
        p(&lab),
        "-o",
        p(&html),
    ]));
    let new = std::fs::read_to_string(&html).unwrap();
    assert!(!new.contains("Withdrawn:") && new.contains("replaces certificate C-000001"));
    let o = common::run(&["report", p(&json), "--lab", p(&lab), "--date", "0000-01-01"]);
    common::refused(&o, &["--date", "0000-01-01"]);
}

/// Class 11: `noise` refuses the time stamps as a channel and a bias
/// stability time shorter than the sample period.
#[test]
fn noise_refuses_stamps_as_a_channel_and_a_time_below_the_period() {
    let csv = common::tmp("n.csv");
    common::ok(&common::run(&[
        "simulate",
        "noise",
        "--rate-hz",
        "100",
        "--duration-s",
        "60",
        "--seed",
        "2",
        "--arw-deg-rth",
        "0.2",
        "-o",
        p(&csv),
    ]));
    let o = common::run(&["noise", "--input", p(&csv), "--columns", "time_s"]);
    common::refused(&o, &["time_s is the record's time stamps, not a channel"]);
    let o = common::run(&["noise", "--input", p(&csv), "--stability-tau-s", "0.001"]);
    common::refused(
        &o,
        &["--stability-tau-s", "shorter than the sample period 0.01 s"],
    );
}

/// Class 12: `batch` says an option the procedure refuses once, not once
/// per recording, and reduces nothing.
#[test]
fn batch_says_an_option_error_once() {
    let dir = common::workdir("batchopt");
    let mut files = Vec::new();
    for k in 0..3 {
        let f = dir.join(format!("n{k}.csv"));
        common::ok(&common::run(&[
            "simulate",
            "noise",
            "--rate-hz",
            "10",
            "--duration-s",
            "100",
            "--seed",
            &k.to_string(),
            "-o",
            p(&f),
        ]));
        files.push(f);
    }
    let mut args = vec!["batch", "noise"];
    args.extend(files.iter().map(|f| p(f)));
    args.extend(["--", "--stability-tau-s", "-1"]);
    let o = common::run(&args);
    common::refused(&o, &["--stability-tau-s", "nothing reduced"]);
}

/// Class 5: options a rig cannot have are refused before they reach a
/// result: a centrifuge alignment tolerance above 10 deg, a K1 beyond
/// 1e15 either way, a plan's u(K1) not below |K1|.
#[test]
fn options_a_rig_cannot_have_never_reach_a_result() {
    let c = common::tmp("c.csv");
    common::ok(&common::run(&[
        "simulate",
        "centrifuge",
        "--seed",
        "12",
        "-o",
        p(&c),
    ]));
    let o = common::run(&[
        "centrifuge",
        "--input",
        p(&c),
        "--k0",
        "1.2e-4",
        "--u-k0",
        "2e-6",
        "--k1",
        "1.3",
        "--u-k1",
        "1.3e-6",
        "--radius-m",
        "0.71",
        "--latitude-deg",
        "39.9",
        "--alignment-tolerance-deg",
        "1e300",
    ]);
    common::refused(&o, &["--alignment-tolerance-deg", "0..10 deg"]);
    let g = common::tmp("gp.csv");
    common::ok(&common::run(&[
        "simulate",
        "gyro-positions",
        "--samples",
        "4",
        "--seed",
        "17",
        "-o",
        p(&g),
    ]));
    for k1 in ["1e300", "1e-300"] {
        let o = common::run(&[
            "gyro",
            "positions",
            "--input",
            p(&g),
            "--latitude-deg",
            "39",
            "--axial",
            "sa",
            "--azimuth-deg",
            "10",
            "--k1",
            k1,
        ]);
        common::refused(&o, &["k1", "1e-15 to 1e15"]);
    }
    let o = common::run(&[
        "plan",
        "gyro-positions",
        "--latitude-deg",
        "39",
        "--k1",
        "1",
        "--u-k1",
        "2",
        "--noise",
        "0.01",
    ]);
    common::refused(&o, &["--u-k1", "not below |k1|"]);
}

/// The fuzz campaign of this round found two messages too long for one
/// line: a correlation entry of 1e38 echoed in full, and an unknown key of
/// an export line (serde echoes it whole, newlines included). Both are one
/// short line now.
#[test]
fn refusals_found_by_the_fuzz_campaign_are_one_short_line() {
    let dir = common::workdir("fuzzfound");
    let docs = plateaus(&dir);
    let mut bad = docs[1].clone();
    bad["correlation"]["matrix"][1][2] = (-1.5478958639871e-6).into();
    bad["correlation"]["matrix"][2][1] = (-1.5478958639871e38).into();
    let f = common::write("asym.json", &bad.to_string());
    let good0 = common::write("g0.json", &docs[0].to_string());
    let good2 = common::write("g2.json", &docs[2].to_string());
    let o = common::run(&["thermal", "fit", p(&good0), p(&f), p(&good2)]);
    common::refused(&o, &["$.correlation.matrix[1][2]"]);
    let key = format!("document{}", "x\\n".repeat(2000));
    let line = format!("{{\"id\": 1, \"{key}\": 1}}\n");
    let export = common::write("long_key.jsonl", &line);
    let o = common::run(&["record", "import", p(&export), "--db", p(&dir.join("s.db"))]);
    common::refused(&o, &["line 1: not an exported record"]);
}
