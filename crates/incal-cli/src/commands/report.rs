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
    let mut stored: Option<incal_records::StoredRecord> = None;
    let (history, record) = match store(a, &doc)? {
        Some((store, chain)) => {
            let serial = doc.instrument.serial.as_deref().unwrap_or_default();
            let id = store
                .find(serial, &text)
                .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?
                .map(|(id, _)| id);
            if let Some(id) = id {
                stored = Some(
                    store
                        .show(id)
                        .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?,
                );
            }
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
    let certificate = profile.map(|profile| certificate(a, profile, &text, stored.as_ref()));
    let opts = RenderOptions {
        date: None,
        record,
        certificate,
    };
    let html = incal_report::render_html_with(&doc, &history, &opts)
        .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?;
    write_text(a.output.as_deref(), &html)?;
    if a.pdf {
        if let Some(out) = &a.output {
            print_pdf(out)?;
        }
    }
    crate::options::check_fail_on(&doc, a.fail_on)
}

/// The certificate's own data: its number (from the record id when the
/// document is stored, else from the document's SHA-256, so the same
/// result always gets the same number), the dates and what it replaces.
fn certificate(
    a: &Args,
    profile: incal_report::certificate::LabProfile,
    text: &str,
    stored: Option<&incal_records::StoredRecord>,
) -> incal_report::certificate::Certificate {
    let prefix = profile.lab.certificate_prefix.clone().unwrap_or_default();
    let number_of = |id: i64| format!("{prefix}{id:06}");
    let number = match stored {
        Some(r) => number_of(r.id),
        None => {
            // The first 12 hex digits of the document's SHA-256.
            let hash = incal_io::sha256_hex(text.as_bytes());
            format!("{prefix}{}", hash[..12].to_uppercase())
        }
    };
    let (calibration_date, source) = match (&a.date, stored) {
        (Some(d), _) => (Some(d.clone()), "as given".to_string()),
        (None, Some(r)) => (
            Some(r.created_utc.chars().take(10).collect()),
            format!("the date record {} was stored", r.id),
        ),
        (None, None) => (None, String::new()),
    };
    let today: String = incal_report::format::now_utc_text()
        .chars()
        .take(10)
        .collect();
    incal_report::certificate::Certificate {
        profile,
        number,
        customer: a.customer.clone(),
        calibration_date,
        calibration_date_source: source,
        issue_date: today,
        environment: a.environment.clone(),
        replaces: stored
            .and_then(|r| r.supersedes.as_ref())
            .map(|s| (number_of(s.old_id), s.reason.clone())),
    }
}

/// Print `html` (a file just written) to `html` with `.pdf`, through
/// headless Chromium with the page margins of the print stylesheet.
fn print_pdf(html: &std::path::Path) -> CliResult<()> {
    let browser = ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|b| {
            std::process::Command::new(b)
                .arg("--version")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        })
        .ok_or_else(|| {
            CliError::Failure(anyhow::anyhow!(
                "--pdf: headless Chromium is not installed (apt-get install chromium); the HTML was written"
            ))
        })?;
    let abs = std::fs::canonicalize(html)
        .map_err(|e| CliError::Failure(anyhow::anyhow!("{}: {e}", html.display())))?;
    let pdf = abs.with_extension("pdf");
    let profile = std::env::temp_dir().join(format!("incal-chromium-{}", std::process::id()));
    let status = std::process::Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--no-pdf-header-footer",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(format!("--print-to-pdf={}", pdf.display()))
        .arg(format!("file://{}", abs.display()))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status();
    let _ = std::fs::remove_dir_all(&profile);
    match status {
        Ok(s) if s.success() && pdf.metadata().is_ok_and(|m| m.len() > 0) => Ok(()),
        _ => Err(CliError::Failure(anyhow::anyhow!(
            "--pdf: {browser} printed no {}",
            pdf.display()
        ))),
    }
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
            .history_if_any(serial, name, Some(doc.procedure.as_str()), None)
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
            drift: h.drift.as_ref().map(|d| incal_report::DriftLine {
                intercept: d.intercept,
                rate_per_day: d.value,
                covariance: d.covariance,
                k95: incal::estimation::coverage_factor(d.dof.unwrap_or(f64::INFINITY), 0.95),
            }),
        });
    }
    Ok(out)
}
