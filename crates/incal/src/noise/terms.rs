//! The IEEE Std 952-1997 Annex C noise terms from the Allan variance, and
//! bias stability as GJB 2426A / IEEE Std 1431 define it.
//!
//! Allan variance model (IEEE Std 952 eq. C.15 ff., rate unit `u`, τ in s):
//! `σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π) B² + K²τ/3 + R²τ²/2`
//! with Q quantization (u·s), N angle random walk (u·√s), B bias
//! instability (u), K rate random walk (u/√s), R rate ramp (u/s).

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::{fit, Design, Estimates, FitOptions, Variance};
use crate::warning::{Warning, WarningCode};

use super::DevSeries;

/// `2 ln 2 / π`: the flicker (bias-instability) level of the Allan
/// variance, IEEE Std 952 eq. C.20 (σ = 0.664 B at the flat floor).
pub const FLICKER: f64 = 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI;

/// The five terms, in the order of the fit.
pub const TERMS: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// Regressor of term `j` at τ (the factor multiplying its square).
pub fn regressor(j: usize, tau: f64) -> f64 {
    match j {
        0 => 3.0 / (tau * tau),
        1 => 1.0 / tau,
        2 => FLICKER,
        3 => tau / 3.0,
        _ => tau * tau / 2.0,
    }
}

/// One identified term: amplitude and its standard uncertainty, in the
/// rate unit's base (Q in u·s, N in u·√s, B in u, K in u/√s, R in u/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    /// Amplitude (Q, N, B, K or R).
    pub value: f64,
    /// Standard uncertainty of the amplitude.
    pub u: f64,
    /// Degrees of freedom of u (∞ when the EDF weights held).
    pub dof: f64,
}

/// The weighted fit of the five terms.
#[derive(Debug, Clone, PartialEq)]
pub struct TermFit {
    /// Each term when identified (`None` = not identified), in [`TERMS`] order.
    pub terms: [Option<Term>; 5],
    /// The fitted squared amplitudes of the kept terms (θ = amplitude²)
    /// with covariance.
    pub squares: Option<Estimates>,
    /// Warnings (terms not identified, and why).
    pub warnings: Vec<Warning>,
    /// Residual χ² of the final fit and its degrees of freedom.
    pub chi2: Option<(f64, usize)>,
}

impl TermFit {
    /// The model Allan deviation at τ from the identified terms.
    pub fn model(&self, tau: f64) -> f64 {
        let mut v = 0.0;
        for (j, t) in self.terms.iter().enumerate() {
            if let Some(t) = t {
                v += t.value * t.value * regressor(j, tau);
            }
        }
        v.sqrt()
    }
}

/// Correlation of the OADEV variance estimates one octave apart, by the
/// noise exponent α (measured over 300 simulated records of each pure noise
/// type, 2^15 points, octave τ: white FM 0.53, flicker FM 0.69, random-walk
/// FM 0.89; white and flicker PM taken as white FM).
fn octave_correlation(alpha: Option<i32>) -> f64 {
    match alpha {
        Some(a) if a <= -2 => 0.89,
        Some(-1) => 0.69,
        _ => 0.53,
    }
}

