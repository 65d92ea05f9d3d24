//! Magnetometer plans: for a session (orientations, dwell, rate, how the
//! unit is turned) and the expected noise, the predicted u of every
//! coefficient by reducing [`PLAN_RECORDS`] simulated sessions (root mean
//! square of their u), as the response and warm-up plans do. A session
//! that cannot separate a term is refused naming it (the reduction's own
//! check: a planar session cannot give the soft iron about its axis).

use serde_json::json;

use super::sim::{acc_noise, fifty, one, seed_one, sixty, thirty_six, two, MagSimOptions, Motion};
use super::{calibrate, MagOptions};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};
use crate::procedures::response::plan::rms_u;
pub use crate::procedures::response::plan::PLAN_RECORDS;

/// Options of `incal plan mag`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MagPlanOptions {
    /// Orientations held (default 36).
    #[serde(default = "thirty_six")]
    pub orientations: usize,
    /// Seconds held in each (default 2).
    #[serde(default = "two")]
    pub dwell_s: f64,
    /// Seconds moving between two (default 1).
    #[serde(default = "one")]
    pub move_s: f64,
    /// Sampling rate (Hz; default 50).
    #[serde(default = "fifty")]
    pub rate_hz: f64,
    /// How the unit is turned (default random).
    #[serde(default)]
    pub motion: Motion,
    /// The local field (µT; default 50).
    #[serde(default = "fifty")]
    pub field_ut: f64,
    /// The local inclination (degrees; default 60).
    #[serde(default = "sixty")]
    pub inclination_deg: f64,
    /// White noise per axis (µT; default 0.3).
    #[serde(default = "super::sim::noise")]
    pub noise_ut: f64,
    /// Gauss–Markov noise σ per axis (µT; default 0).
    #[serde(default)]
    pub gm_ut: f64,
    /// Gauss–Markov correlation time (s; default 1).
    #[serde(default = "one")]
    pub gm_tau_s: f64,
    /// Without an accelerometer (no alignment or inclination; default
    /// false).
    #[serde(default)]
    pub no_accelerometer: bool,
    /// Accelerometer white noise (m/s²; default 0.02).
    #[serde(default = "acc_noise")]
    pub acc_noise: f64,
    /// Seed of the first simulated session (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

impl crate::procedures::Plan for super::Mag {
    type Options = MagPlanOptions;

    fn plan(options: &MagPlanOptions) -> Result<PlanDocument> {
        plan_document(options)
    }
}

/// The plan document (module docs).
pub fn plan_document(o: &MagPlanOptions) -> Result<PlanDocument> {
    let sim = |seed: u64| MagSimOptions {
        orientations: o.orientations,
        dwell_s: o.dwell_s,
        move_s: o.move_s,
        rate_hz: o.rate_hz,
        motion: o.motion,
        field_ut: o.field_ut,
        inclination_deg: o.inclination_deg,
        noise_ut: o.noise_ut,
        gm_ut: o.gm_ut,
        gm_tau_s: o.gm_tau_s,
        no_accelerometer: o.no_accelerometer,
        acc_noise: o.acc_noise,
        seed,
        ..MagSimOptions::default()
    };
    sim(o.seed).rows()?;
    let r = MagOptions {
        field_ut: Some(o.field_ut),
        ..MagOptions::default()
    };
    let mut results = Vec::new();
    for k in 0..PLAN_RECORDS {
        let rec = sim(o.seed.wrapping_add(k)).record()?;
        let m = calibrate(&rec, &r)
            .map_err(|e| Error::Unsupported(format!("this session cannot be reduced: {e}")))?;
        results.push(m);
    }
    let units: Vec<(String, String)> = results[0]
        .coefficients
        .names()
        .iter()
        .map(|n| Ok((n.clone(), results[0].unit_of(n)?.as_str().to_string())))
        .collect::<Result<_>>()?;
    let all = rms_u(results.iter().map(|m| Ok(m.coefficients.clone())))?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::Mag,
        format!(
            "Magnetometer plan: {} orientations ({}) of {} s at {} Hz",
            o.orientations,
            match o.motion {
                Motion::Random => "random",
                Motion::Planar => "planar",
            },
            o.dwell_s,
            o.rate_hz
        ),
    );
    d.with_options(o)?;
    d.set("orientations_found", json!(results[0].orientations))?;
    d.set("coverage_spread", json!(results[0].coverage.0))?;
    for (name, u) in all {
        let unit = units
            .iter()
            .find(|x| x.0 == name)
            .map_or("", |x| x.1.as_str());
        d.predict(&name, u, unit)?;
    }
    d.note(format!("predicted by reducing {PLAN_RECORDS} simulated sessions with the default hard and soft iron (seeds from {}): the u of each coefficient is the root mean square of theirs", o.seed));
    Ok(d)
}
