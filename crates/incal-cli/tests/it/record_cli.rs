//! `incal record …` through the real binary: the JSON contract of add,
//! list, show, supersede, history and verify; drift recovered from
//! simulated tumble calibrations whose K0 steps linearly over chosen dates;
//! bad input; a store file changed behind incal's back; concurrent writer
//! processes; and `record add` killed at random moments.

use crate::common;
use common::*;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use incal::document::{Coefficient, DocumentBuilder, Procedure};
use incal::units::Unit;
use serde_json::Value;

/// `incal ARGS`, which must succeed; its standard output.
fn ok(args: &[&str]) -> String {
    let o = run(args);
    assert!(
        o.status.success(),
        "incal {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8(o.stdout).unwrap()
}

fn ok_json(args: &[&str]) -> Value {
    serde_json::from_str(&ok(args)).unwrap()
}

/// `incal ARGS`, which must fail with `code` and exactly one stderr line,
/// no panic; that line.
fn fails(code: i32, args: &[&str]) -> String {
    let o = run(args);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(code), "incal {args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("incal: "), "{err}");
    err.trim_end().to_string()
}

/// A fresh directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("incal-record-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A tumble result of `incal tumble` on `incal simulate tumble --k0 K0`.
fn tumble_result(dir: &Path, tag: &str, k0: f64, seed: u64, serial: Option<&str>) -> PathBuf {
    let csv = dir.join(format!("{tag}.csv"));
    let json = dir.join(format!("{tag}.json"));
    ok(&[
        "simulate",
        "tumble",
        "--k0",
        &k0.to_string(),
        "--seed",
        &seed.to_string(),
        "-o",
        s(&csv),
    ]);
    let mut args = vec![
        "tumble",
        "--mount",
        "pendulum",
        "--input",
        s(&csv),
        "--json",
        "-o",
        s(&json),
    ];
    if let Some(sn) = serial {
        args.extend(["--serial", sn]);
    }
    ok(&args);
    json
}

#[test]
fn add_list_show_supersede_history_verify_keep_the_contract() {
    let dir = temp_dir("contract");
    let db = dir.join("lab.db");
    let db = s(&db);
    // K0 drifts 0.2 µg/day from 8 mg; calibrations on irregular dates.
    let k0_0 = 8e-3;
    let rate = 0.2e-6;
    let dates = [
        ("2024-01-10", 0),
        ("2024-04-02", 83),
        ("2024-09-15", 249),
        ("2025-02-01", 388),
    ];
    let mut ids = Vec::new();
    let mut files = Vec::new();
    for (k, (date, day)) in dates.iter().enumerate() {
        let k0 = k0_0 + rate * *day as f64;
        let f = tumble_result(&dir, &format!("cal{k}"), k0, 100 + k as u64, Some("SN-7"));
        let added = ok_json(&[
            "record",
            "add",
            s(&f),
            "--db",
            db,
            "--operator",
            "lee",
            "--created-utc",
            date,
            "--json",
        ]);
        let bytes = std::fs::read(&f).unwrap();
        let keys: Vec<&str> = added
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        assert_eq!(keys, ["id", "sha256"]);
        assert_eq!(
            added["sha256"].as_str().unwrap(),
            incal_records::sha256_hex(&bytes),
            "sha256 of the stored bytes"
        );
        ids.push(added["id"].as_i64().unwrap());
        files.push(f);
    }
    assert_eq!(ids, [1, 2, 3, 4]);

    // A wrong result (a K0 far off), then its correction.
    let wrong = tumble_result(&dir, "wrong", 9e-3, 7, None);
    let text_id = ok(&[
        "record",
        "add",
        s(&wrong),
        "--db",
        db,
        "--serial",
        "SN-7",
        "--created-utc",
        "2025-06-01T09:00:00Z",
    ]);
    assert_eq!(text_id, "5\n", "text form: the id alone");
    let right = tumble_result(&dir, "right", k0_0 + rate * 508.0, 8, Some("SN-7"));
    let sup = ok_json(&[
        "record",
        "supersede",
        "5",
        s(&right),
        "--reason",
        "wrong K0 truth entered",
        "--db",
        db,
        "--created-utc",
        "2025-06-01T10:00:00Z",
        "--json",
    ]);
    assert_eq!(sup["id"], 6);
    fails(
        2,
        &[
            "record",
            "supersede",
            "5",
            s(&right),
            "--reason",
            "again",
            "--db",
            db,
        ],
    );

    // list: exact keys, superseded_by.
    let list = ok_json(&["record", "list", "--db", db, "--json"]);
    let recs = list["records"].as_array().unwrap();
    assert_eq!(recs.len(), 6);
    for r in recs {
        for key in [
            "id",
            "serial",
            "procedure",
            "created_utc",
            "sha256",
            "superseded_by",
        ] {
            assert!(r.get(key).is_some(), "{key} in {r}");
        }
        assert_eq!(r["serial"], "SN-7");
        assert_eq!(r["procedure"], "tumble");
    }
    assert_eq!(recs[0]["created_utc"], "2024-01-10T00:00:00Z");
    assert_eq!(recs[4]["superseded_by"], 6);
    assert_eq!(recs[5]["superseded_by"], Value::Null);
    let none = ok_json(&["record", "list", "--db", db, "--serial", "SN-0", "--json"]);
    assert_eq!(none["records"].as_array().unwrap().len(), 0);
    assert!(ok(&["record", "list", "--db", db]).contains("SN-7"));

    // show: the document unchanged.
    for (id, f) in [(2, &files[1]), (5, &wrong)] {
        let shown = ok_json(&["record", "show", &id.to_string(), "--db", db, "--json"]);
        assert_eq!(shown["id"], id);
        assert_eq!(shown["serial"], "SN-7");
        let original: Value = serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
        assert_eq!(shown["result"], original, "record {id}");
    }
    let text = ok(&["record", "show", "6", "--db", db]);
    assert!(
        text.contains("supersedes record 5: wrong K0 truth entered"),
        "{text}"
    );
    assert!(text.contains("Coefficients"), "{text}");

    // history: superseded record 5 left out, drift recovered.
    let h = ok_json(&[
        "record",
        "history",
        "--serial",
        "SN-7",
        "--coefficient",
        "K0",
        "--db",
        db,
        "--json",
    ]);
    let pts = h["points"].as_array().unwrap();
    let pid: Vec<i64> = pts.iter().map(|p| p["id"].as_i64().unwrap()).collect();
    assert_eq!(pid, [1, 2, 3, 4, 6]);
    for p in pts {
        for key in ["id", "created_utc", "value", "U95"] {
            assert!(p[key].is_number() || p[key].is_string(), "{key} in {p}");
        }
    }
    assert_eq!(h["unit"], "g");
    let d = &h["drift_per_day"];
    let (dv, du) = (d["value"].as_f64().unwrap(), d["u"].as_f64().unwrap());
    assert!(du > 0.0);
    assert!(
        (dv - rate).abs() < 3.0 * du,
        "drift {dv} ± {du} per day vs truth {rate}"
    );
    assert!(h["repeatability"]["value"].as_f64().unwrap() > 0.0);
    assert_eq!(h["repeatability"]["dof"], 4.0);
    assert!(h["En_latest"].is_number());
    let table = ok(&[
        "record",
        "history",
        "--serial",
        "SN-7",
        "--coefficient",
        "K0",
        "--db",
        db,
    ]);
    assert!(
        table.contains("created_utc") && table.contains("ug/day"),
        "{table}"
    );

    let v = ok(&["record", "verify", "--db", db]);
    assert!(v.starts_with("ok: 6 records"), "{v}");
    let vj = ok_json(&["record", "verify", "--db", db, "--json"]);
    assert_eq!(vj["records"], 6);
    // record list shows the same chain head, text and JSON.
    let head = vj["head"].as_str().unwrap();
    let lj = ok_json(&["record", "list", "--db", db, "--json"]);
    assert_eq!(lj["chain"]["head"], head);
    assert_eq!(lj["chain"]["records"], 6);
    let lt = ok(&["record", "list", "--db", db]);
    assert!(
        lt.trim_end()
            .ends_with(&format!("chain: 6 records, hash chain intact; head {head}")),
        "{lt}"
    );

    // $INCAL_DB, and incal.db in the working directory.
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["record", "list", "--json"])
        .env("INCAL_DB", db)
        .output()
        .unwrap();
    assert!(o.status.success());
    let from_env: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(from_env["records"].as_array().unwrap().len(), 6);
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["record", "add", s(&files[0])])
        .env_remove("INCAL_DB")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(dir.join("incal.db").exists());
}

