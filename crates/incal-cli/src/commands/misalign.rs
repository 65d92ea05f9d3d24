//! `incal misalign gyro|accel`, `incal simulate misalign gyro|accel`,
//! `incal plan misalign`, and the misalignment section of `incal demo`
//! (Li et al. 2012; docs/src/misalignment.md).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::estimation::Noise;
use incal::procedures::misalign::accel::AccelOptions;
use incal::procedures::misalign::averaging::TurnPolicy;
use incal::procedures::misalign::gyro::{GyroConfig, GyroOptions};
use incal::procedures::misalign::plan::{MisalignPlan, PlanInstrument};
use incal::procedures::misalign::sim_options::{AccelSimOptions, GyroSimOptions};
use incal::procedures::misalign::{MisalignAccel, MisalignGyro};
use incal::procedures::{Plan, Silent};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// `incal misalign …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Gyro on a rate table: table, fixture and input-axis misalignment from forward/reverse rates.
    Gyro(GyroArgs),
    /// Accelerometer on a vertical reference face: input-axis misalignment from turns about the face normal.
    Accel(AccelArgs),
}

/// `incal simulate misalign …`.
#[derive(Subcommand, Debug)]
pub enum SimCommand {
    /// Gyro on a rate table (Earth rate included); writes the input CSV of `incal misalign gyro`.
    Gyro(SimGyroArgs),
    /// Accelerometer on a vertical face; writes the input CSV of `incal misalign accel`.
    Accel(SimAccelArgs),
}

/// Which samples of a raw record are averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TurnsArg {
    /// The first whole table revolutions of each record (Earth rate cancels).
    Whole,
    /// Every sample, whole revolutions or not.
    All,
}

impl From<TurnsArg> for TurnPolicy {
    fn from(t: TurnsArg) -> TurnPolicy {
        match t {
            TurnsArg::Whole => TurnPolicy::Whole,
            TurnsArg::All => TurnPolicy::All,
        }
    }
}

