//! Weighted linear least squares with covariance and diagnostics: the one
//! solver every incal procedure uses (docs/src/result-document.md).
//!
//! # Model
//! `y = A x + e`, `E[e] = 0`, `Cov(e) = σ² W⁻¹` with `W = diag(w_i)`.
//!
//! # Solution
//! With `A_w = W^{1/2} A`, `y_w = W^{1/2} y` and the column equilibration
//! `D = diag(1/‖a_j‖)` (so that the rank and condition number do not depend
//! on the units of the parameters), the SVD `A_w D = U S Vᵀ` gives
//!
//! * `x̂ = D V S⁻¹ Uᵀ y_w`, the minimiser of `Σ w_i (y_i − a_iᵀx)²`;
//! * `(AᵀWA)⁻¹ = D V S⁻² Vᵀ D`;
//! * `C = s² (AᵀWA)⁻¹` with the variance factor `s²` chosen by
//!   [`Variance`];
//! * rank = number of singular values above `s_max / cond_limit`, and the
//!   condition number `κ = s_max / s_min` of the equilibrated design;
//! * for a rank-deficient design the null space `D V_null` names the
//!   unobservable term combinations ([`Alias`]).
//!
//! The SVD route is used because it never squares the condition number
//! (unlike the normal equations of Wu et al. 2015 eq. 9–10) and because the null
//! space comes for free. Reference: Björck, *Numerical Methods for Least
//! Squares Problems* (1996), §1.2 and §2.7.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use super::estimates::Estimates;
use crate::error::{Alias, Error, Result};
use crate::warning::{Warning, WarningCode};

/// Default limit on the equilibrated condition number: beyond it a design is
/// treated as rank deficient (10 of the 16 significant digits of f64 lost).
pub const DEFAULT_COND_LIMIT: f64 = 1e10;

/// Significance level of incal's one lack-of-fit rule: the weighted
/// residual sum against χ²_{n−p} at p < 0.05 (a) scales u by the residual
/// scatter under [`Variance::AtLeast`], (b) earns the `lack-of-fit`
/// warning ([`Fit::quality_warnings`]) and (c) is the condition for
/// estimating an excess variance component
/// ([`super::repeated::fit_means_excess`]). Below it the prior noise
/// stands, with no warning.
pub const LACK_OF_FIT_ALPHA: f64 = 0.05;

/// Condition number beyond which a separable design earns a warning.
pub const WARN_COND: f64 = 1e6;

/// A design matrix whose columns are named model terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Design {
    names: Vec<String>,
    matrix: DMatrix<f64>,
}

impl Design {
    /// Wrap a matrix (rows = observations, columns = terms).
    pub fn new(names: Vec<String>, matrix: DMatrix<f64>) -> Result<Self> {
        if names.len() != matrix.ncols() {
            return Err(Error::Unsupported(format!(
                "design has {} columns but {} names",
                matrix.ncols(),
                names.len()
            )));
        }
        if let Some(v) = matrix.iter().find(|v| !v.is_finite()) {
            return Err(Error::InvalidValue {
                what: "design-matrix entry".into(),
                value: v.to_string(),
            });
        }
        Ok(Self { names, matrix })
    }

    /// Build from rows of regressor values.
    pub fn from_rows(names: Vec<String>, rows: &[Vec<f64>]) -> Result<Self> {
        let p = names.len();
        if let Some(r) = rows.iter().find(|r| r.len() != p) {
            return Err(Error::Unsupported(format!(
                "design row has {} entries for {p} terms",
                r.len()
            )));
        }
        let m = DMatrix::from_fn(rows.len(), p, |i, j| rows[i][j]);
        Self::new(names, m)
    }

    /// Term names (columns).
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// The matrix `A`.
    pub fn matrix(&self) -> &DMatrix<f64> {
        &self.matrix
    }
    /// Number of observations (rows).
    pub fn nrows(&self) -> usize {
        self.matrix.nrows()
    }
    /// Number of terms (columns).
    pub fn ncols(&self) -> usize {
        self.matrix.ncols()
    }

