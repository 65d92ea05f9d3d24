//! Repeated samples at one test position, and the fit of their means.
//!
//! Every rig here records several samples per steady position. The fit uses
//! the position means `ȳ_i` (n_i samples each) with weights `n_i / s²`,
//! where `s²` is the pooled within-position variance
//! `s² = Σ_i Σ_k (y_ik − ȳ_i)² / Σ_i (n_i − 1)` (ν = Σ(n_i − 1) degrees of
//! freedom). Because position-level errors (index angle, drift, re-mounting)
//! do not average down with more samples, the residuals between positions
//! are tested against that scatter (χ², 5 % level) and, when they show lack
//! of fit, the variance factor becomes `χ²/(n−p)` ([`Variance::AtLeast`]):
//! the residuals can only raise the uncertainty, never hide behind the
//! sample scatter. With a single sample per position the residual scatter alone is
//! used (ν = n − p).
//!
//! # Excess variance with a known shape
//! Some position-level errors have a known shape: a dividing-head index
//! error ε shifts the output by `∂E/∂θ · ε`, so it adds `τ² g_i²` with
//! `g_i = ∂E/∂θ(θ_i)` to the variance of position i. [`fit_means_excess`]
//! estimates `τ²` by the Paule–Mandel moment equation
//! `Σ r_i² / (b_i + τ² g_i²) = n − p` (Paule & Mandel, J. Res. NBS 87
//! (1982) 377; the estimator of interlaboratory key comparisons), where
//! `b_i` is the sample-scatter variance of mean i and the residuals `r_i`
//! come from the weighted fit at that `τ²`. The excess is estimated only
//! when the fit at `τ² = 0` fails the lack-of-fit test at
//! [`LACK_OF_FIT_ALPHA`] (`P(χ²_{n−p} ≥ χ²(0)) < 0.05`); otherwise `τ² = 0`
//! and the fit is that of [`fit_means`].

use nalgebra::DVector;

use super::linear::{fit, Design, Fit, FitOptions, Variance, LACK_OF_FIT_ALPHA};
use crate::error::{Error, Result};

/// Summary of the samples taken at one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionStats {
    /// Number of samples.
    pub n: usize,
    /// Sample mean.
    pub mean: f64,
    /// Sample standard deviation (NaN when `n = 1`).
    pub std: f64,
}

impl PositionStats {
    /// Mean and standard deviation of `samples` (must be non-empty).
    pub fn of(samples: &[f64]) -> Result<PositionStats> {
        let n = samples.len();
        if n == 0 {
            return Err(Error::TooFew {
                what: "samples at a position".into(),
                needed: 1,
                got: 0,
            });
        }
        let mean = samples.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (samples.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            f64::NAN
        };
        Ok(PositionStats { n, mean, std })
    }
}

/// How the noise of one sample is known.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Noise {
    /// From the pooled scatter of repeated samples when there is any, else
    /// from the residuals; never below what the residuals show.
    #[default]
    Auto,
    /// Standard deviation of one sample, known beforehand (output units);
    /// still never below what the residuals show.
    Known {
        /// σ of one sample.
        sigma: f64,
    },
}

impl Noise {
    /// Known noise from an option: `None` (from the data) or σ of one
    /// sample, which must be a positive finite number.
    pub fn from_option(sigma: Option<f64>) -> Result<Noise> {
        let n = match sigma {
            None => Noise::Auto,
            Some(sigma) => Noise::Known { sigma },
        };
        n.validate()?;
        Ok(n)
    }

    /// σ of one sample when known.
    pub fn sigma(self) -> Option<f64> {
        match self {
            Noise::Auto => None,
            Noise::Known { sigma } => Some(sigma),
        }
    }

    /// Refuse a known σ that is not a positive finite number.
    pub fn validate(self) -> Result<()> {
        match self {
            Noise::Auto => Ok(()),
            Noise::Known { sigma } if sigma.is_finite() && sigma > 0.0 => Ok(()),
            Noise::Known { sigma } => crate::options::invalid(
                "noise",
                format!(
                    "the standard deviation of one output sample must be a positive number, got {}",
                    crate::error::short_number(&sigma.to_string())
                ),
            ),
        }
    }
}

