//! The one-sided power spectral density of a noise record by Welch's
//! method, with χ² confidence bounds and the white-noise level of a band
//! (IEEE Std 1554-2005 and IEEE Std 1293-2018 name it beside the Allan
//! variance).
//!
//! The record enters as its phase `x` (the noise procedure's only copy:
//! `x_{k+1} − x_k = (y_k − c) τ0`), so the rate samples are its first
//! differences divided by `τ0`; the constant `c` is removed with each
//! segment's mean. In the conventions of `scipy.signal.welch` (mean
//! removed, window `w`, density scaling, mean of the `K` segments):
//!
//! `G(f_k) = c_k/(f_s Σw²) · (1/K) Σ_m |DFT(w·(y_m − ȳ_m))_k|²`,
//! `c_k = 2` except at 0 and at the Nyquist bin of an even length.
//!
//! # Bounds
//! `ν G/G_true ~ χ²_ν` with `ν = 2 K_eff` (`K_eff` from the segments'
//! overlap, [`super::welch::effective_averages`]; `ν = K_eff` at 0 and
//! Nyquist): the interval at confidence `p` is
//! `[ν G/χ²_ν((1+p)/2), ν G/χ²_ν((1−p)/2)]` (D. B. Percival and A. T.
//! Walden, *Spectral Analysis for Physical Applications*, Cambridge
//! University Press 1993, §7.4, eq. 294).
//!
//! # White level
//! Over the bins of a band, `Ḡ` is their mean; its u is the larger of the
//! estimate's own (`Ḡ/√(K_eff n_b/c)`) and the bins' scatter
//! (`s/√(n_b/c)`), with `n_b/c − 1` degrees of freedom: `n_b` bins and
//! `c = 1 + 2 Σ_{j≥1} |V_j|²/V_0²` (`V` the DFT of `w²`), the variance
//! factor of a mean over neighbouring periodogram bins, which a window
//! correlates (Hann: `c = 1 + 2 (4/9 + 1/36) = 1.94`; none: 1). For white rate noise
//! `σ²_A(τ) = G/(2τ)`, so the IEEE Std 952 angle (velocity) random walk
//! is `N = √(G/2)`, `u(N) = N u(G)/(2G)`.

use rayon::prelude::*;
use realfft::RealFftPlanner;
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::welch::{effective_averages, Window};
use crate::error::{Error, Result};

/// The spectrum of one channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Bin frequencies `k f_s/L` (Hz), `k = 0 … ⌊L/2⌋`.
    pub freq_hz: Vec<f64>,
    /// `G(f)` (unit²/Hz).
    pub density: Vec<f64>,
    /// Lower and upper bound of `G` at `confidence`.
    pub lo: Vec<f64>,
    /// Upper bound.
    pub hi: Vec<f64>,
    /// Segments averaged `K`.
    pub segments: usize,
    /// Independent averages `K_eff`.
    pub effective: f64,
    /// Variance factor `c` of a mean over neighbouring bins (module docs).
    pub bin_correlation: f64,
    /// Confidence of the bounds.
    pub confidence: f64,
}

/// The white level of a band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct White {
    /// Mean `G` over the band (unit²/Hz).
    pub density: f64,
    /// Its standard uncertainty.
    pub u: f64,
    /// Degrees of freedom.
    pub dof: f64,
    /// The band used (Hz).
    pub band_hz: (f64, f64),
}

/// Segments of one block summed in parallel (a fixed chunking: the sum
/// does not depend on the number of threads).
const BLOCK: usize = 32;

