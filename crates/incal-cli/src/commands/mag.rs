//! `incal mag` (magnetometer calibration), `incal mag apply`, `incal mag
//! export`, and its plan and simulator (`incal plan|simulate mag`).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::mag::apply::{parameters, write_parameters, FlightStack, MagCalibration};
use incal::procedures::mag::plan::MagPlanOptions;
use incal::procedures::mag::sim::{MagSimOptions, Motion};
use incal::procedures::mag::{Mag, MagOptions, MagUnit};
use incal::procedures::{Plan, Silent};

use crate::error::{core, in_file, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// The magnetometer's raw unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum UnitArg {
    /// Microtesla.
    Ut,
    /// Nanotesla.
    Nt,
    /// Gauss (100 uT).
    Gauss,
    /// Milligauss (0.1 uT).
    Mgauss,
    /// Raw counts (no comparison with the local field, no export).
    Counts,
}

impl From<UnitArg> for MagUnit {
    fn from(u: UnitArg) -> MagUnit {
        match u {
            UnitArg::Ut => MagUnit::Ut,
            UnitArg::Nt => MagUnit::Nt,
            UnitArg::Gauss => MagUnit::Gauss,
            UnitArg::Mgauss => MagUnit::Mgauss,
            UnitArg::Counts => MagUnit::Counts,
        }
    }
}

/// How the simulated unit is turned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MotionArg {
    /// Uniformly random orientations.
    Random,
    /// Turned about the vertical only, level.
    Planar,
}

impl From<MotionArg> for Motion {
    fn from(m: MotionArg) -> Motion {
        match m {
            MotionArg::Random => Motion::Random,
            MotionArg::Planar => Motion::Planar,
        }
    }
}

/// `incal mag`: calibrate, or one of its tools.
#[derive(clap::Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct MagArgs {
    /// Session turned through many orientations: `mag_x,mag_y,mag_z`, optional `acc_x,acc_y,acc_z` (the alignment and inclination), `gyr_x,gyr_y,gyr_z` (rows at rest, with --max-rate) and `time_s`.
    #[arg(long, required = true)]
    pub input: Option<PathBuf>,
    /// The local field's magnitude, uT (e.g. from the World Magnetic Model at the site): the calibrated field's magnitude; without it the soft iron keeps the sensor's mean scale (determinant 1).
    #[arg(long)]
    pub field_ut: Option<f64>,
    /// Standard uncertainty of --field-ut, uT.
    #[arg(long, default_value_t = 0.0)]
    pub u_field_ut: f64,
    /// The local inclination, degrees (down positive), compared with the fitted one.
    #[arg(long, allow_negative_numbers = true)]
    pub inclination_deg: Option<f64>,
    /// Standard uncertainty of --inclination-deg, degrees.
    #[arg(long, default_value_t = 0.0)]
    pub u_inclination_deg: f64,
    /// The magnetometer's raw unit.
    #[arg(long, value_enum, default_value = "ut")]
    pub unit: UnitArg,
    /// The magnetometer's axes from the file's columns, e.g. y,x,-z (an AK8963 beside its MPU-9250's accelerometer).
    #[arg(long, default_value = "x,y,z", allow_hyphen_values = true)]
    pub axes: String,
    /// Do not fit the alignment to the accelerometer.
    #[arg(long)]
    pub no_alignment: bool,
    /// A row is at rest when |f| is within this fraction of its median.
    #[arg(long, default_value_t = 0.02)]
    pub static_tolerance: f64,
    /// With gyro columns, a row is at rest only when |w| is at most this (gyro units).
    #[arg(long)]
    pub max_rate: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
    #[command(subcommand)]
    pub tool: Option<Tool>,
}

/// The tools of `incal mag`.
#[derive(Subcommand, Debug)]
pub enum Tool {
    /// Correct a raw series with a calibration: mag_x, mag_y, mag_z calibrated row by row, every other column copied.
    Apply(ApplyArgs),
    /// Write a calibration as flight-stack parameters (PX4 CAL_MAG<n>_*, ArduPilot COMPASS_*).
    Export(ExportArgs),
}

/// `incal mag apply`.
#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// Calibration: a result of incal mag (JSON).
    #[arg(long)]
    pub calibration: PathBuf,
    /// Raw CSV with mag_x, mag_y, mag_z (read and written row by row; - reads standard input).
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Write the calibrated CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// The flight stack of an export.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum StackArg {
    /// PX4: CAL_MAG<n>_{X,Y,Z}OFF (gauss), _{X,Y,Z}SCALE, _{X,Y,Z}ODIAG; QGroundControl parameter file.
    Px4,
    /// ArduPilot: COMPASS_OFS_* (milligauss), COMPASS_DIA_*, COMPASS_ODI_*, COMPASS_SCALE; Mission Planner parameter file.
    Ardupilot,
}

