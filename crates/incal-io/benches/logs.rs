//! Robot-log reading throughput (criterion reports MB/s of the log's own
//! bytes): a PX4 ULog of `sensor_combined` and a ROS 2 MCAP of
//! `sensor_msgs/msg/Imu` in CDR, each read by the one [`Reader`] from its
//! bytes to every row's numbers (decoding, units, the CSV the procedures
//! read, SHA-256 of the log).
//!
//! `INCAL_BENCH_MESSAGES` sets the messages per log (default 10⁶; the
//! issue's figure is measured with 10⁷, about 0.5 GB of ULog and 3 GB of
//! MCAP in memory).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use incal_io::logs::LogOptions;
use incal_io::{ReadOptions, Reader};

fn messages() -> usize {
    std::env::var("INCAL_BENCH_MESSAGES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000)
}

/// A pseudo-random value in [-0.5, 0.5) from a message index and a channel.
fn wiggle(k: usize, j: usize) -> f64 {
    ((k * 7919 + j * 104_729) % 10_007) as f64 / 10_007.0 - 0.5
}

/// One ULog message: size, type, body.
fn ulog_msg(out: &mut Vec<u8>, kind: u8, body: &[u8]) {
    out.extend((body.len() as u16).to_le_bytes());
    out.push(kind);
    out.extend(body);
}

/// A ULog (version 1) of `n` `sensor_combined` messages at 1 kHz, with
/// PX4's own field list.
fn ulog(n: usize) -> Vec<u8> {
    let mut out = b"ULog\x01\x12\x35\x01".to_vec();
    out.extend(0u64.to_le_bytes());
    ulog_msg(
        &mut out,
        b'F',
        b"sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;\
int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;\
uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;uint8_t gyro_clipping;\
uint8_t accel_calibration_count;uint8_t gyro_calibration_count;",
    );
    let mut add = vec![0u8];
    add.extend(1u16.to_le_bytes());
    add.extend(b"sensor_combined");
    ulog_msg(&mut out, b'A', &add);
    let mut d = Vec::with_capacity(64);
    for k in 0..n {
        d.clear();
        d.extend(1u16.to_le_bytes());
        d.extend((k as u64 * 1000 + 1_000_000).to_le_bytes());
        for j in 0..3 {
            d.extend((1e-3 * wiggle(k, j) as f32).to_le_bytes());
        }
        d.extend(1000u32.to_le_bytes());
        d.extend(0i32.to_le_bytes());
        for j in 3..6 {
            let g = if j == 5 { 9.80665f32 } else { 0.0 };
            d.extend((g + 0.01 * wiggle(k, j) as f32).to_le_bytes());
        }
        d.extend(1000u32.to_le_bytes());
        d.extend([0u8; 4]);
        ulog_msg(&mut out, b'D', &d);
    }
    out
}

/// One MCAP record: opcode, length, content.
fn mcap_record(out: &mut Vec<u8>, op: u8, body: &[u8]) {
    out.push(op);
    out.extend((body.len() as u64).to_le_bytes());
    out.extend(body);
}

/// An MCAP string: u32 length, bytes.
fn mcap_str(out: &mut Vec<u8>, s: &[u8]) {
    out.extend((s.len() as u32).to_le_bytes());
    out.extend(s);
}

/// A ROS 2 `sensor_msgs/msg/Imu` in little-endian CDR at `k` ms.
fn imu_cdr(d: &mut Vec<u8>, k: usize) {
    d.clear();
    d.extend([0, 1, 0, 0]);
    d.extend(((k / 1000) as i32).to_le_bytes());
    d.extend((((k % 1000) * 1_000_000) as u32).to_le_bytes());
    mcap_str(d, b"imu\0");
    // 8-byte alignment from the encapsulation's end: 4 + 4 + 4 + 4 = 16.
    let mut v = [0.0f64; 37];
    v[3] = 1.0;
    for j in 0..3 {
        v[13 + j] = 1e-3 * wiggle(k, j);
        v[25 + j] = 0.1 * wiggle(k, j + 3) + if j == 2 { 9.80665 } else { 0.0 };
    }
    for x in v {
        d.extend(x.to_le_bytes());
    }
}

/// An MCAP (unchunked) of `n` `sensor_msgs/msg/Imu` messages at 1 kHz.
fn mcap(n: usize) -> Vec<u8> {
    let mut out = b"\x89MCAP0\r\n".to_vec();
    let mut b = Vec::new();
    mcap_str(&mut b, b"ros2");
    mcap_str(&mut b, b"bench");
    mcap_record(&mut out, 0x01, &b);
    b.clear();
    b.extend(1u16.to_le_bytes());
    mcap_str(&mut b, b"sensor_msgs/msg/Imu");
    mcap_str(&mut b, b"ros2msg");
    mcap_str(&mut b, b"");
    mcap_record(&mut out, 0x03, &b);
    b.clear();
    b.extend(1u16.to_le_bytes());
    b.extend(1u16.to_le_bytes());
    mcap_str(&mut b, b"/imu");
    mcap_str(&mut b, b"cdr");
    b.extend(0u32.to_le_bytes());
    mcap_record(&mut out, 0x04, &b);
    let mut d = Vec::with_capacity(320);
    for k in 0..n {
        imu_cdr(&mut d, k);
        b.clear();
        b.extend(1u16.to_le_bytes());
        b.extend((k as u32).to_le_bytes());
        let t = (k as u64) * 1_000_000;
        b.extend(t.to_le_bytes());
        b.extend(t.to_le_bytes());
        b.extend(&d);
        mcap_record(&mut out, 0x05, &b);
    }
    mcap_record(&mut out, 0x0F, &0u32.to_le_bytes());
    let mut f = Vec::new();
    f.extend(0u64.to_le_bytes());
    f.extend(0u64.to_le_bytes());
    f.extend(0u32.to_le_bytes());
    mcap_record(&mut out, 0x02, &f);
    out.extend(b"\x89MCAP0\r\n");
    out
}

/// Read every row's numbers; returns their sum (kept from the optimiser).
fn read_all(name: &str, bytes: &[u8]) -> f64 {
    let opts = ReadOptions {
        log: LogOptions::default(),
        ..ReadOptions::default()
    };
    let mut r = Reader::new(name, bytes, &opts).unwrap();
    let w = r.header().width();
    let mut sum = 0.0;
    while let Some(row) = r.next_row().unwrap() {
        for c in 0..w {
            sum += row.f64(c).unwrap();
        }
    }
    r.finish().unwrap();
    sum
}

fn bench(c: &mut Criterion) {
    let n = messages();
    let mut g = c.benchmark_group("logs");
    g.sample_size(10);
    for (name, bytes) in [("ulog", ulog(n)), ("mcap", mcap(n))] {
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_with_input(BenchmarkId::new(name, n), &bytes, |b, bytes| {
            b.iter(|| read_all(name, bytes))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