/// The PSD of the rate whose phase is `x` (sample period `tau0_s`), with
/// segments of `l` samples overlapping by `overlap` (module docs).
/// Refuses fewer than two segments or a segment below 8 samples.
pub fn psd_of_phase(
    x: &[f64],
    tau0_s: f64,
    (l, overlap): (usize, usize),
    window: Window,
    confidence: f64,
) -> Result<Psd> {
    let n = x.len().saturating_sub(1);
    if l < 8 || overlap >= l {
        return crate::options::invalid(
            "psd_segment_samples",
            format!("{l} with an overlap of {overlap}: at least 8, above the overlap"),
        );
    }
    let step = l - overlap;
    let k = if n >= l { (n - overlap) / step } else { 0 };
    if k < 2 {
        return Err(Error::TooFew {
            what: format!(
                "PSD segments of {l} samples (the record has {n}; shorten psd_segment_samples)"
            ),
            needed: 2,
            got: k,
        });
    }
    let w = window.samples(l);
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let fs = 1.0 / tau0_s;
    let bins = l / 2 + 1;
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(l);
    let blocks: Vec<Vec<f64>> = (0..k.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let mut acc = vec![0.0; bins];
            let mut buf = fft.make_input_vec();
            let mut spec = fft.make_output_vec();
            for m in b * BLOCK..((b + 1) * BLOCK).min(k) {
                let s = m * step;
                let seg = &x[s..s + l + 1];
                let mean = (seg[l] - seg[0]) / (l as f64 * tau0_s);
                for (i, v) in buf.iter_mut().enumerate() {
                    *v = ((seg[i + 1] - seg[i]) / tau0_s - mean) * w[i];
                }
                if fft.process(&mut buf, &mut spec).is_ok() {
                    for (a, z) in acc.iter_mut().zip(&spec) {
                        *a += z.norm_sqr();
                    }
                }
            }
            acc
        })
        .collect();
    let mut sum = vec![0.0; bins];
    for b in &blocks {
        for (s, v) in sum.iter_mut().zip(b) {
            *s += v;
        }
    }
    let edge = |i: usize| i == 0 || (l % 2 == 0 && i == bins - 1);
    let density: Vec<f64> = sum
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let c = if edge(i) { 1.0 } else { 2.0 };
            c / (fs * s2) * v / k as f64
        })
        .collect();
    let effective = effective_averages(&w, step, k);
    let bound = |nu: f64| -> (f64, f64) {
        let chi = ChiSquared::new(nu).ok();
        let q = |p: f64| chi.as_ref().map_or(f64::NAN, |c| c.inverse_cdf(p));
        (
            nu / q(0.5 + confidence / 2.0),
            nu / q(0.5 - confidence / 2.0),
        )
    };
    let (mid, ends) = (bound(2.0 * effective), bound(effective));
    let (lo, hi): (Vec<f64>, Vec<f64>) = density
        .iter()
        .enumerate()
        .map(|(i, g)| {
            let (a, b) = if edge(i) { ends } else { mid };
            (g * a, g * b)
        })
        .unzip();
    let v = |j: usize| -> f64 {
        let (re, im) = w.iter().enumerate().fold((0.0, 0.0), |(a, b), (n, x)| {
            let (sn, cn) = (std::f64::consts::TAU * (j * n) as f64 / l as f64).sin_cos();
            (a + x * x * cn, b - x * x * sn)
        });
        re * re + im * im
    };
    let v0 = v(0);
    let bin_correlation = 1.0 + 2.0 * (1..=4).map(|j| v(j) / v0).sum::<f64>();
    Ok(Psd {
        freq_hz: (0..bins).map(|i| i as f64 * fs / l as f64).collect(),
        density,
        lo,
        hi,
        segments: k,
        effective,
        bin_correlation,
        confidence,
    })
}

impl White {
    /// The amplitude spectral density `√(f² Ḡ)` and its u
    /// (`√(f² Ḡ) u(Ḡ)/(2Ḡ)`), the level in a unit `f` times the one
    /// estimated.
    pub fn asd(&self, f: f64) -> (f64, f64) {
        let a = (self.density * f * f).sqrt();
        if self.density > 0.0 {
            (a, a * self.u / (2.0 * self.density))
        } else {
            // A record without noise: a level of 0 within √u.
            (a, (self.u * f * f).sqrt())
        }
    }

    /// `(N, u(N))`, `N = √(Ḡ/2)` (module docs), in the estimate's unit·√s.
    pub fn n_equivalent(&self) -> (f64, f64) {
        let n = (self.density / 2.0).sqrt();
        if self.density > 0.0 {
            (n, n * self.u / (2.0 * self.density))
        } else {
            (n, (self.u / 2.0).sqrt())
        }
    }
}