    /// Rank, condition and aliasing of the design under `weights`
    /// (`None` = unit weights). Never fails.
    pub fn diagnose(&self, weights: Option<&DVector<f64>>, cond_limit: f64) -> Diagnostics {
        Decomposition::new(self, weights, cond_limit).diagnostics
    }

    /// Test design: the covariance `(AᵀWA)⁻¹` the plan will give, with
    /// `W = diag(1/σ_i²)`, before any data exists (docs/src/plans.md).
    ///
    /// `sigma` holds the standard deviation of each observation. Values are
    /// zero; only the covariance is meaningful. Fails like [`fit`] when the
    /// plan cannot separate the terms.
    pub fn predict(&self, sigma: &DVector<f64>) -> Result<Estimates> {
        if sigma.len() != self.nrows() {
            return Err(Error::Unsupported(format!(
                "{} standard deviations for {} observations",
                sigma.len(),
                self.nrows()
            )));
        }
        if let Some(s) = sigma.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
            return Err(Error::InvalidValue {
                what: "observation standard deviation".into(),
                value: s.to_string(),
            });
        }
        if self.ncols() == 0 {
            return Err(Error::TooFew {
                what: "terms in the model".into(),
                needed: 1,
                got: 0,
            });
        }
        let w = sigma.map(|s| 1.0 / (s * s));
        let dec = Decomposition::new(self, Some(&w), DEFAULT_COND_LIMIT);
        dec.require_separable(self)?;
        Estimates::new(
            self.names.clone(),
            DVector::zeros(self.ncols()),
            dec.unit_covariance(),
            f64::INFINITY,
        )
    }
}

/// Where the variance factor `s²` of the covariance comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Variance {
    /// Weights are relative; `s² = Σ w r² / (n − p)` from the residuals,
    /// with `n − p` degrees of freedom (needs `n > p`).
    FromResiduals,
    /// Weights are `1/σ_i²` of known standard deviations: `s² = 1`.
    /// `dof` is the degrees of freedom behind those σ (∞ if exact).
    Known {
        /// Degrees of freedom of the σ_i.
        dof: f64,
    },
    /// Weights are `1/σ_i²` from an independent estimate (e.g. the scatter
    /// of repeated samples) with `dof` degrees of freedom, and the residuals
    /// may reveal more: when they show lack of fit at the 5 % level
    /// (`P(χ²_{n−p} ≥ Σ w r²) < 0.05`) the variance factor becomes
    /// `s² = Σ w r² / (n − p)` with `n − p` degrees of freedom, else `s² = 1`.
    /// Significant lack of fit is never hidden, the σ_i are never made
    /// smaller, and chance excess in a few residual degrees of freedom does
    /// not throw away the much better-determined prior variance.
    AtLeast {
        /// Degrees of freedom of the σ_i.
        dof: f64,
    },
}

/// Options of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Observation weights `w_i` (`None` = all 1).
    pub weights: Option<DVector<f64>>,
    /// Source of the variance factor.
    pub variance: Variance,
    /// Equilibrated condition number beyond which the design is refused.
    pub cond_limit: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            weights: None,
            variance: Variance::FromResiduals,
            cond_limit: DEFAULT_COND_LIMIT,
        }
    }
}

/// Which source the variance factor finally came from.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum VarianceSource {
    /// Estimated from the residuals (`s² = χ²/(n−p)`).
    Residuals,
    /// Known or independently estimated σ (`s² = 1`).
    Prior,
}

/// Rank, conditioning and aliasing of a design.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostics {
    /// Observations.
    pub n_obs: usize,
    /// Terms.
    pub n_params: usize,
    /// Numerical rank.
    pub rank: usize,
    /// Condition number of the column-equilibrated weighted design
    /// (`f64::INFINITY` when rank deficient).
    pub condition: f64,
    /// Singular values of the equilibrated design, descending.
    pub singular_values: Vec<f64>,
    /// Unobservable combinations (empty when full rank).
    pub aliases: Vec<Alias>,
    /// The direction the design determines worst: terms and their weights
    /// in the last right-singular vector (largest magnitude 1).
    pub weakest: Alias,
}

