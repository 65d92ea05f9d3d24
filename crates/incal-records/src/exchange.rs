//! Moving records between stores: the export (every record in chain
//! order, one JSON object per line, with every field its record hash
//! covers) and the import that appends an export to a store, checking each
//! record as `verify` does.

use incal::document::ResultDocument;
use serde::{Deserialize, Serialize};

use crate::db::{Conn, DbError, Mode, P};
use crate::error::db_err;
use crate::events::Event;
use crate::verify::{check_event, Entry, ScannedEvent};
use crate::workflow::write_event;
use crate::write::{chain_head, instrument_of, new_instrument, write_record};
use crate::{sha256_hex, time, ChainFields, Error, InputHash, Result, Store, Verified};
use crate::{GENESIS, MAX_DOCUMENT_BYTES};

/// What [`Store::import`] did.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Imported {
    /// Records written.
    pub added: i64,
    /// Records the store already held (the same record hash at the same id).
    pub present: i64,
    /// The chain after the import.
    pub chain: Verified,
}

/// A supersession as exported: the record corrected and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportedSupersession {
    /// The superseded record.
    pub id: i64,
    /// Why.
    pub reason: String,
}

/// One record as `incal record export` writes it: one JSON object per
/// line, in chain order, with every field the record hash covers, so an
/// import into another store rebuilds the same chain and checks it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportedRecord {
    /// Record id (1, 2, 3, … in chain order).
    pub id: i64,
    /// Instrument serial.
    pub serial: String,
    /// Instrument model as first recorded.
    pub model: Option<String>,
    /// Procedure of the result.
    pub procedure: String,
    /// `YYYY-MM-DDTHH:MM:SSZ`.
    pub created_utc: String,
    /// Operator.
    pub operator: Option<String>,
    /// Station.
    pub station: Option<String>,
    /// SHA-256 of `document`.
    pub sha256: String,
    /// The input files, in the document's order.
    pub inputs: Vec<InputHash>,
    /// What this record corrects.
    pub supersedes: Option<ExportedSupersession>,
    /// Hash of the record before.
    pub prev_hash: String,
    /// This record's hash.
    pub record_hash: String,
    /// The result document, exactly as stored.
    pub document: String,
}

impl ExportedRecord {
    /// The fields its record hash covers.
    fn fields(&self) -> ChainFields<'_> {
        ChainFields {
            prev_hash: &self.prev_hash,
            id: self.id,
            serial: &self.serial,
            procedure: &self.procedure,
            created_utc: &self.created_utc,
            operator: self.operator.as_deref(),
            station: self.station.as_deref(),
            document_sha256: &self.sha256,
            inputs: &self.inputs,
            supersedes: self.supersedes.as_ref().map(|s| s.id),
            reason: self.supersedes.as_ref().map(|s| s.reason.as_str()),
        }
    }
}

/// One event as `incal record export` writes it, in its place among the
/// records: the event with every field its hash covers, and the password
/// hash it sets (`user.add`, `user.passwd`), so a store restored from its
/// export keeps its accounts. An export is as confidential as the store.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExportedEvent {
    /// The event.
    pub event: Event,
    /// The Argon2id password hash it sets.
    pub password_hash: Option<String>,
}

/// Remove an SQLite store file and the files SQLite keeps beside it
/// (`-wal`, `-shm`, `-journal`), whichever exist: a store this process
/// created and must not leave behind.
pub fn remove_sqlite_files(path: &std::path::Path) {
    for suffix in ["", "-wal", "-shm", "-journal"] {
        let _ = std::fs::remove_file(format!("{}{suffix}", path.display()));
    }
}

