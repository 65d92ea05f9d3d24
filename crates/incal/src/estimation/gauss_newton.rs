//! Gauss–Newton on the linear core, for models `y = h(x) + e` that are
//! linear only after linearisation (e.g. a centrifuge radius iterated with
//! the coefficients, or a rig angle estimated together with a scale factor).
//!
//! Iteration `k`: `A_k = ∂h/∂x (x_k)`, fit `y − h(x_k) = A_k δ + e` with
//! [`fit`], `x_{k+1} = x_k + δ`; stop when every `|δ_j| ≤ tol·u_j` (the step
//! is negligible against the parameter's own uncertainty). The covariance
//! is that of the last linearisation (first-order, GUM).
//! Reference: Björck (1996) §9.2; Nocedal & Wright (2006) §10.3.

use nalgebra::{DMatrix, DVector};

use super::estimates::{numeric_jacobian, Estimates};
use super::linear::{fit, Design, Fit, FitOptions};
use crate::error::{Error, Result};

/// A model `h(x)` predicting every observation from the parameters.
pub trait NonlinearModel {
    /// Parameter names.
    fn names(&self) -> Vec<String>;
    /// Predicted observations `h(x)`.
    fn predict(&self, x: &DVector<f64>) -> DVector<f64>;
    /// Jacobian `∂h/∂x`; the default is central differences.
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let steps: Vec<f64> = x.iter().map(|v| 1e-7 * v.abs().max(1e-6)).collect();
        numeric_jacobian(&|z: &DVector<f64>| self.predict(z), x, &steps)
    }
}

/// Options of [`gauss_newton`].
#[derive(Debug, Clone, PartialEq)]
pub struct GaussNewtonOptions {
    /// Options of each linear fit (weights, variance source, limits).
    pub fit: FitOptions,
    /// Maximum number of iterations.
    pub max_iter: usize,
    /// Convergence: every step below `tol` standard uncertainties.
    pub tol: f64,
}

impl Default for GaussNewtonOptions {
    fn default() -> Self {
        Self {
            fit: FitOptions::default(),
            max_iter: 50,
            tol: 1e-6,
        }
    }
}

/// Minimise `Σ w (y − h(x))²` from `x0`. Returns the final [`Fit`] (its
/// estimates hold `x̂`, residuals are `y − h(x̂)`) and the iteration count.
pub fn gauss_newton(
    model: &impl NonlinearModel,
    y: &DVector<f64>,
    x0: DVector<f64>,
    opts: &GaussNewtonOptions,
) -> Result<(Fit, usize)> {
    let names = model.names();
    let mut x = x0;
    for iter in 1..=opts.max_iter {
        let design = Design::new(names.clone(), model.jacobian(&x))?;
        let r = y - model.predict(&x);
        let step = fit(&design, &r, &opts.fit)?;
        let delta = step.estimates.values().clone();
        x += &delta;
        let converged = (0..x.len()).all(|j| {
            let u = step.estimates.u_at(j);
            delta[j].abs() <= opts.tol * u || delta[j].abs() <= 1e-15 * x[j].abs().max(1e-300)
        });
        if converged {
            // Final linearisation at x̂ for residuals and covariance.
            let design = Design::new(names.clone(), model.jacobian(&x))?;
            let r = y - model.predict(&x);
            let last = fit(&design, &r, &opts.fit)?;
            let estimates = Estimates::new(
                names,
                x,
                last.estimates.covariance().clone(),
                last.estimates.dof(),
            )?;
            return Ok((
                Fit {
                    estimates,
                    residuals: r,
                    ..last
                },
                iter,
            ));
        }
    }
    Err(Error::Unsupported(format!(
        "Gauss–Newton did not converge in {} iterations",
        opts.max_iter
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Exp {
        t: Vec<f64>,
    }
    impl NonlinearModel for Exp {
        fn names(&self) -> Vec<String> {
            vec!["a".into(), "k".into()]
        }
        fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
            DVector::from_iterator(
                self.t.len(),
                self.t.iter().map(|t| x[0] * (-x[1] * t).exp()),
            )
        }
    }

    #[test]
    fn recovers_exponential_decay() {
        let m = Exp {
            t: (0..20).map(|k| k as f64 * 0.25).collect(),
        };
        let truth = DVector::from_vec(vec![2.0, 0.7]);
        let noise: Vec<f64> = (0..20).map(|k| 1e-3 * ((k * 7 % 5) as f64 - 2.0)).collect();
        let y = m.predict(&truth) + DVector::from_vec(noise);
        let (f, iters) = gauss_newton(
            &m,
            &y,
            DVector::from_vec(vec![1.0, 0.3]),
            &GaussNewtonOptions::default(),
        )
        .unwrap();
        assert!(iters < 20);
        let (a, ua) = f.estimates.get("a").unwrap();
        let (k, uk) = f.estimates.get("k").unwrap();
        assert!((a - 2.0).abs() < 4.0 * ua, "{a} ± {ua}");
        assert!((k - 0.7).abs() < 4.0 * uk, "{k} ± {uk}");
        assert!(ua > 0.0 && ua < 1e-2);
    }
}
