//! `incal gfimu calibrate`, `incal gfimu solve`, `incal plan gfimu` and
//! `incal simulate gfimu`: arguments into the core's options
//! ([`incal::procedures::gfimu`]); the core reads, reduces, solves,
//! plans and simulates.

use std::path::PathBuf;

use clap::ValueEnum;
use incal::estimation::Noise;
use incal::procedures::gfimu::input::{
    self, ArrayChoice, ArrayGeometry, GeometryFile, DEFAULT_LEVER_ARM_M,
};
use incal::procedures::gfimu::plan::GfimuPlanOptions;
use incal::procedures::gfimu::sim::six_positions;
use incal::procedures::gfimu::solve::Solver;
use incal::procedures::gfimu::stream::{SolutionFormat, Solve, SolveModel};
use incal::procedures::gfimu::{GfimuCalibrate, GfimuCalibrateOptions, SolveOptions};
use incal::procedures::{Plan, Procedure, Silent};
use incal::units::STANDARD_GRAVITY_M_S2;
use nalgebra::Vector3;

use crate::error::{core, usage, CliError, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// Geometry choice shared by every gfimu command.
#[derive(clap::Args, Debug, Clone)]
pub struct GeometryArgs {
    /// Array geometry file (TOML, [[accelerometer]] tables with name, position_m, direction).
    #[arg(long, conflicts_with = "lever_arm_m")]
    pub geometry: Option<PathBuf>,
    /// Lever arm L (m) of the built-in layout.
    #[arg(long)]
    pub lever_arm_m: Option<f64>,
    /// Built-in layout: paper (six: a, b at ±L on x sensing z; c, d on y sensing x; e, f on z sensing y) or twelve (two across each of ±L on x, y, z: px_y, px_z, mx_y, …; solves the centripetal products directly).
    #[arg(long, value_enum, default_value = "paper", conflicts_with = "geometry")]
    pub layout: Layout,
}

/// Built-in gyro-free layouts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Layout {
    /// The six accelerometers of the GFIMU note's Fig. 1.
    Paper,
    /// Twelve accelerometers, two across each lever arm.
    Twelve,
}

impl From<Layout> for input::Layout {
    fn from(l: Layout) -> Self {
        match l {
            Layout::Paper => input::Layout::Paper,
            Layout::Twelve => input::Layout::Twelve,
        }
    }
}

impl GeometryArgs {
    /// The array as the core's options name it: the geometry file (opened
    /// and hashed here, its text read by the core) or the built-in layout.
    pub fn choice(&self) -> CliResult<ArrayChoice> {
        let geometry = match &self.geometry {
            Some(p) => {
                let (name, bytes, sha) = crate::io::read_hashed(p)?;
                let toml = String::from_utf8(bytes)
                    .map_err(|_| usage(format!("{name}: not valid UTF-8")))?;
                Some(GeometryFile {
                    path: Some(p.display().to_string()),
                    name,
                    sha256: Some(sha),
                    toml,
                })
            }
            None => None,
        };
        Ok(ArrayChoice {
            geometry,
            layout: self.layout.into(),
            lever_arm_m: self.lever_arm_m,
        })
    }

    /// The array: the geometry file (opened here, read by the core) or
    /// the built-in layout; one that cannot solve the motion is refused.
    pub fn load(&self) -> CliResult<ArrayGeometry> {
        match &self.geometry {
            Some(p) => {
                let (name, bytes, sha) = crate::io::read_hashed(p)?;
                ArrayGeometry::from_toml(&name, &p.display().to_string(), &bytes, sha)
            }
            None => ArrayGeometry::builtin(
                self.layout.into(),
                self.lever_arm_m.unwrap_or(DEFAULT_LEVER_ARM_M),
            ),
        }
        .map_err(core)
    }
}

/// Options of `incal gfimu calibrate`.
#[derive(clap::Args, Debug)]
pub struct CalibrateArgs {
    /// Calibration CSV: position (+x, -x, +y, -y, +z, -z) or fx_g, fy_g, fz_g, and one column per accelerometer.
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// Options of `incal gfimu solve`.
#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// Calibration JSON written by `incal gfimu calibrate --json`.
    #[arg(long)]
    pub calibration: PathBuf,
    /// Time series CSV: time_s and one column per accelerometer.
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Angular rate at the first sample (rad/s), x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub omega0_rad_s: Vec<f64>,
    /// Local gravity that defines the g unit (m/s^2).
    #[arg(long, visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Predicted u of the integrated angular rate (rad/s) beyond which a warning is given.
    #[arg(long, default_value_t = 0.01)]
    pub omega_u_limit_rad_s: f64,
    /// Print one JSON object instead of CSV (streamed, like the CSV).
    #[arg(long, conflicts_with = "jsonl")]
    pub json: bool,
    /// Print JSON lines: one object per sample, then one summary object.
    #[arg(long)]
    pub jsonl: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// What `incal simulate gfimu` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SimKind {
    /// Six-position static test (input of `gfimu calibrate`).
    Static,
    /// Rate-table motion time series (input of `gfimu solve`).
    Motion,
}

