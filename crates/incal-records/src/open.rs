//! Opening a store: an SQLite file or a PostgreSQL database, created when
//! missing or refused when it must exist, checked to be an incal store
//! and brought up to date by the schema migrations.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Duration;

use rusqlite::{Connection, ErrorCode, OpenFlags};

use crate::db::{self, Conn, DbError, Mode, P};
use crate::error::db_err;
use crate::{display_url, is_postgres_url, time, Error, Result};

/// The schema migrations, in order: `(version, name, SQL)`.
pub const MIGRATIONS: &[(i64, &str, &str)] = &[
    (1, "0001_init", include_str!("../migrations/0001_init.sql")),
    (
        2,
        "0002_workflow",
        include_str!("../migrations/0002_workflow.sql"),
    ),
];

/// The table that tracks the migrations applied (created when missing).
pub const SCHEMA_MIGRATIONS: &str = include_str!("../migrations/schema_migrations.sql");

/// How long a writer waits for another writer's lock before failing.
pub const BUSY_TIMEOUT: Duration = Duration::from_secs(60);

/// A records store: one SQLite file, or one PostgreSQL database
/// (`postgresql://…`), with the same schema, chain and behaviour.
#[derive(Debug)]
pub struct Store {
    /// The connection.
    pub(crate) conn: RefCell<Conn>,
    /// The SQLite path, or the PostgreSQL URL without its password.
    pub(crate) path: PathBuf,
    /// The private copy a read-only store is read from, if one was needed
    /// ([`crate::readonly`]); removed when the store is closed.
    pub(crate) _copy: Option<crate::readonly::TempCopy>,
    /// SQLite: the file's `data_version` when this connection last found
    /// the whole chain intact (or last wrote to it). Only a commit by
    /// another connection (another process, a hand edit) changes it, so a
    /// write that finds it unchanged needs no second whole-chain check.
    pub(crate) checked: std::cell::Cell<Option<i64>>,
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
        let cannot_open = |e: rusqlite::Error| Error::Store {
            path: name.clone(),
            message: format!("cannot open: {e}"),
        };
        let (conn, copy) = if create {
            let flags = OpenFlags::SQLITE_OPEN_READ_WRITE
                | OpenFlags::SQLITE_OPEN_CREATE
                | OpenFlags::SQLITE_OPEN_NO_MUTEX;
            (
                Connection::open_with_flags(path, flags).map_err(cannot_open)?,
                None,
            )
        } else {
            // Nothing is written beside a store opened to read (an
            // auditor's read-only copy).
            crate::readonly::open(path).map_err(cannot_open)?
        };
        conn.busy_timeout(BUSY_TIMEOUT)
            .map_err(|e| db_err(&name, e.into()))?;
        let store = Store {
            conn: RefCell::new(Conn::Sqlite(conn)),
            path: path.to_path_buf(),
            _copy: copy,
            checked: std::cell::Cell::new(None),
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
            conn: RefCell::new(Conn::Postgres(Box::new(db::Pg::new(client)))),
            path: PathBuf::from(&name),
            _copy: None,
            checked: std::cell::Cell::new(None),
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

    /// A database error on this store as the crate's ([`db_err`]).
    pub(crate) fn db(&self) -> impl Fn(DbError) -> Error + '_ {
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
}