/// `incal mag export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Calibration: a result of incal mag (JSON).
    #[arg(long)]
    pub calibration: PathBuf,
    /// The flight stack.
    #[arg(long, value_enum)]
    pub to: StackArg,
    /// The compass instance (PX4 CAL_MAG<n>; ArduPilot 0 is COMPASS_, 1 is COMPASS2_, ...).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=3))]
    pub instance: u8,
    /// Write the parameter file here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal mag`.
pub fn run(a: &MagArgs) -> CliResult<()> {
    match &a.tool {
        Some(Tool::Apply(t)) => return apply(t),
        Some(Tool::Export(t)) => return export(t),
        None => {}
    }
    let input = a
        .input
        .as_ref()
        .ok_or_else(|| crate::error::usage("--input: a session to calibrate is needed"))?;
    let options = MagOptions {
        field_ut: a.field_ut,
        u_field_ut: a.u_field_ut,
        inclination_deg: a.inclination_deg,
        u_inclination_deg: a.u_inclination_deg,
        unit: a.unit.into(),
        axes: a.axes.clone(),
        // The input layer's --full-scale: for mag, a reading at or beyond
        // it is saturated and refused.
        full_scale: a.read.full_scale,
        no_alignment: a.no_alignment,
        static_tolerance: a.static_tolerance,
        max_rate: a.max_rate,
    };
    crate::run::reduce::<Mag>(input, &a.read, &options, &a.result, &Silent)
}

fn calibration(path: &std::path::Path) -> CliResult<MagCalibration> {
    let (name, _, doc) = crate::documents::read_document(path)?;
    MagCalibration::from_document(&doc).map_err(|e| in_file(&name, e))
}

/// `incal mag apply`: the calibration read by the core, the series read
/// and written row by row.
pub fn apply(a: &ApplyArgs) -> CliResult<()> {
    use incal::procedures::mag::apply::Apply;
    let cal = calibration(&a.calibration)?;
    let read = incal_io::ReadOptions {
        hash: false,
        ..a.read.options()?
    };
    let done = crate::run::stream::<Apply>(cal, &a.input, &read, a.output.as_deref())?;
    crate::run::show_streamed(&done);
    Ok(())
}

/// `incal mag export`.
pub fn export(a: &ExportArgs) -> CliResult<()> {
    let cal = calibration(&a.calibration)?;
    let stack = match a.to {
        StackArg::Px4 => FlightStack::Px4,
        StackArg::Ardupilot => FlightStack::Ardupilot,
    };
    let name = a.calibration.display().to_string();
    let params = parameters(&cal, stack, a.instance as usize).map_err(|e| in_file(&name, e))?;
    let mut text = Vec::new();
    write_parameters(stack, &params, &mut text).map_err(core)?;
    crate::io::write_text(a.output.as_deref(), &String::from_utf8_lossy(&text))
}

/// A magnetometer session: orientations, noise and field.
#[derive(clap::Args, Debug, Clone)]
pub struct SessionArgs {
    /// Orientations held.
    #[arg(long, default_value_t = 36)]
    pub orientations: usize,
    /// Seconds held in each.
    #[arg(long, default_value_t = 2.0)]
    pub dwell_s: f64,
    /// Seconds moving between two.
    #[arg(long, default_value_t = 1.0)]
    pub move_s: f64,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 50.0)]
    pub rate_hz: f64,
    /// How the unit is turned.
    #[arg(long, value_enum, default_value = "random")]
    pub motion: MotionArg,
    /// The local field, uT.
    #[arg(long, default_value_t = 50.0)]
    pub field_ut: f64,
    /// The local inclination, degrees.
    #[arg(long, default_value_t = 60.0, allow_negative_numbers = true)]
    pub inclination_deg: f64,
    /// White noise per axis, uT.
    #[arg(long, default_value_t = 0.3)]
    pub noise_ut: f64,
    /// Gauss-Markov noise sigma per axis, uT.
    #[arg(long, default_value_t = 0.0)]
    pub gm_ut: f64,
    /// Gauss-Markov correlation time, s.
    #[arg(long, default_value_t = 1.0)]
    pub gm_tau_s: f64,
    /// Leave the accelerometer out.
    #[arg(long)]
    pub no_accelerometer: bool,
    /// Accelerometer white noise, m/s^2.
    #[arg(long, default_value_t = 0.02)]
    pub acc_noise: f64,
}

