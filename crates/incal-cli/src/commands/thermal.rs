//! `incal thermal fit|ramp|apply`, `incal simulate thermal` and
//! `incal plan thermal`: arguments in, the core's
//! [`incal::procedures::thermal`] does the rest.

use std::path::PathBuf;

use incal::procedures::thermal::{
    self, apply, plan, ramp::Ramp, ramp::RampOptions, soak, Degree, Thermal,
};
use incal::procedures::{Plan, Silent};

use crate::commands::noise::QuantityArg;
use crate::documents::read_document;
use crate::error::{core, in_file, usage, CliResult};
use crate::input::ReadArgs;
use crate::output::ResultArgs;

/// `incal thermal …`.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Soak (plateau) calibration: result documents of one instrument and one procedure, each at its own temperature, into a polynomial in (T - T_ref) per coefficient (NAME.c0, NAME.c1, ...).
    Fit(FitArgs),
    /// Ramp calibration: a static recording with the sensor's temperature_c while the chamber heats and cools, into the bias polynomial of every channel, the hysteresis between the branches and the sensor's lag behind chamber_c.
    Ramp(RampArgs),
    /// Compensate raw data with its temperature_c column by a thermal model (temperature clamped to the valid range).
    Apply(ApplyArgs),
}

fn parse_degree(s: &str) -> Result<Degree, String> {
    Degree::parse(s)
}

/// `incal thermal fit`.
#[derive(clap::Args, Debug)]
pub struct FitArgs {
    /// Result documents (JSON) of one instrument and one procedure; each one's temperature is its instrument.temperature_c (--meta temperature_c=T) or the mean of its recording's temperature_c column.
    #[arg(value_name = "RESULT.json", required_unless_present = "db")]
    pub results: Vec<PathBuf>,
    /// Instead of files: the records store's calibrations of --serial (not superseded), of --procedure.
    #[arg(
        long,
        value_name = "PATH|URL",
        conflicts_with = "results",
        requires = "serial"
    )]
    pub db: Option<PathBuf>,
    /// With --db: the procedure whose records are fitted (needed when the serial has records of more than one).
    #[arg(long, requires = "db")]
    pub procedure: Option<String>,
    /// Reference temperature T_ref of the polynomials, degC.
    #[arg(long, default_value_t = thermal::DEFAULT_T_REF_C, allow_hyphen_values = true)]
    pub t_ref_c: f64,
    /// Degree of the polynomials: auto (the degree rule: the smallest degree whose lack-of-fit p >= 0.05, at most min(3, plateaus - 2)) or 0 to 3.
    #[arg(long, default_value = "auto", value_parser = parse_degree)]
    pub degree: Degree,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal thermal ramp`.
#[derive(clap::Args, Debug)]
pub struct RampArgs {
    /// Recording: CSV with temperature_c (the sensor's temperature, degC), optional chamber_c and time_s, and the channels (every other column, or --columns).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Sample rate, Hz (the time base when there is no time_s column; the block length in rows). Default: the rate of the time_s stamps, the blocks cut by time; needed without them.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// What the channels measure: their unit (gyro deg/s, accel g, generic 1).
    #[arg(long, value_enum, default_value = "generic")]
    pub quantity: QuantityArg,
    /// Reference temperature T_ref of the polynomials, degC.
    #[arg(long, default_value_t = thermal::DEFAULT_T_REF_C)]
    pub t_ref_c: f64,
    /// Degree of the polynomials: auto (the degree rule) or 0 to 3.
    #[arg(long, default_value = "auto", value_parser = parse_degree)]
    pub degree: Degree,
    /// Length of the blocks the rows are averaged in, s.
    #[arg(long, default_value_t = 10.0)]
    pub block_s: f64,
    /// Fit a dT/dt term as well (thermal.NAME.rate_term, in unit per degC/s).
    #[arg(long)]
    pub rate_term: bool,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal thermal apply`.
#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// The thermal model (a result of incal thermal ramp or fit, JSON).
    #[arg(value_name = "MODEL.json")]
    pub model: PathBuf,
    /// Raw data: CSV with temperature_c and columns named like the model's channels (- reads standard input).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Write the compensated CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal thermal`.
