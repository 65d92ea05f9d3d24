//! The one harness of the CLI tests: run the real `incal` binary, make
//! scratch files under cargo's `CARGO_TARGET_TMPDIR`, and check its
//! contract (exit 0 with JSON, or exit 2 with one line naming the problem).
//! Each test file says `mod common;` and uses what it needs.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

/// The binary under test, with standard input closed and no records
/// store from the environment (`INCAL_DB`).
pub fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_incal"));
    c.stdin(Stdio::null()).env_remove("INCAL_DB");
    c
}

/// Run `incal args…` to completion.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("runs incal")
}

/// Run `incal args…` in the working directory `dir`.
pub fn run_in(dir: &Path, args: &[&str]) -> Output {
    bin()
        .current_dir(dir)
        .args(args)
        .output()
        .expect("runs incal")
}

/// Run `incal args…` with `input` on standard input.
pub fn run_with_stdin(args: &[&str], input: &[u8]) -> Output {
    let mut child = bin()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawns incal");
    // A command may exit before reading all of its input: ignore EPIPE.
    let _ = child.stdin.take().expect("stdin").write_all(input);
    child.wait_with_output().expect("waits for incal")
}

/// Stem of the calling test module's file (`gyro_cli.rs` → `gyro_cli`), so
/// that scratch files of different test files never share a name.
#[track_caller]
fn test_name() -> String {
    // The calling test module's file (`report_cli`, `result_document`):
    // every module of the one test binary has scratch names of its own.
    Path::new(std::panic::Location::caller().file())
        .file_stem()
        .map_or_else(|| "test".into(), |s| s.to_string_lossy().to_string())
}

/// A scratch path ending in `name`, the same on every call with the same
/// name within one test binary (a test may write it and read it back).
#[track_caller]
pub fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "incal_{}_{}_{name}",
        test_name(),
        std::process::id()
    ))
}

/// A scratch path ending in `name`, new on every call (for helpers that
/// tests call concurrently).
#[track_caller]
pub fn unique(name: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let k = N.fetch_add(1, Ordering::SeqCst);
    tmp(&format!("{k}_{name}"))
}

/// A scratch directory of this test binary (created).
#[track_caller]
pub fn dir() -> PathBuf {
    let d = tmp("dir");
    std::fs::create_dir_all(&d).expect("creates the scratch directory");
    d
}

/// A scratch directory of its own for `test` (created).
#[track_caller]
pub fn workdir(test: &str) -> PathBuf {
    let d = tmp(test);
    std::fs::create_dir_all(&d).expect("creates the scratch directory");
    d
}

/// Write `text` to [`tmp`]`(name)` and return its path.
#[track_caller]
pub fn write(name: &str, text: &(impl AsRef<[u8]> + ?Sized)) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).expect("writes a scratch file");
    p
}

/// Write `text` to a new [`unique`] path ending in `name` and return it.
#[track_caller]
pub fn write_unique(name: &str, text: &(impl AsRef<[u8]> + ?Sized)) -> PathBuf {
    let p = unique(name);
    std::fs::write(&p, text).expect("writes a scratch file");
    p
}

/// A path as the `&str` an argument list takes.
pub fn p(x: &Path) -> &str {
    x.to_str().expect("UTF-8 path")
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

/// Exit 0 (else the stderr is shown); the standard output.
pub fn ok(o: &Output) -> String {
    assert!(o.status.success(), "stderr: {}", stderr(o));
    stdout(o)
}

/// Exit 0 and a JSON document on standard output.
pub fn json_of(o: &Output) -> Value {
    serde_json::from_str(&ok(o)).expect("stdout is one JSON document")
}

/// Exit 2, exactly one short stderr line (under 400 characters with the
/// scratch directory's path, which the machine chooses, counted as
/// `<tmp>`), no panic, containing every `needle`.
pub fn refused(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(
        o.status.code(),
        Some(2),
        "stderr: {err} stdout: {}",
        stdout(o)
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    let own = err.replace(env!("CARGO_TARGET_TMPDIR"), "<tmp>");
    assert!(own.len() < 400, "too long ({} chars): {own}", own.len());
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in {err}");
    }
}

/// The coefficients of result document `doc`, in its order: name, value
/// and U95 (0 where it has none).
pub fn coefficient_values(doc: &Value) -> Vec<(String, f64, f64)> {
    doc["coefficients"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, c)| {
            (
                k.clone(),
                c["value"].as_f64().unwrap(),
                c["U95"].as_f64().unwrap_or(0.0),
            )
        })
        .collect()
}

