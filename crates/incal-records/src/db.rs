//! The two database servers a store can live on, behind one small
//! interface: SQLite (a file, rusqlite) and PostgreSQL (a server, the
//! `postgres` crate).
//!
//! The store's SQL is written once, with SQLite's numbered parameters
//! (`?1`, `?2`, …); on PostgreSQL they are sent as `$1`, `$2`, …. Values
//! come back as [`Value`], so the store reads rows the same way from both.
//! Transactions:
//!
//! * a **write** is `BEGIN IMMEDIATE` on SQLite (the file's write lock) and
//!   `BEGIN` + `LOCK TABLE records IN SHARE ROW EXCLUSIVE MODE` on
//!   PostgreSQL: writers queue on the chain, readers are not blocked;
//! * a **read** is one snapshot: a deferred transaction in WAL mode on
//!   SQLite, `REPEATABLE READ READ ONLY` on PostgreSQL;
//! * the **migrations** run under `pg_advisory_xact_lock` on PostgreSQL, so
//!   stations that open a new store at the same moment create it once.

use std::borrow::Cow;
use std::time::Duration;

/// A parameter: the store binds only integers and (nullable) text.
#[derive(Debug, Clone, Copy)]
pub(crate) enum P<'a> {
    /// A BIGINT.
    I(i64),
    /// A BIGINT, or NULL.
    OI(Option<i64>),
    /// A TEXT, or NULL.
    T(Option<&'a str>),
}

impl rusqlite::ToSql for P<'_> {
    fn to_sql(&self) -> rusqlite::Result<rusqlite::types::ToSqlOutput<'_>> {
        match self {
            P::I(v) => v.to_sql(),
            P::OI(v) => v.to_sql(),
            P::T(v) => v.to_sql(),
        }
    }
}

/// One value read back.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Null,
    I(i64),
    F(f64),
    T(String),
    /// A blob, or SQLite text that is not UTF-8 (only a hand edit makes one).
    B(Vec<u8>),
}

/// A failure of the database layer.
#[derive(Debug, thiserror::Error)]
pub(crate) enum DbError {
    #[error("{0}")]
    Sqlite(#[from] rusqlite::Error),
    #[error("{}", pg_message(.0))]
    Pg(#[from] postgres::Error),
    /// A column holds a value of a type incal never writes there.
    #[error("column {column} holds {found}, not {wanted}")]
    Type {
        column: usize,
        found: &'static str,
        wanted: &'static str,
    },
}

/// PostgreSQL's own message (the `postgres` crate's Display says only
/// "db error").
fn pg_message(e: &postgres::Error) -> String {
    match e.as_db_error() {
        Some(d) => format!("{}: {}", d.severity(), d.message()),
        None => {
            let mut s = e.to_string();
            let mut src = std::error::Error::source(e);
            while let Some(inner) = src {
                s = format!("{s}: {inner}");
                src = inner.source();
            }
            s
        }
    }
}

impl DbError {
    /// SQLite's "file is not a database" and similar corruption.
    pub(crate) fn not_a_database(&self) -> bool {
        matches!(self, DbError::Sqlite(e) if matches!(
            e.sqlite_error_code(),
            Some(rusqlite::ErrorCode::NotADatabase | rusqlite::ErrorCode::DatabaseCorrupt)
        ))
    }
}

/// A row of values.
#[derive(Debug, Clone)]
pub(crate) struct Row(pub(crate) Vec<Value>);

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "NULL",
        Value::I(_) => "an integer",
        Value::F(_) => "a real",
        Value::T(_) => "text",
        Value::B(_) => "a blob",
    }
}

impl Row {
    fn at(&self, k: usize) -> &Value {
        self.0.get(k).unwrap_or(&Value::Null)
    }
    fn wrong(&self, k: usize, wanted: &'static str) -> DbError {
        DbError::Type {
            column: k,
            found: kind(self.at(k)),
            wanted,
        }
    }
    /// An integer column.
    pub(crate) fn i(&self, k: usize) -> Result<i64, DbError> {
        match self.at(k) {
            Value::I(v) => Ok(*v),
            _ => Err(self.wrong(k, "an integer")),
        }
    }
    /// A nullable integer column.
    pub(crate) fn oi(&self, k: usize) -> Result<Option<i64>, DbError> {
        match self.at(k) {
            Value::Null => Ok(None),
            Value::I(v) => Ok(Some(*v)),
            _ => Err(self.wrong(k, "an integer")),
        }
    }
    /// A text column.
    pub(crate) fn t(&self, k: usize) -> Result<String, DbError> {
        match self.at(k) {
            Value::T(v) => Ok(v.clone()),
            _ => Err(self.wrong(k, "text")),
        }
    }
    /// A nullable text column.
    pub(crate) fn ot(&self, k: usize) -> Result<Option<String>, DbError> {
        match self.at(k) {
            Value::Null => Ok(None),
            Value::T(v) => Ok(Some(v.clone())),
            _ => Err(self.wrong(k, "text")),
        }
    }
    /// A column's bytes, whatever it holds (text or blob; nothing else).
    pub(crate) fn bytes(&self, k: usize) -> Vec<u8> {
        match self.at(k) {
            Value::T(v) => v.as_bytes().to_vec(),
            Value::B(v) => v.clone(),
            _ => Vec::new(),
        }
    }
}

