//! A first-order Gauss–Markov bias fitted to the Allan variance, the bias
//! model of a Kalman filter, with its discrete-time form at a filter rate.
//!
//! A stationary first-order Gauss–Markov process of standard deviation σ
//! and correlation time T (`ḃ = −b/T + w`, `w` white of PSD `2σ²/T`) has
//! the Allan variance (IEEE Std 952-1997 Annex C, "exponentially
//! correlated (Markov) noise", with `q_c² = 2σ²/T`)
//!
//! `σ²_GM(τ) = (2σ²T/τ) [1 − (T/2τ)(3 − 4e^{−τ/T} + e^{−2τ/T})]`,
//!
//! rising as `K²τ/3` (`K² = 2σ²/T`) for τ ≪ T, peaking near τ ≈ 1.89 T and
//! falling as `N²/τ` (`N² = 2σ²T`) for τ ≫ T. The fit is
//! `σ²_A(τ) = 3Q²/τ² + N²/τ + σ²_GM(τ)` by weighted least squares on the
//! octave-spaced OADEV at τ ≥ 4τ0, each weighted by its equivalent degrees
//! of freedom (`var σ²_A = 2σ⁴_A/edf`, the model's value after the first
//! pass): linear in `Q², N², σ²` for each T, T profiled over a log grid and
//! refined by golden section in ln T. Covariance `(JᵀWJ)⁻¹` of
//! `(…, σ², ln T)` with J at the optimum in the sandwich form with the
//! estimates' correlation across octaves, times the Birge ratio χ²/dof
//! when above 1 (then `n − p` degrees of freedom). T is estimated in ln T,
//! so its 95 % interval `T e^{±U(ln T)}` is lopsided: `u(T)` is stated as
//! the wider side, `T (e^{U(ln T)} − 1)/k`. A Gauss–Markov bias is
//! **supported** by the record when its peak lies inside the τ range
//! (`τ_min ≤ 1.89 T ≤ τ_max`) and both σ and T have U95 below their
//! value; otherwise the reason is given and no figure reported.
//!
//! In discrete time at a filter rate `f` (`Δt = 1/f`): `b_{k+1} = φ b_k +
//! w_k`, `φ = e^{−Δt/T}`, `std w_k = q_d = σ√(1 − φ²)`; in continuous time
//! the driving noise density is `q_c = σ√(2/T)` (unit/√s) (A. Gelb, ed.,
//! *Applied Optimal Estimation*, MIT Press 1974, Table 3.4-1; R. G. Brown
//! and P. Y. C. Hwang, *Introduction to Random Signals and Applied Kalman
//! Filtering*, 4th ed., Wiley 2012, §2.9).

use nalgebra::{DMatrix, DVector};

use super::DevSeries;

/// Where the Allan variance of a Gauss–Markov process peaks, in T.
pub const PEAK_TAU_OVER_T: f64 = 1.89;

/// The Allan variance of a Gauss–Markov process of variance `sigma2` and
/// correlation time `t_s` at τ (module docs); the series
/// `x²/3 − x³/4 + 7x⁴/60 − x⁵/24` (x = τ/T) below x = 0.01.
pub fn gm_avar(sigma2: f64, t_s: f64, tau: f64) -> f64 {
    let x = tau / t_s;
    let bracket = if x < 0.01 {
        x * x * (1.0 / 3.0 - x * (0.25 - x * (7.0 / 60.0 - x / 24.0)))
    } else {
        1.0 - (-4.0 * (-x).exp_m1() + (-2.0 * x).exp_m1()) / (2.0 * x)
    };
    2.0 * sigma2 * t_s / tau * bracket
}

/// The fit and its verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussMarkov {
    /// σ (internal rate unit) and its standard uncertainty.
    pub sigma: f64,
    /// u(σ).
    pub u_sigma: f64,
    /// Correlation time T (s).
    pub tau_c_s: f64,
    /// u(T) (s).
    pub u_tau_c_s: f64,
    /// Covariance of `(σ², ln T)`.
    pub cov: [[f64; 2]; 2],
    /// The white term N fitted beside it (unit·√s), 0 when dropped.
    pub n: f64,
    /// Degrees of freedom of the u (∞ when the weights held).
    pub dof: f64,
    /// χ² and the number of averaging times fitted.
    pub chi2: f64,
    /// Averaging times fitted.
    pub points: usize,
    /// The τ range fitted (s).
    pub tau_range_s: (f64, f64),
    /// `None` when the record supports the bias, else why not.
    pub unsupported: Option<String>,
}

