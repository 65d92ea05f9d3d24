//! `incal threshold`, its plan and its simulator (`incal plan|simulate
//! threshold`).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::threshold::plan::ThresholdPlanOptions;
use incal::procedures::threshold::sim::{SimSensor, ThresholdSimOptions};
use incal::procedures::threshold::{Threshold, ThresholdOptions};
use incal::procedures::{Plan, Silent};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// The instrument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SensorArg {
    /// A gyro on a rate table (`rate_deg_s`, deg/s).
    Gyro,
    /// An accelerometer on a dividing head (`tilt_deg`, inputs in g).
    Accel,
}

impl From<SensorArg> for SimSensor {
    fn from(s: SensorArg) -> SimSensor {
        match s {
            SensorArg::Gyro => SimSensor::Gyro,
            SensorArg::Accel => SimSensor::Accel,
        }
    }
}

/// `incal threshold`.
#[derive(clap::Args, Debug)]
pub struct ThresholdArgs {
    /// Recording of the steps: `rate_deg_s` (gyro) or `tilt_deg` (accelerometer), `output`, optional `time_s`; consecutive rows at one input form a plateau.
    #[arg(long)]
    pub input: PathBuf,
    /// Scale factor K1, output per deg/s or per g (default: measured from the plateaus at zero and at the base input).
    #[arg(long, allow_negative_numbers = true)]
    pub scale_factor: Option<f64>,
    /// Standard uncertainty of the given scale factor.
    #[arg(long, default_value_t = 0.0)]
    pub scale_factor_u: f64,
    /// Base input for the resolution, in the input column's units (deg/s or deg of tilt; default: the non-zero input most plateaus hold).
    #[arg(long, allow_negative_numbers = true)]
    pub base_input: Option<f64>,
    /// Time left out at the start of each plateau, s (needs `time_s` or --rate-hz).
    #[arg(long, default_value_t = 0.0)]
    pub settle_s: f64,
    /// Sampling rate, Hz, for --settle-s when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// The share of K1 times the step a step's output change must reach.
    #[arg(long, default_value_t = 0.5)]
    pub response_fraction: f64,
    /// Level of the one-sided test.
    #[arg(long, default_value_t = 0.05)]
    pub test_level: f64,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal threshold`.
pub fn run(a: &ThresholdArgs) -> CliResult<()> {
    let options = ThresholdOptions {
        scale_factor: a.scale_factor,
        scale_factor_u: a.scale_factor_u,
        base_input: a.base_input,
        settle_s: a.settle_s,
        rate_hz: a.rate_hz,
        response_fraction: a.response_fraction,
        test_level: a.test_level,
    };
    crate::run::reduce::<Threshold>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// A threshold test: the instrument, the steps and the noise.
#[derive(clap::Args, Debug, Clone)]
pub struct TestArgs {
    /// The instrument.
    #[arg(long, value_enum, default_value = "gyro")]
    pub sensor: SensorArg,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 10.0)]
    pub rate_hz: f64,
    /// Length of each plateau, s.
    #[arg(long, default_value_t = 30.0)]
    pub dwell_s: f64,
    /// Step sizes, deg/s or g (default gyro 0.001,0.002,0.005,0.01,0.02,0.05; accelerometer 2e-6..1e-4).
    #[arg(long, value_delimiter = ',')]
    pub steps: Option<Vec<f64>>,
    /// Base input, deg/s or deg of tilt (default 10 deg/s or 30 deg; 0: steps at zero only).
    #[arg(long, allow_negative_numbers = true)]
    pub base_input: Option<f64>,
    /// Scale factor, output per deg/s or per g.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub scale_factor: f64,
    /// White noise of one sample, output units (default 0.002 gyro, 1e-5 accelerometer).
    #[arg(long)]
    pub noise: Option<f64>,
    /// Gauss–Markov noise sigma, output units.
    #[arg(long, default_value_t = 0.0)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time, s.
    #[arg(long, default_value_t = 2.0)]
    pub gm_tau_s: f64,
}

/// `incal plan threshold`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub test: TestArgs,
    /// Expected threshold, deg/s or g (default 0.008 or 2e-5).
    #[arg(long)]
    pub expected_threshold: Option<f64>,
    /// Expected resolution, deg/s or g (default 0.004 or 1e-5).
    #[arg(long)]
    pub expected_resolution: Option<f64>,
    /// Seed of the first of the simulated records the prediction reduces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan threshold`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let t = &a.test;
    let options = ThresholdPlanOptions {
        sensor: t.sensor.into(),
        rate_hz: t.rate_hz,
        dwell_s: t.dwell_s,
        steps: t.steps.clone(),
        base_input: t.base_input,
        scale_factor: t.scale_factor,
        expected_threshold: a.expected_threshold,
        expected_resolution: a.expected_resolution,
        noise: t.noise,
        gm_sigma: t.gm_sigma,
        gm_tau_s: t.gm_tau_s,
        seed: a.seed,
    };
    a.out.emit(&<Threshold as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate threshold`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub test: TestArgs,
    /// Bias, output units.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub bias: f64,
    /// Half-width of the dead band at zero, deg/s or g (default 0.004 or 1e-5).
    #[arg(long)]
    pub dead_band: Option<f64>,
    /// Half-width of the dead band about the base input, deg/s or g (default 0.002 or 5e-6).
    #[arg(long)]
    pub resolution_band: Option<f64>,
    /// Output quantum, output units (0: none).
    #[arg(long, default_value_t = 0.0)]
    pub quantum: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (threshold and resolution at 50 %, dead bands, K1) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate threshold`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let t = &a.test;
    let options = ThresholdSimOptions {
        sensor: t.sensor.into(),
        rate_hz: t.rate_hz,
        dwell_s: t.dwell_s,
        steps: t.steps.clone(),
        base_input: t.base_input,
        scale_factor: t.scale_factor,
        bias: a.bias,
        dead_band: a.dead_band,
        resolution_band: a.resolution_band,
        noise: t.noise,
        gm_sigma: t.gm_sigma,
        gm_tau_s: t.gm_tau_s,
        quantum: a.quantum,
        seed: a.seed,
    };
    crate::run::simulate::<Threshold>(&options, a.output.as_deref())?;
    crate::run::write_truth::<Threshold>(&options, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Threshold and resolution: the smallest input step answered at zero and at a base input (IEEE Std 952 / 1431, GJB 2426A, GJB 1037A).
    Threshold(ThresholdArgs),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Threshold(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
pub enum Plans {
    /// Threshold plan: predicted u of the threshold and resolution for the steps, plateaus and noise; refuses steps that do not bracket the expected values.
    Threshold(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Threshold(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
pub enum Simulations {
    /// A gyro or accelerometer stepped about zero and a base input, with dead bands, noise and a quantizer; writes the input CSV of `incal threshold`.
    Threshold(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Threshold(a) => simulate(a),
        }
    }
}
