//! Criterion bench of the stepped-sine response (issue target: 60 dwells
//! × 10 s at 1 kHz, 600k rows of two channels, reduced in ≤ 0.5 s on one
//! core): from the dwells in memory, and from the CSV through the input
//! layer. Speed is measured here, never asserted in tests.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use incal::procedures::response::plan::DwellChoice;
use incal::procedures::response::sim::ResponseSimOptions;
use incal::procedures::response::{calibrate, ResponseOptions, ResponseSine};
use incal::procedures::{reduce_source, Silent, Simulate};
use std::hint::black_box;

fn sixty_dwells() -> ResponseSimOptions {
    ResponseSimOptions {
        dwells: DwellChoice {
            f_min_hz: 1.0,
            f_max_hz: 400.0,
            dwells: 60,
            seconds_per_dwell: 10.0,
            min_cycles: 2.0,
            ..DwellChoice::default()
        },
        seed: 1,
        ..ResponseSimOptions::default()
    }
}

fn bench_response(c: &mut Criterion) {
    let s = sixty_dwells();
    let dwells = s.dwells().unwrap();
    let rows: usize = dwells.iter().map(|d| d.time_s.len()).sum();
    let mut csv = Vec::new();
    ResponseSine::simulate(&s, &mut csv).unwrap();
    let o = ResponseOptions::default();
    let mut group = c.benchmark_group("response sine");
    group.sample_size(10);
    group.throughput(Throughput::Elements(rows as u64));
    group.bench_function("60 dwells x 10 s at 1 kHz, in memory", |b| {
        b.iter(|| black_box(calibrate(&dwells, &o).unwrap().part.coefficients.len()))
    });
    group.bench_function("60 dwells x 10 s at 1 kHz, from CSV", |b| {
        b.iter(|| {
            let d = reduce_source::<ResponseSine, _>(
                "bench.csv",
                csv.as_slice(),
                &incal_io::ReadOptions::default(),
                &o,
                &Silent,
            )
            .unwrap();
            black_box(d.coefficients.len())
        })
    });
    group.finish();
}

criterion_group!(benches, bench_response);
criterion_main!(benches);
