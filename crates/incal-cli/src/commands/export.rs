//! `incal export imucal RESULT.json -o cal.json`: an IMU calibration in the
//! JSON form another tool reads ([`incal::procedures::imu::apply::to_imucal`]);
//! `incal export kalibr --gyro G.json --accel A.json -o imu.yaml`: noise
//! terms as Kalibr's IMU noise model, and `incal export px4 …` as PX4's
//! EKF2 noise parameters ([`incal::procedures::noise::export`]);
//! `incal export vins|orbslam3|openvins|basalt …` as those estimators'
//! configuration ([`incal::procedures::noise::stacks`]).

use std::path::PathBuf;

use crate::documents::read_document;
use crate::error::{in_file, CliResult};
use crate::output::{json_text, write_text};

/// `incal export …`.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// An imu ferraris, multipos or autocal result as imucal's calibration JSON (FerrarisCalibrationInfo, loaded by imucal's load_calibration_info).
    Imucal(Args),
    /// Gyro and accelerometer noise results (incal noise --quantity gyro / accel) as Kalibr's imu.yaml: noise densities and random walks in SI units, the largest axis per sensor.
    Kalibr(KalibrArgs),
    /// PX4 parameters in a QGroundControl parameter file: a thermal model (MODEL.json) as thermal compensation (TC_A0_* or TC_G0_*), or two noise results (--gyro, --accel) as EKF2 IMU noise (EKF2_GYR_NOISE, EKF2_ACC_NOISE, EKF2_GYR_B_NOISE, EKF2_ACC_B_NOISE).
    Px4(Px4Args),
    /// A thermal model (incal thermal ramp or fit) as ArduPilot's IMU temperature calibration (INS_TCALn_*), NAME,VALUE lines.
    Ardupilot(ArdupilotArgs),
    /// Gyro and accelerometer noise results as VINS-Mono / VINS-Fusion's acc_n, gyr_n, acc_w, gyr_w (discrete time per IMU sample).
    Vins(StackArgs),
    /// Gyro and accelerometer noise results as ORB-SLAM3's IMU.NoiseGyro, IMU.NoiseAcc, IMU.GyroWalk, IMU.AccWalk, IMU.Frequency (continuous time).
    Orbslam3(StackArgs),
    /// Gyro and accelerometer noise results as OpenVINS's kalibr_imu_chain.yaml (continuous time).
    Openvins(OpenvinsArgs),
    /// Gyro and accelerometer noise results as Basalt's calibration keys accel_noise_std, gyro_noise_std, accel_bias_std, gyro_bias_std per axis (continuous time, JSON).
    Basalt(StackArgs),
}