/// Options of `incal misalign gyro`.
#[derive(clap::Args, Debug)]
pub struct GyroArgs {
    /// Input CSV: alpha_deg,beta_deg,rate,output (record means), or with time_s,table_angle_deg added (raw records).
    #[arg(long)]
    pub input: PathBuf,
    /// Known gyro scale factor kI (output per deg/s).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Fit one bias per (alpha, beta) configuration instead of a common one.
    #[arg(long)]
    pub per_config_bias: bool,
    /// Known standard deviation of one row's output (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Raw records: average whole table revolutions only, or every sample (--turns is an old name of this option).
    #[arg(long = "average", alias = "turns", value_enum, default_value = "whole")]
    pub average: TurnsArg,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// Options of `incal misalign accel`.
#[derive(clap::Args, Debug)]
pub struct AccelArgs {
    /// Input CSV: beta_deg,output (rows repeat = samples).
    #[arg(long)]
    pub input: PathBuf,
    /// Known accelerometer scale factor kI (output per g).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Known standard deviation of one row's output (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal misalign gyro|accel`.
pub fn run(c: &Command) -> CliResult<()> {
    match c {
        Command::Gyro(a) => {
            let options = GyroOptions {
                per_config_bias: a.per_config_bias,
                noise: Noise::from_option(a.noise).map_err(core)?,
                average: a.average.into(),
                ..GyroOptions::new(a.scale_factor)
            };
            crate::run::reduce::<MisalignGyro>(&a.input, &a.read, &options, &a.result, &Silent)
        }
        Command::Accel(a) => {
            let options = AccelOptions {
                noise: Noise::from_option(a.noise).map_err(core)?,
                ..AccelOptions::new(a.scale_factor)
            };
            crate::run::reduce::<MisalignAccel>(&a.input, &a.read, &options, &a.result, &Silent)
        }
    }
}

/// Parse `A:B` (deg) configuration pairs.
fn parse_configs(list: &[String]) -> CliResult<Vec<GyroConfig>> {
    list.iter()
        .map(|p| GyroConfig::parse(p).map_err(core))
        .collect()
}

const PAPER_CONFIGS: &str = "0:0,0:180,180:180,90:180,0:90";

/// Which instrument a plan is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Instrument {
    /// Gyro on a rate table.
    Gyro,
    /// Accelerometer on a vertical face.
    Accel,
}

/// Options of `incal plan misalign`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// Instrument of the plan.
    #[arg(long, value_enum, default_value = "gyro")]
    pub instrument: Instrument,
    /// Gyro: configurations ALPHA:BETA (deg), comma separated (default: the paper's five).
    #[arg(long, value_delimiter = ',', default_value = PAPER_CONFIGS)]
    pub configs: Vec<String>,
    /// Gyro: table rate magnitudes (deg/s), each run forward and reverse.
    #[arg(long, value_delimiter = ',', default_value = "20,30,40")]
    pub rates_deg_s: Vec<f64>,
    /// Gyro: fit one bias per configuration.
    #[arg(long)]
    pub per_config_bias: bool,
    /// Accelerometer: angles beta (deg), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,90,180,270",
        allow_hyphen_values = true
    )]
    pub betas_deg: Vec<f64>,
    /// Samples (rows: record means or single readings) per position.
    #[arg(long = "samples", visible_alias = "readings", default_value_t = 1)]
    pub samples: usize,
    /// Scale factor kI (gyro: output per deg/s; accelerometer: output per g).
    #[arg(long, visible_alias = "k1", allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Standard deviation of one reading (output units).
    #[arg(long)]
    pub noise: f64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan misalign`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let gyro = a.instrument == Instrument::Gyro;
    let options = MisalignPlan {
        instrument: match a.instrument {
            Instrument::Gyro => PlanInstrument::Gyro,
            Instrument::Accel => PlanInstrument::Accel,
        },
        configs: if gyro {
            Some(parse_configs(&a.configs)?)
        } else {
            None
        },
        rates_deg_s: Some(a.rates_deg_s.clone()),
        per_config_bias: Some(a.per_config_bias),
        betas_deg: Some(a.betas_deg.clone()),
        samples: a.samples,
        scale_factor: a.scale_factor,
        noise: a.noise,
    };
    let doc = if gyro {
        <MisalignGyro as Plan>::plan(&options)
    } else {
        <MisalignAccel as Plan>::plan(&options)
    };
    a.out.emit(&doc.map_err(core)?)
}

/// Options of `incal simulate misalign gyro`.
#[derive(clap::Args, Debug)]
pub struct SimGyroArgs {
    /// Scale factor kI (output per deg/s).
    #[arg(long, default_value_t = -2.9222, allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Bias V0 (output).
    #[arg(long, default_value_t = 0.002, allow_hyphen_values = true)]
    pub bias: f64,
    /// Standard deviation of the bias shift per configuration (output).
    #[arg(long, default_value_t = 0.0)]
    pub bias_shift: f64,
    /// True table-face angle about x (arcsec).
    #[arg(long, default_value_t = 2.4, allow_hyphen_values = true)]
    pub dtheta_x0_arcsec: f64,
    /// True table-face angle about y (arcsec).
    #[arg(long, default_value_t = -7.5, allow_hyphen_values = true)]
    pub dtheta_y0_arcsec: f64,
    /// True fixture-face angle about y (arcsec).
    #[arg(long, default_value_t = -54.0, allow_hyphen_values = true)]
    pub dtheta_y1_arcsec: f64,
    /// True fixture-face angle about z (arcsec; second order, not estimable).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub dtheta_z1_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    #[arg(long, default_value_t = -162.2, allow_hyphen_values = true)]
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    #[arg(long, default_value_t = 55.8, allow_hyphen_values = true)]
    pub dtheta_z2_arcsec: f64,
    /// Configurations ALPHA:BETA (deg), comma separated.
    #[arg(long, value_delimiter = ',', default_value = PAPER_CONFIGS)]
    pub configs: Vec<String>,
    /// Table rate magnitudes (deg/s); each is run forward then reverse.
    #[arg(long, value_delimiter = ',', default_value = "20,30,40")]
    pub rates_deg_s: Vec<f64>,
    /// Records per configuration and signed rate.
    #[arg(long, default_value_t = 2)]
    pub records: usize,
    /// Table revolutions per record (a non-whole number shows the Earth-rate error).
    #[arg(long, default_value_t = 1.0)]
    pub turns: f64,
    /// Samples per revolution.
    #[arg(long, default_value_t = 36)]
    pub samples_per_turn: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 1e-3)]
    pub noise: f64,
    /// Latitude (deg), for the Earth rate.
    #[arg(long, default_value_t = 45.75, allow_hyphen_values = true)]
    pub latitude_deg: f64,
    /// Write raw records (time_s, table_angle_deg per sample) instead of record means.
    #[arg(long)]
    pub time_series: bool,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate misalign gyro|accel`: the arguments into the core's
