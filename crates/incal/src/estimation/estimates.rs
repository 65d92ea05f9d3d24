//! Named estimates with a covariance matrix, and their propagation through
//! a map to derived quantities (GUM linear propagation, JCGM 100 §5.2).

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

use crate::error::{Error, Result};

/// A vector of named estimates `x̂` with covariance `C` and the effective
/// degrees of freedom `ν` of the variance estimate behind `C`
/// (`f64::INFINITY` when the variance was known a priori).
#[derive(Debug, Clone, PartialEq)]
pub struct Estimates {
    names: Vec<String>,
    values: DVector<f64>,
    covariance: DMatrix<f64>,
    dof: f64,
}

impl Estimates {
    /// Build from names, values, covariance and degrees of freedom.
    ///
    /// Fails when the dimensions disagree or a value is not finite.
    pub fn new(
        names: Vec<String>,
        values: DVector<f64>,
        covariance: DMatrix<f64>,
        dof: f64,
    ) -> Result<Self> {
        let n = names.len();
        if values.len() != n || covariance.nrows() != n || covariance.ncols() != n {
            return Err(Error::Unsupported(format!(
                "estimates: {n} names, {} values, {}x{} covariance",
                values.len(),
                covariance.nrows(),
                covariance.ncols()
            )));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::InvalidValue {
                what: format!("estimate of {}", names[k]),
                value: values[k].to_string(),
            });
        }
        Ok(Self {
            names,
            values,
            covariance,
            dof,
        })
    }

    /// Parameter names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// Estimated values `x̂`.
    pub fn values(&self) -> &DVector<f64> {
        &self.values
    }
    /// Covariance matrix `C` of the estimates.
    pub fn covariance(&self) -> &DMatrix<f64> {
        &self.covariance
    }
    /// Effective degrees of freedom of the variance estimate.
    pub fn dof(&self) -> f64 {
        self.dof
    }
    /// Number of estimates.
    pub fn len(&self) -> usize {
        self.names.len()
    }
    /// True when there are no estimates.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }
    /// Position of `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }
    /// Value of `name`.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.index(name).map(|k| self.values[k])
    }
    /// Standard uncertainty `u = sqrt(C_kk)` of `name`.
    pub fn u(&self, name: &str) -> Option<f64> {
        self.index(name).map(|k| self.u_at(k))
    }
    /// Standard uncertainty of the `k`-th estimate.
    pub fn u_at(&self, k: usize) -> f64 {
        self.covariance[(k, k)].max(0.0).sqrt()
    }
    /// `(value, u)` of `name`.
    pub fn get(&self, name: &str) -> Option<(f64, f64)> {
        self.index(name).map(|k| (self.values[k], self.u_at(k)))
    }

    /// Correlation matrix `ρ_jk = C_jk / (u_j u_k)` (0 where a `u` is 0).
    pub fn correlation(&self) -> DMatrix<f64> {
        let n = self.len();
        DMatrix::from_fn(n, n, |j, k| {
            let d = self.u_at(j) * self.u_at(k);
            if d > 0.0 {
                self.covariance[(j, k)] / d
            } else if j == k {
                1.0
            } else {
                0.0
            }
        })
    }

    /// Coverage factor `k_p` for a two-sided coverage probability `p`:
    /// the Student-t quantile `t_{(1+p)/2, ν}` (normal quantile when ν = ∞),
    /// JCGM 100 Annex G.
    pub fn coverage_factor(&self, p: f64) -> f64 {
        coverage_factor(self.dof, p)
    }

    /// The sub-vector of the named estimates (with their covariance block).
    pub fn select(&self, names: &[&str]) -> Result<Estimates> {
        let idx: Vec<usize> = names
            .iter()
            .map(|n| {
                self.index(n)
                    .ok_or_else(|| Error::Unsupported(format!("no estimate named {n}")))
            })
            .collect::<Result<_>>()?;
        let values = DVector::from_iterator(idx.len(), idx.iter().map(|&k| self.values[k]));
        let cov = DMatrix::from_fn(idx.len(), idx.len(), |a, b| {
            self.covariance[(idx[a], idx[b])]
        });
        Estimates::new(
            names.iter().map(|s| s.to_string()).collect(),
            values,
            cov,
            self.dof,
        )
    }

    /// Propagate through `y = f(x)` with Jacobian `J = ∂f/∂x` at `x̂`:
    /// `ŷ = f(x̂)`, `C_y = J C Jᵀ` (GUM first-order propagation).
    pub fn map(
        &self,
        names: Vec<String>,
        f: impl Fn(&DVector<f64>) -> DVector<f64>,
        jacobian: impl Fn(&DVector<f64>) -> DMatrix<f64>,
    ) -> Result<Estimates> {
        let y = f(&self.values);
        let j = jacobian(&self.values);
        if j.nrows() != y.len() || j.ncols() != self.len() {
            return Err(Error::Unsupported(format!(
                "Jacobian is {}x{}, expected {}x{}",
                j.nrows(),
                j.ncols(),
                y.len(),
                self.len()
            )));
        }
        Estimates::new(names, y, propagate(&self.covariance, &j), self.dof)
    }

    /// Append derived quantities `g(x̂)` to the estimates, with the full
    /// joint covariance: `[x̂; g(x̂)]` with Jacobian `[I; J_g]`, so the new
    /// entries keep their correlation with the old ones (GUM, JCGM 100
    /// §5.2). `jacobian` is `∂g/∂x` (rows: new names).
    pub fn augment(
        &self,
        names: Vec<String>,
        g: impl Fn(&DVector<f64>) -> DVector<f64>,
        jacobian: impl Fn(&DVector<f64>) -> DMatrix<f64>,
    ) -> Result<Estimates> {
        let (n, m) = (self.len(), names.len());
        let mut all = self.names.clone();
        all.extend(names);
        self.map(
            all,
            |x| {
                let y = g(x);
                DVector::from_iterator(n + y.len(), x.iter().chain(y.iter()).copied())
            },
            |x| {
                let j = jacobian(x);
                let mut full = DMatrix::zeros(n + j.nrows(), n);
                full.view_mut((0, 0), (n, n)).fill_with_identity();
                if j.ncols() == n && j.nrows() == m {
                    full.view_mut((n, 0), (m, n)).copy_from(&j);
                }
                full
            },
        )
    }

    /// As [`Estimates::map`], with the Jacobian by central differences
    /// (step `h_k = 1e-6·max(|x_k|, u_k, 1e-12)`).
    pub fn map_numeric(
        &self,
        names: Vec<String>,
        f: impl Fn(&DVector<f64>) -> DVector<f64>,
    ) -> Result<Estimates> {
        let steps: Vec<f64> = (0..self.len())
            .map(|k| 1e-6 * self.values[k].abs().max(self.u_at(k)).max(1e-12))
            .collect();
        let j = numeric_jacobian(&f, &self.values, &steps);
        Estimates::new(
            names,
            f(&self.values),
            propagate(&self.covariance, &j),
            self.dof,
        )
    }
}

