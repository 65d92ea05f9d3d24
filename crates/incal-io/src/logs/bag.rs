//! ROS 1 bags (format 2.0): records `u32 header length, header fields
//! (u32 length, name=value), u32 data length, data`; the field `op` gives
//! the record: 0x07 connection (`conn`, `topic`; its data the connection
//! header with `type`), 0x05 chunk (`compression` none, bz2 or lz4, data
//! the records inside), 0x02 message data (`conn`, `time`: u32 s, u32 ns).
//! Index records are skipped; connections are read wherever they are.

use std::collections::BTreeMap;
use std::io::Read;

use super::ros::{Kind, Topics};
use super::{choose, Bytes, Format, LogOptions, Series};
use crate::error::{InputError, Result};

/// Magic line of a bag 2.0.
const MAGIC: usize = 13;
/// Largest chunk inflated (bytes): a bag's are a few MB (rosbag's
/// default is 768 KiB).
const MAX_CHUNK_BYTES: usize = 1 << 28;

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
    let mut out = Vec::with_capacity(size.min(1 << 26));
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
            "a ROS 1 bag: a chunk inflates beyond 256 MiB",
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

/// The records of one chunk (inflated), read into `conns` and `topics`.
fn chunk(
    file: &str,
    data: &[u8],
    conns: &mut BTreeMap<u32, Connection>,
    topics: &mut Topics,
) -> Result<()> {
    let inner = records(data, 0).map_err(|at| {
        InputError::file(
            file,
            format!("a ROS 1 bag: a broken record at byte {at} of a chunk"),
        )
    })?;
    for (f, d) in inner {
        match op(&f) {
            Some(0x07) => add_connection(&f, d, conns, topics),
            Some(0x02) => {
                let time = f.get("time").map(|t| Bytes { data: t });
                let (Some(conn), Some((s, ns))) = (
                    u32_of(&f, "conn"),
                    time.and_then(|t| Some((t.u32(0)?, t.u32(4)?))),
                ) else {
                    return Err(InputError::file(
                        file,
                        "a ROS 1 bag: a message record without its conn or time field",
                    ));
                };
                let Some(c) = conns.get(&conn) else {
                    return Err(InputError::file(
                        file,
                        format!("a ROS 1 bag: a message of connection {conn} before that connection's record"),
                    ));
                };
                if let Some(kind) = c.kind {
                    let log_ns = s as i128 * 1_000_000_000 + ns as i128;
                    topics.message(&c.topic, kind, false, log_ns, d);
                }
            }
            _ => {}
        }
    }
    Ok(())
}

fn add_connection(
    f: &BTreeMap<&str, &[u8]>,
    d: &[u8],
    conns: &mut BTreeMap<u32, Connection>,
    topics: &mut Topics,
) {
    if let Some((id, c)) = connection(f, d) {
        topics.connection(&c.topic, &c.type_name);
        conns.insert(id, c);
    }
}

/// The series of the topics chosen (module [`super`]): each chunk is
/// inflated, read and dropped in turn, so only the decoded samples are
/// kept.
pub(super) fn read(file: &str, bytes: &[u8], opts: &LogOptions) -> Result<Vec<Series>> {
    let broken =
        |at: usize| InputError::file(file, format!("a ROS 1 bag: a broken record at byte {at}"));
    let top = records(bytes, MAGIC).map_err(broken)?;
    let mut conns: BTreeMap<u32, Connection> = BTreeMap::new();
    let mut topics = Topics::default();
    for (f, d) in &top {
        match op(f) {
            Some(0x07) => add_connection(f, d, &mut conns, &mut topics),
            Some(0x05) => chunk(file, &inflate(file, f, d)?, &mut conns, &mut topics)?,
            _ => {}
        }
    }
    let chosen = choose(file, Format::Bag, &topics.offered(), opts)?;
    topics.series(file, &chosen, opts.stamps, "record time")
}