/// simulator options, run by [`crate::run::simulate`].
pub fn simulate(c: &SimCommand) -> CliResult<()> {
    match c {
        SimCommand::Gyro(a) => {
            let options = GyroSimOptions {
                scale_factor: a.scale_factor,
                bias: a.bias,
                bias_shift: a.bias_shift,
                dtheta_x0_arcsec: a.dtheta_x0_arcsec,
                dtheta_y0_arcsec: a.dtheta_y0_arcsec,
                dtheta_y1_arcsec: a.dtheta_y1_arcsec,
                dtheta_z1_arcsec: a.dtheta_z1_arcsec,
                dtheta_y2_arcsec: a.dtheta_y2_arcsec,
                dtheta_z2_arcsec: a.dtheta_z2_arcsec,
                configs: parse_configs(&a.configs)?,
                rates_deg_s: a.rates_deg_s.clone(),
                records: a.records,
                turns: a.turns,
                samples_per_turn: a.samples_per_turn,
                noise: a.noise,
                latitude_deg: a.latitude_deg,
                time_series: a.time_series,
                seed: a.seed,
            };
            crate::run::simulate::<MisalignGyro>(&options, a.output.as_deref())
        }
        SimCommand::Accel(a) => {
            let options = AccelSimOptions {
                scale_factor: a.scale_factor,
                bias: a.bias,
                dtheta_y0_arcsec: a.dtheta_y0_arcsec,
                dtheta_y2_arcsec: a.dtheta_y2_arcsec,
                dtheta_z2_arcsec: a.dtheta_z2_arcsec,
                betas_deg: a.betas_deg.clone(),
                samples: a.samples,
                noise: a.noise,
                seed: a.seed,
            };
            crate::run::simulate::<MisalignAccel>(&options, a.output.as_deref())
        }
    }
}

/// Options of `incal simulate misalign accel`.
#[derive(clap::Args, Debug)]
pub struct SimAccelArgs {
    /// Scale factor kI (output per g).
    #[arg(long, default_value_t = 1.299, allow_hyphen_values = true)]
    pub scale_factor: f64,
    /// Bias V0 (output).
    #[arg(long, default_value_t = -0.002, allow_hyphen_values = true)]
    pub bias: f64,
    /// True verticality error of the face, about y (arcsec).
    #[arg(long, default_value_t = 30.0, allow_hyphen_values = true)]
    pub dtheta_y0_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    #[arg(long, default_value_t = -5.3, allow_hyphen_values = true)]
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    #[arg(long, default_value_t = 20.5, allow_hyphen_values = true)]
    pub dtheta_z2_arcsec: f64,
    /// Angles beta (deg), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0,90,180,270",
        allow_hyphen_values = true
    )]
    pub betas_deg: Vec<f64>,
    /// Samples per angle.
    #[arg(long, default_value_t = 10)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 2e-5)]
    pub noise: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Misalignment separation: gyro on a rate table, accelerometer on a vertical face (Li et al. 2012).
    #[command(subcommand)]
    Misalign(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Misalign(c) => run(c),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Misalignment plan: predicted u of each angle for a configuration set.
    Misalign(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Misalign(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Misalignment test: gyro on a rate table or accelerometer on a vertical face.
    #[command(subcommand)]
    Misalign(SimCommand),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Misalign(c) => simulate(c),
        }
    }
}
