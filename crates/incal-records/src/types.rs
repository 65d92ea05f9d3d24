//! The records a store takes and gives: a new record, what was written,
//! a record's summary and its full content, a supersession, a history and
//! an intact chain.

use incal::units::Unit;
use serde::Serialize;

use crate::{Drift, HistoryPoint, InputHash, Repeatability};

/// The largest result document a record holds (as every document incal
/// reads whole).
pub const MAX_DOCUMENT_BYTES: usize = 64 << 20;

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
    /// The record's time (RFC 3339, [`time`](crate::time)) instead of now:
    /// for entering past calibrations (backfill) and for tests. History
    /// uses this time as the calibration's date.
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

/// One line of [`Store::list`](crate::Store::list).
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

/// One stored record in full ([`Store::show`](crate::Store::show)).
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
/// ([`Store::history`](crate::Store::history); formulas in
/// [`history`](crate::history)).
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

/// An intact store ([`Store::verify`](crate::Store::verify)).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Verified {
    /// Number of records.
    pub records: i64,
    /// Number of events (approvals, rejections, submissions, account
    /// changes) in the same chain.
    pub events: i64,
    /// `record_hash` of the last record ([`GENESIS`](crate::GENESIS) when
    /// empty): write it down to anchor the chain (module docs of
    /// [`chain`](crate::chain)).
    pub head: String,
}
