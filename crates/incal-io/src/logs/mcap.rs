//! MCAP files through the `mcap` crate's sans-io reader (Foxglove's:
//! records, chunks compressed with zstd or lz4), with a record length
//! limit so that no length field makes it allocate beyond it: channels
//! whose schema is `sensor_msgs/msg/Imu` or `sensor_msgs/msg/Temperature`,
//! messages in `cdr` (ROS 2) or `ros1` encoding, each decoded as it comes;
//! `log_time` is the log's time.

use std::collections::HashMap;

use ::mcap::records::Record;
use ::mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use super::ros::{Kind, Topics};
use super::{choose, Format, LogOptions, Series};
use crate::error::{InputError, Result};

/// Longest record (and inflated chunk) read: far above any IMU log's.
const MAX_RECORD_BYTES: usize = 1 << 28;

/// A channel: topic, schema id and message encoding.
struct Channel {
    topic: String,
    schema: u16,
    encoding: String,
}

/// The series of the topics chosen (module [`super`]). The crate's reader
/// can fail an internal check on a record that runs past its chunk (an
/// arithmetic overflow, a panic where those are checked): that is the
/// file's inconsistency, refused as such.
pub(super) fn read(file: &str, bytes: &[u8], opts: &LogOptions) -> Result<Vec<Series>> {
    let read = std::panic::AssertUnwindSafe(|| topics(file, bytes));
    let topics = std::panic::catch_unwind(read).map_err(|_| {
        InputError::file(
            file,
            "an MCAP file: its records are inconsistent (a record runs past its chunk)",
        )
    })??;
    let chosen = choose(file, Format::Mcap, &topics.offered(), opts)?;
    topics.series(file, &chosen, opts.stamps, "log_time")
}

/// Every record of the file, read into topics.
fn topics(file: &str, bytes: &[u8]) -> Result<Topics> {
    let bad = |e: ::mcap::McapError| InputError::file(file, format!("an MCAP file: {e}"));
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_end_magic(true)
            .with_record_length_limit(MAX_RECORD_BYTES),
    );
    let mut schemas: HashMap<u16, String> = HashMap::new();
    let mut channels: HashMap<u16, Channel> = HashMap::new();
    let mut topics = Topics::default();
    let mut at = 0usize;
    while let Some(event) = reader.next_event() {
        match event.map_err(bad)? {
            LinearReadEvent::ReadRequest(need) => {
                let n = need.min(bytes.len() - at);
                reader.insert(n).copy_from_slice(&bytes[at..at + n]);
                reader.notify_read(n);
                at += n;
            }
            LinearReadEvent::Record { data, opcode } => {
                match ::mcap::parse_record(opcode, data).map_err(bad)? {
                    Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    Record::Channel(c) => {
                        // A known type in an encoding incal does not read
                        // is not offered as that type.
                        let schema = schemas.get(&c.schema_id).cloned().unwrap_or_default();
                        let type_name = match c.message_encoding.as_str() {
                            "cdr" | "ros1" => schema,
                            other => format!("{schema} ({other})"),
                        };
                        topics.connection(&c.topic, &type_name);
                        channels.insert(
                            c.id,
                            Channel {
                                topic: c.topic,
                                schema: c.schema_id,
                                encoding: c.message_encoding,
                            },
                        );
                    }
                    Record::Message { header, data } => {
                        let Some(c) = channels.get(&header.channel_id) else {
                            return Err(InputError::file(
                                file,
                                format!("an MCAP file: a message of channel {} before that channel's record", header.channel_id),
                            ));
                        };
                        let kind = schemas.get(&c.schema).and_then(|s| Kind::of(s));
                        let cdr = match c.encoding.as_str() {
                            "cdr" => Some(true),
                            "ros1" => Some(false),
                            _ => None,
                        };
                        if let (Some(kind), Some(cdr)) = (kind, cdr) {
                            topics.message(&c.topic, kind, cdr, header.log_time as i128, &data);
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(topics)
}
