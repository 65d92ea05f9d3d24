//! Robot logs as recordings: PX4 ULog, ROS 1 bags and ROS 2 MCAP files,
//! read by the same [`crate::Reader`] as CSV.
//!
//! A log is recognised by its first bytes ([`Format::detect`]), whatever
//! its name. One topic (`--topic`, [`LogOptions::topics`]) is decoded into
//! incal's CSV — the text `incal convert` writes — and read from there:
//! every procedure, front end and check (stamps, gaps, clipped samples,
//! segments, environment) sees a log exactly as it sees that CSV, and a
//! message names a line of it. The result's `sha256` is that of the log's
//! own bytes.
//!
//! The CSV's columns, in incal's units, converted here and nowhere else:
//!
//! | column | from |
//! |---|---|
//! | `time_s` | the message's stamp ([`Stamps`]), s from the first row's |
//! | `gyr_x`, `gyr_y`, `gyr_z` | rad/s × 180/π → deg/s |
//! | `acc_x`, `acc_y`, `acc_z` | m/s² ÷ g₀ (9.80665 m/s²) → g |
//! | `mag_x`, `mag_y`, `mag_z` | gauss × 100 → µT |
//! | `temperature_c` | °C |
//!
//! The lines before the header state what was read and how (format,
//! topic, message type, stamps, the first stamp, the units' conversion);
//! they are the document's `preamble`. Rows are in the order of the log's
//! time (the receive or write time, as the formats' reference readers give
//! them); `time_s` is the stamp chosen.
//!
//! Formats: [ULog](https://docs.px4.io/main/en/dev_log/ulog_file_format)
//! (PX4 Autopilot project, file format version 1, topics
//! `sensor_combined`, `sensor_gyro`, `sensor_accel`, `sensor_mag`,
//! `vehicle_imu`, with `NAME:INSTANCE` for a multi-instance topic);
//! [rosbag 2.0](http://wiki.ros.org/Bags/Format/2.0) (Open Robotics,
//! chunks uncompressed, bz2 or lz4); [MCAP](https://mcap.dev/spec)
//! (Foxglove, with `ros2msg` CDR or `ros1msg` messages). The message types
//! are `sensor_msgs/Imu` and `sensor_msgs/Temperature` (ROS), joined to
//! the first topic by the latest value at or before each row.

mod bag;
mod mcap;
mod ros;
mod ulog;

use crate::error::{InputError, Result};
use crate::frames::push_number;

/// Degrees per radian.
const DEG_PER_RAD: f64 = 180.0 / std::f64::consts::PI;
/// Standard gravity, m/s² (CGPM 1901): m/s² → g.
const G0_M_S2: f64 = 9.806_65;
/// µT per gauss.
const UT_PER_GAUSS: f64 = 100.0;

/// The robot-log formats incal reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// PX4 ULog.
    Ulog,
    /// ROS 1 bag, version 2.0.
    Bag,
    /// MCAP (ROS 2 and others).
    Mcap,
}

impl Format {
    /// Bytes needed to recognise every format.
    pub const MAGIC_BYTES: usize = 13;

    /// The format whose magic number `head` starts with.
    pub fn detect(head: &[u8]) -> Option<Self> {
        if head.starts_with(b"ULog\x01\x12\x35") {
            Some(Self::Ulog)
        } else if head.starts_with(b"#ROSBAG V2.0\n") {
            Some(Self::Bag)
        } else if head.starts_with(b"\x89MCAP0\r\n") {
            Some(Self::Mcap)
        } else {
            None
        }
    }

    /// Its name in messages and in the preamble.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ulog => "PX4 ULog",
            Self::Bag => "ROS 1 bag",
            Self::Mcap => "MCAP",
        }
    }
}

/// Which time stamp becomes `time_s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Stamps {
    /// The sensor's own: `header.stamp` (ROS), `timestamp_sample` (ULog,
    /// `timestamp` where the topic has no other).
    #[default]
    Header,
    /// The log's: the time the message was received or written (bag record
    /// time, MCAP `log_time`, ULog `timestamp`).
    Log,
}

impl Stamps {
    /// From `header` or `log`.
    pub fn parse(s: &str) -> std::result::Result<Self, String> {
        match s {
            "header" => Ok(Self::Header),
            "log" => Ok(Self::Log),
            _ => Err(format!("'{}': expected header or log", crate::clip(s))),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Header => "header",
            Self::Log => "log",
        }
    }
}

/// How a robot log is read.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct LogOptions {
    /// The topics (`--topic A[,B]`): the first gives the rows, the others
    /// (a `sensor_msgs/Temperature`, say) are joined to them. Empty: the
    /// log's one topic of a known type, refused naming them when there are
    /// several.
    pub topics: Vec<String>,
    /// The stamps of `time_s`.
    pub stamps: Stamps,
}

/// One decoded message: its log time (ns, for the order), its stamp (ns)
/// and its values in the columns' order.
#[derive(Debug, Clone)]
struct Sample {
    log_ns: i128,
    stamp_ns: i128,
    values: Vec<f64>,
}

