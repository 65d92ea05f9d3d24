//! Robot logs: bags built record by record (every chunk compression), CDR
//! in both byte orders, joined topics, and the reader over a real ULog in
//! small pieces.

use std::io::{Read, Write};

use super::*;
use crate::{ReadOptions, Reader};

/// A bag record: header fields, then data.
fn record(fields: &[(&str, &[u8])], data: &[u8]) -> Vec<u8> {
    let mut h = Vec::new();
    for (k, v) in fields {
        h.extend(((k.len() + 1 + v.len()) as u32).to_le_bytes());
        h.extend(k.as_bytes());
        h.push(b'=');
        h.extend(*v);
    }
    let mut out = (h.len() as u32).to_le_bytes().to_vec();
    out.extend(h);
    out.extend((data.len() as u32).to_le_bytes());
    out.extend(data);
    out
}

/// A ROS 1 `sensor_msgs/Imu` with stamp `s`.`ns`, rates `w` and
/// accelerations `a`.
fn imu_ros1(s: u32, ns: u32, w: [f64; 3], a: [f64; 3]) -> Vec<u8> {
    let mut m = 9u32.to_le_bytes().to_vec();
    m.extend(s.to_le_bytes());
    m.extend(ns.to_le_bytes());
    m.extend(4u32.to_le_bytes());
    m.extend(b"imu0");
    let mut d = vec![0.0; 28];
    d[13..16].copy_from_slice(&w);
    d[25..28].copy_from_slice(&a);
    d.extend([0.0; 9]);
    for x in d {
        m.extend(x.to_le_bytes());
    }
    m
}

fn temperature_ros1(s: u32, t: f64) -> Vec<u8> {
    let mut m = 1u32.to_le_bytes().to_vec();
    m.extend(s.to_le_bytes());
    m.extend(0u32.to_le_bytes());
    m.extend(0u32.to_le_bytes());
    m.extend(t.to_le_bytes());
    m.extend(0.0f64.to_le_bytes());
    m
}

fn connection(id: u32, topic: &str, kind: &str) -> Vec<u8> {
    let inner = record(
        &[("topic", topic.as_bytes()), ("type", kind.as_bytes())],
        &[],
    );
    // The connection header is the fields alone (no data length).
    let header = &inner[4..inner.len() - 4];
    record(
        &[
            ("op", &[7]),
            ("conn", &id.to_le_bytes()),
            ("topic", topic.as_bytes()),
        ],
        header,
    )
}

fn message(conn: u32, s: u32, data: &[u8]) -> Vec<u8> {
    let mut time = s.to_le_bytes().to_vec();
    time.extend(500u32.to_le_bytes());
    record(
        &[("op", &[2]), ("conn", &conn.to_le_bytes()), ("time", &time)],
        data,
    )
}

/// A bag of one uncompressed chunk holding `inner`'s records.
fn bag_of(inner: &[u8]) -> Vec<u8> {
    let mut b = b"#ROSBAG V2.0\n".to_vec();
    let size = (inner.len() as u32).to_le_bytes();
    b.extend(record(
        &[("op", &[5]), ("compression", b"none"), ("size", &size)],
        inner,
    ));
    b
}

/// A bag of 20 Imu messages at 100 Hz and 3 temperatures, in one chunk
/// compressed as `compression` says.
fn bag(compression: &str) -> Vec<u8> {
    let mut inner = connection(0, "/imu", "sensor_msgs/Imu");
    inner.extend(connection(1, "/temp", "sensor_msgs/Temperature"));
    inner.extend(message(1, 0, &temperature_ros1(0, 21.5)));
    for k in 0..20u32 {
        let w = [0.01 * k as f64, -0.02, 0.5];
        inner.extend(message(
            0,
            k,
            &imu_ros1(100, k * 10_000_000, w, [0.0, 0.1, 9.80665]),
        ));
        if k == 10 {
            inner.extend(message(1, k, &temperature_ros1(k, 22.0)));
        }
    }
    let data = match compression {
        "none" => inner.clone(),
        "bz2" => {
            let mut e = bzip2::write::BzEncoder::new(Vec::new(), bzip2::Compression::best());
            e.write_all(&inner).unwrap();
            e.finish().unwrap()
        }
        _ => {
            let mut e = lz4::EncoderBuilder::new().build(Vec::new()).unwrap();
            e.write_all(&inner).unwrap();
            e.finish().0
        }
    };
    let mut out = b"#ROSBAG V2.0\n".to_vec();
    out.extend(record(&[("op", &[3])], &[b' '; 16]));
    out.extend(record(
        &[
            ("op", &[5]),
            ("compression", compression.as_bytes()),
            ("size", &(inner.len() as u32).to_le_bytes()),
        ],
        &data,
    ));
    out
}

