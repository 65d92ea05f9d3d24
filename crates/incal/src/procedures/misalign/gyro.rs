//! Gyro misalignment on a single-axis rate table (Li et al. 2012 §2; docs/src/misalignment.md).
//!
//! # Model
//! Whole-revolution mean output at gyro angle α on the fixture, fixture
//! angle β on the table and signed table rate ω (Li et al. 2012 eq. 4, linearised;
//! re-derived in docs/src/misalignment.md):
//!
//! ```text
//! V(α, β, ω) = V0 + kI ω [ −Δθy0 cos β + Δθx0 sin β − Δθy1
//!                          − Δθy2 cos α + Δθz2 sin α ]
//! ```
//!
//! | symbol | unit | meaning |
//! |---|---|---|
//! | `V` | output | mean output over whole table revolutions |
//! | `kI` | output per °/s | known scale factor |
//! | `ω` | °/s | table rate, + forward, − reverse |
//! | `Δθx0, Δθy0` | rad | table face vs spin axis |
//! | `Δθy1` | rad | fixture face vs its base |
//! | `Δθy2, Δθz2` | rad | gyro input axis vs its mounting face |
//! | `V0` | output | bias (one, or one per (α, β) configuration) |
//!
//! With `kI` known the model is linear in the five angles and the bias(es):
//! design columns `1` (or one indicator per configuration) and
//! `kI ω f_k(α, β)` with `f` of [`gyro_factors`]. Least squares over any
//! set of configurations and rates; the paper's five configurations at
//! `±ω` give exactly its closed forms (the bias column is orthogonal to the
//! `±ω` columns), and more rates or configurations give redundancy and
//! uncertainties. `Δθz1` enters only at second order and is not estimated.
//!
//! # Uncertainty
//! Rows with the same (α, β, ω) are repeated samples: their means are
//! fitted with weights from the pooled scatter, and the residuals between
//! positions can only raise the uncertainty ([`fit_means`]). With one
//! sample per position the residual scatter alone is used. A bias that
//! shifts between mountings shows up as lack of fit of a common-bias model;
//! [`GyroOptions::per_config_bias`] gives each configuration its own V0.

use std::collections::BTreeMap;

use super::{angle_key, azimuth, key_angle, small_gamma_warning, with_gamma};
use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::rigs::rate_table::gyro_factors;

/// The five separable angles, in design order.
pub const GYRO_ANGLES: [&str; 5] = [
    "dtheta_y0",
    "dtheta_x0",
    "dtheta_y1",
    "dtheta_y2",
    "dtheta_z2",
];

/// One recorded (whole-revolution mean) output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroObservation {
    /// Gyro angle α on the fixture (rad).
    pub alpha_rad: f64,
    /// Fixture angle β on the table (rad).
    pub beta_rad: f64,
    /// Signed table rate ω (°/s; + forward, − reverse).
    pub rate_deg_s: f64,
    /// Output (output units).
    pub output: f64,
}

/// A (α, β) configuration; at the edges (a plan's `configs`) the text
/// `ALPHA:BETA` in degrees (`90:180`).
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(try_from = "String", into = "String")]
pub struct GyroConfig {
    /// Gyro angle α on the fixture (rad).
    pub alpha_rad: f64,
    /// Fixture angle β on the table (rad).
    pub beta_rad: f64,
}

impl GyroConfig {
    /// From degrees.
    pub fn deg(alpha_deg: f64, beta_deg: f64) -> Self {
        Self {
            alpha_rad: alpha_deg.to_radians(),
            beta_rad: beta_deg.to_radians(),
        }
    }

    /// The paper's five configurations (α, β) = (0,0), (0,180°),
    /// (180°,180°), (90°,180°), (0,90°) (Li et al. 2012 eq. 5–9).
    pub fn paper() -> Vec<GyroConfig> {
        [
            (0.0, 0.0),
            (0.0, 180.0),
            (180.0, 180.0),
            (90.0, 180.0),
            (0.0, 90.0),
        ]
        .iter()
        .map(|&(a, b)| GyroConfig::deg(a, b))
        .collect()
    }

    /// From `ALPHA:BETA` in degrees (`0:180`); anything else is
    /// [`Error::InvalidOption`] for `configs`.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = || {
            crate::options::invalid(
                "configs",
                format!(
                    "'{}' is not ALPHA:BETA in degrees (e.g. 0:180)",
                    incal_io::clip(text)
                ),
            )
        };
        let Some((a, b)) = text.split_once(':') else {
            return bad();
        };
        match (a.trim().parse::<f64>(), b.trim().parse::<f64>()) {
            (Ok(a), Ok(b)) if a.is_finite() && b.is_finite() => Ok(GyroConfig::deg(a, b)),
            _ => bad(),
        }
    }

    /// Name of this configuration's bias term, `bias(alpha=A,beta=B)` (deg).
    pub fn bias_name(&self) -> String {
        format!(
            "bias(alpha={},beta={})",
            fmt_deg(self.alpha_rad),
            fmt_deg(self.beta_rad)
        )
    }
}