/// Options of `incal simulate gfimu`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// static (six-position calibration test) or motion (time series).
    #[arg(long, value_enum, default_value = "static")]
    pub kind: SimKind,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Nominal scale factor of every accelerometer (output/g); truth K0, Ks are built from it.
    #[arg(long, default_value_t = 1.0)]
    pub k1: f64,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 1e-4)]
    pub noise: f64,
    /// Samples per static position.
    #[arg(long, default_value_t = 10)]
    pub samples: usize,
    /// Motion: record length (s).
    #[arg(long, default_value_t = 2.0)]
    pub duration_s: f64,
    /// Motion: sample rate (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
    /// Motion: spin-up duration with constant angular acceleration (s).
    #[arg(long, default_value_t = 1.005)]
    pub spin_up_s: f64,
    /// Motion: angular acceleration during spin-up (rad/s^2).
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub angular_accel_rad_s2: f64,
    /// Motion: rotation axis x,y,z (unit frame).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,1"
    )]
    pub axis: Vec<f64>,
    /// Motion: angular rate at t = 0 (rad/s), x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub omega0_rad_s: Vec<f64>,
    /// Motion: specific force at the origin (g), x,y,z (gravity along +z plus a constant acceleration).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0.05,0,1"
    )]
    pub f0_g: Vec<f64>,
    /// Motion: the frame --f0-g is fixed in: unit (does not turn) or table (given at t = 0, turns through the unit as it rotates).
    #[arg(long, value_enum, default_value = "unit")]
    pub f0_frame: F0FrameArg,
    /// Motion: amplitude of a sinusoidal rate oscillation about the axis (rad/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub oscillation_amplitude_rad_s: f64,
    /// Motion: frequency of the rate oscillation (Hz, below half the sample rate).
    #[arg(long, default_value_t = 0.0)]
    pub oscillation_hz: f64,
    /// Local gravity that defines the g unit (m/s^2).
    #[arg(long, visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write the truth (every accelerometer's K0 and Ks, and how the run was simulated) to this JSON file; the CSV holds only the header and the rows.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
}

/// Options of `incal plan gfimu`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Static positions, comma separated, from +x, -x, +y, -y, +z, -z (default: the six-position test).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub positions: Option<Vec<String>>,
    /// Samples per position.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Nominal scale factor of every accelerometer (output/g).
    #[arg(long, default_value_t = 1.0)]
    pub k1: f64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `--f0-frame`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum F0FrameArg {
    Unit,
    Table,
}

/// A vector option `x,y,z`.
fn vec3(opt: &str, v: &[f64]) -> CliResult<Vector3<f64>> {
    match v {
        [x, y, z] => Ok(Vector3::new(*x, *y, *z)),
        _ => Err(usage(format!(
            "{opt}: expected three numbers x,y,z, got {v:?}"
        ))),
    }
}