pub fn run(c: &Command) -> CliResult<()> {
    match c {
        Command::Fit(a) => run_fit(a),
        Command::Ramp(a) => {
            let o = RampOptions {
                rate_hz: a.rate_hz,
                quantity: a.quantity.into(),
                t_ref_c: a.t_ref_c,
                degree: a.degree,
                block_s: a.block_s,
                rate_term: a.rate_term,
            };
            crate::run::reduce::<Ramp>(&a.input, &a.read, &o, &a.result, &Silent)
        }
        Command::Apply(a) => run_apply(a),
    }
}

fn run_fit(a: &FitArgs) -> CliResult<()> {
    if a.result.monte_carlo.is_some() {
        // Refused before any input is read, never ignored.
        return Err(core(incal::Error::InvalidOption {
            key: "monte_carlo".into(),
            message: "thermal fit reduces result documents, not a recording: it draws no synthetic recordings (a Monte Carlo runs on each plateau's reduction)".into(),
        }));
    }
    let mut inputs = Vec::with_capacity(a.results.len());
    for p in &a.results {
        let (name, sha256, doc) = read_document(p)?;
        inputs.push(soak::SoakInput { name, sha256, doc });
    }
    if let Some(db) = &a.db {
        inputs = from_store(
            db,
            a.result.serial.as_deref().unwrap_or(""),
            a.procedure.as_deref(),
        )?;
    }
    let o = soak::SoakOptions {
        t_ref_c: a.t_ref_c,
        degree: a.degree,
    };
    let doc = soak::fit_documents(&inputs, &o).map_err(core)?;
    a.result.emit(doc)
}

/// The calibrations of `serial` in the store `db` (not superseded; of
/// `procedure` when given, which is needed when there are several), as
/// inputs named `record N` ([`incal_records::Store::current_calibrations`]).
fn from_store(
    db: &std::path::Path,
    serial: &str,
    procedure: Option<&str>,
) -> CliResult<Vec<soak::SoakInput>> {
    let (_, records) = crate::documents::store_calibrations(db, serial, procedure)?;
    Ok(records
        .into_iter()
        .map(|(rec, doc)| soak::SoakInput {
            name: format!("record {}", rec.id),
            sha256: rec.sha256,
            doc,
        })
        .collect())
}

fn run_apply(a: &ApplyArgs) -> CliResult<()> {
    let (name, _, doc) = read_document(&a.model)?;
    let model = thermal::Model::of(&doc).map_err(|e| in_file(&name, e))?;
    let read = incal_io::ReadOptions::default();
    let done = crate::run::stream::<apply::Compensate>(model, &a.input, &read, a.output.as_deref())?;
    crate::run::show_streamed(&done);
    Ok(())
}

/// `incal simulate thermal`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// What the channels measure: gyro (deg/s, channels gx,gy,gz) or accel (g, channels ax,ay,az).
    #[arg(long, value_enum, default_value = "gyro")]
    pub quantity: QuantityArg,
    /// Low temperature of the ramp profile (hold, heat, hold, cool, hold), degC.
    #[arg(long, default_value_t = -20.0)]
    pub t_low_c: f64,
    /// High temperature of the chamber profile, degC.
    #[arg(long, default_value_t = 60.0)]
    pub t_high_c: f64,
    /// A soak sequence instead of the ramp: the chamber's plateaus in order, degC, comma separated (e.g. -40,-10,25,60,85,25); each held --hold-s, moved between at --ramp-c-per-min.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["t_low_c", "t_high_c"])]
    pub plateaus_c: Option<Vec<f64>>,
    /// Ramp rate of the chamber, degC/min.
    #[arg(long, default_value_t = 1.0)]
    pub ramp_c_per_min: f64,
    /// Hold at the start, at the top and at the end, s.
    #[arg(long, default_value_t = 1800.0)]
    pub hold_s: f64,
    /// The sensor's first-order lag behind the chamber, s.
    #[arg(long, default_value_t = 120.0)]
    pub lag_s: f64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 10.0)]
    pub rate_hz: f64,
    /// Noise of the temperature reading, degC.
    #[arg(long, default_value_t = 0.0)]
    pub temperature_noise_c: f64,
    /// Reference temperature of the truth polynomials, degC.
    #[arg(long, default_value_t = thermal::DEFAULT_T_REF_C)]
    pub t_ref_c: f64,
    /// Random seed.
    #[arg(long)]
    pub seed: u64,
    /// Write the truth (polynomials, hysteresis, lag) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
}

