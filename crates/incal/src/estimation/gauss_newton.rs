//! Gauss–Newton on the linear core, for models `y = h(x) + e` that are
//! linear only after linearisation (e.g. a centrifuge radius iterated with
//! the coefficients, a rig angle estimated together with a scale factor,
//! or the autocalibration of an IMU triad).
//!
//! Iteration `k`: `A_k = ∂h/∂x (x_k)`, `r_k = y − h(x_k)`, fit
//! `r_k = A_k δ + e` with [`fit`] (weights `w` of [`FitOptions`]); the
//! step `δ` minimises `Σ w (r_k − A_k δ)²`. Stop when every `|δ_j| ≤ tol·u_j`
//! (the step is negligible against the parameter's own uncertainty `u_j`
//! of that linear fit), optionally also when `|δ_j| ≤ rel_tol·|x_j|`. The
//! step taken is chosen by [`StepControl`]: the full step
//! `x_{k+1} = x_k + δ`, or a damped one `x_k + α δ` with `α = 1, ½, ¼, …`
//! the first that does not raise the cost `S(x) = Σ w (y − h(x))²`
//! (step halving). The covariance is that of the last linearisation
//! (first-order, GUM).
//!
//! A least-squares problem stated as residuals, `min Σ w r(x)²`, is the
//! model `h = r` with observations `y = 0`.
//!
//! References: Björck, *Numerical Methods for Least Squares Problems*
//! (SIAM, 1996) §9.2 (Gauss–Newton, damped by step halving); Nocedal &
//! Wright, *Numerical Optimization* (Springer, 2nd ed. 2006) §3.1
//! (backtracking) and §10.3 (Gauss–Newton).

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

/// How the Gauss–Newton step `δ` is taken (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepControl {
    /// The full step `x + δ` every iteration (the default).
    Full,
    /// Damped Gauss–Newton (Björck 1996 §9.2.1): `x + α δ` with the first
    /// `α = 2^−m`, `m = 0 … halvings − 1`, whose cost `S` is finite and not
    /// above the current one; when none is, the current `x` is the
    /// minimum at machine precision ([`Stop::NoDescent`]). Near the
    /// minimum the cost changes below its rounding while the normal
    /// equations `Aᵀ W r = 0` are still resolved: once every
    /// `|δ_j| ≤ polish·u_j` the full step is taken without the cost test,
    /// and after `polish_steps` such steps the iteration stops
    /// ([`Stop::Polished`]).
    Halving {
        /// Largest number of trial step lengths `α` (e.g. 40).
        halvings: usize,
        /// Steps within `polish` standard uncertainties are taken in full
        /// (e.g. 1e-3).
        polish: f64,
        /// Full steps near the minimum after which the iteration stops
        /// (e.g. 8).
        polish_steps: usize,
    },
}

/// Options of [`minimize`] and [`gauss_newton`].
#[derive(Debug, Clone, PartialEq)]
pub struct GaussNewtonOptions {
    /// Options of each linear fit (weights, variance source, limits).
    pub fit: FitOptions,
    /// Maximum number of iterations (linearisations).
    pub max_iter: usize,
    /// Convergence: every step below `tol` standard uncertainties.
    pub tol: f64,
    /// Convergence also for a step `|δ_j| ≤ rel_tol·max(|x_j|, 1e-300)`
    /// (`x_j` after the step): a step at the rounding of the value.
    pub rel_tol: Option<f64>,
    /// How a step is taken.
    pub step: StepControl,
}

impl Default for GaussNewtonOptions {
    fn default() -> Self {
        Self {
            fit: FitOptions::default(),
            max_iter: 50,
            tol: 1e-6,
            rel_tol: Some(1e-15),
            step: StepControl::Full,
        }
    }
}

/// Why [`minimize`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stop {
    /// Every step component within the tolerances ([`GaussNewtonOptions`]);
    /// the step was taken.
    Converged,
    /// The full steps near the minimum were taken
    /// ([`StepControl::Halving`]).
    Polished,
    /// No step length lowered the cost ([`StepControl::Halving`]).
    NoDescent,
    /// [`GaussNewtonOptions::max_iter`] iterations without a stop.
    MaxIterations,
}

/// The point where [`minimize`] stopped.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    /// `x̂` (the last iterate when [`Stop::MaxIterations`]).
    pub x: DVector<f64>,
    /// Linearisations done.
    pub iterations: usize,
    /// Why the iteration stopped.
    pub stop: Stop,
}

/// `S = Σ w r²` (`Σ r²` without weights).
fn cost(r: &DVector<f64>, weights: Option<&DVector<f64>>) -> f64 {
    match weights {
        Some(w) => r.iter().zip(w.iter()).map(|(a, b)| a * a * b).sum::<f64>(),
        None => r.norm_squared(),
    }
}