/// `σ²` of a known noise level, refusing a non-positive or non-finite σ.
fn known_variance(sigma: f64) -> Result<f64> {
    if sigma.is_finite() && sigma > 0.0 {
        Ok(sigma * sigma)
    } else {
        Err(Error::InvalidValue {
            what: "noise sigma".into(),
            value: sigma.to_string(),
        })
    }
}

/// Pooled within-position variance and its degrees of freedom.
pub fn pooled_variance(positions: &[PositionStats]) -> (f64, usize) {
    let dof: usize = positions.iter().map(|p| p.n.saturating_sub(1)).sum();
    if dof == 0 {
        return (f64::NAN, 0);
    }
    let ss: f64 = positions
        .iter()
        .filter(|p| p.n > 1)
        .map(|p| p.std * p.std * (p.n - 1) as f64)
        .sum();
    (ss / dof as f64, dof)
}

/// Fit the position means with the noise policy of the module docs.
/// Returns the fit and the weights used (for standardized residuals).
pub fn fit_means(
    design: &Design,
    positions: &[PositionStats],
    noise: Noise,
) -> Result<(Fit, DVector<f64>)> {
    let y = DVector::from_iterator(positions.len(), positions.iter().map(|p| p.mean));
    let counts = DVector::from_iterator(positions.len(), positions.iter().map(|p| p.n as f64));
    let (weights, variance) = match noise {
        Noise::Known { sigma } => (
            counts / known_variance(sigma)?,
            Variance::AtLeast { dof: f64::INFINITY },
        ),
        Noise::Auto => {
            let (s2, dof) = pooled_variance(positions);
            if dof > 0 && s2 > 0.0 {
                (counts / s2, Variance::AtLeast { dof: dof as f64 })
            } else {
                (counts, Variance::FromResiduals)
            }
        }
    };
    let opts = FitOptions {
        weights: Some(weights.clone()),
        variance,
        ..FitOptions::default()
    };
    Ok((fit(design, &y, &opts)?, weights))
}

/// `Σ w_i r_i²` of the weighted least-squares fit of `y` on `design`
/// (Householder QR of `√W A`, residual `√W y − Q Qᵀ √W y`); `None` when the
/// weighted design is not of full column rank or a value is not finite
/// (the caller then runs the full fit, which says why).
fn weighted_rss(design: &Design, y: &DVector<f64>, w: &DVector<f64>) -> Option<f64> {
    let a = design.matrix();
    let (n, p) = (a.nrows(), a.ncols());
    if n < p || w.len() != n || y.len() != n {
        return None;
    }
    let sw = w.map(f64::sqrt);
    let aw = nalgebra::DMatrix::from_fn(n, p, |i, j| a[(i, j)] * sw[i]);
    let yw = y.component_mul(&sw);
    let qr = aw.qr();
    let r = qr.r();
    let scale = r.diagonal().amax();
    if !(scale > 0.0 && scale.is_finite()) || r.diagonal().iter().any(|d| d.abs() <= 1e-12 * scale)
    {
        return None;
    }
    let q = qr.q();
    let resid = &yw - &q * (q.transpose() * &yw);
    let out = resid.norm_squared();
    out.is_finite().then_some(out)
}

/// The effective degrees of freedom of a fit whose position variances are
/// `b_i + τ² g_i²`, `b` with `ν_b` and `τ²` with `ν_τ` degrees of freedom
/// (JCGM 100:2008 G.4.1, Welch–Satterthwaite): with `H = C AᵀW` (`C` the
/// fit's unit covariance), coefficient `k`'s variance splits into
/// `V_b = Σ H_ki² b_i` and `V_τ = τ² Σ H_ki² g_i²`, and
/// `ν_k = (V_b + V_τ)² / (V_b²/ν_b + V_τ²/ν_τ)`; the least `ν_k` is
/// returned (one dof serves every coefficient; at least the smaller of
/// `ν_b` and `ν_τ`), truncated to an integer as G.4.1 says.
#[allow(clippy::too_many_arguments)]
fn welch_satterthwaite_dof(
    design: &Design,
    fit: &Fit,
    w: &DVector<f64>,
    base: &DVector<f64>,
    base_dof: f64,
    tau2: f64,
    g2: &DVector<f64>,
    tau_dof: f64,
) -> f64 {
    let a = design.matrix();
    let c = fit.estimates.covariance();
    let mut least = f64::INFINITY;
    for k in 0..a.ncols() {
        let (mut vb, mut vt) = (0.0, 0.0);
        for i in 0..a.nrows() {
            let h: f64 = (0..a.ncols()).map(|j| c[(k, j)] * a[(i, j)]).sum::<f64>() * w[i];
            vb += h * h * base[i];
            vt += h * h * tau2 * g2[i];
        }
        let denom = vb * vb / base_dof + vt * vt / tau_dof;
        let nu = (vb + vt).powi(2) / denom;
        if nu.is_nan() {
            return tau_dof;
        }
        if denom > 0.0 {
            least = least.min(nu);
        }
    }
    // JCGM 100 G.4.1: a fractional ν_eff is truncated to the next lower
    // integer.
    if least.is_finite() {
        least.floor().max(1.0)
    } else {
        least
    }
}

