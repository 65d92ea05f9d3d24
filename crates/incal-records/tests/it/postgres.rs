//! The records store on a PostgreSQL server (a throwaway server started
//! for this test process, `tests/common`): the same records give the same
//! hash chain as on SQLite; tampering, supersession, history and eight
//! concurrent writers behave as on SQLite; `export` from one and `import`
//! into the other rebuild the same chain.

use crate::common;

use std::sync::{Arc, Barrier};

use common::{outsider, pg_database, temp_dir, tumble_doc};
use incal_records::{Error, NewRecord, Store};

/// The same calibrations, corrections included, written to `location`.
fn fill(location: &str) -> Store {
    let mut s = Store::open(location).unwrap();
    for (k, day) in [
        (1.0e-3, "2025-01-01"),
        (1.1e-3, "2025-02-01"),
        (1.2e-3, "2025-03-01"),
    ] {
        let doc = tumble_doc(Some("SN-1"), k, 1e-5, 20.0);
        s.add(&NewRecord {
            operator: Some("lee"),
            created_utc: Some(day),
            ..NewRecord::new(&doc)
        })
        .unwrap();
    }
    let doc = tumble_doc(None, 5e-4, 1e-5, 20.0);
    s.add(&NewRecord {
        serial: Some("SN-2"),
        station: Some("head-2"),
        created_utc: Some("2025-03-02T10:00:00Z"),
        ..NewRecord::new(&doc)
    })
    .unwrap();
    let fixed = tumble_doc(Some("SN-1"), 1.15e-3, 1e-5, 20.0);
    s.supersede(
        2,
        &NewRecord {
            created_utc: Some("2025-03-05"),
            ..NewRecord::new(&fixed)
        },
        "wrong gravity",
    )
    .unwrap();
    s
}

fn sqlite(name: &str) -> String {
    temp_dir(name).join("incal.db").display().to_string()
}

#[test]
fn the_same_records_make_the_same_chain_on_sqlite_and_postgresql() {
    let lite = fill(&sqlite("pg-same"));
    let url = pg_database("same");
    let pg = fill(&url);
    assert!(pg.is_postgres() && !lite.is_postgres());
    let (a, b) = (lite.verify().unwrap(), pg.verify().unwrap());
    assert_eq!(a.records, 5);
    assert_eq!(a, b, "identical chain heads");
    assert_eq!(lite.list(None).unwrap(), pg.list(None).unwrap());
    assert_eq!(
        lite.list(Some("SN-2")).unwrap(),
        pg.list(Some("SN-2")).unwrap()
    );
    for id in 1..=5 {
        assert_eq!(lite.show(id).unwrap(), pg.show(id).unwrap(), "record {id}");
    }
    // Supersession: record 2 is out of history, record 5 in.
    let (h1, h2) = (
        lite.history("SN-1", "K0").unwrap(),
        pg.history("SN-1", "K0").unwrap(),
    );
    assert_eq!(h1, h2);
    assert_eq!(
        h2.points.iter().map(|p| p.id).collect::<Vec<_>>(),
        [1, 3, 5]
    );
    assert!(h2.drift.is_some());
    assert_eq!(pg.list(None).unwrap()[1].superseded_by, Some(5));
    let mut pg = pg;
    let again = tumble_doc(Some("SN-1"), 1.2e-3, 1e-5, 20.0);
    let e = pg
        .supersede(2, &NewRecord::new(&again), "again")
        .unwrap_err();
    assert!(
        e.to_string().contains("already superseded by record 5"),
        "{e}"
    );
    // A retried add stores nothing.
    let added = pg.add(&NewRecord::new(&again)).unwrap();
    assert!(added.existing && added.id == 3);
    assert_eq!(pg.verify_head(&a.head).unwrap().records, 5);
    assert!(pg
        .path()
        .display()
        .to_string()
        .starts_with("postgresql://incal@127.0.0.1:"));
}

