//! Tones (spectral lines) of a noise record: bins of the Welch PSD that
//! stand above their local noise floor by a significance test, then each
//! line's frequency and rms amplitude with u from a least-squares
//! sinusoid fitted to the whole record.
//!
//! # Search
//! The floor at bin `k` is the mean `F̂_k` of the `m` bins within
//! [`NEIGHBOURS`] of it outside its lobe (the window's main lobe and one
//! bin more: ±3 for Hann, ±2 for no window). Without a line,
//! `G_k/G_true ~ χ²_ν/ν` with `ν = 2 K_eff`, and `F̂_k/G_true ~
//! χ²_{ν m'}/(ν m')` with `m' = m/c` independent bins (`c` the bin
//! correlation of [`super::psd`]), so `G_k/F̂_k ~ F(ν, ν m')`. A bin is a
//! line when that ratio exceeds the F quantile at `1 − α/n` (`n` bins
//! searched, `α` the false-alarm rate per spectrum: Bonferroni, so at
//! most `α` false lines per spectrum). A floor that curves (1/f) is
//! convex and its mean lies above the centre, which keeps the rate. The
//! search starts at bin 16 (the floor of a steep low-frequency slope is
//! not flat over the neighbours) and ends below Nyquist; local maxima
//! closer than two lobes to a stronger one are its own lobe.
//!
//! # Estimate
//! The rate `y(t) = c₀ + c₁ t + a cos ωt + b sin ωt + e(t)` (`t` from the
//! record's middle) is fitted by Gauss–Newton from the peak's frequency,
//! first refined by the mean phase advance `arg Σ Z_{m+1} Z_m*` of the
//! DFT `Z_m` of consecutive segments at that frequency (within half a
//! Welch bin, unambiguous). Near the line the noise is white with the
//! density of the floor, so the parameters' covariance is `(JᵀJ)⁻¹ σ²`,
//! `σ² = F̂ f_s/2` (the variance of white noise of one-sided density `F̂`
//! at rate `f_s`). The rms amplitude `A = √((a² + b²)/2)`, with
//! `u(A)² = (a² V_aa + 2ab V_ab + b² V_bb)/(4A²)`; the frequency
//! `f = ω/2π`. Their degrees of freedom are the floor's, `ν m'` (S. M.
//! Kay, *Fundamentals of Statistical Signal Processing: Estimation
//! Theory*, Prentice Hall 1993, §7.10 and §13.5, for the estimator and its
//! bound).

use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

use super::psd::Psd;
use super::welch::Window;

/// Bins on each side of a candidate's lobe averaged into its floor.
pub const NEIGHBOURS: usize = 32;

/// The first bin searched.
pub const FIRST_BIN: usize = 16;

/// Lines estimated at most (the strongest); more are counted.
pub const MAX_TONES: usize = 16;

/// What the search did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    /// The false-alarm rate per spectrum `α`.
    pub false_alarm: f64,
    /// The ratio `G/F̂` a bin must exceed (with a full neighbourhood).
    pub threshold: f64,
    /// Bins searched.
    pub bins: usize,
    /// The band searched (Hz).
    pub band_hz: (f64, f64),
    /// Lines found beyond [`MAX_TONES`] and not estimated.
    pub more: usize,
}

/// A bin standing above its floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    /// The bin.
    pub bin: usize,
    /// Its floor `F̂` (unit²/Hz).
    pub floor: f64,
    /// `G/F̂`.
    pub ratio: f64,
    /// Degrees of freedom of the floor `ν m'`.
    pub floor_dof: f64,
    /// The peak's frequency interpolated on ln G (Hz).
    pub f_hz: f64,
}

/// A line of the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tone {
    /// Frequency (Hz) and its standard uncertainty.
    pub frequency_hz: f64,
    /// u of the frequency (Hz).
    pub u_frequency_hz: f64,
    /// rms amplitude (the estimate's unit).
    pub amplitude_rms: f64,
    /// Its standard uncertainty.
    pub u_amplitude_rms: f64,
    /// Degrees of freedom of both.
    pub dof: f64,
    /// The search's candidate.
    pub peak: Candidate,
}

