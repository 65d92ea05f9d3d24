//! Output: the one text renderer of every result document, the common
//! result options (`--json`, `--output`, instrument identity) and plain
//! text tables. Engineering units (µg, µg/g², arcsec, mm) come from
//! [`incal::units::Unit::engineering`], the one place that chooses them.

use std::path::PathBuf;

use incal::document::{InputFile, ResultDocument};

use crate::error::CliResult;

/// Options every reducing command shares: output form and destination,
/// and the identity of the instrument.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ResultArgs {
    /// Print the result document as one JSON object (schema incal.result/1) instead of the readable report.
    #[arg(long)]
    pub json: bool,
    /// Write the result to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Serial number of the instrument (recorded in the result).
    #[arg(long)]
    pub serial: Option<String>,
    /// Model or part number of the instrument (recorded in the result).
    #[arg(long)]
    pub model: Option<String>,
    /// Further identity or conditions, KEY=VALUE (repeatable), e.g. --meta operator=lee --meta temperature_c=23.
    #[arg(long = "meta", value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
    /// The instrument's output unit (V, mA, counts, LSB, ...): every unit that says "output" (output, output/g, output/(deg/s)) is written with it (K1 in V/g), and limits may use it (V/g, mV/g). Values are unchanged.
    #[arg(long, value_name = "UNIT")]
    pub output_unit: Option<String>,
    /// Limits file (TOML): judge every limited coefficient (pass, conditional-pass, not-determined, conditional-fail, fail).
    #[arg(long, value_name = "FILE")]
    pub limits: Option<PathBuf>,
    /// With --limits: exit 3 after writing the result when the overall verdict is fail, conditional-fail or not-determined (fail), or any but pass (conditional).
    #[arg(long, value_enum, value_name = "WHEN", requires = "limits")]
    pub fail_on: Option<crate::options::FailOn>,
    /// Monte Carlo propagation of distributions (JCGM 101, GUM Supplement 1): M trials (100 to 1000000) or auto (batches of 10000 until stable); synthetic recordings from the fitted model and the input distributions, each reduced; the document's monte_carlo section validates (or not) every GUM interval.
    #[arg(long, value_name = "M|auto")]
    pub monte_carlo: Option<incal::montecarlo::Trials>,
    /// With --monte-carlo: the seed every trial's stream derives from (same seed, same result on any number of threads) [default: 1].
    #[arg(long, value_name = "N", requires = "monte_carlo")]
    pub seed: Option<u64>,
    /// With --monte-carlo: significant digits of a standard uncertainty that set the numerical tolerance of the validation (1 to 3) [default: 1].
    #[arg(long, value_name = "D", requires = "monte_carlo")]
    pub mc_digits: Option<u32>,
}

impl ResultArgs {
    /// The Monte Carlo asked for, if any.
    pub fn monte_carlo(&self) -> Option<incal::montecarlo::MonteCarloOptions> {
        self.monte_carlo.map(|t| {
            let mut o = incal::montecarlo::MonteCarloOptions::new(t);
            if let Some(s) = self.seed {
                o.seed = s;
            }
            if let Some(d) = self.mc_digits {
                o.digits = d;
            }
            o
        })
    }
}

/// Judge `doc` against the limits file `path` (its hash joins the inputs).
pub fn apply_limits(doc: &mut ResultDocument, path: &std::path::Path) -> CliResult<()> {
    let (name, text) = crate::io::read_text(path)?;
    let finish = incal::document::finish::Finish {
        limits: Some(incal::document::finish::LimitsText { name, text }),
        ..Default::default()
    };
    finish.apply(doc).map_err(finish_error)
}

/// An error of [`incal::document::finish::Finish::apply`]: a limits
/// file's problem as the file says it (its keys are not options), an
/// option's as [`crate::error::core`] spells it.
fn finish_error(e: incal::Error) -> crate::error::CliError {
    match e {
        incal::Error::Input(i) => crate::error::CliError::Input(i.to_string()),
        other => crate::error::core(other),
    }
}

impl ResultArgs {
    /// Put the instrument identity into `doc`, render it (JSON or text)
    /// and write it to `--output` or standard output.
    pub fn emit(&self, mut doc: ResultDocument) -> CliResult<()> {
        if self.monte_carlo.is_some() && doc.monte_carlo.is_none() {
            return Err(crate::error::usage(
                "--monte-carlo: this command reduces no recording it can draw again (give it to the reductions whose results it reads)",
            ));
        }
        let limits = match &self.limits {
            Some(path) => {
                let (name, text) = crate::io::read_text(path)?;
                Some(incal::document::finish::LimitsText { name, text })
            }
            None => None,
        };
        let finish = incal::document::finish::Finish {
            serial: self.serial.clone(),
            model: self.model.clone(),
            meta: self.meta.clone(),
            output_unit: self.output_unit.clone(),
            limits,
            fail_on: None,
        };
        finish.apply(&mut doc).map_err(finish_error)?;
        let text = if self.json {
            format!("{}\n", doc.to_json())
        } else {
            render(&doc)
        };
        write_text(self.output.as_deref(), &text)?;
        crate::options::check_fail_on(&doc, self.fail_on)
    }
}

/// The record of one input file of a result.
pub fn input_file(role: &str, path: &str, bytes_sha256: String, rows: Option<usize>) -> InputFile {
    InputFile {
        role: role.to_string(),
        path: path.to_string(),
        sha256: bytes_sha256,
        rows: rows.map(|r| r as u64),
    }
}

pub use crate::io::write_text;
pub use incal_report::format::{dof_text, measured, shown_name, sig};
pub use incal_report::text::{render, render_plan, render_table, table};

/// Pretty JSON of any serializable value, with a final newline.
pub fn json_text(v: &serde_json::Value) -> String {
    format!(
        "{}\n",
        serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string())
    )
}

/// Options every plan command shares: output form and destination.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct PlanOut {
    /// Print the plan document as one JSON object (schema incal.plan/1) instead of the readable plan.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Also write the run sheet for the operator: a CSV of the positions, speeds or rates in the order they are run (step, settings, samples).
    #[arg(long, value_name = "FILE")]
    pub run_sheet: Option<PathBuf>,
}

impl PlanOut {
    /// Render the plan document (JSON or text) and write it, and the run
    /// sheet when asked.
    pub fn emit(&self, doc: &incal::document::plan::PlanDocument) -> CliResult<()> {
        if let Some(path) = &self.run_sheet {
            let csv = doc.run_sheet_csv().map_err(|e| match e {
                incal::Error::InvalidOption { message, .. } => {
                    crate::error::usage(format!("--run-sheet: {message}"))
                }
                other => crate::error::CliError::Failure(anyhow::anyhow!("--run-sheet: {other}")),
            })?;
            write_text(Some(path), &csv)?;
        }
        let text = if self.json {
            json_text(&serde_json::to_value(doc).unwrap_or(serde_json::Value::Null))
        } else {
            render_plan(doc)
        };
        write_text(self.output.as_deref(), &text)
    }
}
