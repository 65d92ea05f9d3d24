//! Criterion bench of the gyro-free motion solution per sample: the
//! twelve-accelerometer layout (direct) and the paper's six (feedback).
//! Speed is measured here, never asserted in tests.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use incal::models::gfimu::Geometry;
use incal::procedures::gfimu::solve::Solver;
use incal::procedures::gfimu::SolveOptions;
use incal::sim::gfimu::{simulate_motion, GfimuTruth, MotionProfile};
use std::hint::black_box;

fn bench_solve(c: &mut Criterion) {
    let mut group = c.benchmark_group("gfimu solve");
    for (label, g) in [
        ("twelve (direct)", Geometry::twelve(0.1).unwrap()),
        ("paper six (feedback)", Geometry::paper(0.1).unwrap()),
    ] {
        let t = GfimuTruth::typical(&g, 1.0);
        let m = MotionProfile {
            duration_s: 10.0,
            rate_hz: 1000.0,
            spin_up_s: 1.0005,
            ..MotionProfile::rate_table()
        };
        let noise = 1e-5;
        let series = simulate_motion(&g, &t, &m, noise, 1).unwrap();
        let cal = t.calibration(Some(noise));
        group.throughput(Throughput::Elements(series.len() as u64));
        group.bench_function(format!("{label}, 10^4 samples"), |b| {
            b.iter(|| {
                let mut s = Solver::new(&g, &cal, &SolveOptions::default()).unwrap();
                let mut acc = 0.0;
                for (time, e) in &series {
                    // A diverging feedback solution stops early; either way
                    // the per-sample work is what is timed.
                    match s.step(*time, e) {
                        Ok(x) => acc += x.f0_g.z,
                        Err(_) => break,
                    }
                }
                black_box(acc)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_solve);
criterion_main!(benches);
