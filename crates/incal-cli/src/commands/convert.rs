//! `incal convert`: a robot log's topic as incal's CSV, exactly the text
//! every reducing command reads from that log (`incal_io::logs`).

use std::io::Read;
use std::path::PathBuf;

use incal_io::logs::{self, Format, LogOptions, Stamps};

use crate::error::{CliError, CliResult};

/// Options of `incal convert`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The log: a PX4 ULog, a ROS 1 bag or an MCAP file, recognised by its first bytes; - reads standard input.
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// The topic (as for the reducing commands' --topic): sensor_combined, sensor_gyro[:N], sensor_accel[:N], sensor_mag[:N], vehicle_imu[:N] (ULog); a sensor_msgs/Imu topic, then any sensor_msgs/Temperature topic joined to it, comma separated (bag, MCAP). Default: the log's one such topic.
    #[arg(long, value_name = "NAME", value_delimiter = ',')]
    pub topic: Vec<String>,
    /// The stamps of time_s: header (the sensor's: header.stamp, ULog timestamp_sample; default) or log (the time the message was received or written).
    #[arg(long, value_name = "header|log")]
    pub stamps: Option<String>,
    /// Write the CSV to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Decode the log and write its CSV.
pub fn run(a: &Args) -> CliResult<()> {
    let stamps = match &a.stamps {
        None => Stamps::default(),
        Some(s) => Stamps::parse(s).map_err(|e| CliError::Input(format!("--stamps: {e}")))?,
    };
    let o = incal_io::open(&a.input)?;
    let mut bytes = Vec::with_capacity(o.size);
    o.reader
        .take(u64::MAX)
        .read_to_end(&mut bytes)
        .map_err(|e| incal_io::InputError::io(&o.name, &e))?;
    let Some(format) = Format::detect(&bytes) else {
        return Err(CliError::Input(format!(
            "{}: not a PX4 ULog, a ROS 1 bag or an MCAP file (its first bytes say none of them)",
            o.name
        )));
    };
    let opts = LogOptions {
        topics: a.topic.iter().map(|t| t.trim().to_string()).collect(),
        stamps,
    };
    let c = logs::convert(&o.name, format, &bytes, &opts)?;
    crate::io::write_text(a.output.as_deref(), &c.text)
}