#[test]
fn bad_input_is_one_line_and_exit_2() {
    let dir = temp_dir("bad");
    let db = dir.join("r.db");
    let db = s(&db);
    let with = tumble_result(&dir, "with", 8e-3, 1, Some("SN-1"));
    let without = tumble_result(&dir, "without", 8e-3, 2, None);
    let csv = dir.join("with.csv");
    let m = fails(2, &["record", "add", s(&csv), "--db", db]);
    assert!(m.contains("with.csv") && m.contains("JSON"), "{m}");
    let other = dir.join("other.json");
    std::fs::write(&other, r#"{"schema": "incal.plan/1"}"#).unwrap();
    let m = fails(2, &["record", "add", s(&other), "--db", db]);
    assert!(m.contains("other.json") && m.contains("$.schema"), "{m}");
    let m = fails(2, &["record", "add", s(&without), "--db", db]);
    assert!(m.contains("--serial"), "{m}");
    let m = fails(
        2,
        &["record", "add", s(&with), "--db", db, "--serial", "SN-2"],
    );
    assert!(m.contains("--serial 'SN-2'") && m.contains("SN-1"), "{m}");
    let m = fails(
        2,
        &[
            "record",
            "add",
            s(&with),
            "--db",
            db,
            "--created-utc",
            "2024-13-01",
        ],
    );
    assert!(m.contains("--created-utc"), "{m}");
    let m = fails(2, &["record", "add", s(&dir.join("none.json")), "--db", db]);
    assert!(m.contains("none.json"), "{m}");
    // Nothing was written; reading commands do not create a store.
    let m = fails(2, &["record", "list", "--db", db]);
    assert!(m.contains("r.db") && m.contains("no records store"), "{m}");
    assert!(!Path::new(db).exists());

    ok(&["record", "add", s(&with), "--db", db]);
    assert!(fails(2, &["record", "show", "7", "--db", db]).contains("record 7"));
    fails(2, &["record", "show", "x", "--db", db]);
    let m = fails(
        2,
        &[
            "record",
            "history",
            "--serial",
            "SN-1",
            "--coefficient",
            "K9",
            "--db",
            db,
        ],
    );
    assert!(m.contains("K9") && m.contains("K0"), "{m}");
    fails(
        2,
        &[
            "record",
            "history",
            "--serial",
            "SN-9",
            "--coefficient",
            "K0",
            "--db",
            db,
        ],
    );
    let m = fails(2, &["record", "history", "--serial", "SN-1", "--db", db]);
    assert!(m.contains("--coefficient"), "{m}");
    fails(2, &["record", "supersede", "1", s(&with), "--db", db]);
    fails(
        2,
        &[
            "record",
            "supersede",
            "1",
            s(&with),
            "--reason",
            " ",
            "--db",
            db,
        ],
    );
    let junk = dir.join("junk.db");
    std::fs::write(&junk, vec![b'x'; 4096]).unwrap();
    let m = fails(2, &["record", "list", "--db", s(&junk)]);
    assert!(m.contains("junk.db"), "{m}");
    // One calibration: history without drift, nulls and no non-finite number.
    let h = ok_json(&[
        "record",
        "history",
        "--serial",
        "SN-1",
        "--coefficient",
        "K0",
        "--db",
        db,
        "--json",
    ]);
    assert_eq!(h["drift_per_day"]["value"], Value::Null);
    assert_eq!(h["repeatability"]["value"], Value::Null);
    assert_eq!(h["En_latest"], Value::Null);
    ok(&["record", "verify", "--db", db]);
}

#[test]
fn verify_names_a_record_changed_behind_incals_back() {
    let dir = temp_dir("tamper");
    let db = dir.join("r.db");
    for k in 0..3 {
        let f = tumble_result(&dir, &format!("t{k}"), 8e-3, 20 + k, Some("SN-3"));
        ok(&["record", "add", s(&f), "--db", s(&db)]);
    }
    ok(&["record", "verify", "--db", s(&db)]);
    // A coefficient value edited in the stored document of record 2.
    let c = rusqlite::Connection::open(&db).unwrap();
    let doc: String = c
        .query_row("SELECT document FROM records WHERE id = 2", [], |r| {
            r.get(0)
        })
        .unwrap();
    let mut v: Value = serde_json::from_str(&doc).unwrap();
    let k0 = v["coefficients"]["K0"]["value"].as_f64().unwrap();
    v["coefficients"]["K0"]["value"] = Value::from(k0 + 1e-6);
    c.execute(
        "UPDATE records SET document = ?1 WHERE id = 2",
        [serde_json::to_string_pretty(&v).unwrap()],
    )
    .unwrap();
    drop(c);
    let m = fails(1, &["record", "verify", "--db", s(&db)]);
    assert!(
        m.starts_with(&format!("incal: {}: record 2: ", s(&db))),
        "{m}"
    );
    // Reading commands refuse the broken store naming the record, and
    // nothing is added onto it.
    for args in [
        vec!["record", "show", "1", "--db", s(&db)],
        vec![
            "record",
            "history",
            "--serial",
            "SN-3",
            "--coefficient",
            "K0",
            "--db",
            s(&db),
        ],
    ] {
        let m = fails(1, &args);
        assert!(
            m.contains("record 2: ") && m.contains("the chain is broken"),
            "{m}"
        );
    }
    let f = tumble_result(&dir, "t9", 8e-3, 29, Some("SN-3"));
    let m = fails(1, &["record", "add", s(&f), "--db", s(&db)]);
    assert!(m.contains("nothing is added to a broken chain"), "{m}");
}

/// The newest record deleted passes a plain verify (what is left is a
/// whole chain) but not `verify --head` with the head written down before;
/// a future date and a correction of another procedure are refused; names
/// are printed without control or bidi characters.
#[test]
fn head_checking_dates_procedures_and_printable_names() {
    let dir = temp_dir("head");
    let db = dir.join("r.db");
    for k in 0..3 {
        let f = tumble_result(&dir, &format!("t{k}"), 8e-3, 40 + k, Some("SN-4"));
        ok(&["record", "add", s(&f), "--db", s(&db)]);
    }
    let v = ok_json(&["record", "verify", "--db", s(&db), "--json"]);
    let head = v["head"].as_str().unwrap().to_string();
    ok(&["record", "verify", "--db", s(&db), "--head", &head]);
    let c = rusqlite::Connection::open(&db).unwrap();
    c.execute_batch(
        "DELETE FROM record_inputs WHERE record_id = 3; DELETE FROM records WHERE id = 3;",
    )
    .unwrap();
    drop(c);
    ok(&["record", "verify", "--db", s(&db)]);
    let m = fails(1, &["record", "verify", "--db", s(&db), "--head", &head]);
    assert!(m.contains(&format!("does not hold head {head}")), "{m}");
    let m = fails(2, &["record", "verify", "--db", s(&db), "--head", "abc"]);
    assert!(m.contains("--head") && m.contains("64 hexadecimal"), "{m}");

    let f = tumble_result(&dir, "late", 8e-3, 50, Some("SN-4"));
    let m = fails(
        2,
        &[
            "record",
            "add",
            s(&f),
            "--db",
            s(&db),
            "--created-utc",
            "2999-01-01",
        ],
    );
    assert!(m.contains("in the future"), "{m}");

    // A centrifuge-procedure document may not supersede a tumble record.
    let text = std::fs::read_to_string(&f).unwrap();
    let mut doc: Value = serde_json::from_str(&text).unwrap();
    doc["procedure"] = Value::from("centrifuge");
    let other = dir.join("other.json");
    std::fs::write(&other, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    let o = run(&[
        "record",
        "supersede",
        "1",
        s(&other),
        "--reason",
        "x",
        "--db",
        s(&db),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("must be of the same procedure") || err.contains("procedure"),
        "{err}"
    );

    let f = tumble_result(&dir, "esc", 8e-3, 51, Some("SN\u{1b}[2J\u{202e}x"));
    ok(&["record", "add", s(&f), "--db", s(&db)]);
    let list = ok(&["record", "list", "--db", s(&db)]);
    assert!(
        !list.contains('\u{1b}') && !list.contains('\u{202e}'),
        "{list:?}"
    );
    assert!(list.contains("SN\\u{001b}[2J\\u{202e}x"), "{list}");
}

/// SplitMix64, seeded: the kill delays.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// A small result document with a distinct K0.
fn small_doc(k: usize) -> String {
    let mut b = DocumentBuilder::new(Procedure::Tumble, "kill test");
    let c = Coefficient::new("K0", 1e-3 + k as f64 * 1e-9, 1e-6, Unit::G, 10.0).unwrap();
    b.coefficient("K0", c).unwrap();
    let mut doc = b.finish();
    doc.instrument.serial = Some("SN-K".into());
    doc.to_json()
}

#[test]
fn killing_record_add_at_random_moments_never_leaves_a_partial_record() {
    // 400 kills in the statistical tier.
    let n_trials = incal::sim::tier::trials(80, 400);
    let dir = temp_dir("kill");
    let db = dir.join("k.db");
    let docs: Vec<PathBuf> = (0..n_trials)
        .map(|k| {
            let p = dir.join(format!("d{k}.json"));
            std::fs::write(&p, small_doc(k)).unwrap();
            p
        })
        .collect();
    // How long one add takes here (on a scratch store): the delays span it.
    let scratch = dir.join("scratch.db");
    let mut took = Vec::new();
    for d in docs.iter().take(5) {
        let t = Instant::now();
        ok(&["record", "add", s(d), "--db", s(&scratch)]);
        took.push(t.elapsed());
    }
    took.sort();
    // The delays span about one add; the span follows the machine's load
    // (longer after a kill, shorter after a completed add), so that about
    // two thirds complete and one third is killed however busy it is.
    let mut span = (took[2].as_micros() as u64 * 3 / 2).clamp(2_000, 20_000);
    let mut rng = Rng(0x1AB_5EED);
    let started = Instant::now();
    let mut completed = Vec::new();
    let mut killed = 0;
    for (k, d) in docs.iter().enumerate() {
        let mut child = Command::new(env!("CARGO_BIN_EXE_incal"))
            .args(["record", "add", s(d), "--db", s(&db), "--json"])
            .env_remove("INCAL_DB")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_micros(rng.next() % span));
        let _ = child.kill();
        let out = child.wait_with_output().unwrap();
        if out.status.success() {
            completed.push(k);
            span = (span * 19 / 20).max(1_000);
        } else {
            killed += 1;
            span = (span * 11 / 10).min(2_000_000);
            // Killed, never failed on its own.
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(out.status.code().is_none(), "trial {k}: {err}");
        }
    }
    let elapsed = started.elapsed();
    eprintln!(
        "{n_trials} trials in {elapsed:?}: {} completed, {killed} killed (delays up to {span} µs at the end)",
        completed.len()
    );
    assert!(
        killed > n_trials / 10,
        "too few kills ({killed}) to test anything"
    );
    assert!(completed.len() > n_trials / 10, "too few completed adds");
    let v = ok(&["record", "verify", "--db", s(&db)]);
    assert!(v.starts_with("ok: "), "{v}");
    let store = incal_records::Store::open_existing(&db).unwrap();
    let list = store.list(None).unwrap();
    assert!(list.len() >= completed.len() && list.len() <= n_trials);
    // Every add that reported success is there, whole, with its document.
    for k in &completed {
        let sha = incal_records::sha256_hex(small_doc(*k).as_bytes());
        let r = list.iter().find(|r| r.sha256 == sha);
        assert!(r.is_some(), "trial {k} succeeded but its record is missing");
        let shown = store.show(r.unwrap().id).unwrap();
        assert_eq!(shown.document, small_doc(*k));
    }
    let c = rusqlite::Connection::open(&db).unwrap();
    let check: String = c
        .query_row("PRAGMA integrity_check", [], |r| r.get(0))
        .unwrap();
    assert_eq!(check, "ok");
    // The store still takes records after all that.
    ok(&["record", "add", s(&docs[0]), "--db", s(&db)]);
    ok(&["record", "verify", "--db", s(&db)]);
}

#[test]
fn eight_writer_processes_at_once_lose_nothing() {
    const WRITERS: usize = 8;
    const EACH: usize = 3;
    let dir = temp_dir("procs");
    let db = dir.join("p.db");
    let docs: Vec<PathBuf> = (0..WRITERS * EACH)
        .map(|k| {
            let p = dir.join(format!("d{k}.json"));
            std::fs::write(&p, small_doc(1000 + k)).unwrap();
            p
        })
        .collect();
    // Each writer is a shell-free chain: one process per record, the
    // writers' processes all running at once.
    let handles: Vec<_> = (0..WRITERS)
        .map(|w| {
            let mine: Vec<PathBuf> = docs[w * EACH..(w + 1) * EACH].to_vec();
            let db = db.clone();
            std::thread::spawn(move || {
                for d in mine {
                    ok(&["record", "add", s(&d), "--db", s(&db)]);
                }
            })
        })
        .collect();
    for h in handles {
        h.join().expect("a writer failed");
    }
    let list = ok_json(&["record", "list", "--db", s(&db), "--json"]);
    let ids: Vec<i64> = list["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["id"].as_i64().unwrap())
        .collect();
    assert_eq!(ids, (1..=(WRITERS * EACH) as i64).collect::<Vec<_>>());
    ok(&["record", "verify", "--db", s(&db)]);
}

/// Records are never lost or stored twice: in-memory
/// and URI stores are refused; an output that fails after the commit says
/// the record is stored (exit 3) and the retry finds it instead of adding
/// a duplicate; reading commands refuse an empty or foreign file and
/// leave it as it was.
#[test]
fn no_record_is_lost_or_stored_twice() {
    let dir = temp_dir("lost-or-twice");
    let r = tumble_result(&dir, "a", 1e-3, 3, Some("SN-9"));
    for db in [":memory:", "file::memory:", "file:x.db?mode=memory"] {
        let e = fails(2, &["record", "add", s(&r), "--db", db]);
        assert!(e.contains("give the path of a records file"), "{e}");
    }
    let db = dir.join("r.db");
    if Path::new("/dev/full").exists() {
        let e = fails(
            3,
            &["record", "add", s(&r), "--db", s(&db), "-o", "/dev/full"],
        );
        assert!(
            e.contains("record 1 stored; writing the output failed"),
            "{e}"
        );
    } else {
        ok(&["record", "add", s(&r), "--db", s(&db)]);
    }
    let o = run(&["record", "add", s(&r), "--db", s(&db), "--json"]);
    let again: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(again["id"], 1);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("record 1 already holds this document"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let list = ok_json(&["record", "list", "--db", s(&db), "--json"]);
    assert_eq!(
        list["records"]
            .as_array()
            .map(|a| a.len())
            .unwrap_or(usize::MAX),
        1,
        "{list}"
    );

    let empty = dir.join("empty.db");
    std::fs::write(&empty, b"").unwrap();
    for cmd in ["verify", "list"] {
        let e = fails(2, &["record", cmd, "--db", s(&empty)]);
        assert!(
            e.contains("not an incal records store (an empty file)"),
            "{e}"
        );
    }
    assert_eq!(std::fs::metadata(&empty).unwrap().len(), 0);
    let foreign = dir.join("other.sqlite");
    rusqlite::Connection::open(&foreign)
        .unwrap()
        .execute_batch("CREATE TABLE notes (id INTEGER PRIMARY KEY, text TEXT); INSERT INTO notes (text) VALUES ('mine');")
        .unwrap();
    let bytes = std::fs::read(&foreign).unwrap();
    for args in [
        vec!["record", "verify", "--db", s(&foreign)],
        vec!["record", "add", s(&r), "--db", s(&foreign)],
    ] {
        let e = fails(2, &args);
        assert!(e.contains("not an incal records store"), "{e}");
    }
    assert_eq!(std::fs::read(&foreign).unwrap(), bytes);
}

#[test]
fn the_certificate_names_its_record_and_the_chain_head() {
    let dir = temp_dir("certificate-head");
    let db = dir.join("incal.db");
    let a = tumble_result(&dir, "a", 8000.0, 1, Some("SN-C"));
    let b = tumble_result(&dir, "b", 8001.0, 2, Some("SN-C"));
    for f in [&a, &b] {
        ok(&["record", "add", s(f), "--db", s(&db)]);
    }
    let head = ok_json(&["record", "verify", "--db", s(&db), "--json"])["head"]
        .as_str()
        .unwrap()
        .to_string();
    let html = ok(&["report", s(&a), "--db", s(&db)]);
    assert!(html.contains("record 1 in"), "the record of this document");
    assert!(html.contains(&head), "the chain head, whole");
    // A result of a new instrument, judged against limits: with the store
    // named, a certificate with no history, said so (not "no records of
    // this instrument"); with an incal.db merely lying in the working
    // directory, no store at all.
    let c = tumble_result(&dir, "c", 8000.0, 3, Some("SN-NEW"));
    let limits = dir.join("l.toml");
    std::fs::write(&limits, "[tumble]\nK1 = { min = 9.9, max = 10.1 }\n").unwrap();
    let report_in_dir = |extra: &[&str]| {
        let mut args = vec!["report", s(&c), "--limits", s(&limits), "-o", "c.html"];
        args.extend_from_slice(extra);
        let o = Command::new(env!("CARGO_BIN_EXE_incal"))
            .args(&args)
            .env_remove("INCAL_DB")
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(dir.join("c.html")).unwrap()
    };
    let html = report_in_dir(&["--db", "incal.db"]);
    assert!(
        html.contains("not stored in incal.db"),
        "named as not stored"
    );
    assert!(html.contains(&head));
    assert!(html.contains("No history: incal.db holds fewer than two calibrations"));
    let html = report_in_dir(&[]);
    assert!(
        !html.contains("incal.db") && !html.contains(&head),
        "no store unless named"
    );
    // A store named by $INCAL_DB must exist, as one named by --db.
    let missing = dir.join("missing.db");
    let o = Command::new(env!("CARGO_BIN_EXE_incal"))
        .args(["report", s(&c)])
        .env("INCAL_DB", &missing)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.db"));
}

#[path = "../../../incal-records/tests/it/common/pg.rs"]
mod pg;

/// `--db postgresql://…` keeps the same store on a PostgreSQL server
/// (a throwaway one for this test): export from SQLite, import into
/// PostgreSQL, the same chain head, list, history and export; stations
/// writing at once; a URL's password is never printed.
#[test]
fn a_store_moves_between_sqlite_and_postgresql() {
    let dir = temp_dir("pg");
    let db = dir.join("lab.db");
    let docs: Vec<PathBuf> = [(1.0e-3, 1, "SN-1"), (1.1e-3, 2, "SN-1"), (5e-4, 3, "SN-2")]
        .iter()
        .map(|&(k0, seed, sn)| tumble_result(&dir, &format!("r{seed}"), k0, seed, Some(sn)))
        .collect();
    for (d, day) in docs.iter().zip(["2025-01-01", "2025-02-01", "2025-02-02"]) {
        ok(&["record", "add", s(d), "--db", s(&db), "--created-utc", day]);
    }
    let fixed = tumble_result(&dir, "fixed", 1.05e-3, 4, Some("SN-1"));
    ok(&[
        "record",
        "supersede",
        "2",
        s(&fixed),
        "--reason",
        "wrong gravity",
        "--db",
        s(&db),
        "--created-utc",
        "2025-02-03",
    ]);
    let export = dir.join("lab.jsonl");
    ok(&["record", "export", "--db", s(&db), "-o", s(&export)]);
    assert_eq!(std::fs::read_to_string(&export).unwrap().lines().count(), 4);

    let url = pg::pg_database("cli_move");
    let imported = ok_json(&["record", "import", s(&export), "--db", &url, "--json"]);
    assert_eq!(imported["added"], 4);
    assert_eq!(imported["present"], 0);
    let lite = ok_json(&["record", "verify", "--db", s(&db), "--json"]);
    let post = ok_json(&["record", "verify", "--db", &url, "--json"]);
    assert_eq!(lite, post, "the same chain head on both stores");
    assert_eq!(post["records"], 4);
    for args in [
        vec!["record", "list", "--json"],
        vec![
            "record",
            "history",
            "--serial",
            "SN-1",
            "--coefficient",
            "K0",
            "--json",
        ],
        vec!["record", "show", "4", "--json"],
    ] {
        let on = |store: &str| {
            let mut a = args.clone();
            a.extend(["--db", store]);
            ok(&a)
        };
        assert_eq!(on(s(&db)), on(&url), "{args:?}");
    }
    assert_eq!(
        ok(&["record", "export", "--db", &url]),
        std::fs::read_to_string(&export).unwrap(),
        "PostgreSQL's export is SQLite's, byte for byte"
    );
    let again = ok_json(&["record", "import", s(&export), "--db", &url, "--json"]);
    assert_eq!(
        (again["added"].as_i64(), again["present"].as_i64()),
        (Some(0), Some(4))
    );
    // A certificate from the PostgreSQL store names the record and head.
    let html = ok(&["report", s(&fixed), "--db", &url]);
    assert!(
        html.contains(post["head"].as_str().unwrap()),
        "the head on the certificate"
    );

    // Stations writing to the shared store at once: nothing lost.
    let handles: Vec<_> = (0..8)
        .map(|w| {
            let (url, p) = (url.clone(), dir.join(format!("st{w}.json")));
            std::fs::write(&p, small_doc(2000 + w)).unwrap();
            std::thread::spawn(move || ok(&["record", "add", s(&p), "--db", &url]))
        })
        .collect();
    let mut ids: Vec<i64> = handles
        .into_iter()
        .map(|h| h.join().unwrap().trim().parse().unwrap())
        .collect();
    ids.sort_unstable();
    assert_eq!(ids, (5..=12).collect::<Vec<_>>());
    assert_eq!(
        ok_json(&["record", "verify", "--db", &url, "--json"])["records"],
        12
    );

    // Bad stores: one line, exit 2, no password.
    let e = fails(
        2,
        &[
            "record",
            "list",
            "--db",
            "postgresql://lab:s3cret@127.0.0.1:1/none",
        ],
    );
    assert!(
        e.starts_with("incal: postgresql://lab@127.0.0.1:1/none: cannot connect"),
        "{e}"
    );
    assert!(!e.contains("s3cret"));
    let e = fails(
        2,
        &["record", "add", s(&docs[0]), "--db", "mysql://host/db"],
    );
    assert!(e.contains("a URL incal cannot open"), "{e}");
    let other = pg::pg_database("cli_other");
    ok(&["record", "add", s(&fixed), "--db", &other]);
    let e = fails(2, &["record", "import", s(&export), "--db", &other]);
    assert!(
        e.contains("line 1: record 1 differs from the store's record 1"),
        "{e}"
    );
}

/// `incal batch`: many recordings on the local cores, results as the
/// one-file command gives them and in order, parallel equal to serial,
/// each bad recording named on its own line without stopping the rest,
/// records written once each however often the batch runs.
#[test]
fn batch_reduces_many_recordings_and_names_the_bad_ones() {
    let dir = temp_dir("batch");
    let runs = dir.join("runs");
    std::fs::create_dir_all(&runs).unwrap();
    for k in 1..=10 {
        let p = runs.join(format!("SN-{k:03}.csv"));
        ok(&[
            "simulate",
            "tumble",
            "--seed",
            &k.to_string(),
            "--k0",
            &format!("{}e-4", k),
            "-o",
            s(&p),
        ]);
    }
    std::fs::write(runs.join("SN-900.csv"), "angle_deg,output\n0,1\n90,x\n").unwrap();
    std::fs::write(runs.join("SN-901.csv"), "").unwrap();
    std::fs::write(runs.join(".hidden.csv"), "not a recording").unwrap();
    let db = dir.join("line.db");
    let batch = |jobs: &str, extra: &[&str]| {
        let mut args = vec![
            "batch",
            "tumble",
            s(&runs),
            "--jobs",
            jobs,
            "--serial-from-stem",
            "--json",
        ];
        args.extend(extra);
        args.extend(["--", "--mount", "pendulum"]);
        run(&args)
    };
    let serial = batch("1", &[]);
    let parallel = batch("2", &["--db", s(&db)]);
    for o in [&serial, &parallel] {
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        let lines: Vec<&str> = err.lines().collect();
        assert_eq!(lines.len(), 3, "{err}");
        assert!(
            lines[0].starts_with("incal: ") && lines[0].contains("SN-900.csv:3"),
            "{err}"
        );
        assert!(lines[1].contains("SN-901.csv"), "{err}");
        assert_eq!(
            lines[2],
            "incal: batch: 2 of 12 recordings refused (named above)"
        );
    }
    let (a, b): (Value, Value) = (
        serde_json::from_slice(&serial.stdout).unwrap(),
        serde_json::from_slice(&parallel.stdout).unwrap(),
    );
    assert_eq!(
        (
            b["recordings"].as_i64(),
            b["ok"].as_i64(),
            b["failed"].as_i64()
        ),
        (Some(12), Some(10), Some(2))
    );
    for (k, (x, y)) in a["results"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["results"].as_array().unwrap())
        .enumerate()
    {
        assert_eq!(x["input"], y["input"], "in order");
        assert_eq!(x["result"], y["result"], "parallel = serial");
        if k < 10 {
            assert_eq!(y["record"], k as i64 + 1);
            let one = ok_json(&[
                "tumble",
                "--mount",
                "pendulum",
                "--input",
                x["input"].as_str().unwrap(),
                "--json",
                "--serial",
                &format!("SN-{:03}", k + 1),
            ]);
            assert_eq!(x["result"], one, "as the one-file command");
        }
    }
    // Again into the same store: nothing stored twice.
    let again: Value = serde_json::from_slice(&batch("2", &["--db", s(&db)]).stdout).unwrap();
    assert!(again["results"].as_array().unwrap()[..10]
        .iter()
        .all(|r| r["already_stored"] == true));
    assert_eq!(
        ok_json(&["record", "verify", "--db", s(&db), "--json"])["records"],
        10
    );

    // A list file, an output directory and the text summary.
    let list = dir.join("todo.txt");
    std::fs::write(&list, "# today\nruns/SN-002.csv\n\nruns/SN-404.csv\n").unwrap();
    let out = dir.join("out");
    let o = run(&[
        "batch",
        "tumble",
        "--list",
        s(&list),
        "--out-dir",
        s(&out),
        "--",
        "--mount",
        "pendulum",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("ok    ") && text.contains("SN-002.json"),
        "{text}"
    );
    assert!(
        text.ends_with("1 of 2 recordings reduced, 1 failed\n"),
        "{text}"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("SN-404.csv: cannot read"));
    assert!(out.join("SN-002.json").is_file());

    // Usage errors are the batch's, said once.
    let e = fails(
        2,
        &["batch", "tumble", s(&runs), "--", "--mount", "sideways"],
    );
    assert!(e.contains("invalid value 'sideways' for '--mount"), "{e}");
    let e = fails(2, &["batch", "wobble", s(&runs)]);
    assert!(
        e.contains("'wobble' is not a procedure (one of: tumble, centrifuge"),
        "{e}"
    );
    let e = fails(2, &["batch", "tumble", s(&runs), "--", "--input", "x.csv"]);
    assert!(e.contains("--input is set by the batch"), "{e}");
    let e = fails(2, &["batch", "tumble"]);
    assert!(e.contains("no recordings"), "{e}");
}
