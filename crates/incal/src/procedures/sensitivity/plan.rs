//! Sensitivity plans: for runs (levels, directions, inputs, run length,
//! gaps, order) and the expected noise (white per sample, bias
//! instability, random walk), the predicted u of every sensitivity: the
//! run means' covariance of that noise ([`super::noise`]) and the
//! model's design give `(Aᵀ Σ⁻¹ A)⁻¹`, the covariance the reduction
//! reports when it finds that noise (its own estimate of the noise
//! scatters about it). A plan
//! that cannot separate a term is refused naming it; a single level is
//! refused as the reduction refuses it.

use nalgebra::DMatrix;
use serde_json::json;

use super::fit::{self, Term};
use super::input::{Record, Run};
use super::noise::{NoiseModel, Span};
use super::sim::{hundred, one, seed_one, ten, thirty, three, xyz, SensitivitySimOptions};
use super::{coefficient_name, Kind, Sensor};
use crate::document::plan::PlanDocument;
use crate::error::Result;

/// Options of `incal plan sensitivity`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensitivityPlanOptions {
    /// The stimulus (default vibration).
    #[serde(default = "vibration")]
    pub kind: Kind,
    /// The instrument (default accel).
    #[serde(default)]
    pub sensor: Sensor,
    /// Levels, comma-separated (as `incal simulate sensitivity`).
    #[serde(default)]
    pub levels: Option<String>,
    /// Vibration directions (degrees), comma-separated (default 0).
    #[serde(default = "zero_text")]
    pub angles_deg: String,
    /// Field axes the coil turns to (default x,y,z).
    #[serde(default = "xyz")]
    pub field_axes: String,
    /// Magnetic outputs: 1 or 3 (default 3).
    #[serde(default = "three")]
    pub outputs: usize,
    /// A run at zero between two levels (default false).
    #[serde(default)]
    pub interleave: bool,
    /// Runs per level (default 1).
    #[serde(default = "one")]
    pub repeats: usize,
    /// Applied inputs, comma-separated (default none).
    #[serde(default)]
    pub inputs: Option<String>,
    /// White noise per sample (reporting units; default 50 µg or 36 °/h).
    #[serde(default)]
    pub noise: Option<f64>,
    /// Bias instability (reporting units; default 2 µg or 0.5 °/h).
    #[serde(default)]
    pub flicker: Option<f64>,
    /// Random walk (reporting units/√s; default 0).
    #[serde(default)]
    pub random_walk: f64,
    /// Seconds per run (default 30).
    #[serde(default = "thirty")]
    pub run_s: f64,
    /// Seconds between runs (default 10).
    #[serde(default = "ten")]
    pub gap_s: f64,
    /// Sampling rate (Hz; default 100).
    #[serde(default = "hundred")]
    pub rate_hz: f64,
}

fn vibration() -> Kind {
    Kind::Vibration
}
fn zero_text() -> String {
    "0".into()
}

impl SensitivityPlanOptions {
    /// The simulator's options of this session (truth at its defaults).
    pub fn session(&self) -> SensitivitySimOptions {
        SensitivitySimOptions {
            kind: self.kind,
            sensor: self.sensor,
            levels: self.levels.clone(),
            angles_deg: self.angles_deg.clone(),
            field_axes: self.field_axes.clone(),
            outputs: self.outputs,
            interleave: self.interleave,
            repeats: self.repeats,
            inputs: self.inputs.clone(),
            noise: self.noise,
            flicker: self.flicker,
            random_walk: self.random_walk,
            run_s: self.run_s,
            gap_s: self.gap_s,
            rate_hz: self.rate_hz,
            seed: seed_one(),
            ..SensitivitySimOptions::default()
        }
    }
}

impl crate::procedures::Plan for super::Sensitivity {
    type Options = SensitivityPlanOptions;

    fn plan(options: &SensitivityPlanOptions) -> Result<PlanDocument> {
        plan_document(options)
    }
}

/// The predicted covariance of `terms` (module docs).
fn predict(terms: &[Term], cov: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    fit::require_separable(terms)?;
    super::terms_covariance(terms, cov)
}

/// The plan document (module docs).
pub fn plan_document(o: &SensitivityPlanOptions) -> Result<PlanDocument> {
    let sim = o.session();
    let planned = sim.plan_runs()?;
    let dt = 1.0 / o.rate_hz;
    let red = sim.reduction();
    let labels = red.labels()?;
    let rec = Record {
        kind: sim.kind(),
        columns: red.column_names()?,
        field_axes: sim.field_flags()?,
        dt_s: dt,
        runs: planned
            .iter()
            .map(|p| Run {
                label: p.label.clone(),
                line: 0,
                start_s: p.start_s,
                duration_s: p.n as f64 * dt,
                dropped: 0,
                stimulus: p.stimulus,
                input: p.input,
                samples: Vec::new(),
            })
            .collect(),
    };
    let model = fit::model(&rec)?;
    let (w, fl) = sim.noise_terms();
    if w == 0.0 && fl == 0.0 && o.random_walk == 0.0 {
        return crate::options::invalid(
            "noise",
            "noise, flicker and random_walk are all 0: nothing to predict a u from",
        );
    }
    let nm = NoiseModel {
        white: w * w * dt,
        flicker: (0.664 * fl).powi(2),
        walk: o.random_walk.powi(2) / 3.0,
        dof: f64::INFINITY,
        points: Vec::new(),
    };
    let spans: Vec<Span> = rec
        .runs
        .iter()
        .map(|r| Span {
            start_s: r.start_s,
            length_s: r.duration_s,
        })
        .collect();
    let cov = nm.run_covariance(&spans)?;
    let c = predict(&model.base, &cov)?;
    let k0 = o.sensor.unit_scale_factor();
    let mut d = PlanDocument::new(
        crate::document::Procedure::Sensitivity,
        format!(
            "{} sensitivity plan: {} runs of {} s, {} s apart",
            sim.kind().as_str(),
            rec.runs.len(),
            o.run_s,
            o.gap_s
        ),
    );
    d.with_options(o)?;
    d.set("runs", json!(rec.runs.len()))?;
    d.set("run_u", json!(nm.avar(o.run_s).sqrt()))?;
    for l in &labels {
        for (j, t) in model.base.iter().enumerate().filter(|(_, t)| t.reported) {
            let u = c[(j, j)].sqrt();
            let (u, top) = if t.sf {
                (1e6 * u / k0, "ppm")
            } else {
                (u, red.report_unit())
            };
            let unit = if t.per.is_empty() {
                top.to_string()
            } else {
                format!("{top}/{}", t.per)
            };
            d.predict(&coefficient_name(&t.name, l.as_deref()), u, &unit)?;
        }
    }
    d.note(format!(
        "predicted from the run means' covariance of this noise (white {w} per sample, bias instability {fl}, random walk {} per √s) and the runs' design; run_u is a run's u (the Allan deviation at its length); a scale-factor term's ppm is of a unit scale factor",
        o.random_walk
    ));
    Ok(d)
}

impl Default for SensitivityPlanOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}
