//! What a records store says about one result document, for its report
//! and certificate: the record that holds it (its stamp and the chain it
//! belongs to), the history of every limited coefficient of the
//! instrument, and the certificate's number, dates and replacement notice.
//! Every front end (the CLI's `incal report --db`, Python's
//! `Result.report(db=…)`) takes it from here.

use incal::document::ResultDocument;
use incal_records::{Store, StoredRecord};

use crate::certificate::{Certificate, LabProfile};
use crate::{DriftLine, HistoryPoint, HistorySeries, RecordStamp};

/// Why the store could not say: bad input (exit 2: a history that cannot
/// be read for this document) or a failure (exit 1: the store itself).
#[derive(Debug, thiserror::Error)]
pub enum StoredError {
    /// Bad input, the message naming the store.
    #[error("{0}")]
    Input(String),
    /// The store failed, the message naming it.
    #[error("{0}")]
    Failure(String),
}

/// A document's place in a store ([`of_document`]).
#[derive(Debug, Clone)]
pub struct Stored {
    /// The record stamp printed on the report.
    pub stamp: RecordStamp,
    /// The history plots of the limited coefficients (two or more
    /// calibrations each).
    pub history: Vec<HistorySeries>,
    /// The record holding this very document (same serial and text), if
    /// the store has it.
    pub record: Option<StoredRecord>,
}

/// The store's view of `doc` (whose JSON text is `text`): the chain
/// checked whole, the record holding `text`, the history of every
/// coefficient `doc` has a verdict for. A document without a serial has
/// no place in a store (`None`).
pub fn of_document(
    store: &Store,
    doc: &ResultDocument,
    text: &str,
) -> Result<Option<Stored>, StoredError> {
    let Some(serial) = doc.instrument.serial.as_deref() else {
        return Ok(None);
    };
    let path = store.path().display().to_string();
    let failed = |e: incal_records::Error| StoredError::Failure(format!("{path}: {e}"));
    let chain = store.check_chain().map_err(failed)?;
    let id = store
        .find(serial, text)
        .map_err(|e| StoredError::Failure(e.to_string()))?
        .map(|(id, _)| id);
    let record = match id {
        Some(id) => Some(
            store
                .show(id)
                .map_err(|e| StoredError::Failure(e.to_string()))?,
        ),
        None => None,
    };
    Ok(Some(Stored {
        stamp: RecordStamp {
            store: path,
            id,
            records: chain.records,
            head: chain.head,
        },
        history: history(store, doc)?,
        record,
    }))
}

/// The history of every limited coefficient of the instrument, from the
/// store, when there are two or more calibrations; the drift band at 95 %
/// (Student t for the drift's degrees of freedom).
fn history(store: &Store, doc: &ResultDocument) -> Result<Vec<HistorySeries>, StoredError> {
    let (Some(serial), Some(verdicts)) = (&doc.instrument.serial, &doc.verdicts) else {
        return Ok(Vec::new());
    };
    let path = store.path().display().to_string();
    let mut out = Vec::new();
    for (name, v) in verdicts {
        // A new instrument, or a coefficient not recorded before, has no
        // history to plot.
        let Ok(h) = store
            .history_if_any(serial, name, Some(doc.procedure.as_str()), None)
            .map_err(|e| StoredError::Input(format!("{path}: {e}")))?
        else {
            continue;
        };
        if h.points.len() < 2 {
            continue;
        }
        out.push(HistorySeries {
            coefficient: name.clone(),
            unit: h.unit.clone(),
            points: h
                .points
                .iter()
                .map(|p| HistoryPoint {
                    id: p.id,
                    created_utc: p.created_utc.clone(),
                    value: p.value,
                    u95: p.u95,
                })
                .collect(),
            min: v.min,
            max: v.max,
            drift: h.drift.as_ref().map(|d| DriftLine {
                intercept: d.intercept,
                rate_per_day: d.value,
                covariance: d.covariance,
                k95: incal::estimation::coverage_factor(d.dof.unwrap_or(f64::INFINITY), 0.95),
            }),
        });
    }
    Ok(out)
}

/// [`of_document`] in `store`, when one is given.
fn held(
    store: Option<&Store>,
    doc: &ResultDocument,
    text: &str,
) -> Result<Option<Stored>, StoredError> {
    match store {
        Some(s) => of_document(s, doc, text),
        None => Ok(None),
    }
}