impl Store {
    /// Write every record, in chain order, to `out` as one JSON object
    /// per line ([`ExportedRecord`]), after checking the chain (a broken
    /// chain is not exported). The chain exported.
    pub fn export(&self, out: &mut dyn std::io::Write) -> Result<Verified> {
        let chain = self.check_chain()?;
        let io = |e: std::io::Error| Error::Output(e.to_string());
        let mut n = 0i64;
        let mut head = GENESIS.to_string();
        let last = chain.records + chain.events;
        let mut events = 0i64;
        self.scan(|entry| {
            // Only the entries verified above: one appended since belongs
            // to the next export.
            if entry.id() > last {
                return Ok(());
            }
            let r = match entry {
                Entry::Record(r) => r,
                Entry::Event(ev) => {
                    let line = ExportedEvent {
                        event: ev.event,
                        password_hash: ev.password,
                    };
                    let text =
                        serde_json::to_string(&line).map_err(|e| Error::Output(e.to_string()))?;
                    out.write_all(text.as_bytes()).map_err(io)?;
                    out.write_all(b"\n").map_err(io)?;
                    head = line.event.event_hash;
                    events += 1;
                    return Ok(());
                }
            };
            let document = String::from_utf8(r.document).map_err(|_| Error::Tampered {
                id: r.id,
                problem: "the stored document is not UTF-8 text".into(),
            })?;
            let line = ExportedRecord {
                id: r.id,
                serial: r.serial.unwrap_or_default(),
                model: r.model,
                procedure: r.procedure,
                created_utc: r.created_utc,
                operator: r.operator,
                station: r.station,
                sha256: r.document_sha256,
                inputs: r.inputs,
                supersedes: r.supersedes.map(|s| ExportedSupersession {
                    id: s.old_id,
                    reason: s.reason,
                }),
                prev_hash: r.prev_hash,
                record_hash: r.record_hash,
                document,
            };
            let text = serde_json::to_string(&line).map_err(|e| Error::Output(e.to_string()))?;
            out.write_all(text.as_bytes()).map_err(io)?;
            out.write_all(b"\n").map_err(io)?;
            head = line.record_hash;
            n += 1;
            Ok(())
        })?;
        out.flush().map_err(io)?;
        Ok(Verified {
            records: n,
            events,
            head,
        })
    }

    /// [`Store::import`] into the store at `location`, created when
    /// missing: a refused import leaves no store file it created (nor its
    /// `-wal` and `-shm`).
    pub fn import_at(
        location: &std::path::Path,
        lines: impl std::io::BufRead,
        source: &str,
    ) -> Result<Imported> {
        let is_file = !location.to_str().is_some_and(crate::is_postgres_url);
        let existed = !is_file || location.exists();
        let done = Store::open(location).and_then(|mut store| store.import(lines, source));
        if done.is_err() && !existed {
            remove_sqlite_files(location);
        }
        done
    }

