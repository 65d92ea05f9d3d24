//! Broadband plans: for a record length, a white excitation of RMS `A`
//! and output noise σ, the predicted coherence and u of every bin and of
//! the model's coefficients.
//!
//! For white excitation the one-sided densities are `P_xx = 2A²/f_s` and
//! `P_nn = 2σ²/f_s`, so `γ² = |H|²A²/(|H|²A² + σ²)` at each bin: the bins
//! a plan can fit, and a refusal when they stop below the expected
//! bandwidth. The coefficients' u are the reduction's own on
//! [`PLAN_RECORDS`] simulated records of the expected response (the
//! jackknife of the reduction takes the correlation of neighbouring bins
//! and the window's leakage into account, which a formula over
//! independent bins does not).

use serde_json::json;

use super::welch::{effective_averages, hann};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};
use crate::options::{check_positive, check_range, invalid};
use crate::procedures::response::model::{self, response, Point};
use crate::procedures::response::plan::ModelGuess;

/// Options of `incal plan response-broadband`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BroadbandPlanOptions {
    /// The expected response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Record length (s; default 60).
    #[serde(default = "sixty")]
    pub duration_s: f64,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// RMS of the reference (default 10).
    #[serde(default = "ten")]
    pub amplitude: f64,
    /// Output noise σ of one sample (default 0.02).
    #[serde(default = "noise")]
    pub noise: f64,
    /// Samples per Welch segment (default 1024).
    #[serde(default = "segment")]
    pub segment_samples: usize,
    /// Bins below this coherence are not fitted (default 0.9).
    #[serde(default = "coherence")]
    pub min_coherence: f64,
    /// Highest frequency fitted (Hz; default the last bin below Nyquist).
    #[serde(default)]
    pub f_max_hz: Option<f64>,
    /// Seed of the first simulated record (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn seed_one() -> u64 {
    1
}

pub(super) fn sixty() -> f64 {
    60.0
}
pub(super) fn thousand() -> f64 {
    1000.0
}
pub(super) fn ten() -> f64 {
    10.0
}
pub(super) fn noise() -> f64 {
    0.02
}
pub(super) fn segment() -> usize {
    1024
}
pub(super) fn coherence() -> f64 {
    0.9
}

impl crate::procedures::Plan for super::ResponseBroadband {
    type Options = BroadbandPlanOptions;

    fn plan(o: &BroadbandPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

pub use crate::procedures::response::plan::PLAN_RECORDS;

/// The u of every coefficient as the reduction gives it on
/// [`PLAN_RECORDS`] simulated records of the plan (root mean square).
fn simulated_u(o: &BroadbandPlanOptions) -> Result<Vec<(String, f64)>> {
    let mut r = super::BroadbandOptions {
        segment_samples: o.segment_samples,
        min_coherence: o.min_coherence,
        f_max_hz: o.f_max_hz,
        ..super::BroadbandOptions::default()
    };
    r.model.order = o.model.order.into();
    crate::procedures::response::plan::rms_u((0..PLAN_RECORDS).map(|k| {
        let sim = super::sim::BroadbandSimOptions {
            model: o.model.clone(),
            duration_s: o.duration_s,
            rate_hz: o.rate_hz,
            amplitude: o.amplitude,
            noise: o.noise,
            seed: o.seed.wrapping_add(k),
            ..super::sim::BroadbandSimOptions::default()
        };
        Ok(super::calibrate(&sim.record()?, &r)?.part.coefficients)
    }))
}

/// The plan document (module docs). Refused when the bins fitted stop
/// below the expected bandwidth, or the record holds fewer than two
/// segments.
pub fn plan_document(o: &BroadbandPlanOptions) -> Result<PlanDocument> {
    check_range("rate_hz", o.rate_hz, 1e-3, 1e7, "Hz")?;
    check_range("duration_s", o.duration_s, 1e-3, 1e8, "s")?;
    check_positive("amplitude", o.amplitude)?;
    check_positive("noise", o.noise)?;
    check_range("min_coherence", o.min_coherence, 0.0, 1.0, "")?;
    let l = o.segment_samples;
    if !(8..=1 << 24).contains(&l) {
        return invalid("segment_samples", format!("from 8 to 16777216, got {l}"));
    }
    let x = o.model.x()?;
    let order = o.model.order;
    let n = (o.duration_s * o.rate_hz).round() as usize;
    let step = l - l / 2;
    let k = if n >= l { (n - l / 2) / step } else { 0 };
    if k < 2 {
        return invalid(
            "duration_s",
            format!("{n} samples hold {k} segments of {l}: at least 2"),
        );
    }
    let w = hann(l);
    let n_d = effective_averages(&w, step, k);
    let nyquist = o.rate_hz / 2.0;
    let top = o.f_max_hz.unwrap_or(nyquist).min(nyquist);
    let points: Vec<Point> = (1..l / 2)
        .map(|j| j as f64 * o.rate_hz / l as f64)
        .filter(|f| *f <= top)
        .filter_map(|f| {
            let (m, ph) = response(order, &x, f);
            let s = (m * o.amplitude).powi(2);
            let g2 = s / (s + o.noise * o.noise);
            let eps = ((1.0 - g2) / (2.0 * n_d * g2)).sqrt();
            (g2 >= o.min_coherence && eps > 0.0).then_some(Point {
                freq_hz: f,
                gain: m,
                u_gain: m * eps,
                phase_rad: ph,
                u_phase_rad: eps,
            })
        })
        .collect();
    let bw = model::bandwidth_hz(order, &x);
    let last = points.last().map_or(0.0, |p| p.freq_hz);
    if last < bw {
        return Err(Error::InvalidOption {
            key: "f_max_hz".into(),
            message: format!("bandwidth_hz is not determined: the coherent bins stop at {last:.4} Hz, below the expected bandwidth ({bw:.4} Hz); raise the excitation, lower the noise or raise f_max_hz"),
        });
    }
    let all = simulated_u(o)?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::ResponseBroadband,
        format!(
            "Broadband plan: {} s at {} Hz, {} segments of {l} ({} coherent bins), {} order model",
            o.duration_s,
            o.rate_hz,
            k,
            points.len(),
            order.name()
        ),
    );
    d.with_options(o)?;
    d.set("segments", json!(k))?;
    d.set("effective_averages", json!(n_d))?;
    d.set("coherent_bins", json!(points.len()))?;
    d.set("resolution_hz", json!(o.rate_hz / l as f64))?;
    for (name, u) in &all {
        d.predict(
            name,
            *u,
            crate::procedures::response::document::unit_of(name)?.as_str(),
        )?;
    }
    d.note(format!("predicted by reducing {PLAN_RECORDS} simulated records of the expected response (seeds from {}): the u of each coefficient is the root mean square of theirs", o.seed));
    Ok(d)
}
