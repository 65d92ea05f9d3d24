//! MCAP files through the `mcap` crate (Foxglove's reader: records,
//! chunks compressed with zstd or lz4): channels whose schema is
//! `sensor_msgs/msg/Imu` or `sensor_msgs/msg/Temperature`, messages in
//! `cdr` (ROS 2) or `ros1` encoding; `log_time` is the log's time.

use super::ros::{self, Kind};
use super::{choose, Format, LogOptions, Offered, Series};
use crate::error::{InputError, Result};

/// A channel incal reads: its type and whether its messages are CDR.
fn readable(ch: &::mcap::Channel<'_>) -> Option<(Kind, bool)> {
    let kind = Kind::of(&ch.schema.as_ref()?.name)?;
    match ch.message_encoding.as_str() {
        "cdr" => Some((kind, true)),
        "ros1" => Some((kind, false)),
        _ => None,
    }
}

/// The series of the topics chosen (module [`super`]).
pub(super) fn read(file: &str, bytes: &[u8], opts: &LogOptions) -> Result<Vec<Series>> {
    let bad = |e: ::mcap::McapError| InputError::file(file, format!("an MCAP file: {e}"));
    let stream = ::mcap::MessageStream::new_with_options(
        bytes,
        ::mcap::read::Options::IgnoreEndMagic.into(),
    )
    .map_err(bad)?;
    // (topic, kind, cdr, log ns, data) of every readable message.
    let mut messages = Vec::new();
    let mut offered: Vec<Offered> = Vec::new();
    for m in stream {
        let m = m.map_err(bad)?;
        let Some((kind, cdr)) = readable(&m.channel) else {
            continue;
        };
        if !offered.iter().any(|o| o.name == m.channel.topic) {
            offered.push(Offered {
                name: m.channel.topic.clone(),
                kind: m
                    .channel
                    .schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default(),
            });
        }
        messages.push((
            m.channel.topic.clone(),
            kind,
            cdr,
            m.log_time as i128,
            m.data.into_owned(),
        ));
    }
    let topics = choose(file, Format::Mcap, &offered, opts)?;
    topics
        .iter()
        .map(|t| {
            let type_name = offered
                .iter()
                .find(|o| &o.name == t)
                .map_or("", |o| &o.kind);
            let of_topic = messages.iter().filter(|(topic, ..)| topic == t).map(
                |(_, kind, cdr, log_ns, data)| ros::Message {
                    kind: *kind,
                    cdr: *cdr,
                    log_ns: *log_ns,
                    data,
                },
            );
            ros::series(file, t, type_name, of_topic, opts.stamps, "log_time")
        })
        .collect()
}
