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
///
/// The decomposition is checked: `U S Vᵀ` must give `a` back to 1e-9 of
/// its Frobenius norm. nalgebra 0.35 returns, rarely, a wrong one (found
/// by the Monte Carlo of a tumble test: an equilibrated 12 × 6 design with
/// a repeated singular value came back 4 % off, and the fit with it
/// silently wrong); then the SVD of `aᵀ` is taken, then that of `R` from
/// `a = Q R`; `None` when none of them holds (the caller refuses). `U` and
/// `V` are always computed (`compute_u`, `compute_v` kept for callers'
/// clarity).
pub fn bounded_svd(
    a: DMatrix<f64>,
    compute_u: bool,
    compute_v: bool,
) -> Option<SVD<f64, Dyn, Dyn>> {
    let _ = (compute_u, compute_v);
    if a.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let sweeps = 1000 + 100 * a.nrows().min(a.ncols());
    // nalgebra's own `svd` tolerance (5 ε), so results are bit-identical.
    let svd_of = |m: DMatrix<f64>| m.try_svd(true, true, 5.0 * f64::EPSILON, sweeps);
    let holds = |svd: &SVD<f64, Dyn, Dyn>| -> bool {
        let norm = a.norm();
        match svd.clone().recompose() {
            Ok(r) => (r - &a).norm() <= 1e-9 * norm.max(f64::MIN_POSITIVE),
            Err(_) => false,
        }
    };
    if let Some(svd) = svd_of(a.clone()) {
        if holds(&svd) {
            return Some(svd);
        }
    }
    // Through the transpose: aᵀ = V S Uᵀ.
    if let Some(t) = svd_of(a.transpose()) {
        let svd = SVD {
            u: t.v_t.map(|m| m.transpose()),
            v_t: t.u.map(|m| m.transpose()),
            singular_values: t.singular_values,
        };
        if holds(&svd) {
            return Some(svd);
        }
    }
    // Through a = Q R (a tall or square a): R = U_r S Vᵀ, U = Q U_r.
    if a.nrows() >= a.ncols() {
        let qr = a.clone().qr();
        let (q, r) = (qr.q(), qr.r());
        if let Some(t) = svd_of(r) {
            let svd = SVD {
                u: t.u.map(|ur| q * ur),
                v_t: t.v_t,
                singular_values: t.singular_values,
            };
            if holds(&svd) {
                return Some(svd);
            }
        }
    }
    None
}

#[cfg(test)]
mod svd_regression {
    use super::*;
    use nalgebra::DVector;

    /// The equilibrated design of a 12-position tumble test with the six
    /// default pendulum terms (column-major, 12 × 6): nalgebra 0.35's SVD
    /// of it does not give it back (an error of 0.13 in Frobenius norm on
    /// unit columns); [`bounded_svd`] does, to rounding.
    #[test]
    fn a_design_nalgebra_decomposes_wrongly_is_decomposed_right() {
        let a = DMatrix::from_column_slice(
            12,
            6,
            &[
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                2.8867513459481287e-1,
                0.0e0,
                2.041241452319315e-1,
                3.535533905932738e-1,
                4.082482904638631e-1,
                3.5355339059327384e-1,
                2.041241452319315e-1,
                4.9995996217394886e-17,
                -2.041241452319316e-1,
                -3.535533905932737e-1,
                -4.082482904638631e-1,
                -3.535533905932738e-1,
                -2.041241452319317e-1,
                0.0e0,
                1.178511301977579e-1,
                3.535533905932738e-1,
                4.7140452079103173e-1,
                3.535533905932739e-1,
                1.178511301977579e-1,
                7.06993541647375e-33,
                1.1785113019775799e-1,
                3.535533905932736e-1,
                4.7140452079103173e-1,
                3.535533905932738e-1,
                1.1785113019775816e-1,
                0.0e0,
                6.454972243679026e-2,
                3.354101966249684e-1,
                5.163977794943222e-1,
                3.354101966249685e-1,
                6.454972243679026e-2,
                9.484554169980213e-49,
                -6.454972243679033e-2,
                -3.354101966249682e-1,
                -5.163977794943222e-1,
                -3.354101966249684e-1,
                -6.454972243679045e-2,
                4.0824829046386296e-1,
                3.5355339059327373e-1,
                2.0412414523193154e-1,
                2.4997998108697437e-17,
                -2.041241452319314e-1,
                -3.5355339059327373e-1,
                -4.0824829046386296e-1,
                -3.535533905932737e-1,
                -2.0412414523193165e-1,
                -7.499399432609231e-17,
                2.0412414523193154e-1,
                3.535533905932736e-1,
                0.0e0,
                3.535533905932737e-1,
                3.535533905932738e-1,
                4.9995996217394874e-17,
                -3.535533905932736e-1,
                -3.535533905932737e-1,
                -9.999199243478975e-17,
                3.535533905932738e-1,
                3.5355339059327395e-1,
                1.4998798865218462e-16,
                -3.535533905932738e-1,
                -3.5355339059327395e-1,
            ],
        );
        let svd = bounded_svd(a.clone(), true, true).unwrap();
        let back = svd.clone().recompose().unwrap();
        assert!((back - &a).norm() < 1e-12, "{:?}", svd.singular_values);
        // The least-squares solution through it fits an exact right-hand
        // side exactly.
        let x = DVector::from_fn(6, |j, _| 1.0 + j as f64);
        let y = &a * &x;
        let got = svd.solve(&y, 1e-12).unwrap();
        assert!((got - x).amax() < 1e-10);
    }
}