fn csv(bytes: &[u8], topics: &[&str], stamps: Stamps) -> Result<String> {
    let format = Format::detect(bytes).expect("a log");
    let opts = LogOptions {
        topics: topics.iter().map(|t| t.to_string()).collect(),
        stamps,
    };
    convert("t.bag", format, bytes, &opts).map(|c| c.text)
}

#[test]
fn a_bag_reads_the_same_whatever_its_chunks_compression() {
    let plain = csv(&bag("none"), &["/imu", "/temp"], Stamps::Header).unwrap();
    assert_eq!(
        csv(&bag("bz2"), &["/imu", "/temp"], Stamps::Header).unwrap(),
        plain
    );
    assert_eq!(
        csv(&bag("lz4"), &["/imu", "/temp"], Stamps::Header).unwrap(),
        plain
    );
    let lines: Vec<&str> = plain.lines().collect();
    let h = lines.iter().position(|l| l.starts_with("time_s")).unwrap();
    assert_eq!(
        lines[h],
        "time_s,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,temperature_c"
    );
    // Header stamps 100 s + k·10 ms: exact decimal seconds from the first.
    assert!(lines[h + 1].starts_with("0,0,"), "{}", lines[h + 1]);
    assert!(lines[h + 4].starts_with("0.03,"), "{}", lines[h + 4]);
    // 0.5 rad/s in deg/s; 9.80665 m/s² is 1 g; the temperature held.
    assert!(
        lines[h + 1].ends_with(&format!(
            ",{:?},0,{:?},1,21.5",
            0.5f64.to_degrees(),
            0.1 / 9.80665
        )),
        "{}",
        lines[h + 1]
    );
    assert!(lines[h + 11].ends_with(",22"), "{}", lines[h + 11]);
    assert!(lines.contains(&"first_stamp_s,100"), "{plain}");
    // The log's record times: 1 s apart (and 500 ns).
    let by_log = csv(&bag("none"), &["/imu"], Stamps::Log).unwrap();
    assert!(by_log.lines().any(|l| l.starts_with("3,")), "{by_log}");
}

#[test]
fn a_bag_refuses_what_it_cannot_read() {
    let mut b = bag("none");
    let e = csv(&b, &[], Stamps::Header).unwrap_err().to_string();
    assert!(e.contains("give --topic, one of the topics incal reads here: /imu (sensor_msgs/Imu), /temp (sensor_msgs/Temperature)"), "{e}");
    let e = csv(&b, &["/odom"], Stamps::Header).unwrap_err().to_string();
    assert!(e.contains("--topic '/odom': not in this ROS 1 bag"), "{e}");
    b.truncate(b.len() - 3);
    let e = csv(&b, &["/imu"], Stamps::Header).unwrap_err().to_string();
    assert!(e.contains("a broken record at byte"), "{e}");
    let mut z = bag("none");
    let at = z.windows(4).position(|w| w == b"none").unwrap();
    z[at..at + 4].copy_from_slice(b"zstd");
    let e = csv(&z, &["/imu"], Stamps::Header).unwrap_err().to_string();
    assert!(e.contains("chunk compression 'zstd'"), "{e}");
}

