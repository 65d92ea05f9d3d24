//! Reader throughput on numeric CSV (criterion reports MB/s): the tumble
//! layout (two columns) and an IMU session (time and six channels), every
//! cell parsed as a number, hashing on and off.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use incal_io::{ReadOptions, Reader};

fn tumble_csv(rows: usize) -> Vec<u8> {
    let mut s = String::from("angle_deg,output\n");
    for k in 0..rows {
        let angle = (k / 60_000 % 12) as f64 * 30.0;
        let out =
            10.0 * angle.to_radians().sin() + 1e-5 * ((k * 7919 % 1000) as f64 - 500.0) / 500.0;
        s.push_str(&format!("{angle},{out}\n"));
    }
    s.into_bytes()
}

fn imu_csv(rows: usize) -> Vec<u8> {
    let mut s = String::from("time_s,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    for k in 0..rows {
        let t = k as f64 * 0.01;
        let n = |j: usize| ((k * 7919 + j * 104729) % 10007) as f64 / 10007.0 - 0.5;
        s.push_str(&format!(
            "{t},{},{},{},{},{},{}\n",
            0.01 * n(1),
            0.02 * n(2),
            9.80665 + 0.01 * n(3),
            1e-3 * n(4),
            1e-3 * n(5),
            1e-3 * n(6)
        ));
    }
    s.into_bytes()
}

fn parse_all(bytes: &[u8], hash: bool) -> f64 {
    let opts = ReadOptions {
        hash,
        ..ReadOptions::default()
    };
    let mut r = Reader::new("bench.csv", bytes, &opts).unwrap();
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
    let mut g = c.benchmark_group("reader");
    for (name, bytes) in [
        ("tumble_720k", tumble_csv(720_000)),
        ("imu_200k", imu_csv(200_000)),
    ] {
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.sample_size(20);
        g.bench_with_input(BenchmarkId::new("parse", name), &bytes, |b, bytes| {
            b.iter(|| parse_all(bytes, false))
        });
        g.bench_with_input(
            BenchmarkId::new("parse+sha256", name),
            &bytes,
            |b, bytes| b.iter(|| parse_all(bytes, true)),
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