/// Options of `incal export vins|orbslam3|openvins|basalt`.
#[derive(clap::Args, Debug)]
pub struct StackArgs {
    /// The gyro noise result (incal noise --quantity gyro --json).
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// The accelerometer noise result (incal noise --quantity accel --json), recorded at the same rate.
    #[arg(long, value_name = "FILE")]
    pub accel: PathBuf,
    /// Every noise value times K, 1 to 1000 (stated in the file; default 1: the sensor at rest).
    #[arg(long, value_name = "K", default_value_t = 1.0)]
    pub inflate: f64,
    /// The IMU rate the estimator runs at, Hz (default: the records' rate).
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Options of `incal export openvins`.
#[derive(clap::Args, Debug)]
pub struct OpenvinsArgs {
    #[command(flatten)]
    pub stack: StackArgs,
    /// The IMU's ROS topic (rostopic; default /imu0).
    #[arg(long)]
    pub topic: Option<String>,
}

/// Options of `incal export px4`.
#[derive(clap::Args, Debug)]
pub struct Px4Args {
    /// A thermal model (a result of incal thermal ramp or fit): written as TC_* thermal compensation parameters.
    #[arg(value_name = "MODEL.json", conflicts_with_all = ["gyro", "accel"])]
    pub model: Option<PathBuf>,
    /// The gyro noise result (incal noise --quantity gyro --json), for EKF2 noise parameters.
    #[arg(long, value_name = "FILE", requires = "accel")]
    pub gyro: Option<PathBuf>,
    /// The accelerometer noise result (incal noise --quantity accel --json), recorded at the same rate.
    #[arg(long, value_name = "FILE", requires = "gyro")]
    pub accel: Option<PathBuf>,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// The EKF's prediction rate in Hz (PX4: 1e6/EKF2_PREDICT_US; default 100; noise parameters only).
    #[arg(long, default_value_t = 100.0)]
    pub ekf_rate_hz: f64,
    #[command(flatten)]
    pub thermal: ThermalExportArgs,
    /// TC_x0_ID: the device id of the sensor the compensation is for (PX4 matches it against the sensor's).
    #[arg(long, default_value_t = 0)]
    pub device_id: u32,
    /// Write c0 (the value at T_ref) as X0; by default X0 = 0 and the offset at T_ref stays with the sensor's regular calibration.
    #[arg(long)]
    pub with_offset: bool,
}

/// Options shared by the thermal exports.
#[derive(clap::Args, Debug)]
pub struct ThermalExportArgs {
    /// The model's channels for the X, Y and Z axes (default: the channels whose names end in x, y, z, or the only three).
    #[arg(long, value_delimiter = ',', value_name = "X,Y,Z")]
    pub axes: Option<Vec<String>>,
}

/// Options of `incal export ardupilot`.
#[derive(clap::Args, Debug)]
pub struct ArdupilotArgs {
    /// A thermal model (a result of incal thermal ramp or fit).
    #[arg(value_name = "MODEL.json")]
    pub model: PathBuf,
    #[command(flatten)]
    pub thermal: ThermalExportArgs,
    /// Which IMU (n in INS_TCALn_*), 1 to 3.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=3))]
    pub imu: u8,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Options of `incal export kalibr`.
#[derive(clap::Args, Debug)]
pub struct KalibrArgs {
    /// The gyro noise result (incal noise --quantity gyro --json).
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// The accelerometer noise result (incal noise --quantity accel --json), recorded at the same rate.
    #[arg(long, value_name = "FILE")]
    pub accel: PathBuf,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Options of `incal export imucal`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// A result document of imu ferraris, multipos or autocal (JSON); - reads standard input.
    pub result: PathBuf,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal export`.
/// A core error of the document `name` whose option keys are spelled as
/// the command line's flags (`--axes`).
fn option_in(name: &str, e: incal::Error) -> crate::error::CliError {
    crate::error::core(incal::Error::InFile {
        file: name.to_string(),
        source: Box::new(e),
    })
}

/// A stack's file from the two noise results of `a`.
fn stack(
    kind: incal::procedures::noise::stacks::Stack,
    a: &StackArgs,
    topic: Option<&str>,
) -> CliResult<()> {
    let (gname, _, gyro) = read_document(&a.gyro)?;
    let (aname, _, accel) = read_document(&a.accel)?;
    let o = incal::procedures::noise::stacks::StackOptions {
        inflate: a.inflate,
        rate_hz: a.rate_hz,
        topic: topic.map(str::to_string),
    };
    let text =
        incal::procedures::noise::stacks::stack_text(kind, (&gyro, &gname), (&accel, &aname), &o)
            .map_err(crate::error::core)?;
    write_text(a.output.as_deref(), &text)
}

pub fn run(c: &Command) -> CliResult<()> {
    use incal::procedures::noise::stacks::Stack;
    match c {
        Command::Vins(a) => stack(Stack::Vins, a, None),
        Command::Orbslam3(a) => stack(Stack::Orbslam3, a, None),
        Command::Openvins(a) => stack(Stack::Openvins, &a.stack, a.topic.as_deref()),
        Command::Basalt(a) => stack(Stack::Basalt, a, None),
        Command::Imucal(a) => {
            let (name, _, doc) = read_document(&a.result)?;
            let cal =
                incal::procedures::imu::apply::to_imucal(&doc).map_err(|e| in_file(&name, e))?;
            write_text(a.output.as_deref(), &json_text(&cal))
        }
        Command::Kalibr(a) => {
            let (gname, _, gyro) = read_document(&a.gyro)?;
            let (aname, _, accel) = read_document(&a.accel)?;
            let imu = incal::procedures::noise::export::kalibr(&gyro, &gname, &accel, &aname)
                .map_err(|e| crate::error::CliError::Input(e.to_string()))?;
            write_text(a.output.as_deref(), &imu.to_yaml())
        }
        Command::Px4(p) => {
            if let Some(m) = &p.model {
                let (name, _, doc) = read_document(m)?;
                let model =
                    incal::procedures::thermal::Model::of(&doc).map_err(|e| in_file(&name, e))?;
                let params = incal::procedures::thermal::export::px4(
                    &model,
                    p.thermal.axes.as_deref(),
                    p.device_id,
                    p.with_offset,
                )
                .map_err(|e| option_in(&name, e))?;
                return write_text(
                    p.output.as_deref(),
                    &incal::procedures::thermal::export::px4_text(&params, &name),
                );
            }
            let (Some(g), Some(acc)) = (&p.gyro, &p.accel) else {
                return Err(crate::error::usage(
                    "export px4: give a thermal MODEL.json, or --gyro and --accel noise results",
                ));
            };
            let (gname, _, gyro) = read_document(g)?;
            let (aname, _, accel) = read_document(acc)?;
            let imu = incal::procedures::noise::export::kalibr(&gyro, &gname, &accel, &aname)
                .map_err(crate::error::core)?;
            let params = incal::procedures::noise::export::px4(&imu, p.ekf_rate_hz)
                .map_err(crate::error::core)?;
            write_text(p.output.as_deref(), &params.to_params())
        }
        Command::Ardupilot(a) => {
            let (name, _, doc) = read_document(&a.model)?;
            let model =
                incal::procedures::thermal::Model::of(&doc).map_err(|e| in_file(&name, e))?;
            let params = incal::procedures::thermal::export::ardupilot(
                &model,
                a.thermal.axes.as_deref(),
                a.imu,
            )
            .map_err(|e| option_in(&name, e))?;
            write_text(
                a.output.as_deref(),
                &incal::procedures::thermal::export::ardupilot_text(&params, &name),
            )
        }
    }
}
