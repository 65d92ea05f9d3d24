//! Plans of a gyro-free unit calibration: the standard uncertainty every
//! accelerometer's K0 and Ks *will* have for a set of static positions
//! ([`super::calibrate::plan`], the calibration itself run on noise-free
//! samples with the noise known), and the conditioning of the array for
//! the motion solution (rank and condition number of the nominal N×6
//! system, and whether a sample is solved directly or with centripetal
//! feedback, [`super::solve::solve_mode`]).

use nalgebra::Vector3;
use serde_json::json;

use super::input::{shown, ArrayGeometry};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};
use crate::units::STANDARD_GRAVITY_M_S2;

/// Largest number of samples per position a plan takes.
pub const MAX_PLAN_SAMPLES: usize = 100_000_000;

/// Largest magnitude of the nominal scale factor (output/g).
pub const MAX_PLAN_K1: f64 = 1e9;

/// Options of a gyro-free unit calibration plan.
#[derive(Debug, Clone, PartialEq)]
pub struct GfimuPlanOptions {
    /// The array.
    pub array: ArrayGeometry,
    /// Static positions: the specific force (g, unit frame) of each.
    pub positions: Vec<Vector3<f64>>,
    /// Samples per position (1 ..= [`MAX_PLAN_SAMPLES`]).
    pub samples: usize,
    /// Standard deviation of one output sample (output, > 0).
    pub noise: f64,
    /// Nominal scale factor of every accelerometer (output/g; non-zero,
    /// at most [`MAX_PLAN_K1`] in magnitude).
    pub k1: f64,
}

impl serde::Serialize for GfimuPlanOptions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(5))?;
        m.serialize_entry("geometry", &self.array.label)?;
        let positions: Vec<[f64; 3]> = self.positions.iter().map(|f| [f.x, f.y, f.z]).collect();
        m.serialize_entry("positions", &positions)?;
        m.serialize_entry("samples", &self.samples)?;
        m.serialize_entry("noise", &self.noise)?;
        m.serialize_entry("k1", &self.k1)?;
        m.end()
    }
}

impl GfimuPlanOptions {
    /// Refuse a noise that is not positive, a sample count outside
    /// 1 ..= [`MAX_PLAN_SAMPLES`] and a zero, non-finite or huge `k1`,
    /// naming the option.
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Unsupported(msg));
        if !(self.noise.is_finite() && self.noise > 0.0) {
            return bad(format!(
                "noise must be a positive number, got {}",
                shown(self.noise)
            ));
        }
        if self.samples == 0 || self.samples > MAX_PLAN_SAMPLES {
            return bad(format!(
                "samples must be within 1..{MAX_PLAN_SAMPLES}, got {}",
                self.samples
            ));
        }
        if !(self.k1.is_finite() && self.k1 != 0.0 && self.k1.abs() <= MAX_PLAN_K1) {
            return bad(format!(
                "k1 must be non-zero and at most 1e9 in magnitude, got {}",
                shown(self.k1)
            ));
        }
        Ok(())
    }
}

/// The plan document (`incal.plan/1`, procedure `gfimu-calibrate`):
/// `predicted_u` of every `NAME.K0` (output) and `NAME.Ks_x`, `NAME.Ks_y`,
/// `NAME.Ks_z` (output/g), the plan's own keys `plan`, `geometry`,
/// `positions` (g), `samples`, `noise`, `k1`, `motion` (rank, condition
/// number, solve mode of the array) and `warnings` of the calibration.
pub fn plan_document(o: &GfimuPlanOptions) -> Result<PlanDocument> {
    o.validate()?;
    let g = &o.array.geometry;
    let label = &o.array.label;
    let cal = super::calibrate::plan(g, &o.positions, o.samples, o.noise, o.k1)
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
    doc.set(
        "positions",
        json!(o
            .positions
            .iter()
            .map(|f| [f.x, f.y, f.z])
            .collect::<Vec<_>>()),
    )?;
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