#[test]
fn cdr_reads_either_byte_order() {
    let w = [0.25, -1.5, 3.0];
    let a = [9.0, 0.5, -0.125];
    let body = |big: bool| {
        let mut b: Vec<u8> = vec![0, if big { 0 } else { 1 }, 0, 0];
        let push = |b: &mut Vec<u8>, x: &[u8]| {
            let mut v = x.to_vec();
            if big {
                v.reverse();
            }
            b.extend(v);
        };
        push(&mut b, &7i32.to_le_bytes());
        push(&mut b, &25u32.to_le_bytes());
        push(&mut b, &4u32.to_le_bytes());
        b.extend(b"imu\0");
        // 12 + 4 = 16: already aligned to 8 from the body's start.
        let mut d = vec![0.0f64; 37];
        d[13..16].copy_from_slice(&w);
        d[25..28].copy_from_slice(&a);
        for x in d {
            push(&mut b, &x.to_le_bytes());
        }
        b
    };
    let le = ros::cdr(ros::Kind::Imu, &body(false)).unwrap();
    let be = ros::cdr(ros::Kind::Imu, &body(true)).unwrap();
    assert_eq!(le.stamp_ns, 7_000_000_025);
    assert_eq!(le.values, be.values);
    assert_eq!(le.values[2], 3.0f64.to_degrees());
    assert_eq!(le.values[5], -0.125 / G0_M_S2);
    assert_eq!(
        ros::cdr(ros::Kind::Imu, &body(false)[..60]).err(),
        Some("is too short for its type")
    );
    assert!(ros::cdr(ros::Kind::Imu, &[0, 7, 0, 0, 1, 2])
        .err()
        .unwrap()
        .contains("not plain CDR"));
}

/// A reader that hands out at most `n` bytes a call.
struct Trickle<'a>(&'a [u8], usize);

impl Read for Trickle<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.1.min(buf.len()).min(self.0.len());
        buf[..n].copy_from_slice(&self.0[..n]);
        self.0 = &self.0[n..];
        Ok(n)
    }
}

#[test]
fn the_reader_reads_a_real_ulog_in_pieces_and_hashes_its_bytes() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../incal/tests/fixtures/robot_logs/pyulog_sample_appended_multiple.ulg"
    );
    let bytes = std::fs::read(path).unwrap();
    let read = |chunk: usize| {
        let mut r = Reader::new("f.ulg", Trickle(&bytes, chunk), &ReadOptions::default()).unwrap();
        assert_eq!(
            r.header().names()[..4],
            ["time_s", "gyr_x", "gyr_y", "gyr_z"]
        );
        let mut first = Vec::new();
        while let Some(row) = r.next_row().unwrap() {
            if first.is_empty() {
                first = (0..row.width()).map(|c| row.text(c).into_owned()).collect();
            }
        }
        (first, r.finish().unwrap())
    };
    let (a, sa) = read(1);
    let (b, sb) = read(7);
    assert_eq!(a, b);
    assert_eq!(sa, sb);
    assert_eq!(sa.rows, 2373);
    assert_eq!(sa.sha256, crate::sha256_hex(&bytes));
    assert_eq!(sa.bytes, bytes.len() as u64);
    assert_eq!(sa.preamble[0].key, "format");
    assert_eq!(sa.preamble[0].value, "PX4 ULog");
    // A CSV named as a log's topic is refused, naming the option.
    let opts = ReadOptions {
        log: LogOptions {
            topics: vec!["sensor_combined".into()],
            stamps: Stamps::Header,
        },
        ..ReadOptions::default()
    };
    let e = Reader::new("a.csv", &b"time_s,x\n0,1\n"[..], &opts)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.starts_with("a.csv: --topic 'sensor_combined': not a PX4 ULog"),
        "{e}"
    );
}

/// A ULog's file header (version 1, start time 0).
fn ulog_start() -> Vec<u8> {
    let mut out = b"ULog\x01\x12\x35\x01".to_vec();
    out.extend(0u64.to_le_bytes());
    out
}

/// An `A` message: subscription `id` of `topic`'s `instance`.
fn subscribe(instance: u8, id: u16, topic: &str) -> Vec<u8> {
    let mut add = vec![instance];
    add.extend(id.to_le_bytes());
    add.extend(topic.as_bytes());
    msg(b'A', &add)
}

/// A small PX4 ULog of `sensor_gyro` (nested and array fields, padding).
fn ulog_bytes(rows: usize) -> Vec<u8> {
    let mut out = ulog_start();
    out.extend(msg(b'F', b"clip:uint8_t[3] counter;"));
    out.extend(msg(b'F', b"sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;float x;float y;float z;float temperature;clip c;uint8_t[1] _padding0;"));
    out.extend(subscribe(1, 3, "sensor_gyro"));
    for k in 0..rows as u64 {
        let mut d = 3u16.to_le_bytes().to_vec();
        d.extend((k * 4000 + 100).to_le_bytes());
        d.extend((k * 4000).to_le_bytes());
        for v in [0.01f32, -0.02, 0.5, 35.5] {
            d.extend(v.to_le_bytes());
        }
        d.extend([0u8; 4]);
        out.extend(msg(b'D', &d));
    }
    out
}