    /// Append the records of an export ([`Store::export`]: JSON lines, in
    /// chain order) to this store, keeping their ids, times and hashes, in
    /// one transaction: all of them or none. Records the store already
    /// holds (the same record hash at the same id) are skipped, so an
    /// import can be repeated or resumed and never stores a record twice;
    /// a store whose chain differs from the export's is refused. Each new
    /// record is checked as `verify` would (document hash, link, record
    /// hash) before it is written; a bad line is [`Error::Input`] naming
    /// `source` and the line.
    pub fn import(&mut self, lines: impl std::io::BufRead, source: &str) -> Result<Imported> {
        use std::io::{BufRead, Read};
        self.verify_before_writing()?;
        let name = self.path.display().to_string();
        let e = |e| db_err(&name, e);
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Write).map_err(e)?;
        let (mut head_id, mut head_hash) = chain_head(&mut tx).map_err(e)?;
        let (mut added, mut present) = (0i64, 0i64);
        // One line holds one document: bounded as documents are.
        let limit = 2 * MAX_DOCUMENT_BYTES as u64 + 65_536;
        let mut reader = lines;
        let mut buf = String::new();
        let mut line_no = 0usize;
        loop {
            buf.clear();
            line_no += 1;
            let at = |m: String| Error::Input(format!("{source}: line {line_no}: {m}"));
            let got = (&mut reader)
                .take(limit)
                .read_line(&mut buf)
                .map_err(|err| at(format!("cannot read ({err})")))?;
            if got == 0 {
                break;
            }
            if got as u64 == limit && !buf.ends_with('\n') {
                return Err(at(format!("longer than {limit} bytes")));
            }
            if buf.trim().is_empty() {
                continue;
            }
            if buf.trim_start().starts_with("{\"event\"") {
                let ev: ExportedEvent = serde_json::from_str(buf.trim()).map_err(|err| {
                    let why = incal_io::clip_to(&err.to_string(), 160);
                    at(format!("not an exported event ({why})"))
                })?;
                if import_event(&mut tx, &name, ev, (head_id, &head_hash), &at)? {
                    present += 1;
                } else {
                    added += 1;
                    (head_id, head_hash) = chain_head(&mut tx).map_err(e)?;
                }
                continue;
            }
            let r: ExportedRecord = serde_json::from_str(buf.trim()).map_err(|err| {
                // serde echoes an unknown key whole: one short line.
                let why = incal_io::clip_to(&err.to_string(), 160);
                at(format!("not an exported record ({why})"))
            })?;
            if r.id <= head_id {
                // A line the store holds is compared whole, not skipped on
                // its id: its document and every field its record hash
                // covers must be the store's.
                let have = tx
                    .query_opt(
                        "SELECT r.record_hash, i.model FROM records r
                         LEFT JOIN instruments i ON i.id = r.instrument_id
                         WHERE r.id = ?1",
                        &[P::I(r.id)],
                    )
                    .map_err(e)?
                    .map(|row| Ok::<_, DbError>((row.t(0)?, row.ot(1)?)))
                    .transpose()
                    .map_err(e)?;
                let Some((hash, model)) = have else {
                    return Err(at(format!("record {}: the store has no such record", r.id)));
                };
                if hash != r.record_hash {
                    return Err(at(format!(
                        "record {} differs from the store's record {}: the store holds another chain",
                        r.id, r.id
                    )));
                }
                let tampered = if sha256_hex(r.document.as_bytes()) != r.sha256 {
                    Some("its document does not match its sha256")
                } else if r.fields().record_hash() != r.record_hash {
                    Some("its fields do not match its record_hash")
                } else if model != r.model {
                    Some("its model is not the store's")
                } else {
                    None
                };
                if let Some(why) = tampered {
                    return Err(at(format!(
                        "record {}: {why}: the line was changed after the export (the store's record {} is kept)",
                        r.id, r.id
                    )));
                }
                present += 1;
                continue;
            }
            let doc = check_next(&mut tx, &name, &r, (head_id, &head_hash), &at)?;
            let instrument_id = match instrument_of(&mut tx, &r.serial).map_err(e)? {
                Some(id) => id,
                None => new_instrument(&mut tx, &r.serial, doc.instrument.model.as_deref())
                    .map_err(e)?,
            };
            write_record(
                &mut tx,
                instrument_id,
                &r.fields(),
                &r.document,
                &r.record_hash,
            )
            .map_err(e)?;
            head_id = r.id;
            head_hash = r.record_hash;
            added += 1;
        }
        tx.commit().map_err(e)?;
        drop(c);
        Ok(Imported {
            added,
            present,
            chain: self.verify()?,
        })
    }
}

