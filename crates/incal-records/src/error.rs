//! What can go wrong: the crate's error and result types, and how a
//! database error reads (an unusable store, or any other failure).

use crate::db::DbError;

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
    /// chain ([`Store::verify`](crate::Store::verify); exit 1).
    #[error("record {id}: {problem}")]
    Tampered {
        /// The first record that does not match.
        id: i64,
        /// What does not match.
        problem: String,
    },
    /// The chain no longer holds a head kept elsewhere: records were
    /// removed or the chain rebuilt since
    /// ([`Store::verify_head`](crate::Store::verify_head); exit 1).
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

/// A database error on the store at `path`: a file that is not a database
/// is an unusable store ([`Error::Store`]), anything else
/// [`Error::Database`].
pub(crate) fn db_err(path: &str, e: DbError) -> Error {
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