/// `incal gfimu calibrate`.
pub fn run_calibrate(a: &CalibrateArgs) -> CliResult<()> {
    let noise = Noise::from_option(a.noise).map_err(core)?;
    let options = GfimuCalibrateOptions {
        array: a.geometry.choice()?,
        noise,
    };
    // The array is checked before the recording is opened.
    GfimuCalibrate::validate(&options).map_err(core)?;
    crate::run::reduce::<GfimuCalibrate>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// `incal gfimu solve`: one row in, one row out, constant memory
/// ([`incal::procedures::gfimu::stream`]).
pub fn run_solve(a: &SolveArgs) -> CliResult<()> {
    let opts = SolveOptions {
        omega0_rad_s: vec3("--omega0-rad-s", &a.omega0_rad_s)?,
        gravity_m_s2: a.gravity_m_s2,
        omega_u_limit_rad_s: a.omega_u_limit_rad_s,
    };
    opts.validate().map_err(core)?;
    let array = a.geometry.load()?;
    let g = &array.geometry;
    // Everything about the calibration is checked before the series is read.
    let (cal_name, bytes) = crate::io::read_bytes(&a.calibration)?;
    let cal = input::read_calibration(&cal_name, &bytes, g).map_err(core)?;
    let solver = Solver::for_calibration(&cal_name, g, &cal, &opts).map_err(core)?;
    let format = if a.json {
        SolutionFormat::Json
    } else if a.jsonl {
        SolutionFormat::JsonLines
    } else {
        SolutionFormat::Csv
    };
    // The spill file lives (and is removed) here; the solver writes
    // through a second handle to it.
    let spill = match format {
        SolutionFormat::Json => Some(Spill::new()?),
        _ => None,
    };
    let scratch = match &spill {
        Some(s) => Some(Box::new(s.file.try_clone().map_err(|e| {
            CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", s.path.display()))
        })?) as Box<dyn incal::procedures::gfimu::stream::Scratch + Send>),
        None => None,
    };
    let model = SolveModel {
        solver,
        geometry: g.clone(),
        format,
        scratch,
    };
    let done = crate::run::stream::<Solve>(model, &a.input, &a.read.options()?, a.output.as_deref())?;
    // The CSV is rows only (pandas reads it as it is): its mode and
    // warnings go to standard error, as imu apply's do; a JSON output
    // holds them.
    if format == SolutionFormat::Csv {
        crate::run::show_streamed(&done);
    }
    drop(spill);
    Ok(())
}

/// A temporary file holding the JSON document's `"uncertainty"` array
/// while the samples stream out, so a long series needs no memory for it;
/// removed when dropped.
struct Spill {
    path: PathBuf,
    file: std::fs::File,
}

impl Spill {
    fn new() -> CliResult<Spill> {
        static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("incal-gfimu-u-{}-{n}.json", std::process::id()));
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .map_err(|e| {
                CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", path.display()))
            })?;
        Ok(Spill { path, file })
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// `incal simulate gfimu`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    use incal::procedures::gfimu::sim_options::{F0FrameOption, GfimuSimKind, GfimuSimOptions};
    let three = |opt: &str, v: &[f64]| vec3(opt, v).map(|v| [v.x, v.y, v.z]);
    let options = GfimuSimOptions {
        kind: match a.kind {
            SimKind::Static => GfimuSimKind::Static,
            SimKind::Motion => GfimuSimKind::Motion,
        },
        array: a.geometry.choice()?,
        k1: a.k1,
        noise: a.noise,
        samples: a.samples,
        duration_s: a.duration_s,
        rate_hz: a.rate_hz,
        spin_up_s: a.spin_up_s,
        angular_accel_rad_s2: a.angular_accel_rad_s2,
        axis: three("--axis", &a.axis)?,
        omega0_rad_s: three("--omega0-rad-s", &a.omega0_rad_s)?,
        f0_g: three("--f0-g", &a.f0_g)?,
        f0_frame: match a.f0_frame {
            F0FrameArg::Unit => F0FrameOption::Unit,
            F0FrameArg::Table => F0FrameOption::Table,
        },
        oscillation_amplitude_rad_s: a.oscillation_amplitude_rad_s,
        oscillation_hz: a.oscillation_hz,
        gravity_m_s2: a.gravity_m_s2,
        seed: a.seed,
    };
    crate::run::simulate::<GfimuCalibrate>(&options, a.output.as_deref())?;
    crate::run::write_truth::<GfimuCalibrate>(&options, a.truth_out.as_deref())
}

/// `incal plan gfimu`: predicted u of every K0 and Ks, and the geometry's
/// conditioning for the motion solution.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let positions: Vec<Vector3<f64>> = match &a.positions {
        None => six_positions(),
        Some(list) => list
            .iter()
            .map(|p| {
                input::parse_position(p).ok_or_else(|| {
                    usage(format!(
                        "--positions: '{}' is not one of +x, -x, +y, -y, +z, -z",
                        incal_io::clip(p)
                    ))
                })
            })
            .collect::<CliResult<_>>()?,
    };
    let options = GfimuPlanOptions {
        array: a.geometry.choice()?,
        positions: positions.iter().map(|f| [f.x, f.y, f.z]).collect(),
        samples: a.samples,
        noise: a.noise,
        k1: a.k1,
    };
    a.out
        .emit(&<GfimuCalibrate as Plan>::plan(&options).map_err(core)?)
}

/// `incal gfimu …`.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Calibrate every accelerometer's K0 and Ks from static positions (six-position test or any >= 6 orientations).
    Calibrate(CalibrateArgs),
    /// Solve a time series of outputs for f0, angular acceleration and angular rate.
    Solve(SolveArgs),
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Gyro-free inertial unit of six (or more) accelerometers: calibrate K0 and Ks, solve motion (the GFIMU note).
    #[command(subcommand)]
    Gfimu(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Gfimu(Command::Calibrate(a)) => run_calibrate(a),
            Self::Gfimu(Command::Solve(a)) => run_solve(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Gyro-free unit calibration plan: predicted u of every accelerometer's K0 and Ks, and the geometry's conditioning.
    Gfimu(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Gfimu(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Gyro-free unit: six-position static test or rate-table motion.
    Gfimu(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Gfimu(a) => simulate(a),
        }
    }
}
