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
