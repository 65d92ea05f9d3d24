//! The result document of the gyro rate-transfer test.

use serde_json::json;

use super::{coefficient_unit, RateResult, RateTerm};
use crate::document::{
    position_stats, position_table, variance_decision, Cell, DecisionCode, Procedure,
    ResultDocument, Table,
};
use crate::error::{Error, Result};
use crate::procedures::gyro::DocumentHead;
use crate::units::Unit;

fn rate_unit(name: &str) -> Result<Unit> {
    match name {
        "asymmetry" | "K1_pos" | "K1_neg" => Ok(Unit::parse(coefficient_unit(name))),
        other => RateTerm::parse(other).map(|t| Unit::parse(t.unit())),
    }
}

impl RateResult {
    /// The result document: coefficients `K1`, `B`, `K2`, `K3` (those
    /// fitted), `asymmetry` (ppm), `K1_pos`, `K1_neg` (rates of both signs); top-level
    /// `nonlinearity_ppm_fs`; per-rate table; per-run K1.
    pub fn document(&self, known_noise: bool, rate_uncertainty_ppm: f64) -> Result<ResultDocument> {
        let f = &self.fit;
        let mut b = DocumentHead {
            procedure: Procedure::GyroRate,
            title: "Gyro rate-transfer test".into(),
            observations: "rates",
            terms: self.terms.iter().map(|t| t.name()).collect(),
            coefficients: &self.coefficients,
            dof: &self.dof,
            unit_of: rate_unit,
            fit: f,
            residual_unit: Unit::Output,
        }
        .builder()?;
        b.option("rate_uncertainty_ppm", json!(rate_uncertainty_ppm));
        b.decision(
            DecisionCode::VarianceSource,
            variance_decision(f.variance_source, known_noise),
        );
        if !self.nonlinearity_ppm_fs.is_finite() {
            return Err(Error::InvalidValue {
                what: "nonlinearity".into(),
                value: self.nonlinearity_ppm_fs.to_string(),
            });
        }
        b.extra("nonlinearity_ppm_fs", json!(self.nonlinearity_ppm_fs))?;
        self.range_document(&mut b)?;
        b.extra("full_scale_output", json!(self.full_scale_output))?;
        if let Some((ppm, dof)) = self.repeatability {
            b.extra(
                "scale_factor_repeatability",
                json!({"value": ppm, "unit": "ppm", "dof": dof, "runs": self.runs.len()}),
            )?;
        }
        b.warnings(self.warnings.iter().cloned());

        let mut pos = position_table(
            "positions",
            "Rates",
            &[
                ("rate", Some(Unit::DegPerS)),
                ("input_rate", Some(Unit::DegPerS)),
                ("run", None),
            ],
        );
        for p in &self.positions {
            let mut row = vec![
                Cell::num(p.rate_deg_s),
                Cell::num(p.input_deg_s),
                p.run.clone().map_or(Cell::Null, Cell::Text),
            ];
            row.extend(position_stats(
                &p.stats,
                p.residual,
                p.standardized_residual,
            ));
            pos.push(row)?;
        }
        b.table(pos);
        // The model's curve against the nominal rate (the input rate is
        // the nominal one plus Earth's constant projection).
        if self.positions.len() >= 2 {
            let n = self.positions.len() as f64;
            let offset = self
                .positions
                .iter()
                .map(|p| p.input_deg_s - p.rate_deg_s)
                .sum::<f64>()
                / n;
            let (lo, hi) = self
                .positions
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                    (a.min(p.rate_deg_s), b.max(p.rate_deg_s))
                });
            if lo < hi {
                let rates = crate::document::grid(lo, hi, 121);
                let inputs: Vec<f64> = rates.iter().map(|r| r + offset).collect();
                let d = super::design(&inputs, &self.terms, self.asymmetric)?;
                b.extra(
                    "model_curves",
                    json!({ "positions": crate::document::model_curve(&rates, &d, &self.fit.estimates) }),
                )?;
            }
        }
        let fs = self.full_scale_output;
        let mut line = Table::new(
            "nonlinearity",
            "Deviation of the mean output from the least-squares straight line (IEEE Std 952 nonlinearity)",
            &[
                ("input_rate", Some(Unit::DegPerS)),
                ("deviation", Some(Unit::Output)),
                ("deviation_ppm_fs", Some(Unit::Other("ppm".into()))),
            ],
        );
        for p in &self.positions {
            line.push(vec![
                Cell::num(p.input_deg_s),
                Cell::num(p.line_deviation),
                Cell::opt((fs > 0.0).then(|| p.line_deviation / fs * 1e6)),
            ])?;
        }
        b.table(line);
        if !self.runs.is_empty() {
            let mut t = Table::new(
                "runs",
                "Scale factor of each run alone",
                &[
                    ("run", None),
                    ("rates", None),
                    ("K1", Some(Unit::OutputPerDegS)),
                    ("u", Some(Unit::OutputPerDegS)),
                ],
            );
            for r in &self.runs {
                t.push(vec![
                    Cell::text(r.run.clone()),
                    Cell::num(r.rates as f64),
                    Cell::num(r.k1),
                    Cell::num(r.u),
                ])?;
            }
            b.table(t);
        }
        Ok(b.finish())
    }
}

impl RateResult {
    /// The input range as the coefficient `input_range_deg_s` (a tested
    /// rate: u = 0) and the `input_range` extra (the limit, the largest
    /// deviation within the range, the next tested rate, the rates beyond
    /// it and the clipped ones).
    fn range_document(&self, b: &mut crate::document::DocumentBuilder) -> Result<()> {
        if let Some(r) = &self.range {
            if let Some(v) = r.range_deg_s {
                b.coefficient(
                    "input_range_deg_s",
                    crate::document::Coefficient::new(
                        "input_range_deg_s",
                        v,
                        0.0,
                        Unit::DegPerS,
                        f64::INFINITY,
                    )?,
                )?;
                b.decision(
                    DecisionCode::ModelDegree,
                    format!(
                        "input range {v} deg/s: the largest tested input rate up to which every mean lies within {} ppm of the range's full-scale output from the straight line (largest {:.3} ppm){}",
                        r.linearity_ppm,
                        r.ppm_at_range.unwrap_or(0.0),
                        r.next_deg_s.map_or(String::new(), |n| format!("; at {n} deg/s it does not"))
                    ),
                );
            }
        }
        if self.range.is_some() || !self.clipped_deg_s.is_empty() {
            b.extra(
                "input_range",
                json!({
                    "linearity_ppm": self.range.as_ref().map(|r| r.linearity_ppm),
                    "input_range_deg_s": self.range.as_ref().and_then(|r| r.range_deg_s),
                    "ppm_at_range": self.range.as_ref().and_then(|r| r.ppm_at_range),
                    "next_rate_deg_s": self.range.as_ref().and_then(|r| r.next_deg_s),
                    "beyond_deg_s": self.beyond_deg_s,
                    "clipped_deg_s": self.clipped_deg_s,
                }),
            )?;
        }
        Ok(())
    }
}