/// Minimise `S(x) = Σ w (y − h(x))²` from `x0` (module docs): `x̂`, the
/// iterations and why it stopped. Refuses a start whose cost is not
/// finite; a linear fit that fails (rank, condition) is an error.
pub fn minimize(
    model: &impl NonlinearModel,
    y: &DVector<f64>,
    x0: DVector<f64>,
    opts: &GaussNewtonOptions,
) -> Result<Minimum> {
    let names = model.names();
    let weights = opts.fit.weights.as_ref();
    let mut x = x0;
    let mut r = y - model.predict(&x);
    let mut c = cost(&r, weights);
    if !c.is_finite() {
        return Err(Error::Unsupported(
            "the starting point gives a non-finite residual".into(),
        ));
    }
    let done = |x: DVector<f64>, iterations: usize, stop: Stop| Minimum {
        x,
        iterations,
        stop,
    };
    let mut polished = 0;
    for iter in 1..=opts.max_iter {
        let design = Design::new(names.clone(), model.jacobian(&x))?;
        let step = fit(&design, &r, &opts.fit)?;
        let delta = step.estimates.values().clone();
        let within = |f: f64| (0..x.len()).all(|j| delta[j].abs() <= f * step.estimates.u_at(j));
        let converged = (0..x.len()).all(|j| {
            delta[j].abs() <= opts.tol * step.estimates.u_at(j)
                || opts
                    .rel_tol
                    .is_some_and(|rel| delta[j].abs() <= rel * (x[j] + delta[j]).abs().max(1e-300))
        });
        if converged {
            return Ok(done(x + delta, iter, Stop::Converged));
        }
        match opts.step {
            StepControl::Full => {
                x += &delta;
                r = y - model.predict(&x);
            }
            StepControl::Halving {
                polish,
                polish_steps,
                ..
            } if within(polish) => {
                x += &delta;
                r = y - model.predict(&x);
                c = cost(&r, weights);
                polished += 1;
                if polished >= polish_steps {
                    return Ok(done(x, iter, Stop::Polished));
                }
            }
            StepControl::Halving { halvings, .. } => {
                let Some((xn, rn, cn)) = halve(model, y, weights, &x, &delta, c, halvings) else {
                    return Ok(done(x, iter, Stop::NoDescent));
                };
                (x, r, c) = (xn, rn, cn);
            }
        }
    }
    Ok(done(x, opts.max_iter, Stop::MaxIterations))
}

/// The damped step of [`StepControl::Halving`]: the first `x + α δ`,
/// `α = 1, ½, …` (`halvings` trials), whose cost is finite and at most
/// `c`, with its residuals and cost; `None` when there is none.
fn halve(
    model: &impl NonlinearModel,
    y: &DVector<f64>,
    weights: Option<&DVector<f64>>,
    x: &DVector<f64>,
    delta: &DVector<f64>,
    c: f64,
    halvings: usize,
) -> Option<(DVector<f64>, DVector<f64>, f64)> {
    let mut alpha = 1.0;
    for _ in 0..halvings {
        let xn = x + delta * alpha;
        let rn = y - model.predict(&xn);
        let cn = cost(&rn, weights);
        if cn.is_finite() && cn <= c {
            return Some((xn, rn, cn));
        }
        alpha *= 0.5;
    }
    None
}

/// Minimise `Σ w (y − h(x))²` from `x0` ([`minimize`]) and linearise once
/// more at `x̂`. Returns the final [`Fit`] (its estimates hold `x̂` with the
/// covariance of that last linearisation, residuals are `y − h(x̂)`) and
/// the iteration count; an error when the iteration did not converge in
/// [`GaussNewtonOptions::max_iter`] iterations.
pub fn gauss_newton(
    model: &impl NonlinearModel,
    y: &DVector<f64>,
    x0: DVector<f64>,
    opts: &GaussNewtonOptions,
) -> Result<(Fit, usize)> {
    let m = minimize(model, y, x0, opts)?;
    if m.stop == Stop::MaxIterations {
        return Err(Error::Unsupported(format!(
            "Gauss–Newton did not converge in {} iterations",
            opts.max_iter
        )));
    }
    // Final linearisation at x̂ for residuals and covariance.
    let names = model.names();
    let design = Design::new(names.clone(), model.jacobian(&m.x))?;
    let r = y - model.predict(&m.x);
    let last = fit(&design, &r, &opts.fit)?;
    let estimates = Estimates::new(
        names,
        m.x,
        last.estimates.covariance().clone(),
        last.estimates.dof(),
    )?;
    Ok((
        Fit {
            estimates,
            residuals: r,
            ..last
        },
        m.iterations,
    ))
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

    /// From a far start (rate 8 for a true 0.7) the full step overshoots
    /// into a region where the fit fails or wanders; step halving keeps
    /// the cost descending and reaches the minimum of the full iteration
    /// started near it.
    #[test]
    fn step_halving_descends_from_a_far_start() {
        let m = Exp {
            t: (0..20).map(|k| k as f64 * 0.25).collect(),
        };
        let truth = DVector::from_vec(vec![2.0, 0.7]);
        let noise: Vec<f64> = (0..20).map(|k| 1e-3 * ((k * 7 % 5) as f64 - 2.0)).collect();
        let y = m.predict(&truth) + DVector::from_vec(noise);
        let damped = GaussNewtonOptions {
            max_iter: 200,
            tol: 1e-10,
            rel_tol: None,
            step: StepControl::Halving {
                halvings: 40,
                polish: 1e-3,
                polish_steps: 8,
            },
            ..GaussNewtonOptions::default()
        };
        let far = DVector::from_vec(vec![0.5, 8.0]);
        let min = minimize(&m, &y, far, &damped).unwrap();
        assert_ne!(min.stop, Stop::MaxIterations);
        let (near, _) =
            gauss_newton(&m, &y, truth.clone(), &GaussNewtonOptions::default()).unwrap();
        for j in 0..2 {
            let (x, u) = (near.estimates.values()[j], near.estimates.u_at(j));
            assert!(
                (min.x[j] - x).abs() < 1e-6 * u,
                "{j}: {} vs {x} ± {u}",
                min.x[j]
            );
        }
    }

    #[test]
    fn a_non_finite_start_is_refused() {
        let m = Exp { t: vec![0.0, 1.0] };
        let y = DVector::from_vec(vec![1.0, 0.5]);
        let e = minimize(
            &m,
            &y,
            DVector::from_vec(vec![f64::NAN, 1.0]),
            &GaussNewtonOptions::default(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("non-finite residual"), "{e}");
    }
}