#[test]
fn a_ulog_topic_with_nested_fields_reads_by_its_instance() {
    let bytes = ulog_bytes(5);
    let text = csv(&bytes, &["sensor_gyro:1"], Stamps::Header).unwrap();
    let rows: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("time_s"))
        .collect();
    assert_eq!(rows[0], "time_s,gyr_x,gyr_y,gyr_z,temperature_c");
    assert_eq!(rows.len(), 6);
    assert!(rows[2].starts_with("0.004,"), "{}", rows[2]);
    assert!(rows[1].ends_with(",35.5"), "{}", rows[1]);
    let log = csv(&bytes, &[], Stamps::Log).unwrap();
    assert!(
        log.contains("stamps,\"log (timestamp, us), s from the first row's\""),
        "{log}"
    );
    let e = csv(&bytes, &["sensor_gyro"], Stamps::Header)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(
            "--topic 'sensor_gyro': not in this PX4 ULog (topics incal reads here: sensor_gyro:1)"
        ),
        "{e}"
    );
    // A format as large as a message cannot be is nobody's.
    let mut big = ulog_start();
    big.extend(msg(
        b'F',
        b"sensor_gyro:uint64_t timestamp;float[1000000000] x;",
    ));
    big.extend(subscribe(0, 3, "sensor_gyro"));
    let e = csv(&big, &[], Stamps::Header).unwrap_err().to_string();
    assert!(
        e.contains("give --topic, one of the topics incal reads here: none"),
        "{e}"
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]

    /// A log damaged anywhere (bytes changed, the end cut) is read or
    /// refused: never a panic.
    #[test]
    fn a_damaged_log_is_read_or_refused(
        which in 0usize..3,
        edits in proptest::collection::vec((0usize..1 << 20, proptest::prelude::any::<u8>()), 0..6),
        cut in 0usize..1 << 20,
    ) {
        let mut bytes = match which {
            0 => ulog_bytes(20),
            1 => bag("none"),
            _ => bag("lz4"),
        };
        for (at, v) in edits {
            let n = bytes.len();
            bytes[at % n] = v;
        }
        let keep = Format::MAGIC_BYTES + cut % bytes.len();
        bytes.truncate(keep);
        if let Some(format) = Format::detect(&bytes) {
            let _ = convert("f", format, &bytes, &LogOptions::default());
            let _ = convert("f", format, &bytes, &LogOptions { topics: vec!["/imu".into(), "/temp".into()], stamps: Stamps::Log });
        }
    }
}

#[test]
fn a_damaged_mcap_is_read_or_refused() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../incal/tests/fixtures/robot_logs/husky_rl_test1_imu_zstd.mcap"
    );
    let good = std::fs::read(path).unwrap();
    // Deterministic damage: a byte changed every 97 KiB, then the end cut.
    for step in [97 * 1024, 331 * 1024] {
        let mut bytes = good.clone();
        for at in (4096..bytes.len()).step_by(step) {
            bytes[at] ^= 0x5a;
        }
        let _ = convert("f.mcap", Format::Mcap, &bytes, &LogOptions::default());
        bytes.truncate(bytes.len() / 3);
        let _ = convert("f.mcap", Format::Mcap, &bytes, &LogOptions::default());
    }
}

/// ULog messages: size, type, body.
fn msg(kind: u8, body: &[u8]) -> Vec<u8> {
    let mut m = (body.len() as u16).to_le_bytes().to_vec();
    m.push(kind);
    m.extend(body);
    m
}

/// A `sensor_accel` data message (subscription 5) at `t_us`.
fn accel_row(t_us: u64, z: f32) -> Vec<u8> {
    let mut d = 5u16.to_le_bytes().to_vec();
    d.extend(t_us.to_le_bytes());
    for v in [0.0f32, 0.0, z, 30.0] {
        d.extend(v.to_le_bytes());
    }
    msg(b'D', &d)
}

