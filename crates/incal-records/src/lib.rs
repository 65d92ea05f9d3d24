//! Calibration records for incal: an embedded, append-only store of result
//! documents (`incal.result/1`) per instrument, with a hash chain, history
//! and drift.
//!
//! * **Storage**: one SQLite file (rusqlite, bundled SQLite), schema in the
//!   plain-SQL migrations under `migrations/` (applied in order, tracked in
//!   `schema_migrations`), written to run unchanged on PostgreSQL.
//! * **Append-only**: there is no update and no delete. A correction is a
//!   new record that supersedes an old one, with a reason
//!   ([`Store::supersede`]).
//! * **Hash chain**: every record carries the hash of the record before it;
//!   `record_hash = SHA-256(canonical form)` ([`chain`] documents the form).
//!   [`Store::verify`] recomputes every document hash and every link and
//!   names the first record that does not match.
//! * **Crash and concurrency safety**: every write is one
//!   `BEGIN IMMEDIATE` transaction (the head of the chain is read and the
//!   record inserted under the same write lock) in WAL mode with
//!   `synchronous=FULL` and a busy timeout: a process killed at any moment
//!   leaves the whole record or none, and concurrent writers queue.
//! * **History**: [`Store::history`] gives one coefficient of one
//!   instrument across its calibrations (superseded records left out), the
//!   drift rate per day by weighted least squares on the incal estimation
//!   core, the repeatability and the En of the latest calibration against
//!   the previous ([`history`] has the formulas).
//!
//! ```no_run
//! use incal_records::{NewRecord, Store};
//! let mut store = Store::open("incal.db")?;
//! let text = std::fs::read_to_string("tumble.json").unwrap();
//! let added = store.add(&NewRecord::new(&text))?;
//! let h = store.history("SN-042", "K0")?;
//! println!("record {}: drift {:?}", added.id, h.drift);
//! # Ok::<(), incal_records::Error>(())
//! ```

pub mod chain;
pub mod history;
pub mod time;

use std::path::{Path, PathBuf};
use std::time::Duration;

use incal::document::ResultDocument;
use incal::units::Unit;
use rusqlite::{params, Connection, ErrorCode, OpenFlags, OptionalExtension, TransactionBehavior};
use serde::Serialize;

pub use chain::{sha256_hex, ChainFields, InputHash, GENESIS};
pub use history::{Drift, HistoryPoint, Repeatability};

/// The schema migrations, in order: `(version, name, SQL)`.
pub const MIGRATIONS: &[(i64, &str, &str)] =
    &[(1, "0001_init", include_str!("../migrations/0001_init.sql"))];

/// The table that tracks the migrations applied (created when missing).
pub const SCHEMA_MIGRATIONS: &str = include_str!("../migrations/schema_migrations.sql");

/// How long a writer waits for another writer's lock before failing.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(60);

/// What can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input: a document that is not an incal result, a serial that
    /// is missing or conflicts, an unknown record id, … (the CLI's exit 2).
    #[error("{0}")]
    Input(String),
    /// The file is not a records store this version can use (not SQLite,
    /// missing, a newer schema) (exit 2).
    #[error("{path}: {message}")]
    Store {
        /// The store's path.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A stored record does not match its hashes or its place in the
    /// chain ([`Store::verify`]; exit 1).
    #[error("record {id}: {problem}")]
    Tampered {
        /// The first record that does not match.
        id: i64,
        /// What does not match.
        problem: String,
    },
    /// The chain no longer holds a head kept elsewhere: records were
    /// removed or the chain rebuilt since ([`Store::verify_head`]; exit 1).
    #[error("the chain does not hold head {head}: records were removed or the chain rebuilt since it was written down")]
    HeadMissing {
        /// The head looked for.
        head: String,
    },
    /// Any other database failure (exit 1).
    #[error("{path}: {source}")]
    Database {
        /// The store's path.
        path: String,
        /// SQLite's error.
        source: rusqlite::Error,
    },
}

impl Error {
    /// True for bad input or an unusable store file (the CLI's exit 2).
    pub fn is_input(&self) -> bool {
        matches!(self, Error::Input(_) | Error::Store { .. })
    }
}

