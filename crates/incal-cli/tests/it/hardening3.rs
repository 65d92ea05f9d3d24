//! The third hardening round (the issue "Third hardening round"): one
//! regression test per class of failure found by the generated cases,
//! each on the class, not only its first example.

use std::os::unix::fs::PermissionsExt;
use std::path::Path;

use crate::common::{self, p, stderr};

/// A tumble result with a serial, as a file in `dir`.
fn result_in(dir: &Path) -> std::path::PathBuf {
    let csv = dir.join("t.csv");
    common::ok(&common::run(&[
        "simulate",
        "tumble",
        "--seed",
        "3",
        "-o",
        p(&csv),
    ]));
    let json = dir.join("r.json");
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
            vec!["record", "history", "--serial", "SN-1", "--coefficient", "K1", "--db", s],
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