/// One linear fit at a fixed T: `(θ of the kept columns, kept, χ²)`.
fn linear(obs: &[(f64, f64, f64)], w: &[f64], t: f64) -> Option<(Vec<f64>, Vec<usize>, f64)> {
    let col = |j: usize, tau: f64| column(j, t, tau);
    let mut kept = vec![0usize, 1, 2];
    loop {
        let a = DMatrix::from_fn(obs.len(), kept.len(), |i, k| {
            col(kept[k], obs[i].0) * w[i].sqrt()
        });
        let b = DVector::from_fn(obs.len(), |i, _| obs[i].1 * w[i].sqrt());
        let th = crate::estimation::bounded_svd(a.clone(), true, true)?
            .solve(&b, 1e-14)
            .ok()?;
        if let Some(k) = (0..kept.len()).find(|&k| th[k] < 0.0) {
            if kept[k] == 2 {
                return None;
            }
            kept.remove(k);
            continue;
        }
        let r = a * &th - b;
        return Some((th.iter().copied().collect(), kept, r.norm_squared()));
    }
}

/// The model at τ of the fit `(θ, kept)` at T.
fn model(th: &[f64], kept: &[usize], t: f64, tau: f64) -> f64 {
    kept.iter()
        .zip(th)
        .map(|(&j, v)| v * column(j, t, tau))
        .sum()
}

/// Column `j` of the fit at τ: Q² and N² as the IEEE term fit regresses
/// them ([`super::terms::regressor`] 0 and 1), then σ² of the
/// Gauss–Markov term of correlation time `t`.
fn column(j: usize, t: f64, tau: f64) -> f64 {
    if j < 2 {
        super::terms::regressor(j, tau)
    } else {
        gm_avar(1.0, t, tau)
    }
}