impl Diagnostics {
    /// True when every term can be separated.
    pub fn is_separable(&self) -> bool {
        self.aliases.is_empty()
    }
}

/// Result of a least-squares fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// `x̂` with `C = s² (AᵀWA)⁻¹`.
    pub estimates: Estimates,
    /// Residuals `r = y − A x̂` (unweighted, in the units of `y`).
    pub residuals: DVector<f64>,
    /// Leverages `h_ii` (diagonal of the hat matrix).
    pub leverage: DVector<f64>,
    /// Degrees of freedom `n − p`.
    pub dof: usize,
    /// `Σ w_i r_i²` (χ² when the weights are inverse variances).
    pub weighted_rss: f64,
    /// Residual standard deviation of unit weight, `sqrt(Σ w r²/(n−p))`
    /// (NaN when `n = p`).
    pub sigma: f64,
    /// Variance factor `s²` applied to `(AᵀWA)⁻¹`.
    pub variance_factor: f64,
    /// Where `s²` came from.
    pub variance_source: VarianceSource,
    /// `P(χ²_{n−p} ≥ Σ w r²)`: the lack-of-fit test, meaningful only when
    /// the weights are inverse variances ([`Variance::Known`] or
    /// [`Variance::AtLeast`]).
    pub chi2_p_value: Option<f64>,
    /// Rank and conditioning.
    pub diagnostics: Diagnostics,
}

impl Fit {
    /// What an engineer must be told about this fit: a weakly conditioned
    /// plan (condition number above [`WARN_COND`], naming the worst-determined
    /// combination) and residuals beyond the prior noise (χ² p <
    /// [`LACK_OF_FIT_ALPHA`], the level that scales u), with
    /// `likely_causes` saying what the rig usually does to cause them.
    pub fn quality_warnings(&self, likely_causes: &str) -> Vec<Warning> {
        let mut out = Vec::new();
        if self.diagnostics.condition > WARN_COND {
            out.push(Warning::new(
                WarningCode::WeakConditioning,
                format!(
                    "weakly conditioned plan (condition number {:.2e}): the combination {} is poorly determined",
                    self.diagnostics.condition,
                    self.diagnostics.weakest.combination()
                ),
            ));
        }
        if let Some(p) = self.chi2_p_value.filter(|p| *p < LACK_OF_FIT_ALPHA) {
            let u = if self.variance_source == VarianceSource::Residuals {
                "uncertainties are scaled up by the residual scatter"
            } else {
                "uncertainties keep the stated noise"
            };
            out.push(Warning::new(
                WarningCode::LackOfFit,
                format!(
                    "residuals between positions exceed the sample scatter (chi-square p = {p:.2e}): {likely_causes}; {u}"
                ),
            ));
        }
        out
    }

    /// Standardized residuals `r_i √w_i / (s √(1 − h_ii))` (0 where `h_ii = 1`).
    pub fn standardized_residuals(&self, weights: Option<&DVector<f64>>) -> DVector<f64> {
        let s = self.variance_factor.sqrt();
        DVector::from_fn(self.residuals.len(), |i, _| {
            let w = weights.map_or(1.0, |w| w[i]);
            let d = s * (1.0 - self.leverage[i]).max(0.0).sqrt();
            if d > 0.0 {
                self.residuals[i] * w.sqrt() / d
            } else {
                0.0
            }
        })
    }
}

