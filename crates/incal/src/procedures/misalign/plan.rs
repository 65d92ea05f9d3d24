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
    if noise.is_finite() && noise > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: "noise of one reading (output units)".into(),
            value: noise.to_string(),
        })
    }
}

fn check_readings(readings: usize) -> Result<()> {
    if (1..=MAX_PLAN_SAMPLES).contains(&readings) {
        Ok(())
    } else {
        Error::invalid(
            format!("samples (1 to {MAX_PLAN_SAMPLES} per position)"),
            readings,
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

/// Which instrument a misalignment plan is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanInstrument {
    /// Gyro on a rate table ([`predict_gyro`]).
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
/// `per_config_bias`; or `betas_deg`).
#[derive(Debug, Clone, PartialEq)]
pub struct MisalignPlan {
    /// Gyro or accelerometer.
    pub instrument: PlanInstrument,
    /// Gyro: configurations, in test order.
    pub configs: Vec<GyroConfig>,
    /// Gyro: table rate magnitudes (deg/s), each run forward and reverse.
    pub rates_deg_s: Vec<f64>,
    /// Gyro: one bias per configuration.
    pub per_config_bias: bool,
    /// Accelerometer: angles β (deg).
    pub betas_deg: Vec<f64>,
    /// Samples (record means or single readings) per position, ≥ 1.
    pub samples: usize,
    /// Scale factor kI (gyro: output per deg/s; accelerometer: output per g).
    pub scale_factor: f64,
    /// Standard deviation of one sample (output units), > 0.
    pub noise: f64,
}

impl serde::Serialize for MisalignPlan {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("instrument", self.instrument.name())?;
        match self.instrument {
            PlanInstrument::Gyro => {
                let configs: Vec<String> = self
                    .configs
                    .iter()
                    .map(|c| format!("{}:{}", c.alpha_rad.to_degrees(), c.beta_rad.to_degrees()))
                    .collect();
                m.serialize_entry("configs", &configs)?;
                m.serialize_entry("rates_deg_s", &self.rates_deg_s)?;
                m.serialize_entry("per_config_bias", &self.per_config_bias)?;
            }
            PlanInstrument::Accel => m.serialize_entry("betas_deg", &self.betas_deg)?,
        }
        m.serialize_entry("samples", &self.samples)?;
        m.serialize_entry("scale_factor", &self.scale_factor)?;
        m.serialize_entry("noise", &self.noise)?;
        m.end()
    }
}

impl MisalignPlan {
    /// Refuse options that make no plan: no sample, a scale factor that
    /// is zero or not finite, an angle that is not finite (the design
    /// refuses what cannot separate an angle, naming it).
    pub fn validate(&self) -> Result<()> {
        check_readings(self.samples)?;
        if !(self.scale_factor.is_finite() && self.scale_factor != 0.0) {
            return Error::invalid("scale_factor (a finite non-zero number)", self.scale_factor);
        }
        match self.instrument {
            PlanInstrument::Gyro => {
                if self.rates_deg_s.is_empty() {
                    return Error::invalid("rates_deg_s (at least one rate)", "none");
                }
                for c in &self.configs {
                    if !(c.alpha_rad.is_finite() && c.beta_rad.is_finite()) {
                        return Error::invalid("configs (finite angles)", "not finite");
                    }
                }
            }
            PlanInstrument::Accel => {
                if self.betas_deg.is_empty() {
                    return Error::invalid("betas_deg (at least one angle)", "none");
                }
                if let Some(b) = self.betas_deg.iter().find(|b| !b.is_finite()) {
                    return Error::invalid("betas_deg (finite angles)", b);
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
        let (procedure, what, p) = match self.instrument {
            PlanInstrument::Gyro => (
                crate::document::Procedure::MisalignGyro,
                "gyro on a rate table",
                predict_gyro(
                    &self.configs,
                    &self.rates_deg_s,
                    self.samples,
                    self.scale_factor,
                    self.noise,
                    self.per_config_bias,
                )?,
            ),
            PlanInstrument::Accel => {
                let b: Vec<f64> = self.betas_deg.iter().map(|x| x.to_radians()).collect();
                (
                    crate::document::Procedure::MisalignAccel,
                    "accelerometer on a vertical face",
                    predict_accel(&b, self.samples, self.scale_factor, self.noise)?,
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
        d.with_options(self)?;
        d.set("instrument", json!(self.instrument.name()))?;
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