/// A connection to one of the two servers.
pub(crate) enum Conn {
    Sqlite(rusqlite::Connection),
    Postgres(Box<Pg>),
}

/// A PostgreSQL connection with its prepared statements, kept by SQL text
/// (as rusqlite's `prepare_cached`): a statement is parsed and planned
/// once per connection, not on every call.
pub(crate) struct Pg {
    pub(crate) client: postgres::Client,
    statements: std::collections::HashMap<String, postgres::Statement>,
}

/// Most statements kept per connection (the store's SQL is a few dozen
/// texts; beyond this, the cache starts afresh).
const MAX_STATEMENTS: usize = 256;

impl Pg {
    pub(crate) fn new(client: postgres::Client) -> Pg {
        Pg {
            client,
            statements: std::collections::HashMap::new(),
        }
    }

    /// The prepared statement of `sql` (SQLite parameters rewritten).
    fn prepared(&mut self, sql: &str) -> Result<postgres::Statement, DbError> {
        if let Some(st) = self.statements.get(sql) {
            return Ok(st.clone());
        }
        let st = self.client.prepare(pg_sql(sql).as_ref())?;
        if self.statements.len() >= MAX_STATEMENTS {
            self.statements.clear();
        }
        self.statements.insert(sql.to_string(), st.clone());
        Ok(st)
    }
}

impl std::fmt::Debug for Conn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Conn::Sqlite(_) => "Conn::Sqlite",
            Conn::Postgres(_) => "Conn::Postgres",
        })
    }
}

/// `?N` → `$N` (the store's SQL holds no `?` anywhere else).
fn pg_sql(sql: &str) -> Cow<'_, str> {
    if sql.contains('?') {
        Cow::Owned(sql.replace('?', "$"))
    } else {
        Cow::Borrowed(sql)
    }
}

fn pg_params<'a>(params: &'a [P<'a>]) -> Vec<&'a (dyn postgres::types::ToSql + Sync)> {
    params
        .iter()
        .map(|p| match p {
            P::I(v) => v as &(dyn postgres::types::ToSql + Sync),
            P::OI(v) => v as &(dyn postgres::types::ToSql + Sync),
            P::T(v) => v as &(dyn postgres::types::ToSql + Sync),
        })
        .collect()
}

fn pg_row(r: &postgres::Row) -> Result<Row, DbError> {
    use postgres::types::Type;
    let mut out = Vec::with_capacity(r.len());
    for (k, c) in r.columns().iter().enumerate() {
        let t = c.type_();
        let v = if *t == Type::INT8 {
            r.try_get::<_, Option<i64>>(k)?.map(Value::I)
        } else if *t == Type::INT4 {
            r.try_get::<_, Option<i32>>(k)?.map(|v| Value::I(v.into()))
        } else if *t == Type::INT2 {
            r.try_get::<_, Option<i16>>(k)?.map(|v| Value::I(v.into()))
        } else if *t == Type::BOOL {
            r.try_get::<_, Option<bool>>(k)?.map(|v| Value::I(v.into()))
        } else if *t == Type::FLOAT8 {
            r.try_get::<_, Option<f64>>(k)?.map(Value::F)
        } else if *t == Type::BYTEA {
            r.try_get::<_, Option<Vec<u8>>>(k)?.map(Value::B)
        } else {
            // TEXT, VARCHAR, NAME and anything else that reads as text.
            r.try_get::<_, Option<String>>(k)?.map(Value::T)
        };
        out.push(v.unwrap_or(Value::Null));
    }
    Ok(Row(out))
}

fn sqlite_row(r: &rusqlite::Row, n: usize) -> rusqlite::Result<Row> {
    use rusqlite::types::ValueRef;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        out.push(match r.get_ref(k)? {
            ValueRef::Null => Value::Null,
            ValueRef::Integer(v) => Value::I(v),
            ValueRef::Real(v) => Value::F(v),
            ValueRef::Text(b) => match std::str::from_utf8(b) {
                Ok(s) => Value::T(s.to_string()),
                Err(_) => Value::B(b.to_vec()),
            },
            ValueRef::Blob(b) => Value::B(b.to_vec()),
        });
    }
    Ok(Row(out))
}

