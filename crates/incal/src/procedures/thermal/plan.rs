//! Plateau plan: the predicted u of every polynomial coefficient for a
//! set of plateau temperatures, before the chamber is booked
//! (`incal plan thermal`).
//!
//! With each plateau's coefficient known to `u_p` (from the reduction's
//! own plan, e.g. `incal plan tumble`), the polynomial (1) of degree `d`
//! has `C = (AᵀWA)⁻¹`, `A_ik = (T_i − T_ref)^k`, `W = diag(1/u_p²)`: the
//! same design the fit uses ([`super::fit_poly`]), so the prediction is
//! the fit's own covariance when the plateaus deliver their u. A degree
//! the plateaus cannot separate (`d + 1` above the distinct
//! temperatures) is refused naming the term.

use super::{distinct_temperatures, fit_poly, MAX_DEGREE};
use crate::error::{Error, Result};

/// The predicted standard uncertainty of `c_0…c_d` (unit per °C^k) and
/// the residual degrees of freedom `n − d − 1`.
pub fn predict(
    plateaus_c: &[f64],
    u_plateau: f64,
    degree: usize,
    t_ref_c: f64,
) -> Result<(Vec<f64>, usize)> {
    if !(u_plateau.is_finite() && u_plateau > 0.0) {
        return Err(Error::InvalidValue {
            what: "u of a plateau (above 0)".into(),
            value: u_plateau.to_string(),
        });
    }
    if degree > MAX_DEGREE {
        return Err(Error::InvalidValue {
            what: format!("degree (0 to {MAX_DEGREE})"),
            value: degree.to_string(),
        });
    }
    let m = distinct_temperatures(plateaus_c);
    if degree + 1 > m {
        return Err(Error::Unsupported(format!(
            "{m} distinct plateau temperature(s) cannot separate c{degree} (the degree-{degree} term): add plateaus, at least {}",
            degree + 1
        )));
    }
    // The fit of zeros has the design's covariance.
    let n = plateaus_c.len();
    let f = fit_poly(
        plateaus_c,
        &vec![0.0; n],
        &vec![u_plateau; n],
        &[],
        t_ref_c,
        degree,
        f64::INFINITY,
    )?;
    let u = (0..=degree)
        .map(|k| f.covariance[(k, k)].max(0.0).sqrt())
        .collect();
    Ok((u, n - degree - 1))
}
