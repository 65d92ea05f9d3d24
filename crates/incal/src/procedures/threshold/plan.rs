//! Threshold plans: for the step sizes, plateau length, noise and the
//! expected threshold and resolution, the predicted u of each, by
//! reducing [`PLAN_RECORDS`] simulated records (root mean square of their
//! u), as the other plans by simulation do. Refused when the step sizes
//! do not bracket an expected value (the test would be refused), naming
//! `steps`.

use serde_json::json;

use super::sim::{one, seed_one, ten, thirty, two, SimSensor, ThresholdSimOptions};
use super::ThresholdOptions;
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::options::invalid;
use crate::procedures::response::plan::rms_u;
pub use crate::procedures::response::plan::PLAN_RECORDS;

/// Options of `incal plan threshold` (inputs in deg/s for a gyro, g for
/// an accelerometer; the base input in deg/s or deg of tilt).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThresholdPlanOptions {
    /// Gyro or accelerometer (default gyro).
    #[serde(default)]
    pub sensor: SimSensor,
    /// Sampling rate (Hz; default 10).
    #[serde(default = "ten")]
    pub rate_hz: f64,
    /// Length of each plateau (s; default 30).
    #[serde(default = "thirty")]
    pub dwell_s: f64,
    /// Step sizes (input units; default as the simulator's).
    #[serde(default)]
    pub steps: Option<Vec<f64>>,
    /// Base input (deg/s or deg of tilt; default as the simulator's; 0:
    /// none).
    #[serde(default)]
    pub base_input: Option<f64>,
    /// Expected scale factor (output per input unit; default 1).
    #[serde(default = "one")]
    pub scale_factor: f64,
    /// Expected threshold (input units; default 0.008 deg/s or 2e-5 g).
    #[serde(default)]
    pub expected_threshold: Option<f64>,
    /// Expected resolution (input units; default 0.004 deg/s or 1e-5 g).
    #[serde(default)]
    pub expected_resolution: Option<f64>,
    /// White noise σ of one sample (output units; default as the
    /// simulator's).
    #[serde(default)]
    pub noise: Option<f64>,
    /// Gauss–Markov noise σ (output units; default 0).
    #[serde(default)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time (s; default 2).
    #[serde(default = "two")]
    pub gm_tau_s: f64,
    /// Seed of the first simulated record (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

impl crate::procedures::Plan for super::Threshold {
    type Options = ThresholdPlanOptions;

    fn plan(o: &ThresholdPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document (module docs).
pub fn plan_document(o: &ThresholdPlanOptions) -> Result<PlanDocument> {
    let gyro = o.sensor == SimSensor::Gyro;
    let threshold = o
        .expected_threshold
        .unwrap_or(if gyro { 0.008 } else { 2e-5 });
    let resolution = o
        .expected_resolution
        .unwrap_or(if gyro { 0.004 } else { 1e-5 });
    crate::options::check_range("expected_threshold", threshold, 1e-12, 1e4, "")?;
    crate::options::check_range("expected_resolution", resolution, 1e-12, 1e4, "")?;
    let sim = |seed: u64| ThresholdSimOptions {
        sensor: o.sensor,
        rate_hz: o.rate_hz,
        dwell_s: o.dwell_s,
        steps: o.steps.clone(),
        base_input: o.base_input,
        scale_factor: o.scale_factor,
        dead_band: Some(threshold / 2.0),
        resolution_band: Some(resolution / 2.0),
        noise: o.noise,
        gm_sigma: o.gm_sigma,
        gm_tau_s: o.gm_tau_s,
        seed,
        ..ThresholdSimOptions::default()
    };
    let s = sim(o.seed).settled()?;
    let (lo, hi) = s
        .steps
        .iter()
        .fold((f64::MAX, 0.0f64), |a, v| (a.0.min(*v), a.1.max(*v)));
    let mut expected = vec![("threshold", threshold)];
    if s.base != 0.0 {
        expected.push(("resolution", resolution));
    }
    for (name, v) in &expected {
        if !(lo < *v && *v < hi) {
            return invalid(
                "steps",
                format!("the step sizes {lo:e}..{hi:e} do not bracket the expected {name} {v:e}: the test would be refused; steps below and above it"),
            );
        }
    }
    let r = ThresholdOptions {
        scale_factor: (s.base == 0.0).then_some(o.scale_factor),
        ..ThresholdOptions::default()
    };
    let all = rms_u((0..PLAN_RECORDS).map(|k| {
        let rec = sim(o.seed.wrapping_add(k)).record()?;
        super::calibrate(&rec, &r)?.coefficients()
    }))?;
    let sensor: super::input::Sensor = o.sensor.into();
    let mut d = PlanDocument::new(
        crate::document::Procedure::Threshold,
        format!(
            "Threshold plan: {} step sizes {lo:e}..{hi:e} {}, {} s plateaus at {} Hz",
            s.steps.len(),
            sensor.unit(),
            o.dwell_s,
            o.rate_hz
        ),
    );
    d.with_options(o)?;
    d.set(
        "plateaus",
        json!(
            1 + 4 * s.steps.len() * if s.base != 0.0 { 2 } else { 1 } + usize::from(s.base != 0.0)
        ),
    )?;
    d.set(
        "duration_s",
        json!(
            o.dwell_s
                * (1 + 4 * s.steps.len() * if s.base != 0.0 { 2 } else { 1 }
                    + usize::from(s.base != 0.0)) as f64
        ),
    )?;
    for (name, u) in all {
        let unit = if name == "K1" {
            super::document::scale_unit(sensor)
        } else {
            super::document::input_unit(sensor)
        };
        d.predict(&name, u, unit.as_str())?;
    }
    d.note(format!("predicted by reducing {PLAN_RECORDS} simulated records with dead bands at the expected threshold's and resolution's halves (seeds from {}): the u of each coefficient is the root mean square of theirs", o.seed));
    Ok(d)
}
