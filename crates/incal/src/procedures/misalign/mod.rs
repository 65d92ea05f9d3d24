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
mod montecarlo;
pub mod plan;
pub mod sim;
pub mod sim_options;

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
        crate::options::invalid(
            "scale_factor",
            format!(
                "must be a finite, non-zero number, got {}",
                crate::error::short_number(&k.to_string())
            ),
        )
    }
}

/// The unit of a gyro's scale factor as the document records it
/// (`scale_factor_unit`): output per °/s, the only one.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
pub enum GyroScaleFactorUnit {
    /// `output/(deg/s)`.
    #[default]
    #[serde(rename = "output/(deg/s)")]
    OutputPerDegS,
}

/// The unit of an accelerometer's scale factor as the document records
/// it (`scale_factor_unit`): output per g, the only one.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
pub enum AccelScaleFactorUnit {
    /// `output/g`.
    #[default]
    #[serde(rename = "output/g")]
    OutputPerG,
}

/// `incal misalign gyro`: a gyro on a rate table ([`gyro`]), from record
/// means or raw records ([`input`]); options [`gyro::GyroOptions`].
#[derive(Debug, Clone, Copy, Default)]
pub struct MisalignGyro;

impl super::Procedure for MisalignGyro {
    const ID: crate::document::Procedure = crate::document::Procedure::MisalignGyro;
    type Options = gyro::GyroOptions;
    type Input = input::GyroInput;

    fn example() -> gyro::GyroOptions {
        gyro::GyroOptions::new(-2.9222)
    }

    fn validate(o: &gyro::GyroOptions) -> Result<()> {
        check_scale_factor(o.scale_factor)?;
        o.noise.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &gyro::GyroOptions,
    ) -> Result<input::GyroInput> {
        input::read_gyro(rows, o.average)
    }

    fn reduce(
        i: &input::GyroInput,
        o: &gyro::GyroOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        gyro::calibrate(&i.observations, o)?.document(o, &i.records)
    }

    fn synthesis(
        i: &input::GyroInput,
        o: &gyro::GyroOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<input::GyroInput>>> {
        montecarlo::gyro_synthesis(i, o).map(Some)
    }
}

/// `incal misalign accel`: an accelerometer on a vertical face ([`accel`]);
/// options [`accel::AccelOptions`].
#[derive(Debug, Clone, Copy, Default)]
pub struct MisalignAccel;

impl super::Procedure for MisalignAccel {
    const ID: crate::document::Procedure = crate::document::Procedure::MisalignAccel;
    type Options = accel::AccelOptions;
    type Input = Vec<accel::AccelObservation>;

    fn example() -> accel::AccelOptions {
        accel::AccelOptions::new(1.299)
    }

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

