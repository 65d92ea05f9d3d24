//! Misalignment separation (Li et al. 2012; docs/src/misalignment.md): a gyro on a single-axis
//! rate table turned to several fixture/table configurations at forward and
//! reverse rates ([`gyro`]), raw time series averaged over whole table
//! revolutions ([`averaging`]), and an accelerometer turned about the
//! normal of a vertical reference face ([`accel`]). Test plans and their
//! predicted uncertainties are in [`plan`].
//!
//! Every procedure builds a design matrix from the linearised model and
//! fits it with [`crate::estimation::fit_means`]; the total misalignment
//! and its azimuth come from [`crate::estimation::Estimates::map`].
//!
//! # Misalignment and azimuth (Li et al. 2012 eq. 1)
//! The input axis, seen in its mounting-face frame (normal x, face axes
//! y, z), is `[1, Δθz2, −Δθy2]` to first order (`P2 = Py(Δθy2) Pz(Δθz2)`,
//! [`crate::rigs::rate_table`]). The total misalignment is
//! `γ = sqrt(Δθy2² + Δθz2²)` and its azimuth, the direction of the axis'
//! projection on the face measured from face y towards face z, is
//! `ψ = atan2(−Δθy2, Δθz2)` in [0, 2π), so that `Δθy2 = −γ sin ψ`,
//! `Δθz2 = γ cos ψ`: Li et al. 2012's `Δαx = −Δα sin β`, `Δαy = Δα cos β` with
//! its face axes (X, Y) taken as (y, z). Jacobians:
//! `∂γ/∂(Δθy2, Δθz2) = (Δθy2, Δθz2)/γ`,
//! `∂ψ/∂(Δθy2, Δθz2) = (−Δθz2, Δθy2)/γ²`.

pub mod accel;
pub mod averaging;
pub mod document;
pub mod gyro;
pub mod input;
pub mod plan;
pub mod sim;

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::Estimates;

/// Name of the total misalignment γ in results.
pub const GAMMA: &str = "gamma";
/// Name of the azimuth ψ in results.
pub const AZIMUTH: &str = "azimuth";

/// Append `γ` to the estimates of `(…, Δθy2, Δθz2, …)`: returns the named
/// angles plus `gamma`, with covariance by GUM propagation (module docs).
/// `iy`, `iz` are the positions of Δθy2, Δθz2 in `angles`.
pub fn with_gamma(angles: &Estimates, iy: usize, iz: usize) -> Result<Estimates> {
    let n = angles.len();
    let mut names = angles.names().to_vec();
    names.push(GAMMA.to_string());
    angles.map(
        names,
        |x| {
            let mut y = x.clone().resize_vertically(n + 1, 0.0);
            y[n] = x[iy].hypot(x[iz]);
            y
        },
        |x| {
            let mut j = DMatrix::zeros(n + 1, n);
            for k in 0..n {
                j[(k, k)] = 1.0;
            }
            let g = x[iy].hypot(x[iz]);
            // At γ = 0 the derivative does not exist; 0 keeps the result
            // finite and the warning of `small_gamma_warning` says why.
            if g > 0.0 {
                j[(n, iy)] = x[iy] / g;
                j[(n, iz)] = x[iz] / g;
            }
            j
        },
    )
}

/// The azimuth `ψ = atan2(−Δθy2, Δθz2)` in [0, 2π) with its uncertainty
/// (module docs); `iy`, `iz` as in [`with_gamma`].
pub fn azimuth(angles: &Estimates, iy: usize, iz: usize) -> Result<Estimates> {
    with_azimuth(angles, iy, iz)?.select(&[AZIMUTH])
}