/// Result of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// A result document to store, and what the record adds to it.
#[derive(Debug, Clone, Default)]
pub struct NewRecord<'a> {
    /// The result document's text, stored exactly as given.
    pub document: &'a str,
    /// Serial of the instrument; needed when the document's
    /// `instrument.serial` is null, and must equal it otherwise.
    pub serial: Option<&'a str>,
    /// Who made the calibration; default the document's
    /// `instrument.operator` (from `--meta operator=…`), which it must
    /// equal when both are given.
    pub operator: Option<&'a str>,
    /// Where (rig, bench, lab); default the document's
    /// `instrument.station`, which it must equal when both are given.
    pub station: Option<&'a str>,
    /// The record's time (RFC 3339, [`time`]) instead of now: for entering
    /// past calibrations (backfill) and for tests. History uses this time
    /// as the calibration's date.
    pub created_utc: Option<&'a str>,
}

impl<'a> NewRecord<'a> {
    /// A record of `document` with everything else from the document.
    pub fn new(document: &'a str) -> Self {
        Self {
            document,
            ..Self::default()
        }
    }
}

/// A record just written.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Added {
    /// Its id.
    pub id: i64,
    /// SHA-256 of the stored document's bytes.
    pub sha256: String,
    /// Its hash in the chain.
    pub record_hash: String,
    /// The same document was already stored for this instrument: this is
    /// that record, and nothing was written (a retried `add` never makes a
    /// duplicate).
    pub existing: bool,
}

/// One line of [`Store::list`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RecordSummary {
    /// Record id.
    pub id: i64,
    /// Instrument serial.
    pub serial: String,
    /// Procedure of the result.
    pub procedure: String,
    /// `YYYY-MM-DDTHH:MM:SSZ`.
    pub created_utc: String,
    /// SHA-256 of the stored document.
    pub sha256: String,
    /// Operator.
    pub operator: Option<String>,
    /// Station.
    pub station: Option<String>,
    /// The record that supersedes this one.
    pub superseded_by: Option<i64>,
}

/// A correction: what a record supersedes and why.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Supersession {
    /// The superseded record.
    pub old_id: i64,
    /// The correcting record.
    pub new_id: i64,
    /// Why.
    pub reason: String,
    /// When (the correcting record's time).
    pub created_utc: String,
}

/// One stored record in full ([`Store::show`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StoredRecord {
    /// Record id.
    pub id: i64,
    /// Instrument serial.
    pub serial: String,
    /// Instrument model as first recorded.
    pub model: Option<String>,
    /// Procedure.
    pub procedure: String,
    /// `YYYY-MM-DDTHH:MM:SSZ`.
    pub created_utc: String,
    /// Operator.
    pub operator: Option<String>,
    /// Station.
    pub station: Option<String>,
    /// The result document, exactly as stored.
    pub document: String,
    /// SHA-256 of `document`.
    pub sha256: String,
    /// Hash of the record before.
    pub prev_hash: String,
    /// This record's hash.
    pub record_hash: String,
    /// Its input files.
    pub inputs: Vec<InputHash>,
    /// What this record corrects.
    pub supersedes: Option<Supersession>,
    /// The record that corrects this one.
    pub superseded_by: Option<i64>,
}

/// One coefficient of one instrument across its calibrations
/// ([`Store::history`]; formulas in [`history`]).
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    /// Instrument serial.
    pub serial: String,
    /// Coefficient name.
    pub coefficient: String,
    /// Its unit.
    pub unit: Unit,
    /// Every calibration that is not superseded and has the coefficient,
    /// in time order (created_utc, then id).
    pub points: Vec<HistoryPoint>,
    /// Drift rate per day (weighted least squares, weights 1/u²).
    pub drift: Option<Drift>,
    /// Standard deviation of the values (dof n − 1).
    pub repeatability: Option<Repeatability>,
    /// En of the latest calibration against the previous (U95 of each).
    pub en_latest: Option<f64>,
    /// Why drift, repeatability or En is missing.
    pub notes: Vec<String>,
}

/// An intact store ([`Store::verify`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Verified {
    /// Number of records.
    pub records: i64,
    /// `record_hash` of the last record ([`GENESIS`] when empty): write it
    /// down to anchor the chain (module docs of [`chain`]).
    pub head: String,
}

/// A records store: one SQLite file.
#[derive(Debug)]
pub struct Store {
    conn: Connection,
    path: PathBuf,
}