impl Psd {
    /// The white level of the bins within `band_hz` (module docs); `None`
    /// when fewer than 3 independent bins lie in it.
    pub fn white(&self, band_hz: (f64, f64)) -> Option<White> {
        self.white_without(band_hz, &[], 0)
    }

    /// As [`Psd::white`] without the bins within `half` of each bin in
    /// `lines` (a tone's lobe is no part of the noise).
    pub fn white_without(
        &self,
        band_hz: (f64, f64),
        lines: &[usize],
        half: usize,
    ) -> Option<White> {
        let g: Vec<f64> = self
            .freq_hz
            .iter()
            .zip(&self.density)
            .enumerate()
            .filter(|(i, (f, _))| {
                *i > 0
                    && *i + 1 < self.freq_hz.len()
                    && **f >= band_hz.0
                    && **f <= band_hz.1
                    && lines.iter().all(|k| k.abs_diff(*i) > half)
            })
            .map(|(_, (_, g))| *g)
            .collect();
        let nb = g.len() as f64 / self.bin_correlation.max(1.0);
        if nb < 3.0 {
            return None;
        }
        let mean = g.iter().sum::<f64>() / g.len() as f64;
        let sd = (g.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (g.len() - 1) as f64).sqrt();
        let own = mean / (self.effective * nb).sqrt();
        Some(White {
            density: mean,
            u: own.max(sd / nb.sqrt()),
            dof: nb - 1.0,
            band_hz,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_noise_of_known_density_is_read_back_within_its_u() {
        let mut r = crate::sim::rng(3);
        let (fs, sigma) = (100.0, 0.5);
        let mut x = vec![0.0];
        for _ in 0..200_000 {
            let y = 7.0 + crate::sim::normal(&mut r, sigma);
            x.push(x.last().unwrap() + y / fs);
        }
        let p = psd_of_phase(&x, 1.0 / fs, (1024, 512), Window::Hann, 0.95).unwrap();
        // White noise of variance σ² at rate fs: G = 2σ²/fs one-sided.
        let truth = 2.0 * sigma * sigma / fs;
        let w = p.white((5.0, 25.0)).unwrap();
        assert!(
            (w.density - truth).abs() < 3.0 * w.u,
            "{w:?} against {truth}"
        );
        assert!(w.u < 0.02 * truth);
        let inside =
            p.lo.iter()
                .zip(&p.hi)
                .skip(1)
                .filter(|(a, b)| **a <= truth && truth <= **b)
                .count() as f64
                / (p.lo.len() - 1) as f64;
        assert!(inside > 0.9 && inside < 0.99, "{inside}");
    }

    #[test]
    fn the_bin_correlation_of_hann_and_of_no_window() {
        let x: Vec<f64> = (0..5000).map(|i| (i as f64).sin()).collect();
        let h = psd_of_phase(&x, 1.0, (256, 128), Window::Hann, 0.95).unwrap();
        assert!((h.bin_correlation - (1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0))).abs() < 1e-9);
        let r = psd_of_phase(&x, 1.0, (256, 128), Window::Rectangular, 0.95).unwrap();
        assert!((r.bin_correlation - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_record_without_noise_has_a_finite_white_level() {
        // The fuzz seed of a simulation with every term 0 gave u = NaN.
        let w = White {
            density: 0.0,
            u: 0.0,
            dof: 10.0,
            band_hz: (1.0, 2.0),
        };
        assert_eq!(w.asd(3.0), (0.0, 0.0));
        assert_eq!(w.n_equivalent(), (0.0, 0.0));
        let w = White { u: 4e-6, ..w };
        assert!((w.asd(1.0).1 - 2e-3).abs() < 1e-15);
    }

    #[test]
    fn a_record_shorter_than_two_segments_is_refused() {
        let x: Vec<f64> = (0..1500).map(|i| i as f64).collect();
        let e = psd_of_phase(&x, 0.01, (1024, 512), Window::Hann, 0.95).unwrap_err();
        assert!(e.to_string().contains("psd_segment_samples"), "{e}");
    }
}