/// `incal simulate thermal`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    use incal::procedures::thermal::sim::{SimQuantity, ThermalSimOptions};
    let options = ThermalSimOptions {
        quantity: match a.quantity {
            QuantityArg::Gyro => SimQuantity::Gyro,
            QuantityArg::Accel => SimQuantity::Accel,
            QuantityArg::Generic => return Err(usage("--quantity: gyro or accel")),
        },
        t_low_c: a.t_low_c,
        t_high_c: a.t_high_c,
        plateaus_c: a.plateaus_c.clone(),
        ramp_c_per_min: a.ramp_c_per_min,
        hold_s: a.hold_s,
        lag_s: a.lag_s,
        rate_hz: a.rate_hz,
        temperature_noise_c: a.temperature_noise_c,
        t_ref_c: a.t_ref_c,
        seed: a.seed,
    };
    crate::run::simulate::<Ramp>(&options, a.output.as_deref())?;
    crate::run::write_truth::<Ramp>(&options, a.truth_out.as_deref())
}

/// `incal plan thermal`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// Plateau temperatures, degC, comma separated (a soak plan; with --u).
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        required_unless_present = "ramp_c_per_min"
    )]
    pub plateaus_c: Option<Vec<f64>>,
    /// Standard uncertainty of the coefficient at one plateau (from the reduction's own plan), in its unit.
    #[arg(long, required_unless_present = "ramp_c_per_min")]
    pub u: Option<f64>,
    /// A ramp plan instead: the chamber's ramp rate, degC/min (with --t-low-c, --t-high-c, --hold-s, --lag-s, --rate-hz, --noise, --block-s).
    #[arg(long, conflicts_with_all = ["plateaus_c", "u"])]
    pub ramp_c_per_min: Option<f64>,
    /// Ramp plan: low temperature, degC.
    #[arg(long, default_value_t = -20.0, allow_hyphen_values = true)]
    pub t_low_c: f64,
    /// Ramp plan: high temperature, degC.
    #[arg(long, default_value_t = 60.0, allow_hyphen_values = true)]
    pub t_high_c: f64,
    /// Ramp plan: hold at each end, s.
    #[arg(long, default_value_t = 1800.0)]
    pub hold_s: f64,
    /// Ramp plan: the sensor's lag behind the chamber, s.
    #[arg(long, default_value_t = 120.0)]
    pub lag_s: f64,
    /// Ramp plan: sample rate, Hz.
    #[arg(long, default_value_t = 10.0)]
    pub rate_hz: f64,
    /// Ramp plan: white noise of one sample, in the channel's unit.
    #[arg(long)]
    pub noise: Option<f64>,
    /// Ramp plan: block length, s.
    #[arg(long, default_value_t = 10.0)]
    pub block_s: f64,
    /// Degree of the polynomial (0 to 3).
    #[arg(long)]
    pub degree: usize,
    /// Reference temperature T_ref, degC.
    #[arg(long, default_value_t = thermal::DEFAULT_T_REF_C, allow_hyphen_values = true)]
    pub t_ref_c: f64,
    #[command(flatten)]
    pub out: crate::output::PlanOut,
}

/// `incal plan thermal`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let o = plan::ThermalPlanOptions {
        plateaus_c: a.plateaus_c.clone(),
        u: a.u,
        ramp_c_per_min: a.ramp_c_per_min,
        t_low_c: a.t_low_c,
        t_high_c: a.t_high_c,
        hold_s: a.hold_s,
        lag_s: a.lag_s,
        rate_hz: a.rate_hz,
        noise: a.noise,
        block_s: a.block_s,
        degree: a.degree,
        t_ref_c: a.t_ref_c,
    };
    a.out.emit(&<Thermal as Plan>::plan(&o).map_err(core)?)
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Thermal calibration: coefficients as polynomials in temperature from soak plateaus (fit) or a chamber ramp (ramp), and compensation (apply).
    #[command(subcommand)]
    Thermal(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Thermal(c) => run(c),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Thermal plateau plan: predicted u of every polynomial coefficient for a set of plateau temperatures.
    Thermal(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Thermal(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Thermal chamber ramp (hold, heat, hold, cool, hold) with a lagging sensor whose biases follow known polynomials with hysteresis; writes the input CSV of `incal thermal ramp`.
    Thermal(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Thermal(a) => simulate(a),
        }
    }
}
