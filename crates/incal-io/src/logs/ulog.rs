//! PX4 ULog (file format version 1): the definitions (`F` formats, `A`
//! subscriptions) and the `D` data messages of the topics incal reads.
//!
//! A message is `u16 size, u8 type, size bytes`; a format is
//! `name:type field;…` with the types `int8_t` … `uint64_t`, `float`,
//! `double`, `bool`, `char`, arrays `type[n]` and other formats nested,
//! packed without alignment (padding is explicit, `_paddingN`). Data
//! appended after a crash (flag bits, `B`) follows the log and is read in
//! order; a message cut by the end of the file ends the log.

use std::collections::HashMap;

use super::{choose, Bytes, Format, LogOptions, Offered, Sample, Series, Stamps};
use super::{DEG_PER_RAD, G0_M_S2, UT_PER_GAUSS};
use crate::error::{InputError, Result};

/// Header: magic (7 bytes), version, start time (µs).
const HEADER_BYTES: usize = 16;
/// Nesting of formats allowed (PX4's are at most 3 deep).
const MAX_DEPTH: usize = 8;
/// Largest message (its size is a `u16`): no format flattens beyond it.
const MAX_MESSAGE_BYTES: usize = u16::MAX as usize;
/// The topics incal reads (module [`super`]); no other format is flattened.
const TOPICS: [&str; 5] = [
    "sensor_combined",
    "sensor_gyro",
    "sensor_accel",
    "sensor_mag",
    "vehicle_imu",
];

/// A flattened field: offset in the message, scalar type.
#[derive(Debug, Clone, Copy)]
struct Field {
    offset: usize,
    kind: Scalar,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
    Bool,
    Char,
}

impl Scalar {
    fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "int8_t" => Self::I8,
            "uint8_t" => Self::U8,
            "int16_t" => Self::I16,
            "uint16_t" => Self::U16,
            "int32_t" => Self::I32,
            "uint32_t" => Self::U32,
            "int64_t" => Self::I64,
            "uint64_t" => Self::U64,
            "float" => Self::F32,
            "double" => Self::F64,
            "bool" => Self::Bool,
            "char" => Self::Char,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 | Self::Bool | Self::Char => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    fn value(self, b: &[u8]) -> f64 {
        let a = |n: usize| -> [u8; 8] {
            let mut x = [0u8; 8];
            x[..n].copy_from_slice(&b[..n]);
            x
        };
        match self {
            Self::I8 => b[0] as i8 as f64,
            Self::U8 | Self::Bool | Self::Char => b[0] as f64,
            Self::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            Self::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            Self::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::I64 => i64::from_le_bytes(a(8)) as f64,
            Self::U64 => u64::from_le_bytes(a(8)) as f64,
            Self::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Self::F64 => f64::from_le_bytes(a(8)),
        }
    }
}

/// A format flattened: `name` or `name[i]` (nested: `outer.inner`) to its
/// field, and the message's size.
#[derive(Debug, Clone, Default)]
struct Flat {
    fields: HashMap<String, Field>,
    size: usize,
}

/// Flatten format `name` from the raw definitions (`name` → field list).
fn flatten(raw: &HashMap<String, String>, name: &str, depth: usize) -> Option<Flat> {
    if depth > MAX_DEPTH {
        return None;
    }
    let body = raw.get(name)?;
    let mut flat = Flat::default();
    for item in body.split(';').map(str::trim).filter(|s| !s.is_empty()) {
        let (ty, field) = item.split_once(' ')?;
        // `type[n]` is an array of n (`type[0]` of none), `type` one.
        let (base, array) = match ty.split_once('[') {
            Some((b, n)) => (b, Some(n.strip_suffix(']')?.parse::<usize>().ok()?)),
            None => (ty, None),
        };
        let n = array.unwrap_or(1);
        if n > MAX_MESSAGE_BYTES {
            return None;
        }
        let name_at = |i: usize| match array {
            None => field.to_string(),
            Some(_) => format!("{field}[{i}]"),
        };
        if let Some(s) = Scalar::parse(base) {
            // Sizes are checked before any field is made: a format larger
            // than a message can be is not a message's.
            if flat.size.checked_add(n.checked_mul(s.size())?)? > MAX_MESSAGE_BYTES {
                return None;
            }
            for i in 0..n {
                let offset = flat.size.checked_add(i.checked_mul(s.size())?)?;
                flat.fields.insert(name_at(i), Field { offset, kind: s });
            }
            flat.size = flat.size.checked_add(n.checked_mul(s.size())?)?;
        } else {
            let inner = flatten(raw, base, depth + 1)?;
            if flat.size.checked_add(n.checked_mul(inner.size)?)? > MAX_MESSAGE_BYTES {
                return None;
            }
            for i in 0..n {
                let at = flat.size.checked_add(i.checked_mul(inner.size)?)?;
                for (k, f) in &inner.fields {
                    flat.fields.insert(
                        format!("{}.{k}", name_at(i)),
                        Field {
                            offset: at + f.offset,
                            kind: f.kind,
                        },
                    );
                }
            }
            flat.size = flat.size.checked_add(n.checked_mul(inner.size)?)?;
        }
    }
    Some(flat)
}