/// The best T on a log grid then by golden section: `(T, θ, kept, χ²)`.
fn profile(obs: &[(f64, f64, f64)], w: &[f64]) -> Option<(f64, Vec<f64>, Vec<usize>, f64)> {
    let (lo, hi) = (obs[0].0 / 8.0, obs[obs.len() - 1].0 * 8.0);
    let at = |lt: f64| linear(obs, w, lt.exp()).map(|(th, k, c)| (lt.exp(), th, k, c));
    let n = 64;
    let grid: Vec<f64> = (0..=n)
        .map(|i| lo.ln() + (hi.ln() - lo.ln()) * i as f64 / n as f64)
        .collect();
    let (i, _) = grid
        .iter()
        .enumerate()
        .filter_map(|(i, &lt)| at(lt).map(|r| (i, r.3)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let (mut a, mut b) = (grid[i.saturating_sub(1)], grid[(i + 1).min(n)]);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let chi = |lt: f64| at(lt).map_or(f64::INFINITY, |r| r.3);
    for _ in 0..60 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if chi(c) < chi(d) {
            b = d;
        } else {
            a = c;
        }
    }
    at(0.5 * (a + b))
}

/// The correlation of OADEV estimates an octave apart where the local
/// log–log slope of σ²_A is `mu`: 0.53 for white rate noise (μ = −1),
/// 0.69 for flicker (μ = 0), 0.89 for a random walk (μ ≥ 1), linear
/// between (the values the IEEE term fit uses, [`super::terms`]).
fn octave_correlation(mu: f64) -> f64 {
    if mu <= -1.0 {
        0.53
    } else if mu <= 0.0 {
        0.69 + 0.16 * mu
    } else {
        0.69 + 0.2 * mu.min(1.0)
    }
}

/// The sandwich covariance of `(θ kept…, ln T)` at the fit `(T, θ,
/// kept)`: `B V Bᵀ`, `B = (JᵀWJ)⁻¹JᵀW`, V the estimates' covariance (each
/// `2 m²/edf`, octaves correlated by [`octave_correlation`] of the
/// model's local slope), times the Birge ratio `rᵀV⁻¹r/(n − p)` when
/// above 1. Returns `(cov, dof, χ², n − p)`.
fn covariance(
    obs: &[(f64, f64, f64)],
    w: &[f64],
    (t, th, kept): (f64, &[f64], &[usize]),
) -> Option<(DMatrix<f64>, f64, f64, usize)> {
    let n = obs.len();
    let p = kept.len() + 1;
    let gm = kept.iter().position(|&j| j == 2)?;
    let h = 1e-4_f64;
    let jac = DMatrix::from_fn(n, p, |i, k| {
        let tau = obs[i].0;
        if k < kept.len() {
            let mut e = vec![0.0; kept.len()];
            e[k] = 1.0;
            model(&e, kept, t, tau)
        } else {
            th[gm] * (gm_avar(1.0, t * h.exp(), tau) - gm_avar(1.0, t * (-h).exp(), tau))
                / (2.0 * h)
        }
    });
    let wm = DMatrix::from_diagonal(&DVector::from_column_slice(w));
    let inv = (jac.transpose() * &wm * &jac).try_inverse()?;
    let b = &inv * jac.transpose() * &wm;
    let m: Vec<f64> = obs
        .iter()
        .map(|o| model(th, kept, t, o.0).max(1e-300))
        .collect();
    let sd: Vec<f64> = m
        .iter()
        .zip(obs)
        .map(|(m, o)| m * (2.0 / o.2).sqrt())
        .collect();
    let slope = |tau: f64| {
        let (a, c) = (model(th, kept, t, tau / 1.1), model(th, kept, t, tau * 1.1));
        (c / a).ln() / (1.21f64).ln()
    };
    let rho: Vec<f64> = obs.iter().map(|o| octave_correlation(slope(o.0))).collect();
    let mut v = DMatrix::<f64>::zeros(n, n);
    for i in 0..n {
        v[(i, i)] = sd[i] * sd[i];
        let mut r = 1.0;
        for j in i + 1..n {
            r *= (rho[j - 1] * rho[j])
                .sqrt()
                .powf((obs[j].0 / obs[j - 1].0).log2());
            v[(i, j)] = r * sd[i] * sd[j];
            v[(j, i)] = v[(i, j)];
        }
    }
    let mut cov = &b * &v * b.transpose();
    let r = DVector::from_iterator(n, obs.iter().zip(&m).map(|(o, m)| o.1 - m));
    let chi2 = v.clone().cholesky().map(|c| r.dot(&c.solve(&r)))?;
    let dof_n = n.saturating_sub(p);
    let mut dof = f64::INFINITY;
    if dof_n > 0 && chi2 > dof_n as f64 {
        cov *= chi2 / dof_n as f64;
        dof = dof_n as f64;
    }
    Some((cov, dof, chi2, dof_n))
}

/// The Gauss–Markov fit of the OADEV at `taus` (module docs); the reason
/// when there is none to report a verdict on (fewer than four usable
/// averaging times, or a σ² below zero at every T).
pub fn fit_gauss_markov(
    taus: &[f64],
    oadev: &DevSeries,
    tau0: f64,
) -> std::result::Result<GaussMarkov, String> {
    fit_inner(taus, oadev, tau0).ok_or_else(|| {
        "the Allan variance is explained without one (no positive sigma^2 at any correlation time, or fewer than four averaging times)".to_string()
    })
}

fn fit_inner(taus: &[f64], oadev: &DevSeries, tau0: f64) -> Option<GaussMarkov> {
    let mut obs: Vec<(f64, f64, f64)> = Vec::new();
    for (i, &t) in taus.iter().enumerate() {
        let (Some(s), Some(e)) = (oadev.value[i], oadev.edf[i]) else {
            continue;
        };
        if t < 4.0 * tau0 * (1.0 - 1e-9)
            || !(s > 0.0 && e > 0.0)
            || obs.last().is_some_and(|o| t < 1.9 * o.0)
        {
            continue;
        }
        obs.push((t, s * s, e));
    }
    if obs.len() < 4 {
        return None;
    }
    // Weights from the observed values, then from the first fit's model.
    let mut w: Vec<f64> = obs.iter().map(|o| o.2 / (2.0 * o.1 * o.1)).collect();
    let mut best = profile(&obs, &w)?;
    for _ in 0..2 {
        w = obs
            .iter()
            .map(|o| {
                let m = model(&best.1, &best.2, best.0, o.0).max(1e-300);
                o.2 / (2.0 * m * m)
            })
            .collect();
        best = profile(&obs, &w)?;
    }
    // The χ² that counts is the correlated one of [`covariance`].
    let (t, th, kept, _) = best;
    let gm = kept.iter().position(|&j| j == 2)?;
    let sigma2 = th[gm];
    let (v, dof, chi2, dof_n) = covariance(&obs, &w, (t, &th, &kept))?;
    let p = kept.len() + 1;
    let (vs, vt, vst) = (v[(gm, gm)], v[(p - 1, p - 1)], v[(gm, p - 1)]);
    let sigma = sigma2.sqrt();
    let n = kept
        .iter()
        .position(|&j| j == 1)
        .map_or(0.0, |k| th[k].max(0.0).sqrt());
    let k = crate::estimation::coverage_factor(dof, 0.95);
    // T is estimated in ln T: its interval T e^{±k u} is not symmetric;
    // the stated u is the wider side's half-width over k.
    let (u_sigma, u_t) = (
        vs.max(0.0).sqrt() / (2.0 * sigma),
        t * (k * vt.max(0.0).sqrt()).exp_m1() / k,
    );
    let range = (obs[0].0, obs[obs.len() - 1].0);
    let peak = PEAK_TAU_OVER_T * t;
    let unsupported = if dof_n == 0 {
        Some("as many parameters as averaging times".to_string())
    } else if peak > range.1 {
        Some(format!(
            "its Allan variance would peak at tau = {} s, beyond the longest averaging time {} s: the record shows a rising curve that a rate random walk explains as well",
            crate::error::short_f64(peak),
            crate::error::short_f64(range.1)
        ))
    } else if peak < range.0 {
        Some(format!(
            "its Allan variance would peak at tau = {} s, below the shortest averaging time fitted {} s",
            crate::error::short_f64(peak),
            crate::error::short_f64(range.0)
        ))
    } else if k * u_sigma >= sigma || k * u_t >= t {
        Some(format!(
            "sigma or tau_c has a U95 at or above its value (sigma {} +- {}, tau_c {} +- {} s, U95)",
            crate::error::short_f64(sigma),
            crate::error::short_f64(k * u_sigma),
            crate::error::short_f64(t),
            crate::error::short_f64(k * u_t)
        ))
    } else {
        None
    };
    Some(GaussMarkov {
        sigma,
        u_sigma,
        tau_c_s: t,
        u_tau_c_s: u_t,
        cov: [[vs, vst], [vst, vt]],
        n,
        dof,
        chi2,
        points: obs.len(),
        tau_range_s: range,
        unsupported,
    })
}

impl GaussMarkov {
    /// The discrete-time form at `rate_hz` (module docs): `(φ, u(φ), q_d,
    /// u(q_d))`, u from the covariance of `(σ², ln T)`.
    pub fn discrete(&self, rate_hz: f64) -> (f64, f64, f64, f64) {
        let f = |s2: f64, lt: f64| {
            let phi = (-1.0 / (rate_hz * lt.exp())).exp();
            (phi, s2.max(0.0).sqrt() * (1.0 - phi * phi).max(0.0).sqrt())
        };
        let (s2, lt) = (self.sigma * self.sigma, self.tau_c_s.ln());
        let (phi, q) = f(s2, lt);
        let (hs, ht) = (1e-6 * s2, 1e-6);
        let d = |g: &dyn Fn(f64, f64) -> f64| {
            let a = (g(s2 + hs, lt) - g(s2 - hs, lt)) / (2.0 * hs);
            let b = (g(s2, lt + ht) - g(s2, lt - ht)) / (2.0 * ht);
            let c = &self.cov;
            (a * a * c[0][0] + 2.0 * a * b * c[0][1] + b * b * c[1][1])
                .max(0.0)
                .sqrt()
        };
        (phi, d(&|a, b| f(a, b).0), q, d(&|a, b| f(a, b).1))
    }

    /// `(q_c, u(q_c))`: the continuous-time driving density `σ√(2/T)`.
    pub fn continuous(&self) -> (f64, f64) {
        let q = self.sigma * (2.0 / self.tau_c_s).sqrt();
        // ln q = ½ ln σ² + ½ ln 2 − ½ ln T.
        let c = &self.cov;
        let s2 = self.sigma * self.sigma;
        let (a, b) = (0.5 / s2, -0.5);
        let rel = (a * a * c[0][0] + 2.0 * a * b * c[0][1] + b * b * c[1][1])
            .max(0.0)
            .sqrt();
        (q, q * rel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_allan_variance_has_its_two_asymptotes_and_its_series() {
        let (s2, t) = (2.0, 50.0);
        // τ ≪ T: K²τ/3 with K² = 2σ²/T; τ ≫ T: 2σ²T/τ.
        let short = gm_avar(s2, t, 0.05);
        assert!((short / (2.0 * s2 / t * 0.05 / 3.0) - 1.0).abs() < 1e-3);
        let long = gm_avar(s2, t, 5e5);
        assert!((long / (2.0 * s2 * t / 5e5) - 1.0).abs() < 1e-3);
        // The series and the closed form agree where they meet.
        let (a, b) = (gm_avar(s2, t, 0.0099999 * t), gm_avar(s2, t, 0.0100001 * t));
        assert!((a / b - 1.0).abs() < 1e-4);
        // The peak near 1.89 T.
        let taus: Vec<f64> = (1..4000).map(|i| i as f64 * 0.05).collect();
        let best = taus
            .iter()
            .copied()
            .max_by(|x, y| gm_avar(s2, 1.0, *x).total_cmp(&gm_avar(s2, 1.0, *y)))
            .unwrap();
        assert!((best - PEAK_TAU_OVER_T).abs() < 0.06, "{best}");
    }
}