    fn synthesis(
        obs: &Vec<accel::AccelObservation>,
        o: &accel::AccelOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<accel::AccelObservation>>>> {
        montecarlo::accel_synthesis(obs, o).map(Some)
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

    fn key_of<T: serde::de::DeserializeOwned + schemars::JsonSchema + std::fmt::Debug>(
        v: serde_json::Value,
    ) -> String {
        crate::options::refused_key(crate::options::from_json::<T>(&v))
    }

    #[test]
    fn options_round_trip_the_documents_and_name_a_bad_key() {
        use super::super::Procedure;
        use serde_json::json;
        let g = json!({"average": "whole", "noise": null, "per_config_bias": false,
            "scale_factor": -2.9222, "scale_factor_unit": "output/(deg/s)"});
        let o: gyro::GyroOptions = crate::options::from_json(&g).unwrap();
        assert_eq!(serde_json::to_value(o).unwrap(), g);
        assert_eq!(
            crate::options::from_json::<gyro::GyroOptions>(&json!({"scale_factor": -2.9222}))
                .unwrap(),
            o
        );
        assert_eq!(
            json!(crate::units::Unit::OutputPerDegS.as_str()),
            g["scale_factor_unit"]
        );
        let a = json!({"noise": 0.001, "scale_factor": 1.299, "scale_factor_unit": "output/g"});
        let o: accel::AccelOptions = crate::options::from_json(&a).unwrap();
        assert_eq!(serde_json::to_value(o).unwrap(), a);
        assert_eq!(
            json!(crate::units::Unit::OutputPerG.as_str()),
            a["scale_factor_unit"]
        );
        assert_eq!(
            key_of::<gyro::GyroOptions>(json!({"scale_factor": 1.0, "averge": "all"})),
            "averge"
        );
        assert_eq!(
            key_of::<gyro::GyroOptions>(json!({"scale_factor": 1.0, "average": "half"})),
            "average"
        );
        assert_eq!(
            key_of::<accel::AccelOptions>(json!({"scale_factor": 1.0, "scale_factor_unit": "V/g"})),
            "scale_factor_unit"
        );
        for bad in [0.0, f64::INFINITY] {
            match MisalignAccel::validate(&accel::AccelOptions::new(bad)) {
                Err(crate::Error::InvalidOption { key, .. }) => assert_eq!(key, "scale_factor"),
                other => panic!("{other:?}"),
            }
        }
        let mut n = gyro::GyroOptions::new(1.0);
        n.noise = crate::estimation::Noise::Known { sigma: -1.0 };
        assert!(matches!(
            MisalignGyro::validate(&n),
            Err(crate::Error::InvalidOption { key, .. }) if key == "noise"
        ));
    }

    #[test]
    fn plan_options_round_trip_the_plan_documents() {
        use serde_json::json;
        let gyro_plan = json!({"instrument": "gyro",
            "configs": ["0:0", "0:180", "180:180", "90:180", "0:90"],
            "rates_deg_s": [20.0, 30.0, 40.0], "per_config_bias": false,
            "samples": 1, "scale_factor": 1.0, "noise": 0.01});
        let o: plan::MisalignPlan = crate::options::from_json(&json!({
            "scale_factor": 1.0, "noise": 0.01}))
        .unwrap();
        let settled = serde_json::to_value(o.settled()).unwrap();
        assert_eq!(settled, gyro_plan);
        let back: plan::MisalignPlan = crate::options::from_json(&settled).unwrap();
        assert_eq!(back, o.settled());
        let doc = o.document().unwrap();
        assert_eq!(json!(doc.options), gyro_plan);
        let accel_plan = json!({"instrument": "accel", "betas_deg": [0.0, 90.0, 180.0, 270.0],
            "samples": 3, "scale_factor": 1.3, "noise": 0.01});
        let o: plan::MisalignPlan = crate::options::from_json(&json!({"instrument": "accel",
            "samples": 3, "scale_factor": 1.3, "noise": 0.01, "rates_deg_s": [5.0]}))
        .unwrap();
        assert_eq!(json!(o.document().unwrap().options), accel_plan);
        assert_eq!(
            key_of::<plan::MisalignPlan>(
                json!({"scale_factor": 1.0, "noise": 0.1, "configs": ["0:0", "90"]})
            ),
            "configs[1]"
        );
        let refused = |v: serde_json::Value| -> String {
            let p: plan::MisalignPlan = crate::options::from_json(&v).unwrap();
            match p.document() {
                Err(crate::Error::InvalidOption { key, .. }) => key,
                other => panic!("{other:?}"),
            }
        };
        assert_eq!(refused(json!({"scale_factor": 1.0, "noise": 0.0})), "noise");
        assert_eq!(
            refused(json!({"scale_factor": 0.0, "noise": 0.1})),
            "scale_factor"
        );
        assert_eq!(
            refused(json!({"scale_factor": 1.0, "noise": 0.1, "samples": 0})),
            "samples"
        );
        assert_eq!(
            refused(json!({"scale_factor": 1.0, "noise": 0.1, "rates_deg_s": [-1.0]})),
            "rates_deg_s"
        );
    }
}