/// What incal takes from a topic: columns from fields, each value
/// `field × scale` or, for integrated topics, `field ÷ (dt µs · 10⁻⁶) × scale`.
struct Recipe {
    columns: Vec<&'static str>,
    units: &'static str,
    sources: Vec<Source>,
}

/// A column's field, its scale and the field (µs) it is divided by.
type Source = (String, f64, Option<&'static str>);

fn triad(
    cols: [&'static str; 3],
    fields: [&str; 3],
    scale: f64,
    dt: Option<&'static str>,
) -> Vec<(&'static str, Source)> {
    (0..3)
        .map(|i| (cols[i], (fields[i].to_string(), scale, dt)))
        .collect()
}

const GYR: [&str; 3] = ["gyr_x", "gyr_y", "gyr_z"];
const ACC: [&str; 3] = ["acc_x", "acc_y", "acc_z"];
const MAG: [&str; 3] = ["mag_x", "mag_y", "mag_z"];

/// The recipe of a known topic, given its fields (`None`: not one incal
/// reads).
fn recipe(topic: &str, flat: &Flat) -> Option<Recipe> {
    let has = |f: &str| flat.fields.contains_key(f);
    let g = 1.0 / G0_M_S2;
    let (mut parts, units) = match topic {
        "sensor_combined" => {
            let mut p = triad(
                GYR,
                ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]"],
                DEG_PER_RAD,
                None,
            );
            p.extend(triad(
                ACC,
                [
                    "accelerometer_m_s2[0]",
                    "accelerometer_m_s2[1]",
                    "accelerometer_m_s2[2]",
                ],
                g,
                None,
            ));
            (p, "gyro_rad: rad/s x 180/pi -> gyr deg/s; accelerometer_m_s2: m/s2 / 9.80665 -> acc g")
        }
        "sensor_gyro" => (
            triad(GYR, ["x", "y", "z"], DEG_PER_RAD, None),
            "x y z: rad/s x 180/pi -> gyr deg/s; temperature: degC",
        ),
        "sensor_accel" => (
            triad(ACC, ["x", "y", "z"], g, None),
            "x y z: m/s2 / 9.80665 -> acc g; temperature: degC",
        ),
        "sensor_mag" => (
            triad(MAG, ["x", "y", "z"], UT_PER_GAUSS, None),
            "x y z: gauss x 100 -> mag uT; temperature: degC",
        ),
        "vehicle_imu" => {
            let mut p = triad(
                GYR,
                ["delta_angle[0]", "delta_angle[1]", "delta_angle[2]"],
                DEG_PER_RAD,
                Some("delta_angle_dt"),
            );
            p.extend(triad(
                ACC,
                [
                    "delta_velocity[0]",
                    "delta_velocity[1]",
                    "delta_velocity[2]",
                ],
                g,
                Some("delta_velocity_dt"),
            ));
            (p, "delta_angle / delta_angle_dt: rad/s x 180/pi -> gyr deg/s; delta_velocity / delta_velocity_dt: m/s2 / 9.80665 -> acc g")
        }
        _ => return None,
    };
    if topic != "sensor_combined" && topic != "vehicle_imu" && has("temperature") {
        parts.push(("temperature_c", ("temperature".into(), 1.0, None)));
    }
    if !parts
        .iter()
        .all(|(_, (f, _, dt))| has(f) && dt.is_none_or(has))
    {
        return None;
    }
    Some(Recipe {
        columns: parts.iter().map(|(c, _)| *c).collect(),
        units,
        sources: parts.into_iter().map(|(_, s)| s).collect(),
    })
}

/// A subscription: its topic's format and the instance.
struct Subscription {
    format: String,
    instance: u8,
}

/// The definitions and subscriptions of a log, and its data messages.
struct Parsed<'a> {
    formats: HashMap<String, String>,
    /// One per topic and instance, however often subscribed.
    subs: Vec<Subscription>,
    /// Data messages: the subscription (index into `subs`) and the body.
    data: Vec<(usize, &'a [u8])>,
}

/// The flag bits (`B`): where data appended after a crash starts.
/// Refuses incompatible flags this reader does not know.
fn flag_bits(file: &str, body: &[u8]) -> Result<Vec<usize>> {
    let m = Bytes { data: body };
    let incompat = m.get(8, 8).unwrap_or(&[0; 8]);
    if incompat[0] & !1 != 0 || incompat[1..].iter().any(|&x| x != 0) {
        return Err(InputError::file(
            file,
            format!(
                "a PX4 ULog with incompatible flags this reader does not know ({incompat:02x?})"
            ),
        ));
    }
    let mut offsets: Vec<usize> = (0..3)
        .filter_map(|k| m.get(16 + 8 * k, 8))
        .map(|x| u64::from_le_bytes(x.try_into().unwrap_or([0; 8])) as usize)
        .filter(|&o| o > 0 && incompat[0] & 1 == 1)
        .collect();
    offsets.sort_unstable();
    Ok(offsets)
}

/// Every message of the log (definitions and data), in order. Data
/// appended after a crash starts at the offsets the flag bits give: the
/// message before each (often cut) ends where it starts.
fn parse<'a>(file: &str, bytes: &'a [u8]) -> Result<Parsed<'a>> {
    if bytes.len() < HEADER_BYTES {
        return Err(InputError::file(file, "a PX4 ULog shorter than its header"));
    }
    let b = Bytes { data: bytes };
    let mut p = Parsed {
        formats: HashMap::new(),
        subs: Vec::new(),
        data: Vec::new(),
    };
    let mut ids: HashMap<u16, usize> = HashMap::new();
    let mut appended: Vec<usize> = Vec::new();
    let mut at = HEADER_BYTES;
    while let (Some(size), Some(kind)) = (b.u16(at), b.u8(at + 2)) {
        let end = at + 3 + size as usize;
        if let Some(&next) = appended.first() {
            if end > next || at >= next {
                appended.remove(0);
                if next > at {
                    at = next;
                    continue;
                }
            }
        }
        let Some(body) = b.get(at + 3, size as usize) else {
            break; // cut by the end of the file: the log ends here
        };
        let m = Bytes { data: body };
        match kind {
            b'B' => {
                appended = flag_bits(file, body)?
                    .into_iter()
                    .filter(|&o| o > at)
                    .collect()
            }
            b'F' => {
                let text = String::from_utf8_lossy(body);
                if let Some((name, fields)) = text.split_once(':') {
                    p.formats.insert(name.to_string(), fields.to_string());
                }
            }
            b'A' => {
                if let (Some(instance), Some(id)) = (m.u8(0), m.u16(1)) {
                    let format = String::from_utf8_lossy(&body[3..])
                        .trim_end_matches('\0')
                        .to_string();
                    let k = match p
                        .subs
                        .iter()
                        .position(|s| s.format == format && s.instance == instance)
                    {
                        Some(k) => k,
                        None => {
                            p.subs.push(Subscription { format, instance });
                            p.subs.len() - 1
                        }
                    };
                    ids.insert(id, k);
                }
            }
            b'R' => {
                if let Some(id) = m.u16(0) {
                    ids.remove(&id);
                }
            }
            b'D' => {
                if let Some(k) = m.u16(0).and_then(|id| ids.get(&id)) {
                    p.data.push((*k, &body[2..]));
                }
            }
            _ => {}
        }
        at = end;
    }
    Ok(p)
}