impl TryFrom<String> for GyroConfig {
    type Error = Error;

    fn try_from(text: String) -> Result<Self> {
        GyroConfig::parse(&text)
    }
}

impl From<GyroConfig> for String {
    /// `ALPHA:BETA` in degrees, as a plan document records it.
    fn from(c: GyroConfig) -> String {
        format!("{}:{}", c.alpha_rad.to_degrees(), c.beta_rad.to_degrees())
    }
}

fn fmt_deg(rad: f64) -> String {
    let d = key_angle(angle_key(rad)).to_degrees();
    let r = (d * 1e6).round() / 1e6;
    format!("{r}")
}

/// Options of [`calibrate`] and of [`super::MisalignGyro`]. In the
/// document: `{"average": "whole", "noise": null, "per_config_bias": false,
/// "scale_factor": -2.9222, "scale_factor_unit": "output/(deg/s)"}`.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct GyroOptions {
    /// Known scale factor kI (output per °/s); must be finite and non-zero.
    pub scale_factor: f64,
    /// The unit of `scale_factor` (recorded; always `output/(deg/s)`).
    #[serde(default)]
    pub scale_factor_unit: super::GyroScaleFactorUnit,
    /// One bias per (α, β) configuration instead of a common one.
    #[serde(default)]
    pub per_config_bias: bool,
    /// Noise policy of one sample: σ (output units), or null for "from the data".
    #[serde(default)]
    pub noise: Noise,
    /// Which samples of a raw record are averaged (unused for record means).
    #[serde(default)]
    pub average: super::averaging::TurnPolicy,
}

impl GyroOptions {
    /// The scale factor kI (output per °/s), a common bias, noise from the
    /// data, whole turns averaged.
    pub fn new(scale_factor: f64) -> Self {
        Self {
            scale_factor,
            scale_factor_unit: Default::default(),
            per_config_bias: false,
            noise: Noise::Auto,
            average: Default::default(),
        }
    }
}

/// Fit summary at one (α, β, ω) position.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroPosition {
    /// Configuration.
    pub config: GyroConfig,
    /// Signed table rate (°/s).
    pub rate_deg_s: f64,
    /// Samples, mean and scatter of the output.
    pub stats: PositionStats,
    /// Mean minus fitted output (output units).
    pub residual: f64,
    /// Residual over its standard deviation.
    pub standardized_residual: f64,
}

/// Everything a gyro misalignment calibration produces.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroResult {
    /// `dtheta_y0, dtheta_x0, dtheta_y1, dtheta_y2, dtheta_z2, gamma` (rad).
    pub angles: Estimates,
    /// Azimuth ψ of the gyro misalignment (rad, [0, 2π)).
    pub azimuth: Estimates,
    /// Bias(es) V0 (output units).
    pub biases: Estimates,
    /// The linear fit (biases then angles), residuals, diagnostics.
    pub fit: Fit,
    /// Per-position summaries.
    pub positions: Vec<GyroPosition>,
    /// Warnings.
    pub warnings: Vec<crate::Warning>,
}

/// Group samples into positions (α, β, ω) in order of first appearance.
fn group(obs: &[GyroObservation]) -> Vec<(GyroConfig, f64, Vec<f64>)> {
    let mut index: BTreeMap<(i64, i64, i64), usize> = BTreeMap::new();
    let mut out: Vec<(GyroConfig, f64, Vec<f64>)> = Vec::new();
    for o in obs {
        let (ka, kb) = (angle_key(o.alpha_rad), angle_key(o.beta_rad));
        let kr = (o.rate_deg_s * 1e9).round() as i64;
        let slot = *index.entry((ka, kb, kr)).or_insert_with(|| {
            out.push((
                GyroConfig {
                    alpha_rad: key_angle(ka),
                    beta_rad: key_angle(kb),
                },
                o.rate_deg_s,
                Vec::new(),
            ));
            out.len() - 1
        });
        out[slot].2.push(o.output);
    }
    out
}

/// Distinct configurations of `positions`, in order of first appearance.
fn configs_of(positions: &[(GyroConfig, f64)]) -> Vec<GyroConfig> {
    let mut out: Vec<GyroConfig> = Vec::new();
    for (c, _) in positions {
        if !out.iter().any(|o| {
            angle_key(o.alpha_rad) == angle_key(c.alpha_rad)
                && angle_key(o.beta_rad) == angle_key(c.beta_rad)
        }) {
            out.push(*c);
        }
    }
    out
}

