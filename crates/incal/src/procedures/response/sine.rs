//! Least-squares sine fit of one dwell (IEEE Std 1057-2017, §4.1.3.1: the
//! three-parameter fit at a known frequency), extended by harmonics and a
//! linear drift.
//!
//! At the dwell frequency `f` (`ω = 2πf`), with `t' = t − t₀` from the
//! dwell's first stamp (of the output, when the reference has a clock of
//! its own), each channel is fitted at its own stamps by
//!
//! `y(t) = A₁ cos ωt' + B₁ sin ωt' + Σ_{k=2..h} (A_k cos kωt' + B_k sin kωt') + C + D (t' − t̄')`
//!
//! on the estimation core ([`crate::estimation::fit`], variance from the
//! residuals, `n − p` degrees of freedom). The fundamental is
//! `y₁ = R cos(ωt' + φ)` with
//!
//! `R = √(A₁² + B₁²)`, `φ = atan2(−B₁, A₁)`,
//!
//! and by first-order propagation (JCGM 100 §5.1.2)
//! `∂R/∂(A₁, B₁) = (A₁, B₁)/R`, `∂φ/∂(A₁, B₁) = (B₁, −A₁)/R²`.
//! The total harmonic distortion is `THD = √(Σ_{k≥2} R_k²)/R` (harmonics at
//! or above the Nyquist frequency are not fitted). Reference and output
//! share one origin, so their phase difference does not depend on `t₀`;
//! on one clock they share one design.
//!
//! When the frequency is not known, [`fit_frequency`] estimates it from
//! one channel by the four-parameter fit (IEEE Std 1057-2017 §4.1.3.2):
//! starting from `ω₀`, each step fits the three-parameter model at `ω_i`
//! and then the same model with the column
//! `∂y/∂ω = Σ_k k t' (−A_k sin kωt' + B_k cos kωt')` added; its
//! coefficient is the step `Δω`, `ω_{i+1} = ω_i + Δω`, until `|Δω|` is
//! below 10⁻¹⁰ of `ω`; `u(f)` is the last step's `u(Δω)/2π`. Both channels
//! are then fitted at the estimated frequency on one origin: an error of
//! `f` moves both phases alike, so gain and phase difference do not
//! depend on it to first order.

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::{fit, Design, FitOptions};

/// The fundamental of one channel at one dwell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelFit {
    /// Amplitude `R` (channel units).
    pub amplitude: f64,
    /// Standard uncertainty of `R`.
    pub u_amplitude: f64,
    /// Phase `φ` of `R cos(ωt' + φ)` (rad, in (−π, π]).
    pub phase_rad: f64,
    /// Standard uncertainty of `φ` (rad).
    pub u_phase_rad: f64,
    /// Constant term `C` (channel units).
    pub offset: f64,
    /// Total harmonic distortion (ratio), `None` when no harmonic is fitted.
    pub thd: Option<f64>,
    /// Residual standard deviation (channel units).
    pub residual_sd: f64,
    /// Residual degrees of freedom `n − p`.
    pub dof: usize,
}

/// The shared design of a dwell: columns and their names.
#[derive(Debug, Clone)]
pub struct SineDesign {
    design: Design,
    /// Harmonics fitted besides the fundamental (orders 2..).
    harmonics: usize,
}

