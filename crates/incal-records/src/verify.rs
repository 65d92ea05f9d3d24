//! Checking the hash chain: every record scanned in chain order from one
//! snapshot, its document hash, its link to the record before and its
//! record hash recomputed ([`chain`](crate::chain) has the canonical
//! form), and a head kept elsewhere looked for.

use crate::db::{Conn, DbError, Mode, P};
use crate::events::Event;
use crate::query::{inputs_between, supersessions_between};
use crate::workflow::{event_row, EVENT_COLUMNS};
use crate::GENESIS;
use crate::{sha256_hex, ChainFields, Error, InputHash, Result, Store, Supersession, Verified};

/// Rows read per round trip when the whole chain is scanned.
const PAGE: i64 = 256;

/// A record as read by a scan of the chain: every column, unchecked.
pub(crate) struct Scanned {
    pub(crate) id: i64,
    pub(crate) serial: Option<String>,
    pub(crate) model: Option<String>,
    pub(crate) procedure: String,
    pub(crate) created_utc: String,
    pub(crate) operator: Option<String>,
    pub(crate) station: Option<String>,
    pub(crate) document: Vec<u8>,
    pub(crate) document_sha256: String,
    pub(crate) prev_hash: String,
    pub(crate) record_hash: String,
    pub(crate) inputs: Vec<InputHash>,
    pub(crate) supersedes: Option<Supersession>,
}

impl Scanned {
    /// The fields its record hash covers, with the serial of its
    /// instrument row.
    fn fields<'a>(&'a self, serial: &'a str) -> ChainFields<'a> {
        ChainFields {
            prev_hash: &self.prev_hash,
            id: self.id,
            serial,
            procedure: &self.procedure,
            created_utc: &self.created_utc,
            operator: self.operator.as_deref(),
            station: self.station.as_deref(),
            document_sha256: &self.document_sha256,
            inputs: &self.inputs,
            supersedes: self.supersedes.as_ref().map(|s| s.old_id),
            reason: self.supersedes.as_ref().map(|s| s.reason.as_str()),
        }
    }
}

impl Store {
    /// Recompute the chain: for every record in id order, the id follows
    /// the one before, `prev_hash` is the record before's `record_hash`
    /// (64 zeros for record 1), the stored document's SHA-256 is
    /// `document_sha256`, and `record_hash` is the hash of its canonical
    /// form ([`chain`](crate::chain)); every supersession and input-file
    /// row belongs to a record that covers it. The first record that fails
    /// is [`Error::Tampered`]. Reads one consistent snapshot.
    pub fn verify(&self) -> Result<Verified> {
        self.verify_holding(None)
    }

    /// [`Store::verify`], and check that the chain still holds `head`, a
    /// `record_hash` kept elsewhere (on a certificate, in another system):
    /// a store truncated or rebuilt since no longer holds it
    /// ([`Error::HeadMissing`]).
    pub fn verify_head(&self, head: &str) -> Result<Verified> {
        self.verify_holding(Some(head))
    }

    /// Refuse to read a store whose chain is broken, naming the first
    /// record that does not match (for `show`, `history` and reports);
    /// the intact chain's count and head otherwise.
    pub fn check_chain(&self) -> Result<Verified> {
        self.verify().map_err(|e| match e {
            Error::Tampered { id, problem } => Error::Tampered {
                id,
                problem: format!("{problem} (the chain is broken: nothing is read from this store; 'incal record verify' names it)"),
            },
            other => other,
        })
    }

