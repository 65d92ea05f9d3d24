//! The ROS messages incal reads, in both serialisations: ROS 1 (packed,
//! little-endian, `Header` with a `seq`) and ROS 2 CDR (an encapsulation
//! header, then each primitive aligned to its size from the body's start;
//! `Header` without `seq`; strings with their terminating NUL counted).
//!
//! `sensor_msgs/Imu`: header, orientation (4 float64), its covariance (9),
//! angular_velocity (3, rad/s), its covariance (9), linear_acceleration
//! (3, m/s²), its covariance (9). `sensor_msgs/Temperature`: header,
//! temperature (float64, °C), variance.

use super::{Bytes, Sample, Series, Stamps, DEG_PER_RAD, G0_M_S2};
use crate::error::{InputError, Result};

/// A message type incal reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    /// `sensor_msgs/Imu`.
    Imu,
    /// `sensor_msgs/Temperature`.
    Temperature,
}

impl Kind {
    /// From a type name: `sensor_msgs/Imu` (ROS 1) or `sensor_msgs/msg/Imu`
    /// (ROS 2).
    pub(super) fn of(type_name: &str) -> Option<Self> {
        match type_name.replace("/msg/", "/").as_str() {
            "sensor_msgs/Imu" => Some(Self::Imu),
            "sensor_msgs/Temperature" => Some(Self::Temperature),
            _ => None,
        }
    }

    /// The CSV columns.
    pub(super) fn columns(self) -> Vec<&'static str> {
        match self {
            Self::Imu => vec!["gyr_x", "gyr_y", "gyr_z", "acc_x", "acc_y", "acc_z"],
            Self::Temperature => vec!["temperature_c"],
        }
    }

    /// The conversion, as the preamble states it.
    pub(super) fn units(self) -> &'static str {
        match self {
            Self::Imu => "angular_velocity: rad/s x 180/pi -> gyr deg/s; linear_acceleration: m/s2 / 9.80665 -> acc g",
            Self::Temperature => "temperature: degC",
        }
    }

    /// Float64 values after the header up to the last one read.
    fn doubles(self) -> usize {
        match self {
            // orientation 4 + cov 9 + angular_velocity 3 + cov 9 + linear_acceleration 3
            Self::Imu => 28,
            Self::Temperature => 1,
        }
    }

    /// The CSV values from the float64s after the header.
    fn values(self, d: &[f64]) -> Vec<f64> {
        match self {
            Self::Imu => {
                let mut v: Vec<f64> = d[13..16].iter().map(|x| x * DEG_PER_RAD).collect();
                v.extend(d[25..28].iter().map(|x| x / G0_M_S2));
                v
            }
            Self::Temperature => vec![d[0]],
        }
    }
}

/// A decoded message: its header stamp (ns) and its CSV values.
pub(super) struct Decoded {
    pub stamp_ns: i128,
    pub values: Vec<f64>,
}

/// A ROS 1 message: `seq` (u32), stamp (u32 s, u32 ns), `frame_id`
/// (u32 length, bytes), then the float64s. `None`: too short.
pub(super) fn ros1(kind: Kind, data: &[u8]) -> Option<Decoded> {
    let b = Bytes { data };
    let sec = b.u32(4)?;
    let nsec = b.u32(8)?;
    let len = b.u32(12)? as usize;
    let start = 16usize.checked_add(len)?;
    let d: Vec<f64> = (0..kind.doubles())
        .map(|i| b.f64(start + 8 * i))
        .collect::<Option<_>>()?;
    Some(Decoded {
        stamp_ns: sec as i128 * 1_000_000_000 + nsec as i128,
        values: kind.values(&d),
    })
}

/// A ROS 2 CDR message: the 4-byte encapsulation (`00 01` little-endian,
/// `00 00` big-endian), stamp (i32 s, u32 ns), `frame_id` (u32 length with
/// its NUL, bytes), then the float64s aligned to 8 from the body's start.
/// `None`: too short or an encapsulation other than plain CDR.
pub(super) fn cdr(kind: Kind, data: &[u8]) -> Option<Decoded> {
    let little = match data.get(..2)? {
        [0, 1] => true,
        [0, 0] => false,
        _ => return None,
    };
    let body = data.get(4..)?;
    let word = |at: usize, n: usize| -> Option<u64> {
        let s = body.get(at..at.checked_add(n)?)?;
        let mut x = [0u8; 8];
        if little {
            x[..n].copy_from_slice(s);
            Some(u64::from_le_bytes(x))
        } else {
            x[8 - n..].copy_from_slice(s);
            Some(u64::from_be_bytes(x))
        }
    };
    let sec = word(0, 4)? as u32 as i32;
    let nsec = word(4, 4)? as u32;
    let len = word(8, 4)? as usize;
    let end = 12usize.checked_add(len)?;
    let start = end.checked_add(7)? / 8 * 8;
    let d: Vec<f64> = (0..kind.doubles())
        .map(|i| word(start + 8 * i, 8).map(f64::from_bits))
        .collect::<Option<_>>()?;
    Some(Decoded {
        stamp_ns: sec as i128 * 1_000_000_000 + nsec as i128,
        values: kind.values(&d),
    })
}

/// One message of a ROS topic as a log holds it.
pub(super) struct Message<'a> {
    /// Its type.
    pub kind: Kind,
    /// CDR (ROS 2) rather than ROS 1.
    pub cdr: bool,
    /// The log's time of it, ns.
    pub log_ns: i128,
    /// Its bytes.
    pub data: &'a [u8],
}

/// A ROS topic's messages decoded into a series; `log_name` names the
/// log's time (`record time`, `log_time`). A message too short for its
/// type is refused, naming its number.
pub(super) fn series<'a>(
    file: &str,
    topic: &str,
    type_name: &str,
    messages: impl Iterator<Item = Message<'a>>,
    stamps: Stamps,
    log_name: &'static str,
) -> Result<Series> {
    let mut samples = Vec::new();
    let mut kind = Kind::of(type_name).unwrap_or(Kind::Imu);
    for (n, m) in messages.enumerate() {
        kind = m.kind;
        let d = if m.cdr {
            cdr(m.kind, m.data)
        } else {
            ros1(m.kind, m.data)
        }
        .ok_or_else(|| {
            InputError::file(
                file,
                format!(
                    "topic {topic}: message {} too short for its type{}",
                    n + 1,
                    if m.cdr { " or not plain CDR" } else { "" }
                ),
            )
        })?;
        samples.push(Sample {
            log_ns: m.log_ns,
            stamp_ns: match stamps {
                Stamps::Header => d.stamp_ns,
                Stamps::Log => m.log_ns,
            },
            values: d.values,
        });
    }
    Ok(Series {
        topic: topic.to_string(),
        kind: type_name.to_string(),
        columns: kind.columns(),
        units: kind.units(),
        stamp_name: match stamps {
            Stamps::Header => "header.stamp",
            Stamps::Log => log_name,
        },
        samples,
    })
}
