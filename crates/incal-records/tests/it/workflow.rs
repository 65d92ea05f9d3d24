//! The workflow and accounts in the hash chain: the rules the store keeps
//! whichever front end calls it, and `verify` catching a role, a decision
//! or a password changed behind incal's back.

use incal_records::{Actor, Error, EventKind, NewRecord, Role, State, Store};
use rusqlite::Connection;

use crate::common::{temp_dir, tumble_doc};

/// A well-formed Argon2id PHC string (the store checks the form only).
fn phc(tag: &str) -> String {
    format!("$argon2id$v=19$m=19456,t=2,p=1$c2FsdHNhbHQ${tag}")
}

fn as_(name: &str, role: Role) -> Actor {
    Actor {
        name: name.into(),
        role,
    }
}

/// A store with accounts eve (engineer), sam and sue (signatories), vic
/// (viewer), ada (admin), and record 6 submitted by eve.
fn lab(name: &str) -> (std::path::PathBuf, Store) {
    let path = temp_dir(name).join("lab.db");
    let s = lab_at(&path);
    (path, s)
}

/// The accounts and record of [`lab`] in the store at `location`.
fn lab_at(location: &std::path::Path) -> Store {
    let mut s = Store::open(location).unwrap();
    let root = Actor::console("root");
    for (u, r) in [
        ("eve", Role::Engineer),
        ("sam", Role::Signatory),
        ("sue", Role::Signatory),
        ("vic", Role::Viewer),
        ("ada", Role::Admin),
    ] {
        s.add_user(&root, u, r, &phc(u)).unwrap();
    }
    let doc = tumble_doc(Some("SN-1"), 0.01, 1e-4, 20.0);
    let added = s
        .submit(&as_("eve", Role::Engineer), &NewRecord::new(&doc))
        .unwrap();
    assert_eq!(added.id, 6);
    s
}

#[test]
fn the_workflow_runs_the_same_on_postgresql() {
    let url = crate::common::pg_database("workflow");
    let mut pg = lab_at(std::path::Path::new(&url));
    let (_, mut lite) = lab("pg-twin");
    for s in [&mut pg, &mut lite] {
        s.approve(&as_("sam", Role::Signatory), 6, Some("ok"))
            .unwrap();
        s.set_role(&Actor::console("root"), "vic", Role::Engineer)
            .unwrap();
        assert_eq!(s.review(6).unwrap().state, State::Approved);
        assert_eq!(s.account("vic").unwrap().unwrap().role, Role::Engineer);
        let v = s.verify().unwrap();
        assert_eq!((v.records, v.events), (1, 8));
    }
    assert_eq!(pg.accounts().unwrap().len(), 5);
    let mut out = Vec::new();
    pg.export(&mut out).unwrap();
    let copy = temp_dir("pg-copy").join("copy.db");
    let done = Store::import_at(&copy, std::io::Cursor::new(&out), "pg.jsonl").unwrap();
    assert_eq!(done.chain.events, 8);
    // A role raised behind incal's back on the server is caught there too.
    let mut c = postgres::Client::connect(&url, postgres::NoTls).unwrap();
    c.batch_execute("UPDATE events SET role = 'admin' WHERE username = 'eve'")
        .unwrap();
    assert!(matches!(
        pg.verify().unwrap_err(),
        Error::Tampered { id: 1, .. }
    ));
}

fn input(e: Error) -> String {
    assert!(e.is_input(), "{e}");
    e.to_string()
}