/// One topic decoded: what it is, its columns and its samples.
#[derive(Debug, Clone)]
struct Series {
    topic: String,
    kind: String,
    columns: Vec<&'static str>,
    units: &'static str,
    stamp_name: &'static str,
    samples: Vec<Sample>,
}

/// A topic a log offers, as a user names it, and its type.
#[derive(Debug, Clone)]
struct Offered {
    name: String,
    kind: String,
}

/// Pick the topics to read: the ones named (each must be offered), or the
/// log's only one.
fn choose(
    file: &str,
    format: Format,
    offered: &[Offered],
    opts: &LogOptions,
) -> Result<Vec<String>> {
    // ULog instances of one topic are listed together: `sensor_gyro
    // (instances 0, 1, 2)`; a ROS topic with its type.
    let list = || {
        let mut names: Vec<(String, Vec<String>)> = Vec::new();
        for o in offered {
            match o
                .name
                .strip_prefix(&o.kind)
                .and_then(|r| r.strip_prefix(':'))
            {
                Some(n) => match names.iter_mut().find(|(k, _)| k == &o.kind) {
                    Some((_, v)) => v.push(n.to_string()),
                    None => names.push((o.kind.clone(), vec![n.to_string()])),
                },
                None if o.name == o.kind => names.push((o.name.clone(), vec!["0".into()])),
                None => names.push((format!("{} ({})", o.name, o.kind), Vec::new())),
            }
        }
        let text: Vec<String> = names
            .into_iter()
            .map(|(k, v)| match v.as_slice() {
                [] => k,
                [n] if n == "0" => k,
                [n] => format!("{k}:{n}"),
                _ => format!("{k} (instances {})", v.join(", ")),
            })
            .collect();
        if text.is_empty() {
            "none".to_string()
        } else {
            crate::clip_to(&text.join(", "), 240)
        }
    };
    if opts.topics.is_empty() {
        return match offered {
            [one] => Ok(vec![one.name.clone()]),
            _ => Err(InputError::file(
                file,
                format!(
                    "a {}: give --topic, one of the topics incal reads here: {}",
                    format.name(),
                    list()
                ),
            )),
        };
    }
    for (k, t) in opts.topics.iter().enumerate() {
        if opts.topics[..k].contains(t) {
            return Err(InputError::file(
                file,
                format!("--topic '{}' given twice", crate::clip(t)),
            ));
        }
        if !offered.iter().any(|o| &o.name == t) {
            return Err(InputError::file(
                file,
                format!(
                    "--topic '{}': not in this {} (topics incal reads here: {})",
                    crate::clip(t),
                    format.name(),
                    list()
                ),
            ));
        }
    }
    Ok(opts.topics.clone())
}

/// The decoded CSV of a robot log and what the reader records of it.
#[derive(Debug)]
pub struct Converted {
    /// incal's CSV: the preamble lines, the header, one row per message.
    pub text: String,
    /// File line of the header row.
    pub header_line: usize,
    /// SHA-256 of the log's bytes.
    pub sha256: String,
}

/// Decode `bytes` (a log in `format`, named `file` in messages) into
/// incal's CSV (module docs).
pub fn convert(file: &str, format: Format, bytes: &[u8], opts: &LogOptions) -> Result<Converted> {
    let series = match format {
        Format::Ulog => ulog::read(file, bytes, opts)?,
        Format::Bag => bag::read(file, bytes, opts)?,
        Format::Mcap => mcap::read(file, bytes, opts)?,
    };
    let (text, header_line) = write_csv(file, format, series, opts.stamps)?;
    Ok(Converted {
        text,
        header_line,
        sha256: crate::sha256_hex(bytes),
    })
}

