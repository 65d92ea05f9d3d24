//! Misalignment test plans and their predicted uncertainties before the
//! test (methods.md §0 step 5, §3): the design of [`super::gyro::design`]
//! or [`super::accel::design`] through [`Design::predict`].
//!
//! The predicted u of γ depends on the (unknown) direction of the
//! misalignment; the bound reported is the worst direction,
//! `u(γ) ≤ sqrt(λ_max)` of the 2×2 covariance of `(Δθy2, Δθz2)`.

use nalgebra::DVector;

use super::accel::{self, ACCEL_ANGLES};
use super::gyro::{self, GyroConfig, GYRO_ANGLES};
use crate::error::{Error, Result};
use crate::estimation::{Design, Estimates};

/// A predicted plan: u of each angle (rad) and the worst-direction u of γ.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// Covariance of the angles (values 0), rad.
    pub angles: Estimates,
    /// Worst-direction standard uncertainty of γ (rad).
    pub u_gamma_max: f64,
    /// Observations in the plan.
    pub n_obs: usize,
    /// Terms fitted (angles and biases).
    pub n_params: usize,
}

fn check_noise(noise: f64) -> Result<()> {
    if noise.is_finite() && noise > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: "noise of one reading (output units)".into(),
            value: noise.to_string(),
        })
    }
}

fn worst_gamma(c: &Estimates, y2: &str, z2: &str) -> Result<f64> {
    let two = c.select(&[y2, z2])?;
    let m = two.covariance();
    let (a, b, d) = (m[(0, 0)], m[(0, 1)], m[(1, 1)]);
    let tr = 0.5 * (a + d);
    let det = ((0.5 * (a - d)).powi(2) + b * b).sqrt();
    Ok((tr + det).max(0.0).sqrt())
}

fn predict_design(d: &Design, noise: f64, keep: &[&str]) -> Result<Prediction> {
    check_noise(noise)?;
    let sigma = DVector::from_element(d.nrows(), noise);
    let all = d.predict(&sigma)?;
    let angles = all.select(keep)?;
    let n = keep.len();
    let u_gamma_max = worst_gamma(&angles, keep[n - 2], keep[n - 1])?;
    Ok(Prediction {
        angles,
        u_gamma_max,
        n_obs: d.nrows(),
        n_params: d.ncols(),
    })
}

/// Predict a gyro plan: every configuration at `+ω` and `−ω` for every
/// rate magnitude in `rates_deg_s`, `readings` whole-revolution means each,
/// `noise` the σ of one mean (output units). Refuses a plan that cannot
/// separate an angle, naming it.
pub fn predict_gyro(
    configs: &[GyroConfig],
    rates_deg_s: &[f64],
    readings: usize,
    scale_factor: f64,
    noise: f64,
    per_config_bias: bool,
) -> Result<Prediction> {
    let positions = gyro_positions(configs, rates_deg_s, readings)?;
    let d = gyro::design(&positions, scale_factor, per_config_bias)?;
    predict_design(&d, noise, &GYRO_ANGLES)
}

/// The positions of a gyro plan, forward then reverse at each rate.
pub fn gyro_positions(
    configs: &[GyroConfig],
    rates_deg_s: &[f64],
    readings: usize,
) -> Result<Vec<(GyroConfig, f64)>> {
    if configs.is_empty() || rates_deg_s.is_empty() || readings == 0 {
        return Err(Error::TooFew {
            what: "configurations, rates and readings in a plan (each)".into(),
            needed: 1,
            got: 0,
        });
    }
    if let Some(r) = rates_deg_s.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
        return Err(Error::InvalidValue {
            what: "rate magnitude (deg/s, > 0)".into(),
            value: r.to_string(),
        });
    }
    let mut out = Vec::new();
    for c in configs {
        for &w in rates_deg_s {
            for sign in [1.0, -1.0] {
                for _ in 0..readings {
                    out.push((*c, sign * w));
                }
            }
        }
    }
    Ok(out)
}

/// Predict an accelerometer plan at `betas_rad`, `readings` per angle.
pub fn predict_accel(
    betas_rad: &[f64],
    readings: usize,
    scale_factor: f64,
    noise: f64,
) -> Result<Prediction> {
    let mut distinct: Vec<i64> = betas_rad.iter().map(|b| super::angle_key(*b)).collect();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < 3 {
        return Err(Error::TooFew {
            what: "distinct angles beta (offset, dtheta_y2, dtheta_z2)".into(),
            needed: 3,
            got: distinct.len(),
        });
    }
    let all: Vec<f64> = betas_rad
        .iter()
        .flat_map(|b| std::iter::repeat_n(*b, readings))
        .collect();
    let d = accel::design(&all, scale_factor)?;
    predict_design(&d, noise, &ACCEL_ANGLES)
}