impl SineDesign {
    /// The design at `freq_hz` for stamps `t_s` (s) with time measured
    /// from `origin_s` (one origin for channels on their own clocks): the
    /// fundamental, harmonics `2..=harmonics` below `nyquist_hz`, a
    /// constant, and a linear drift when `drift`.
    pub fn new(
        t_s: &[f64],
        origin_s: f64,
        freq_hz: f64,
        harmonics: usize,
        drift: bool,
        nyquist_hz: f64,
    ) -> Result<Self> {
        let n = t_s.len();
        let t0 = origin_s;
        let mean = t_s.iter().map(|t| t - t0).sum::<f64>() / n.max(1) as f64;
        let orders: Vec<usize> = (1..=harmonics.max(1))
            .filter(|&k| k == 1 || (k as f64) * freq_hz < nyquist_hz)
            .collect();
        let mut names: Vec<String> = Vec::new();
        for k in &orders {
            names.push(format!("A{k}"));
            names.push(format!("B{k}"));
        }
        names.push("C".into());
        if drift {
            names.push("D".into());
        }
        let p = names.len();
        let w = std::f64::consts::TAU * freq_hz;
        let mut m = DMatrix::zeros(n, p);
        for (i, t) in t_s.iter().enumerate() {
            let tp = t - t0;
            for (j, &k) in orders.iter().enumerate() {
                let (s, c) = (k as f64 * w * tp).sin_cos();
                m[(i, 2 * j)] = c;
                m[(i, 2 * j + 1)] = s;
            }
            m[(i, 2 * orders.len())] = 1.0;
            if drift {
                m[(i, 2 * orders.len() + 1)] = tp - mean;
            }
        }
        Ok(Self {
            design: Design::new(names, m)?,
            harmonics: orders.len() - 1,
        })
    }

    /// Fit one channel `y` (same length as the stamps).
    pub fn fit(&self, y: &[f64]) -> Result<ChannelFit> {
        let f = fit(
            &self.design,
            &DVector::from_column_slice(y),
            &FitOptions::default(),
        )?;
        let e = &f.estimates;
        let v = e.values();
        let c = e.covariance();
        let (a, b) = (v[0], v[1]);
        let r = a.hypot(b);
        let (u_r, u_phi) = if r > 0.0 {
            let ja = [a / r, b / r];
            let jp = [b / (r * r), -a / (r * r)];
            let quad = |j: [f64; 2]| {
                (j[0] * j[0] * c[(0, 0)] + 2.0 * j[0] * j[1] * c[(0, 1)] + j[1] * j[1] * c[(1, 1)])
                    .max(0.0)
                    .sqrt()
            };
            (quad(ja), quad(jp))
        } else {
            (c[(0, 0)].max(0.0).sqrt(), std::f64::consts::PI)
        };
        let thd = (self.harmonics > 0 && r > 0.0).then(|| {
            let h: f64 = (1..=self.harmonics)
                .map(|j| v[2 * j].powi(2) + v[2 * j + 1].powi(2))
                .sum();
            h.sqrt() / r
        });
        let offset = v[2 * (self.harmonics + 1)];
        Ok(ChannelFit {
            amplitude: r,
            u_amplitude: u_r,
            phase_rad: (-b).atan2(a),
            u_phase_rad: u_phi,
            offset,
            thd,
            residual_sd: f.sigma,
            dof: f.dof,
        })
    }
}

