//! `incal repeatability`, its plan and its simulator (`incal
//! plan|simulate repeatability`): runs from a table, from result
//! documents or from the records store, into the core's
//! [`incal::procedures::repeatability`].

use std::path::PathBuf;

use clap::Subcommand;
use incal::document::InputFile;
use incal::procedures::repeatability::input::{runs_from_documents, DocumentRun};
use incal::procedures::repeatability::plan::RepeatPlanOptions;
use incal::procedures::repeatability::sim::RepeatSimOptions;
use incal::procedures::repeatability::{analyse, Repeatability, RepeatabilityOptions};
use incal::procedures::{Plan, Silent};

use crate::documents::read_document;
use crate::error::{core, usage, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// `incal repeatability`.
#[derive(clap::Args, Debug)]
pub struct RepeatArgs {
    /// Result documents (JSON) of one procedure, one per turn-on; each one's day is its instrument's `day` (--meta day=...).
    #[arg(value_name = "RESULT.json")]
    pub results: Vec<PathBuf>,
    /// Instead: a table of runs, one row per turn-on: `value`, `u`, optional `day` and `dof`.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["results", "db"])]
    pub input: Option<PathBuf>,
    /// Instead of files: the records store's calibrations of --serial (not superseded) of --procedure; each record's day is its `day` entry or the date it was recorded.
    #[arg(long, value_name = "PATH|URL", conflicts_with = "results", requires = "serial")]
    pub db: Option<PathBuf>,
    /// With --db: the procedure whose records are analysed.
    #[arg(long, requires = "db")]
    pub procedure: Option<String>,
    /// The coefficient analysed (its name in the documents, e.g. K1, K0, bias_settled); with --input, its label.
    #[arg(long, default_value = "value")]
    pub coefficient: String,
    /// The coefficient's unit for a table of runs (documents give their own).
    #[arg(long, default_value = "output")]
    pub unit: String,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal repeatability`.
pub fn run(a: &RepeatArgs) -> CliResult<()> {
    let mut options = RepeatabilityOptions {
        coefficient: a.coefficient.clone(),
        unit: a.unit.clone(),
    };
    if let Some(input) = &a.input {
        return crate::run::reduce::<Repeatability>(input, &a.read, &options, &a.result, &Silent);
    }
    let (docs, inputs) = match &a.db {
        Some(db) => from_store(db, a.result.serial.as_deref().unwrap_or(""), a.procedure.as_deref())?,
        None => {
            if a.results.is_empty() {
                return Err(usage("give result documents, --input FILE or --db STORE --serial S"));
            }
            let mut docs = Vec::new();
            let mut inputs = Vec::new();
            for p in &a.results {
                let (name, sha256, doc) = read_document(p)?;
                inputs.push(InputFile {
                    role: "result".into(),
                    path: name.clone(),
                    sha256,
                    rows: None,
                });
                docs.push(DocumentRun {
                    name,
                    date: None,
                    doc,
                });
            }
            (docs, inputs)
        }
    };
    let (runs, unit) = runs_from_documents(&docs, &a.coefficient).map_err(core)?;
    if let Some(u) = unit {
        options.unit = u;
    }
    let mut doc = analyse(&runs, &options).map_err(core)?.document().map_err(core)?;
    if let Some(mc) = a.result.monte_carlo() {
        // The runs read from the documents are the input the trials draw.
        let (section, warnings) =
            incal::montecarlo::run::<Repeatability>(&runs, &options, &doc, &mc, &Silent)
                .map_err(core)?;
        doc.monte_carlo = Some(section);
        doc.warnings.extend(warnings);
    }
    doc.inputs = inputs;
    doc.options = incal::procedures::options_map(&options).map_err(core)?;
    a.result.emit(doc)
}

/// The calibrations of `serial` in the store (not superseded; of
/// `procedure` when given), each with the date it was recorded.
fn from_store(
    db: &std::path::Path,
    serial: &str,
    procedure: Option<&str>,
) -> CliResult<(Vec<DocumentRun>, Vec<InputFile>)> {
    let (name, records) = crate::documents::store_calibrations(db, serial, procedure)?;
    let mut docs = Vec::new();
    let mut inputs = Vec::new();
    for (rec, doc) in records {
        inputs.push(InputFile {
            role: "record".into(),
            path: format!("{name}#{}", rec.id),
            sha256: rec.sha256.clone(),
            rows: None,
        });
        docs.push(DocumentRun {
            name: format!("record {}", rec.id),
            date: rec.created_utc.get(..10).map(str::to_string),
            doc,
        });
    }
    Ok((docs, inputs))
}

/// The runs of a repeatability test.
#[derive(clap::Args, Debug, Clone)]
pub struct TestArgs {
    /// Days.
    #[arg(long, default_value_t = 5)]
    pub days: usize,
    /// Turn-ons a day.
    #[arg(long, default_value_t = 3)]
    pub turn_ons_per_day: usize,
    /// Day-to-day standard deviation.
    #[arg(long, default_value_t = 0.02)]
    pub day_sd: f64,
    /// Turn-on-to-turn-on standard deviation.
    #[arg(long, default_value_t = 0.01)]
    pub turn_on_sd: f64,
    /// Each run's own u.
    #[arg(long, default_value_t = 0.005)]
    pub within_u: f64,
}

/// `incal plan repeatability`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub test: TestArgs,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan repeatability`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let t = &a.test;
    let o = RepeatPlanOptions {
        days: t.days,
        turn_ons_per_day: t.turn_ons_per_day,
        day_sd: t.day_sd,
        turn_on_sd: t.turn_on_sd,
        within_u: t.within_u,
        seed: 1,
    };
    a.out.emit(&<Repeatability as Plan>::plan(&o).map_err(core)?)
}

/// `incal simulate repeatability`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub test: TestArgs,
    /// The coefficient's mean.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    pub mean: f64,
    /// Spread of the runs' u (largest over smallest possible; 1: all equal).
    #[arg(long, default_value_t = 1.0)]
    pub u_spread: f64,
    /// Degrees of freedom of each run's u (default: exact).
    #[arg(long)]
    pub within_dof: Option<f64>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (the components as standard deviations) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate repeatability`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let t = &a.test;
    let o = RepeatSimOptions {
        days: t.days,
        turn_ons_per_day: t.turn_ons_per_day,
        mean: a.mean,
        day_sd: t.day_sd,
        turn_on_sd: t.turn_on_sd,
        within_u: t.within_u,
        u_spread: a.u_spread,
        within_dof: a.within_dof,
        seed: a.seed,
    };
    crate::run::simulate::<Repeatability>(&o, a.output.as_deref())?;
    crate::run::write_truth::<Repeatability>(&o, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Repeatability turn-on to turn-on and day to day of one coefficient: nested analysis of variance over runs (IEEE Std 952 / 1431, GJB 2426A, GJB 1037A).
    Repeatability(RepeatArgs),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Repeatability(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
pub enum Plans {
    /// Repeatability plan: predicted u of the turn-on and day components for days and turn-ons.
    Repeatability(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Repeatability(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
pub enum Simulations {
    /// Runs over days and turn-ons with known variance components; writes the input CSV of `incal repeatability --input`.
    Repeatability(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Repeatability(a) => simulate(a),
        }
    }
}
