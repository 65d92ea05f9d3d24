//! The result document of a magnetometer calibration: hard iron, soft
//! iron, the field's radius and, with an accelerometer, the alignment and
//! inclination as coefficients with their correlation; the `mag` extra
//! (session, coverage, noise, references) and the `mag_points` table (at
//! most [`POINTS`] readings, raw and calibrated, for the plots).

use serde_json::json;

use super::fit;
use super::MagResult;
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::units::Unit;

/// Rows of the `mag_points` table at most.
pub const POINTS: usize = 400;

impl MagResult {
    /// The unit of a coefficient.
    pub fn unit_of(&self, name: &str) -> Result<Unit> {
        let raw = self.options.unit.as_str();
        Ok(match name {
            n if n.starts_with("hard_iron") || n == "field_raw" => Unit::Other(raw.into()),
            n if n.starts_with("soft_iron") => Unit::Other(format!("{}/{raw}", self.output_unit())),
            "field_ut" => Unit::Other("uT".into()),
            n if n.ends_with("_deg") => Unit::Deg,
            _ => Unit::One,
        })
    }

    /// The `mag_points` table.
    fn table(&self) -> Result<Table> {
        let raw = || Some(Unit::Other(self.options.unit.as_str().into()));
        let out = || Some(Unit::Other(self.output_unit().into()));
        let mut t = Table::new(
            "mag_points",
            "Magnetometer readings, raw and calibrated, with the calibrated field's magnitude",
            &[
                ("row", Some(Unit::One)),
                ("raw_x", raw()),
                ("raw_y", raw()),
                ("raw_z", raw()),
                ("cal_x", out()),
                ("cal_y", out()),
                ("cal_z", out()),
                ("magnitude", out()),
            ],
        );
        let (soft, hard) = (self.soft_iron(), self.hard_iron());
        for (row, m) in &self.points {
            let b = soft * (m - hard);
            t.push(vec![
                Cell::num(*row as f64),
                Cell::num(m.x),
                Cell::num(m.y),
                Cell::num(m.z),
                Cell::num(b.x),
                Cell::num(b.y),
                Cell::num(b.z),
                Cell::num(b.norm()),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let h = self.hard_iron();
        let radius = self.coefficients.value("field_raw").unwrap_or(0.0);
        let mut b = DocumentBuilder::new(
            Procedure::Mag,
            format!(
                "Magnetometer calibration: hard iron ({:.4}, {:.4}, {:.4}) {u}, field radius {radius:.4} {u}, {} orientations",
                h.x,
                h.y,
                h.z,
                self.orientations,
                u = self.options.unit.as_str()
            ),
        );
        b.estimates(&self.coefficients, "", |n| self.unit_of(n))?;
        b.fit(FitSummary::of("mag", &self.solved.fit, Unit::One));
        let (sd, kappa) = self.solved.magnitude;
        let mut how = format!(
            "each block weighted by its residual variance times the inflation of its mean from the residuals' autocorrelation in time order: magnitude sd {:.3e} of the radius, inflation {kappa:.2}",
            sd
        );
        if let Some((sd, k)) = self.solved.dot {
            how.push_str(&format!(
                "; gravity-field angle sd {sd:.3e} (cosine), inflation {k:.2}"
            ));
        }
        how.push_str(&format!(
            "; {:.0} effective degrees of freedom",
            self.solved.dof
        ));
        b.decision(DecisionCode::VarianceSource, how);
        let scale = match self.options.field_ut {
            Some(f) => format!("scaled so that the calibrated field's magnitude is the local field, {f} uT"),
            None => "scaled to determinant 1: the calibrated field keeps the sensor's mean scale (its magnitude is field_raw)".into(),
        };
        b.decision(DecisionCode::FixedByModel, format!("soft-iron matrix symmetric (its rotation is the alignment's), {scale}; the fit's magnitude target is 1 + {:.2e} (the noise's bias on a magnitude)", self.solved.target - 1.0));
        b.warnings(self.solved.fit.quality_warnings(
            "a field that is not uniform over the session (iron near the rig, a current), motion during the rows at rest, or a magnetometer that is not linear",
        ));
        b.warnings(self.warnings.clone());
        b.extra("mag", self.extra())?;
        b.table(self.table()?);
        Ok(b.finish())
    }

    /// The `mag` extra.
    fn extra(&self) -> serde_json::Value {
        let (spread, axis) = self.coverage;
        let o = &self.options;
        json!({
            "unit": o.unit.as_str(),
            "output_unit": self.output_unit(),
            "axes": o.axes,
            "rows": self.rows.0,
            "rows_fitted": self.rows.1,
            "stride": self.rows.2,
            "orientations": self.orientations,
            "coverage_spread": spread,
            "coverage_axis": [axis.x, axis.y, axis.z],
            "condition": self.condition,
            "magnitude_target": self.solved.target,
            "magnitude_sd": self.solved.magnitude.0,
            "magnitude_inflation": self.solved.magnitude.1,
            "rest_rows": self.rest_rows,
            "angle_sd": self.solved.dot.map(|d| d.0),
            "angle_inflation": self.solved.dot.map(|d| d.1),
            "dof": self.solved.dof,
            "field_reference_ut": o.field_ut,
            "inclination_reference_deg": o.inclination_deg,
            "parameters": fit::HARD.iter().chain(fit::SOFT.iter()).collect::<Vec<_>>(),
        })
    }
}