#[test]
fn roles_are_read_from_the_chain() {
    let (_, mut s) = lab("roles");
    let ada = as_("ada", Role::Admin);
    assert_eq!(s.account("eve").unwrap().unwrap().role, Role::Engineer);
    s.set_role(&ada, "eve", Role::Signatory).unwrap();
    s.set_disabled(&ada, "vic", true).unwrap();
    s.set_password(&ada, "sam", &phc("new")).unwrap();
    let acc = s.accounts().unwrap();
    assert_eq!(acc.len(), 5);
    assert_eq!(acc[0].role, Role::Signatory);
    assert!(acc[3].disabled);
    assert_eq!(acc[1].password_hash, phc("new"));
    let v = s.verify().unwrap();
    assert_eq!((v.records, v.events), (1, 9));
    // Only an admin manages accounts; an actor must hold its role.
    let e = input(
        s.add_user(&as_("sam", Role::Signatory), "x", Role::Admin, &phc("x"))
            .unwrap_err(),
    );
    assert!(e.contains("admin only"), "{e}");
    let e = input(
        s.add_user(&as_("eve", Role::Admin), "x", Role::Admin, &phc("x"))
            .unwrap_err(),
    );
    assert!(e.contains("is signatory, not admin"), "{e}");
    let e = input(
        s.add_user(&ada, "eve", Role::Viewer, &phc("x"))
            .unwrap_err(),
    );
    assert!(e.contains("exists"), "{e}");
    let e = input(
        s.add_user(&ada, "<script>", Role::Viewer, &phc("x"))
            .unwrap_err(),
    );
    assert!(e.contains("letters, digits"), "{e}");
    let e = input(
        s.add_user(&ada, "plain", Role::Viewer, "secret")
            .unwrap_err(),
    );
    assert!(e.contains("Argon2id"), "{e}");
    // A disabled account does nothing.
    s.set_disabled(&ada, "ada", true).unwrap();
    let e = input(s.set_role(&ada, "vic", Role::Admin).unwrap_err());
    assert!(e.contains("disabled"), "{e}");
}

#[test]
fn approval_follows_the_rules() {
    let (_, mut s) = lab("approve");
    assert_eq!(s.review(6).unwrap().state, State::Submitted);
    assert_eq!(s.review(6).unwrap().submitted_by.as_deref(), Some("eve"));
    let doc = tumble_doc(Some("SN-2"), 0.02, 1e-4, 20.0);
    let e = input(
        s.submit(&as_("vic", Role::Viewer), &NewRecord::new(&doc))
            .unwrap_err(),
    );
    assert!(e.contains("viewer may not submit"), "{e}");
    let e = input(s.approve(&as_("eve", Role::Engineer), 6, None).unwrap_err());
    assert!(e.contains("signatory only"), "{e}");
    let e = input(s.approve(&as_("ada", Role::Admin), 6, None).unwrap_err());
    assert!(e.contains("signatory only"), "{e}");
    // A signatory does not approve their own submission.
    let own = s
        .submit(&as_("sam", Role::Signatory), &NewRecord::new(&doc))
        .unwrap();
    let e = input(
        s.approve(&as_("sam", Role::Signatory), own.id, None)
            .unwrap_err(),
    );
    assert!(e.contains("someone else"), "{e}");
    let e = input(
        s.reject(&as_("sue", Role::Signatory), own.id, "  ")
            .unwrap_err(),
    );
    assert!(e.contains("reason"), "{e}");
    s.reject(&as_("sue", Role::Signatory), own.id, "wrong rig")
        .unwrap();
    assert_eq!(s.review(own.id).unwrap().state, State::Rejected);
    let ev = s
        .approve(&as_("sam", Role::Signatory), 6, Some("checked"))
        .unwrap();
    assert_eq!(ev.kind, EventKind::Approve);
    let r = s.review(6).unwrap();
    assert_eq!(r.state, State::Approved);
    assert_eq!(r.decision.unwrap().actor, "sam");
    // Once only, and never after a rejection.
    let e = input(
        s.approve(&as_("sue", Role::Signatory), 6, None)
            .unwrap_err(),
    );
    assert!(e.contains("is approved"), "{e}");
    let e = input(
        s.approve(&as_("sam", Role::Signatory), own.id, None)
            .unwrap_err(),
    );
    assert!(e.contains("is rejected"), "{e}");
    let e = input(
        s.approve(&as_("sam", Role::Signatory), 999, None)
            .unwrap_err(),
    );
    assert!(e.contains("no such record"), "{e}");
    // A superseded submission is not approved.
    let fix = tumble_doc(Some("SN-2"), 0.03, 1e-4, 20.0);
    let new = s
        .supersede_as(
            &as_("eve", Role::Engineer),
            own.id,
            &NewRecord::new(&fix),
            "rig fixed",
        )
        .unwrap();
    assert_eq!(s.review(own.id).unwrap().state, State::Superseded);
    assert_eq!(s.reviews().unwrap()[&new.id].state, State::Submitted);
    assert_eq!(s.events(Some(6), 10).unwrap().len(), 2);
    s.verify().unwrap();
}

