//! `incal gyro rate|positions`, `incal plan gyro-rate|gyro-positions`,
//! `incal simulate gyro-rate|gyro-positions` (IEEE Std 952 / 1431 / 517):
//! arguments into the core's options; reading, checks, reduction, plans
//! and simulators live in `incal::procedures::gyro`.

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::estimation::Noise;
use incal::procedures::gyro::positions::plan::PositionsPlanOptions;
use incal::procedures::gyro::positions::sim::GyroPositionsSimOptions;
use incal::procedures::gyro::positions::{
    self as gp, Axial, DriftTerm, GyroPositions, GyroPositionsOptions, K1Source,
};
use incal::procedures::gyro::rate::plan::RatePlanOptions;
use incal::procedures::gyro::rate::sim::GyroRateSimOptions;
use incal::procedures::gyro::rate::{self as gr, GyroRate, GyroRateOptions, InputAxis, RateTerm};
use incal::procedures::{Plan, Silent};

use crate::documents::read_document;
use crate::error::{core, usage, CliError, CliResult};
use crate::input::ReadArgs;
use crate::output::{input_file, PlanOut, ResultArgs};

/// `incal gyro …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Rate-transfer test on a rate table: scale factor K1, bias B, K2/K3, asymmetry, nonlinearity, repeatability.
    Rate(RateArgs),
    /// Multi-position test on a dividing head: bias and g-sensitive drift terms, Earth rate as the known input.
    Positions(PositionsArgs),
}

/// Input axis on the rate table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum IaArg {
    /// IA up, along the table's counter-clockwise rotation axis.
    Up,
    /// IA down.
    Down,
}

impl From<IaArg> for InputAxis {
    fn from(a: IaArg) -> InputAxis {
        match a {
            IaArg::Up => InputAxis::Up,
            IaArg::Down => InputAxis::Down,
        }
    }
}

/// Gyro axis along the head axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AxialArg {
    /// Spin axis along the head axis (the in-plane axis is OA).
    Sa,
    /// Output axis along the head axis (the in-plane axis is SA).
    Oa,
}

impl From<AxialArg> for Axial {
    fn from(a: AxialArg) -> Axial {
        match a {
            AxialArg::Sa => Axial::Sa,
            AxialArg::Oa => Axial::Oa,
        }
    }
}

