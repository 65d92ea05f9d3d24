//! Reading a store that cannot be written: an auditor's copy in a
//! read-only directory, a backup on read-only media, a file owned by
//! another user. SQLite in WAL mode needs its `-shm` file beside the store
//! even to read, and creating it there fails ("attempt to write a readonly
//! database"). A read is then opened so that nothing is written where the
//! store lies:
//!
//! * with the whole chain in the store file (no `-wal` beside it, or an
//!   empty one: the last writer checkpointed on close), as an immutable
//!   database (`immutable=1`: no lock, no `-shm`);
//! * with records still in the `-wal` file, from a private copy of the
//!   store and its `-wal` in the temporary directory, removed when the
//!   store is closed, so those records are read too.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use rusqlite::{Connection, ErrorCode, OpenFlags};

/// A private copy of a read-only store, removed on drop.
#[derive(Debug)]
pub(crate) struct TempCopy(PathBuf);

impl Drop for TempCopy {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `path` (made absolute) as an SQLite URI with `query`: every byte but
/// letters, digits and `/-_.~` percent-encoded.
fn uri(path: &Path, query: &str) -> String {
    let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let mut out = String::from("file:");
    for b in abs.as_os_str().as_encoded_bytes() {
        if b.is_ascii_alphanumeric() || b"/-_.~".contains(b) {
            out.push(*b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    format!("{out}?{query}")
}

/// True when a read failed because SQLite could not write its shared
/// memory or lock files beside the store.
fn cannot_write_beside(e: &rusqlite::Error) -> bool {
    matches!(
        e.sqlite_error_code(),
        Some(ErrorCode::ReadOnly | ErrorCode::CannotOpen | ErrorCode::PermissionDenied)
    )
}

/// Ask the connection for the schema: the first read, where WAL's `-shm`
/// is needed.
fn probe(conn: &Connection) -> rusqlite::Result<i64> {
    conn.query_row("SELECT count(*) FROM sqlite_master", [], |r| r.get(0))
}

/// Open `path` read-only without writing beside it (module docs): the
/// connection, and the private copy it reads when one was needed.
pub(crate) fn open(path: &Path) -> rusqlite::Result<(Connection, Option<TempCopy>)> {
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let conn = Connection::open_with_flags(path, flags)?;
    let first = match probe(&conn) {
        Ok(_) => return Ok((conn, None)),
        Err(e) if cannot_write_beside(&e) => e,
        // Not a database, or another problem: the caller names it.
        Err(_) => return Ok((conn, None)),
    };
    drop(conn);
    let wal = PathBuf::from(format!("{}-wal", path.display()));
    let pending = wal.metadata().is_ok_and(|m| m.len() > 0);
    if !pending {
        let conn = Connection::open_with_flags(
            uri(path, "immutable=1"),
            flags | OpenFlags::SQLITE_OPEN_URI,
        )?;
        return match probe(&conn) {
            Ok(_) => Ok((conn, None)),
            Err(_) => Err(first),
        };
    }
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "incal-readonly-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let copy = TempCopy(dir.clone());
    let copied = (|| {
        std::fs::create_dir_all(&dir)?;
        let db = dir.join("store.db");
        std::fs::copy(path, &db)?;
        std::fs::copy(&wal, dir.join("store.db-wal"))?;
        Ok::<_, std::io::Error>(db)
    })();
    let Ok(db) = copied else { return Err(first) };
    let conn = Connection::open_with_flags(&db, flags)?;
    probe(&conn)?;
    Ok((conn, Some(copy)))
}