/// Weighted least squares `min Σ w_i (y_i − a_iᵀ x)²` (see module docs).
///
/// Refuses (with the names of the aliased terms) a design the plan cannot
/// separate; never solves a rank-deficient problem silently.
pub fn fit(design: &Design, y: &DVector<f64>, opts: &FitOptions) -> Result<Fit> {
    let (n, p) = (design.nrows(), design.ncols());
    if y.len() != n {
        return Err(Error::Unsupported(format!(
            "{} observations for a design of {n} rows",
            y.len()
        )));
    }
    if let Some(v) = y.iter().find(|v| !v.is_finite()) {
        return Err(Error::InvalidValue {
            what: "observation".into(),
            value: v.to_string(),
        });
    }
    if let Some(w) = &opts.weights {
        if w.len() != n {
            return Err(Error::Unsupported(format!(
                "{} weights for {n} observations",
                w.len()
            )));
        }
        if let Some(v) = w.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(Error::InvalidValue {
                what: "observation weight (1/variance: a zero, negative or non-finite noise level or sample scatter)".into(),
                value: v.to_string(),
            });
        }
    }
    if p == 0 {
        return Err(Error::TooFew {
            what: "terms in the model".into(),
            needed: 1,
            got: 0,
        });
    }
    if n < p {
        return Err(Error::TooFew {
            what: format!("observations for {p} terms"),
            needed: p,
            got: n,
        });
    }
    let needs_residual_dof = matches!(opts.variance, Variance::FromResiduals);
    if needs_residual_dof && n == p {
        return Err(Error::TooFew {
            what: format!(
                "observations to estimate the residual variance of {p} terms (add positions or give a noise level)"
            ),
            needed: p + 1,
            got: n,
        });
    }
    let dec = Decomposition::new(design, opts.weights.as_ref(), opts.cond_limit);
    dec.require_separable(design)?;

    let sqrt_w = opts
        .weights
        .as_ref()
        .map_or_else(|| DVector::from_element(n, 1.0), |w| w.map(f64::sqrt));
    let y_w = y.component_mul(&sqrt_w);
    // x̂ = D V S⁻¹ Uᵀ y_w
    let uty = dec.u.transpose() * &y_w;
    let z = DVector::from_fn(p, |k, _| uty[k] / dec.s[k]);
    let x = dec.d.component_mul(&(&dec.v * z));
    let residuals = y - design.matrix() * &x;
    let weighted_rss: f64 = residuals
        .iter()
        .zip(sqrt_w.iter())
        .map(|(r, sw)| (r * sw).powi(2))
        .sum();
    let dof = n - p;
    let sigma = if dof > 0 {
        (weighted_rss / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    let chi2_p_value = match opts.variance {
        Variance::Known { .. } | Variance::AtLeast { .. } if dof > 0 => ChiSquared::new(dof as f64)
            .ok()
            .map(|c| 1.0 - c.cdf(weighted_rss)),
        _ => None,
    };
    let (variance_factor, variance_source, est_dof) = match opts.variance {
        Variance::FromResiduals => (sigma * sigma, VarianceSource::Residuals, dof as f64),
        Variance::Known { dof: d } => (1.0, VarianceSource::Prior, d),
        Variance::AtLeast { dof: d } => {
            let lack_of_fit = chi2_p_value.is_some_and(|p| p < LACK_OF_FIT_ALPHA);
            if lack_of_fit {
                (
                    weighted_rss / dof as f64,
                    VarianceSource::Residuals,
                    dof as f64,
                )
            } else {
                (1.0, VarianceSource::Prior, d)
            }
        }
    };
    let leverage = DVector::from_fn(n, |i, _| dec.u.row(i).norm_squared());
    let estimates = Estimates::new(
        design.names().to_vec(),
        x,
        dec.unit_covariance() * variance_factor,
        est_dof,
    )?;
    Ok(Fit {
        estimates,
        residuals,
        leverage,
        dof,
        weighted_rss,
        sigma,
        variance_factor,
        variance_source,
        chi2_p_value,
        diagnostics: dec.diagnostics,
    })
}

/// The SVD of the weighted, column-equilibrated design.
struct Decomposition {
    /// Column scaling `D` (diagonal).
    d: DVector<f64>,
    u: DMatrix<f64>,
    s: DVector<f64>,
    v: DMatrix<f64>,
    diagnostics: Diagnostics,
}

impl Decomposition {
    fn new(design: &Design, weights: Option<&DVector<f64>>, cond_limit: f64) -> Self {
        let (n, p) = (design.nrows(), design.ncols());
        let mut a = design.matrix().clone();
        if let Some(w) = weights {
            for i in 0..n {
                let sw = w[i].sqrt();
                a.row_mut(i).scale_mut(sw);
            }
        }
        let mut d = DVector::from_element(p, 1.0);
        let mut zero_cols = Vec::new();
        // A column 1e-13 below the largest is zero up to rounding (e.g.
        // sin θ cos θ at θ = 90°): equilibration would otherwise blow the
        // rounding noise up into a seemingly independent regressor.
        let max_norm = (0..p).map(|j| a.column(j).norm()).fold(0.0, f64::max);
        for j in 0..p {
            let norm = a.column(j).norm();
            if norm > 1e-13 * max_norm {
                d[j] = 1.0 / norm;
                a.column_mut(j).scale_mut(d[j]);
            } else {
                zero_cols.push(j);
                a.column_mut(j).fill(0.0);
            }
        }
        // A wide design still gets a full p×p V so the null space is complete.
        let padded = if n < p {
            let mut m = DMatrix::zeros(p, p);
            m.view_mut((0, 0), (n, p)).copy_from(&a);
            m
        } else {
            a
        };
        let (u, s, v) = if p == 0 || n == 0 {
            // Nothing to decompose; every quantity below degenerates cleanly.
            (
                DMatrix::zeros(n, p),
                DVector::zeros(p),
                DMatrix::identity(p, p),
            )
        } else if let Some(svd) = super::bounded_svd(padded, true, true) {
            let s = svd.singular_values.clone();
            let u_full = svd.u.unwrap_or_else(|| DMatrix::zeros(n.max(p), p));
            let u = u_full.rows(0, n).into_owned();
            let v = svd
                .v_t
                .map(|vt| vt.transpose())
                .unwrap_or_else(|| DMatrix::identity(p, p));
            (u, s, v)
        } else {
            // Weights times design overflowed (both are checked finite):
            // no direction is resolved, so the fit is refused as
            // unseparable rather than solved with infinities.
            (
                DMatrix::zeros(n, p),
                DVector::zeros(p),
                DMatrix::identity(p, p),
            )
        };
        let s_max = s.iter().cloned().fold(0.0, f64::max);
        let tol = s_max / cond_limit;
        let rank = s.iter().filter(|&&x| x > tol && x > 0.0).count();
        let condition = if rank == p && p > 0 {
            s_max / s[p - 1]
        } else {
            f64::INFINITY
        };
        let names = design.names();
        let mut aliases: Vec<Alias> = zero_cols
            .iter()
            .map(|&j| Alias {
                terms: vec![names[j].clone()],
                coefficients: vec![1.0],
            })
            .collect();
        if rank < p {
            // Null-space basis in original column coordinates, made sparse by
            // reduced row echelon form so each alias names few terms.
            let k = p - rank;
            let mut basis = DMatrix::zeros(k, p);
            for (r, c) in (rank..p).enumerate() {
                for j in 0..p {
                    basis[(r, j)] = v[(j, c)] * d[j];
                }
            }
            for row in rref(basis).row_iter() {
                let alias = alias_from(names, row.transpose().as_slice(), 1e-6);
                let is_zero_col =
                    alias.terms.len() == 1 && zero_cols.iter().any(|&j| names[j] == alias.terms[0]);
                if !alias.terms.is_empty() && !is_zero_col {
                    aliases.push(alias);
                }
            }
        }
        let weakest_v: Vec<f64> = if p > 0 {
            (0..p).map(|j| v[(j, p - 1)] * d[j]).collect()
        } else {
            Vec::new()
        };
        let weakest = alias_from(names, &weakest_v, 0.1);
        let diagnostics = Diagnostics {
            n_obs: n,
            n_params: p,
            rank,
            condition,
            singular_values: s.iter().copied().collect(),
            aliases,
            weakest,
        };
        Self {
            d,
            u,
            s,
            v,
            diagnostics,
        }
    }

    fn require_separable(&self, design: &Design) -> Result<()> {
        if !self.diagnostics.aliases.is_empty() {
            return Err(Error::Unseparable {
                aliases: self.diagnostics.aliases.clone(),
            });
        }
        if self.diagnostics.rank < design.ncols() {
            return Err(Error::IllConditioned {
                terms: self.diagnostics.weakest.terms.join(", "),
                condition: self.diagnostics.condition,
                limit: DEFAULT_COND_LIMIT,
            });
        }
        Ok(())
    }

    /// `(AᵀWA)⁻¹ = D V S⁻² Vᵀ D`.
    fn unit_covariance(&self) -> DMatrix<f64> {
        let p = self.d.len();
        let mut vs = self.v.clone();
        for k in 0..p {
            let inv = 1.0 / self.s[k];
            vs.column_mut(k).scale_mut(inv);
        }
        let c = &vs * vs.transpose();
        let c = DMatrix::from_fn(p, p, |i, j| c[(i, j)] * self.d[i] * self.d[j]);
        (&c + c.transpose()) * 0.5
    }
}

/// Alias from coefficients: drop entries below `rel` of the largest, scale
/// the largest to ±1 (first nonzero positive).
fn alias_from(names: &[String], coef: &[f64], rel: f64) -> Alias {
    let max = coef.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if max == 0.0 {
        return Alias {
            terms: Vec::new(),
            coefficients: Vec::new(),
        };
    }
    let keep: Vec<usize> = (0..coef.len())
        .filter(|&j| coef[j].abs() >= rel * max)
        .collect();
    let sign = if coef[keep[0]] < 0.0 { -1.0 } else { 1.0 };
    Alias {
        terms: keep.iter().map(|&j| names[j].clone()).collect(),
        coefficients: keep.iter().map(|&j| sign * coef[j] / max).collect(),
    }
}

/// Reduced row echelon form with partial pivoting (rows = basis vectors).
fn rref(mut m: DMatrix<f64>) -> DMatrix<f64> {
    let (rows, cols) = m.shape();
    let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    let mut r = 0;
    for c in 0..cols {
        if r == rows {
            break;
        }
        let (piv, val) = (r..rows)
            .map(|i| (i, m[(i, c)].abs()))
            .fold((r, 0.0), |b, x| if x.1 > b.1 { x } else { b });
        if val <= tol {
            continue;
        }
        m.swap_rows(r, piv);
        let pv = m[(r, c)];
        m.row_mut(r).scale_mut(1.0 / pv);
        for i in 0..rows {
            if i != r {
                let f = m[(i, c)];
                if f != 0.0 {
                    for j in 0..cols {
                        let v = m[(r, j)];
                        m[(i, j)] -= f * v;
                    }
                }
            }
        }
        r += 1;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn straight_line_matches_closed_form() {
        // y = 1 + 2x on x = 0..4 with residuals ±0.1: closed-form regression.
        let xs = [0.0, 1.0, 2.0, 3.0, 4.0];
        let ys = [1.1, 2.9, 5.1, 6.9, 9.1];
        let rows: Vec<Vec<f64>> = xs.iter().map(|x| vec![1.0, *x]).collect();
        let d = Design::from_rows(names(&["a", "b"]), &rows).unwrap();
        let f = fit(&d, &DVector::from_row_slice(&ys), &FitOptions::default()).unwrap();
        let xm = 2.0;
        let ym = ys.iter().sum::<f64>() / 5.0;
        let sxx: f64 = xs.iter().map(|x| (x - xm).powi(2)).sum();
        let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - xm) * (y - ym)).sum();
        let b = sxy / sxx;
        let a = ym - b * xm;
        let rss: f64 = xs
            .iter()
            .zip(ys)
            .map(|(x, y)| (y - a - b * x).powi(2))
            .sum();
        let s2 = rss / 3.0;
        assert!((f.estimates.value("b").unwrap() - b).abs() < 1e-12);
        assert!((f.estimates.value("a").unwrap() - a).abs() < 1e-12);
        assert!((f.estimates.u("b").unwrap() - (s2 / sxx).sqrt()).abs() < 1e-12);
        let ua = (s2 * (1.0 / 5.0 + xm * xm / sxx)).sqrt();
        assert!((f.estimates.u("a").unwrap() - ua).abs() < 1e-12);
        assert_eq!(f.dof, 3);
        assert!((f.leverage.sum() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn aliased_columns_are_named() {
        // columns 1, s², c² with s² + c² = 1: K0 − K2 − Kpp is unobservable.
        let rows: Vec<Vec<f64>> = (0..12)
            .map(|k| {
                let t = (k as f64 * 30.0).to_radians();
                vec![1.0, t.sin(), t.sin().powi(2), t.cos().powi(2)]
            })
            .collect();
        let d = Design::from_rows(names(&["K0", "K1", "K2", "K_pp"]), &rows).unwrap();
        let y = DVector::from_element(12, 1.0);
        let err = fit(&d, &y, &FitOptions::default()).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("K0") && msg.contains("K2") && msg.contains("K_pp"),
            "{msg}"
        );
        assert!(!msg.contains("K1"), "{msg}");
        match err {
            Error::Unseparable { aliases } => {
                assert_eq!(aliases.len(), 1);
                assert_eq!(aliases[0].coefficients.len(), 3);
            }
            e => panic!("wrong error {e:?}"),
        }
    }

    #[test]
    fn zero_column_is_named() {
        // sin θ cos θ at 0/90/180/270° is zero only up to rounding (6e-17).
        let rows: Vec<Vec<f64>> = [0.0f64, 90.0, 180.0, 270.0, 0.0, 90.0]
            .iter()
            .map(|d| {
                let t = d.to_radians();
                vec![1.0, t.sin(), t.sin() * t.cos()]
            })
            .collect();
        let d = Design::from_rows(names(&["K0", "K1", "K_ip"]), &rows).unwrap();
        let diag = d.diagnose(None, DEFAULT_COND_LIMIT);
        assert_eq!(diag.aliases.len(), 1);
        assert_eq!(diag.aliases[0].terms, vec!["K_ip".to_string()]);
    }

    #[test]
    fn known_variance_and_prediction_agree() {
        let rows: Vec<Vec<f64>> = (0..10).map(|k| vec![1.0, k as f64]).collect();
        let d = Design::from_rows(names(&["a", "b"]), &rows).unwrap();
        let sigma = DVector::from_element(10, 0.5);
        let pred = d.predict(&sigma).unwrap();
        let opts = FitOptions {
            weights: Some(sigma.map(|s| 1.0 / (s * s))),
            variance: Variance::Known { dof: f64::INFINITY },
            ..FitOptions::default()
        };
        let y = DVector::from_fn(10, |k, _| {
            3.0 + 0.5 * k as f64 + if k % 2 == 0 { 0.3 } else { -0.3 }
        });
        let f = fit(&d, &y, &opts).unwrap();
        assert!((pred.u("b").unwrap() - f.estimates.u("b").unwrap()).abs() < 1e-14);
        assert!(f.chi2_p_value.is_some());
    }

    #[test]
    fn one_rule_scales_u_and_warns_at_the_same_level() {
        // Residuals swept from well inside to well beyond the prior noise:
        // u is scaled exactly when the lack-of-fit warning is given, and
        // both happen between p = 0.01 and 0.05 (the old warning level).
        let rows: Vec<Vec<f64>> = (0..8).map(|k| vec![1.0, k as f64]).collect();
        let d = Design::from_rows(names(&["a", "b"]), &rows).unwrap();
        let w = DVector::from_element(8, 1.0);
        let mut between = 0;
        for step in 0..60 {
            let e = 0.2 + 0.05 * step as f64;
            let y = DVector::from_fn(8, |k, _| 1.0 + k as f64 + if k % 2 == 0 { e } else { -e });
            let f = fit(
                &d,
                &y,
                &FitOptions {
                    weights: Some(w.clone()),
                    variance: Variance::AtLeast { dof: 100.0 },
                    ..FitOptions::default()
                },
            )
            .unwrap();
            let p = f.chi2_p_value.unwrap();
            let scaled = f.variance_source == VarianceSource::Residuals;
            let warned = f
                .quality_warnings("test")
                .iter()
                .any(|w| w.code == WarningCode::LackOfFit);
            assert_eq!(scaled, warned, "p = {p}");
            assert_eq!(scaled, p < LACK_OF_FIT_ALPHA, "p = {p}");
            if (0.01..0.05).contains(&p) {
                assert!(scaled && warned, "p = {p}");
                between += 1;
            }
        }
        assert!(between > 0);
    }

    #[test]
    fn at_least_never_shrinks_prior() {
        let rows: Vec<Vec<f64>> = (0..8).map(|k| vec![1.0, k as f64]).collect();
        let d = Design::from_rows(names(&["a", "b"]), &rows).unwrap();
        let y = DVector::from_fn(8, |k, _| {
            1.0 + k as f64 + if k % 2 == 0 { 1.0 } else { -1.0 }
        });
        let w = DVector::from_element(8, 1.0 / 0.01); // σ = 0.1, residuals ±1: lack of fit
        let f = fit(
            &d,
            &y,
            &FitOptions {
                weights: Some(w.clone()),
                variance: Variance::AtLeast { dof: 100.0 },
                ..FitOptions::default()
            },
        )
        .unwrap();
        assert_eq!(f.variance_source, VarianceSource::Residuals);
        assert!(f.variance_factor > 1.0);
        assert_eq!(f.estimates.dof(), 6.0);
        assert!(f.chi2_p_value.unwrap() < 1e-6);
    }

    #[test]
    fn empty_designs_are_refused_not_panicking() {
        let d = Design::new(Vec::new(), DMatrix::zeros(3, 0)).unwrap();
        assert!(fit(&d, &DVector::zeros(3), &FitOptions::default()).is_err());
        assert!(d.predict(&DVector::from_element(3, 1.0)).is_err());
        let e = Design::new(names(&["a"]), DMatrix::zeros(0, 1)).unwrap();
        assert_eq!(e.diagnose(None, DEFAULT_COND_LIMIT).rank, 0);
        assert!(fit(&e, &DVector::zeros(0), &FitOptions::default()).is_err());
    }

    #[test]
    fn chance_excess_keeps_the_prior() {
        // 4 points, 3 terms: 1 residual dof. χ² = 2 < 3.84 (5 % point of χ²₁):
        // the prior σ and its 50 dof stand.
        let rows: Vec<Vec<f64>> = (0..4)
            .map(|k| vec![1.0, k as f64, (k * k) as f64])
            .collect();
        let d = Design::from_rows(names(&["a", "b", "c"]), &rows).unwrap();
        // Residual pattern of a 1-dof quadratic fit is ∝ (1, −3, 3, −1)/√20.
        let amp = 2f64.sqrt();
        let y = DVector::from_fn(4, |k, _| [1.0, -3.0, 3.0, -1.0][k] * amp / 20f64.sqrt());
        let f = fit(
            &d,
            &y,
            &FitOptions {
                weights: Some(DVector::from_element(4, 1.0)),
                variance: Variance::AtLeast { dof: 50.0 },
                ..FitOptions::default()
            },
        )
        .unwrap();
        assert!((f.weighted_rss - 2.0).abs() < 1e-12);
        assert_eq!(f.variance_source, VarianceSource::Prior);
        assert_eq!(f.variance_factor, 1.0);
        assert_eq!(f.estimates.dof(), 50.0);
    }

    #[test]
    fn too_few_is_refused() {
        let d = Design::from_rows(names(&["a", "b"]), &[vec![1.0, 0.0]]).unwrap();
        let e = fit(&d, &DVector::from_element(1, 1.0), &FitOptions::default()).unwrap_err();
        assert!(matches!(e, Error::TooFew { .. }));
    }
}
