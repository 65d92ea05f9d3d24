//! CSV input through the one input layer ([`incal_io`]): the options every
//! reading command shares (`--columns`, `--delimiter`) and the conversion
//! of its errors (exit 2, one line naming file, line and column).

use incal_io::{ColumnMap, ReadOptions};

use crate::error::{CliError, CliResult};

impl From<incal_io::InputError> for CliError {
    fn from(e: incal_io::InputError) -> Self {
        CliError::Input(e.to_string())
    }
}

/// How every command reads its CSV input: the same two options everywhere.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ReadArgs {
    /// Columns to read and how the file names them, comma separated: NAME=HEADER reads the header HEADER as incal's column NAME (e.g. "angle_deg=Angle [deg],output=Out"); a bare NAME selects a column by its own header.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub columns: Vec<String>,
    /// Delimiter of the input CSV: ',', ';' or tab (default: detected from the header row).
    #[arg(long, value_name = "CHAR")]
    pub delimiter: Option<String>,
    /// File line of the header row (1-based), for a file whose logger writes lines before it (default: found, the lines before it recorded as the document's preamble).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub header_line: Option<u64>,
    /// Cut a continuous rig log into plateaus of this column (an encoder's angle_deg, a table's rate_deg_s, a centrifuge's omega_rad_s, a chamber's temperature_c) before the reduction: moves and each plateau's settling dropped, the column set to the plateau's nominal value (needs time_s; see docs: Recordings as they come).
    #[arg(long, value_name = "COLUMN")]
    pub segment_by: Option<String>,
    /// Largest deviation of a plateau's rows from its mean, in the column's unit (default per column: angle_deg 0.01, rate_deg_s 0.01 + 0.1 %, omega_rad_s 2e-4 + 0.1 %, temperature_c 0.5).
    #[arg(long, value_name = "X")]
    pub segment_tolerance: Option<f64>,
    /// Time dropped at the start of each plateau, s (default per column: 1 s for angles, 2 s for rates, 600 s for temperature).
    #[arg(long, value_name = "S")]
    pub segment_settle_s: Option<f64>,
    /// Shortest plateau kept after the settle time, s (default 1 s; 60 s for temperature).
    #[arg(long, value_name = "S")]
    pub segment_min_s: Option<f64>,
    /// The plan's nominal values in the order the log visits them, comma separated (default: each plateau's mean); a missing or extra plateau is refused naming its time.
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub segment_values: Vec<f64>,
    /// A converter's full scale in the columns' own unit: two or more samples in a row at or beyond it are named as clipped (a `clipped` warning with their lines); integer converters' ends (-32768, 32767, 65535, ...) always are. `mag` refuses a magnetometer reading at or beyond it (saturated).
    #[arg(long, value_name = "X")]
    pub full_scale: Option<f64>,
    /// A robot log's topic and stamps.
    #[command(flatten)]
    pub log: Box<LogArgs>,
}

/// How a robot log is read (`--topic`, `--stamps`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LogArgs {
    /// A robot log's topic (a PX4 ULog, ROS 1 bag or MCAP file, recognised by its first bytes): sensor_combined, sensor_gyro[:N], sensor_accel[:N], sensor_mag[:N], vehicle_imu[:N] (ULog); a sensor_msgs/Imu topic (bag, MCAP), then any sensor_msgs/Temperature topic joined to it, comma separated (default: the log's one such topic; see docs: Recordings as they come).
    #[arg(long, value_name = "NAME", value_delimiter = ',')]
    pub topic: Vec<String>,
    /// A robot log's stamps for time_s: header (the sensor's: header.stamp, ULog timestamp_sample; default) or log (the time the message was received or written).
    #[arg(long, value_name = "header|log")]
    pub stamps: Option<String>,
}

impl ReadArgs {
    /// The input layer's options.
    pub fn options(&self) -> CliResult<ReadOptions> {
        let columns = ColumnMap::from_entries(&self.columns)
            .map_err(|e| CliError::Input(format!("--columns: {e}")))?;
        let delimiter = match &self.delimiter {
            None => None,
            Some(d) => Some(
                incal_io::parse_delimiter(d)
                    .map_err(|e| CliError::Input(format!("--delimiter: {e}")))?,
            ),
        };
        Ok(ReadOptions {
            delimiter,
            columns,
            header_line: self.header_line.map(|n| n as usize),
            segment: incal_io::SegmentSpec::from_options(
                self.segment_by.as_deref(),
                self.segment_tolerance,
                self.segment_settle_s,
                self.segment_min_s,
                &self.segment_values,
            )
            .map_err(CliError::Input)?,
            full_scale: match self.full_scale {
                Some(x) if !(x.is_finite() && x > 0.0) => {
                    return Err(CliError::Input(format!(
                        "--full-scale: {x} is not a positive full scale"
                    )))
                }
                x => x,
            },
            log: incal_io::logs::LogOptions {
                topics: self
                    .log
                    .topic
                    .iter()
                    .map(|t| t.trim().to_string())
                    .collect(),
                stamps: match &self.log.stamps {
                    None => incal_io::logs::Stamps::default(),
                    Some(s) => incal_io::logs::Stamps::parse(s)
                        .map_err(|e| CliError::Input(format!("--stamps: {e}")))?,
                },
            },
            ..ReadOptions::default()
        })
    }
}