/// A fit of position means with an estimated excess variance.
#[derive(Debug, Clone, PartialEq)]
pub struct ExcessFit {
    /// The final weighted fit.
    pub fit: Fit,
    /// Weights `1/(b_i + τ² g_i²)` used.
    pub weights: DVector<f64>,
    /// Estimated `τ²` (0 when the residuals show no excess; `None` when it
    /// could not be estimated: a single sample per position and no known
    /// noise, where the residual scatter alone is used).
    pub excess_variance: Option<f64>,
}

/// Fit position means with variances `b_i + τ² g_i²`, `τ²` estimated by
/// Paule–Mandel (module docs). `shape` holds `g_i`.
pub fn fit_means_excess(
    design: &Design,
    positions: &[PositionStats],
    noise: Noise,
    shape: &DVector<f64>,
) -> Result<ExcessFit> {
    let n = positions.len();
    if shape.len() != n || shape.iter().any(|g| !g.is_finite()) {
        return Err(Error::Unsupported(
            "excess-variance shape must have one finite entry per position".into(),
        ));
    }
    let counts = DVector::from_iterator(n, positions.iter().map(|p| p.n as f64));
    let (base, base_dof) = match noise {
        Noise::Known { sigma } => {
            let s2 = known_variance(sigma)?;
            (counts.map(|c| s2 / c), f64::INFINITY)
        }
        Noise::Auto => {
            let (s2, dof) = pooled_variance(positions);
            if !(dof > 0 && s2 > 0.0) {
                let (fit, weights) = fit_means(design, positions, noise)?;
                return Ok(ExcessFit {
                    fit,
                    weights,
                    excess_variance: None,
                });
            }
            (counts.map(|c| s2 / c), dof as f64)
        }
    };
    let y = DVector::from_iterator(n, positions.iter().map(|p| p.mean));
    let g2 = shape.map(|g| g * g);
    let p = design.ncols();
    let dof = n.saturating_sub(p) as f64;
    let run = |tau2: f64, variance: Variance| -> Result<(Fit, DVector<f64>)> {
        let w = DVector::from_fn(n, |i, _| 1.0 / (base[i] + tau2 * g2[i]));
        let opts = FitOptions {
            weights: Some(w.clone()),
            variance,
            ..FitOptions::default()
        };
        Ok((fit(design, &y, &opts)?, w))
    };
    let known = Variance::Known { dof: base_dof };
    let (f0, _) = run(0.0, known)?;
    let g2_max = g2.max();
    let mut tau2 = 0.0;
    // One rule with the lack-of-fit test: τ² is estimated only when the
    // prior noise fails it at LACK_OF_FIT_ALPHA (χ²(0) beyond n − p alone
    // is chance half the time).
    let excess = f0.chi2_p_value.is_some_and(|p| p < LACK_OF_FIT_ALPHA);
    if dof > 0.0 && excess && g2_max > 0.0 {
        // χ²(τ²) decreases with τ²: bracket, then bisect on log scale.
        let b_max = base.max();
        let cap = 1e8 * b_max / g2_max;
        // The bracket and the bisection need χ² only: a QR solve each
        // (the full fit, with its decomposition and diagnostics, once at
        // the end).
        let rss = |tau2: f64| -> Result<f64> {
            let w = DVector::from_fn(n, |i, _| 1.0 / (base[i] + tau2 * g2[i]));
            match weighted_rss(design, &y, &w) {
                Some(r) => Ok(r),
                None => Ok(run(tau2, known)?.0.weighted_rss),
            }
        };
        let mut hi = b_max / g2_max;
        while hi < cap && rss(hi)? > dof {
            hi *= 4.0;
        }
        let mut lo = 0.0;
        for _ in 0..200 {
            let mid = if lo > 0.0 { (lo * hi).sqrt() } else { hi / 1e6 };
            if rss(mid)? > dof {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-10 * hi {
                break;
            }
        }
        tau2 = hi;
    }
    // τ² estimated from the between-position residuals has n − p degrees
    // of freedom, the noise its own: each coefficient's variance combines
    // the two by Welch–Satterthwaite, the least over the coefficients
    // kept (AtLeast keeps any excess the shape does not explain).
    let final_dof = if tau2 > 0.0 {
        let (f, w) = run(tau2, known)?;
        welch_satterthwaite_dof(design, &f, &w, &base, base_dof, tau2, &g2, dof)
    } else {
        base_dof
    };
    let (fit, weights) = run(tau2, Variance::AtLeast { dof: final_dof })?;
    Ok(ExcessFit {
        fit,
        weights,
        excess_variance: Some(tau2),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn excess_variance_only_when_the_lack_of_fit_test_fails() {
        // 12 positions, a line (dof 10), σ = 1 per sample, 1 sample each:
        // the scatter of the means swept up from the prior. τ² > 0 exactly
        // when the fit at τ² = 0 fails the 5 % χ² test, never merely when
        // χ²(0) > n − p.
        let rows: Vec<Vec<f64>> = (0..12).map(|k| vec![1.0, k as f64]).collect();
        let d = Design::from_rows(vec!["a".into(), "b".into()], &rows).unwrap();
        let shape = DVector::from_element(12, 1.0);
        let mut chance_excess = 0;
        for step in 0..40 {
            let e = 0.7 + 0.05 * step as f64;
            let positions: Vec<PositionStats> = (0..12)
                .map(|k| PositionStats {
                    n: 1,
                    mean: 2.0 + 0.5 * k as f64 + if k % 2 == 0 { e } else { -e },
                    std: f64::NAN,
                })
                .collect();
            let f0 = fit_means(&d, &positions, Noise::Known { sigma: 1.0 })
                .unwrap()
                .0;
            let p = f0.chi2_p_value.unwrap();
            let ex = fit_means_excess(&d, &positions, Noise::Known { sigma: 1.0 }, &shape).unwrap();
            let tau2 = ex.excess_variance.unwrap();
            assert_eq!(
                tau2 > 0.0,
                p < LACK_OF_FIT_ALPHA,
                "e = {e}, p = {p}, τ² = {tau2}"
            );
            if f0.weighted_rss > 10.0 && p >= LACK_OF_FIT_ALPHA {
                chance_excess += 1;
            }
        }
        assert!(
            chance_excess > 0,
            "the sweep must cross χ² = n − p below the 5 % level"
        );
    }

    /// The fit's dof after an excess: about `n − p` when the excess
    /// dominates, the noise's own (`Σ(n_j − 1)`, large) when it is a small
    /// share, and in between otherwise (JCGM 100 G.4.1).
    #[test]
    fn excess_dof_combines_the_two_components() {
        let rows: Vec<Vec<f64>> = (0..12).map(|k| vec![1.0, k as f64]).collect();
        let d = Design::from_rows(vec!["a".into(), "b".into()], &rows).unwrap();
        let shape = DVector::from_element(12, 1.0);
        let dof_at = |e: f64| {
            // 20 samples per position with scatter 1: noise dof 228.
            let positions: Vec<PositionStats> = (0..12)
                .map(|k| PositionStats {
                    n: 20,
                    mean: 0.5 * k as f64 + if k % 2 == 0 { e } else { -e },
                    std: 1.0,
                })
                .collect();
            let ex = fit_means_excess(&d, &positions, Noise::Auto, &shape).unwrap();
            assert!(ex.excess_variance.unwrap() > 0.0, "e = {e}");
            ex.fit.estimates.dof()
        };
        let (small, large) = (dof_at(0.3), dof_at(5.0));
        assert!((10.0..=11.0).contains(&large), "{large}");
        assert!(small > 20.0 && small < 228.0, "{small}");
        assert_eq!(small, small.floor());
    }
}
