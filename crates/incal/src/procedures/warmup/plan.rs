//! Warm-up plans: for the expected curve (one exponential), noise, rate
//! and record length, the predicted u of the settled value, the
//! amplitude, τ, the settling time and the warm-up drift, by reducing
//! [`PLAN_RECORDS`] simulated records (root mean square of their u), as
//! the response plans do. Refused when the record after turn-on is
//! shorter than 3τ (τ cannot be told from the settled value).

use serde_json::json;

use super::sim::{
    five, half, hour, hundredth, seed_one, ten, three_hundred, two, WarmupSimOptions,
};
use super::{CurveChoice, WarmupOptions};
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::options::invalid;
use crate::procedures::response::plan::rms_u;
pub use crate::procedures::response::plan::PLAN_RECORDS;

/// Options of `incal plan warmup`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WarmupPlanOptions {
    /// Sampling rate (Hz; default 10).
    #[serde(default = "ten")]
    pub rate_hz: f64,
    /// Record length from power-on (s; default 3600).
    #[serde(default = "hour")]
    pub duration_s: f64,
    /// Expected turn-on time (s; default 2).
    #[serde(default = "two")]
    pub turn_on_s: f64,
    /// Expected settled value (output units; default 0.5).
    #[serde(default = "half")]
    pub bias_settled: f64,
    /// Expected transient at power-on (output units; default 0.2).
    #[serde(default = "fifth")]
    pub amplitude: f64,
    /// Expected time constant (s; default 300).
    #[serde(default = "three_hundred")]
    pub tau_s: f64,
    /// White noise σ of one sample (output units; default 0.01).
    #[serde(default = "hundredth")]
    pub noise: f64,
    /// Gauss–Markov noise σ (output units; default 0).
    #[serde(default)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time (s; default 5).
    #[serde(default = "five")]
    pub gm_tau_s: f64,
    /// Seed of the first simulated record (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn fifth() -> f64 {
    0.2
}

impl crate::procedures::Plan for super::Warmup {
    type Options = WarmupPlanOptions;

    fn plan(o: &WarmupPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document (module docs).
pub fn plan_document(o: &WarmupPlanOptions) -> Result<PlanDocument> {
    let sim = |seed: u64| WarmupSimOptions {
        rate_hz: o.rate_hz,
        duration_s: o.duration_s,
        turn_on_s: o.turn_on_s,
        bias_settled: o.bias_settled,
        amplitude: o.amplitude,
        tau_s: o.tau_s,
        noise: o.noise,
        gm_sigma: o.gm_sigma,
        gm_tau_s: o.gm_tau_s,
        seed,
        ..WarmupSimOptions::default()
    };
    sim(o.seed).rows()?;
    if o.amplitude == 0.0 {
        return invalid(
            "amplitude",
            "a warm-up with no transient has no tau to plan",
        );
    }
    let after = o.duration_s - o.turn_on_s;
    if after < 3.0 * o.tau_s {
        return invalid(
            "duration_s",
            format!("tau_s is not determined: the record covers {after:.1} s after turn-on and the expected time constant is {} s; record at least 3 tau ({:.0} s) after turn-on", o.tau_s, 3.0 * o.tau_s),
        );
    }
    let r = WarmupOptions {
        curve: CurveChoice::Exp1,
        ..WarmupOptions::default()
    };
    let all = rms_u((0..PLAN_RECORDS).map(|k| {
        let rec = sim(o.seed.wrapping_add(k)).record()?.0;
        Ok(super::calibrate(&rec, &r)?.coefficients)
    }))?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::Warmup,
        format!(
            "Warm-up plan: {} s at {} Hz, tau {} s",
            o.duration_s, o.rate_hz, o.tau_s
        ),
    );
    d.with_options(o)?;
    d.set("expected_tau_records", json!(after / o.tau_s))?;
    for (name, u) in all {
        d.predict(&name, u, super::document::unit_of(&name)?.as_str())?;
    }
    d.note(format!("predicted by reducing {PLAN_RECORDS} simulated records of the expected warm-up (one exponential; seeds from {}): the u of each coefficient is the root mean square of theirs", o.seed));
    Ok(d)
}
