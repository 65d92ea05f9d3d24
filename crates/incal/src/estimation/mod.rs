//! The estimation core shared by every procedure (methods.md §0):
//! weighted linear least squares with covariance and rank/condition
//! diagnostics ([`linear`]), test-design prediction
//! ([`Design::predict`]), propagation to derived coefficients
//! ([`Estimates::map`]) and a small Gauss–Newton iteration built on the same
//! linear solver for models that are linear only after linearisation
//! ([`gauss_newton`]).

pub mod estimates;
pub mod gauss_newton;
pub mod linear;
pub mod repeated;

pub use estimates::{coverage_factor, numeric_jacobian, propagate, Estimates};
pub use gauss_newton::{gauss_newton, GaussNewtonOptions, NonlinearModel};
pub use linear::{
    fit, Design, Diagnostics, Fit, FitOptions, Variance, VarianceSource, DEFAULT_COND_LIMIT,
    WARN_COND,
};
pub use repeated::{fit_means, fit_means_excess, pooled_variance, ExcessFit, Noise, PositionStats};
