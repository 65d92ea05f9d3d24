//! Tones in the noise record's PSD: a 0.01 °/s line at 37 Hz in a MEMS
//! gyro's record (N = 0.3 °/√h, B = 10 °/h, 200 Hz) is found, and its
//! frequency and rms amplitude lie within their U95 at the stated rate
//! over many seeds; tone-free records (white, white + flicker, white +
//! rate random walk) give false lines at no more than the stated 1 % per
//! spectrum.

use incal::noise::phase_from_rate;
use incal::procedures::noise::sim::{add_tones, SimTone};
use incal::procedures::noise::spectrum::SpectrumOptions;
use incal::sim::monte_carlo;
use incal::sim::noise::{rate_record, NoiseTruth};
use incal::sim::tier::{band, trials};

/// N = 0.3 °/√h and B = 10 °/h in deg/s·√s and deg/s.
fn mems() -> NoiseTruth {
    NoiseTruth {
        n: 0.3 / 60.0,
        b: 10.0 / 3600.0,
        ..NoiseTruth::default()
    }
}

const RATE_HZ: f64 = 200.0;

/// The spectrum of `seconds` of `truth` with `tones` (seeded).
fn spectrum(
    truth: &NoiseTruth,
    tones: &[SimTone],
    seconds: f64,
    seed: u64,
) -> incal::procedures::noise::spectrum::ChannelSpectrum {
    let tau0 = 1.0 / RATE_HZ;
    let mut y = rate_record(truth, tau0, (seconds * RATE_HZ) as usize, seed);
    add_tones(&mut y, tones, tau0, seed);
    let x = phase_from_rate(&y, tau0);
    let o = SpectrumOptions {
        psd: true,
        psd_segment_samples: Some(4096),
        ..SpectrumOptions::default()
    };
    o.compute(&x, tau0).unwrap().unwrap()
}

#[test]
fn a_37_hz_line_is_found_and_its_u95_covers_it() {
    let tone = SimTone {
        frequency_hz: 37.0,
        amplitude_rms: 0.01,
    };
    let n = trials(12, 400);
    let runs = monte_carlo(37, n, |s| {
        let sp = spectrum(&mems(), &[tone], 300.0, s);
        let t = sp
            .tones
            .iter()
            .find(|t| (t.frequency_hz - 37.0).abs() < 0.2)
            .copied();
        let others = sp.tones.len() - usize::from(t.is_some());
        t.map(|t| {
            let k = incal::estimation::coverage_factor(t.dof, 0.95);
            (
                (t.frequency_hz - 37.0).abs() <= k * t.u_frequency_hz,
                (t.amplitude_rms - 0.01).abs() <= k * t.u_amplitude_rms,
                others,
            )
        })
    });
    let found: Vec<_> = runs.iter().flatten().collect();
    let rate = |f: &dyn Fn(&(bool, bool, usize)) -> bool| {
        found.iter().filter(|r| f(r)).count() as f64 / found.len() as f64
    };
    let (freq, amp) = (rate(&|r| r.0), rate(&|r| r.1));
    let extra: usize = found.iter().map(|r| r.2).sum();
    eprintln!(
        "37 Hz line: found {} of {n}; frequency within U95 {freq:.3}, amplitude {amp:.3}; other lines {extra}",
        found.len()
    );
    assert!(found.len() as f64 >= 0.95 * n as f64);
    let (lo, hi) = band(found.len(), 0.93, 0.97);
    assert!((lo..=hi).contains(&freq), "frequency covered {freq:.3}");
    assert!((lo..=hi).contains(&amp), "amplitude covered {amp:.3}");
}

/// Spectra with at least one line out of `n` tone-free records.
fn false_lines(label: &str, truth: NoiseTruth, seed: u64) {
    let n = trials(12, 400);
    let runs = monte_carlo(seed, n, |s| spectrum(&truth, &[], 300.0, s).tones.len());
    let with = runs.iter().filter(|k| **k > 0).count();
    eprintln!("{label}: spectra with a false line {with} of {n}");
    // At most 1 % per spectrum: three binomial standard deviations above.
    let allowed = 0.01 * n as f64 + 3.0 * (0.01 * 0.99 * n as f64).sqrt();
    assert!(with as f64 <= allowed, "{label}: {with} of {n}");
}

#[test]
fn tone_free_white_noise_gives_no_more_false_lines_than_stated() {
    false_lines(
        "white",
        NoiseTruth {
            n: 0.005,
            ..NoiseTruth::default()
        },
        101,
    );
}

#[test]
fn tone_free_flicker_and_random_walk_give_no_more_false_lines_than_stated() {
    false_lines("white + flicker", mems(), 102);
    false_lines(
        "white + rate random walk",
        NoiseTruth {
            n: 0.005,
            k: 0.001,
            ..NoiseTruth::default()
        },
        103,
    );
}