/// A fit of a set of terms after the active set: the estimates of the
/// squares of `active`, the generalized χ² and its dof, and the terms that
/// left the set (with why).
struct Active {
    est: Estimates,
    chi2: f64,
    dof: usize,
    active: Vec<usize>,
    dropped: Vec<(usize, &'static str)>,
}

/// Fit the squares of the terms `active` (module docs of [`fit_terms`]),
/// removing negative ones one by one; `None` when none is left.
fn fit_active(
    obs: &[(f64, f64, f64, Option<i32>)],
    corr: &DMatrix<f64>,
    mut active: Vec<usize>,
) -> Result<Option<Active>> {
    let mut dropped: Vec<(usize, &'static str)> = Vec::new();
    let nobs = obs.len();
    loop {
        // Fewer observations than terms: drop the outermost terms (ramp
        // first, then quantization).
        while !active.is_empty() && active.len() >= nobs {
            let j = if active.contains(&4) {
                4
            } else if active.contains(&0) {
                0
            } else {
                active[active.len() - 1]
            };
            active.retain(|&a| a != j);
            dropped.push((j, "too few averaging times"));
        }
        if active.is_empty() {
            return Ok(None);
        }
        let names: Vec<String> = active.iter().map(|&j| format!("{}2", TERMS[j])).collect();
        // Columns scaled to a largest entry of 1: over decades of τ the
        // regressors span many orders of magnitude (τ² against 1/τ²), which
        // would read as a zero column. θ_j = θ'_j / c_j afterwards.
        let raw = DMatrix::from_fn(nobs, active.len(), |i, k| regressor(active[k], obs[i].0));
        let c: Vec<f64> = (0..active.len())
            .map(|k| raw.column(k).amax().max(f64::MIN_POSITIVE))
            .collect();
        let a = DMatrix::from_fn(nobs, active.len(), |i, k| raw[(i, k)] / c[k]);
        let y = DVector::from_iterator(nobs, obs.iter().map(|o| o.1 * o.1));
        let mut pred: Vec<f64> = obs.iter().map(|o| o.1 * o.1).collect();
        let mut last = None;
        for _ in 0..6 {
            let w = DVector::from_iterator(
                nobs,
                obs.iter().zip(&pred).map(|(o, p)| o.2 / (2.0 * p * p)),
            );
            let design = Design::new(names.clone(), a.clone())?;
            let f = fit(
                &design,
                &y,
                &FitOptions {
                    weights: Some(w.clone()),
                    variance: Variance::Known { dof: f64::INFINITY },
                    ..FitOptions::default()
                },
            )?;
            let m = &a * f.estimates.values();
            for (k, p) in pred.iter_mut().enumerate() {
                // Keep the weights of a poor early model sane.
                let s2 = obs[k].1 * obs[k].1;
                *p = m[k].clamp(s2 / 4.0, s2 * 4.0);
            }
            last = Some((f, w));
        }
        // The loop always runs; an error rather than a panic keeps input
        // from ever aborting the process.
        let (f, w) = last.ok_or_else(|| {
            crate::error::Error::Unsupported("noise-term fit: no iteration ran".into())
        })?;
        // Sandwich covariance of the weighted estimator under the
        // correlated covariance V of the σ̂²: C = B V Bᵀ, B = (AᵀWA)⁻¹AᵀW.
        let sd: Vec<f64> = obs
            .iter()
            .zip(&pred)
            .map(|(o, p)| p * (2.0 / o.2).sqrt())
            .collect();
        let v = DMatrix::from_fn(nobs, nobs, |i, j| corr[(i, j)] * sd[i] * sd[j]);
        let bmat = f.estimates.covariance() * a.transpose() * DMatrix::from_diagonal(&w);
        let mut cov = &bmat * &v * bmat.transpose();
        // Lack of fit against V (generalized χ², 5 % level): scale by the
        // Birge ratio with n − p degrees of freedom.
        let r = &y - &a * f.estimates.values();
        let dofr = nobs - active.len();
        let chi2 = v
            .clone()
            .cholesky()
            .map(|c| r.dot(&c.solve(&r)))
            .unwrap_or(f64::NAN);
        let mut dof = f64::INFINITY;
        if dofr > 0 && chi2.is_finite() {
            let birge = chi2 / dofr as f64;
            if birge > 1.0 {
                cov *= birge;
                dof = dofr as f64;
            }
        }
        let p = active.len();
        let vals = DVector::from_fn(p, |k, _| f.estimates.values()[k] / c[k]);
        let cov = DMatrix::from_fn(p, p, |j, k| cov[(j, k)] / (c[j] * c[k]));
        let est = Estimates::new(names.clone(), vals, cov, dof)?;
        let f = (est, chi2, dofr);
        let v = f.0.values();
        let worst = (0..active.len()).filter(|&k| v[k] < 0.0).min_by(|&a, &b| {
            let za = v[a] / f.0.u_at(a).max(f64::MIN_POSITIVE);
            let zb = v[b] / f.0.u_at(b).max(f64::MIN_POSITIVE);
            za.total_cmp(&zb)
        });
        match worst {
            Some(k) => {
                dropped.push((active[k], "its fitted square is negative"));
                active.remove(k);
            }
            None => {
                return Ok(Some(Active {
                    est: f.0,
                    chi2: f.1,
                    dof: f.2,
                    active,
                    dropped,
                }))
            }
        }
    }
}

/// Fit the IEEE 952 terms to an OADEV series by generalized least squares
/// (weighted least squares on the estimation core).
///
/// Observations are σ̂²(τ_i) at τ at least 1.9× apart (about one per octave),
/// τ below 4τ0 (where sampling distorts every term) left out,
/// each with variance `2σ⁴/ν_i` (χ² with ν_i EDF) at the model σ²
/// (iterated), weighted by its inverse. Overlapping estimates at
/// neighbouring τ share data: their correlation is modelled as a Markov
/// chain in log₂ τ, `ρ_ij = Π_k ρ_k^{log₂(τ_{k+1}/τ_k)}` with the octave
/// correlation ρ_k of the noise type identified there, and the covariance
/// of the estimates is the sandwich `B V Bᵀ`, `B = (AᵀWA)⁻¹AᵀW`. Terms are kept non-negative by an active set
/// (the most negative term, in units of its u, leaves and the fit is
/// repeated). A term is identified when its square exceeds twice its
/// standard uncertainty; u of an amplitude A = √θ is `u(θ)/(2A)`. When the
/// residuals exceed the modelled scatter (generalized χ² above its dof), u grows by the
/// Birge ratio with n − p degrees of freedom.
pub fn fit_terms(
    taus: &[f64],
    oadev: &DevSeries,
    alpha: &[Option<i32>],
    tau0: f64,
) -> Result<TermFit> {
    let mut obs: Vec<(f64, f64, f64, Option<i32>)> = Vec::new();
    for (i, &t) in taus.iter().enumerate() {
        let (Some(s), Some(e)) = (oadev.value[i], oadev.edf[i]) else {
            continue;
        };
        // τ below 4τ0 is left out: sampling distorts the noise there (the
        // sampled flicker's Allan variance is 1.44× its continuous level at
        // τ0, 1.15× at 2τ0, 1.05× at 4τ0; anti-alias filters do the same).
        if t < 4.0 * tau0 - 1e-9 * tau0
            || !(s > 0.0 && e > 0.0)
            || obs.last().is_some_and(|o| t < 1.9 * o.0)
        {
            continue;
        }
        obs.push((t, s, e, alpha.get(i).copied().flatten()));
    }
    let nobs = obs.len();
    // Markov correlation in log2 τ.
    let mut corr = DMatrix::<f64>::identity(nobs, nobs);
    for i in 0..nobs {
        let mut r = 1.0;
        for j in i + 1..nobs {
            let (a, b) = (&obs[j - 1], &obs[j]);
            let rho = (octave_correlation(a.3) * octave_correlation(b.3)).sqrt();
            r *= rho.powf((b.0 / a.0).log2());
            corr[(i, j)] = r;
            corr[(j, i)] = r;
        }
    }
    let mut dropped: Vec<(usize, &str)> = Vec::new();
    // N, B and K first; Q and R join only when they come out significant
    // (a term fitted at zero truth would otherwise take part of the others).
    let mut best = fit_active(&obs, &corr, vec![1, 2, 3])?;
    for c in [0usize, 4] {
        let Some(cur) = &best else { break };
        let mut set = cur.active.clone();
        set.push(c);
        set.sort_unstable();
        let trial = fit_active(&obs, &corr, set)?;
        let keep = trial.as_ref().is_some_and(|t| {
            t.active.iter().position(|&j| j == c).is_some_and(|k| {
                let th = t.est.values()[k];
                th > 2.0 * t.est.u_at(k)
            }) && [1, 2, 3]
                .iter()
                .all(|j| !cur.active.contains(j) || t.active.contains(j))
        });
        if keep {
            best = trial;
        } else {
            dropped.push((c, "it does not come out significant beside the other terms"));
        }
    }
    let mut warnings = Vec::new();
    let Some(best) = best else {
        for j in 0..5 {
            warnings.push(not_identified(j, "too few averaging times"));
        }
        return Ok(TermFit {
            terms: [None; 5],
            squares: None,
            warnings,
            chi2: None,
        });
    };
    dropped.extend(best.dropped.iter().copied());
    let (est, chi2, active) = (best.est, (best.chi2, best.dof), best.active);
    let mut terms = [None; 5];
    for (k, &j) in active.iter().enumerate() {
        let th = est.values()[k];
        let u = est.u_at(k);
        if th > 2.0 * u && th > 0.0 {
            let a = th.sqrt();
            terms[j] = Some(Term {
                value: a,
                u: u / (2.0 * a),
                dof: est.dof(),
            });
        } else {
            dropped.push((j, "its fitted square is below twice its uncertainty"));
        }
    }
    dropped.sort_by_key(|d| d.0);
    for (j, why) in dropped {
        warnings.push(not_identified(j, why));
    }
    Ok(TermFit {
        terms,
        squares: Some(est),
        warnings,
        chi2: Some(chi2),
    })
}

fn not_identified(j: usize, why: &str) -> Warning {
    let name = [
        "quantization Q",
        "random walk N",
        "bias instability B",
        "rate random walk K",
        "rate ramp R",
    ][j];
    Warning::new(
        WarningCode::NoiseTermNotIdentified,
        format!("{name} not identified: {why}; not reported"),
    )
}

/// Slope-line readings of IEEE Std 952 Annex C (Figure C.2): the
/// asymptote of each term touches the σ(τ) curve from below, so each
/// reading is the minimum over τ of σ(τ) divided by its slope line:
/// `Q = min σ τ/√3`, `N = min σ √τ` (the −½ line read at τ = 1 s),
/// `B = min σ / 0.664` (the flat floor), `K = min σ √(3/τ)` (the +½ line
/// read at τ = 3 s), `R = min σ √2/τ`. Upper bounds of each term.
pub fn slope_readings(taus: &[f64], oadev: &DevSeries) -> [Option<f64>; 5] {
    let pts: Vec<(f64, f64)> = taus
        .iter()
        .zip(&oadev.value)
        .filter_map(|(&t, v)| Some((t, (*v)?)))
        .collect();
    let min = |f: &dyn Fn(f64, f64) -> f64| pts.iter().map(|&(t, s)| f(t, s)).reduce(f64::min);
    [
        min(&|t, s| s * t / 3f64.sqrt()),
        min(&|t, s| s * t.sqrt()),
        min(&|_, s| s / FLICKER.sqrt()),
        min(&|t, s| s * (3.0 / t).sqrt()),
        min(&|t, s| s * 2f64.sqrt() / t),
    ]
}

/// Bias stability (GJB 2426A / IEEE Std 1431): the sample standard
/// deviation of the means of consecutive non-overlapping windows of `τ`
/// seconds, from phase `x` at spacing τ0 (window means are
/// `(x_{(j+1)k} − x_{jk})/(kτ0)`, k = round(τ/τ0)), with
/// `u = s/√(2(n−1))` and n − 1 degrees of freedom. `None` with fewer than
/// two windows, or when the differences overflow.
pub fn bias_stability(x: &[f64], tau0: f64, tau: f64) -> Option<Term> {
    let k = (tau / tau0).round() as usize;
    if k == 0 {
        return None;
    }
    let n = (x.len() - 1) / k;
    if n < 2 {
        return None;
    }
    let kt = k as f64 * tau0;
    let means: Vec<f64> = (0..n).map(|j| (x[(j + 1) * k] - x[j * k]) / kt).collect();
    let mu = means.iter().sum::<f64>() / n as f64;
    let s = (means.iter().map(|m| (m - mu) * (m - mu)).sum::<f64>() / (n - 1) as f64).sqrt();
    // Samples near the f64 limit can overflow the differences: no number.
    s.is_finite().then_some(Term {
        value: s,
        u: s / (2.0 * (n - 1) as f64).sqrt(),
        dof: (n - 1) as f64,
    })
}

/// The Allan deviation of the fitted model minus the data, relative, at
/// each τ (for the report's fit lines); unused terms contribute nothing.
pub fn model_curve(fit: &TermFit, taus: &[f64]) -> Vec<f64> {
    taus.iter().map(|&t| fit.model(t)).collect()
}
