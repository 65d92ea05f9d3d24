//! `incal imu ferraris|multipos|autocal|apply` and `incal simulate imu`:
//! IMU triad calibration (three accelerometers, three gyros).

use std::path::PathBuf;

use clap::Subcommand;
use incal::procedures::imu::apply::ImuCalibration;
use incal::procedures::imu::autocal::{Autocal, AutocalSessionOptions, Initial, Method};
use incal::procedures::imu::ferraris::{Convention, Ferraris, FerrarisOptions};
use incal::procedures::imu::multipos::{MatrixForm, Multipos, MultiposSessionOptions};
use incal::procedures::imu::sim::{ImuSimOptions, ImuSimulator, SequenceKind};
use incal::procedures::Silent;

use crate::error::{core, in_file, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// `incal imu …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Ferraris six-position + three-rotation calibration (imucal's method, keys and definitions) with the u of every element.
    Ferraris(FerrarisArgs),
    /// Autocalibration without a fixture (Tedaldi et al. 2014): still intervals found automatically, accelerometer and gyro triads in imu_tk's convention.
    Autocal(AutocalArgs),
    /// Least squares over known orientations (dividing head, cube): bias, scale and misalignment of both triads, gyro g-sensitivity; rotations of a known angle for the gyro scale.
    Multipos(MultiposArgs),
    /// Apply a calibration (any of the three) to a raw series, row by row: calibrated accelerometer (m/s^2) and gyro.
    Apply(ApplyArgs),
}

/// Options of `incal imu ferraris`.
#[derive(clap::Args, Debug)]
pub struct FerrarisArgs {
    /// Session CSV: part,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z (other columns ignored); part is one of x_p, x_a, y_p, y_a, z_p, z_a, x_rot, y_rot, z_rot, or empty for rows between sections; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz): integrates the rotations (default: the rate of the time_s stamps; needed without them).
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Gravity magnitude (m/s^2, > 0); its sign is --convention's.
    #[arg(long, default_value_t = incal::units::STANDARD_GRAVITY_M_S2, allow_hyphen_values = true)]
    pub gravity_m_s2: f64,
    /// Sign convention of the positions: standard (x_p reads +g) or imucal (the positive axis is the one reading -g: imucal's grav = -9.81).
    #[arg(long, value_enum, default_value = "standard")]
    pub convention: ConventionArg,
    /// Angle of each rotation section (deg); negative is clockwise seen from the axis tip (imucal's default -360).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    /// Standard uncertainty of the rotation angle (deg).
    #[arg(long, default_value_t = 0.0)]
    pub u_rotation_deg: f64,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// Sign convention of `incal imu ferraris`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ConventionArg {
    /// x_p: the positive x axis points up and the x accelerometer reads +g.
    Standard,
    /// The positive axis is the one along which the accelerometer reads -g (imucal with grav = -9.81).
    Imucal,
}

/// `incal imu ferraris`.
pub fn run_ferraris(a: &FerrarisArgs) -> CliResult<()> {
    let options = FerrarisOptions {
        rate_hz: a.rate_hz,
        gravity_m_s2: a.gravity_m_s2,
        convention: match a.convention {
            ConventionArg::Standard => Convention::Standard,
            ConventionArg::Imucal => Convention::Imucal,
        },
        rotation_deg: a.rotation_deg,
        u_rotation_deg: a.u_rotation_deg,
    };
    crate::run::reduce::<Ferraris>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// Autocalibration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// incal's weighted least squares with the covariance of every parameter.
    Incal,
    /// imu_tk's exact steps (Tedaldi et al. 2014), for comparison.
    Tedaldi,
}

