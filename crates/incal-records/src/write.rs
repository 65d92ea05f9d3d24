//! Writing records: adding a result document, superseding a record with
//! a correction, and the rows a record is written as (instrument, record,
//! input files, supersession) under one write transaction.

use incal::document::ResultDocument;

use crate::db::{Conn, DbError, Mode, P};
use crate::error::db_err;
use crate::GENESIS;
use crate::{sha256_hex, time, Added, ChainFields, Error, InputHash, NewRecord, Result, Store};

impl Store {
    /// Store `req.document` as a new record (crate docs); see
    /// [`NewRecord`] for the serial, operator and station.
    pub fn add(&mut self, req: &NewRecord) -> Result<Added> {
        self.insert_as(req, None, None)
    }

    /// Store `req.document` as a new record that supersedes record
    /// `old_id` because of `reason`. The old record stays (append-only);
    /// it is left out of history and listed with `superseded_by`. The new
    /// result must be of the same instrument (its serial defaults to the
    /// old record's); a record already superseded cannot be superseded
    /// again (supersede its successor).
    pub fn supersede(&mut self, old_id: i64, req: &NewRecord, reason: &str) -> Result<Added> {
        if reason.trim().is_empty() {
            return Err(Error::Input("the reason of a supersession is empty".into()));
        }
        self.insert_as(req, Some((old_id, reason)), None)
    }

    /// Never extend a broken chain: the new record would seal it. The
    /// whole chain is checked, unless (SQLite) this connection found it
    /// intact and no other connection has committed to the file since
    /// (its `data_version` is the one then: [`Store::checked`]).
    pub(crate) fn verify_before_writing(&self) -> Result<()> {
        let version = self.data_version()?;
        if version.is_some() && version == self.checked.get() {
            return Ok(());
        }
        self.verify().map_err(|e| match e {
            Error::Tampered { id, problem } => Error::Tampered {
                id,
                problem: format!("{problem}; nothing is added to a broken chain"),
            },
            other => other,
        })?;
        // Read before the check: a commit by another connection since
        // then changes it, and the next write checks again.
        self.checked.set(version);
        Ok(())
    }

    /// SQLite's `PRAGMA data_version` of this connection (`None` on
    /// PostgreSQL): it changes when another connection commits.
    pub(crate) fn data_version(&self) -> Result<Option<i64>> {
        let c = self.conn.borrow();
        match &*c {
            Conn::Sqlite(conn) => conn
                .query_row("PRAGMA data_version", [], |r| r.get(0))
                .map(Some)
                .map_err(|e| db_err(&self.path.display().to_string(), e.into())),
            _ => Ok(None),
        }
    }

