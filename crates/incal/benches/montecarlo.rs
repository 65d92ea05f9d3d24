//! Criterion bench of the Monte Carlo propagation (issue target: the
//! tumble test with M = 10⁵ trials in ≤ 10 s on 2 cores), and the
//! rate-transfer test with M = 10⁴ for the chapter's table. Speed is
//! measured here, never asserted in tests.

use criterion::{criterion_group, criterion_main, Criterion};
use incal::montecarlo::{run, MonteCarloOptions, Trials};
use incal::procedures::gyro::rate::{GyroRate, GyroRateOptions, RateObservation};
use incal::procedures::tumble::{Observation, Tumble, TumbleOptions};
use incal::procedures::{Procedure, Silent, Simulate};
use incal::rigs::Mount;
use std::hint::black_box;

/// The two numbers of each data row `incal simulate …` writes with its
/// defaults (comment lines and the header skipped).
fn rows<S: Simulate>(sim: &S::Options) -> Vec<(f64, f64)> {
    let mut csv = Vec::new();
    S::simulate(sim, &mut csv).unwrap();
    String::from_utf8(csv)
        .unwrap()
        .lines()
        .filter_map(|l| {
            let mut f = l.split(',').map(str::parse::<f64>);
            match (f.next(), f.next()) {
                (Some(Ok(a)), Some(Ok(b))) => Some((a, b)),
                _ => None,
            }
        })
        .collect()
}

fn trials(m: u64) -> MonteCarloOptions {
    MonteCarloOptions {
        trials: Trials::Fixed(m),
        seed: 1,
        digits: 1,
    }
}

fn bench_monte_carlo(c: &mut Criterion) {
    let mut group = c.benchmark_group("monte carlo");
    group.sample_size(10);
    // The tumble: `incal simulate tumble` defaults (12 positions × 10
    // samples, six terms), M = 10⁵.
    let obs: Vec<Observation> =
        rows::<Tumble>(&serde_json::from_value(serde_json::json!({})).unwrap())
            .into_iter()
            .map(|(a, y)| Observation {
                angle_rad: a.to_radians(),
                output: y,
                pass: None,
            })
            .collect();
    let o = TumbleOptions::new(Mount::Pendulum);
    let doc = Tumble::reduce(&obs, &o, &Silent).unwrap();
    group.bench_function("tumble, M = 1e5", |b| {
        b.iter(|| {
            let (s, _) = run::<Tumble>(&obs, &o, &doc, &trials(100_000), &Silent).unwrap();
            black_box(s.trials)
        })
    });
    // The rate-transfer test: `incal simulate gyro-rate` defaults, M = 10⁴.
    let obs: Vec<RateObservation> = rows::<GyroRate>(&Default::default())
        .into_iter()
        .map(|(r, y)| RateObservation {
            rate_deg_s: r,
            output: y,
            run: None,
        })
        .collect();
    let o = GyroRateOptions {
        rate_uncertainty_ppm: 20.0,
        ..GyroRate::example()
    };
    let doc = GyroRate::reduce(&obs, &o, &Silent).unwrap();
    group.bench_function("gyro rate, M = 1e4", |b| {
        b.iter(|| {
            let (s, _) = run::<GyroRate>(&obs, &o, &doc, &trials(10_000), &Silent).unwrap();
            black_box(s.trials)
        })
    });
    group.finish();
}

criterion_group!(benches, bench_monte_carlo);
criterion_main!(benches);