/// `incal plan mag`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Seed of the first of the simulated sessions the prediction reduces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan mag`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let s = &a.session;
    let options = MagPlanOptions {
        orientations: s.orientations,
        dwell_s: s.dwell_s,
        move_s: s.move_s,
        rate_hz: s.rate_hz,
        motion: s.motion.into(),
        field_ut: s.field_ut,
        inclination_deg: s.inclination_deg,
        noise_ut: s.noise_ut,
        gm_ut: s.gm_ut,
        gm_tau_s: s.gm_tau_s,
        no_accelerometer: s.no_accelerometer,
        acc_noise: s.acc_noise,
        seed: a.seed,
    };
    a.out.emit(&<Mag as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate mag`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Hard iron, x (raw units).
    #[arg(long, default_value_t = 12.0, allow_negative_numbers = true)]
    pub hard_iron_x: f64,
    /// Hard iron, y (raw units).
    #[arg(long, default_value_t = -8.0, allow_negative_numbers = true)]
    pub hard_iron_y: f64,
    /// Hard iron, z (raw units).
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    pub hard_iron_z: f64,
    /// Soft iron S, xx (dimensionless; S symmetric positive definite).
    #[arg(long, default_value_t = 1.05, allow_negative_numbers = true)]
    pub soft_iron_xx: f64,
    /// Soft iron S, yy.
    #[arg(long, default_value_t = 0.97, allow_negative_numbers = true)]
    pub soft_iron_yy: f64,
    /// Soft iron S, zz.
    #[arg(long, default_value_t = 1.02, allow_negative_numbers = true)]
    pub soft_iron_zz: f64,
    /// Soft iron S, xy.
    #[arg(long, default_value_t = 0.02, allow_negative_numbers = true)]
    pub soft_iron_xy: f64,
    /// Soft iron S, xz.
    #[arg(long, default_value_t = -0.015, allow_negative_numbers = true)]
    pub soft_iron_xz: f64,
    /// Soft iron S, yz.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub soft_iron_yz: f64,
    /// Alignment to the accelerometer, rotation vector x, degrees.
    #[arg(long, default_value_t = 1.5, allow_negative_numbers = true)]
    pub alignment_x_deg: f64,
    /// Alignment, rotation vector y, degrees.
    #[arg(long, default_value_t = -2.0, allow_negative_numbers = true)]
    pub alignment_y_deg: f64,
    /// Alignment, rotation vector z, degrees.
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    pub alignment_z_deg: f64,
    /// The raw unit written.
    #[arg(long, value_enum, default_value = "ut")]
    pub unit: UnitArg,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (hard and soft iron as incal mag reports them with --field-ut, alignment, inclination) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate mag`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let s = &a.session;
    let options = MagSimOptions {
        hard_iron_x: a.hard_iron_x,
        hard_iron_y: a.hard_iron_y,
        hard_iron_z: a.hard_iron_z,
        soft_iron_xx: a.soft_iron_xx,
        soft_iron_yy: a.soft_iron_yy,
        soft_iron_zz: a.soft_iron_zz,
        soft_iron_xy: a.soft_iron_xy,
        soft_iron_xz: a.soft_iron_xz,
        soft_iron_yz: a.soft_iron_yz,
        alignment_x_deg: a.alignment_x_deg,
        alignment_y_deg: a.alignment_y_deg,
        alignment_z_deg: a.alignment_z_deg,
        field_ut: s.field_ut,
        inclination_deg: s.inclination_deg,
        unit: a.unit.into(),
        orientations: s.orientations,
        dwell_s: s.dwell_s,
        move_s: s.move_s,
        rate_hz: s.rate_hz,
        motion: s.motion.into(),
        noise_ut: s.noise_ut,
        gm_ut: s.gm_ut,
        gm_tau_s: s.gm_tau_s,
        no_accelerometer: s.no_accelerometer,
        acc_noise: s.acc_noise,
        seed: a.seed,
    };
    crate::run::simulate::<Mag>(&options, a.output.as_deref())?;
    crate::run::write_truth::<Mag>(&options, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Magnetometer calibration: hard iron, soft iron, alignment to the accelerometer and inclination by a constrained ellipsoid fit, with u and correlations; `apply` and `export` (PX4, ArduPilot).
    Mag(MagArgs),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Mag(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
pub enum Plans {
    /// Magnetometer plan: predicted u of hard and soft iron, alignment and inclination for a session; refuses a session that cannot separate a term.
    Mag(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Mag(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
pub enum Simulations {
    /// A magnetometer and accelerometer turned through orientations with known hard and soft iron, alignment and noise; writes the input CSV of `incal mag`.
    Mag(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Mag(a) => simulate(a),
        }
    }
}