/// True for SQLite's "file is not a database" (and similar corruption on
/// open).
fn not_a_database(e: &rusqlite::Error) -> bool {
    matches!(
        e.sqlite_error_code(),
        Some(ErrorCode::NotADatabase | ErrorCode::DatabaseCorrupt)
    )
}

impl Store {
    /// Open the store at `path`, creating it (and its tables) when it does
    /// not exist, and bring its schema up to date.
    pub fn open(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_with(path.as_ref(), true)
    }

    /// Open an existing store for reading: read-only, so a missing, empty
    /// or foreign file is refused and never created, migrated or changed
    /// (an auditor's read-only copy can be verified).
    pub fn open_existing(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_with(path.as_ref(), false)
    }

    /// Open an existing store for writing (`supersede`): a missing file
    /// is refused, not created.
    pub fn open_to_write(path: impl AsRef<Path>) -> Result<Store> {
        let path = path.as_ref();
        Self::check_path(path)?;
        if !path.exists() {
            return Err(Error::Store {
                path: path.display().to_string(),
                message: "no records store here (no such file; 'incal record add' creates one)"
                    .into(),
            });
        }
        Self::open_with(path, true)
    }

    /// Refuse what is not a plain file path: SQLite's in-memory and URI
    /// names (`:memory:`, `file:…`) would accept a record and keep nothing.
    fn check_path(path: &Path) -> Result<()> {
        let text = path.to_string_lossy();
        let bad = if text.is_empty() {
            Some("an empty path")
        } else if text == ":memory:" || text.starts_with("file:") {
            Some("an in-memory or URI database, which keeps nothing in a file")
        } else {
            None
        };
        match bad {
            Some(what) => Err(Error::Store {
                path: text.into_owned(),
                message: format!("{what}: give the path of a records file"),
            }),
            None => Ok(()),
        }
    }

    fn open_with(path: &Path, create: bool) -> Result<Store> {
        Self::check_path(path)?;
        let name = path.display().to_string();
        if !create && !path.exists() {
            return Err(Error::Store {
                path: name,
                message: "no records store here (no such file; 'incal record add' creates one)"
                    .into(),
            });
        }
        if path.is_dir() {
            return Err(Error::Store {
                path: name,
                message: "is a directory, not a records store".into(),
            });
        }
        if !create && path.metadata().is_ok_and(|m| m.len() == 0) {
            return Err(Error::Store {
                path: name,
                message: "not an incal records store (an empty file)".into(),
            });
        }
        let flags = if create {
            OpenFlags::SQLITE_OPEN_READ_WRITE
                | OpenFlags::SQLITE_OPEN_CREATE
                | OpenFlags::SQLITE_OPEN_NO_MUTEX
        } else {
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX
        };
        let conn = Connection::open_with_flags(path, flags).map_err(|e| Error::Store {
            path: name.clone(),
            message: format!("cannot open: {e}"),
        })?;
        let mut store = Store {
            conn,
            path: path.to_path_buf(),
        };
        if create {
            // Another application's SQLite file is not made a store.
            if store.schema_version()?.is_none() && store.has_tables()? {
                return Err(Error::Store {
                    path: name,
                    message: "not an incal records store (an SQLite file with other tables)".into(),
                });
            }
            store.setup()?;
        } else {
            store.check_readable()?;
        }
        Ok(store)
    }

    /// A store opened for reading: an incal store at the schema this
    /// version knows, checked without writing anything.
    fn check_readable(&mut self) -> Result<()> {
        self.conn.busy_timeout(BUSY_TIMEOUT).map_err(self.db())?;
        let latest = MIGRATIONS.last().map_or(0, |m| m.0);
        let foreign = |what: &str| Error::Store {
            path: self.path.display().to_string(),
            message: format!("not an incal records store ({what})"),
        };
        match self.schema_version()? {
            None => Err(foreign("no incal tables")),
            Some(v) if v > latest => Err(Error::Store {
                path: self.path.display().to_string(),
                message: format!(
                    "schema version {v} is newer than this incal knows ({latest}): use a newer incal"
                ),
            }),
            Some(v) if v < latest => Err(Error::Store {
                path: self.path.display().to_string(),
                message: format!(
                    "schema version {v} is older than this incal's ({latest}): 'incal record add' brings it up to date"
                ),
            }),
            Some(_) => Ok(()),
        }
    }