    /// Every entry (record or event) in chain order, from one consistent
    /// snapshot, a page at a time (memory stays bounded however long the
    /// chain). A column that does not read as incal stores it is
    /// [`Error::Tampered`].
    pub(crate) fn scan(&self, mut visit: impl FnMut(Entry) -> Result<()>) -> Result<()> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let mut after = i64::MIN;
        loop {
            let ids = tx
                .query(
                    "SELECT id FROM records WHERE id > ?1
                     UNION ALL SELECT id FROM events WHERE id > ?1
                     ORDER BY 1 LIMIT ?2",
                    &[P::I(after), P::I(PAGE)],
                )
                .map_err(self.db())?;
            let (Some(first), Some(last)) = (ids.first(), ids.last()) else {
                break;
            };
            let (lo, hi) = (
                first.i(0).map_err(self.db())?,
                last.i(0).map_err(self.db())?,
            );
            let records = scan_records(&mut tx, lo, hi)?;
            let events = scan_events(&mut tx, lo, hi)?;
            let mut merged: Vec<Entry> = records
                .into_iter()
                .map(Entry::Record)
                .chain(events.into_iter().map(Entry::Event))
                .collect();
            merged.sort_by_key(Entry::id);
            for entry in merged {
                visit(entry)?;
            }
            after = hi;
            if (ids.len() as i64) < PAGE || hi == i64::MAX {
                break;
            }
        }
        // Rows that point at no record are covered by no hash.
        let orphan = tx
            .query_opt(
                "SELECT s.old_id, 'a supersession by record ' || s.new_id || ', which does not exist'
                 FROM supersessions s LEFT JOIN records r ON r.id = s.new_id
                 WHERE r.id IS NULL
                 UNION ALL
                 SELECT s.old_id, 'superseded, but the record does not exist'
                 FROM supersessions s LEFT JOIN records r ON r.id = s.old_id
                 WHERE r.id IS NULL
                 UNION ALL
                 SELECT x.record_id, 'an input file row of a record that does not exist'
                 FROM record_inputs x LEFT JOIN records r ON r.id = x.record_id
                 WHERE r.id IS NULL
                 UNION ALL
                 SELECT p.event_id, 'a password row of no user.add or user.passwd event'
                 FROM passwords p LEFT JOIN events e ON e.id = p.event_id
                 WHERE e.id IS NULL OR e.kind NOT IN ('user.add', 'user.passwd')
                 LIMIT 1",
                &[],
            )
            .map_err(self.db())?;
        if let Some(r) = orphan {
            return Err(Error::Tampered {
                id: r.i(0).unwrap_or(0),
                problem: r.t(1).unwrap_or_else(|_| "an orphan row".into()),
            });
        }
        tx.commit().map_err(self.db())
    }

    fn verify_holding(&self, anchor: Option<&str>) -> Result<Verified> {
        let mut held = anchor.is_none() || anchor == Some(GENESIS);
        // The instrument row's model is set from the first record of its
        // serial: checked against that record's (hashed) document.
        let mut seen_serials = std::collections::HashSet::new();
        let (mut prev_id, mut prev_hash) = (0i64, GENESIS.to_string());
        let (mut records, mut events) = (0i64, 0i64);
        self.scan(|entry| {
            let id = entry.id();
            let bad = |problem: String| Error::Tampered { id, problem };
            if id != prev_id + 1 {
                return Err(bad(if prev_id == 0 {
                    "the chain does not start at record 1".into()
                } else if id == prev_id {
                    format!("a record and an event share position {id}")
                } else {
                    format!(
                        "follows record {prev_id}: record {} is missing",
                        prev_id + 1
                    )
                }));
            }
            let hash = match entry {
                Entry::Record(r) => {
                    if r.prev_hash != prev_hash {
                        return Err(bad(format!(
                            "prev_hash does not match the hash of record {prev_id}"
                        )));
                    }
                    check_record(&r, &mut seen_serials).map_err(bad)?;
                    records += 1;
                    r.record_hash
                }
                Entry::Event(ev) => {
                    if ev.event.prev_hash != prev_hash {
                        return Err(bad(format!(
                            "an event ({}): prev_hash does not match the hash of record {prev_id}",
                            ev.event.kind.as_str()
                        )));
                    }
                    check_event(&ev)
                        .map_err(|p| bad(format!("an event ({}): {p}", ev.event.kind.as_str())))?;
                    events += 1;
                    ev.event.event_hash
                }
            };
            if anchor == Some(hash.as_str()) {
                held = true;
            }
            prev_id = id;
            prev_hash = hash;
            Ok(())
        })?;
        if let (false, Some(h)) = (held, anchor) {
            return Err(Error::HeadMissing {
                head: h.to_string(),
            });
        }
        Ok(Verified {
            records,
            events,
            head: prev_hash,
        })
    }
}

/// One entry of the chain as a scan reads it.
pub(crate) enum Entry {
    /// A record.
    Record(Scanned),
    /// An event.
    Event(ScannedEvent),
}

impl Entry {
    /// Its position in the chain.
    pub(crate) fn id(&self) -> i64 {
        match self {
            Entry::Record(r) => r.id,
            Entry::Event(e) => e.event.id,
        }
    }
}

/// An event as read by a scan, with the password hash kept beside it.
pub(crate) struct ScannedEvent {
    pub(crate) event: Event,
    pub(crate) password: Option<String>,
}