#[test]
fn verify_names_the_record_changed_behind_its_back_on_postgresql() {
    let cases = [
        ("UPDATE records SET document = replace(document, '0.0011', '0.0019') WHERE id = 2", 2),
        ("UPDATE records SET created_utc = '2024-12-31T00:00:00Z' WHERE id = 1", 1),
        ("UPDATE records SET operator = 'kim' WHERE id = 2", 2),
        ("UPDATE records SET station = NULL WHERE id = 4", 4),
        ("UPDATE record_inputs SET sha256 = 'ff' WHERE record_id = 3", 3),
        ("UPDATE instruments SET serial = 'SN-X' WHERE serial = 'SN-2'", 4),
        ("UPDATE records SET record_hash = 'ab' WHERE id = 3", 3),
        ("DELETE FROM record_inputs WHERE record_id = 2; DELETE FROM supersessions WHERE old_id = 2; DELETE FROM records WHERE id = 2", 3),
        ("UPDATE supersessions SET reason = 'other' WHERE new_id = 5", 5),
        ("INSERT INTO supersessions (old_id, new_id, reason, created_utc) VALUES (1, 9, 'x', '2025-03-01T00:00:00Z')", 1),
    ];
    for (k, (sql, id)) in cases.into_iter().enumerate() {
        let url = pg_database(&format!("tamper{k}"));
        let mut s = fill(&url);
        outsider(&url, sql);
        let e = s.verify().unwrap_err();
        match &e {
            Error::Tampered { id: got, .. } => assert_eq!(*got, id, "{sql}: {e}"),
            other => panic!("{sql}: expected record {id} named, got {other}"),
        }
        // Nothing is added to a broken chain.
        let doc = tumble_doc(Some("SN-3"), 1e-3, 1e-5, 20.0);
        let e = s.add(&NewRecord::new(&doc)).unwrap_err();
        assert!(e.to_string().contains("nothing is added"), "{e}");
    }
}

#[test]
fn eight_concurrent_writers_on_postgresql_lose_nothing() {
    const WRITERS: usize = 8;
    const EACH: usize = 10;
    let url = pg_database("concurrent");
    // Every writer opens the (still empty) database at the same moment:
    // the migrations race too.
    let barrier = Arc::new(Barrier::new(WRITERS));
    let handles: Vec<_> = (0..WRITERS)
        .map(|w| {
            let (url, barrier) = (url.clone(), Arc::clone(&barrier));
            std::thread::spawn(move || {
                barrier.wait();
                let mut s = Store::open(&url).unwrap();
                let serial = format!("SN-{w}");
                (0..EACH)
                    .map(|k| {
                        let doc = tumble_doc(Some(&serial), 1e-3 + k as f64 * 1e-6, 1e-6, 30.0);
                        s.add(&NewRecord::new(&doc)).unwrap().id
                    })
                    .collect::<Vec<_>>()
            })
        })
        .collect();
    let mut ids: Vec<i64> = handles
        .into_iter()
        .flat_map(|h| h.join().expect("a writer failed"))
        .collect();
    ids.sort_unstable();
    let n = (WRITERS * EACH) as i64;
    assert_eq!(ids, (1..=n).collect::<Vec<_>>(), "every add got its own id");
    let s = Store::open_existing(&url).unwrap();
    assert_eq!(s.list(None).unwrap().len() as i64, n);
    for w in 0..WRITERS {
        let serial = format!("SN-{w}");
        assert_eq!(s.history(&serial, "K0").unwrap().points.len(), EACH);
    }
    assert_eq!(s.verify().unwrap().records, n);
}