/// `angles` with the azimuth ψ appended (joint covariance kept, see
/// [`Estimates::augment`]); `iy`, `iz` as in [`with_gamma`].
pub fn with_azimuth(angles: &Estimates, iy: usize, iz: usize) -> Result<Estimates> {
    let n = angles.len();
    angles.augment(
        vec![AZIMUTH.to_string()],
        |x| DVector::from_element(1, (-x[iy]).atan2(x[iz]).rem_euclid(std::f64::consts::TAU)),
        |x| {
            let g2 = x[iy] * x[iy] + x[iz] * x[iz];
            let mut j = DMatrix::zeros(1, n);
            if g2 > 0.0 {
                j[(0, iy)] = -x[iz] / g2;
                j[(0, iz)] = x[iy] / g2;
            }
            j
        },
    )
}

/// A warning when γ is within 3 u of zero: then the first-order u of γ is
/// not valid (γ is biased upward, Rayleigh-like) and the azimuth is poorly
/// determined.
pub fn small_gamma_warning(gamma: f64, u_gamma: f64) -> Option<crate::Warning> {
    if gamma <= 3.0 * u_gamma {
        Some(crate::Warning::new(crate::WarningCode::SmallAngle, format!(
            "gamma ({:.2} arcsec) is within 3 u ({:.2} arcsec) of zero: its linear uncertainty is not reliable and the azimuth is poorly determined",
            crate::units::rad_to_arcsec(gamma),
            crate::units::rad_to_arcsec(3.0 * u_gamma)
        )))
    } else {
        None
    }
}

/// Largest misalignment angle (rad, 0.02 ≈ 1.15°) for which the
/// linearised model holds to 1 %: its neglected terms (cos θ − 1 ≈ −θ²/2
/// and the products of two angles) are about θ/2 of the first-order terms.
pub const LINEAR_ANGLE_LIMIT_RAD: f64 = 0.02;

/// A `model-range` warning naming every fitted angle beyond
/// [`LINEAR_ANGLE_LIMIT_RAD`]: the linearised model (Li et al. 2012 after eq. 3)
/// then biases the estimates by more than 1 % of their size.
pub fn large_angle_warning(angles: &crate::estimation::Estimates) -> Option<crate::Warning> {
    let big: Vec<String> = angles
        .names()
        .iter()
        .zip(angles.values().iter())
        .filter(|(_, v)| v.abs() > LINEAR_ANGLE_LIMIT_RAD)
        .map(|(n, v)| format!("{n} = {:.2} deg", v.to_degrees()))
        .collect();
    (!big.is_empty()).then(|| {
        crate::Warning::new(
            crate::WarningCode::ModelRange,
            format!(
                "{} beyond {:.2} deg: the linearised model neglects second-order terms of about half the angle's relative size (over 1 %); re-mount closer to nominal or treat these angles as approximate",
                big.join(", "),
                LINEAR_ANGLE_LIMIT_RAD.to_degrees()
            ),
        )
    })
}

/// Refuse a scale factor kI that is zero or not finite.
fn check_scale_factor(k: f64) -> Result<()> {
    if k.is_finite() && k != 0.0 {
        Ok(())
    } else {
        crate::Error::invalid("scale_factor (a finite non-zero number)", k)
    }
}

/// `incal misalign gyro`: a gyro on a rate table ([`gyro`]), from record
/// means or raw records ([`input`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct MisalignGyro;

/// Options of [`MisalignGyro`]: the fit and how raw records are averaged.
/// In the document: `{"average": "whole", "noise": null,
/// "per_config_bias": false, "scale_factor": -2.9222,
/// "scale_factor_unit": "output/(deg/s)"}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroRun {
    /// Scale factor, bias layout and noise policy.
    pub fit: gyro::GyroOptions,
    /// Which samples of a raw record are averaged (unused for record means).
    pub average: averaging::TurnPolicy,
}

impl serde::Serialize for GyroRun {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(5))?;
        m.serialize_entry(
            "average",
            match self.average {
                averaging::TurnPolicy::Whole => "whole",
                averaging::TurnPolicy::All => "all",
            },
        )?;
        m.serialize_entry("noise", &self.fit.noise.sigma())?;
        m.serialize_entry("per_config_bias", &self.fit.per_config_bias)?;
        m.serialize_entry("scale_factor", &self.fit.scale_factor)?;
        m.serialize_entry(
            "scale_factor_unit",
            crate::units::Unit::OutputPerDegS.as_str(),
        )?;
        m.end()
    }
}

