//! A second, independent noise generator: the frequency-domain method of
//! J. Timmer and M. König ("On generating power law noise", Astronomy and
//! Astrophysics 300, 707–710, 1995).
//!
//! Each Fourier coefficient of a record `L` samples long is drawn as
//! `X_k = √(G(f_k)·L·f_s/4)·(a + i b)` with a, b standard normal and
//! `G` the one-sided PSD (u²/Hz) of the IEEE Std 952-1997 Annex C terms
//! (rate unit u, f_s = 1/τ0):
//!
//! | term | G(f) |
//! |---|---|
//! | Q (u·s) | 2Q²τ0·(2 sin(πfτ0)/τ0)² (white phase, differenced) |
//! | N (u·√s) | 2N² |
//! | B (u) | B²/(πf) |
//! | K (u/√s) | K²/(2π²f²) |
//!
//! (Q's is the sampled form of IEEE 952's `(2πf)²Q²τ0`: the rate of a
//! sampled phase is its first difference over τ0, whose gain is
//! `2 sin(πfτ0)/τ0`, not 2πf; the continuous form has 1.4 times less
//! Allan variance at 16τ0.) So `E|X_k|² = G·L·f_s/2` and the inverse transform divided by L
//! has variance `∫G df`. The record is the first `n` of `L = 16n`
//! samples (rounded up to a power of two): the circular transform has no
//! power below `1/(Lτ0)`, which for a rate random walk takes less than
//! 1 % from the Allan variance at the longest τ the term fit uses.
//!
//! Unlike [`super::rate_record`] (a time-domain filter per term: uniform
//! quantizer, Kasdin–Walter flicker, a summed walk) everything here is
//! Gaussian and shaped in the frequency domain at once, so the term
//! selection's false-inclusion and miss rates measured on both are not
//! properties of one generator. A rate ramp (not a stationary noise) is
//! left out: `truth.r` must be 0.

use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;

use super::NoiseTruth;
use crate::sim::{normal, rng};

/// `n` rate samples at spacing `tau0_s` with the terms Q, N, B and K of
/// `truth` (module docs), seeded with `seed`.
///
/// # Panics
/// When `truth.r` is not 0 (a ramp is not a power-law noise).
pub fn spectral_record(truth: &NoiseTruth, tau0_s: f64, n: usize, seed: u64) -> Vec<f64> {
    assert!(truth.r == 0.0, "the spectral generator has no rate ramp");
    if n == 0 {
        return Vec::new();
    }
    let len = (16 * n).next_power_of_two();
    let fs = 1.0 / tau0_s;
    let pi = std::f64::consts::PI;
    let psd = |f: f64| -> f64 {
        let d = 2.0 * (pi * f * tau0_s).sin() / tau0_s;
        2.0 * d * d * truth.q * truth.q * tau0_s
            + 2.0 * truth.n * truth.n
            + truth.b * truth.b / (pi * f)
            + truth.k * truth.k / (2.0 * pi * pi * f * f)
    };
    let mut r = rng(seed);
    let half = len / 2;
    let mut spec: Vec<Complex64> = (0..=half)
        .map(|k| {
            if k == 0 {
                return Complex64::new(0.0, 0.0);
            }
            let f = k as f64 * fs / len as f64;
            let g = psd(f) * len as f64 * fs;
            if k == half {
                // Real at Nyquist: E|X|² = G·L·f_s/2 from one normal.
                Complex64::new(normal(&mut r, (g / 2.0).sqrt()), 0.0)
            } else {
                let s = (g / 4.0).sqrt();
                Complex64::new(normal(&mut r, s), normal(&mut r, s))
            }
        })
        .collect();
    let inv = RealFftPlanner::<f64>::new().plan_fft_inverse(len);
    let mut out = inv.make_output_vec();
    inv.process(&mut spec, &mut out)
        .expect("a real spectrum of the plan's length");
    out.truncate(n);
    let scale = 1.0 / len as f64;
    for v in &mut out {
        *v *= scale;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::{phase_from_rate, stability, StabilityOptions};

    /// Allan variance of the generated record at τ = 16τ0 against the
    /// IEEE 952 model of each term alone (the estimate's own 3σ band).
    #[test]
    fn each_term_has_its_allan_level() {
        let n = 1 << 16;
        for (truth, model) in [
            (
                NoiseTruth {
                    q: 2.0,
                    ..Default::default()
                },
                3.0 * 4.0 / 256.0,
            ),
            (
                NoiseTruth {
                    n: 1.0,
                    ..Default::default()
                },
                1.0 / 16.0,
            ),
            (
                NoiseTruth {
                    b: 1.0,
                    ..Default::default()
                },
                crate::noise::terms::FLICKER,
            ),
            (
                NoiseTruth {
                    k: 0.01,
                    ..Default::default()
                },
                1e-4 * 16.0 / 3.0,
            ),
        ] {
            let y = spectral_record(&truth, 1.0, n, 7);
            let x = phase_from_rate(&y, 1.0);
            let st = stability(&x, &StabilityOptions::default()).unwrap();
            let i = st.taus_s.iter().position(|&t| t == 16.0).unwrap();
            let s2 = st.oadev.value[i].unwrap().powi(2);
            let edf = st.oadev.edf[i].unwrap();
            let rel = (s2 / model - 1.0).abs();
            assert!(rel < 3.0 * (2.0 / edf).sqrt(), "{truth:?}: {s2} vs {model}");
        }
    }
}
