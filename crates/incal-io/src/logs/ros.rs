//! The ROS messages incal reads, in both serialisations: ROS 1 (packed,
//! little-endian, `Header` with a `seq`) and ROS 2 CDR (an encapsulation
//! header, then each primitive aligned to its size from the body's start;
//! `Header` without `seq`; strings with their terminating NUL counted).
//!
//! `sensor_msgs/Imu`: header, orientation (4 float64), its covariance (9),
//! angular_velocity (3, rad/s), its covariance (9), linear_acceleration
//! (3, m/s²), its covariance (9). `sensor_msgs/Temperature`: header,
//! temperature (float64, °C), variance.

use super::{Bytes, Offered, Sample, Series, Stamps, DEG_PER_RAD, G0_M_S2};
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
            // orientation 4 + cov 9 + angular_velocity 3 + cov 9
            // + linear_acceleration 3 + the first of its cov
            Self::Imu => 29,
            Self::Temperature => 1,
        }
    }

    /// The CSV values from the float64s after the header; refused when
    /// the message says a quantity is not provided (`sensor_msgs/Imu`: the
    /// first element of its covariance is −1).
    fn values(self, d: &[f64]) -> std::result::Result<Vec<f64>, &'static str> {
        match self {
            Self::Imu => {
                if d[16] == -1.0 {
                    return Err("says its angular_velocity is not provided (angular_velocity_covariance[0] = -1)");
                }
                if d[28] == -1.0 {
                    return Err("says its linear_acceleration is not provided (linear_acceleration_covariance[0] = -1)");
                }
                let mut v: Vec<f64> = d[13..16].iter().map(|x| x * DEG_PER_RAD).collect();
                v.extend(d[25..28].iter().map(|x| x / G0_M_S2));
                Ok(v)
            }
            Self::Temperature => Ok(vec![d[0]]),
        }
    }
}

/// A decoded message: its header stamp (ns) and its CSV values.
pub(super) struct Decoded {
    pub stamp_ns: i128,
    pub values: Vec<f64>,
}

/// Why a message is not read.
const SHORT: &str = "is too short for its type";

/// A ROS 1 message: `seq` (u32), stamp (u32 s, u32 ns), `frame_id`
/// (u32 length, bytes), then the float64s; `Err`: why not.
pub(super) fn ros1(kind: Kind, data: &[u8]) -> std::result::Result<Decoded, &'static str> {
    let b = Bytes { data };
    let head = || -> Option<(u32, u32, usize)> {
        Some((
            b.u32(4)?,
            b.u32(8)?,
            16usize.checked_add(b.u32(12)? as usize)?,
        ))
    };
    let (sec, nsec, start) = head().ok_or(SHORT)?;
    let d: Vec<f64> = (0..kind.doubles())
        .map(|i| b.f64(start + 8 * i))
        .collect::<Option<_>>()
        .ok_or(SHORT)?;
    Ok(Decoded {
        stamp_ns: sec as i128 * 1_000_000_000 + nsec as i128,
        values: kind.values(&d)?,
    })
}

/// A ROS 2 CDR message: the 4-byte encapsulation (`00 01` little-endian,
/// `00 00` big-endian), stamp (i32 s, u32 ns), `frame_id` (u32 length with
/// its NUL, bytes), then the float64s aligned to 8 from the body's start.
/// `Err`: too short, or an encapsulation other than plain CDR.
pub(super) fn cdr(kind: Kind, data: &[u8]) -> std::result::Result<Decoded, &'static str> {
    let little = match data.get(..2) {
        Some([0, 1]) => true,
        Some([0, 0]) => false,
        Some(_) => return Err("is not plain CDR (its encapsulation is another)"),
        None => return Err(SHORT),
    };
    let body = data.get(4..).ok_or(SHORT)?;
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
    let head = || -> Option<(i32, u32, usize)> {
        let end = 12usize.checked_add(word(8, 4)? as usize)?;
        Some((
            word(0, 4)? as u32 as i32,
            word(4, 4)? as u32,
            end.checked_add(7)? / 8 * 8,
        ))
    };
    let (sec, nsec, start) = head().ok_or(SHORT)?;
    let d: Vec<f64> = (0..kind.doubles())
        .map(|i| word(start + 8 * i, 8).map(f64::from_bits))
        .collect::<Option<_>>()
        .ok_or(SHORT)?;
    Ok(Decoded {
        stamp_ns: sec as i128 * 1_000_000_000 + nsec as i128,
        values: kind.values(&d)?,
    })
}

