//! The result document of the gyro multi-position test.

use serde_json::json;

use super::{DriftTerm, PositionsResult, ScaleFactor};
use crate::document::{variance_decision, Cell, DecisionCode, Procedure, ResultDocument, Table};
use crate::error::Result;
use crate::procedures::gyro::DocumentHead;
use crate::units::Unit;

fn drift_unit(name: &str) -> Result<Unit> {
    if name == "K1" {
        return Ok(Unit::OutputPerDegS);
    }
    DriftTerm::parse(name).map(|t| Unit::parse(t.unit()))
}

impl PositionsResult {
    /// The result document: drift coefficients `B`, `D_I`, … (those fitted,
    /// deg/h, deg/h/g, deg/h/g²), `K1` when fitted; per-position table.
    pub fn document(
        &self,
        known_noise: bool,
        scale_factor: ScaleFactor,
        axial: &str,
    ) -> Result<ResultDocument> {
        let f = &self.fit;
        let fitted_k1 = matches!(scale_factor, ScaleFactor::Fit);
        let res_unit = if fitted_k1 {
            Unit::Output
        } else {
            Unit::Other("deg/h".into())
        };
        let mut b = DocumentHead {
            procedure: Procedure::GyroPositions,
            title: format!("Gyro multi-position test, {axial} axial"),
            observations: "positions",
            terms: self.terms.iter().map(|t| t.name()).collect(),
            coefficients: &self.coefficients,
            dof: &self.dof,
            unit_of: drift_unit,
            fit: f,
            residual_unit: res_unit.clone(),
        }
        .builder()?;
        b.option("axial", json!(axial));
        match scale_factor {
            ScaleFactor::Known { k1, u, dof } => {
                b.extra(
                    "scale_factor",
                    json!({"value": k1, "u": u, "unit": "output/(deg/s)", "dof": if dof.is_finite() { json!(dof) } else { json!(null) }, "source": "given"}),
                )?;
                b.decision(
                    DecisionCode::VarianceSource,
                    format!(
                        "{}; u(K1) propagated into every drift term",
                        variance_decision(f.variance_source, known_noise)
                    ),
                );
            }
            ScaleFactor::Fit => {
                b.decision(
                    DecisionCode::VarianceSource,
                    format!(
                        "{}; K1 fitted from the Earth-rate projection",
                        variance_decision(f.variance_source, known_noise)
                    ),
                );
            }
        }
        b.warnings(self.warnings.iter().cloned());
        let mut t = Table::new(
            "positions",
            "Positions",
            &[
                ("angle", Some(Unit::Deg)),
                ("azimuth", Some(Unit::Deg)),
                ("earth_rate_ia", Some(Unit::Other("deg/h".into()))),
                ("n", None),
                ("mean", Some(Unit::Output)),
                ("std", Some(Unit::Output)),
                ("residual", Some(res_unit)),
                ("standardized_residual", Some(Unit::One)),
            ],
        );
        for p in &self.positions {
            t.push(vec![
                Cell::num(p.angle_rad.to_degrees()),
                Cell::num(p.azimuth_rad.to_degrees()),
                Cell::num(p.earth_rate_deg_h),
                Cell::num(p.stats.n as f64),
                Cell::num(p.stats.mean),
                Cell::num(p.stats.std),
                Cell::num(p.residual),
                Cell::num(p.standardized_residual),
            ])?;
        }
        b.table(t);
        Ok(b.finish())
    }
}
