//! `incal compare A.json B.json`: the core's comparison of two result
//! documents ([`incal::document::compare`]), as JSON or a table.

use std::path::PathBuf;

use incal::document::compare::compare_documents;

use crate::documents::read_document;
use crate::error::{CliError, CliResult};
use crate::output::{json_text, write_text};

/// Options of `incal compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// First result (JSON written by an incal command with --json); - reads standard input.
    pub a: PathBuf,
    /// Second result (the reference for the relative difference).
    pub b: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// differs: exit 3 after writing the comparison when any coefficient's |En| > 1 (the two results disagree beyond their U95).
    #[arg(long, value_enum, value_name = "WHEN")]
    pub fail_on: Option<CompareFailOn>,
}

/// `incal compare --fail-on`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum CompareFailOn {
    /// Any |En| > 1.
    Differs,
}

/// `incal compare`.
pub fn run(a: &Args) -> CliResult<()> {
    let (na, _, da) = read_document(&a.a)?;
    let (nb, _, db) = read_document(&a.b)?;
    let c = compare_documents(&na, &da, &nb, &db).map_err(|e| CliError::Input(e.to_string()))?;
    let text = if a.json {
        json_text(&c.to_json())
    } else {
        incal_report::text::render_comparison(&c)
    };
    write_text(a.output.as_deref(), &text)?;
    if a.fail_on == Some(CompareFailOn::Differs) {
        let differ: Vec<String> = c
            .rows
            .iter()
            .filter_map(|(n, r)| {
                let en = r["En"].as_f64()?;
                (en.abs() > 1.0).then(|| format!("{n} En {en:.2}"))
            })
            .collect();
        if !differ.is_empty() {
            let more = if differ.len() > 6 {
                format!(" and {} more", differ.len() - 6)
            } else {
                String::new()
            };
            return Err(CliError::Stop(format!(
                "{} coefficient(s) differ beyond their U95 ({}{more}): stopped by --fail-on differs",
                differ.len(),
                differ[..differ.len().min(6)].join(", ")
            )));
        }
    }
    Ok(())
}