#[test]
fn export_from_sqlite_and_import_into_postgresql_rebuild_the_same_chain() {
    let lite = fill(&sqlite("pg-export"));
    let mut lines = Vec::new();
    let exported = lite.export(&mut lines).unwrap();
    assert_eq!(exported, lite.verify().unwrap());
    let text = String::from_utf8(lines.clone()).unwrap();
    assert_eq!(text.lines().count(), 5);

    let url = pg_database("import");
    let mut pg = Store::open(&url).unwrap();
    // Half, then all: the second import adds the rest and nothing twice.
    let half: String = text.lines().take(2).map(|l| format!("{l}\n")).collect();
    let first = pg.import(half.as_bytes(), "half.jsonl").unwrap();
    assert_eq!((first.added, first.present), (2, 0));
    let all = pg.import(&lines[..], "all.jsonl").unwrap();
    assert_eq!((all.added, all.present), (3, 2));
    assert_eq!(all.chain, exported, "the same head on both stores");
    let again = pg.import(&lines[..], "all.jsonl").unwrap();
    assert_eq!((again.added, again.present), (0, 5));
    assert_eq!(pg.verify().unwrap(), exported);
    // And back: PostgreSQL's export is byte for byte SQLite's.
    let mut back = Vec::new();
    pg.export(&mut back).unwrap();
    assert_eq!(back, lines);
    assert_eq!(
        lite.history("SN-1", "K0").unwrap(),
        pg.history("SN-1", "K0").unwrap()
    );

    // A store holding another chain is refused; nothing is written.
    let other_url = pg_database("import-other");
    let mut other = Store::open(&other_url).unwrap();
    let doc = tumble_doc(Some("SN-9"), 1e-3, 1e-5, 20.0);
    other.add(&NewRecord::new(&doc)).unwrap();
    let e = other.import(&lines[..], "all.jsonl").unwrap_err();
    assert!(
        e.to_string() == "all.jsonl: line 1: record 1 differs from the store's record 1: the store holds another chain",
        "{e}"
    );
    assert_eq!(other.verify().unwrap().records, 1);
}

#[test]
fn a_bad_export_line_is_named_and_nothing_is_imported() {
    let lite = fill(&sqlite("pg-bad-import"));
    let mut lines = Vec::new();
    lite.export(&mut lines).unwrap();
    let text = String::from_utf8(lines).unwrap();
    let url = pg_database("bad_import");
    let mut pg = Store::open(&url).unwrap();
    let edit = |line: usize, from: &str, to: &str| -> String {
        text.lines()
            .enumerate()
            .map(|(k, l)| {
                let l = if k + 1 == line {
                    l.replacen(from, to, 1)
                } else {
                    l.to_string()
                };
                format!("{l}\n")
            })
            .collect()
    };
    for (bad, want) in [
        (
            edit(3, "\"operator\":\"lee\"", "\"operator\":\"kim\""),
            "line 3: record 3: record_hash does not match its fields",
        ),
        (
            edit(2, "0.0011", "0.0019"),
            "line 2: record 2: the document does not match its sha256",
        ),
        (edit(4, "{", "["), "line 4: not an exported record"),
        (
            text.lines().skip(1).map(|l| format!("{l}\n")).collect(),
            "line 1: record 2 follows record 0: records 1..1 are missing",
        ),
    ] {
        let e = pg.import(bad.as_bytes(), "x.jsonl").unwrap_err();
        assert!(matches!(e, Error::Input(_)), "{e}");
        assert!(
            e.to_string().starts_with(&format!("x.jsonl: {want}")),
            "{e}"
        );
        assert_eq!(pg.verify().unwrap().records, 0, "all or nothing");
    }
}

#[test]
fn reading_a_postgresql_store_never_creates_or_writes() {
    let url = pg_database("readonly");
    let e = Store::open_existing(&url).unwrap_err();
    assert!(
        e.is_input() && e.to_string().contains("no incal tables"),
        "{e}"
    );
    let e = Store::open_to_write(&url).unwrap_err();
    assert!(
        e.is_input() && e.to_string().contains("no records store here"),
        "{e}"
    );
    outsider(&url, "CREATE TABLE inventory (id BIGINT)");
    let e = Store::open(&url).unwrap_err();
    assert!(
        e.is_input() && e.to_string().contains("other tables"),
        "{e}"
    );
    // A wrong port is a store error naming the URL without the password.
    let bad = "postgresql://incal:secret@127.0.0.1:1/none";
    let e = Store::open(bad).unwrap_err();
    assert!(e.is_input(), "{e}");
    assert!(
        e.to_string()
            .starts_with("postgresql://incal@127.0.0.1:1/none: cannot connect"),
        "{e}"
    );
    assert!(!e.to_string().contains("secret"));
    let url = pg_database("readonly2");
    fill(&url);
    let r = Store::open_existing(&url).unwrap();
    assert_eq!(r.verify().unwrap().records, 5);
}