/// `J C Jᵀ`, symmetrised against rounding.
pub fn propagate(covariance: &DMatrix<f64>, jacobian: &DMatrix<f64>) -> DMatrix<f64> {
    let c = jacobian * covariance * jacobian.transpose();
    (&c + c.transpose()) * 0.5
}

/// Central-difference Jacobian of `f` at `x` with per-component steps.
pub fn numeric_jacobian(
    f: &impl Fn(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    steps: &[f64],
) -> DMatrix<f64> {
    let y0 = f(x);
    let mut j = DMatrix::zeros(y0.len(), x.len());
    for k in 0..x.len() {
        let mut xp = x.clone();
        let mut xm = x.clone();
        xp[k] += steps[k];
        xm[k] -= steps[k];
        let d = (f(&xp) - f(&xm)) / (2.0 * steps[k]);
        j.set_column(k, &d);
    }
    j
}

/// Two-sided coverage factor for probability `p` with `dof` degrees of
/// freedom: Student-t quantile, or the normal one for `dof = ∞` (or > 1e6).
pub fn coverage_factor(dof: f64, p: f64) -> f64 {
    let q = 0.5 * (1.0 + p);
    if dof.is_finite() && dof > 0.0 && dof < 1e6 {
        if let Ok(t) = StudentsT::new(0.0, 1.0, dof) {
            return t.inverse_cdf(q);
        }
    }
    match Normal::new(0.0, 1.0) {
        Ok(n) => n.inverse_cdf(q),
        Err(_) => 1.96,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_factors_match_tables() {
        // JCGM 100 Table G.2: t_95 for ν = 6 is 2.45, ν = 10: 2.23, ∞: 1.96.
        assert!((coverage_factor(6.0, 0.95) - 2.447).abs() < 1e-3);
        assert!((coverage_factor(10.0, 0.95) - 2.228).abs() < 1e-3);
        assert!((coverage_factor(f64::INFINITY, 0.95) - 1.960).abs() < 1e-3);
    }

    #[test]
    fn ratio_propagation_matches_analytic() {
        // y = x0/x1: u²(y) = (u0/x1)² + (x0 u1/x1²)² for independent inputs.
        let e = Estimates::new(
            vec!["a".into(), "b".into()],
            DVector::from_vec(vec![2.0, 4.0]),
            DMatrix::from_diagonal(&DVector::from_vec(vec![0.01, 0.04])),
            f64::INFINITY,
        )
        .unwrap();
        let y = e
            .map_numeric(vec!["r".into()], |x| DVector::from_vec(vec![x[0] / x[1]]))
            .unwrap();
        let expect = ((0.1f64 / 4.0).powi(2) + (2.0 * 0.2 / 16.0f64).powi(2)).sqrt();
        assert!((y.u("r").unwrap() - expect).abs() < 1e-9);
        assert_eq!(y.value("r"), Some(0.5));
    }
}