/// The messages of the warnings of result document `v` with `code`.
pub fn warnings_with<'a>(v: &'a Value, code: &str) -> Vec<&'a str> {
    v["warnings"]
        .as_array()
        .expect("a warnings array")
        .iter()
        .filter(|w| w["code"] == code)
        .map(|w| w["message"].as_str().expect("a message"))
        .collect()
}

/// The sorted keys of a JSON object.
pub fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().expect("an object").keys().cloned().collect();
    k.sort();
    k
}

/// One procedure's worked example from the procedure registry.
pub struct RegistryCase {
    /// The registry id.
    pub id: &'static str,
    /// The document id its results carry.
    pub document: &'static str,
    /// `incal simulate` words after `simulate`, with the example's options.
    pub simulate: Vec<&'static str>,
    /// The reducing command's words.
    pub command: &'static [&'static str],
    /// The example's reduction options (besides `--input`).
    pub options: &'static [&'static str],
}

impl RegistryCase {
    /// The reducing command line on `file`: command, `--input FILE`, options.
    pub fn reduce<'a>(&self, file: &'a str) -> Vec<&'a str> {
        let mut v = self.command.to_vec();
        v.extend_from_slice(&["--input", file]);
        v.extend_from_slice(self.options);
        v
    }
}

/// Every procedure that reduces a simulated recording, with its worked
/// example from the procedure registry: the case table of every test that
/// runs all procedures.
pub fn registry_cases() -> Vec<RegistryCase> {
    incal::procedures::registry::REGISTRY
        .iter()
        .filter_map(|e| {
            let example = e.example?;
            let mut simulate = e.simulate?[1..].to_vec();
            simulate.extend_from_slice(example.simulate);
            Some(RegistryCase {
                id: e.id,
                document: e.document.as_str(),
                simulate,
                command: e.command,
                options: example.options,
            })
        })
        .collect()
}

/// A gyro and an accelerometer noise result of three axes (the docs'
/// Kalibr example), the CSV and JSON files in `dir` named `PREFIXgyro…`
/// and `PREFIXaccel…`: the exports' inputs.
pub fn noise_pair(dir: &Path, prefix: &str) -> (PathBuf, PathBuf) {
    let mut out = Vec::new();
    for (q, terms) in [
        ("gyro", ["--arw-deg-rth", "0.2", "--rrw-deg-h-rth", "40"]),
        ("accel", ["--vrw-ug-rthz", "60", "--accel-rw-ug-rts", "30"]),
    ] {
        let csv = dir.join(format!("{prefix}{q}.csv"));
        let mut a = vec![
            "simulate",
            "noise",
            "--quantity",
            q,
            "--rate-hz",
            "100",
            "--duration-s",
            "3600",
            "--channels",
            "3",
            "--seed",
            "11",
            "-o",
            p(&csv),
        ];
        a.extend_from_slice(&terms);
        ok(&run(&a));
        let json = dir.join(format!("{prefix}{q}.json"));
        ok(&run(&[
            "noise",
            "--input",
            p(&csv),
            "--rate-hz",
            "100",
            "--quantity",
            q,
            "--json",
            "-o",
            p(&json),
        ]));
        out.push(json);
    }
    (out[0].clone(), out[1].clone())
}