/// Run `sql` on the store file behind incal's back; verify must fail at
/// `id`.
fn caught(name: &str, sql: &str, id: i64) {
    let (path, mut s) = lab(name);
    s.approve(&as_("sam", Role::Signatory), 6, None).unwrap();
    s.verify().unwrap();
    let c = Connection::open(&path).unwrap();
    c.execute_batch("PRAGMA foreign_keys = OFF").unwrap();
    c.execute_batch(sql).unwrap();
    drop(c);
    match s.verify().unwrap_err() {
        Error::Tampered { id: got, problem } => assert_eq!(got, id, "{sql}: {problem}"),
        other => panic!("{sql}: {other}"),
    }
    // Nothing more is written to a broken chain.
    let e = s
        .set_role(&Actor::console("root"), "vic", Role::Admin)
        .unwrap_err();
    assert!(matches!(e, Error::Tampered { .. }), "{e}");
}

#[test]
fn verify_catches_workflow_edits() {
    // A role raised behind incal's back.
    caught(
        "role",
        "UPDATE events SET role = 'signatory' WHERE username = 'eve'",
        1,
    );
    // An approval given to someone else.
    caught(
        "approver",
        "UPDATE events SET actor = 'sue' WHERE kind = 'record.approve'",
        8,
    );
    // An approval removed (the last entry: found through its absence only
    // with a head kept elsewhere; removed in the middle, the link breaks).
    caught(
        "rejection",
        "UPDATE events SET kind = 'record.reject' WHERE id = 8",
        8,
    );
    caught("removed", "DELETE FROM events WHERE id = 3", 4);
    // A password swapped for one the editor knows.
    caught(
        "password",
        "UPDATE passwords SET password_hash = '$argon2id$v=19$m=19456,t=2,p=1$c2FsdHNhbHQ$forged' WHERE event_id = 2",
        2,
    );
    // An event slipped in at a record's position.
    caught(
        "twin",
        "INSERT INTO events SELECT 6, kind, created_utc, actor, actor_role, record_id, username, role, secret_sha256, reason, prev_hash, event_hash || 'x' FROM events WHERE id = 5",
        6,
    );
}

#[test]
fn an_export_keeps_accounts_and_decisions() {
    let (path, mut s) = lab("export");
    s.approve(&as_("sam", Role::Signatory), 6, None).unwrap();
    let mut out = Vec::new();
    let c = s.export(&mut out).unwrap();
    assert_eq!((c.records, c.events), (1, 7));
    let copy = path.with_file_name("copy.db");
    let done = Store::import_at(&copy, std::io::Cursor::new(&out), "lab.jsonl").unwrap();
    assert_eq!(done.added, 8);
    assert_eq!(done.chain.head, c.head);
    let t = Store::open(&copy).unwrap();
    assert_eq!(t.accounts().unwrap(), s.accounts().unwrap());
    assert_eq!(t.review(6).unwrap().state, State::Approved);
    // Again: nothing twice.
    let mut t = t;
    let again = t.import(std::io::Cursor::new(&out), "lab.jsonl").unwrap();
    assert_eq!((again.added, again.present), (0, 8));
    // An event line edited after the export is refused, naming the line.
    let text = String::from_utf8(out)
        .unwrap()
        .replace("\"role\":\"engineer\"", "\"role\":\"admin\"");
    let third = path.with_file_name("third.db");
    let e = Store::import_at(&third, std::io::Cursor::new(text), "lab.jsonl").unwrap_err();
    assert!(e.to_string().contains("lab.jsonl: line 1: event 1"), "{e}");
    assert!(!third.exists());
}
