//! Step plans: for a record length, step time, step size and noise, the
//! predicted u of the model's coefficients and step metrics, by reducing
//! [`PLAN_RECORDS`] simulated records of the expected response (root mean
//! square of their u), as the broadband plan does. Refused when the record
//! ends before the expected response settles or starts too near the step.

use serde_json::json;

use super::sim::{noise, one, reference_noise, step, ten, thousand, StepSimOptions};
use super::{metrics, StepOptions};
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::options::invalid;
use crate::procedures::response::plan::ModelGuess;
use crate::procedures::response::OrderChoice;

use crate::procedures::response::plan::rms_u;
pub use crate::procedures::response::plan::PLAN_RECORDS;

/// Options of `incal plan response-step`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct StepPlanOptions {
    /// The expected response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Record length (s; default 1).
    #[serde(default = "one")]
    pub duration_s: f64,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// Time of the step (s; default 0.3).
    #[serde(default = "step")]
    pub step_s: f64,
    /// Step of the reference (default 10).
    #[serde(default = "ten")]
    pub amplitude: f64,
    /// Output noise σ of one sample (default 0.02).
    #[serde(default = "noise")]
    pub noise: f64,
    /// Reference noise σ of one sample (default 0.005).
    #[serde(default = "reference_noise")]
    pub reference_noise: f64,
    /// Seed of the first simulated record (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn seed_one() -> u64 {
    1
}

impl crate::procedures::Plan for super::ResponseStep {
    type Options = StepPlanOptions;

    fn plan(o: &StepPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document (module docs).
pub fn plan_document(o: &StepPlanOptions) -> Result<PlanDocument> {
    let sim = |seed: u64| StepSimOptions {
        model: o.model.clone(),
        duration_s: o.duration_s,
        rate_hz: o.rate_hz,
        step_s: o.step_s,
        amplitude: o.amplitude,
        noise: o.noise,
        reference_noise: o.reference_noise,
        bias: 0.0,
        reference_clock_offset_s: 0.0,
        seed,
    };
    sim(o.seed).samples()?;
    let x = o.model.x()?;
    let (_, _, settle) = metrics(o.model.order, &x, 2.0);
    let after = o.duration_s - o.step_s;
    if after < 2.0 * settle {
        return invalid(
            "duration_s",
            format!("settling_time_s is not determined: the record ends {after:.4} s after the step, and the expected response settles (2 %) in {settle:.4} s; record at least twice that"),
        );
    }
    if o.step_s * o.rate_hz < 20.0 {
        return invalid("step_s", "the step comes within 20 samples of the start: the output's noise before it weights the fit");
    }
    let r = StepOptions {
        order: OrderChoice::from(o.model.order),
        ..StepOptions::default()
    };
    let all = rms_u((0..PLAN_RECORDS).map(|k| {
        let rec = sim(o.seed.wrapping_add(k)).record()?.0;
        Ok(super::calibrate(&rec, &r)?.coefficients)
    }))?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::ResponseStep,
        format!(
            "Step plan: {} s at {} Hz, step at {} s, {} order model",
            o.duration_s,
            o.rate_hz,
            o.step_s,
            o.model.order.name()
        ),
    );
    d.with_options(o)?;
    d.set("expected_settling_time_s", json!(settle))?;
    for (name, u) in all {
        d.predict(
            &name,
            u,
            crate::procedures::response::document::unit_of(&name)?.as_str(),
        )?;
    }
    d.note(format!("predicted by reducing {PLAN_RECORDS} simulated records of the expected response (seeds from {}): the u of each coefficient is the root mean square of theirs", o.seed));
    Ok(d)
}
