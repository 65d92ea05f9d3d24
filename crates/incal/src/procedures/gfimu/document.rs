//! The result document of a gyro-free unit calibration (GFIMU note).

use serde_json::{json, Map, Value};

use crate::document::variance_decision;
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::procedures::gfimu::GfimuCalibration;
use crate::units::Unit;

/// Unit of a per-accelerometer coefficient (`K0` in output, `*_rad` in
/// rad, the rest in output/g).
fn unit_of(name: &str) -> Unit {
    if name == "K0" {
        Unit::Output
    } else if name.ends_with("_rad") {
        Unit::Rad
    } else {
        Unit::OutputPerG
    }
}

impl GfimuCalibration {
    /// The result document: per accelerometer `NAME.K0` (output),
    /// `NAME.Ks_x`, `NAME.Ks_y`, `NAME.Ks_z` (output/g) and the derived
    /// `NAME.scale_factor`, `NAME.k1…k3` (output/g), `NAME.*_rad` (rad),
    /// each accelerometer one correlation block (independent data). The
    /// `accelerometers` object keeps the GFIMU note's contract that
    /// `gfimu solve --calibration` reads. `geometry` describes the array.
    pub fn document(&self, geometry: &str, known_noise: bool) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::GfimuCalibrate,
            format!(
                "Gyro-free unit calibration ({} positions, {} accelerometers)",
                self.positions.len(),
                self.accelerometers.len()
            ),
        );
        b.option("geometry", json!(geometry));
        let mut accs = Map::new();
        let mut summary = Table::new(
            "accelerometers",
            "Accelerometers (K0 check: largest difference of the three six-position K0 estimates, in u)",
            &[
                ("accelerometer", None),
                ("K0", Some(Unit::Output)),
                ("u_K0", Some(Unit::Output)),
                ("Ks_x", Some(Unit::OutputPerG)),
                ("Ks_y", Some(Unit::OutputPerG)),
                ("Ks_z", Some(Unit::OutputPerG)),
                ("scale_factor", Some(Unit::OutputPerG)),
                ("misalignment", Some(Unit::Rad)),
                ("u_misalignment", Some(Unit::Rad)),
                ("k0_check", Some(Unit::One)),
            ],
        );
        for a in &self.accelerometers {
            b.estimates(&a.joint, &format!("{}.", a.name), |n| Ok(unit_of(n)))?;
            b.fit(FitSummary::of(&a.name, &a.fit, Unit::Output));
            let l = &a.linear;
            let g = |n: &str| a.derived.get(n);
            let (mis, u_mis) = g("misalignment_rad").unzip();
            summary.push(vec![
                Cell::text(a.name.clone()),
                Cell::num(l.values()[0]),
                Cell::num(l.u_at(0)),
                Cell::num(l.values()[1]),
                Cell::num(l.values()[2]),
                Cell::num(l.values()[3]),
                Cell::opt(g("scale_factor").map(|x| x.0)),
                Cell::opt(mis),
                Cell::opt(u_mis),
                Cell::opt(a.k0_consistency.map(|k| k.max_normalized_difference)),
            ])?;
            let mut m = Map::new();
            m.insert(
                "K0".into(),
                json!({"value": l.values()[0], "u": l.u_at(0), "unit": "output"}),
            );
            m.insert(
                "Ks".into(),
                json!({
                    "value": [l.values()[1], l.values()[2], l.values()[3]],
                    "u": [l.u_at(1), l.u_at(2), l.u_at(3)],
                    "unit": "output/g",
                }),
            );
            let d = a.nominal_direction;
            m.insert("nominal_direction".into(), json!([d.x, d.y, d.z]));
            m.insert(
                "noise_output".into(),
                a.noise_output
                    .filter(|s| s.is_finite())
                    .map_or(Value::Null, |s| json!(s)),
            );
            m.insert(
                "k0_consistency".into(),
                a.k0_consistency.map_or(Value::Null, |k| {
                    json!({
                        "K0_x_pair": k.values[0], "K0_y_pair": k.values[1], "K0_z_pair": k.values[2],
                        "u": k.u,
                        "max_normalized_difference": k.max_normalized_difference,
                        "unit": "output",
                    })
                }),
            );
            accs.insert(a.name.clone(), Value::Object(m));
        }
        if let Some(a) = self.accelerometers.first() {
            b.decision(
                DecisionCode::VarianceSource,
                variance_decision(a.fit.variance_source, known_noise),
            );
        }
        b.extra("accelerometers", Value::Object(accs))?;
        b.table(summary);
        let mut pos = Table::new(
            "positions",
            "Static positions",
            &[("fx_g", None), ("fy_g", None), ("fz_g", None), ("n", None)],
        );
        for (f, n) in &self.positions {
            pos.push(vec![
                Cell::num(f.x),
                Cell::num(f.y),
                Cell::num(f.z),
                Cell::num(*n as f64),
            ])?;
        }
        b.table(pos);
        b.warnings(self.warnings.iter().cloned());
        Ok(b.finish())
    }
}
