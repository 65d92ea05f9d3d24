//! `incal warmup`, its plan and its simulator (`incal plan|simulate
//! warmup`).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::warmup::plan::WarmupPlanOptions;
use incal::procedures::warmup::sim::WarmupSimOptions;
use incal::procedures::warmup::{CurveChoice, Warmup, WarmupOptions};
use incal::procedures::{Plan, Silent};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// The warm-up curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CurveArg {
    /// The simplest curve that passes the 5 % lack-of-fit test.
    Auto,
    /// One exponential.
    Exp1,
    /// One exponential and a linear drift.
    Exp1Drift,
    /// Two exponentials.
    Exp2,
    /// Two exponentials and a linear drift.
    Exp2Drift,
}

impl From<CurveArg> for CurveChoice {
    fn from(m: CurveArg) -> CurveChoice {
        match m {
            CurveArg::Auto => CurveChoice::Auto,
            CurveArg::Exp1 => CurveChoice::Exp1,
            CurveArg::Exp1Drift => CurveChoice::Exp1Drift,
            CurveArg::Exp2 => CurveChoice::Exp2,
            CurveArg::Exp2Drift => CurveChoice::Exp2Drift,
        }
    }
}

/// `incal warmup`.
#[derive(clap::Args, Debug)]
pub struct WarmupArgs {
    /// Recording from power-on: `time_s` (or --rate-hz), the output, optional `status` (valid where not 0) and `temperature_c`; an empty output cell is a missing sample.
    #[arg(long)]
    pub input: PathBuf,
    /// Sampling rate, Hz, when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// The output column.
    #[arg(long, default_value = "output")]
    pub column: String,
    /// Power-on on the file's clock, s: rows before it are left out.
    #[arg(long, default_value_t = 0.0)]
    pub power_on_s: f64,
    /// A valid output is at least this (output units).
    #[arg(long)]
    pub valid_min: Option<f64>,
    /// A valid output is at most this (output units).
    #[arg(long)]
    pub valid_max: Option<f64>,
    /// The warm-up curve.
    #[arg(long, value_enum, default_value = "auto")]
    pub curve: CurveArg,
    /// Half-width of the settling band (output units; default 1 % of the transient at power-on).
    #[arg(long)]
    pub settle_band: Option<f64>,
    /// The warm-up drift's window after turn-on, s.
    #[arg(long, default_value_t = 60.0)]
    pub first_window_s: f64,
    /// Block length, s (default: at most tau/10 and a 400th of the record).
    #[arg(long)]
    pub block_s: Option<f64>,
    /// Largest temperature span after turn-on before a warning, °C.
    #[arg(long, default_value_t = 1.0)]
    pub max_temperature_span_c: f64,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal warmup`.
pub fn run(a: &WarmupArgs) -> CliResult<()> {
    let options = WarmupOptions {
        rate_hz: a.rate_hz,
        column: a.column.clone(),
        power_on_s: a.power_on_s,
        valid_min: a.valid_min,
        valid_max: a.valid_max,
        curve: a.curve.into(),
        settle_band: a.settle_band,
        first_window_s: a.first_window_s,
        block_s: a.block_s,
        max_temperature_span_c: a.max_temperature_span_c,
    };
    crate::run::reduce::<Warmup>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// A warm-up test: the record and the expected curve and noise.
#[derive(clap::Args, Debug, Clone)]
pub struct TestArgs {
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 10.0)]
    pub rate_hz: f64,
    /// Record length from power-on, s.
    #[arg(long, default_value_t = 3600.0)]
    pub duration_s: f64,
    /// Turn-on time, s.
    #[arg(long, default_value_t = 2.0)]
    pub turn_on_s: f64,
    /// Settled value (output units).
    #[arg(long, default_value_t = 0.5)]
    pub bias_settled: f64,
    /// Transient at power-on (output units).
    #[arg(long, default_value_t = 0.2)]
    pub amplitude: f64,
    /// Time constant of the warm-up, s.
    #[arg(long, default_value_t = 300.0)]
    pub tau_s: f64,
    /// White noise of one sample (output units).
    #[arg(long, default_value_t = 0.01)]
    pub noise: f64,
    /// Gauss–Markov noise sigma (output units).
    #[arg(long, default_value_t = 0.0)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time, s.
    #[arg(long, default_value_t = 5.0)]
    pub gm_tau_s: f64,
}

/// `incal plan warmup`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub test: TestArgs,
    /// Seed of the first of the simulated records the prediction reduces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan warmup`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let t = &a.test;
    let options = WarmupPlanOptions {
        rate_hz: t.rate_hz,
        duration_s: t.duration_s,
        turn_on_s: t.turn_on_s,
        bias_settled: t.bias_settled,
        amplitude: t.amplitude,
        tau_s: t.tau_s,
        noise: t.noise,
        gm_sigma: t.gm_sigma,
        gm_tau_s: t.gm_tau_s,
        seed: a.seed,
    };
    a.out.emit(&<Warmup as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate warmup`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub test: TestArgs,
    /// A second transient at power-on (output units; 0: none).
    #[arg(long, default_value_t = 0.0)]
    pub amplitude_2: f64,
    /// Its time constant, s.
    #[arg(long, default_value_t = 30.0)]
    pub tau_2_s: f64,
    /// Linear drift, output units per s.
    #[arg(long, default_value_t = 0.0)]
    pub drift_per_s: f64,
    /// Chamber temperature, °C.
    #[arg(long, default_value_t = 25.0)]
    pub temperature_c: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (the curve, turn-on time, settling time, warm-up drift) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate warmup`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let t = &a.test;
    let options = WarmupSimOptions {
        rate_hz: t.rate_hz,
        duration_s: t.duration_s,
        turn_on_s: t.turn_on_s,
        bias_settled: t.bias_settled,
        amplitude: t.amplitude,
        tau_s: t.tau_s,
        amplitude_2: a.amplitude_2,
        tau_2_s: a.tau_2_s,
        drift_per_s: a.drift_per_s,
        noise: t.noise,
        gm_sigma: t.gm_sigma,
        gm_tau_s: t.gm_tau_s,
        temperature_c: a.temperature_c,
        seed: a.seed,
    };
    crate::run::simulate::<Warmup>(&options, a.output.as_deref())?;
    crate::run::write_truth::<Warmup>(&options, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Turn-on time and warm-up from power-on: settled value, warm-up curve, settling time, drift (IEEE Std 952 / 1431, GJB 2426A).
    Warmup(WarmupArgs),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Warmup(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
pub enum Plans {
    /// Warm-up plan: predicted u of the settled value, tau, settling time and drift for a record and noise.
    Warmup(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Warmup(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
pub enum Simulations {
    /// An instrument switched on into a known warm-up curve with white and Gauss–Markov noise; writes the input CSV of `incal warmup`.
    Warmup(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Warmup(a) => simulate(a),
        }
    }
}
