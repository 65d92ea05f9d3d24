//! `incal report RESULT.json -o REPORT.html`: one self-contained HTML
//! report (a printable certificate) of any result document, written by
//! [`incal_report::render_html`].

use std::path::PathBuf;

use incal::document::ResultDocument;
use incal_report::{HistoryPoint, HistorySeries, RecordStamp, RenderOptions};

use crate::documents::read_document_text;
use crate::error::{CliError, CliResult};
use crate::options::db_choice;
use crate::output::{apply_limits, write_text};

/// Options of `incal report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A result document (JSON written by a reducing command with --json); - reads standard input.
    pub result: PathBuf,
    /// Write the HTML to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Limits file (TOML): verdicts in the coefficient table, limits in the plots.
    #[arg(long, value_name = "FILE")]
    pub limits: Option<PathBuf>,
    /// Records store (SQLite file or postgresql:// URL) for the history plots of the limited coefficients and the record stamp (default: $INCAL_DB; no store is used unless named).
    #[arg(long, value_name = "PATH|URL")]
    pub db: Option<PathBuf>,
    /// With --limits: exit 3 after writing the report when the overall verdict is fail, conditional-fail or not-determined (fail), or any but pass (conditional).
    #[arg(long, value_enum, value_name = "WHEN", requires = "limits")]
    pub fail_on: Option<crate::options::FailOn>,
}

/// `incal report`.
pub fn run(a: &Args) -> CliResult<()> {
    let (_, _, text, mut doc) = read_document_text(&a.result)?;
    if let Some(l) = &a.limits {
        apply_limits(&mut doc, l)?;
    }
    let (history, record) = match store(a, &doc)? {
        Some((store, chain)) => {
            let serial = doc.instrument.serial.as_deref().unwrap_or_default();
            let id = store
                .find(serial, &text)
                .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?
                .map(|(id, _)| id);
            let record = RecordStamp {
                store: store.path().display().to_string(),
                id,
                records: chain.records,
                head: chain.head,
            };
            (history(&store, &doc)?, Some(record))
        }
        None => (Vec::new(), None),
    };
    let opts = RenderOptions { date: None, record };
    let html = incal_report::render_html_with(&doc, &history, &opts)
        .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?;
    write_text(a.output.as_deref(), &html)?;
    crate::options::check_fail_on(&doc, a.fail_on)
}

/// The records store, checked whole, when the result has a serial and a
/// store is named (`--db`, else `$INCAL_DB`: it must exist either way).
fn store(
    a: &Args,
    doc: &ResultDocument,
) -> CliResult<Option<(incal_records::Store, incal_records::Verified)>> {
    // A store named (--db or $INCAL_DB) must exist; incal.db is used when
    // present.
    // Only a store named (--db or $INCAL_DB) is opened: an incal.db that
    // happens to lie in the working directory never changes a certificate.
    let (path, named) = db_choice(a.db.as_deref());
    if doc.instrument.serial.is_none() || !named {
        return Ok(None);
    }
    // Store errors name the path themselves.
    let store = incal_records::Store::open_existing(&path).map_err(|e| {
        if e.is_input() {
            CliError::Input(e.to_string())
        } else {
            CliError::Failure(anyhow::anyhow!("{e}"))
        }
    })?;
    let chain = store
        .check_chain()
        .map_err(|e| CliError::Failure(anyhow::anyhow!("{}: {e}", store.path().display())))?;
    Ok(Some((store, chain)))
}

/// The history of every limited coefficient of the instrument, from the
/// store, when there are two or more calibrations.
fn history(store: &incal_records::Store, doc: &ResultDocument) -> CliResult<Vec<HistorySeries>> {
    let (Some(serial), Some(verdicts)) = (&doc.instrument.serial, &doc.verdicts) else {
        return Ok(Vec::new());
    };
    let path = store.path().display().to_string();
    let mut out = Vec::new();
    for (name, v) in verdicts {
        // A new instrument, or a coefficient not recorded before, has no
        // history to plot.
        let Ok(h) = store
            .history_if_any(serial, name, Some(doc.procedure.as_str()))
            .map_err(|e| CliError::Input(format!("{path}: {e}")))?
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
        });
    }
    Ok(out)
}