    /// Write `req` as the next record of the chain, superseding record
    /// `old_id` because of `reason` when `supersedes` is given; the record
    /// already held when the same document of the same instrument is added
    /// again. With `submitter`, its `record.submit` event follows the
    /// record in the same transaction.
    pub(crate) fn insert_as(
        &mut self,
        req: &NewRecord,
        supersedes: Option<(i64, &str)>,
        submitter: Option<&crate::events::Actor>,
    ) -> Result<Added> {
        let doc = ResultDocument::from_json(req.document).map_err(Error::Input)?;
        let operator = from_meta(&doc, "operator", req.operator)?;
        let station = from_meta(&doc, "station", req.station)?;
        let created_utc = record_time(req.created_utc)?;
        self.verify_before_writing()?;
        let document_sha256 = sha256_hex(req.document.as_bytes());
        let inputs: Vec<InputHash> = doc
            .inputs
            .iter()
            .map(|i| InputHash {
                role: i.role.clone(),
                path: i.path.clone(),
                sha256: i.sha256.clone(),
            })
            .collect();
        let name = self.path.display().to_string();
        let e = |e| db_err(&name, e);
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Write).map_err(e)?;
        let fallback_serial = match supersedes {
            Some((old, _)) => Some(superseded_serial(&mut tx, &name, old, &doc)?),
            None => None,
        };
        let serial = resolve_serial(&doc, req.serial, fallback_serial.as_deref())?;
        if let (Some(old), Some(s)) = (fallback_serial.as_deref(), supersedes) {
            if old != serial {
                return Err(Error::Input(format!(
                    "record {} is of serial '{old}' but the new result is of '{serial}': a correction must be of the same instrument",
                    s.0
                )));
            }
        }
        let instrument_id = instrument_of(&mut tx, &serial).map_err(e)?;
        if instrument_id.is_some() {
            let same = tx
                .query_opt(
                    "SELECT r.id, r.record_hash FROM records r
                     JOIN instruments i ON i.id = r.instrument_id
                     WHERE i.serial = ?1 AND r.document_sha256 = ?2
                     ORDER BY r.id LIMIT 1",
                    &[P::T(Some(&serial)), P::T(Some(&document_sha256))],
                )
                .map_err(e)?;
            if let (Some(r), Some((old, _))) = (&same, supersedes) {
                // A correction brings a new document: one the instrument
                // already holds would be stored twice.
                return Err(Error::Input(format!(
                    "record {} already holds this document for serial '{}': a correction of record {old} must be a different result",
                    r.i(0).map_err(e)?,
                    incal_io::clip(&serial)
                )));
            }
            if let Some(r) = same {
                return Ok(Added {
                    id: r.i(0).map_err(e)?,
                    sha256: document_sha256,
                    record_hash: r.t(1).map_err(e)?,
                    existing: true,
                });
            }
        }
        let instrument_id = match instrument_id {
            Some(id) => id,
            None => new_instrument(&mut tx, &serial, doc.instrument.model.as_deref()).map_err(e)?,
        };
        let (prev_id, prev_hash) = chain_head(&mut tx).map_err(e)?;
        let id = prev_id + 1;
        let procedure = doc.procedure.as_str();
        let fields = ChainFields {
            prev_hash: &prev_hash,
            id,
            serial: &serial,
            procedure,
            created_utc: &created_utc,
            operator: operator.as_deref(),
            station: station.as_deref(),
            document_sha256: &document_sha256,
            inputs: &inputs,
            supersedes: supersedes.map(|s| s.0),
            reason: supersedes.map(|s| s.1),
        };
        let record_hash = fields.record_hash();
        write_record(&mut tx, instrument_id, &fields, req.document, &record_hash).map_err(e)?;
        if let Some(actor) = submitter {
            Store::submit_event(&mut tx, actor, id, &created_utc).map_err(e)?;
        }
        tx.commit().map_err(e)?;
        Ok(Added {
            id,
            sha256: document_sha256,
            record_hash,
            existing: false,
        })
    }
}

/// The time of a new record: the one given (RFC 3339, normalised to
/// `YYYY-MM-DDTHH:MM:SSZ`), else now; a time in the future is refused.
fn record_time(given: Option<&str>) -> Result<String> {
    let created_utc = match given {
        Some(t) => time::normalize_utc(t).map_err(|e| Error::Input(format!("created_utc: {e}")))?,
        None => time::now_utc(),
    };
    if created_utc > time::now_utc() {
        return Err(Error::Input(format!(
            "created_utc {created_utc} is in the future: a record is dated when it was made"
        )));
    }
    Ok(created_utc)
}

/// The serial of record `old` (store `name`), which a correction `doc`
/// supersedes: the record must exist, not be superseded already, and be
/// of the correction's procedure.
fn superseded_serial(tx: &mut Conn, name: &str, old: i64, doc: &ResultDocument) -> Result<String> {
    let e = |e| db_err(name, e);
    let row = tx
        .query_opt(
            "SELECT i.serial, s.new_id, r.procedure FROM records r
             JOIN instruments i ON i.id = r.instrument_id
             LEFT JOIN supersessions s ON s.old_id = r.id
             WHERE r.id = ?1",
            &[P::I(old)],
        )
        .map_err(e)?;
    let row = match row {
        None => None,
        Some(r) => Some((r.t(0).map_err(e)?, r.oi(1).map_err(e)?, r.t(2).map_err(e)?)),
    };
    match row {
        None => Err(Error::Input(format!("record {old}: no such record"))),
        Some((_, Some(by), _)) => Err(Error::Input(format!(
            "record {old} is already superseded by record {by}: supersede record {by} instead"
        ))),
        Some((_, None, procedure)) if procedure != doc.procedure.as_str() => Err(Error::Input(format!(
            "record {old} is a {procedure} result and the correction a {} result: a correction must be of the same procedure",
            doc.procedure.as_str()
        ))),
        Some((serial, None, _)) => Ok(serial),
    }
}

/// The id of instrument `serial`, if it has one.
pub(crate) fn instrument_of(
    tx: &mut Conn,
    serial: &str,
) -> std::result::Result<Option<i64>, DbError> {
    tx.query_opt(
        "SELECT id FROM instruments WHERE serial = ?1",
        &[P::T(Some(serial))],
    )?
    .map(|r| r.i(0))
    .transpose()
}