/// The user's name of a subscription: `topic` for instance 0, else
/// `topic:N`; both forms name instance 0.
fn user_name(s: &Subscription) -> String {
    if s.instance == 0 {
        s.format.clone()
    } else {
        format!("{}:{}", s.format, s.instance)
    }
}

/// The series of the topics chosen (module [`super`]).
pub(super) fn read(file: &str, bytes: &[u8], opts: &LogOptions) -> Result<Vec<Series>> {
    let p = parse(file, bytes)?;
    let mut flats: HashMap<String, Option<Flat>> = HashMap::new();
    let mut offered: Vec<(usize, Offered)> = Vec::new();
    let mut order: Vec<usize> = (0..p.subs.len()).collect();
    order.sort_by_key(|&k| (p.subs[k].format.clone(), p.subs[k].instance));
    for id in order {
        let s = &p.subs[id];
        if !TOPICS.contains(&s.format.as_str()) {
            continue;
        }
        let flat = flats
            .entry(s.format.clone())
            .or_insert_with(|| flatten(&p.formats, &s.format, 0));
        if flat.as_ref().and_then(|f| recipe(&s.format, f)).is_some() {
            offered.push((
                id,
                Offered {
                    name: user_name(s),
                    kind: s.format.clone(),
                },
            ));
        }
    }
    let named: Vec<String> = opts
        .topics
        .iter()
        .map(|t| t.strip_suffix(":0").unwrap_or(t).to_string())
        .collect();
    let wanted = LogOptions {
        topics: named,
        stamps: opts.stamps,
    };
    let list: Vec<Offered> = offered.iter().map(|(_, o)| o.clone()).collect();
    let topics = choose(file, Format::Ulog, &list, &wanted)?;
    let mut out = Vec::new();
    for t in topics {
        let (id, _) = offered.iter().find(|(_, o)| o.name == t).expect("chosen");
        let s = &p.subs[*id];
        let flat = flats[&s.format].as_ref().expect("offered");
        out.push(series(
            file,
            &t,
            &s.format,
            flat,
            *id,
            &p.data,
            opts.stamps,
        )?);
    }
    Ok(out)
}

