//! The noise record's PSD: its χ² bounds cover the true one-sided PSD of
//! simulated white and white-plus-flicker rate noise in 93–97 % of the
//! bins over many seeds, and the white level's U95 covers the truth
//! (`G = 2N² + B²/(π f)` in the internal unit for `σ²_A = N²/τ +
//! (2 ln 2/π) B²`).

use incal::noise::phase_from_rate;
use incal::procedures::noise::spectrum::SpectrumOptions;
use incal::sim::monte_carlo;
use incal::sim::noise::{rate_record, NoiseTruth};
use incal::sim::tier::{band, trials};

fn options() -> SpectrumOptions {
    SpectrumOptions {
        psd: true,
        psd_segment_samples: Some(1024),
        ..SpectrumOptions::default()
    }
}

/// (bins inside their bounds, bins, white level covered by its U95).
fn run(truth: &NoiseTruth, seed: u64, band_hz: (f64, f64)) -> (usize, usize, bool) {
    let y = rate_record(truth, 1.0, 1 << 16, seed);
    let x = phase_from_rate(&y, 1.0);
    let mut o = options();
    o.psd_white_band_hz = Some(vec![band_hz.0, band_hz.1]);
    let s = o.compute(&x, 1.0).unwrap().unwrap();
    let p = &s.psd;
    let g = |f: f64| 2.0 * truth.n * truth.n + truth.b * truth.b / (std::f64::consts::PI * f);
    let mut inside = 0;
    let mut all = 0;
    for i in 1..p.freq_hz.len() - 1 {
        let t = g(p.freq_hz[i]);
        all += 1;
        inside += usize::from(p.lo[i] <= t && t <= p.hi[i]);
    }
    let w = s.white.unwrap();
    let k = incal::estimation::coverage_factor(w.dof, 0.95);
    // The level over the band against the truth's mean over it.
    let t_mean = (0..=100)
        .map(|j| g(band_hz.0 + (band_hz.1 - band_hz.0) * j as f64 / 100.0))
        .sum::<f64>()
        / 101.0;
    (inside, all, (w.density - t_mean).abs() <= k * w.u)
}

/// `level`: also the white level's coverage (a white truth only: the
/// flicker generator's PSD near Nyquist is not exactly `B²/(πf)`).
fn check(label: &str, truth: NoiseTruth, seed: u64, (band_hz, level): ((f64, f64), bool)) {
    let n = trials(10, 200);
    let runs = monte_carlo(seed, n, |s| run(&truth, s, band_hz));
    let (inside, all) = runs.iter().fold((0, 0), |a, r| (a.0 + r.0, a.1 + r.1));
    let rate = inside as f64 / all as f64;
    let white = runs.iter().filter(|r| r.2).count() as f64 / n as f64;
    eprintln!("{label}: bins inside their 95 % bounds {rate:.4} of {all}; white level covered {white:.3} of {n}");
    assert!(
        (0.93..=0.97).contains(&rate),
        "{label}: bins covered {rate:.4}"
    );
    let (lo, hi) = band(n, 0.93, 0.97);
    assert!(
        !level || (lo..=hi).contains(&white),
        "{label}: white level covered {white:.3} of {n} (band {lo:.3}..{hi:.3})"
    );
}

#[test]
fn the_bounds_and_the_white_level_cover_white_noise() {
    let truth = NoiseTruth {
        n: 0.02,
        ..NoiseTruth::default()
    };
    check("white", truth, 51, ((0.05, 0.25), true));
}

#[test]
fn the_bounds_cover_white_and_flicker_noise() {
    let truth = NoiseTruth {
        n: 0.02,
        b: 0.01,
        ..NoiseTruth::default()
    };
    check("white + flicker", truth, 52, ((0.1, 0.4), false));
}
