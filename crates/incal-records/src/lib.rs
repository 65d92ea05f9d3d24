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
mod db;
pub mod history;
pub mod time;

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use incal::document::ResultDocument;
use incal::units::Unit;
use rusqlite::{Connection, ErrorCode, OpenFlags};
use serde::{Deserialize, Serialize};

use db::{Conn, DbError, Mode, P};

pub use chain::{sha256_hex, ChainFields, InputHash, GENESIS};
pub use db::{display_url, is_postgres_url};

/// The largest result document a record holds (as every document incal
/// reads whole).
pub const MAX_DOCUMENT_BYTES: usize = 64 << 20;
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
        /// The store's path (or URL, without its password).
        path: String,
        /// The database's error.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// Writing an export failed (exit 1).
    #[error("writing the export: {0}")]
    Output(String),
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

/// Calibrations of one coefficient spread over more than this (°C) earn a
/// note in its history: their differences may be temperature, not drift.
pub const TEMPERATURE_SPREAD_C: f64 = 5.0;

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

/// A records store: one SQLite file, or one PostgreSQL database
/// (`postgresql://…`), with the same schema, chain and behaviour.
#[derive(Debug)]
pub struct Store {
    conn: RefCell<Conn>,
    /// The SQLite path, or the PostgreSQL URL without its password.
    path: PathBuf,
}

/// How a store is opened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Opening {
    /// Created when missing, brought up to date.
    Create,
    /// Must exist; brought up to date.
    ToWrite,
    /// Must exist at this version; opened read-only.
    Read,
}

/// Rows read per round trip when the whole chain is scanned.
const PAGE: i64 = 256;

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

/// A record as read by a scan of the chain: every column, unchecked.
struct Scanned {
    id: i64,
    serial: Option<String>,
    model: Option<String>,
    procedure: String,
    created_utc: String,
    operator: Option<String>,
    station: Option<String>,
    document: Vec<u8>,
    document_sha256: String,
    prev_hash: String,
    record_hash: String,
    inputs: Vec<InputHash>,
    supersedes: Option<Supersession>,
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
    /// Open the store at `path` (a file, or a `postgresql://` URL),
    /// creating it (and its tables) when it does not exist, and bring its
    /// schema up to date.
    pub fn open(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_at(path.as_ref(), Opening::Create)
    }

    /// Open an existing store for reading: read-only, so a missing, empty
    /// or foreign file (or database) is refused and never created,
    /// migrated or changed (an auditor's read-only copy can be verified).
    pub fn open_existing(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_at(path.as_ref(), Opening::Read)
    }

    /// Open an existing store for writing (`supersede`): a missing store
    /// is refused, not created.
    pub fn open_to_write(path: impl AsRef<Path>) -> Result<Store> {
        Self::open_at(path.as_ref(), Opening::ToWrite)
    }

    fn open_at(path: &Path, how: Opening) -> Result<Store> {
        match path.to_str() {
            Some(url) if is_postgres_url(url) => Self::open_postgres(url, how),
            _ => Self::open_sqlite(path, how),
        }
    }

