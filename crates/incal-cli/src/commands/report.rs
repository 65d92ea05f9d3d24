//! `incal report RESULT.json -o REPORT.html`: one self-contained HTML
//! report (a printable certificate) of any result document, written by
//! [`incal_report::render_html`].

use std::path::PathBuf;

use crate::documents::read_document;
use crate::error::{CliError, CliResult};
use crate::output::write_text;

/// Options of `incal report`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A result document (JSON written by a reducing command with --json); - reads standard input.
    pub result: PathBuf,
    /// Write the HTML to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal report`.
pub fn run(a: &Args) -> CliResult<()> {
    let (_, _, doc) = read_document(&a.result)?;
    let html = incal_report::render_html(&doc, &[])
        .map_err(|e| CliError::Failure(anyhow::anyhow!("{e}")))?;
    write_text(a.output.as_deref(), &html)
}