/// A new instrument row (inside a write transaction).
pub(crate) fn new_instrument(
    tx: &mut Conn,
    serial: &str,
    model: Option<&str>,
) -> std::result::Result<i64, DbError> {
    let id = tx
        .query_one("SELECT COALESCE(MAX(id), 0) + 1 FROM instruments", &[])?
        .i(0)?;
    tx.execute(
        "INSERT INTO instruments (id, serial, model) VALUES (?1, ?2, ?3)",
        &[P::I(id), P::T(Some(serial)), P::T(model)],
    )?;
    Ok(id)
}

/// The last entry's (record's or event's) id and hash (0 and [`GENESIS`]
/// for an empty store).
pub(crate) fn chain_head(tx: &mut Conn) -> std::result::Result<(i64, String), DbError> {
    match tx.query_opt(
        "SELECT id, record_hash FROM records
         UNION ALL SELECT id, event_hash FROM events
         ORDER BY 1 DESC LIMIT 1",
        &[],
    )? {
        Some(r) => Ok((r.i(0)?, r.t(1)?)),
        None => Ok((0, GENESIS.to_string())),
    }
}

/// The rows of one record: the record, its input files, its supersession.
pub(crate) fn write_record(
    tx: &mut Conn,
    instrument_id: i64,
    f: &ChainFields,
    document: &str,
    record_hash: &str,
) -> std::result::Result<(), DbError> {
    tx.execute(
        "INSERT INTO records (id, instrument_id, procedure, created_utc, operator, station,
                              document, document_sha256, prev_hash, record_hash)
         VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
        &[
            P::I(f.id),
            P::I(instrument_id),
            P::T(Some(f.procedure)),
            P::T(Some(f.created_utc)),
            P::T(f.operator),
            P::T(f.station),
            P::T(Some(document)),
            P::T(Some(f.document_sha256)),
            P::T(Some(f.prev_hash)),
            P::T(Some(record_hash)),
        ],
    )?;
    for (k, i) in f.inputs.iter().enumerate() {
        tx.execute(
            "INSERT INTO record_inputs (record_id, position, role, path, sha256)
             VALUES (?1, ?2, ?3, ?4, ?5)",
            &[
                P::I(f.id),
                P::I(k as i64),
                P::T(Some(&i.role)),
                P::T(Some(&i.path)),
                P::T(Some(&i.sha256)),
            ],
        )?;
    }
    if let (Some(old), Some(reason)) = (f.supersedes, f.reason) {
        tx.execute(
            "INSERT INTO supersessions (old_id, new_id, reason, created_utc)
             VALUES (?1, ?2, ?3, ?4)",
            &[
                P::I(old),
                P::I(f.id),
                P::T(Some(reason)),
                P::T(Some(f.created_utc)),
            ],
        )?;
    }
    Ok(())
}

/// The serial of a new record: the document's, the one given, or the
/// fallback (the superseded record's), checked to agree and be non-empty.
fn resolve_serial(
    doc: &ResultDocument,
    given: Option<&str>,
    fallback: Option<&str>,
) -> Result<String> {
    let in_doc = doc.instrument.serial.as_deref();
    let serial = match (in_doc, given) {
        (Some(d), Some(g)) if d != g => {
            return Err(Error::Input(format!(
                "serial '{g}' differs from the result's instrument.serial '{d}'"
            )))
        }
        (Some(d), _) => d,
        (None, Some(g)) => g,
        (None, None) => fallback.ok_or_else(|| {
            Error::Input("the result has no instrument.serial: give the serial (--serial)".into())
        })?,
    };
    if serial.trim().is_empty() {
        return Err(Error::Input("the serial is empty".into()));
    }
    Ok(serial.to_string())
}

/// Operator or station: the one given, else the document's
/// `instrument.KEY`; both given and different is an error.
fn from_meta(doc: &ResultDocument, key: &str, given: Option<&str>) -> Result<Option<String>> {
    let in_doc = doc.instrument.meta.get(key).map(String::as_str);
    match (in_doc, given) {
        (Some(d), Some(g)) if d != g => Err(Error::Input(format!(
            "{key} '{g}' differs from the result's instrument.{key} '{d}'"
        ))),
        (_, Some(g)) | (Some(g), None) => Ok(Some(g.to_string())),
        (None, None) => Ok(None),
    }
}
