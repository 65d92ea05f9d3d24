//! `incal report RESULT.json -o REPORT.html`: one self-contained HTML
//! report (a printable certificate) of any result document, written by
//! [`incal_report::render_html`].

use std::path::PathBuf;

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
    /// Laboratory profile (TOML: [lab] name, address, accreditation; [[signatory]] name, role; [[standard]] rig, id, certificate, due): write a calibration certificate.
    #[arg(long, value_name = "FILE")]
    pub lab: Option<PathBuf>,
    /// With --lab: the customer named on the certificate.
    #[arg(long, value_name = "TEXT", requires = "lab")]
    pub customer: Option<String>,
    /// With --lab: the date of calibration, YYYY-MM-DD (default: the date the result was recorded in the store named by --db).
    #[arg(long, value_name = "YYYY-MM-DD", requires = "lab")]
    pub date: Option<String>,
    /// With --lab: the environmental conditions during the calibration (e.g. "23.0 +- 0.5 degC, 45 % RH").
    #[arg(long, value_name = "TEXT", requires = "lab")]
    pub environment: Option<String>,
    /// Also print the HTML to PDF next to --output (REPORT.pdf) with headless Chromium (it must be installed).
    #[arg(long, requires = "output")]
    pub pdf: bool,
    /// With --lab: write the certificate as a Digital Calibration Certificate (PTB DCC 3.2.0 XML with D-SI quantities) instead of HTML.
    #[arg(long, requires = "lab", conflicts_with = "pdf")]
    pub dcc: bool,
}

/// `incal report`.
pub fn run(a: &Args) -> CliResult<()> {
    let (_, _, text, mut doc) = read_document_text(&a.result)?;
    if let Some(l) = &a.limits {
        apply_limits(&mut doc, l)?;
    }
    let profile = match &a.lab {
        Some(p) => {
            let (name, text) = crate::io::read_text(p)?;
            Some(
                incal_report::certificate::LabProfile::parse(&text)
                    .map_err(|e| CliError::Input(format!("{name}: {e}")))?,
            )
        }
        None => None,
    };
    if let Some(d) = &a.date {
        if !incal_report::certificate::is_date(d) {
            return Err(CliError::Input(format!(
                "--date: '{}' is not a date YYYY-MM-DD",
                incal_io::clip(d)
            )));
        }
    }
    // What the store says about this very document: its record, when it
    // was stored and what it corrects.
    let store = store(a, doc.instrument.serial.as_deref())?;
    let issue = incal_report::stored::Issue {
        customer: a.customer.clone(),
        date: a.date.clone(),
        environment: a.environment.clone(),
    };
    let stored_err = |e| match e {
        incal_report::stored::StoredError::Input(m) => CliError::Input(m),
        incal_report::stored::StoredError::Failure(m) => CliError::Failure(anyhow::anyhow!(m)),
    };
    if let (true, Some(p)) = (a.dcc, profile.clone()) {
        let xml = incal_report::stored::dcc_of(&doc, &text, store.as_ref(), p, &issue)
            .map_err(stored_err)?;
        write_text(a.output.as_deref(), &xml)?;
        return crate::options::check_fail_on(&doc, a.fail_on);
    }
    let html = incal_report::stored::report_html(&doc, &text, store.as_ref(), profile, &issue)
        .map_err(stored_err)?;
    write_text(a.output.as_deref(), &html)?;
    if a.pdf {
        if let Some(out) = &a.output {
            print_pdf(out)?;
        }
    }
    crate::options::check_fail_on(&doc, a.fail_on)
}

/// Print `html` (a file just written) to `html` with `.pdf`
/// ([`incal_report::pdf::print`]); a failure (exit 1) names why.
fn print_pdf(html: &std::path::Path) -> CliResult<()> {
    incal_report::pdf::print(html)
        .map(|_| ())
        .map_err(|e| CliError::Failure(anyhow::anyhow!("--pdf: {e}")))
}

/// The records store named (`--db`, else `$INCAL_DB`: it must exist
/// either way); an `incal.db` that happens to lie in the working directory
/// never changes a certificate.
/// A result without a serial has no place in a store: none is opened.
fn store(a: &Args, serial: Option<&str>) -> CliResult<Option<incal_records::Store>> {
    let (path, named) = db_choice(a.db.as_deref());
    if serial.is_none() || !named {
        return Ok(None);
    }
    // Store errors name the path themselves.
    incal_records::Store::open_existing(&path)
        .map(Some)
        .map_err(|e| {
            if e.is_input() {
                CliError::Input(e.to_string())
            } else {
                CliError::Failure(anyhow::anyhow!("{e}"))
            }
        })
}
