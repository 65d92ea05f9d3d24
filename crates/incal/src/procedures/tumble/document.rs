//! The result document of a tumble calibration.

use serde_json::json;

use crate::document::variance_decision;
use crate::document::{
    position_stats, position_table, term_unit, Cell, DecisionCode, DocumentBuilder, FitSummary,
    Procedure, ResultDocument, Table, Warning, WarningCode,
};
use crate::error::Result;
use crate::estimation::Estimates;
use crate::procedures::tumble::TumbleResult;
use crate::units::{rad_to_arcsec, Unit};

/// Rows `term, value, u, U95, unit` of a set of term estimates (values in
/// the row's unit).
fn term_table(id: &str, title: &str, e: &Estimates) -> Result<Table> {
    let mut t = Table::new(
        id,
        title,
        &[
            ("term", None),
            ("value", None),
            ("u", None),
            ("U95", None),
            ("unit", None),
        ],
    );
    let k95 = e.coverage_factor(0.95);
    for (k, name) in e.names().iter().enumerate() {
        let u = e.u_at(k);
        t.push(vec![
            Cell::text(name.clone()),
            Cell::num(e.values()[k]),
            Cell::num(u),
            Cell::num(k95 * u),
            Cell::text(term_unit(name)?.as_str()),
        ])?;
    }
    Ok(t)
}

impl TumbleResult {
    /// The fitted model `E(θ) = a(θ)ᵀ p̂` on a grid of 3° (61 to 181
    /// points) over the angles tested, with `U95 = k95 sqrt(a(θ)ᵀ C a(θ))`
    /// of the linear fit: the report draws it as the model's curve.
    fn model_curve(&self) -> Result<Option<serde_json::Value>> {
        let (lo, hi) = self
            .positions
            .iter()
            .map(|p| p.angle_rad)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(t), b.max(t))
            });
        if hi.is_nan() || lo.is_nan() || hi <= lo {
            return Ok(None);
        }
        let n = (((hi - lo).to_degrees() / 3.0).ceil() as usize).clamp(60, 180) + 1;
        let grid = crate::document::grid(lo, hi, n);
        let d = super::design(self.mount, &self.terms, &grid)?;
        let deg: Vec<f64> = grid.iter().map(|t| t.to_degrees()).collect();
        Ok(Some(crate::document::model_curve(
            &deg,
            &d,
            &self.fit.estimates,
        )))
    }

    /// The result document (coefficients K0, K1, K2, … in g units, K1 in
    /// output/g, angles in rad; positions, pass comparisons; warnings).
    pub fn document(&self, known_noise: bool) -> Result<ResultDocument> {
        let f = &self.fit;
        let mut b = DocumentBuilder::new(
            Procedure::Tumble,
            format!(
                "Tumble calibration, {} mount ({} positions, {} terms)",
                self.mount.name(),
                f.diagnostics.n_obs,
                f.diagnostics.n_params
            ),
        );
        b.estimates(&self.coefficients, "", term_unit)?;
        b.fit(FitSummary::of("main", f, Unit::Output));
        b.option("mount", json!(self.mount.name()));
        b.option(
            "terms",
            json!(self.terms.iter().map(|t| t.name()).collect::<Vec<_>>()),
        );
        b.decision(
            DecisionCode::VarianceSource,
            variance_decision(f.variance_source, known_noise),
        );
        if let Some(e) = self.index_error_rad {
            b.decision(
                DecisionCode::ExcessVariance,
                if e > 0.0 {
                    format!(
                        "index-angle error of the head estimated from the residuals: {:.3} arcsec rms, included in u",
                        rad_to_arcsec(e)
                    )
                } else {
                    "index-angle error of the head: none detected beyond the sample scatter".into()
                },
            );
            b.extra("index_error_arcsec", json!(rad_to_arcsec(e)))?;
        }
        for a in &self.absorbed {
            b.decision(DecisionCode::Absorbed, a.to_string());
        }
        b.warnings(self.warnings.iter().cloned());
        for (label, e) in &self.pass_errors {
            b.warnings([Warning::new(
                WarningCode::PartFailed,
                format!("pass {label} alone: {e}"),
            )]);
        }

        let mut pos = position_table(
            "positions",
            "Positions",
            &[("angle", Some(Unit::Deg)), ("pass", None)],
        );
        for p in &self.positions {
            let mut row = vec![
                Cell::num(p.angle_rad.to_degrees()),
                p.pass.clone().map_or(Cell::Null, Cell::Text),
            ];
            row.extend(position_stats(
                &p.stats,
                p.residual,
                p.standardized_residual,
            ));
            pos.push(row)?;
        }
        b.table(pos);
        if let Some(curve) = self.model_curve()? {
            b.extra("model_curves", json!({ "positions": curve }))?;
        }
        for p in &self.passes {
            let pair = format!("{}-{}", p.other, p.reference);
            b.table(term_table(
                &format!("pass-difference.{pair}"),
                &format!(
                    "Pass difference: {} minus {} (u from both passes)",
                    p.other, p.reference
                ),
                &p.difference,
            )?);
            let mut t = Table::new(
                &format!("pass-positions.{pair}"),
                &format!(
                    "Per-angle mean output, {} minus {} (hysteresis, drift)",
                    p.other, p.reference
                ),
                &[
                    ("angle", Some(Unit::Deg)),
                    ("difference", Some(Unit::Output)),
                    ("u", Some(Unit::Output)),
                ],
            );
            for (a, d, u) in &p.position_differences {
                t.push(vec![
                    Cell::num(a.to_degrees()),
                    Cell::num(*d),
                    Cell::num(*u),
                ])?;
            }
            b.table(t);
        }
        Ok(b.finish())
    }
}
