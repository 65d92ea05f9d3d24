//! Welch's averaged, windowed periodograms: the auto- and cross-spectral
//! densities of a reference `x` and an output `y`, one-sided, in the
//! conventions of `scipy.signal.welch` and `scipy.signal.csd` (periodic
//! Hann window, or none, mean removed from each segment, density scaling, mean of
//! the segments), so the two agree on the same data to rounding.
//!
//! Segment `m` starts at `m·S` (`S = L − overlap`, `L` the segment
//! length; `K = ⌊(N − overlap)/S⌋` segments, the samples after the last
//! left out). With `X_m = DFT(w·(x_m − mean x_m))`:
//!
//! `P_xy(f_k) = c_k/(f_s Σw²) · (1/K) Σ_m conj(X_m(k)) Y_m(k)`, `c_k = 2`
//! except at 0 and at the Nyquist bin of an even `L` (`c = 1`).
//!
//! Welch P. D., *The use of fast Fourier transform for the estimation of
//! power spectra*, IEEE Trans. Audio Electroacoustics, 1967, AU-15(2),
//! pp. 70–73 (the overlap's effect on the number of independent averages,
//! [`effective_averages`]).

use std::sync::Arc;

use realfft::num_complex::Complex64;
use realfft::{RealFftPlanner, RealToComplex};

use crate::error::{Error, Result};

/// The spectra of one record.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectra {
    /// Bin frequencies `k f_s / L` (Hz), `k = 0 … ⌊L/2⌋`.
    pub freq_hz: Vec<f64>,
    /// `P_xx` (reference units²/Hz).
    pub pxx: Vec<f64>,
    /// `P_yy` (output units²/Hz).
    pub pyy: Vec<f64>,
    /// `P_xy` (reference·output units/Hz).
    pub pxy: Vec<Complex64>,
    /// Segments averaged `K`.
    pub segments: usize,
    /// Independent averages `K_eff` ([`effective_averages`]).
    pub effective: f64,
    /// Equivalent noise bandwidth of the window in bins, `L Σw²/(Σw)²`.
    pub enbw_bins: f64,
}

/// The window of each segment.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Window {
    /// The periodic Hann window (random or chirp excitation).
    #[default]
    Hann,
    /// No window (`scipy`'s `boxcar`): for a periodic excitation whose
    /// period divides the segment (a multisine), which then leaks nothing.
    Rectangular,
}

impl Window {
    /// Its `l` samples.
    pub fn samples(self, l: usize) -> Vec<f64> {
        match self {
            Window::Hann => hann(l),
            Window::Rectangular => vec![1.0; l],
        }
    }
}

/// The periodic Hann window of length `l`: `w_n = ½ − ½ cos(2πn/l)`
/// (`scipy.signal.get_window("hann", l)`).
pub fn hann(l: usize) -> Vec<f64> {
    (0..l)
        .map(|n| 0.5 - 0.5 * (std::f64::consts::TAU * n as f64 / l as f64).cos())
        .collect()
}

/// `K_eff = K / (1 + 2 Σ_{j=1}^{K−1} (1 − j/K) ρ_j²)`, `ρ_j = Σ_n w_n
/// w_{n+jS} / Σ w²` (Welch 1967, eq. 21): the number of independent
/// averages `K` overlapping segments are worth.
pub fn effective_averages(w: &[f64], step: usize, k: usize) -> f64 {
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let mut d = 1.0;
    for j in 1..k {
        let shift = j * step;
        if shift >= w.len() {
            break;
        }
        let rho: f64 = w[..w.len() - shift]
            .iter()
            .zip(&w[shift..])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / s2;
        d += 2.0 * (1.0 - j as f64 / k as f64) * rho * rho;
    }
    k as f64 / d
}

fn plan(l: usize) -> Arc<dyn RealToComplex<f64>> {
    RealFftPlanner::<f64>::new().plan_fft_forward(l)
}

/// The unscaled sums of one group of consecutive segments.
#[derive(Debug, Clone, PartialEq)]
pub struct Sums {
    /// `Σ |X_m|²`.
    pub xx: Vec<f64>,
    /// `Σ |Y_m|²`.
    pub yy: Vec<f64>,
    /// `Σ conj(X_m) Y_m`.
    pub xy: Vec<Complex64>,
    /// Segments summed.
    pub segments: usize,
}

impl Sums {
    fn zeros(bins: usize) -> Self {
        Sums {
            xx: vec![0.0; bins],
            yy: vec![0.0; bins],
            xy: vec![Complex64::new(0.0, 0.0); bins],
            segments: 0,
        }
    }
}

/// Welch's estimate with its segments summed in groups: the spectra of
/// all segments, and each group's sums, so the spectra without a group
/// ([`Welch::leave_out`]) cost no new transform (the delete-a-group
/// jackknife of the broadband reduction).
#[derive(Debug, Clone, PartialEq)]
pub struct Welch {
    /// The spectra of every segment.
    pub spectra: Spectra,
    /// Sums of `groups` runs of consecutive segments.
    pub groups: Vec<Sums>,
    /// `c_k/(f_s Σw²)` per bin (module docs).
    scale: Vec<f64>,
}