    /// The store's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn db(&self) -> impl Fn(rusqlite::Error) -> Error + '_ {
        move |e| {
            if not_a_database(&e) {
                Error::Store {
                    path: self.path.display().to_string(),
                    message: format!("not an incal records store ({e})"),
                }
            } else {
                Error::Database {
                    path: self.path.display().to_string(),
                    source: e,
                }
            }
        }
    }

    /// Pragmas, then the migrations not yet applied (each store is brought
    /// up to date in one write transaction).
    fn setup(&mut self) -> Result<()> {
        self.conn.busy_timeout(BUSY_TIMEOUT).map_err(self.db())?;
        // Switching to WAL needs a moment alone with the file: retry while
        // another process holds it (busy_timeout covers most of this).
        let mut tries = 0;
        loop {
            let r: rusqlite::Result<String> =
                self.conn
                    .query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0));
            match r {
                Ok(_) => break,
                Err(e)
                    if tries < 100
                        && matches!(
                            e.sqlite_error_code(),
                            Some(ErrorCode::DatabaseBusy | ErrorCode::DatabaseLocked)
                        ) =>
                {
                    tries += 1;
                    std::thread::sleep(Duration::from_millis(20));
                }
                Err(e) => return Err(self.db()(e)),
            }
        }
        self.conn
            .execute_batch("PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON;")
            .map_err(self.db())?;
        let latest = MIGRATIONS.last().map_or(0, |m| m.0);
        if self.schema_version()? == Some(latest) {
            return Ok(());
        }
        let name = self.path.display().to_string();
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(|e| db_err(&name, e))?;
        tx.execute_batch(SCHEMA_MIGRATIONS)
            .map_err(|e| db_err(&name, e))?;
        let have: i64 = tx
            .query_row(
                "SELECT COALESCE(MAX(version), 0) FROM schema_migrations",
                [],
                |r| r.get(0),
            )
            .map_err(|e| db_err(&name, e))?;
        if have > latest {
            return Err(Error::Store {
                path: name,
                message: format!(
                    "schema version {have} is newer than this incal knows ({latest}): use a newer incal"
                ),
            });
        }
        for (version, mname, sql) in MIGRATIONS.iter().filter(|m| m.0 > have) {
            tx.execute_batch(sql).map_err(|e| db_err(&name, e))?;
            tx.execute(
                "INSERT INTO schema_migrations (version, name, applied_utc) VALUES (?1, ?2, ?3)",
                params![version, mname, time::now_utc()],
            )
            .map_err(|e| db_err(&name, e))?;
        }
        tx.commit().map_err(|e| db_err(&name, e))
    }

    /// True when the file holds any table (of anyone).
    fn has_tables(&self) -> Result<bool> {
        self.conn
            .query_row(
                "SELECT COUNT(*) > 0 FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'",
                [],
                |r| r.get(0),
            )
            .map_err(self.db())
    }

    /// The schema version (`None` before the first migration).
    fn schema_version(&self) -> Result<Option<i64>> {
        let exists: bool = self
            .conn
            .query_row(
                "SELECT COUNT(*) > 0 FROM sqlite_master WHERE type = 'table' AND name = 'schema_migrations'",
                [],
                |r| r.get(0),
            )
            .map_err(self.db())?;
        if !exists {
            return Ok(None);
        }
        self.conn
            .query_row("SELECT MAX(version) FROM schema_migrations", [], |r| {
                r.get(0)
            })
            .map_err(self.db())
    }

    /// Store `req.document` as a new record (module docs); see
    /// [`NewRecord`] for the serial, operator and station.
    pub fn add(&mut self, req: &NewRecord) -> Result<Added> {
        self.insert(req, None)
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
        self.insert(req, Some((old_id, reason)))
    }

    fn insert(&mut self, req: &NewRecord, supersedes: Option<(i64, &str)>) -> Result<Added> {
        let doc = ResultDocument::from_json(req.document).map_err(Error::Input)?;
        let operator = from_meta(&doc, "operator", req.operator)?;
        let station = from_meta(&doc, "station", req.station)?;
        let created_utc = match req.created_utc {
            Some(t) => {
                time::normalize_utc(t).map_err(|e| Error::Input(format!("created_utc: {e}")))?
            }
            None => time::now_utc(),
        };
        if created_utc > time::now_utc() {
            return Err(Error::Input(format!(
                "created_utc {created_utc} is in the future: a record is dated when it was made"
            )));
        }
        // Never extend a broken chain: the new record would seal it.
        self.verify().map_err(|e| match e {
            Error::Tampered { id, problem } => Error::Tampered {
                id,
                problem: format!("{problem}; nothing is added to a broken chain"),
            },
            other => other,
        })?;
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
        let e = |e: rusqlite::Error| db_err(&name, e);
        let tx = self
            .conn
            .transaction_with_behavior(TransactionBehavior::Immediate)
            .map_err(e)?;
        let fallback_serial = match supersedes {
            Some((old, _)) => {
                let row: Option<(String, Option<i64>, String)> = tx
                    .query_row(
                        "SELECT i.serial, s.new_id, r.procedure FROM records r
                         JOIN instruments i ON i.id = r.instrument_id
                         LEFT JOIN supersessions s ON s.old_id = r.id
                         WHERE r.id = ?1",
                        [old],
                        |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
                    )
                    .optional()
                    .map_err(e)?;
                match row {
                    None => return Err(Error::Input(format!("record {old}: no such record"))),
                    Some((_, Some(by), _)) => {
                        return Err(Error::Input(format!(
                            "record {old} is already superseded by record {by}: supersede record {by} instead"
                        )))
                    }
                    Some((_, None, procedure)) if procedure != doc.procedure.as_str() => {
                        return Err(Error::Input(format!(
                            "record {old} is a {procedure} result and the correction a {} result: a correction must be of the same procedure",
                            doc.procedure.as_str()
                        )))
                    }
                    Some((serial, None, _)) => Some(serial),
                }
            }
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
        let instrument_id: Option<i64> = tx
            .query_row(
                "SELECT id FROM instruments WHERE serial = ?1",
                [&serial],
                |r| r.get(0),
            )
            .optional()
            .map_err(e)?;
        if let (Some(_), None) = (instrument_id, supersedes) {
            let same: Option<(i64, String)> = tx
                .query_row(
                    "SELECT r.id, r.record_hash FROM records r
                     JOIN instruments i ON i.id = r.instrument_id
                     WHERE i.serial = ?1 AND r.document_sha256 = ?2
                     ORDER BY r.id LIMIT 1",
                    params![serial, document_sha256],
                    |r| Ok((r.get(0)?, r.get(1)?)),
                )
                .optional()
                .map_err(e)?;
            if let Some((id, record_hash)) = same {
                return Ok(Added {
                    id,
                    sha256: document_sha256,
                    record_hash,
                    existing: true,
                });
            }
        }
        let instrument_id = match instrument_id {
            Some(id) => id,
            None => {
                let id: i64 = tx
                    .query_row(
                        "SELECT COALESCE(MAX(id), 0) + 1 FROM instruments",
                        [],
                        |r| r.get(0),
                    )
                    .map_err(e)?;
                tx.execute(
                    "INSERT INTO instruments (id, serial, model) VALUES (?1, ?2, ?3)",
                    params![id, serial, doc.instrument.model],
                )
                .map_err(e)?;
                id
            }
        };
        let (prev_id, prev_hash): (i64, String) = tx
            .query_row(
                "SELECT id, record_hash FROM records ORDER BY id DESC LIMIT 1",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
            .map_err(e)?
            .unwrap_or((0, GENESIS.to_string()));
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
        tx.execute(
            "INSERT INTO records (id, instrument_id, procedure, created_utc, operator, station,
                                  document, document_sha256, prev_hash, record_hash)
             VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
            params![
                id,
                instrument_id,
                procedure,
                created_utc,
                operator,
                station,
                req.document,
                document_sha256,
                prev_hash,
                record_hash
            ],
        )
        .map_err(e)?;
        for (k, i) in inputs.iter().enumerate() {
            tx.execute(
                "INSERT INTO record_inputs (record_id, position, role, path, sha256)
                 VALUES (?1, ?2, ?3, ?4, ?5)",
                params![id, k as i64, i.role, i.path, i.sha256],
            )
            .map_err(e)?;
        }
        if let Some((old, reason)) = supersedes {
            tx.execute(
                "INSERT INTO supersessions (old_id, new_id, reason, created_utc)
                 VALUES (?1, ?2, ?3, ?4)",
                params![old, id, reason, created_utc],
            )
            .map_err(e)?;
        }
        tx.commit().map_err(e)?;
        Ok(Added {
            id,
            sha256: document_sha256,
            record_hash,
            existing: false,
        })
    }

    /// Every record (of `serial` only, when given), by id.
    pub fn list(&self, serial: Option<&str>) -> Result<Vec<RecordSummary>> {
        let mut st = self
            .conn
            .prepare(
                "SELECT r.id, i.serial, r.procedure, r.created_utc, r.document_sha256,
                        r.operator, r.station, s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE ?1 IS NULL OR i.serial = ?1
                 ORDER BY r.id",
            )
            .map_err(self.db())?;
        let rows = st
            .query_map([serial], |r| {
                Ok(RecordSummary {
                    id: r.get(0)?,
                    serial: r.get(1)?,
                    procedure: r.get(2)?,
                    created_utc: r.get(3)?,
                    sha256: r.get(4)?,
                    operator: r.get(5)?,
                    station: r.get(6)?,
                    superseded_by: r.get(7)?,
                })
            })
            .map_err(self.db())?;
        rows.collect::<rusqlite::Result<Vec<_>>>()
            .map_err(self.db())
    }

    /// Record `id` in full, its document exactly as stored.
    pub fn show(&self, id: i64) -> Result<StoredRecord> {
        let tx = self.conn.unchecked_transaction().map_err(self.db())?;
        let rec = tx
            .query_row(
                "SELECT r.id, i.serial, i.model, r.procedure, r.created_utc, r.operator,
                        r.station, r.document, r.document_sha256, r.prev_hash, r.record_hash,
                        s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE r.id = ?1",
                [id],
                |r| {
                    Ok(StoredRecord {
                        id: r.get(0)?,
                        serial: r.get(1)?,
                        model: r.get(2)?,
                        procedure: r.get(3)?,
                        created_utc: r.get(4)?,
                        operator: r.get(5)?,
                        station: r.get(6)?,
                        document: r.get(7)?,
                        sha256: r.get(8)?,
                        prev_hash: r.get(9)?,
                        record_hash: r.get(10)?,
                        inputs: Vec::new(),
                        supersedes: None,
                        superseded_by: r.get(11)?,
                    })
                },
            )
            .optional()
            .map_err(self.db())?;
        let Some(mut rec) = rec else {
            return Err(Error::Input(format!("record {id}: no such record")));
        };
        rec.inputs = inputs_of(&tx, id).map_err(self.db())?;
        rec.supersedes = supersession_of(&tx, id).map_err(self.db())?;
        Ok(rec)
    }

    /// Coefficient `coefficient` of instrument `serial` across its
    /// calibrations that are not superseded, with drift, repeatability and
    /// En ([`history`]). Records whose result has no such coefficient are
    /// left out; none at all, or a unit that changes between records, is
    /// an error.
    pub fn history(&self, serial: &str, coefficient: &str) -> Result<History> {
        self.history_if_any(serial, coefficient)?
            .map_err(Error::Input)
    }

    /// As [`Store::history`], with "nothing to show" (no records of the
    /// instrument, every one superseded, none with the coefficient) as
    /// `Ok(Err(why))` rather than an error: a report plots the histories
    /// there are.
    pub fn history_if_any(
        &self,
        serial: &str,
        coefficient: &str,
    ) -> Result<std::result::Result<History, String>> {
        let mut st = self
            .conn
            .prepare(
                "SELECT r.id, r.created_utc, r.document
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE i.serial = ?1 AND s.old_id IS NULL
                 ORDER BY r.created_utc, r.id",
            )
            .map_err(self.db())?;
        let rows: Vec<(i64, String, String)> = st
            .query_map([serial], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .map_err(self.db())?
            .collect::<rusqlite::Result<_>>()
            .map_err(self.db())?;
        if rows.is_empty() {
            let known: bool = self
                .conn
                .query_row(
                    "SELECT COUNT(*) > 0 FROM instruments WHERE serial = ?1",
                    [serial],
                    |r| r.get(0),
                )
                .map_err(self.db())?;
            return Ok(Err(if known {
                format!("serial '{serial}': every record is superseded")
            } else {
                format!("serial '{serial}': no records of this instrument")
            }));
        }
        let mut points: Vec<HistoryPoint> = Vec::new();
        let mut names: Vec<String> = Vec::new();
        for (id, created_utc, text) in rows {
            let doc = ResultDocument::from_json(&text).map_err(|e| Error::Tampered {
                id,
                problem: format!("the stored document no longer reads as a result: {e}"),
            })?;
            let Some(c) = doc.coefficients.get(coefficient) else {
                for n in doc.coefficients.names() {
                    if !names.contains(&n) {
                        names.push(n);
                    }
                }
                continue;
            };
            if let Some(first) = points.first() {
                if first.unit != c.unit {
                    return Err(Error::Input(format!(
                        "coefficient {coefficient} is in '{}' in record {} but in '{}' in record {id}",
                        first.unit, first.id, c.unit
                    )));
                }
            }
            points.push(HistoryPoint {
                id,
                created_utc,
                value: c.value,
                u: c.u,
                u95: c.u95,
                dof: c.dof,
                unit: c.unit.clone(),
            });
        }
        if points.is_empty() {
            return Ok(Err(format!(
                "serial '{serial}': no calibration has a coefficient '{coefficient}' (recorded: {})",
                names.join(", ")
            )));
        }
        let a = history::analyse(&points);
        Ok(Ok(History {
            serial: serial.to_string(),
            coefficient: coefficient.to_string(),
            unit: points[0].unit.clone(),
            points,
            drift: a.drift,
            repeatability: a.repeatability,
            en_latest: a.en_latest,
            notes: a.notes,
        }))
    }

    /// Recompute the chain: for every record in id order, the id follows
    /// the one before, `prev_hash` is the record before's `record_hash`
    /// (64 zeros for record 1), the stored document's SHA-256 is
    /// `document_sha256`, and `record_hash` is the hash of its canonical
    /// form ([`chain`]); every supersession and input-file row belongs to
    /// a record that covers it. The first record that fails is
    /// [`Error::Tampered`]. Reads one consistent snapshot.
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

    /// The record of instrument `serial` whose stored document is
    /// `document` byte for byte (its SHA-256), the first if corrected
    /// since: `(id, record_hash)`, or `None`. A certificate of that
    /// document names the record.
    pub fn find(&self, serial: &str, document: &str) -> Result<Option<(i64, String)>> {
        self.conn
            .query_row(
                "SELECT r.id, r.record_hash FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 WHERE i.serial = ?1 AND r.document_sha256 = ?2
                 ORDER BY r.id LIMIT 1",
                params![serial, sha256_hex(document.as_bytes())],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
            .map_err(self.db())
    }

    fn verify_holding(&self, anchor: Option<&str>) -> Result<Verified> {
        let mut held = anchor.is_none() || anchor == Some(GENESIS);
        let tx = self.conn.unchecked_transaction().map_err(self.db())?;
        let mut st = tx
            .prepare(
                "SELECT r.id, i.serial, r.procedure, r.created_utc, r.operator, r.station,
                        r.document, r.document_sha256, r.prev_hash, r.record_hash, i.model
                 FROM records r
                 LEFT JOIN instruments i ON i.id = r.instrument_id
                 ORDER BY r.id",
            )
            .map_err(self.db())?;
        type Row = (
            i64,
            Option<String>,
            String,
            String,
            Option<String>,
            Option<String>,
            Vec<u8>,
            String,
            String,
            String,
            Option<String>,
        );
        let mut rows = st.query([]).map_err(self.db())?;
        // The instrument row's model is set from the first record of its
        // serial: checked against that record's (hashed) document.
        let mut seen_serials = std::collections::HashSet::new();
        let (mut prev_id, mut prev_hash) = (0i64, GENESIS.to_string());
        let mut count = 0i64;
        while let Some(r) = rows.next().map_err(self.db())? {
            // The document is read as bytes: a value changed to a blob or
            // to text that is not UTF-8 is reported, not a read failure.
            let row: Row = (|| {
                Ok::<Row, rusqlite::Error>((
                    r.get(0)?,
                    r.get(1)?,
                    r.get(2)?,
                    r.get(3)?,
                    r.get(4)?,
                    r.get(5)?,
                    match r.get_ref(6)? {
                        rusqlite::types::ValueRef::Text(b) | rusqlite::types::ValueRef::Blob(b) => {
                            b.to_vec()
                        }
                        _ => Vec::new(),
                    },
                    r.get(7)?,
                    r.get(8)?,
                    r.get(9)?,
                    r.get(10)?,
                ))
            })()
            .map_err(|e| Error::Tampered {
                id: r.get(0).unwrap_or(prev_id + 1),
                problem: format!("a column does not read as stored by incal ({e})"),
            })?;
            let (
                id,
                serial,
                procedure,
                created,
                operator,
                station,
                document,
                doc_sha,
                prev,
                hash,
                model,
            ) = row;
            let bad = |problem: String| Error::Tampered { id, problem };
            if id != prev_id + 1 {
                return Err(bad(if prev_id == 0 {
                    "the chain does not start at record 1".into()
                } else {
                    format!(
                        "follows record {prev_id}: record {} is missing",
                        prev_id + 1
                    )
                }));
            }
            if prev != prev_hash {
                return Err(bad(format!(
                    "prev_hash does not match the hash of record {prev_id}"
                )));
            }
            if sha256_hex(&document) != doc_sha {
                return Err(bad("the stored document does not match its SHA-256".into()));
            }
            let serial = serial.ok_or_else(|| bad("its instrument row is missing".into()))?;
            if seen_serials.insert(serial.clone()) {
                let doc_model = serde_json::from_slice::<serde_json::Value>(&document)
                    .ok()
                    .and_then(|v| v["instrument"]["model"].as_str().map(String::from));
                if doc_model != model {
                    return Err(bad(format!(
                        "the instrument's model ({}) is not the one in its first record's document ({})",
                        model.as_deref().unwrap_or("none"),
                        doc_model.as_deref().unwrap_or("none")
                    )));
                }
            }
            let inputs = inputs_of(&tx, id).map_err(self.db())?;
            let sup = supersession_of(&tx, id).map_err(self.db())?;
            if let Some(s) = &sup {
                if s.created_utc != created {
                    return Err(bad(format!(
                        "the supersession of record {} has a time other than the record's",
                        s.old_id
                    )));
                }
                if s.old_id >= id {
                    return Err(bad(format!(
                        "supersedes record {}, which is not older",
                        s.old_id
                    )));
                }
            }
            let fields = ChainFields {
                prev_hash: &prev,
                id,
                serial: &serial,
                procedure: &procedure,
                created_utc: &created,
                operator: operator.as_deref(),
                station: station.as_deref(),
                document_sha256: &doc_sha,
                inputs: &inputs,
                supersedes: sup.as_ref().map(|s| s.old_id),
                reason: sup.as_ref().map(|s| s.reason.as_str()),
            };
            if fields.record_hash() != hash {
                return Err(bad(
                    "record_hash does not match its fields (serial, procedure, time, operator, station, inputs or supersession changed)"
                        .into(),
                ));
            }
            if anchor == Some(hash.as_str()) {
                held = true;
            }
            prev_id = id;
            prev_hash = hash;
            count += 1;
        }
        drop(rows);
        // Rows that point at no record are covered by no hash.
        let orphan: Option<(i64, String)> = tx
            .query_row(
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
                 LIMIT 1",
                [],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )
            .optional()
            .map_err(self.db())?;
        if let Some((id, problem)) = orphan {
            return Err(Error::Tampered { id, problem });
        }
        if let (false, Some(h)) = (held, anchor) {
            return Err(Error::HeadMissing {
                head: h.to_string(),
            });
        }
        Ok(Verified {
            records: count,
            head: prev_hash,
        })
    }
}

fn db_err(path: &str, e: rusqlite::Error) -> Error {
    if not_a_database(&e) {
        Error::Store {
            path: path.to_string(),
            message: format!("not an incal records store ({e})"),
        }
    } else {
        Error::Database {
            path: path.to_string(),
            source: e,
        }
    }
}

fn inputs_of(conn: &Connection, id: i64) -> rusqlite::Result<Vec<InputHash>> {
    let mut st = conn.prepare_cached(
        "SELECT role, path, sha256 FROM record_inputs WHERE record_id = ?1 ORDER BY position",
    )?;
    let rows = st.query_map([id], |r| {
        Ok(InputHash {
            role: r.get(0)?,
            path: r.get(1)?,
            sha256: r.get(2)?,
        })
    })?;
    rows.collect()
}

fn supersession_of(conn: &Connection, new_id: i64) -> rusqlite::Result<Option<Supersession>> {
    conn.query_row(
        "SELECT old_id, new_id, reason, created_utc FROM supersessions WHERE new_id = ?1",
        [new_id],
        |r| {
            Ok(Supersession {
                old_id: r.get(0)?,
                new_id: r.get(1)?,
                reason: r.get(2)?,
                created_utc: r.get(3)?,
            })
        },
    )
    .optional()
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
