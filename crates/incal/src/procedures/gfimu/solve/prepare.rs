//! The preparation of the motion solve ([`super::Solver::new`]): the
//! calibration and options checked, the calibrated geometry's rank and
//! condition, the per-sample design and its weighted pseudo-inverse with
//! the base of the per-sample noise covariance.

use nalgebra::{DMatrix, DVector, Vector3};

use super::{product_regressor, CalibratedAccelerometer, NoiseSource, SolveOptions, PRODUCTS};
use crate::error::{Error, Result};
use crate::estimation::{Diagnostics, DEFAULT_COND_LIMIT, WARN_COND};
use crate::models::gfimu::Geometry;
use crate::warning::{Warning, WarningCode};

/// Refuse a calibration of another length than the geometry, a gravity,
/// initial rate or u limit that is not finite and positive, and an
/// accelerometer whose coefficients, u or noise are not finite (naming
/// it). Returns the gravity (m/s²).
pub(super) fn check_inputs(
    n: usize,
    cal: &[CalibratedAccelerometer],
    opts: &SolveOptions,
) -> Result<f64> {
    if cal.len() != n {
        return Err(Error::Unsupported(format!(
            "{} calibrated accelerometers for a geometry of {n}",
            cal.len()
        )));
    }
    let g = opts.gravity_m_s2;
    if !(g.is_finite() && g > 0.0) {
        return Err(Error::InvalidValue {
            what: "gravity (m/s^2)".into(),
            value: g.to_string(),
        });
    }
    if let Some(v) = opts.omega0_rad_s.iter().find(|v| !v.is_finite()) {
        return Err(Error::InvalidValue {
            what: "initial angular rate".into(),
            value: v.to_string(),
        });
    }
    if !(opts.omega_u_limit_rad_s.is_finite() && opts.omega_u_limit_rad_s > 0.0) {
        return Err(Error::InvalidValue {
            what: "omega uncertainty limit (rad/s)".into(),
            value: opts.omega_u_limit_rad_s.to_string(),
        });
    }
    for (j, c) in cal.iter().enumerate() {
        let finite = c.k0.is_finite()
            && c.ks.iter().all(|v| v.is_finite())
            && c.u_k0.is_finite()
            && c.u_k0 >= 0.0
            && c.u_ks.iter().all(|v| v.is_finite() && *v >= 0.0);
        if !finite {
            return Err(Error::InvalidValue {
                what: format!("calibration of accelerometer {}", j + 1),
                value: format!("K0 {} Ks {:?}", c.k0, c.ks.as_slice()),
            });
        }
        if let Some(s) = c.noise_output {
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::InvalidValue {
                    what: format!("noise of accelerometer {}", j + 1),
                    value: s.to_string(),
                });
            }
        }
    }
    Ok(g)
}

/// Rank and condition of the calibrated N×6 system: refused when it
/// cannot separate f0 and ω̇, warned when weak.
pub(super) fn geometry_diagnostics(
    geometry: &Geometry,
    ks: &[Vector3<f64>],
    g: f64,
) -> Result<(Diagnostics, Vec<Warning>)> {
    let base = geometry.motion_design(ks, g)?;
    let diagnostics = base.diagnose(None, DEFAULT_COND_LIMIT);
    if !diagnostics.aliases.is_empty() {
        return Err(Error::Unseparable {
            aliases: diagnostics.aliases,
        });
    }
    let mut warnings = Vec::new();
    if diagnostics.condition > WARN_COND {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!(
                "weak calibrated geometry (condition number {:.2e}): {} is poorly determined",
                diagnostics.condition,
                diagnostics.weakest.combination()
            ),
        ));
    }
    Ok((diagnostics, warnings))
}

/// The per-sample design `A` (N × p): `Ks_j`, `(r_j × Ks_j)/g`, then the
/// regressors of the products solved directly.
pub(super) fn sample_design(
    ks: &[Vector3<f64>],
    r: &[Vector3<f64>],
    g: f64,
    direct_products: &[usize],
) -> DMatrix<f64> {
    let p = 6 + direct_products.len();
    DMatrix::from_fn(ks.len(), p, |i, j| {
        let s = &ks[i];
        match j {
            0..=2 => s[j],
            3..=5 => r[i].cross(s)[j - 3] / g,
            _ => product_regressor(s, &r[i], PRODUCTS[direct_products[j - 6]]) / g,
        }
    })
}

/// The weighted pseudo-inverse `P = (AᵀWA)⁻¹AᵀW` of the design (SVD of
/// `W^{1/2}A`, never squaring the condition number), where the noise
/// covariance comes from, and the per-sample covariance base
/// (`(AᵀWA)⁻¹`, `P Pᵀ` or zero).
pub(super) fn weighted_pinv(
    design: &DMatrix<f64>,
    cal: &[CalibratedAccelerometer],
    diagnostics: &Diagnostics,
) -> Result<(DMatrix<f64>, DMatrix<f64>, NoiseSource)> {
    let (n, p) = design.shape();
    let sigmas: Option<Vec<f64>> = cal.iter().map(|c| c.noise_output).collect();
    let w: DVector<f64> = match &sigmas {
        Some(s) => DVector::from_iterator(n, s.iter().map(|s| 1.0 / (s * s))),
        None => DVector::from_element(n, 1.0),
    };
    // (AᵀWA)⁻¹ by SVD of W^{1/2}A (never squares the condition number).
    let sw = w.map(f64::sqrt);
    let aw = DMatrix::from_fn(n, p, |i, j| design[(i, j)] * sw[i]);
    let svd = crate::estimation::bounded_svd(aw, true, true).ok_or_else(|| {
        Error::Unsupported(
            "the calibration's Ks and noise_output give a motion design that is not finite".into(),
        )
    })?;
    let (Some(u), Some(vt)) = (svd.u.as_ref(), svd.v_t.as_ref()) else {
        return Err(Error::Unsupported("SVD of the motion design failed".into()));
    };
    let smax = svd.singular_values.max();
    if svd
        .singular_values
        .iter()
        .any(|s| *s <= smax / DEFAULT_COND_LIMIT)
    {
        return Err(Error::IllConditioned {
            terms: diagnostics.weakest.combination(),
            condition: f64::INFINITY,
            limit: DEFAULT_COND_LIMIT,
        });
    }
    let sinv = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / s));
    let v = vt.transpose();
    // P = V S⁻¹ Uᵀ W^{1/2}
    let pinv_w = &v * &sinv * u.transpose();
    let pinv = DMatrix::from_fn(p, n, |i, j| pinv_w[(i, j)] * sw[j]);
    let noise = if sigmas.is_some() {
        NoiseSource::Known
    } else if n > p {
        NoiseSource::Residuals
    } else {
        NoiseSource::None
    };
    let base_cov = match noise {
        NoiseSource::Known => &v * &sinv * &sinv * v.transpose(),
        NoiseSource::Residuals => &pinv * pinv.transpose(),
        NoiseSource::None => DMatrix::zeros(p, p),
    };
    Ok((pinv, base_cov, noise))
}