/// Bins on each side of a line's peak that belong to its lobe.
pub fn lobe(window: Window) -> usize {
    match window {
        Window::Hann => 3,
        Window::Rectangular => 2,
    }
}

/// The ratio `r` with `P(F(ν₁, ν₂) > r) = p` (bisection on the survival
/// function, accurate far in the tail).
fn upper_quantile(nu1: f64, nu2: f64, p: f64) -> f64 {
    let Ok(d) = FisherSnedecor::new(nu1, nu2) else {
        return f64::INFINITY;
    };
    let (mut lo, mut hi) = (1.0, 2.0);
    while d.sf(hi) > p && hi < 1e12 {
        lo = hi;
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if d.sf(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The lines of `p` (module docs) at false-alarm rate `alpha` per
/// spectrum, strongest first.
pub fn search(p: &Psd, window: Window, alpha: f64) -> (Search, Vec<Candidate>) {
    let g = &p.density;
    let n = g.len();
    let e = lobe(window);
    let nu = 2.0 * p.effective;
    let df = p.freq_hz.get(1).copied().unwrap_or(0.0);
    let mut prefix = vec![0.0; n + 1];
    for (i, v) in g.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    // Bins 1 … n−2 hold no edge (0 Hz, Nyquist).
    let sum = |a: usize, b: usize| prefix[b] - prefix[a];
    let floors: Vec<(usize, f64, usize)> = (FIRST_BIN..n.saturating_sub(1))
        .filter_map(|k| {
            let (l0, l1) = (k.saturating_sub(e + NEIGHBOURS).max(1), k - e);
            let (r0, r1) = (k + e + 1, (k + e + 1 + NEIGHBOURS).min(n - 1));
            let m = l1.saturating_sub(l0) + r1.saturating_sub(r0);
            let s = sum(l0, l1.max(l0)) + if r1 > r0 { sum(r0, r1) } else { 0.0 };
            (m >= 8).then(|| (k, s / m as f64, m))
        })
        .collect();
    let bins = floors.len();
    let per_bin = alpha / bins.max(1) as f64;
    let c = p.bin_correlation.max(1.0);
    let mut thresholds = std::collections::HashMap::new();
    let mut threshold = |m: usize| -> f64 {
        *thresholds
            .entry(m)
            .or_insert_with(|| upper_quantile(nu, nu * m as f64 / c, per_bin))
    };
    let full = threshold(2 * NEIGHBOURS);
    let mut found: Vec<Candidate> = Vec::new();
    for &(k, floor, m) in &floors {
        let ratio = g[k] / floor;
        if !(floor > 0.0 && ratio > threshold(m) && g[k] >= g[k - 1] && g[k] >= g[k + 1]) {
            continue;
        }
        let (a, b, z) = (g[k - 1].ln(), g[k].ln(), g[k + 1].ln());
        let den = a - 2.0 * b + z;
        let d = if den < 0.0 {
            (0.5 * (a - z) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        found.push(Candidate {
            bin: k,
            floor,
            ratio,
            floor_dof: nu * m as f64 / c,
            f_hz: (k as f64 + d) * df,
        });
    }
    found.sort_by(|x, y| g[y.bin].total_cmp(&g[x.bin]));
    let mut kept: Vec<Candidate> = Vec::new();
    for cand in found {
        if kept.iter().all(|k| k.bin.abs_diff(cand.bin) > 2 * e) {
            kept.push(cand);
        }
    }
    let more = kept.len().saturating_sub(MAX_TONES);
    kept.truncate(MAX_TONES);
    let band_hz = match (floors.first(), floors.last()) {
        (Some(a), Some(b)) => (a.0 as f64 * df, b.0 as f64 * df),
        _ => (0.0, 0.0),
    };
    let s = Search {
        false_alarm: alpha,
        threshold: full,
        bins,
        band_hz,
        more,
    };
    (s, kept)
}

/// Samples per block of the passes over the record (fixed: the sums do
/// not depend on the number of threads).
const BLOCK: usize = 1 << 16;

/// `Σ` over the record of `f(n, t_s, cos ωt, sin ωt, y)` (`t_s` the time
/// from the middle over half the length), blockwise in parallel and
/// added in block order; the phase is rotated within a block from its
/// exact value at the block's start.
fn pass<const R: usize, const C: usize>(
    x: &[f64],
    tau0: f64,
    omega: f64,
    f: impl Fn(f64, f64, f64, f64) -> SMatrix<f64, R, C> + Sync,
) -> SMatrix<f64, R, C> {
    let n = x.len().saturating_sub(1);
    let mid = 0.5 * (n as f64 - 1.0);
    let half = (0.5 * n as f64 * tau0).max(tau0);
    let (ds, dc) = (omega * tau0).sin_cos();
    let parts: Vec<SMatrix<f64, R, C>> = (0..n.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let mut acc = SMatrix::<f64, R, C>::zeros();
            let start = b * BLOCK;
            let (mut s, mut co) = (omega * (start as f64 - mid) * tau0).sin_cos();
            for i in start..(start + BLOCK).min(n) {
                let t = (i as f64 - mid) * tau0;
                let y = (x[i + 1] - x[i]) / tau0;
                acc += f(t / half, co, s, y);
                let c2 = co * dc - s * ds;
                s = s * dc + co * ds;
                co = c2;
            }
            acc
        })
        .collect();
    parts.into_iter().fold(SMatrix::zeros(), |a, b| a + b)
}

/// The frequency refined by the mean phase advance between consecutive
/// segments of `l` samples at `f_hz` (module docs).
fn refine(x: &[f64], tau0: f64, f_hz: f64, l: usize) -> f64 {
    let n = x.len().saturating_sub(1);
    let segs = n / l;
    if segs < 2 {
        return f_hz;
    }
    let omega = std::f64::consts::TAU * f_hz;
    let (ds, dc) = (omega * tau0).sin_cos();
    let z: Vec<(f64, f64)> = (0..segs)
        .into_par_iter()
        .map(|m| {
            let (mut re, mut im) = (0.0, 0.0);
            let (mut s, mut c) = (omega * (m * l) as f64 * tau0).sin_cos();
            for i in m * l..(m + 1) * l {
                let y = (x[i + 1] - x[i]) / tau0;
                re += y * c;
                im -= y * s;
                let c2 = c * dc - s * ds;
                s = s * dc + c * ds;
                c = c2;
            }
            (re, im)
        })
        .collect();
    let (mut re, mut im) = (0.0, 0.0);
    for w in z.windows(2) {
        // Z_{m+1} · conj(Z_m).
        re += w[1].0 * w[0].0 + w[1].1 * w[0].1;
        im += w[1].1 * w[0].0 - w[1].0 * w[0].1;
    }
    f_hz + im.atan2(re) / (std::f64::consts::TAU * l as f64 * tau0)
}

/// The line at candidate `cand` of the rate whose phase is `x` (sample
/// period `tau0`, Welch segments of `l` samples): `None` when the fit
/// does not converge.
pub fn estimate(x: &[f64], tau0: f64, l: usize, cand: &Candidate) -> Option<Tone> {
    let n = x.len().saturating_sub(1);
    let half = (0.5 * n as f64 * tau0).max(tau0);
    let mut omega = std::f64::consts::TAU * refine(x, tau0, cand.f_hz, l);
    let (mut a, mut b) = (0.0, 0.0);
    let mut cov = SMatrix::<f64, 5, 5>::zeros();
    let mut converged = false;
    for it in 0..12 {
        // The first pass holds ω fixed (a, b start at 0).
        let (aa, bb) = (a, b);
        let m = pass::<5, 6>(x, tau0, omega, |s, c, sn, y| {
            let j = SVector::<f64, 5>::from([
                1.0,
                s,
                c,
                sn,
                if it == 0 {
                    0.0
                } else {
                    s * (-aa * sn + bb * c)
                },
            ]);
            let mut out = SMatrix::<f64, 5, 6>::zeros();
            out.fixed_view_mut::<5, 5>(0, 0)
                .copy_from(&(j * j.transpose()));
            out.fixed_view_mut::<5, 1>(0, 5).copy_from(&(j * y));
            out
        });
        let mut jtj: SMatrix<f64, 5, 5> = m.fixed_view::<5, 5>(0, 0).into();
        let rhs: SVector<f64, 5> = m.fixed_view::<5, 1>(0, 5).into();
        if it == 0 {
            jtj[(4, 4)] = 1.0;
        }
        let inv = jtj.try_inverse()?;
        let p = inv * rhs;
        // The linearisation: y ≈ a cos + b sin + Δω' s (−a sin + b cos)
        // with the previous a, b; p₄ is Δω times half the length.
        let step = if it == 0 { 0.0 } else { p[4] / half };
        a = p[2];
        b = p[3];
        omega += step;
        cov = inv;
        if it > 0 && (step * half).abs() < 1e-9 {
            converged = true;
            break;
        }
    }
    if !(converged && a.is_finite() && b.is_finite() && omega.is_finite()) {
        return None;
    }
    let sigma2 = cand.floor / (2.0 * tau0);
    let v = cov * sigma2;
    let amp = ((a * a + b * b) / 2.0).sqrt();
    let var_amp = (a * a * v[(2, 2)] + 2.0 * a * b * v[(2, 3)] + b * b * v[(3, 3)])
        / (4.0 * amp * amp).max(f64::MIN_POSITIVE);
    let u_f = v[(4, 4)].sqrt() / half / std::f64::consts::TAU;
    Some(Tone {
        frequency_hz: omega / std::f64::consts::TAU,
        u_frequency_hz: u_f,
        amplitude_rms: amp,
        u_amplitude_rms: var_amp.sqrt(),
        dof: cand.floor_dof,
        peak: *cand,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tail_quantile_has_the_asked_survival() {
        for (a, b, p) in [(16.0, 480.0, 3e-7), (40.0, 1250.0, 1e-3), (8.0, 64.0, 0.05)] {
            let r = upper_quantile(a, b, p);
            let d = FisherSnedecor::new(a, b).unwrap();
            assert!((d.sf(r) / p - 1.0).abs() < 1e-6, "{a} {b} {p}: {r}");
        }
    }

    #[test]
    fn two_lines_are_found_apart_and_fitted() {
        let (fs, n) = (100.0, 40_000);
        let mut r = crate::sim::rng(9);
        let mut x = vec![0.0];
        for i in 0..n {
            let t = i as f64 / fs;
            let y = crate::sim::normal(&mut r, 0.05)
                + 0.03 * (std::f64::consts::TAU * 12.25 * t).sin()
                + 0.01 * (std::f64::consts::TAU * 31.0 * t + 1.0).cos();
            x.push(x.last().unwrap() + y / fs);
        }
        let p = super::super::psd::psd_of_phase(&x, 1.0 / fs, (2048, 1024), Window::Hann, 0.95)
            .unwrap();
        let (s, found) = search(&p, Window::Hann, 0.01);
        assert_eq!(found.len(), 2, "{found:?}");
        assert!(s.threshold > 1.0 && s.bins > 900);
        let lines: Vec<Tone> = found
            .iter()
            .map(|c| estimate(&x, 1.0 / fs, 2048, c).unwrap())
            .collect();
        // The stronger first; rms = peak/√2.
        assert!((lines[0].frequency_hz - 12.25).abs() < 4.0 * lines[0].u_frequency_hz);
        assert!(
            (lines[0].amplitude_rms - 0.03 / 2f64.sqrt()).abs() < 4.0 * lines[0].u_amplitude_rms
        );
        assert!((lines[1].frequency_hz - 31.0).abs() < 4.0 * lines[1].u_frequency_hz);
        assert!(
            (lines[1].amplitude_rms - 0.01 / 2f64.sqrt()).abs() < 4.0 * lines[1].u_amplitude_rms
        );
    }
}