impl Welch {
    /// `(P_xx, P_yy, P_xy)` of every segment but those of group `g`.
    pub fn leave_out(&self, g: usize) -> (Vec<f64>, Vec<f64>, Vec<Complex64>) {
        let gs = &self.groups[g];
        let k = (self.spectra.segments - gs.segments).max(1) as f64;
        let all = &self.spectra;
        let n = all.segments as f64;
        let bins = self.scale.len();
        let (mut xx, mut yy, mut xy) = (
            vec![0.0; bins],
            vec![0.0; bins],
            vec![Complex64::new(0.0, 0.0); bins],
        );
        for j in 0..bins {
            let c = self.scale[j];
            xx[j] = (all.pxx[j] * n / c - gs.xx[j]) * c / k;
            yy[j] = (all.pyy[j] * n / c - gs.yy[j]) * c / k;
            xy[j] = (all.pxy[j] * n / c - gs.xy[j]) * c / k;
        }
        (xx, yy, xy)
    }
}

/// Welch's estimate of `P_xx`, `P_yy` and `P_xy` (module docs) with
/// segments of `l` samples under `window` overlapping by `overlap` at
/// `fs_hz`, their
/// sums also kept in `groups` runs of consecutive segments. Refuses fewer
/// than two segments, a segment shorter than 8 samples, or an overlap not
/// below the segment.
pub fn welch(
    x: &[f64],
    y: &[f64],
    fs_hz: f64,
    l: usize,
    overlap: usize,
    groups: usize,
    window: Window,
) -> Result<Welch> {
    if l < 8 {
        return crate::options::invalid("segment_samples", format!("at least 8, got {l}"));
    }
    if overlap >= l {
        return crate::options::invalid(
            "overlap_samples",
            format!("must be below `segment_samples` ({l}), got {overlap}"),
        );
    }
    let n = x.len().min(y.len());
    let step = l - overlap;
    let k = if n >= l { (n - overlap) / step } else { 0 };
    if k < 2 {
        return Err(Error::TooFew {
            what: format!("segments of {l} samples (the record has {n}; shorten segment_samples)"),
            needed: 2,
            got: k,
        });
    }
    let groups = groups.clamp(1, k);
    let w = window.samples(l);
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let sum: f64 = w.iter().sum();
    let fft = plan(l);
    let bins = l / 2 + 1;
    let mut sums: Vec<Sums> = (0..groups).map(|_| Sums::zeros(bins)).collect();
    let mut bx = fft.make_input_vec();
    let mut by = fft.make_input_vec();
    let mut fx = fft.make_output_vec();
    let mut fy = fft.make_output_vec();
    for m in 0..k {
        let (xs, ys) = (&x[m * step..m * step + l], &y[m * step..m * step + l]);
        let (mx, my) = (
            xs.iter().sum::<f64>() / l as f64,
            ys.iter().sum::<f64>() / l as f64,
        );
        for i in 0..l {
            bx[i] = (xs[i] - mx) * w[i];
            by[i] = (ys[i] - my) * w[i];
        }
        fft.process(&mut bx, &mut fx)
            .map_err(|e| Error::Unsupported(format!("FFT: {e}")))?;
        fft.process(&mut by, &mut fy)
            .map_err(|e| Error::Unsupported(format!("FFT: {e}")))?;
        let g = &mut sums[m * groups / k];
        g.segments += 1;
        for j in 0..bins {
            g.xx[j] += fx[j].norm_sqr();
            g.yy[j] += fy[j].norm_sqr();
            g.xy[j] += fx[j].conj() * fy[j];
        }
    }
    let scale: Vec<f64> = (0..bins)
        .map(|j| {
            let c = if j == 0 || (l % 2 == 0 && j == bins - 1) {
                1.0
            } else {
                2.0
            };
            c / (fs_hz * s2)
        })
        .collect();
    let mut total = Sums::zeros(bins);
    for g in &sums {
        for j in 0..bins {
            total.xx[j] += g.xx[j];
            total.yy[j] += g.yy[j];
            total.xy[j] += g.xy[j];
        }
    }
    let kf = k as f64;
    Ok(Welch {
        spectra: Spectra {
            freq_hz: (0..bins).map(|j| j as f64 * fs_hz / l as f64).collect(),
            pxx: (0..bins).map(|j| total.xx[j] * scale[j] / kf).collect(),
            pyy: (0..bins).map(|j| total.yy[j] * scale[j] / kf).collect(),
            pxy: (0..bins).map(|j| total.xy[j] * scale[j] / kf).collect(),
            segments: k,
            effective: effective_averages(&w, step, k),
            enbw_bins: l as f64 * s2 / (sum * sum),
        },
        groups: sums,
        scale,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hann_at_half_overlap_is_worth_about_k_over_1_056() {
        let w = hann(1024);
        let e = effective_averages(&w, 512, 1000);
        // ρ₁ = 1/6 for the Hann window at 50 % overlap.
        assert!((1000.0 / e - (1.0 + 2.0 / 36.0)).abs() < 2e-3, "{e}");
        assert!(
            (hann(1024).iter().map(|v| v * v).sum::<f64>() * 1024.0
                / hann(1024).iter().sum::<f64>().powi(2)
                - 1.5)
                .abs()
                < 1e-12
        );
    }

    #[test]
    fn a_sine_in_both_channels_has_unit_coherence_and_its_gain() {
        let fs = 100.0;
        let x: Vec<f64> = (0..4096).map(|i| (0.3 * i as f64).sin()).collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let s = welch(&x, &y, fs, 256, 128, 1, Window::Hann)
            .unwrap()
            .spectra;
        let k = (0..s.pxx.len())
            .max_by(|a, b| s.pxx[*a].total_cmp(&s.pxx[*b]))
            .unwrap();
        let h = s.pxy[k] / s.pxx[k];
        assert!((h.re - 2.0).abs() < 1e-12 && h.im.abs() < 1e-12);
        let coh = s.pxy[k].norm_sqr() / (s.pxx[k] * s.pyy[k]);
        assert!((coh - 1.0).abs() < 1e-12);
    }
}