/// The ROS topics of a log as it is read, in the order they first
/// appear: each message decoded as it comes (the log's bytes are not
/// kept), and every type a topic was published with.
#[derive(Default)]
pub(super) struct Topics {
    topics: Vec<Topic>,
}

/// One topic: its types and its messages (log time ns, decoded or why
/// not).
struct Topic {
    name: String,
    types: Vec<String>,
    kind: Option<Kind>,
    messages: Vec<(i128, std::result::Result<Decoded, &'static str>)>,
}

impl Topics {
    fn entry(&mut self, topic: &str) -> &mut Topic {
        let k = match self.topics.iter().position(|t| t.name == topic) {
            Some(k) => k,
            None => {
                self.topics.push(Topic {
                    name: topic.to_string(),
                    types: Vec::new(),
                    kind: None,
                    messages: Vec::new(),
                });
                self.topics.len() - 1
            }
        };
        &mut self.topics[k]
    }

    /// A connection or channel of `topic` with `type_name`.
    pub fn connection(&mut self, topic: &str, type_name: &str) {
        let t = self.entry(topic);
        if !t.types.iter().any(|x| x == type_name) {
            t.types.push(type_name.to_string());
        }
        if t.kind.is_none() {
            t.kind = Kind::of(type_name);
        }
    }

    /// A message of `topic` of type `kind`, CDR or ROS 1, logged at
    /// `log_ns`.
    pub fn message(&mut self, topic: &str, kind: Kind, cdr_bytes: bool, log_ns: i128, data: &[u8]) {
        let d = if cdr_bytes {
            cdr(kind, data)
        } else {
            ros1(kind, data)
        };
        self.entry(topic).messages.push((log_ns, d));
    }

    /// The topics incal reads here (those of a known type).
    pub fn offered(&self) -> Vec<Offered> {
        self.topics
            .iter()
            .filter(|t| t.kind.is_some())
            .map(|t| Offered {
                name: t.name.clone(),
                kind: t.types.join(" and "),
            })
            .collect()
    }

    /// The chosen topics' series; `log_name` names the log's time. A topic
    /// published with two types, or a message that cannot be read, is
    /// refused, naming it.
    pub fn series(
        mut self,
        file: &str,
        chosen: &[String],
        stamps: Stamps,
        log_name: &'static str,
    ) -> Result<Vec<Series>> {
        let mut out = Vec::with_capacity(chosen.len());
        for name in chosen {
            let t = std::mem::replace(
                self.entry(name),
                Topic {
                    name: String::new(),
                    types: Vec::new(),
                    kind: None,
                    messages: Vec::new(),
                },
            );
            let Some(kind) = t.kind else { continue };
            if t.types.len() > 1 {
                return Err(InputError::file(
                    file,
                    format!("topic {name} is published with {} types ({}): incal reads a topic of one type", t.types.len(), t.types.join(", ")),
                ));
            }
            let mut samples = Vec::with_capacity(t.messages.len());
            for (n, (log_ns, d)) in t.messages.into_iter().enumerate() {
                let d = d.map_err(|why| {
                    InputError::file(file, format!("topic {name}: message {} {why}", n + 1))
                })?;
                samples.push(Sample {
                    log_ns,
                    stamp_ns: match stamps {
                        Stamps::Header => d.stamp_ns,
                        Stamps::Log => log_ns,
                    },
                    values: d.values,
                });
            }
            out.push(Series {
                topic: name.clone(),
                kind: t.types.join(""),
                columns: kind.columns(),
                units: kind.units(),
                stamp_name: match stamps {
                    Stamps::Header => "header.stamp",
                    Stamps::Log => log_name,
                },
                samples,
            });
        }
        Ok(out)
    }
}
