//! The identity a new record is filed under, checked against the result
//! it stores before the store is opened: a serial, operator or station
//! given beside the document must agree with the document's own, and none
//! may be empty; a creation time must read as UTC. Every front end (the
//! CLI's `record add`, Python's `Records.add`) checks with this.

use incal::document::ResultDocument;

use crate::NewRecord;

/// A new record's identity that cannot be filed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum IdentityError {
    /// An option given beside the document (`key`: `serial`, `operator`,
    /// `station`, `created_utc`); `rest` follows the option's name in a
    /// message (`" 'SN-2' differs from r.json's instrument.serial
    /// 'SN-1'"`, `": empty"`).
    Option {
        /// The option.
        key: &'static str,
        /// The message after the option's name.
        rest: String,
    },
    /// The document itself (`NAME: $.instrument.KEY: …`).
    Document(String),
}

/// Check `req` (with its document `doc`, named `name` in messages).
pub fn check_identity(
    name: &str,
    doc: &ResultDocument,
    req: &NewRecord<'_>,
) -> Result<(), IdentityError> {
    let given = [
        ("serial", doc.instrument.serial.as_deref(), req.serial),
        (
            "operator",
            doc.instrument.meta.get("operator").map(String::as_str),
            req.operator,
        ),
        (
            "station",
            doc.instrument.meta.get("station").map(String::as_str),
            req.station,
        ),
    ];
    for (key, in_doc, opt) in given {
        if let (Some(d), Some(g)) = (in_doc, opt) {
            if d != g {
                return Err(IdentityError::Option {
                    key,
                    rest: format!(" '{g}' differs from {name}'s instrument.{key} '{d}'"),
                });
            }
        }
        if opt.is_some_and(|g| g.trim().is_empty()) {
            return Err(IdentityError::Option {
                key,
                rest: ": empty".into(),
            });
        }
        if in_doc.is_some_and(|d| d.trim().is_empty()) {
            return Err(IdentityError::Document(format!(
                "{name}: $.instrument.{key}: empty (the record's {key} must name one)"
            )));
        }
    }
    if let Some(t) = req.created_utc {
        crate::time::normalize_utc(t).map_err(|e| IdentityError::Option {
            key: "created_utc",
            rest: format!(": {e}"),
        })?;
    }
    Ok(())
}
