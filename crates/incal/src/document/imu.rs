//! The result documents of the IMU triad calibrations.

use serde_json::json;

use super::{Cell, DocumentBuilder, Procedure, ResultDocument, Table};
use crate::error::Result;
use crate::procedures::imu::ferraris::{FerrarisResult, QUANTITIES, SECTIONS};
use crate::procedures::imu::rows;
use crate::units::Unit;

/// Unit of a Ferraris element (`K_a.xy` → `output/(m/s^2)`).
pub fn ferraris_unit(name: &str) -> Result<Unit> {
    let q = name.split('.').next().unwrap_or(name);
    Ok(Unit::Other(
        match q {
            "K_a" | "K_ga" => "output/(m/s^2)",
            "K_g" => "output/(deg/s)",
            "R_a" | "R_g" => "1",
            _ => "output",
        }
        .into(),
    ))
}

/// The per-section statistics table (label, samples, means and scatter of
/// the six channels).
fn section_table(labels: &[&str], stats: &[crate::procedures::imu::SectionStats]) -> Result<Table> {
    let ch = ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"];
    let mut cols: Vec<(String, Option<Unit>)> =
        vec![("section".into(), None), ("samples".into(), None)];
    for c in ch {
        cols.push((format!("{c}_mean"), Some(Unit::Output)));
    }
    for c in ch {
        cols.push((format!("{c}_std"), Some(Unit::Output)));
    }
    let cols_ref: Vec<(&str, Option<Unit>)> =
        cols.iter().map(|(n, u)| (n.as_str(), u.clone())).collect();
    let mut t = Table::new(
        "sections",
        "Sections: samples, mean and standard deviation of each channel",
        &cols_ref,
    );
    for (l, s) in labels.iter().zip(stats) {
        let mut row = vec![Cell::text(*l), Cell::num(s.n as f64)];
        row.extend((0..6).map(|k| Cell::num(s.mean[k])));
        row.extend((0..6).map(|k| Cell::num(s.std(k))));
        t.push(row)?;
    }
    Ok(t)
}

impl FerrarisResult {
    /// The result document: every element as `K_a.xx`, `R_a.xy`, `b_a.x`,
    /// … in `coefficients` (with u, one correlation block), and the
    /// matrices at the top level in imucal's keys and definitions
    /// (`K_a`, `R_a`, `b_a`, `K_g`, `R_g`, `K_ga`, `b_g`; lists of rows),
    /// plus `acc_unit`, `gyr_unit` as imucal writes them.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let mut b = DocumentBuilder::new(
            Procedure::ImuFerraris,
            format!(
                "IMU Ferraris calibration (6 positions + 3 rotations of {} deg, g = {} m/s^2)",
                o.rotation_deg, o.gravity
            ),
        );
        b.estimates(&self.estimates, "", ferraris_unit)?;
        b.option("rate_hz", json!(o.rate_hz));
        b.option("gravity_m_s2", json!(o.gravity));
        b.option("rotation_deg", json!(o.rotation_deg));
        b.option("u_rotation_deg", json!(o.u_rotation_deg));
        let m = &self.matrices;
        for q in QUANTITIES {
            let v = match m.matrix(q) {
                Some(mm) => json!(rows(&mm)),
                None => {
                    let v = if q == "b_a" { m.b_a } else { m.b_g };
                    json!([v[0], v[1], v[2]])
                }
            };
            b.extra(q, v)?;
        }
        b.extra("acc_unit", json!("m/s^2"))?;
        b.extra("gyr_unit", json!("deg/s"))?;
        b.extra("cal_type", json!("Ferraris"))?;
        b.warnings(self.warnings.iter().cloned());
        b.table(section_table(&SECTIONS, &self.sections)?);
        Ok(b.finish())
    }
}
