//! Misalignment test plans and their predicted uncertainties before the
//! test (docs/src/plans.md, §3): the design of [`super::gyro::design`]
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
    crate::options::check_positive("noise", noise)
}

fn check_readings(readings: usize) -> Result<()> {
    if (1..=MAX_PLAN_SAMPLES).contains(&readings) {
        Ok(())
    } else {
        crate::options::invalid(
            "samples",
            format!("must be 1 to {MAX_PLAN_SAMPLES} per position, got {readings}"),
        )
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

/// Largest number of samples per position a plan takes (the simulators'
/// row cap): beyond it the plan is refused rather than predicted.
pub const MAX_PLAN_SAMPLES: usize = 100_000_000;

/// The prediction of design `d` (one row per position) with `readings`
/// samples of σ `noise` at each position: `readings` equal rows of σ weigh
/// as one row of σ/√readings, so the design is never repeated in memory.
fn predict_design(d: &Design, readings: usize, noise: f64, keep: &[&str]) -> Result<Prediction> {
    check_noise(noise)?;
    check_readings(readings)?;
    let sigma = DVector::from_element(d.nrows(), noise / (readings as f64).sqrt());
    let all = d.predict(&sigma)?;
    let angles = all.select(keep)?;
    let n = keep.len();
    let u_gamma_max = worst_gamma(&angles, keep[n - 2], keep[n - 1])?;
    Ok(Prediction {
        angles,
        u_gamma_max,
        n_obs: d.nrows() * readings,
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
    check_readings(readings)?;
    let positions = gyro_positions(configs, rates_deg_s, 1)?;
    let d = gyro::design(&positions, scale_factor, per_config_bias)?;
    predict_design(&d, readings, noise, &GYRO_ANGLES)
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
    let d = accel::design(betas_rad, scale_factor)?;
    predict_design(&d, readings, noise, &ACCEL_ANGLES)
}

/// Which instrument a misalignment plan is for (`gyro` or `accel`).
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
#[serde(rename_all = "lowercase")]
pub enum PlanInstrument {
    /// Gyro on a rate table ([`predict_gyro`]).
    #[default]
    Gyro,
    /// Accelerometer on a vertical face ([`predict_accel`]).
    Accel,
}

impl PlanInstrument {
    /// Name in documents: `gyro` or `accel`.
    pub fn name(self) -> &'static str {
        match self {
            PlanInstrument::Gyro => "gyro",
            PlanInstrument::Accel => "accel",
        }
    }
}

/// Options of a misalignment plan. In the document's `options`: the
/// instrument, `samples`, `scale_factor`, `noise`, and the instrument's
/// own keys (`configs` as `ALPHA:BETA` in deg, `rates_deg_s`,
/// `per_config_bias`; or `betas_deg`): [`MisalignPlan::settled`] keeps
/// only those of the instrument, with their defaults when not given.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct MisalignPlan {
    /// Gyro or accelerometer (default: gyro).
    #[serde(default)]
    pub instrument: PlanInstrument,
    /// Gyro: configurations `ALPHA:BETA` (deg), in test order (default:
    /// the paper's five, [`GyroConfig::paper`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub configs: Option<Vec<GyroConfig>>,
    /// Gyro: table rate magnitudes (deg/s), each run forward and reverse
    /// (default: 20, 30, 40).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rates_deg_s: Option<Vec<f64>>,
    /// Gyro: one bias per configuration (default: false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub per_config_bias: Option<bool>,
    /// Accelerometer: angles β (deg) (default: 0, 90, 180, 270).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub betas_deg: Option<Vec<f64>>,
    /// Samples (record means or single readings) per position, ≥ 1
    /// (default: 1).
    #[serde(default = "one")]
    pub samples: usize,
    /// Scale factor kI (gyro: output per deg/s; accelerometer: output per g).
    pub scale_factor: f64,
    /// Standard deviation of one sample (output units), > 0.
    pub noise: f64,
}

fn one() -> usize {
    1
}

/// Default table rate magnitudes of a gyro plan (deg/s).
pub const DEFAULT_RATES_DEG_S: [f64; 3] = [20.0, 30.0, 40.0];
/// Default face angles of an accelerometer plan (deg).
pub const DEFAULT_BETAS_DEG: [f64; 4] = [0.0, 90.0, 180.0, 270.0];

impl MisalignPlan {
    /// The plan as predicted and recorded: the instrument's own keys, with
    /// their defaults when not given; the other instrument's keys dropped.
    pub fn settled(&self) -> MisalignPlan {
        let mut o = self.clone();
        match o.instrument {
            PlanInstrument::Gyro => {
                o.configs.get_or_insert_with(GyroConfig::paper);
                o.rates_deg_s
                    .get_or_insert_with(|| DEFAULT_RATES_DEG_S.to_vec());
                o.per_config_bias.get_or_insert(false);
                o.betas_deg = None;
            }
            PlanInstrument::Accel => {
                o.betas_deg
                    .get_or_insert_with(|| DEFAULT_BETAS_DEG.to_vec());
                o.configs = None;
                o.rates_deg_s = None;
                o.per_config_bias = None;
            }
        }
        o
    }

    /// Refuse options that make no plan: no sample, a scale factor that
    /// is zero or not finite, a noise that is not positive, no rate or
    /// angle, an angle that is not finite (the design refuses what cannot
    /// separate an angle, naming it).
    pub fn validate(&self) -> Result<()> {
        use crate::options::invalid;
        check_readings(self.samples)?;
        if !(self.scale_factor.is_finite() && self.scale_factor != 0.0) {
            return invalid(
                "scale_factor",
                format!(
                    "must be a finite, non-zero number, got {}",
                    crate::error::short_number(&self.scale_factor.to_string())
                ),
            );
        }
        check_noise(self.noise)?;
        let o = self.settled();
        match o.instrument {
            PlanInstrument::Gyro => {
                let rates = o.rates_deg_s.unwrap_or_default();
                if rates.is_empty() {
                    return invalid("rates_deg_s", "give at least one rate");
                }
                if let Some(r) = rates.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
                    return invalid(
                        "rates_deg_s",
                        format!("a rate magnitude must be a positive number (deg/s), got {r}"),
                    );
                }
                let configs = o.configs.unwrap_or_default();
                if configs.is_empty() {
                    return invalid("configs", "give at least one configuration");
                }
                if configs
                    .iter()
                    .any(|c| !(c.alpha_rad.is_finite() && c.beta_rad.is_finite()))
                {
                    return invalid("configs", "the angles must be finite");
                }
            }
            PlanInstrument::Accel => {
                let betas = o.betas_deg.unwrap_or_default();
                if betas.is_empty() {
                    return invalid("betas_deg", "give at least one angle");
                }
                if let Some(b) = betas.iter().find(|b| !b.is_finite()) {
                    return invalid("betas_deg", format!("the angles must be finite, got {b}"));
                }
            }
        }
        Ok(())
    }

    /// The plan document: observations and terms, the predicted u of every
    /// separable angle (rad) and the worst-direction u of γ.
    pub fn document(&self) -> Result<crate::document::plan::PlanDocument> {
        use serde_json::json;
        self.validate()?;
        let o = self.settled();
        let (procedure, what, p) = match o.instrument {
            PlanInstrument::Gyro => (
                crate::document::Procedure::MisalignGyro,
                "gyro on a rate table",
                predict_gyro(
                    o.configs.as_deref().unwrap_or_default(),
                    o.rates_deg_s.as_deref().unwrap_or_default(),
                    o.samples,
                    o.scale_factor,
                    o.noise,
                    o.per_config_bias.unwrap_or(false),
                )?,
            ),
            PlanInstrument::Accel => {
                let b: Vec<f64> = o
                    .betas_deg
                    .iter()
                    .flatten()
                    .map(|x| x.to_radians())
                    .collect();
                (
                    crate::document::Procedure::MisalignAccel,
                    "accelerometer on a vertical face",
                    predict_accel(&b, o.samples, o.scale_factor, o.noise)?,
                )
            }
        };
        let mut d = crate::document::plan::PlanDocument::new(
            procedure,
            format!(
                "Misalignment plan ({what}): {} samples, {} terms",
                p.n_obs, p.n_params
            ),
        );
        d.with_options(&o)?;
        d.set("instrument", json!(o.instrument.name()))?;
        d.set("observations", json!(p.n_obs))?;
        d.set("parameters", json!(p.n_params))?;
        for (j, n) in p.angles.names().iter().enumerate() {
            d.predict(n, p.angles.u_at(j), "rad")?;
        }
        d.predict(super::GAMMA, p.u_gamma_max, "rad")?;
        d.note("gamma: the worst direction of the misalignment (its u depends on the unknown direction)");
        Ok(d)
    }
}

/// The run sheet of a gyro misalignment plan: each configuration (α:β)
/// at every rate, forward then reverse (`alpha_deg`, `beta_deg`,
/// `rate_deg_s`).
pub fn run_sheet_gyro(
    d: &crate::document::plan::PlanDocument,
) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, texts, values};
    let rates = values(&d.options, "rates_deg_s");
    let mut rows = Vec::new();
    for c in texts(&d.options, "configs") {
        let (a, b) = c.split_once(':').unwrap_or((c.as_str(), ""));
        for &r in &rates {
            for sr in [r, -r] {
                rows.push(vec![a.trim().to_string(), b.trim().to_string(), num(sr)]);
            }
        }
    }
    (vec!["alpha_deg", "beta_deg", "rate_deg_s"], rows)
}

/// The run sheet of an accelerometer misalignment plan: the face angles
/// in order (`beta_deg`).
pub fn run_sheet_accel(
    d: &crate::document::plan::PlanDocument,
) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let rows = values(&d.options, "betas_deg");
    (
        vec!["beta_deg"],
        rows.into_iter().map(|b| vec![num(b)]).collect(),
    )
}

impl crate::procedures::Plan for super::MisalignGyro {
    type Options = MisalignPlan;

    /// The plan of either instrument (`instrument` chooses; the plan
    /// command is shared by both misalignment procedures).
    fn plan(o: &MisalignPlan) -> Result<crate::document::plan::PlanDocument> {
        o.document()
    }
}

impl crate::procedures::Plan for super::MisalignAccel {
    type Options = MisalignPlan;

    /// The plan of either instrument (`instrument` chooses; the plan
    /// command is shared by both misalignment procedures).
    fn plan(o: &MisalignPlan) -> Result<crate::document::plan::PlanDocument> {
        o.document()
    }
}