impl super::Procedure for MisalignGyro {
    const ID: crate::document::Procedure = crate::document::Procedure::MisalignGyro;
    type Options = GyroRun;
    type Input = input::GyroInput;

    fn validate(o: &GyroRun) -> Result<()> {
        check_scale_factor(o.fit.scale_factor)?;
        o.fit.noise.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &GyroRun,
    ) -> Result<input::GyroInput> {
        input::read_gyro(rows, o.average)
    }

    fn reduce(
        i: &input::GyroInput,
        o: &GyroRun,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        gyro::calibrate(&i.observations, &o.fit)?.document(&o.fit, &i.records)
    }
}

/// `incal misalign accel`: an accelerometer on a vertical face ([`accel`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct MisalignAccel;

impl serde::Serialize for accel::AccelOptions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(3))?;
        m.serialize_entry("noise", &self.noise.sigma())?;
        m.serialize_entry("scale_factor", &self.scale_factor)?;
        m.serialize_entry("scale_factor_unit", crate::units::Unit::OutputPerG.as_str())?;
        m.end()
    }
}

impl super::Procedure for MisalignAccel {
    const ID: crate::document::Procedure = crate::document::Procedure::MisalignAccel;
    type Options = accel::AccelOptions;
    type Input = Vec<accel::AccelObservation>;

    fn validate(o: &accel::AccelOptions) -> Result<()> {
        check_scale_factor(o.scale_factor)?;
        o.noise.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &accel::AccelOptions,
    ) -> Result<Vec<accel::AccelObservation>> {
        input::read_accel(rows)
    }

    fn reduce(
        obs: &Vec<accel::AccelObservation>,
        o: &accel::AccelOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        accel::calibrate(obs, o)?.document(o)
    }
}

/// Grouping key of an angle: micro-degrees in [0, 360°).
pub(crate) fn angle_key(angle_rad: f64) -> i64 {
    let d = angle_rad.to_degrees().rem_euclid(360.0);
    ((d * 1e6).round() as i64).rem_euclid(360_000_000)
}

/// The angle of a key, in radians.
pub(crate) fn key_angle(key: i64) -> f64 {
    (key as f64 / 1e6).to_radians()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_and_azimuth_jacobians_match_numeric() {
        let e = Estimates::new(
            vec!["dtheta_y2".into(), "dtheta_z2".into()],
            DVector::from_vec(vec![-7.9e-4, 2.7e-4]),
            DMatrix::from_row_slice(2, 2, &[1e-11, 2e-12, 2e-12, 4e-12]),
            f64::INFINITY,
        )
        .unwrap();
        let g = with_gamma(&e, 0, 1).unwrap();
        let gn = e
            .map_numeric(vec!["g".into()], |x| {
                DVector::from_element(1, x[0].hypot(x[1]))
            })
            .unwrap();
        assert!((g.u(GAMMA).unwrap() - gn.u_at(0)).abs() < 1e-9 * gn.u_at(0).max(1e-12) + 1e-15);
        let a = azimuth(&e, 0, 1).unwrap();
        let an = e
            .map_numeric(vec!["a".into()], |x| {
                DVector::from_element(1, (-x[0]).atan2(x[1]))
            })
            .unwrap();
        assert!((a.u_at(0) - an.u_at(0)).abs() < 1e-6 * an.u_at(0));
        // Δθy2 = −γ sin ψ, Δθz2 = γ cos ψ
        let (gv, psi) = (g.value(GAMMA).unwrap(), a.values()[0]);
        assert!((-gv * psi.sin() - -7.9e-4).abs() < 1e-15);
        assert!((gv * psi.cos() - 2.7e-4).abs() < 1e-15);
    }
}
