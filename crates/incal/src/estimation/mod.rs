//! The estimation core shared by every procedure (docs/src/result-document.md):
//! weighted linear least squares with covariance and rank/condition
//! diagnostics ([`linear`]), test-design prediction
//! ([`Design::predict`]), propagation to derived coefficients
//! ([`Estimates::map`]) and the crate's one Gauss–Newton iteration, built
//! on the same linear solver, for models that are linear only after
//! linearisation ([`gauss_newton()`]; [`minimize`] with optional step
//! halving, [`StepControl`]).

pub mod estimates;
pub mod gauss_newton;
pub mod linear;
pub mod repeated;

pub use estimates::{coverage_factor, numeric_jacobian, propagate, Estimates};
pub use gauss_newton::{
    gauss_newton, minimize, GaussNewtonOptions, Minimum, NonlinearModel, StepControl, Stop,
};
pub use linear::{
    fit, Design, Diagnostics, Fit, FitOptions, Variance, VarianceSource, DEFAULT_COND_LIMIT,
    WARN_COND,
};
pub use repeated::{fit_means, fit_means_excess, pooled_variance, ExcessFit, Noise, PositionStats};

use nalgebra::{DMatrix, Dyn, SVD};

/// The SVD of `a`, or `None` when `a` holds a non-finite entry or the
/// iteration has not converged within a bound (nalgebra's `svd` iterates
/// without end on NaN or infinity, so every SVD of the core goes through
/// here). The bound, 100 sweeps per singular value plus 1000, is far above
/// the few sweeps per value a finite matrix needs.
pub fn bounded_svd(
    a: DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
) -> Option<SVD<f64, Dyn, Dyn>> {
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let sweeps = 1000 + 100 * a.nrows().min(a.ncols());
    // nalgebra's own `svd` tolerance (5 ε), so results are bit-identical.
    a.try_svd(compute_u, compute_v, 5.0 * f64::EPSILON, sweeps)
}