/// The frequency (Hz) of `y` at stamps `t_s` and its standard
/// uncertainty, by the four-parameter fit from `f0_hz` (module docs),
/// with the harmonics and drift of [`SineDesign::new`]. Refused when the
/// steps do not settle in 50 or leave `(0, nyquist_hz)`: the start is
/// more than about half a cycle over the record away.
pub fn fit_frequency(
    t_s: &[f64],
    f0_hz: f64,
    harmonics: usize,
    drift: bool,
    nyquist_hz: f64,
    y: &[f64],
) -> Result<(f64, f64)> {
    let n = t_s.len();
    let origin = t_s.first().copied().unwrap_or(0.0);
    // t' from the record's middle: the step is the least correlated with
    // the phase there (the result does not depend on it).
    let mid = 0.5 * (origin + t_s.last().copied().unwrap_or(origin));
    let y_v = DVector::from_column_slice(y);
    let mut f = f0_hz;
    for _ in 0..50 {
        let d = SineDesign::new(t_s, mid, f, harmonics, drift, nyquist_hz)?;
        let three = fit(&d.design, &y_v, &FitOptions::default())?;
        let v = three.estimates.values();
        let w = std::f64::consts::TAU * f;
        let orders = d.harmonics + 1;
        let mut m = d
            .design
            .matrix()
            .clone()
            .insert_column(d.design.matrix().ncols(), 0.0);
        let last = m.ncols() - 1;
        for (i, t) in t_s.iter().enumerate() {
            let tp = t - mid;
            m[(i, last)] = (1..=orders)
                .map(|k| {
                    let (s, c) = (k as f64 * w * tp).sin_cos();
                    k as f64 * tp * (-v[2 * (k - 1)] * s + v[2 * k - 1] * c)
                })
                .sum();
        }
        let mut names = d.design.names().to_vec();
        names.push("dw".into());
        let step = fit(&Design::new(names, m)?, &y_v, &FitOptions::default())?;
        let dw = step.estimates.values()[last];
        let u_dw = step.estimates.covariance()[(last, last)].max(0.0).sqrt();
        f += dw / std::f64::consts::TAU;
        if !(f > 0.0 && f < nyquist_hz) || n < 8 {
            break;
        }
        if dw.abs() <= 1e-10 * w {
            return Ok((f, u_dw / std::f64::consts::TAU));
        }
    }
    Err(crate::error::Error::Unsupported(format!(
        "the four-parameter sine fit from {f0_hz} Hz does not settle on a frequency"
    )))
}

/// `x` wrapped into (−π, π].
pub fn wrap_pi(x: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let y = x - tau * (x / tau).round();
    if y <= -std::f64::consts::PI {
        y + tau
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_noiseless_sine_with_harmonics_and_drift_is_recovered_exactly() {
        let t: Vec<f64> = (0..2000).map(|i| i as f64 / 1000.0).collect();
        let w = std::f64::consts::TAU * 7.0;
        let y: Vec<f64> = t
            .iter()
            .map(|t| 2.5 * (w * t + 0.7).cos() + 0.1 * (2.0 * w * t).sin() + 0.3 + 0.05 * t)
            .collect();
        let d = SineDesign::new(&t, 0.0, 7.0, 3, true, 500.0).unwrap();
        let f = d.fit(&y).unwrap();
        assert!((f.amplitude - 2.5).abs() < 1e-9, "{f:?}");
        assert!((f.phase_rad - 0.7).abs() < 1e-9);
        assert!((f.thd.unwrap() - 0.1 / 2.5).abs() < 1e-9);
    }

    #[test]
    fn the_four_parameter_fit_finds_the_frequency_from_a_start_a_bin_away() {
        let t: Vec<f64> = (0..5000).map(|i| i as f64 / 1000.0).collect();
        let f_true = 12.3456;
        let w = std::f64::consts::TAU * f_true;
        let y: Vec<f64> = t
            .iter()
            .map(|t| 1.5 * (w * t + 0.3).cos() + 0.05 * (2.0 * w * t).cos() + 0.2 + 0.01 * t)
            .collect();
        // A bin of a 5 s record is 0.2 Hz: start 0.15 Hz away.
        let (f, u) = fit_frequency(&t, f_true + 0.15, 3, true, 500.0, &y).unwrap();
        assert!((f - f_true).abs() < 1e-9, "{f}");
        assert!(u < 1e-9, "{u}");
    }

    #[test]
    fn harmonics_at_or_above_nyquist_are_not_fitted() {
        let t: Vec<f64> = (0..400).map(|i| i as f64 / 100.0).collect();
        let d = SineDesign::new(&t, 0.0, 20.0, 3, false, 50.0).unwrap();
        assert_eq!(d.harmonics, 1);
    }

    #[test]
    fn wrap_is_into_the_half_open_interval() {
        assert!((wrap_pi(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_pi(-std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_pi(0.5) - 0.5).abs() < 1e-15);
    }
}
