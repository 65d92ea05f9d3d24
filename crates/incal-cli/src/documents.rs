//! Reading result documents (`incal.result/1`) given as input: `compare`,
//! `centrifuge --from`, and the records store's current calibrations of
//! one instrument (`thermal fit --db`, `repeatability --db`).

use std::path::Path;

use incal::document::ResultDocument;

use crate::error::{CliError, CliResult};

/// Read a result document: `(display name, SHA-256 of the bytes,
/// document)`. `-` reads standard input; a UTF-8 BOM is accepted. Anything
/// that is not an incal result is refused with one line naming the file
/// and the JSON path.
pub fn read_document(path: &Path) -> CliResult<(String, String, ResultDocument)> {
    read_document_text(path).map(|(name, sha, _, doc)| (name, sha, doc))
}

/// As [`read_document`], with the document's text (without a BOM: the
/// text `incal record add` stores).
pub fn read_document_text(path: &Path) -> CliResult<(String, String, String, ResultDocument)> {
    let (name, bytes, sha) = crate::io::read_hashed(path)?;
    let text =
        String::from_utf8(bytes).map_err(|_| CliError::Input(format!("{name}: not UTF-8 text")))?;
    if text.trim().is_empty() {
        return Err(CliError::Input(format!("{name}: empty file")));
    }
    let doc =
        ResultDocument::from_json(&text).map_err(|e| CliError::Input(format!("{name}: {e}")))?;
    Ok((name, sha, text, doc))
}

/// The calibrations of `serial` in the records store `db` (not
/// superseded; of `procedure` when given, which is needed when there are
/// several), after checking the store's chain, with the store's name for
/// messages ([`incal_records::Store::current_calibrations`]).
pub fn store_calibrations(
    db: &Path,
    serial: &str,
    procedure: Option<&str>,
) -> CliResult<(String, Vec<(incal_records::StoredRecord, ResultDocument)>)> {
    let name = crate::options::store_name(db);
    let err = |e| crate::options::store_error(&name, e);
    let want = match procedure {
        Some(p) => Some(crate::options::procedure_id("--procedure", p)?),
        None => None,
    };
    let store = incal_records::Store::open_existing(db).map_err(err)?;
    store.check_chain().map_err(err)?;
    let records = store.current_calibrations(serial, want).map_err(err)?;
    Ok((name, records))
}