/// Check exported record `r`, to be appended after the store's head
/// `(head_id, head_hash)` of store `name`, as `verify` would: it follows
/// the head, links to it, its document matches its SHA-256 and reads as a
/// result of its procedure, its time is normalised, its record hash
/// covers its fields, and what it supersedes is held and not superseded
/// yet. Its document; a failure is `at(what)`.
fn check_next(
    tx: &mut Conn,
    name: &str,
    r: &ExportedRecord,
    (head_id, head_hash): (i64, &str),
    at: &dyn Fn(String) -> Error,
) -> Result<ResultDocument> {
    let e = |e| db_err(name, e);
    if r.id != head_id + 1 {
        return Err(at(format!(
            "record {} follows record {head_id}: records {}..{} are missing",
            r.id,
            head_id + 1,
            r.id - 1
        )));
    }
    if r.prev_hash != head_hash {
        return Err(at(format!(
            "record {}: prev_hash is not the hash of record {head_id}",
            r.id
        )));
    }
    if sha256_hex(r.document.as_bytes()) != r.sha256 {
        return Err(at(format!(
            "record {}: the document does not match its sha256",
            r.id
        )));
    }
    let doc = ResultDocument::from_json(&r.document)
        .map_err(|err| at(format!("record {}: {err}", r.id)))?;
    if r.serial.trim().is_empty() {
        return Err(at(format!("record {}: an empty serial", r.id)));
    }
    if let Some(own) = doc.instrument.serial.as_deref() {
        if own != r.serial {
            return Err(at(format!(
                "record {}: serial '{}' is not its document's instrument.serial '{}'",
                r.id,
                incal_io::clip(&r.serial),
                incal_io::clip(own)
            )));
        }
    }
    if doc.procedure.as_str() != r.procedure {
        return Err(at(format!(
            "record {}: procedure '{}' is not the document's '{}'",
            r.id,
            r.procedure,
            doc.procedure.as_str()
        )));
    }
    time::normalize_utc(&r.created_utc)
        .ok()
        .filter(|t| *t == r.created_utc)
        .ok_or_else(|| {
            at(format!(
                "record {}: created_utc '{}' is not YYYY-MM-DDTHH:MM:SSZ",
                r.id, r.created_utc
            ))
        })?;
    if r.fields().record_hash() != r.record_hash {
        return Err(at(format!(
            "record {}: record_hash does not match its fields",
            r.id
        )));
    }
    if let Some(s) = &r.supersedes {
        let old = tx
            .query_opt(
                "SELECT s.new_id FROM records r
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE r.id = ?1",
                &[P::I(s.id)],
            )
            .map_err(e)?;
        match old.map(|row| row.oi(0)).transpose().map_err(e)? {
            None => {
                return Err(at(format!(
                    "record {} supersedes record {}, which the store does not hold",
                    r.id, s.id
                )))
            }
            Some(Some(by)) => {
                return Err(at(format!(
                    "record {} supersedes record {}, already superseded by record {by}",
                    r.id, s.id
                )))
            }
            Some(None) => {}
        }
    }
    Ok(doc)
}

/// Import exported event `ev` after the store's head `(head_id,
/// head_hash)`: true when the store already holds it (the same hash at the
/// same position), else checked as `verify` checks it and written.
fn import_event(
    tx: &mut Conn,
    name: &str,
    ev: ExportedEvent,
    (head_id, head_hash): (i64, &str),
    at: &dyn Fn(String) -> Error,
) -> Result<bool> {
    let e = |e| db_err(name, e);
    let id = ev.event.id;
    if id <= head_id {
        let have = tx
            .query_opt("SELECT event_hash FROM events WHERE id = ?1", &[P::I(id)])
            .map_err(e)?;
        let same = match have {
            Some(row) => row.t(0).map_err(e)? == ev.event.event_hash,
            None => false,
        };
        if !same {
            return Err(at(format!(
                "event {id} differs from the store's entry {id}: the store holds another chain"
            )));
        }
        return Ok(true);
    }
    if id != head_id + 1 {
        return Err(at(format!(
            "event {id} follows record {head_id}: records {}..{} are missing",
            head_id + 1,
            id - 1
        )));
    }
    if ev.event.prev_hash != head_hash {
        return Err(at(format!(
            "event {id}: prev_hash is not the hash of record {head_id}"
        )));
    }
    let scanned = ScannedEvent {
        event: ev.event,
        password: ev.password_hash,
    };
    check_event(&scanned).map_err(|p| at(format!("event {id}: {p}")))?;
    write_event(tx, &scanned.event, scanned.password.as_deref()).map_err(e)?;
    Ok(false)
}
