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
//! The crate is split along what a store does: `open` (opening and
//! migrating a store, [`Store`] itself), `write` (add, supersede),
//! `query` (list, show, find, history), `verify` (the hash chain) and
//! `exchange` (export, import); `types` holds the records they take and
//! give, `error` what can go wrong.
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
mod error;
pub mod events;
mod exchange;
pub mod history;
mod identity;
mod open;
mod query;
mod readonly;
pub mod time;
mod types;
mod verify;
mod workflow;
mod write;

pub use chain::{sha256_hex, ChainFields, InputHash, GENESIS};
pub use db::{display_url, is_postgres_url, store_message, store_name};
pub use error::{Error, Result};
pub use events::{Actor, Event, EventKind, Role};
pub use exchange::{remove_sqlite_files, ExportedRecord, ExportedSupersession, Imported};
pub use history::{Drift, HistoryPoint, Repeatability};
pub use identity::{check_identity, IdentityError};
pub use open::{Store, BUSY_TIMEOUT, MIGRATIONS, SCHEMA_MIGRATIONS};
pub use query::TEMPERATURE_SPREAD_C;
pub use types::{
    Added, History, NewRecord, RecordSummary, StoredRecord, Supersession, Verified,
    MAX_DOCUMENT_BYTES,
};
pub use workflow::{check_username, Account, Review, State, MAX_USERNAME};
