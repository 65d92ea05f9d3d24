//! Accelerometer misalignment on a vertical reference face (Li et al. 2012 §3;
//! docs/src/misalignment.md).
//!
//! # Model
//! IA horizontal, the instrument turned by β about the horizontal normal of
//! a vertical reference face:
//!
//! ```text
//! V(β) = c + kI (−Δθy2 cos β + Δθz2 sin β)
//! ```
//!
//! | symbol | unit | meaning |
//! |---|---|---|
//! | `V` | output | mean output at β |
//! | `kI` | output per g | known scale factor |
//! | `c` | output | `V0 + kI·(face verticality and fixture terms)`, constant |
//! | `Δθy2, Δθz2` | rad | input axis vs mounting face |
//!
//! Least squares over any ≥ 3 distinct β; at the paper's 0/90/180/270° it
//! gives `Δθy2 = (V(180°) − V(0))/(2kI)`, `Δθz2 = (V(90°) − V(270°))/(2kI)`
//! (Li et al. 2012 eq. 10–13) with one degree of freedom for the uncertainty.
//! Repeated rows at one β are samples ([`fit_means`]).

use std::collections::BTreeMap;

use super::{angle_key, azimuth, key_angle, small_gamma_warning, with_gamma, GAMMA};
use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::rigs::rate_table::face_factors;

/// The two separable angles, in design order (after the offset `c`).
pub const ACCEL_ANGLES: [&str; 2] = ["dtheta_y2", "dtheta_z2"];

/// One recorded output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelObservation {
    /// Turn β about the face normal (rad).
    pub beta_rad: f64,
    /// Output (output units).
    pub output: f64,
}

/// Options of [`calibrate`] and of [`super::MisalignAccel`]. In the
/// document: `{"noise": null, "scale_factor": 1.299, "scale_factor_unit":
/// "output/g"}`.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct AccelOptions {
    /// Known scale factor kI (output per g); finite, non-zero.
    pub scale_factor: f64,
    /// The unit of `scale_factor` (recorded; always `output/g`).
    #[serde(default)]
    pub scale_factor_unit: super::AccelScaleFactorUnit,
    /// Noise policy of one sample: σ (output units), or null for "from the data".
    #[serde(default)]
    pub noise: Noise,
}

impl AccelOptions {
    /// The scale factor kI (output per g), noise from the data.
    pub fn new(scale_factor: f64) -> Self {
        Self {
            scale_factor,
            scale_factor_unit: Default::default(),
            noise: Noise::Auto,
        }
    }
}

/// Fit summary at one β.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelPosition {
    /// β (rad, [0, 2π)).
    pub beta_rad: f64,
    /// Samples, mean and scatter.
    pub stats: PositionStats,
    /// Mean minus fitted output.
    pub residual: f64,
    /// Residual over its standard deviation.
    pub standardized_residual: f64,
}

/// Everything an accelerometer misalignment calibration produces.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelResult {
    /// `dtheta_y2, dtheta_z2, gamma` (rad).
    pub angles: Estimates,
    /// Azimuth ψ (rad, [0, 2π)).
    pub azimuth: Estimates,
    /// The constant `c` (output units), named `offset`.
    pub offset: Estimates,
    /// The linear fit (offset, Δθy2, Δθz2).
    pub fit: Fit,
    /// Per-position summaries.
    pub positions: Vec<AccelPosition>,
    /// Warnings.
    pub warnings: Vec<crate::Warning>,
}

/// Design matrix at angles `betas_rad`: `[1, −kI cos β, kI sin β]`.
pub fn design(betas_rad: &[f64], scale_factor: f64) -> Result<Design> {
    if !(scale_factor.is_finite() && scale_factor != 0.0) {
        return Err(Error::InvalidValue {
            what: "scale factor kI (output per g)".into(),
            value: scale_factor.to_string(),
        });
    }
    let rows: Vec<Vec<f64>> = betas_rad
        .iter()
        .map(|&b| {
            let f = face_factors(b);
            vec![1.0, scale_factor * f[0], scale_factor * f[1]]
        })
        .collect();
    let mut names = vec!["offset".to_string()];
    names.extend(ACCEL_ANGLES.iter().map(|s| s.to_string()));
    Design::from_rows(names, &rows)
}

/// Calibrate from outputs at several β (module docs).
pub fn calibrate(obs: &[AccelObservation], opts: &AccelOptions) -> Result<AccelResult> {
    if let Some(o) = obs.iter().find(|o| !o.beta_rad.is_finite()) {
        return Err(Error::InvalidValue {
            what: "angle beta".into(),
            value: o.beta_rad.to_string(),
        });
    }
    let mut index: BTreeMap<i64, usize> = BTreeMap::new();
    let mut groups: Vec<(f64, Vec<f64>)> = Vec::new();
    for o in obs {
        let k = angle_key(o.beta_rad);
        let slot = *index.entry(k).or_insert_with(|| {
            groups.push((key_angle(k), Vec::new()));
            groups.len() - 1
        });
        groups[slot].1.push(o.output);
    }
    if groups.len() < 3 {
        return Err(Error::TooFew {
            what: "distinct angles beta (offset, dtheta_y2, dtheta_z2)".into(),
            needed: 3,
            got: groups.len(),
        });
    }
    let betas: Vec<f64> = groups.iter().map(|g| g.0).collect();
    let stats: Vec<PositionStats> = groups
        .iter()
        .map(|g| PositionStats::of(&g.1))
        .collect::<Result<_>>()?;
    let d = design(&betas, opts.scale_factor)?;
    let (fit, weights) = fit_means(&d, &stats, opts.noise)?;
    let two = fit.estimates.select(&ACCEL_ANGLES)?;
    let offset = fit.estimates.select(&["offset"])?;
    let angles = with_gamma(&two, 0, 1)?;
    let az = azimuth(&two, 0, 1)?;
    let std_res = fit.standardized_residuals(Some(&weights));
    let positions = groups
        .iter()
        .zip(&stats)
        .enumerate()
        .map(|(i, (g, s))| AccelPosition {
            beta_rad: g.0,
            stats: *s,
            residual: fit.residuals[i],
            standardized_residual: std_res[i],
        })
        .collect();
    let mut warnings = fit.quality_warnings("re-mounting error or drift");
    if let (Some(g), Some(u)) = (angles.value(GAMMA), angles.u(GAMMA)) {
        warnings.extend(small_gamma_warning(g, u));
    }
    warnings.extend(super::large_angle_warning(&angles));
    Ok(AccelResult {
        angles,
        azimuth: az,
        offset,
        fit,
        positions,
        warnings,
    })
}
