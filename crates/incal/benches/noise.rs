//! Speed of the Allan-family kernels (`cargo bench -p incal --bench noise`).
//! Compare with allantools by `scripts/bench-allantools.sh`. The `psd`
//! group times the power spectral density (`--psd`, default segment)
//! beside the whole stability analysis of the same record: what `--psd`
//! adds to a run.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use incal::noise::{dev, id, phase_from_rate, stability, StabilityOptions, TauGrid};
use incal::sim::noise::{rate_record, NoiseTruth};

fn phase(n: usize) -> Vec<f64> {
    let t = NoiseTruth {
        n: 1.0,
        ..Default::default()
    };
    phase_from_rate(&rate_record(&t, 1.0, n, 1), 1.0)
}

fn kernels(c: &mut Criterion) {
    let mut g = c.benchmark_group("octave");
    g.sample_size(10);
    for n in [1_000_000usize, 10_000_000] {
        let x = phase(n);
        let ms = TauGrid::Octave.factors(x.len());
        g.bench_with_input(BenchmarkId::new("oadev", n), &x, |b, x| {
            b.iter(|| {
                ms.iter()
                    .map(|&m| dev::oavar(x, m, 1.0, true).unwrap().var)
                    .sum::<f64>()
            })
        });
        g.bench_with_input(BenchmarkId::new("mdev", n), &x, |b, x| {
            b.iter(|| {
                ms.iter()
                    .map(|&m| dev::mvar(x, m, 1.0, true).unwrap().var)
                    .sum::<f64>()
            })
        });
        g.bench_with_input(BenchmarkId::new("mdev_many", n), &x, |b, x| {
            b.iter(|| {
                dev::mvar_many(x, &ms, 1.0, true)
                    .iter()
                    .flatten()
                    .map(|v| v.var)
                    .sum::<f64>()
            })
        });
        g.bench_with_input(BenchmarkId::new("ohdev", n), &x, |b, x| {
            b.iter(|| {
                ms.iter()
                    .map(|&m| dev::ohvar(x, m, 1.0, true).unwrap().var)
                    .sum::<f64>()
            })
        });
        g.bench_with_input(BenchmarkId::new("totdev", n), &x, |b, x| {
            b.iter(|| {
                ms.iter()
                    .map(|&m| dev::totvar(x, m, 1.0, true).unwrap().var)
                    .sum::<f64>()
            })
        });
        g.bench_with_input(BenchmarkId::new("noise_id", n), &x, |b, x| {
            b.iter(|| id::identify_many(x, &ms, true).iter().flatten().count())
        });
        g.bench_with_input(
            BenchmarkId::new("stability_all_deviations_with_ci", n),
            &x,
            |b, x| b.iter(|| stability(x, &StabilityOptions::default()).unwrap()),
        );
    }
    g.finish();
    let mut g = c.benchmark_group("all_taus");
    g.sample_size(10);
    let x = phase(100_000);
    let ms = TauGrid::All.factors(x.len());
    g.bench_function("oadev_1e5", |b| {
        b.iter(|| {
            ms.iter()
                .map(|&m| dev::oavar(&x, m, 1.0, true).unwrap().var)
                .sum::<f64>()
        })
    });
    g.bench_function("mdev_1e5", |b| {
        b.iter(|| {
            ms.iter()
                .map(|&m| dev::mvar(&x, m, 1.0, true).unwrap().var)
                .sum::<f64>()
        })
    });
    g.bench_function("mdev_many_1e5", |b| {
        b.iter(|| {
            dev::mvar_many(&x, &ms, 1.0, true)
                .iter()
                .flatten()
                .map(|v| v.var)
                .sum::<f64>()
        })
    });
    g.finish();
}

fn spectrum(c: &mut Criterion) {
    use incal::procedures::noise::spectrum::SpectrumOptions;
    let mut g = c.benchmark_group("psd");
    g.sample_size(10);
    let n = 10_000_000usize;
    let x = phase(n);
    let o = SpectrumOptions {
        psd: true,
        ..SpectrumOptions::default()
    };
    g.bench_with_input(BenchmarkId::new("stability", n), &x, |b, x| {
        b.iter(|| stability(x, &StabilityOptions::default()).unwrap())
    });
    g.bench_with_input(BenchmarkId::new("psd", n), &x, |b, x| {
        b.iter(|| o.compute(x, 1.0).unwrap().map(|s| s.psd.segments))
    });
    g.finish();
}

criterion_group!(benches, kernels, spectrum);
criterion_main!(benches);
