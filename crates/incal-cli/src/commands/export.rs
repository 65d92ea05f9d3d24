//! `incal export imucal RESULT.json -o cal.json`: an IMU calibration in the
//! JSON form another tool reads ([`incal::procedures::imu::apply::to_imucal`]).

use std::path::PathBuf;

use crate::documents::read_document;
use crate::error::{in_file, CliResult};
use crate::output::{json_text, write_text};

/// `incal export …`.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// An imu ferraris, multipos or autocal result as imucal's calibration JSON (FerrarisCalibrationInfo, loaded by imucal's load_calibration_info).
    Imucal(Args),
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
    }
}
