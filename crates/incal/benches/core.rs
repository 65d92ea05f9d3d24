//! Criterion benches of the estimation core and the tumble procedure.
//! Speed is measured here, never asserted in tests.

use criterion::{criterion_group, criterion_main, Criterion};
use incal::estimation::{fit, Design, FitOptions};
use incal::models::AccelerometerModel;
use incal::procedures::tumble::plan::TumblePlan;
use incal::procedures::tumble::{calibrate, default_terms, design, TumbleOptions};
use incal::rigs::Mount;
use incal::sim::tumble::{simulate, TumbleSim};
use nalgebra::DVector;
use std::hint::black_box;

fn bench_fit(c: &mut Criterion) {
    let terms = default_terms(Mount::Pendulum);
    let d: Design = design(Mount::Pendulum, &terms, &TumblePlan::gjb12().angles_rad()).unwrap();
    let y = DVector::from_fn(12, |i, _| (i as f64 * 0.3).sin());
    c.bench_function("fit 12x6 (GJB tumble design)", |b| {
        b.iter(|| fit(black_box(&d), black_box(&y), &FitOptions::default()).unwrap())
    });
    let rows: Vec<Vec<f64>> = (0..2000)
        .map(|i| {
            (0..20)
                .map(|j| ((i * (j + 1)) as f64 * 0.001).sin())
                .collect()
        })
        .collect();
    let names = (0..20).map(|j| format!("x{j}")).collect();
    let big = Design::from_rows(names, &rows).unwrap();
    let yb = DVector::from_fn(2000, |i, _| (i as f64 * 0.01).cos());
    c.bench_function("fit 2000x20", |b| {
        b.iter(|| fit(black_box(&big), black_box(&yb), &FitOptions::default()).unwrap())
    });
}

fn bench_tumble(c: &mut Criterion) {
    let obs = simulate(&TumbleSim {
        truth: AccelerometerModel::wu2015(),
        mount: Mount::Pendulum,
        angles_deg: TumblePlan::gjb12().angles_deg,
        samples: 10,
        noise: 1e-6,
        index_error_rad: 5e-6,
        passes: 2,
        seed: 1,
    });
    let opts = TumbleOptions::new(Mount::Pendulum);
    c.bench_function(
        "tumble calibrate, 2 passes x 12 positions x 10 samples",
        |b| b.iter(|| calibrate(black_box(&obs), &opts).unwrap()),
    );
}

criterion_group!(benches, bench_fit, bench_tumble);
criterion_main!(benches);