/// Design matrix over positions (configuration, signed rate °/s): bias
/// column(s) then `kI ω f(α, β)` (module docs).
pub fn design(
    positions: &[(GyroConfig, f64)],
    scale_factor: f64,
    per_config_bias: bool,
) -> Result<Design> {
    if !(scale_factor.is_finite() && scale_factor != 0.0) {
        return Err(Error::InvalidValue {
            what: "scale factor kI (output per deg/s)".into(),
            value: scale_factor.to_string(),
        });
    }
    let configs = configs_of(positions);
    let mut names: Vec<String> = if per_config_bias {
        configs.iter().map(GyroConfig::bias_name).collect()
    } else {
        vec!["bias".to_string()]
    };
    let nb = names.len();
    names.extend(GYRO_ANGLES.iter().map(|s| s.to_string()));
    let rows: Vec<Vec<f64>> = positions
        .iter()
        .map(|(c, w)| {
            let mut row = vec![0.0; nb];
            if per_config_bias {
                let k = configs
                    .iter()
                    .position(|o| {
                        angle_key(o.alpha_rad) == angle_key(c.alpha_rad)
                            && angle_key(o.beta_rad) == angle_key(c.beta_rad)
                    })
                    .unwrap_or(0);
                row[k] = 1.0;
            } else {
                row[0] = 1.0;
            }
            row.extend(
                gyro_factors(c.alpha_rad, c.beta_rad)
                    .iter()
                    .map(|f| scale_factor * w * f),
            );
            row
        })
        .collect();
    Design::from_rows(names, &rows)
}

/// The expected output of a position for given angles (rad, in
/// [`GYRO_ANGLES`] order) and bias: the model of the module docs.
pub fn model_output(
    config: GyroConfig,
    rate_deg_s: f64,
    scale_factor: f64,
    bias: f64,
    angles_rad: &[f64; 5],
) -> f64 {
    let f = gyro_factors(config.alpha_rad, config.beta_rad);
    bias + scale_factor * rate_deg_s * f.iter().zip(angles_rad).map(|(f, t)| f * t).sum::<f64>()
}

/// Calibrate from whole-revolution mean outputs (module docs).
pub fn calibrate(obs: &[GyroObservation], opts: &GyroOptions) -> Result<GyroResult> {
    if obs.is_empty() {
        return Err(Error::TooFew {
            what: "observations".into(),
            needed: 1,
            got: 0,
        });
    }
    if let Some(o) = obs
        .iter()
        .find(|o| !(o.alpha_rad.is_finite() && o.beta_rad.is_finite() && o.rate_deg_s.is_finite()))
    {
        return Err(Error::InvalidValue {
            what: "configuration angle or rate".into(),
            value: format!("{o:?}"),
        });
    }
    let groups = group(obs);
    let positions: Vec<(GyroConfig, f64)> = groups.iter().map(|g| (g.0, g.1)).collect();
    let stats: Vec<PositionStats> = groups
        .iter()
        .map(|g| PositionStats::of(&g.2))
        .collect::<Result<_>>()?;
    let d = design(&positions, opts.scale_factor, opts.per_config_bias)?;
    let nb = d.ncols() - GYRO_ANGLES.len();
    let (fit, weights) = fit_means(&d, &stats, opts.noise)?;
    let names: Vec<&str> = d.names().iter().map(String::as_str).collect();
    let five = fit.estimates.select(&names[nb..])?;
    let biases = fit.estimates.select(&names[..nb])?;
    let angles = with_gamma(&five, 3, 4)?;
    let az = azimuth(&five, 3, 4)?;
    let std_res = fit.standardized_residuals(Some(&weights));
    let positions_out = groups
        .iter()
        .zip(&stats)
        .enumerate()
        .map(|(i, (g, s))| GyroPosition {
            config: g.0,
            rate_deg_s: g.1,
            stats: *s,
            residual: fit.residuals[i],
            standardized_residual: std_res[i],
        })
        .collect();
    let mut warnings = fit.quality_warnings(if opts.per_config_bias {
        "drift or Earth-rate leakage"
    } else {
        "bias shift between mountings, drift or Earth-rate leakage (consider a bias per configuration)"
    });
    let rates: Vec<f64> = positions.iter().map(|p| p.1).collect();
    if !(rates.iter().any(|r| *r > 0.0) && rates.iter().any(|r| *r < 0.0)) {
        warnings.push(crate::Warning::new(
            crate::WarningCode::NoReversal,
            "no forward/reverse pair: the bias is separated from the angles only through the rate dependence",
        ));
    }
    if let (Some(g), Some(u)) = (angles.value(super::GAMMA), angles.u(super::GAMMA)) {
        warnings.extend(small_gamma_warning(g, u));
    }
    warnings.extend(super::large_angle_warning(&angles));
    Ok(GyroResult {
        angles,
        azimuth: az,
        biases,
        fit,
        positions: positions_out,
        warnings,
    })
}

/// Observations from a table of mean outputs `(α°, β°, ω °/s, V)`.
pub fn observations_deg(rows: &[(f64, f64, f64, f64)]) -> Vec<GyroObservation> {
    rows.iter()
        .map(|&(a, b, w, v)| GyroObservation {
            alpha_rad: a.to_radians(),
            beta_rad: b.to_radians(),
            rate_deg_s: w,
            output: v,
        })
        .collect()
}
