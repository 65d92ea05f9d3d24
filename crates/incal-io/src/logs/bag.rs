//! ROS 1 bags (format 2.0): records `u32 header length, header fields
//! (u32 length, name=value), u32 data length, data`; the field `op` gives
//! the record: 0x07 connection (`conn`, `topic`; its data the connection
//! header with `type`), 0x05 chunk (`compression` none, bz2 or lz4, data
//! the records inside), 0x02 message data (`conn`, `time`: u32 s, u32 ns).
//! Index records are skipped; connections are read wherever they are.

use std::collections::BTreeMap;
use std::io::Read;

use super::ros::{self, Kind};
use super::{choose, Bytes, Format, LogOptions, Offered, Series};
use crate::error::{InputError, Result};

/// Magic line of a bag 2.0.
const MAGIC: usize = 13;
/// Largest chunk inflated (bytes): a bag's are a few MB.
const MAX_CHUNK_BYTES: usize = 1 << 30;

/// A record's header fields.
fn fields(h: &[u8]) -> Option<BTreeMap<&str, &[u8]>> {
    let b = Bytes { data: h };
    let mut out = BTreeMap::new();
    let mut at = 0usize;
    while at < h.len() {
        let len = b.u32(at)? as usize;
        let f = b.get(at + 4, len)?;
        let eq = f.iter().position(|&c| c == b'=')?;
        out.insert(std::str::from_utf8(&f[..eq]).ok()?, &f[eq + 1..]);
        at += 4 + len;
    }
    Some(out)
}

/// One record: header fields and data.
type Record<'a> = (BTreeMap<&'a str, &'a [u8]>, &'a [u8]);

/// The records of `data` from `at`; `Err` names the offset of a broken one.
fn records(data: &[u8], mut at: usize) -> std::result::Result<Vec<Record<'_>>, usize> {
    let b = Bytes { data };
    let mut out = Vec::new();
    while at < data.len() {
        let broken = at;
        let hl = b.u32(at).ok_or(broken)? as usize;
        let h = b.get(at + 4, hl).ok_or(broken)?;
        let dl_at = at + 4 + hl;
        let dl = b.u32(dl_at).ok_or(broken)? as usize;
        let d = b.get(dl_at + 4, dl).ok_or(broken)?;
        out.push((fields(h).ok_or(broken)?, d));
        at = dl_at + 4 + dl;
    }
    Ok(out)
}

fn op(f: &BTreeMap<&str, &[u8]>) -> Option<u8> {
    f.get("op").and_then(|v| v.first().copied())
}

fn u32_of(f: &BTreeMap<&str, &[u8]>, key: &str) -> Option<u32> {
    Bytes { data: f.get(key)? }.u32(0)
}

/// A chunk's records, inflated.
fn inflate(file: &str, f: &BTreeMap<&str, &[u8]>, data: &[u8]) -> Result<Vec<u8>> {
    let compression = f.get("compression").copied().unwrap_or(b"none");
    let size = u32_of(f, "size").unwrap_or(0) as usize;
    let bad = |e: std::io::Error| {
        InputError::file(
            file,
            format!("a ROS 1 bag: a chunk cannot be inflated: {e}"),
        )
    };
    let mut out = Vec::with_capacity(size.min(MAX_CHUNK_BYTES));
    let limit = (MAX_CHUNK_BYTES + 1) as u64;
    match compression {
        b"none" => return Ok(data.to_vec()),
        b"bz2" => bzip2::read::BzDecoder::new(data)
            .take(limit)
            .read_to_end(&mut out)
            .map_err(bad)?,
        b"lz4" => lz4::Decoder::new(data)
            .map_err(bad)?
            .take(limit)
            .read_to_end(&mut out)
            .map_err(bad)?,
        other => {
            return Err(InputError::file(
                file,
                format!(
                    "a ROS 1 bag: chunk compression '{}' (incal reads none, bz2 and lz4)",
                    String::from_utf8_lossy(other)
                ),
            ))
        }
    };
    if out.len() > MAX_CHUNK_BYTES {
        return Err(InputError::file(
            file,
            "a ROS 1 bag: a chunk inflates beyond 1 GiB",
        ));
    }
    Ok(out)
}

/// A connection: topic and message type.
struct Connection {
    topic: String,
    kind: Option<Kind>,
    type_name: String,
}

fn connection(f: &BTreeMap<&str, &[u8]>, data: &[u8]) -> Option<(u32, Connection)> {
    let id = u32_of(f, "conn")?;
    let topic = String::from_utf8_lossy(f.get("topic")?).into_owned();
    let inner = fields(data)?;
    let type_name = String::from_utf8_lossy(inner.get("type")?).into_owned();
    Some((
        id,
        Connection {
            topic,
            kind: Kind::of(&type_name),
            type_name,
        },
    ))
}

/// The series of the topics chosen (module [`super`]).
pub(super) fn read(file: &str, bytes: &[u8], opts: &LogOptions) -> Result<Vec<Series>> {
    let broken =
        |at: usize| InputError::file(file, format!("a ROS 1 bag: a broken record at byte {at}"));
    let top = records(bytes, MAGIC).map_err(broken)?;
    let mut conns: BTreeMap<u32, Connection> = BTreeMap::new();
    // (conn, record time ns, data) of every message, in file order.
    let mut chunks: Vec<Vec<u8>> = Vec::new();
    for (f, d) in &top {
        match op(f) {
            Some(0x07) => conns.extend(connection(f, d)),
            Some(0x05) => chunks.push(inflate(file, f, d)?),
            _ => {}
        }
    }
    let mut messages: Vec<(u32, i128, &[u8])> = Vec::new();
    for c in &chunks {
        let inner = records(c, 0).map_err(|at| {
            InputError::file(
                file,
                format!("a ROS 1 bag: a broken record at byte {at} of a chunk"),
            )
        })?;
        for (f, d) in inner {
            match op(&f) {
                Some(0x07) => conns.extend(connection(&f, d)),
                Some(0x02) => {
                    let (Some(conn), Some(t)) = (u32_of(&f, "conn"), f.get("time")) else {
                        return Err(broken(0));
                    };
                    let t = Bytes { data: t };
                    let (Some(s), Some(ns)) = (t.u32(0), t.u32(4)) else {
                        return Err(broken(0));
                    };
                    messages.push((conn, s as i128 * 1_000_000_000 + ns as i128, d));
                }
                _ => {}
            }
        }
    }
    let mut offered: Vec<Offered> = Vec::new();
    for c in conns.values() {
        if c.kind.is_some() && !offered.iter().any(|o| o.name == c.topic) {
            offered.push(Offered {
                name: c.topic.clone(),
                kind: c.type_name.clone(),
            });
        }
    }
    let topics = choose(file, Format::Bag, &offered, opts)?;
    topics
        .iter()
        .map(|t| {
            let ids: Vec<(u32, Kind)> = conns
                .iter()
                .filter(|(_, c)| &c.topic == t)
                .filter_map(|(id, c)| c.kind.map(|k| (*id, k)))
                .collect();
            let type_name = offered
                .iter()
                .find(|o| &o.name == t)
                .map_or("", |o| &o.kind);
            let of_topic = messages.iter().filter_map(|(c, log_ns, data)| {
                let (_, kind) = ids.iter().find(|(i, _)| i == c)?;
                Some(ros::Message {
                    kind: *kind,
                    cdr: false,
                    log_ns: *log_ns,
                    data,
                })
            });
            ros::series(file, t, type_name, of_topic, opts.stamps, "record time")
        })
        .collect()
}