    /// Refuse what is not a plain file path: SQLite's in-memory and URI
    /// names (`:memory:`, `file:…`) would accept a record and keep nothing.
    fn check_path(path: &Path) -> Result<()> {
        let text = path.to_string_lossy();
        let bad = if text.is_empty() {
            Some("an empty path")
        } else if text == ":memory:" || text.starts_with("file:") {
            Some("an in-memory or URI database, which keeps nothing in a file")
        } else if text.contains("://") {
            Some("a URL incal cannot open (a records store is a file path or a postgresql:// URL)")
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

    fn open_sqlite(path: &Path, how: Opening) -> Result<Store> {
        Self::check_path(path)?;
        let name = path.display().to_string();
        let create = how != Opening::Read;
        if (how != Opening::Create) && !path.exists() {
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
        conn.busy_timeout(BUSY_TIMEOUT)
            .map_err(|e| db_err(&name, e.into()))?;
        let store = Store {
            conn: RefCell::new(Conn::Sqlite(conn)),
            path: path.to_path_buf(),
        };
        if create {
            // Another application's SQLite file is not made a store.
            // (The version is asked again after the tables: another
            // incal's first migration may have committed in between.)
            if store.schema_version()?.is_none()
                && store.has_tables()?
                && store.schema_version()?.is_none()
            {
                return Err(store.foreign_tables());
            }
            store.sqlite_pragmas()?;
            store.migrate()?;
        } else {
            store.check_readable()?;
        }
        Ok(store)
    }

    fn open_postgres(url: &str, how: Opening) -> Result<Store> {
        let name = display_url(url);
        let client = db::connect_postgres(url).map_err(|message| Error::Store {
            path: name.clone(),
            message,
        })?;
        let store = Store {
            conn: RefCell::new(Conn::Postgres(Box::new(client))),
            path: PathBuf::from(&name),
        };
        if how == Opening::Read {
            // Reading never writes, whatever the code path.
            store
                .conn
                .borrow_mut()
                .batch("SET default_transaction_read_only = on")
                .map_err(store.db())?;
            store.check_readable()?;
            return Ok(store);
        }
        match store.schema_version()? {
            None if how == Opening::ToWrite => {
                return Err(Error::Store {
                    path: name,
                    message:
                        "no records store here (no incal tables; 'incal record add' creates them)"
                            .into(),
                })
            }
            // Whether the tables are someone else's is decided in
            // `migrate`, under its lock: checked here, another incal's
            // migration committing between two queries looked foreign.
            _ => {}
        }
        store.migrate()?;
        Ok(store)
    }

    /// A store opened for reading: an incal store at the schema this
    /// version knows, checked without writing anything.
    fn check_readable(&self) -> Result<()> {
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

    /// The store's path: the SQLite file, or the PostgreSQL URL without
    /// its password.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// True when the store is on a PostgreSQL server.
    pub fn is_postgres(&self) -> bool {
        self.conn.borrow().is_postgres()
    }

    fn db(&self) -> impl Fn(DbError) -> Error + '_ {
        move |e| db_err(&self.path.display().to_string(), e)
    }

    /// SQLite only: WAL, full sync, foreign keys.
    fn sqlite_pragmas(&self) -> Result<()> {
        let mut c = self.conn.borrow_mut();
        let Conn::Sqlite(conn) = &mut *c else {
            return Ok(());
        };
        // Switching to WAL needs a moment alone with the file: retry while
        // another process holds it (busy_timeout covers most of this).
        let mut tries = 0;
        loop {
            let r: rusqlite::Result<String> =
                conn.query_row("PRAGMA journal_mode = WAL", [], |r| r.get(0));
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
                Err(e) => return Err(db_err(&self.path.display().to_string(), e.into())),
            }
        }
        conn.execute_batch("PRAGMA synchronous = FULL; PRAGMA foreign_keys = ON;")
            .map_err(|e| db_err(&self.path.display().to_string(), e.into()))
    }

    /// The migrations not yet applied, in one transaction (under an
    /// advisory lock on PostgreSQL, so stations opening a new store at
    /// once create it once).
    fn migrate(&self) -> Result<()> {
        let latest = MIGRATIONS.last().map_or(0, |m| m.0);
        if self.schema_version()? == Some(latest) {
            return Ok(());
        }
        let name = self.path.display().to_string();
        let e = |e| db_err(&name, e);
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Migrate).map_err(e)?;
        // Under the migration lock, so a concurrent first migration has
        // either committed all its tables or none.
        if !tx.table_exists("schema_migrations").map_err(e)? && tx.has_tables().map_err(e)? {
            drop(tx);
            drop(c);
            return Err(self.foreign_tables());
        }
        tx.batch(SCHEMA_MIGRATIONS).map_err(e)?;
        let have = tx
            .query_one(
                "SELECT COALESCE(MAX(version), 0) FROM schema_migrations",
                &[],
            )
            .and_then(|r| r.i(0))
            .map_err(e)?;
        if have > latest {
            return Err(Error::Store {
                path: name.clone(),
                message: format!(
                    "schema version {have} is newer than this incal knows ({latest}): use a newer incal"
                ),
            });
        }
        let now = time::now_utc();
        for (version, mname, sql) in MIGRATIONS.iter().filter(|m| m.0 > have) {
            tx.batch(sql).map_err(e)?;
            tx.execute(
                "INSERT INTO schema_migrations (version, name, applied_utc) VALUES (?1, ?2, ?3)",
                &[P::I(*version), P::T(Some(mname)), P::T(Some(&now))],
            )
            .map_err(e)?;
        }
        tx.commit().map_err(e)
    }

    /// The refusal to make another application's database a store.
    fn foreign_tables(&self) -> Error {
        let what = if self.is_postgres() {
            "a PostgreSQL schema with other tables: give incal a database or schema of its own"
        } else {
            "an SQLite file with other tables"
        };
        Error::Store {
            path: self.path.display().to_string(),
            message: format!("not an incal records store ({what})"),
        }
    }

    /// True when the store holds any table (of anyone).
    fn has_tables(&self) -> Result<bool> {
        self.conn.borrow_mut().has_tables().map_err(self.db())
    }

    /// The schema version (`None` before the first migration).
    fn schema_version(&self) -> Result<Option<i64>> {
        let mut c = self.conn.borrow_mut();
        if !c.table_exists("schema_migrations").map_err(self.db())? {
            return Ok(None);
        }
        c.query_one("SELECT MAX(version) FROM schema_migrations", &[])
            .and_then(|r| r.oi(0))
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

    /// Never extend a broken chain: the new record would seal it.
    fn verify_before_writing(&self) -> Result<Verified> {
        self.verify().map_err(|e| match e {
            Error::Tampered { id, problem } => Error::Tampered {
                id,
                problem: format!("{problem}; nothing is added to a broken chain"),
            },
            other => other,
        })
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
            Some((old, _)) => {
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
        let instrument_id = instrument_of(&mut tx, &serial).map_err(e)?;
        if let (Some(_), None) = (instrument_id, supersedes) {
            let same = tx
                .query_opt(
                    "SELECT r.id, r.record_hash FROM records r
                     JOIN instruments i ON i.id = r.instrument_id
                     WHERE i.serial = ?1 AND r.document_sha256 = ?2
                     ORDER BY r.id LIMIT 1",
                    &[P::T(Some(&serial)), P::T(Some(&document_sha256))],
                )
                .map_err(e)?;
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
        let rows = self
            .conn
            .borrow_mut()
            .query(
                "SELECT r.id, i.serial, r.procedure, r.created_utc, r.document_sha256,
                        r.operator, r.station, s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE CAST(?1 AS TEXT) IS NULL OR i.serial = ?1
                 ORDER BY r.id",
                &[P::T(serial)],
            )
            .map_err(self.db())?;
        rows.iter()
            .map(|r| {
                Ok(RecordSummary {
                    id: r.i(0)?,
                    serial: r.t(1)?,
                    procedure: r.t(2)?,
                    created_utc: r.t(3)?,
                    sha256: r.t(4)?,
                    operator: r.ot(5)?,
                    station: r.ot(6)?,
                    superseded_by: r.oi(7)?,
                })
            })
            .collect::<std::result::Result<Vec<_>, DbError>>()
            .map_err(self.db())
    }

    /// Record `id` in full, its document exactly as stored.
    pub fn show(&self, id: i64) -> Result<StoredRecord> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let row = tx
            .query_opt(
                "SELECT r.id, i.serial, i.model, r.procedure, r.created_utc, r.operator,
                        r.station, r.document, r.document_sha256, r.prev_hash, r.record_hash,
                        s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE r.id = ?1",
                &[P::I(id)],
            )
            .map_err(self.db())?;
        let Some(r) = row else {
            return Err(Error::Input(format!("record {id}: no such record")));
        };
        let read = |tx: &mut Conn| -> std::result::Result<StoredRecord, DbError> {
            Ok(StoredRecord {
                id: r.i(0)?,
                serial: r.t(1)?,
                model: r.ot(2)?,
                procedure: r.t(3)?,
                created_utc: r.t(4)?,
                operator: r.ot(5)?,
                station: r.ot(6)?,
                document: r.t(7)?,
                sha256: r.t(8)?,
                prev_hash: r.t(9)?,
                record_hash: r.t(10)?,
                inputs: inputs_between(tx, id, id)?.remove(&id).unwrap_or_default(),
                supersedes: supersessions_between(tx, id, id)?.remove(&id),
                superseded_by: r.oi(11)?,
            })
        };
        let rec = read(&mut tx).map_err(self.db())?;
        tx.commit().map_err(self.db())?;
        Ok(rec)
    }

    /// Coefficient `coefficient` of instrument `serial` across its
    /// calibrations that are not superseded, with drift, repeatability and
    /// En ([`history`]). Records whose result has no such coefficient are
    /// left out; none at all, or a unit that changes between records, is
    /// an error; so are records of more than one procedure (a tumble's K2
    /// is K2 − K_pp, a centrifuge's is K2: [`Store::history_of`] picks one).
    pub fn history(&self, serial: &str, coefficient: &str) -> Result<History> {
        self.history_of(serial, coefficient, None, None)
    }

    /// [`Store::history`] over the records of `procedure` only (a
    /// procedure id, `tumble`), when given.
    pub fn history_of(
        &self,
        serial: &str,
        coefficient: &str,
        procedure: Option<&str>,
        temperature: Option<(f64, f64)>,
    ) -> Result<History> {
        self.history_if_any(serial, coefficient, procedure, temperature)?
            .map_err(Error::Input)
    }

    /// As [`Store::history`], with "nothing to show" (no records of the
    /// instrument, every one superseded, none with the coefficient) as
    /// `Ok(Err(why))` rather than an error: a report plots the histories
    /// there are.
    ///
    /// With `temperature = Some((t, tol))` only the records made within
    /// `tol` °C of `t` count (a coefficient that moves with temperature
    /// drifts only at one temperature); without it, records spread over
    /// more than [`TEMPERATURE_SPREAD_C`] earn a note.
    pub fn history_if_any(
        &self,
        serial: &str,
        coefficient: &str,
        procedure: Option<&str>,
        temperature: Option<(f64, f64)>,
    ) -> Result<std::result::Result<History, String>> {
        let (rows, known) = {
            let mut c = self.conn.borrow_mut();
            let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
            let rows = tx
                .query(
                    "SELECT r.id, r.created_utc, r.document, r.procedure
                     FROM records r
                     JOIN instruments i ON i.id = r.instrument_id
                     LEFT JOIN supersessions s ON s.old_id = r.id
                     WHERE i.serial = ?1 AND s.old_id IS NULL
                       AND (CAST(?2 AS TEXT) IS NULL OR r.procedure = ?2)
                     ORDER BY r.created_utc, r.id",
                    &[P::T(Some(serial)), P::T(procedure)],
                )
                .and_then(|rows| {
                    rows.iter()
                        .map(|r| Ok((r.i(0)?, r.t(1)?, r.t(2)?, r.t(3)?)))
                        .collect::<std::result::Result<Vec<_>, DbError>>()
                })
                .map_err(self.db())?;
            let known = instrument_of(&mut tx, serial).map_err(self.db())?.is_some();
            tx.commit().map_err(self.db())?;
            (rows, known)
        };
        if rows.is_empty() {
            return Ok(Err(match (known, procedure) {
                (true, Some(p)) => {
                    format!("serial '{serial}': no {p} records (not superseded) of this instrument")
                }
                (true, None) => format!("serial '{serial}': every record is superseded"),
                (false, _) => format!("serial '{serial}': no records of this instrument"),
            }));
        }
        let mut points: Vec<HistoryPoint> = Vec::new();
        let mut names: Vec<String> = Vec::new();
        let mut procedures: Vec<String> = Vec::new();
        let mut skipped_by_temperature = 0usize;
        for (id, created_utc, text, proc_id) in rows {
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
            let temperature_c = incal::procedures::thermal::soak::temperature_of(&doc).ok();
            if let Some((t, tol)) = temperature {
                if !temperature_c.is_some_and(|x| (x - t).abs() <= tol) {
                    skipped_by_temperature += 1;
                    continue;
                }
            }
            if !procedures.contains(&proc_id) {
                procedures.push(proc_id);
            }
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
                temperature_c,
            });
        }
        if points.is_empty() && skipped_by_temperature > 0 {
            let (t, tol) = temperature.unwrap_or_default();
            return Ok(Err(format!(
                "serial '{serial}': no calibration with {coefficient} within {tol} degC of {t} degC ({skipped_by_temperature} at other or unknown temperatures)"
            )));
        }
        if points.is_empty() {
            return Ok(Err(format!(
                "serial '{serial}': no calibration has a coefficient '{coefficient}' (recorded: {})",
                names.join(", ")
            )));
        }
        if procedures.len() > 1 {
            return Err(Error::Input(format!(
                "coefficient {coefficient} of serial '{serial}' comes from {} records: one procedure's {coefficient} is not another's; give the procedure (--procedure {})",
                procedures.join(" and "),
                procedures[0]
            )));
        }
        let mut a = history::analyse(&points);
        let temps: Vec<f64> = points.iter().filter_map(|p| p.temperature_c).collect();
        let (lo, hi) = temps
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(*t), b.max(*t))
            });
        if temperature.is_none() && hi - lo > TEMPERATURE_SPREAD_C {
            a.notes.push(format!(
                "the calibrations were made from {lo} to {hi} degC: a coefficient that moves with temperature shows that as drift; give --at-temperature-c to keep one temperature, or fit the thermal model (incal thermal fit)"
            ));
        }
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
        let sha = sha256_hex(document.as_bytes());
        let row = self
            .conn
            .borrow_mut()
            .query_opt(
                "SELECT r.id, r.record_hash FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 WHERE i.serial = ?1 AND r.document_sha256 = ?2
                 ORDER BY r.id LIMIT 1",
                &[P::T(Some(serial)), P::T(Some(&sha))],
            )
            .map_err(self.db())?;
        row.map(|r| Ok((r.i(0)?, r.t(1)?)))
            .transpose()
            .map_err(self.db())
    }

    /// Every record in chain order, from one consistent snapshot, a page
    /// at a time (memory stays bounded however long the chain). A column
    /// that does not read as incal stores it is [`Error::Tampered`].
    fn scan(&self, mut visit: impl FnMut(Scanned) -> Result<()>) -> Result<()> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let mut after = i64::MIN;
        loop {
            let rows = tx
                .query(
                    "SELECT r.id, i.serial, r.procedure, r.created_utc, r.operator, r.station,
                            r.document, r.document_sha256, r.prev_hash, r.record_hash, i.model
                     FROM records r
                     LEFT JOIN instruments i ON i.id = r.instrument_id
                     WHERE r.id > ?1
                     ORDER BY r.id LIMIT ?2",
                    &[P::I(after), P::I(PAGE)],
                )
                .map_err(self.db())?;
            let Some(last) = rows.last() else { break };
            let first_id = rows[0].i(0).unwrap_or(after);
            let last_id = last.i(0).unwrap_or(i64::MAX);
            let mut inputs = inputs_between(&mut tx, first_id, last_id).map_err(self.db())?;
            let mut sups = supersessions_between(&mut tx, first_id, last_id).map_err(self.db())?;
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
                let s = read().map_err(|e| Error::Tampered {
                    id: r.i(0).unwrap_or(after.max(0) + 1),
                    problem: format!("a column does not read as stored by incal ({e})"),
                })?;
                after = s.id;
                visit(s)?;
            }
            if last_id == i64::MAX || (rows.len() as i64) < PAGE {
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
        let mut count = 0i64;
        self.scan(|r| {
            let id = r.id;
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
            if r.prev_hash != prev_hash {
                return Err(bad(format!(
                    "prev_hash does not match the hash of record {prev_id}"
                )));
            }
            if sha256_hex(&r.document) != r.document_sha256 {
                return Err(bad("the stored document does not match its SHA-256".into()));
            }
            let serial = r
                .serial
                .clone()
                .ok_or_else(|| bad("its instrument row is missing".into()))?;
            if seen_serials.insert(serial.clone()) {
                let doc_model = serde_json::from_slice::<serde_json::Value>(&r.document)
                    .ok()
                    .and_then(|v| v["instrument"]["model"].as_str().map(String::from));
                if doc_model != r.model {
                    return Err(bad(format!(
                        "the instrument's model ({}) is not the one in its first record's document ({})",
                        r.model.as_deref().unwrap_or("none"),
                        doc_model.as_deref().unwrap_or("none")
                    )));
                }
            }
            if let Some(s) = &r.supersedes {
                if s.created_utc != r.created_utc {
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
            if r.fields(&serial).record_hash() != r.record_hash {
                return Err(bad(
                    "record_hash does not match its fields (serial, procedure, time, operator, station, inputs or supersession changed)"
                        .into(),
                ));
            }
            if anchor == Some(r.record_hash.as_str()) {
                held = true;
            }
            prev_id = id;
            prev_hash = r.record_hash;
            count += 1;
            Ok(())
        })?;
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

    /// Write every record, in chain order, to `out` as one JSON object
    /// per line ([`ExportedRecord`]), after checking the chain (a broken
    /// chain is not exported). The chain exported.
    pub fn export(&self, out: &mut dyn std::io::Write) -> Result<Verified> {
        let chain = self.check_chain()?;
        let io = |e: std::io::Error| Error::Output(e.to_string());
        let mut n = 0i64;
        let mut head = GENESIS.to_string();
        self.scan(|r| {
            // Only the records verified above: a record appended since
            // belongs to the next export.
            if r.id > chain.records {
                return Ok(());
            }
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
        Ok(Verified { records: n, head })
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
            let r: ExportedRecord = serde_json::from_str(buf.trim())
                .map_err(|err| at(format!("not an exported record ({err})")))?;
            if r.id <= head_id {
                let have = tx
                    .query_opt(
                        "SELECT record_hash FROM records WHERE id = ?1",
                        &[P::I(r.id)],
                    )
                    .map_err(e)?
                    .map(|row| row.t(0))
                    .transpose()
                    .map_err(e)?;
                if have.as_deref() != Some(r.record_hash.as_str()) {
                    return Err(at(format!(
                        "record {} differs from the store's record {}: the store holds another chain",
                        r.id, r.id
                    )));
                }
                present += 1;
                continue;
            }
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
            let fields = r.fields();
            if fields.record_hash() != r.record_hash {
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
            let instrument_id = match instrument_of(&mut tx, &r.serial).map_err(e)? {
                Some(id) => id,
                None => new_instrument(&mut tx, &r.serial, doc.instrument.model.as_deref())
                    .map_err(e)?,
            };
            write_record(&mut tx, instrument_id, &fields, &r.document, &r.record_hash)
                .map_err(e)?;
            head_id = r.id;
            head_hash = r.record_hash;
            added += 1;
        }
        tx.commit().map_err(e)?;
        // The chain was verified before and each record appended was
        // checked as verify checks it: its head is the last one written.
        Ok(Imported {
            added,
            present,
            chain: Verified {
                records: head_id,
                head: head_hash,
            },
        })
    }
}

fn db_err(path: &str, e: DbError) -> Error {
    if e.not_a_database() {
        Error::Store {
            path: path.to_string(),
            message: format!("not an incal records store ({e})"),
        }
    } else {
        Error::Database {
            path: path.to_string(),
            source: Box::new(e),
        }
    }
}

/// The id of instrument `serial`, if it has one.
fn instrument_of(tx: &mut Conn, serial: &str) -> std::result::Result<Option<i64>, DbError> {
    tx.query_opt(
        "SELECT id FROM instruments WHERE serial = ?1",
        &[P::T(Some(serial))],
    )?
    .map(|r| r.i(0))
    .transpose()
}

/// A new instrument row (inside a write transaction).
fn new_instrument(
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

/// The last record's id and hash (0 and [`GENESIS`] for an empty store).
fn chain_head(tx: &mut Conn) -> std::result::Result<(i64, String), DbError> {
    match tx.query_opt(
        "SELECT id, record_hash FROM records ORDER BY id DESC LIMIT 1",
        &[],
    )? {
        Some(r) => Ok((r.i(0)?, r.t(1)?)),
        None => Ok((0, GENESIS.to_string())),
    }
}

/// The rows of one record: the record, its input files, its supersession.
fn write_record(
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

/// The input files of records `lo..=hi`, by record, in order.
fn inputs_between(
    tx: &mut Conn,
    lo: i64,
    hi: i64,
) -> std::result::Result<HashMap<i64, Vec<InputHash>>, DbError> {
    let rows = tx.query(
        "SELECT record_id, role, path, sha256 FROM record_inputs
         WHERE record_id >= ?1 AND record_id <= ?2 ORDER BY record_id, position",
        &[P::I(lo), P::I(hi)],
    )?;
    let mut out: HashMap<i64, Vec<InputHash>> = HashMap::new();
    for r in rows {
        out.entry(r.i(0)?).or_default().push(InputHash {
            role: r.t(1)?,
            path: r.t(2)?,
            sha256: r.t(3)?,
        });
    }
    Ok(out)
}

/// The supersessions made by records `lo..=hi`, by the correcting record.
fn supersessions_between(
    tx: &mut Conn,
    lo: i64,
    hi: i64,
) -> std::result::Result<HashMap<i64, Supersession>, DbError> {
    let rows = tx.query(
        "SELECT old_id, new_id, reason, created_utc FROM supersessions
         WHERE new_id >= ?1 AND new_id <= ?2",
        &[P::I(lo), P::I(hi)],
    )?;
    let mut out = HashMap::new();
    for r in rows {
        let s = Supersession {
            old_id: r.i(0)?,
            new_id: r.i(1)?,
            reason: r.t(2)?,
            created_utc: r.t(3)?,
        };
        out.insert(s.new_id, s);
    }
    Ok(out)
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