/// The HTML report of `doc` (its JSON text `text`), as `incal report`
/// writes it for every front end: with what `store` says about it (the
/// record stamp and the history plots), and as a certificate under
/// `profile` when one is given. A report that cannot be rendered is a
/// failure.
pub fn report_html(
    doc: &ResultDocument,
    text: &str,
    store: Option<&Store>,
    profile: Option<LabProfile>,
    issue: &Issue,
) -> Result<String, StoredError> {
    let held = held(store, doc, text)?;
    let record = held.as_ref().and_then(|s| s.record.as_ref());
    let certificate = profile.map(|p| certificate(p, text, record, issue));
    let (history, stamp) = match held {
        Some(s) => (s.history, Some(s.stamp)),
        None => (Vec::new(), None),
    };
    let opts = crate::RenderOptions {
        date: None,
        record: stamp,
        certificate,
    };
    crate::render_html_with(doc, &history, &opts).map_err(|e| StoredError::Failure(e.to_string()))
}

/// The Digital Calibration Certificate XML ([`crate::dcc`]) of the
/// document `text` under `profile`, with the number, dates and customer
/// the HTML certificate of [`report_html`] states, signed by the profile's
/// first signatory, and the record and chain head when `store` holds it.
pub fn dcc_of(
    doc: &ResultDocument,
    text: &str,
    store: Option<&Store>,
    profile: LabProfile,
    issue: &Issue,
) -> Result<String, StoredError> {
    let held = held(store, doc, text)?;
    let record = held.as_ref().and_then(|s| s.record.as_ref());
    let c = certificate(profile, text, record, issue);
    let info = crate::dcc::DccInfo {
        number: c.number.clone(),
        lab_name: c.profile.lab.name.clone(),
        lab_address: c.profile.lab.address.replace('\n', ", "),
        country: c.profile.lab.country.clone().unwrap_or_default(),
        customer: c.customer.clone(),
        calibration_date: c
            .calibration_date
            .clone()
            .unwrap_or_else(|| c.issue_date.clone()),
        issue_date: c.issue_date.clone(),
        signatory: c
            .profile
            .signatory
            .first()
            .map(|s| (s.name.clone(), s.role.clone())),
        record: held.map(|h| match h.stamp.id {
            Some(id) => format!(
                "record {id} of {}; chain head {}",
                h.stamp.store, h.stamp.head
            ),
            None => format!(
                "not stored in {}; chain head {}",
                h.stamp.store, h.stamp.head
            ),
        }),
    };
    Ok(crate::dcc::dcc_xml(doc, &info))
}

/// What the certificate states beside the profile: the customer, the date
/// of calibration (as given, else the day the record was stored) and the
/// environment.
#[derive(Debug, Clone, Default)]
pub struct Issue {
    /// The customer named on the certificate.
    pub customer: Option<String>,
    /// The date of calibration, `YYYY-MM-DD` (checked by the caller with
    /// [`crate::certificate::is_date`]).
    pub date: Option<String>,
    /// The environmental conditions during the calibration.
    pub environment: Option<String>,
}

/// The certificate of the document `text` under `profile`: its number
/// (`prefix` + the record id on six digits when the document is stored,
/// else + the first 12 hex digits of its SHA-256, so the same result always
/// gets the same number), the dates, and what it replaces when its record
/// supersedes another.
pub fn certificate(
    profile: LabProfile,
    text: &str,
    record: Option<&StoredRecord>,
    issue: &Issue,
) -> Certificate {
    let prefix = profile.lab.certificate_prefix.clone().unwrap_or_default();
    let number_of = |id: i64| format!("{prefix}{id:06}");
    let number = match record {
        Some(r) => number_of(r.id),
        None => {
            let hash = incal_io::sha256_hex(text.as_bytes());
            format!("{prefix}{}", hash[..12].to_uppercase())
        }
    };
    let (calibration_date, source) = match (&issue.date, record) {
        (Some(d), _) => (Some(d.clone()), "as given".to_string()),
        (None, Some(r)) => (
            Some(r.created_utc.chars().take(10).collect()),
            format!("the date record {} was stored", r.id),
        ),
        (None, None) => (None, String::new()),
    };
    let today: String = crate::format::now_utc_text().chars().take(10).collect();
    Certificate {
        profile,
        number,
        customer: issue.customer.clone(),
        calibration_date,
        calibration_date_source: source,
        issue_date: today,
        environment: issue.environment.clone(),
        replaces: record
            .and_then(|r| r.supersedes.as_ref())
            .map(|s| (number_of(s.old_id), s.reason.clone())),
        superseded_by: record.and_then(|r| r.superseded_by).map(number_of),
    }
}