/// How long a writer waits for another's lock on PostgreSQL (as SQLite's
/// busy timeout).
pub(crate) fn lock_timeout_sql(t: Duration) -> String {
    format!("SET LOCAL lock_timeout = '{}ms'", t.as_millis())
}

impl Conn {
    /// Every row of `sql`.
    pub(crate) fn query(&mut self, sql: &str, params: &[P]) -> Result<Vec<Row>, DbError> {
        match self {
            Conn::Sqlite(c) => {
                let mut st = c.prepare_cached(sql)?;
                let n = st.column_count();
                let rows = st.query_map(rusqlite::params_from_iter(params.iter()), |r| {
                    sqlite_row(r, n)
                })?;
                Ok(rows.collect::<rusqlite::Result<Vec<_>>>()?)
            }
            Conn::Postgres(c) => {
                let st = c.prepared(sql)?;
                c.client
                    .query(&st, &pg_params(params))?
                    .iter()
                    .map(pg_row)
                    .collect()
            }
        }
    }

    /// The first row of `sql`, if any.
    pub(crate) fn query_opt(&mut self, sql: &str, params: &[P]) -> Result<Option<Row>, DbError> {
        Ok(self.query(sql, params)?.into_iter().next())
    }

    /// The first row of `sql`, which must exist.
    pub(crate) fn query_one(&mut self, sql: &str, params: &[P]) -> Result<Row, DbError> {
        self.query_opt(sql, params)?
            .ok_or(DbError::Sqlite(rusqlite::Error::QueryReturnedNoRows))
    }

    /// Run one statement with parameters; the number of rows changed.
    pub(crate) fn execute(&mut self, sql: &str, params: &[P]) -> Result<u64, DbError> {
        match self {
            Conn::Sqlite(c) => {
                let mut st = c.prepare_cached(sql)?;
                Ok(st.execute(rusqlite::params_from_iter(params.iter()))? as u64)
            }
            Conn::Postgres(c) => {
                let st = c.prepared(sql)?;
                Ok(c.client.execute(&st, &pg_params(params))?)
            }
        }
    }

    /// Run statements without parameters (migrations, transaction control).
    pub(crate) fn batch(&mut self, sql: &str) -> Result<(), DbError> {
        match self {
            Conn::Sqlite(c) => Ok(c.execute_batch(sql)?),
            Conn::Postgres(c) => Ok(c.client.batch_execute(sql)?),
        }
    }

    /// True when a table of this name exists (in the current schema on
    /// PostgreSQL).
    pub(crate) fn table_exists(&mut self, name: &str) -> Result<bool, DbError> {
        let sql = match self {
            Conn::Sqlite(_) => {
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name = ?1"
            }
            Conn::Postgres(_) => {
                "SELECT COUNT(*) FROM information_schema.tables
                 WHERE table_schema = current_schema() AND table_name = ?1"
            }
        };
        Ok(self.query_one(sql, &[P::T(Some(name))])?.i(0)? > 0)
    }

    /// True when any table of anyone exists (in the current schema).
    pub(crate) fn has_tables(&mut self) -> Result<bool, DbError> {
        let sql = match self {
            Conn::Sqlite(_) => {
                "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table' AND name NOT LIKE 'sqlite_%'"
            }
            Conn::Postgres(_) => {
                "SELECT COUNT(*) FROM information_schema.tables WHERE table_schema = current_schema()"
            }
        };
        Ok(self.query_one(sql, &[])?.i(0)? > 0)
    }

    fn begin(&mut self, mode: Mode) -> Result<(), DbError> {
        let timeout = lock_timeout_sql(crate::BUSY_TIMEOUT);
        match (&*self, mode) {
            (Conn::Sqlite(_), Mode::Read) => self.batch("BEGIN DEFERRED"),
            (Conn::Sqlite(_), Mode::Write | Mode::Migrate) => self.batch("BEGIN IMMEDIATE"),
            (Conn::Postgres(_), Mode::Read) => {
                self.batch("BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY")
            }
            (Conn::Postgres(_), Mode::Write) => self.batch(&format!(
                "BEGIN; {timeout}; LOCK TABLE records IN SHARE ROW EXCLUSIVE MODE"
            )),
            (Conn::Postgres(_), Mode::Migrate) => self.batch(&format!(
                "BEGIN; {timeout}; SELECT pg_advisory_xact_lock({MIGRATION_LOCK})"
            )),
        }
    }

