//! Plans of a gyro-free unit calibration: the standard uncertainty every
//! accelerometer's K0 and Ks *will* have for a set of static positions
//! ([`super::calibrate::plan`], the calibration itself run on noise-free
//! samples with the noise known), and the conditioning of the array for
//! the motion solution (rank and condition number of the nominal N×6
//! system, and whether a sample is solved directly or with centripetal
//! feedback, [`super::solve::solve_mode`]).

use nalgebra::Vector3;
use serde_json::json;

use super::input::{shown, ArrayChoice};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};
use crate::units::STANDARD_GRAVITY_M_S2;

/// Largest number of samples per position a plan takes.
pub const MAX_PLAN_SAMPLES: usize = 100_000_000;

/// Largest magnitude of the nominal scale factor (output/g).
pub const MAX_PLAN_K1: f64 = 1e9;

/// Options of a gyro-free unit calibration plan. In the plan document's
/// `options`: `geometry` (the array's label), `positions` (g), `samples`,
/// `noise`, `k1`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GfimuPlanOptions {
    /// The array (recorded as its label).
    #[serde(flatten)]
    pub array: ArrayChoice,
    /// Static positions: the specific force (g, unit frame) of each
    /// (default: the six-position test, ±1 g along each axis).
    #[serde(default = "default_positions")]
    pub positions: Vec<[f64; 3]>,
    /// Samples per position (1 ..= [`MAX_PLAN_SAMPLES`]).
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Standard deviation of one output sample (output, > 0).
    pub noise: f64,
    /// Nominal scale factor of every accelerometer (output/g; non-zero,
    /// at most [`MAX_PLAN_K1`] in magnitude).
    #[serde(default = "default_k1")]
    pub k1: f64,
}

fn default_positions() -> Vec<[f64; 3]> {
    super::sim::six_positions()
        .iter()
        .map(|f| [f.x, f.y, f.z])
        .collect()
}

fn default_samples() -> usize {
    1
}

fn default_k1() -> f64 {
    1.0
}

impl GfimuPlanOptions {
    /// Refuse a noise that is not positive, a sample count outside
    /// 1 ..= [`MAX_PLAN_SAMPLES`], a zero, non-finite or huge `k1` and a
    /// position that is not a finite specific force, naming the option.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, invalid};
        check_positive("noise", self.noise)?;
        if self.samples == 0 || self.samples > MAX_PLAN_SAMPLES {
            return invalid(
                "samples",
                format!("must be within 1..{MAX_PLAN_SAMPLES}, got {}", self.samples),
            );
        }
        if !(self.k1.is_finite() && self.k1 != 0.0 && self.k1.abs() <= MAX_PLAN_K1) {
            return invalid(
                "k1",
                format!(
                    "must be non-zero and at most 1e9 in magnitude, got {}",
                    shown(self.k1)
                ),
            );
        }
        if let Some(p) = self
            .positions
            .iter()
            .find(|p| !p.iter().all(|x| x.is_finite() && x.abs() <= 1e3))
        {
            return invalid(
                "positions",
                format!("a specific force (g) of finite components, got {p:?}"),
            );
        }
        Ok(())
    }

    /// The positions as vectors (g, unit frame).
    pub fn position_vectors(&self) -> Vec<Vector3<f64>> {
        self.positions.iter().map(|p| Vector3::from(*p)).collect()
    }
}

impl crate::procedures::Plan for super::GfimuCalibrate {
    type Options = GfimuPlanOptions;

    fn plan(o: &GfimuPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document (`incal.plan/1`, procedure `gfimu-calibrate`):
/// `predicted_u` of every `NAME.K0` (output) and `NAME.Ks_x`, `NAME.Ks_y`,
/// `NAME.Ks_z` (output/g), the plan's own keys `plan`, `geometry`,
/// `positions` (g), `samples`, `noise`, `k1`, `motion` (rank, condition
/// number, solve mode of the array) and `warnings` of the calibration.
pub fn plan_document(o: &GfimuPlanOptions) -> Result<PlanDocument> {
    o.validate()?;
    let array = o.array.load()?;
    let g = &array.geometry;
    let label = &array.label;
    let positions = o.position_vectors();
    let cal = super::calibrate::plan(g, &positions, o.samples, o.noise, o.k1)
        .map_err(|e| Error::Unsupported(format!("{label}: {e}")))?;
    let d = g.check()?;
    let directions: Vec<Vector3<f64>> = g.accelerometers().iter().map(|a| a.direction).collect();
    let mode = super::solve::solve_mode(g, &directions, STANDARD_GRAVITY_M_S2)?;
    let mut doc = PlanDocument::new(
        crate::document::Procedure::GfimuCalibrate,
        format!(
            "Gyro-free unit calibration plan: {label}, {} positions x {} samples, noise {:e} per sample, K1 = {} output/g",
            o.positions.len(),
            o.samples,
            o.noise,
            o.k1
        ),
    );
    doc.with_options(o)?;
    doc.options.insert("geometry".into(), json!(label));
    for acc in &cal.accelerometers {
        for (k, term) in super::LINEAR_TERMS.iter().enumerate() {
            let unit = if k == 0 { "output" } else { "output/g" };
            doc.predict(&format!("{}.{term}", acc.name), acc.linear.u_at(k), unit)?;
        }
    }
    // Each accelerometer is its own fit of the same positions.
    doc.expect_dof(o.positions.len(), o.samples, super::LINEAR_TERMS.len());
    doc.set("plan", json!("gfimu"))?;
    doc.set("geometry", json!(label))?;
    doc.set("positions", json!(o.positions))?;
    doc.set("samples", json!(o.samples))?;
    doc.set("noise", json!(o.noise))?;
    doc.set("k1", json!(o.k1))?;
    doc.set(
        "motion",
        json!({
            "rank": d.rank,
            "condition_number": d.condition.is_finite().then_some(d.condition),
            "mode": mode.name(),
        }),
    )?;
    doc.set("warnings", json!(cal.warnings))?;
    Ok(doc)
}

/// The run sheet of a gyro-free unit plan: the direction of gravity in the
/// unit's frame at each position (`g_x`, `g_y`, `g_z`).
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::sheet_number as num;
    use serde_json::Value;
    let rows = d
        .plan
        .get("positions")
        .and_then(Value::as_array)
        .map(|ps| {
            ps.iter()
                .map(|p| {
                    p.as_array()
                        .map(|v| v.iter().filter_map(Value::as_f64).map(num).collect())
                        .unwrap_or_default()
                })
                .collect()
        })
        .unwrap_or_default();
    (vec!["g_x", "g_y", "g_z"], rows)
}