/// One topic's samples.
fn series(
    file: &str,
    topic: &str,
    format: &str,
    flat: &Flat,
    id: usize,
    data: &[(usize, &[u8])],
    stamps: Stamps,
) -> Result<Series> {
    let r = recipe(format, flat).expect("offered");
    let field = |name: &str| flat.fields.get(name).copied();
    let log_field = field("timestamp")
        .ok_or_else(|| InputError::file(file, format!("topic {topic}: no timestamp field")))?;
    let (stamp_field, stamp_name) = match (stamps, field("timestamp_sample")) {
        (Stamps::Header, Some(f)) => (f, "timestamp_sample, us"),
        _ => (log_field, "timestamp, us"),
    };
    // Stamps are whole microseconds: a format that declares them otherwise
    // is no PX4 topic's.
    for f in [log_field, stamp_field] {
        if !matches!(
            f.kind,
            Scalar::U64 | Scalar::I64 | Scalar::U32 | Scalar::I32
        ) {
            return Err(InputError::file(
                file,
                format!("topic {topic}: its time stamps are not integers (microseconds)"),
            ));
        }
    }
    let sources: Vec<(Field, f64, Option<Field>)> = r
        .sources
        .iter()
        .map(|(f, scale, dt)| (field(f).expect("recipe"), *scale, dt.and_then(field)))
        .collect();
    let read = |f: Field, msg: &[u8]| -> Option<f64> {
        msg.get(f.offset..f.offset + f.kind.size())
            .map(|b| f.kind.value(b))
    };
    let mut samples = Vec::new();
    for (n, (_, msg)) in data.iter().filter(|(i, _)| *i == id).enumerate() {
        let short = || {
            InputError::file(
                file,
                format!(
                    "topic {topic}: data message {} shorter than its format ({} bytes)",
                    n + 1,
                    flat.size
                ),
            )
        };
        let log = read(log_field, msg).ok_or_else(short)?;
        let stamp = read(stamp_field, msg).ok_or_else(short)?;
        let mut values = Vec::with_capacity(sources.len());
        for (f, scale, dt) in &sources {
            let mut v = read(*f, msg).ok_or_else(short)? * scale;
            if let Some(dt) = dt {
                v /= read(*dt, msg).ok_or_else(short)? * 1e-6;
            }
            values.push(v);
        }
        samples.push(Sample {
            log_ns: log as i128 * 1000,
            stamp_ns: stamp as i128 * 1000,
            values,
        });
    }
    Ok(Series {
        topic: topic.to_string(),
        kind: format.to_string(),
        columns: r.columns,
        units: r.units,
        stamp_name,
        samples,
    })
}