/// Options of `incal imu autocal`.
#[derive(clap::Args, Debug)]
pub struct AutocalArgs {
    /// Record CSV: time_s (optional),acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z], raw counts or physical units; starts still; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz); the time_s column, when present, gives the time steps instead (default: the stamps' rate; needed without them).
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Gravity magnitude (m/s^2): the calibrated accelerometer output is in this unit.
    #[arg(long, default_value_t = incal::units::STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Duration of the still start (s): its variance sets the static threshold, its gyro mean the gyro bias.
    #[arg(long, default_value_t = 50.0)]
    pub init_static_s: f64,
    /// incal (weighted, with covariance) or tedaldi (imu_tk's exact steps).
    #[arg(long, value_enum, default_value = "incal")]
    pub method: MethodArg,
    /// Time trimmed from both ends of every still interval (s; method incal).
    #[arg(long, default_value_t = 0.1)]
    pub settle_s: f64,
    /// Put rows that are out of time order in order by time_s instead of refusing them (warning time-sorted counts the rows moved).
    #[arg(long)]
    pub sort_time: bool,
    /// Initial accelerometer bias (raw units): one value for all axes or X,Y,Z (e.g. 32768 for offset 16-bit counts); default: from the data.
    #[arg(
        long,
        value_name = "B",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub init_acc_bias: Option<Vec<f64>>,
    /// Initial accelerometer scale (m/s^2 per raw unit): one value or X,Y,Z; default: from the data.
    #[arg(
        long,
        value_name = "S",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub init_acc_scale: Option<Vec<f64>>,
    /// Initial gyro scale (rad/s per raw unit): one value or X,Y,Z (e.g. 0.000159795 for 1/6258); default: from the data.
    #[arg(
        long,
        value_name = "S",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub init_gyro_scale: Option<Vec<f64>>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal imu autocal`.
pub fn run_autocal(a: &AutocalArgs) -> CliResult<()> {
    let options = AutocalSessionOptions {
        rate_hz: a.rate_hz,
        method: match a.method {
            MethodArg::Incal => Method::Incal,
            MethodArg::Tedaldi => Method::Tedaldi,
        },
        gravity_m_s2: a.gravity_m_s2,
        init_static_s: a.init_static_s,
        settle_s: a.settle_s,
        init: Initial {
            acc_bias: triple("--init-acc-bias", &a.init_acc_bias)?,
            acc_scale: triple("--init-acc-scale", &a.init_acc_scale)?,
            gyro_scale: triple("--init-gyro-scale", &a.init_gyro_scale)?,
        },
        sort_time: a.sort_time,
        ..AutocalSessionOptions::new(100.0, Method::Incal)
    };
    crate::run::reduce::<Autocal>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// One value for the three axes, or one per axis.
fn triple(flag: &str, v: &Option<Vec<f64>>) -> CliResult<Option<[f64; 3]>> {
    match v.as_deref() {
        None => Ok(None),
        Some(&[x]) => Ok(Some([x; 3])),
        Some(&[x, y, z]) => Ok(Some([x, y, z])),
        Some(other) => Err(crate::error::usage(format!(
            "{flag} takes one value or three (X,Y,Z), not {}",
            other.len()
        ))),
    }
}

/// Session sequence of `incal simulate imu`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SequenceArg {
    /// imucal's nine labelled sections (input of `incal imu ferraris`).
    Ferraris,
    /// A still start, then random orientations joined by rotations (input of `incal imu autocal`).
    Random,
    /// As random, but every turn is 90 deg about a sensor axis: the six faces of a cube visited again and again (a hand-held session).
    Faces,
    /// Static positions with their labels and fx,fy,fz (input of `incal imu multipos`).
    Positions,
}

/// Options of `incal simulate imu`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// ferraris, random, faces or positions.
    #[arg(long, value_enum, default_value = "ferraris")]
    pub sequence: SequenceArg,
    #[command(flatten)]
    pub session: SessionArgs,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write the truth (imucal's, imu_tk's and the sensor model's parameters) as JSON here.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
}

/// The session of `incal simulate imu` and of the IMU plans: rig, timing,
/// sensor and noise.
#[derive(clap::Args, Debug)]
pub struct SessionArgs {
    /// Sample rate (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
    /// Duration of every static position (s).
    #[arg(long, default_value_t = 3.0)]
    pub static_s: f64,
    /// Random: orientations after the still start.
    #[arg(long, default_value_t = 30)]
    pub orientations: usize,
    /// Random: duration of the still start (s).
    #[arg(long, default_value_t = 50.0)]
    pub init_static_s: f64,
    /// Random: duration of each rotation between orientations (s).
    #[arg(long, default_value_t = 1.5)]
    pub move_s: f64,
    /// Positions: labels, comma separated (faces x_p..z_a, edges and corners as x_p+y_a, x_p+y_p+z_a).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "x_p,x_a,y_p,y_a,z_p,z_a,x_p+y_p,x_p+y_a,x_a+y_p,x_a+y_a,x_p+z_p,x_p+z_a,x_a+z_p,x_a+z_a,y_p+z_p,y_p+z_a,y_a+z_p,y_a+z_a"
    )]
    pub positions: Vec<String>,
    /// Positions: append the rotations x_rot, y_rot, z_rot (--rotation-deg, --rotation-s) for the gyro scale.
    #[arg(long)]
    pub rotations: bool,
    /// Ferraris and positions: angle of each rotation (deg; imucal's sign: -360 is clockwise seen from the tip).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    /// Ferraris: duration of each rotation (s).
    #[arg(long, default_value_t = 6.0)]
    pub rotation_s: f64,
    /// Gravity (m/s^2).
    #[arg(long, default_value_t = incal::units::STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Accelerometer white noise, one sample (output units).
    #[arg(long, default_value_t = 3.0)]
    pub noise_acc: f64,
    /// Gyro white noise, one sample (output units).
    #[arg(long, default_value_t = 2.0)]
    pub noise_gyr: f64,
    /// Latitude (deg): adds the Earth rate (positions also get the north direction nx,ny,nz).
    #[arg(long, allow_hyphen_values = true)]
    pub latitude_deg: Option<f64>,
    /// Sensor: 0 is a typical MEMS IMU in counts; any other number draws scales, biases, misalignments and g-sensitivity around it with that seed.
    #[arg(long, default_value_t = 0)]
    pub truth_seed: u64,
    /// No gyro g-sensitivity (K_ga = 0), as the autocalibration model assumes.
    #[arg(long)]
    pub no_g_sensitivity: bool,
    /// Random seed of the noise and the orientations.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl SessionArgs {
    /// The simulator's options for `sequence`.
    fn options(&self, sequence: SequenceKind) -> ImuSimOptions {
        ImuSimOptions {
            sequence,
            rate_hz: self.rate_hz,
            static_s: self.static_s,
            orientations: self.orientations,
            init_static_s: self.init_static_s,
            move_s: self.move_s,
            positions: self.positions.clone(),
            rotations: self.rotations,
            rotation_deg: self.rotation_deg,
            rotation_s: self.rotation_s,
            gravity_m_s2: self.gravity_m_s2,
            noise_acc: self.noise_acc,
            noise_gyr: self.noise_gyr,
            latitude_deg: self.latitude_deg,
            truth_seed: self.truth_seed,
            no_g_sensitivity: self.no_g_sensitivity,
            seed: self.seed,
        }
    }
}

/// Options of `incal plan imu-ferraris`, `imu-multipos` and `imu-autocal`:
/// the planned session (its sequence is the procedure's) and the seeds.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Sessions simulated and reduced (seeds --seed, --seed + 1, …): the predicted u is the root mean square of their u.
    #[arg(long, default_value_t = 5)]
    pub seeds: usize,
    #[command(flatten)]
    pub out: PlanOut,
}

/// A plan by simulation of procedure `P` ([`incal::procedures::sim_plan`]):
/// the session as given, the procedure's sequence and the reduction's
/// options derived from it by the core.
fn plan_by_simulation<P: incal::procedures::sim_plan::Planned<ImuSimulator>>(
    a: &PlanArgs,
) -> CliResult<()>
where
    P::Options: Clone,
{
    use incal::procedures::sim_plan::{BySimulation, SimPlanOptions};
    use incal::procedures::Plan;
    let o = SimPlanOptions {
        session: a.session.options(SequenceKind::default()),
        reduce: None,
        seeds: a.seeds,
    };
    a.out
        .emit(&BySimulation::<P, ImuSimulator>::plan(&o).map_err(core)?)
}

/// `incal plan imu-ferraris`.
pub fn plan_ferraris(a: &PlanArgs) -> CliResult<()> {
    plan_by_simulation::<incal::procedures::imu::ferraris::Ferraris>(a)
}

/// `incal plan imu-multipos`.
pub fn plan_multipos(a: &PlanArgs) -> CliResult<()> {
    plan_by_simulation::<incal::procedures::imu::multipos::Multipos>(a)
}

/// `incal plan imu-autocal`.
pub fn plan_autocal(a: &PlanArgs) -> CliResult<()> {
    plan_by_simulation::<incal::procedures::imu::autocal::Autocal>(a)
}

/// `incal simulate imu`: the core's simulator (`ImuSimulator`) with the
/// options as given; the truth as JSON when asked.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let o = a.session.options(match a.sequence {
        SequenceArg::Ferraris => SequenceKind::Ferraris,
        SequenceArg::Random => SequenceKind::Random,
        SequenceArg::Faces => SequenceKind::Faces,
        SequenceArg::Positions => SequenceKind::Positions,
    });
    crate::run::simulate::<ImuSimulator>(&o, a.output.as_deref())?;
    crate::run::write_truth::<ImuSimulator>(&o, a.truth_out.as_deref())
}

/// Accelerometer matrix convention of `incal imu multipos`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MatrixArg {
    /// All nine elements (the fixture defines the IMU frame).
    Full,
    /// Upper-triangular (the accelerometers define the IMU frame).
    Upper,
}

/// Options of `incal imu multipos`.
#[derive(clap::Args, Debug)]
pub struct MultiposArgs {
    /// Session CSV: position (a label: x_p, x_a, … or 2-3 of them joined by '+'; x_rot, y_rot, z_rot for rotations; empty between positions) and/or fx,fy,fz (unit up direction in the IMU frame), optional nx,ny,nz (north), acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z]; consecutive rows of one position are its samples; - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    /// Sample rate (Hz): times the rotations (default: the rate of the time_s stamps; needed without them).
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Gravity (m/s^2).
    #[arg(long, default_value_t = incal::units::STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Accelerometer matrix: full or upper (triangular).
    #[arg(long, value_enum, default_value = "full")]
    pub matrix: MatrixArg,
    /// Latitude (deg): the Earth rate becomes a known gyro input (needs nx,ny,nz).
    #[arg(long, allow_hyphen_values = true)]
    pub latitude_deg: Option<f64>,
    /// Angle of each rotation section (deg; -360 is clockwise seen from the axis tip).
    #[arg(long, default_value_t = -360.0, allow_hyphen_values = true)]
    pub rotation_deg: f64,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal imu multipos`.
pub fn run_multipos(a: &MultiposArgs) -> CliResult<()> {
    let options = MultiposSessionOptions {
        gravity_m_s2: a.gravity_m_s2,
        matrix: match a.matrix {
            MatrixArg::Full => MatrixForm::Full,
            MatrixArg::Upper => MatrixForm::Upper,
        },
        rate_hz: a.rate_hz,
        latitude_deg: a.latitude_deg,
        rotation_deg: a.rotation_deg,
    };
    crate::run::reduce::<Multipos>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// Options of `incal imu apply`.
#[derive(clap::Args, Debug)]
pub struct ApplyArgs {
    /// Calibration: a result of incal imu ferraris, multipos or autocal (JSON).
    #[arg(long)]
    pub calibration: PathBuf,
    /// Raw CSV: acc_x,acc_y,acc_z[,gyr_x,gyr_y,gyr_z], optional time_s (copied); read and written row by row (any length); - reads standard input.
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Write the calibrated CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Put rows that are out of time order in order by time_s instead of refusing them (holds the series in memory; warning time-sorted on standard error counts the rows moved).
    #[arg(long)]
    pub sort_time: bool,
}

/// `incal imu apply`: the calibration read from its document by the core,
/// the raw series read row by row through the input layer, every row
/// written as soon as it is calibrated (numbers in shortest round-trip
/// form).
pub fn run_apply(a: &ApplyArgs) -> CliResult<()> {
    use incal::procedures::imu::apply::{Apply, ApplyModel};
    let (cal_name, _, doc) = crate::documents::read_document(&a.calibration)?;
    let calibration = ImuCalibration::from_document(&doc).map_err(|e| in_file(&cal_name, e))?;
    let read = incal_io::ReadOptions {
        hash: false,
        ..a.read.options()?
    };
    let model = ApplyModel {
        calibration,
        sort_time: a.sort_time,
    };
    let done = crate::run::stream::<Apply>(model, &a.input, &read, a.output.as_deref())?;
    crate::run::show_streamed(&done);
    Ok(())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// IMU triad calibration: Ferraris (imucal), least squares over known orientations, autocalibration (Tedaldi / imu_tk), apply.
    #[command(subcommand)]
    Imu(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Imu(Command::Ferraris(a)) => run_ferraris(a),
            Self::Imu(Command::Autocal(a)) => run_autocal(a),
            Self::Imu(Command::Multipos(a)) => run_multipos(a),
            Self::Imu(Command::Apply(a)) => run_apply(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
#[allow(clippy::enum_variant_names)] // the command names: imu-ferraris, …
pub enum Plans {
    /// IMU Ferraris session plan: the session simulated and reduced with the given noise (a few seeds), the u the reduction will report for every element.
    ImuFerraris(PlanArgs),
    /// IMU multi-position session plan: the positions (and rotations) simulated and reduced with the given noise, the u of every element.
    ImuMultipos(PlanArgs),
    /// IMU autocalibration session plan: the random orientations simulated and reduced with the given noise, the u of every element.
    ImuAutocal(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::ImuFerraris(a) => plan_ferraris(a),
            Self::ImuMultipos(a) => plan_multipos(a),
            Self::ImuAutocal(a) => plan_autocal(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// IMU session (three accelerometers, three gyros): Ferraris sequence, random orientations or static positions.
    Imu(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Imu(a) => simulate(a),
        }
    }
}