fn rate_terms(list: &Option<Vec<String>>) -> CliResult<Vec<RateTerm>> {
    match list {
        None => Ok(gr::default_terms()),
        Some(v) => v
            .iter()
            .map(|s| RateTerm::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
            .collect(),
    }
}

fn drift_terms(list: &Option<Vec<String>>, axial: Axial) -> CliResult<Vec<DriftTerm>> {
    match list {
        None => Ok(gp::default_terms(axial)),
        Some(v) => v
            .iter()
            .map(|s| DriftTerm::parse(s).map_err(|e| usage(format!("--terms: {e}"))))
            .collect(),
    }
}

/// Options of `incal gyro rate`.
#[derive(clap::Args, Debug)]
pub struct RateArgs {
    /// Input CSV: rate_deg_s,output (optional run); rows with the same rate (and run) are samples; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Latitude of the rate table (deg, -90..90): the Earth rate's vertical component is an input.
    #[arg(long)]
    pub latitude_deg: f64,
    /// Input axis along the table axis, up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Terms, comma separated, from K1, B, K2, K3 (K1 always).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Relative standard uncertainty of the table rate (ppm), a type-B component of K1, B, K2, K3.
    #[arg(long, default_value_t = 0.0)]
    pub rate_uncertainty_ppm: f64,
    /// Largest nonlinearity over the input range, ppm of its full-scale output: the input range is found and rates beyond it are named and left out of the fit.
    #[arg(long)]
    pub linearity_ppm: Option<f64>,
    /// The output's limit (output units): a rate with a sample at or beyond it is clipped (default: rates at the record's extreme output).
    #[arg(long)]
    pub output_limit: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal gyro rate`.
pub fn run_rate(a: &RateArgs) -> CliResult<()> {
    let options = GyroRateOptions {
        latitude_deg: a.latitude_deg,
        ia: a.ia.into(),
        terms: rate_terms(&a.terms)?,
        noise: Noise::from_option(a.noise).map_err(core)?,
        rate_uncertainty_ppm: a.rate_uncertainty_ppm,
        linearity_ppm: a.linearity_ppm,
        output_limit: a.output_limit,
    };
    crate::run::reduce::<GyroRate>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// Options of `incal gyro positions`.
#[derive(clap::Args, Debug)]
pub struct PositionsArgs {
    /// Input CSV: angle_deg,output (optional azimuth_deg, overriding --azimuth-deg); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Latitude (deg, -90..90).
    #[arg(long)]
    pub latitude_deg: f64,
    /// Azimuth of the head axis (deg from north towards east); needed unless the CSV has azimuth_deg.
    #[arg(long)]
    pub azimuth_deg: Option<f64>,
    /// Gyro axis along the head axis: sa (spin axis; the in-plane axis is OA) or oa.
    #[arg(long, value_enum)]
    pub axial: AxialArg,
    /// Scale factor K1 (output/(deg/s)) from a rate test.
    #[arg(long, group = "k1_source")]
    pub k1: Option<f64>,
    /// Standard uncertainty of --k1 (output/(deg/s)).
    #[arg(long)]
    pub u_k1: Option<f64>,
    /// A gyro rate result (JSON) whose K1 (with u and dof) is used.
    #[arg(long = "from", group = "k1_source")]
    pub k1_from: Option<PathBuf>,
    /// Fit K1 from the Earth-rate projection (needs several azimuths).
    #[arg(long, group = "k1_source")]
    pub fit_k1: bool,
    /// Drift terms, comma separated, from B, D_I, D_O, D_S, D_II, D_IO, D_IS, D_OO, D_SS (default: B, D_I and D_O for sa or D_S for oa).
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal gyro positions`: K1 from `--k1`/`--u-k1`, `--fit-k1`, or
/// `--from` (a gyro-rate result, read here); the core checks the choice.
pub fn run_positions(a: &PositionsArgs) -> CliResult<()> {
    let axial: Axial = a.axial.into();
    let k1_from = match &a.k1_from {
        Some(p) => {
            let (name, sha, doc) = read_document(p)?;
            let record = input_file("from", &p.display().to_string(), sha, None);
            Some(
                K1Source::from_rate_result(&doc, record)
                    .map_err(|e| CliError::Input(format!("{name}: --from: {e}")))?,
            )
        }
        None => None,
    };
    let options = GyroPositionsOptions {
        latitude_deg: a.latitude_deg,
        azimuth_deg: a.azimuth_deg,
        axial,
        terms: drift_terms(&a.terms, axial)?,
        noise: Noise::from_option(a.noise).map_err(core)?,
        k1: a.k1,
        u_k1: a.u_k1,
        fit_k1: a.fit_k1,
        k1_from,
    };
    crate::run::reduce::<GyroPositions>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// Options of `incal plan gyro-rate`.
#[derive(clap::Args, Debug)]
pub struct PlanRateArgs {
    /// Table rates (deg/s), comma separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Nominal scale factor K1 (output/(deg/s)).
    #[arg(long)]
    pub k1: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 0.0)]
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Terms, comma separated, from K1, B, K2, K3.
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Relative standard uncertainty of the table rate (ppm).
    #[arg(long, default_value_t = 0.0)]
    pub rate_uncertainty_ppm: f64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan gyro-rate`.
pub fn plan_rate(a: &PlanRateArgs) -> CliResult<()> {
    let options = RatePlanOptions {
        rates_deg_s: a.rates_deg_s.clone(),
        samples: a.samples,
        noise: a.noise,
        k1: a.k1,
        latitude_deg: a.latitude_deg,
        ia: a.ia.into(),
        terms: rate_terms(&a.terms)?,
        rate_uncertainty_ppm: a.rate_uncertainty_ppm,
    };
    a.out
        .emit(&<GyroRate as Plan>::plan(&options).map_err(core)?)
}

/// Options of `incal plan gyro-positions`.
#[derive(clap::Args, Debug)]
pub struct PlanPositionsArgs {
    /// Head angles (deg), comma separated (default: 0, 30, ..., 330).
    #[arg(long, value_delimiter = ',')]
    pub angles_deg: Option<Vec<f64>>,
    /// Azimuths of the head axis (deg), comma separated; every angle at each.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub azimuths_deg: Vec<f64>,
    /// Latitude (deg).
    #[arg(long)]
    pub latitude_deg: f64,
    /// Gyro axis along the head axis.
    #[arg(long, value_enum, default_value = "sa")]
    pub axial: AxialArg,
    /// Drift terms, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub terms: Option<Vec<String>>,
    /// Nominal scale factor K1 (output/(deg/s)).
    #[arg(long)]
    pub k1: f64,
    /// Standard uncertainty of K1 (output/(deg/s)).
    #[arg(long, default_value_t = 0.0)]
    pub u_k1: f64,
    /// Predict with K1 fitted from the Earth-rate projection.
    #[arg(long)]
    pub fit_k1: bool,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Samples per position.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan gyro-positions`.
pub fn plan_positions(a: &PlanPositionsArgs) -> CliResult<()> {
    let axial: Axial = a.axial.into();
    let options = PositionsPlanOptions {
        angles_deg: a.angles_deg.clone().unwrap_or_else(gp::default_angles_deg),
        azimuths_deg: a.azimuths_deg.clone(),
        latitude_deg: a.latitude_deg,
        axial,
        terms: drift_terms(&a.terms, axial)?,
        k1: a.k1,
        u_k1: a.u_k1,
        fit_k1: a.fit_k1,
        noise: a.noise,
        samples: a.samples,
    };
    a.out
        .emit(&<GyroPositions as Plan>::plan(&options).map_err(core)?)
}

/// Options of `incal simulate gyro-rate`.
#[derive(clap::Args, Debug)]
pub struct SimRateArgs {
    /// Scale factor K1 (output/(deg/s)), the mean of K1+ and K1-.
    #[arg(long, default_value_t = 0.02)]
    pub k1: f64,
    /// Scale-factor asymmetry (K1+ - K1-)/K1 (ppm).
    #[arg(long, default_value_t = 0.0)]
    pub asymmetry_ppm: f64,
    /// Bias B (deg/h).
    #[arg(long, default_value_t = 5.0)]
    pub b_deg_h: f64,
    /// K2 (1/(deg/s)).
    #[arg(long, default_value_t = 0.0)]
    pub k2: f64,
    /// K3 (1/(deg/s)^2).
    #[arg(long, default_value_t = 0.0)]
    pub k3: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 45.0)]
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[arg(long, value_enum, default_value = "up")]
    pub ia: IaArg,
    /// Table rates (deg/s), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "-200,-100,-50,-10,-1,1,10,50,100,200"
    )]
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    #[arg(long, default_value_t = 20)]
    pub samples: usize,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 2e-5)]
    pub noise: f64,
    /// Runs (2 or more add a run column).
    #[arg(long, default_value_t = 1)]
    pub runs: usize,
    /// Run-to-run scatter of K1 (ppm, standard deviation).
    #[arg(long, default_value_t = 0.0)]
    pub run_scatter_ppm: f64,
    /// The output clips at plus or minus this (output units; 0: never).
    #[arg(long, default_value_t = 0.0)]
    pub clip: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate gyro-rate`.
pub fn simulate_rate_cmd(a: &SimRateArgs) -> CliResult<()> {
    let options = GyroRateSimOptions {
        k1: a.k1,
        asymmetry_ppm: a.asymmetry_ppm,
        b_deg_h: a.b_deg_h,
        k2: a.k2,
        k3: a.k3,
        latitude_deg: a.latitude_deg,
        ia: a.ia.into(),
        rates_deg_s: a.rates_deg_s.clone(),
        samples: a.samples,
        noise: a.noise,
        runs: a.runs,
        run_scatter_ppm: a.run_scatter_ppm,
        clip: a.clip,
        seed: a.seed,
    };
    crate::run::simulate::<GyroRate>(&options, a.output.as_deref())
}

/// Options of `incal simulate gyro-positions`.
#[derive(clap::Args, Debug)]
pub struct SimPositionsArgs {
    /// Scale factor K1 (output/(deg/s)).
    #[arg(long, default_value_t = 0.02)]
    pub k1: f64,
    /// Bias B (deg/h).
    #[arg(long, default_value_t = 3.0)]
    pub b_deg_h: f64,
    /// D_I (deg/h/g).
    #[arg(long, default_value_t = 0.8)]
    pub d_i_deg_h_g: f64,
    /// D_O (deg/h/g).
    #[arg(long, default_value_t = -0.5)]
    pub d_o_deg_h_g: f64,
    /// D_S (deg/h/g).
    #[arg(long, default_value_t = 0.4)]
    pub d_s_deg_h_g: f64,
    /// D_II (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_ii_deg_h_g2: f64,
    /// D_IO (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_io_deg_h_g2: f64,
    /// D_IS (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_is_deg_h_g2: f64,
    /// D_OO (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_oo_deg_h_g2: f64,
    /// D_SS (deg/h/g^2).
    #[arg(long, default_value_t = 0.0)]
    pub d_ss_deg_h_g2: f64,
    /// Latitude (deg).
    #[arg(long, default_value_t = 45.0)]
    pub latitude_deg: f64,
    /// Azimuths of the head axis (deg), comma separated; two or more add an azimuth_deg column.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub azimuths_deg: Vec<f64>,
    /// Gyro axis along the head axis.
    #[arg(long, value_enum, default_value = "sa")]
    pub axial: AxialArg,
    /// Head angles (deg), comma separated (default: 0, 30, ..., 330).
    #[arg(long, value_delimiter = ',')]
    pub angles_deg: Option<Vec<f64>>,
    /// Samples per position.
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

/// `incal simulate gyro-positions`.
pub fn simulate_positions_cmd(a: &SimPositionsArgs) -> CliResult<()> {
    let options = GyroPositionsSimOptions {
        k1: a.k1,
        b_deg_h: a.b_deg_h,
        d_i_deg_h_g: a.d_i_deg_h_g,
        d_o_deg_h_g: a.d_o_deg_h_g,
        d_s_deg_h_g: a.d_s_deg_h_g,
        d_ii_deg_h_g2: a.d_ii_deg_h_g2,
        d_io_deg_h_g2: a.d_io_deg_h_g2,
        d_is_deg_h_g2: a.d_is_deg_h_g2,
        d_oo_deg_h_g2: a.d_oo_deg_h_g2,
        d_ss_deg_h_g2: a.d_ss_deg_h_g2,
        latitude_deg: a.latitude_deg,
        azimuths_deg: a.azimuths_deg.clone(),
        axial: a.axial.into(),
        angles_deg: a.angles_deg.clone().unwrap_or_else(gp::default_angles_deg),
        samples: a.samples,
        noise: a.noise,
        seed: a.seed,
    };
    crate::run::simulate::<GyroPositions>(&options, a.output.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Gyro tests: rate-transfer test on a rate table, multi-position test on a dividing head (IEEE Std 952 / 1431 / 517).
    #[command(subcommand)]
    Gyro(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Gyro(Command::Rate(a)) => run_rate(a),
            Self::Gyro(Command::Positions(a)) => run_positions(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Gyro rate-transfer plan: predicted u of K1, B, K2, K3 and the asymmetry for a set of table rates.
    GyroRate(PlanRateArgs),
    /// Gyro multi-position plan: predicted u of every drift term for head angles and azimuths.
    GyroPositions(PlanPositionsArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::GyroRate(a) => plan_rate(a),
            Self::GyroPositions(a) => plan_positions(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Gyro rate-transfer test on a rate table; writes the input CSV of `incal gyro rate`.
    GyroRate(SimRateArgs),
    /// Gyro multi-position test on a dividing head; writes the input CSV of `incal gyro positions`.
    GyroPositions(SimPositionsArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::GyroRate(a) => simulate_rate_cmd(a),
            Self::GyroPositions(a) => simulate_positions_cmd(a),
        }
    }
}