/// The series as CSV: the first gives the rows (in log-time order), the
/// others are joined by their latest sample at or before each row; rows
/// before every joined topic has a sample are left out (counted in the
/// preamble).
fn write_csv(
    file: &str,
    format: Format,
    mut series: Vec<Series>,
    stamps: Stamps,
) -> Result<(String, usize)> {
    for s in &mut series {
        s.samples.sort_by_key(|m| m.log_ns);
    }
    let Some(first) = series.first() else {
        return Err(InputError::file(file, "no topic to read"));
    };
    if first.samples.is_empty() {
        return Err(InputError::file(
            file,
            format!("topic {}: no messages", first.topic),
        ));
    }
    // A joined topic's column already given by an earlier one is left out
    // (stated in the preamble).
    let mut header: Vec<&str> = vec!["time_s"];
    let mut keep: Vec<Vec<usize>> = Vec::with_capacity(series.len());
    let mut pre: Vec<(String, String)> = vec![("format".into(), format.name().into())];
    for s in &series {
        pre.push(("topic".into(), format!("{} ({})", s.topic, s.kind)));
        pre.push(("units".into(), s.units.into()));
        let mut kept = Vec::new();
        for (j, c) in s.columns.iter().enumerate() {
            if header.contains(c) {
                pre.push((
                    "left_out".into(),
                    format!("{c} of {} (given before)", s.topic),
                ));
            } else {
                header.push(c);
                kept.push(j);
            }
        }
        keep.push(kept);
    }
    pre.push((
        "stamps".into(),
        format!(
            "{} ({}), s from the first row's",
            stamps.name(),
            first.stamp_name
        ),
    ));
    // Rows written straight into one buffer (no text per row or value).
    let width = header.len();
    // The preamble is put in front at the end (`insert_str` moves the
    // rows once; the spare capacity only spares a reallocation).
    const PREAMBLE_ROOM: usize = 1 << 14;
    let mut body = String::with_capacity(PREAMBLE_ROOM + first.samples.len() * (8 + 20 * width));
    let mut rows = 0usize;
    let mut cursor = vec![0usize; series.len()];
    let mut origin: Option<i128> = None;
    let mut skipped = 0usize;
    'rows: for m in &first.samples {
        let start = body.len();
        let t0 = *origin.get_or_insert(m.stamp_ns);
        push_seconds(&mut body, m.stamp_ns - t0);
        for v in &m.values {
            body.push(',');
            push_number(&mut body, *v);
        }
        for (k, s) in series.iter().enumerate().skip(1) {
            while cursor[k] < s.samples.len() && s.samples[cursor[k]].log_ns <= m.log_ns {
                cursor[k] += 1;
            }
            let Some(j) = cursor[k].checked_sub(1) else {
                skipped += 1;
                body.truncate(start);
                if rows == 0 {
                    origin = None;
                }
                continue 'rows;
            };
            for &c in &keep[k] {
                body.push(',');
                push_number(&mut body, s.samples[j].values[c]);
            }
        }
        body.push('\n');
        rows += 1;
    }
    if rows == 0 {
        return Err(InputError::file(
            file,
            "no row of the first topic has a sample of every other topic at or before it",
        ));
    }
    if let Some(t0) = origin {
        pre.push(("first_stamp_s".into(), seconds_text(t0)));
    }
    if skipped > 0 {
        pre.push((
            "rows_left_out".into(),
            format!("{skipped} (before the first sample of a joined topic)"),
        ));
    }
    // One line each: a name's control characters (a newline in a topic)
    // are shown as '?'.
    let line = |v: &str| -> String {
        crate::csv_text(
            &v.chars()
                .map(|c| if c.is_control() { '?' } else { c })
                .collect::<String>(),
        )
        .into_owned()
    };
    let mut text = String::with_capacity(PREAMBLE_ROOM);
    for (k, v) in &pre {
        text.push_str(&line(k));
        text.push(',');
        text.push_str(&line(v));
        text.push('\n');
    }
    text.push_str(&header.join(","));
    text.push('\n');
    body.insert_str(0, &text);
    Ok((body, pre.len() + 1))
}

/// Nanoseconds as exact decimal seconds (`3.003325`, `-0.5`, `0`).
fn seconds_text(ns: i128) -> String {
    let mut s = String::new();
    push_seconds(&mut s, ns);
    s
}

/// Append [`seconds_text`]`(ns)` to `out` without allocating.
fn push_seconds(out: &mut String, ns: i128) {
    if ns < 0 {
        out.push('-');
    }
    let (s, frac) = (
        ns.unsigned_abs() / 1_000_000_000,
        (ns.unsigned_abs() % 1_000_000_000) as u32,
    );
    out.push_str(itoa::Buffer::new().format(s));
    if frac == 0 {
        return;
    }
    // Nine digits, trailing zeros dropped.
    let mut digits = [b'0'; 9];
    let mut f = frac;
    for d in digits.iter_mut().rev() {
        *d = b'0' + (f % 10) as u8;
        f /= 10;
    }
    let end = 9 - digits.iter().rev().take_while(|&&d| d == b'0').count();
    out.push('.');
    out.extend(digits[..end].iter().map(|&d| d as char));
}

/// Bounds-checked little-endian reads over a message's bytes.
#[derive(Debug, Clone, Copy)]
struct Bytes<'a> {
    data: &'a [u8],
}

impl<'a> Bytes<'a> {
    fn get(&self, at: usize, n: usize) -> Option<&'a [u8]> {
        self.data.get(at..at.checked_add(n)?)
    }
    fn u8(&self, at: usize) -> Option<u8> {
        self.data.get(at).copied()
    }
    fn u16(&self, at: usize) -> Option<u16> {
        Some(u16::from_le_bytes(self.get(at, 2)?.try_into().ok()?))
    }
    fn u32(&self, at: usize) -> Option<u32> {
        Some(u32::from_le_bytes(self.get(at, 4)?.try_into().ok()?))
    }
    fn f64(&self, at: usize) -> Option<f64> {
        Some(f64::from_le_bytes(self.get(at, 8)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests;
