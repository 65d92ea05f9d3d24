//! `incal export imucal RESULT.json -o cal.json`: an IMU calibration in the
//! JSON form another tool reads ([`incal::procedures::imu::apply::to_imucal`]);
//! `incal export kalibr --gyro G.json --accel A.json -o imu.yaml`: noise
//! terms as Kalibr's IMU noise model, and `incal export px4 …` as PX4's
//! EKF2 noise parameters ([`incal::procedures::noise::export`]).

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
    /// The same two noise results as PX4's EKF2 IMU noise parameters (EKF2_GYR_NOISE, EKF2_ACC_NOISE, EKF2_GYR_B_NOISE, EKF2_ACC_B_NOISE) in a QGroundControl parameter file.
    Px4(Px4Args),
}

/// Options of `incal export px4`.
#[derive(clap::Args, Debug)]
pub struct Px4Args {
    #[command(flatten)]
    pub results: KalibrArgs,
    /// The EKF's prediction rate in Hz (PX4: 1e6/EKF2_PREDICT_US; default 100).
    #[arg(long, default_value_t = 100.0)]
    pub ekf_rate_hz: f64,
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
pub fn run(c: &Command) -> CliResult<()> {
    match c {
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
            let a = &p.results;
            let (gname, _, gyro) = read_document(&a.gyro)?;
            let (aname, _, accel) = read_document(&a.accel)?;
            let to_input = |e: incal::Error| crate::error::CliError::Input(e.to_string());
            let imu = incal::procedures::noise::export::kalibr(&gyro, &gname, &accel, &aname)
                .map_err(to_input)?;
            let params =
                incal::procedures::noise::export::px4(&imu, p.ekf_rate_hz).map_err(to_input)?;
            write_text(a.output.as_deref(), &params.to_params())
        }
    }
}