    /// Begin a transaction; it rolls back unless committed.
    pub(crate) fn transaction(&mut self, mode: Mode) -> Result<Tx<'_>, DbError> {
        self.begin(mode)?;
        Ok(Tx {
            conn: self,
            open: true,
        })
    }

    /// True for PostgreSQL.
    pub(crate) fn is_postgres(&self) -> bool {
        matches!(self, Conn::Postgres(_))
    }
}

/// The key of the advisory lock the migrations take on PostgreSQL
/// ("incal" in ASCII).
const MIGRATION_LOCK: i64 = 0x0069_6e63_616c;

/// What a transaction is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    /// One consistent snapshot, nothing written.
    Read,
    /// Appending to the chain: writers queue.
    Write,
    /// Creating or upgrading the schema.
    Migrate,
}

/// An open transaction: rolled back when dropped uncommitted.
pub(crate) struct Tx<'c> {
    conn: &'c mut Conn,
    open: bool,
}

impl Tx<'_> {
    /// Commit.
    pub(crate) fn commit(mut self) -> Result<(), DbError> {
        self.open = false;
        self.conn.batch("COMMIT")
    }
}

impl std::ops::Deref for Tx<'_> {
    type Target = Conn;
    fn deref(&self) -> &Conn {
        self.conn
    }
}

impl std::ops::DerefMut for Tx<'_> {
    fn deref_mut(&mut self) -> &mut Conn {
        self.conn
    }
}

impl Drop for Tx<'_> {
    fn drop(&mut self) {
        if self.open {
            let _ = self.conn.batch("ROLLBACK");
        }
    }
}

/// True when `location` names a PostgreSQL database
/// (`postgresql://…` or `postgres://…`).
pub fn is_postgres_url(location: &str) -> bool {
    location.starts_with("postgresql://") || location.starts_with("postgres://")
}

/// A records store as named in messages: its path, or its PostgreSQL URL
/// without the password ([`display_url`]).
pub fn store_name(location: &std::path::Path) -> String {
    match location.to_str() {
        Some(u) if is_postgres_url(u) => display_url(u),
        _ => location.display().to_string(),
    }
}

/// The one line of an error of the store named `name`
/// ([`store_name`]): `NAME: …`, the name said once.
pub fn store_message(name: &str, e: &crate::Error) -> String {
    let msg = e.to_string();
    if msg.starts_with(&format!("{name}: ")) {
        msg
    } else {
        format!("{name}: {msg}")
    }
}

/// A PostgreSQL URL as shown in messages: user, host, port and database,
/// never the password.
pub fn display_url(url: &str) -> String {
    let Ok(c) = url.parse::<postgres::Config>() else {
        // Unparsable: show only the scheme and what follows the last '@'.
        return match url.rsplit_once('@') {
            Some((_, rest)) => format!("postgresql://…@{rest}"),
            None => url.to_string(),
        };
    };
    let host = c
        .get_hosts()
        .first()
        .map(|h| match h {
            postgres::config::Host::Tcp(s) => s.clone(),
            postgres::config::Host::Unix(p) => p.display().to_string(),
        })
        .unwrap_or_default();
    let port = c
        .get_ports()
        .first()
        .map(|p| format!(":{p}"))
        .unwrap_or_default();
    let user = c.get_user().map(|u| format!("{u}@")).unwrap_or_default();
    let db = c.get_dbname().unwrap_or_default();
    format!("postgresql://{user}{host}{port}/{db}")
}

/// Connect to a PostgreSQL URL (no TLS; 10 s to connect unless the URL
/// says otherwise).
pub(crate) fn connect_postgres(url: &str) -> Result<postgres::Client, String> {
    let mut c: postgres::Config = url
        .parse()
        .map_err(|e: postgres::Error| format!("not a PostgreSQL URL ({})", pg_message(&e)))?;
    if c.get_connect_timeout().is_none() {
        c.connect_timeout(Duration::from_secs(10));
    }
    if c.get_application_name().is_none() {
        c.application_name("incal");
    }
    c.connect(postgres::NoTls)
        .map_err(|e| format!("cannot connect ({})", pg_message(&e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_shown_without_their_password() {
        assert_eq!(
            display_url("postgresql://lab:s3cret@db.example:5433/records"),
            "postgresql://lab@db.example:5433/records"
        );
        assert!(!display_url("postgresql://lab:s3cret@[bad").contains("s3cret"));
        assert!(is_postgres_url("postgres://x/y"));
        assert!(!is_postgres_url("incal.db"));
        assert_eq!(pg_sql("a = ?1 AND b = ?2"), "a = $1 AND b = $2");
    }
}