/// The header, flag bits (`incompat[0]`, appended offset), the
/// `sensor_accel` format (with a `float[0]` field) and its subscription.
fn accel_head(incompat: u8, appended: u64) -> Vec<u8> {
    let mut out = ulog_start();
    let mut flags = vec![0u8; 16];
    flags[8] = incompat;
    flags.extend(appended.to_le_bytes());
    flags.extend([0u8; 16]);
    out.extend(msg(b'B', &flags));
    out.extend(msg(
        b'F',
        b"sensor_accel:uint64_t timestamp;float[0] none;float x;float y;float z;float temperature;",
    ));
    out.extend(subscribe(0, 5, "sensor_accel"));
    out
}

#[test]
fn ulog_data_appended_after_a_crash_is_read_from_its_offset() {
    // Two rows, then a third cut by the crash, then the appended data at
    // the offset the flag bits give.
    let mut bytes = accel_head(1, 0);
    bytes.extend(accel_row(1000, -9.80665));
    bytes.extend(accel_row(2000, -9.80665));
    let cut = accel_row(3000, 1.0);
    bytes.extend(&cut[..10]);
    let offset = bytes.len() as u64;
    bytes.extend(accel_row(4000, 2.0 * -9.80665));
    // The offset into the flag bits: after the file header (16 bytes),
    // the message header (3), compat (8) and incompat (8) flags.
    bytes[35..43].copy_from_slice(&offset.to_le_bytes());
    let text = csv(&bytes, &[], Stamps::Header).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip_while(|l| !l.starts_with("time_s"))
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    let times: Vec<f64> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(times, [0.0, 0.001, 0.003], "{text}");
    assert!((rows[2][3] + 2.0).abs() < 1e-6, "{text}");
    // Flags this reader does not know: refused.
    let e = csv(&accel_head(2, 0), &[], Stamps::Header)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("incompatible flags this reader does not know"),
        "{e}"
    );
}

#[test]
fn a_ulog_topic_with_fractional_stamps_is_refused() {
    let mut out = ulog_start();
    out.extend(msg(
        b'F',
        b"sensor_accel:double timestamp;float x;float y;float z;",
    ));
    out.extend(subscribe(0, 5, "sensor_accel"));
    let mut d = 5u16.to_le_bytes().to_vec();
    d.extend(1e300f64.to_le_bytes());
    d.extend([0u8; 12]);
    out.extend(msg(b'D', &d));
    let e = csv(&out, &[], Stamps::Header).unwrap_err().to_string();
    assert!(
        e.contains("topic sensor_accel: its time stamps are not integers"),
        "{e}"
    );
}

#[test]
fn ros_topics_of_two_types_and_unprovided_quantities_are_refused() {
    // /imu also published as Temperature.
    let mut inner = connection(0, "/imu", "sensor_msgs/Imu");
    inner.extend(connection(1, "/imu", "sensor_msgs/Temperature"));
    inner.extend(message(0, 1, &imu_ros1(1, 0, [0.0; 3], [0.0; 3])));
    inner.extend(message(1, 2, &temperature_ros1(2, 20.0)));
    let b = bag_of(&inner);
    let e = csv(&b, &["/imu"], Stamps::Header).unwrap_err().to_string();
    assert!(
        e.contains(
            "topic /imu is published with 2 types (sensor_msgs/Imu, sensor_msgs/Temperature)"
        ),
        "{e}"
    );
    // angular_velocity_covariance[0] = -1: no gyro in this message.
    let mut m = imu_ros1(1, 0, [0.0; 3], [0.0; 3]);
    let at = 20 + 8 * 16;
    m[at..at + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
    let mut inner = connection(0, "/imu", "sensor_msgs/Imu");
    inner.extend(message(0, 1, &m));
    let b = bag_of(&inner);
    let e = csv(&b, &[], Stamps::Header).unwrap_err().to_string();
    assert!(
        e.contains("topic /imu: message 1 says its angular_velocity is not provided"),
        "{e}"
    );
    let e = csv(&bag("none"), &["/imu", "/imu"], Stamps::Header)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--topic '/imu' given twice"), "{e}");
}

#[test]
fn seconds_are_exact_decimals() {
    for (ns, text) in [
        (0, "0"),
        (1_000_000_000, "1"),
        (-500_000_000, "-0.5"),
        (3_003_325_000, "3.003325"),
        (1, "0.000000001"),
        (-1_234_000_000_001, "-1234.000000001"),
    ] {
        assert_eq!(super::seconds_text(ns), text);
    }
}