/// The records at positions `lo..=hi`, with their inputs and supersessions.
fn scan_records(tx: &mut Conn, lo: i64, hi: i64) -> Result<Vec<Scanned>> {
    let db = |e: DbError| Error::Tampered {
        id: lo,
        problem: format!("the chain cannot be read here ({e})"),
    };
    let rows = tx
        .query(
            "SELECT r.id, i.serial, r.procedure, r.created_utc, r.operator, r.station,
                    r.document, r.document_sha256, r.prev_hash, r.record_hash, i.model
             FROM records r
             LEFT JOIN instruments i ON i.id = r.instrument_id
             WHERE r.id >= ?1 AND r.id <= ?2
             ORDER BY r.id",
            &[P::I(lo), P::I(hi)],
        )
        .map_err(db)?;
    let mut inputs = inputs_between(tx, lo, hi).map_err(db)?;
    let mut sups = supersessions_between(tx, lo, hi).map_err(db)?;
    let mut out = Vec::with_capacity(rows.len());
    for r in &rows {
        let mut read = || -> std::result::Result<Scanned, DbError> {
            let id = r.i(0)?;
            Ok(Scanned {
                id,
                serial: r.ot(1)?,
                procedure: r.t(2)?,
                created_utc: r.t(3)?,
                operator: r.ot(4)?,
                station: r.ot(5)?,
                // As bytes: a value changed to a blob or to text
                // that is not UTF-8 is reported, not a failure.
                document: r.bytes(6),
                document_sha256: r.t(7)?,
                prev_hash: r.t(8)?,
                record_hash: r.t(9)?,
                model: r.ot(10)?,
                inputs: inputs.remove(&id).unwrap_or_default(),
                supersedes: sups.remove(&id),
            })
        };
        out.push(read().map_err(|e| Error::Tampered {
            id: r.i(0).unwrap_or(lo),
            problem: format!("a column does not read as stored by incal ({e})"),
        })?);
    }
    Ok(out)
}

/// The events at positions `lo..=hi`, with their password hashes.
fn scan_events(tx: &mut Conn, lo: i64, hi: i64) -> Result<Vec<ScannedEvent>> {
    let rows = tx
        .query(
            &format!(
                "SELECT {EVENT_COLUMNS}, p.password_hash FROM events
                 LEFT JOIN passwords p ON p.event_id = events.id
                 WHERE events.id >= ?1 AND events.id <= ?2 ORDER BY events.id"
            ),
            &[P::I(lo), P::I(hi)],
        )
        .map_err(|e| Error::Tampered {
            id: lo,
            problem: format!("the chain cannot be read here ({e})"),
        })?;
    rows.iter()
        .map(|r| {
            let read = || -> std::result::Result<ScannedEvent, DbError> {
                Ok(ScannedEvent {
                    event: event_row(r)?,
                    password: r.ot(12)?,
                })
            };
            read().map_err(|e| Error::Tampered {
                id: r.i(0).unwrap_or(lo),
                problem: format!("an event's column does not read as stored by incal ({e})"),
            })
        })
        .collect()
}

/// What is wrong with record `r` apart from its link: its document hash,
/// its instrument row, its supersession, its record hash.
fn check_record(
    r: &Scanned,
    seen_serials: &mut std::collections::HashSet<String>,
) -> std::result::Result<(), String> {
    if sha256_hex(&r.document) != r.document_sha256 {
        return Err("the stored document does not match its SHA-256".into());
    }
    let serial = r
        .serial
        .clone()
        .ok_or_else(|| "its instrument row is missing".to_string())?;
    if seen_serials.insert(serial.clone()) {
        // Only the model is read (serde skips the rest without building
        // it: the whole document was hashed above).
        #[derive(serde::Deserialize)]
        struct Doc {
            instrument: Instrument,
        }
        #[derive(serde::Deserialize)]
        struct Instrument {
            model: Option<serde_json::Value>,
        }
        let doc_model = serde_json::from_slice::<Doc>(&r.document)
            .ok()
            .and_then(|d| d.instrument.model)
            .and_then(|m| m.as_str().map(String::from));
        if doc_model != r.model {
            return Err(format!(
                "the instrument's model ({}) is not the one in its first record's document ({})",
                r.model.as_deref().unwrap_or("none"),
                doc_model.as_deref().unwrap_or("none")
            ));
        }
    }
    if let Some(s) = &r.supersedes {
        if s.created_utc != r.created_utc {
            return Err(format!(
                "the supersession of record {} has a time other than the record's",
                s.old_id
            ));
        }
        if s.old_id >= r.id {
            return Err(format!(
                "supersedes record {}, which is not older",
                s.old_id
            ));
        }
    }
    if r.fields(&serial).record_hash() != r.record_hash {
        return Err(
            "record_hash does not match its fields (serial, procedure, time, operator, station, inputs or supersession changed)"
                .into(),
        );
    }
    Ok(())
}

/// What is wrong with event `ev` apart from its link: its hash, its
/// password hash, the record it names.
pub(crate) fn check_event(ev: &ScannedEvent) -> std::result::Result<(), String> {
    let e = &ev.event;
    if e.hash() != e.event_hash {
        return Err("event_hash does not match its fields (kind, time, actor, role, record, account or reason changed)".into());
    }
    match (&ev.password, &e.secret_sha256) {
        (Some(p), Some(h)) if sha256_hex(p.as_bytes()) == *h => {}
        (None, None) if !e.kind.sets_password() => {}
        (None, _) if e.kind.sets_password() => return Err("its password hash is missing".into()),
        _ => return Err("the password hash does not match its secret_sha256".into()),
    }
    if e.kind.is_record() != e.record_id.is_some() {
        return Err("names a record where it should not, or none where it should".into());
    }
    if e.record_id.is_some_and(|r| r >= e.id) {
        return Err("names a record that is not older".into());
    }
    Ok(())
}
