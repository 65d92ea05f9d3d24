//! The result document of a warm-up: the curve's parameters, the settled
//! value, settling time, warm-up drift and turn-on time as coefficients,
//! the `warmup` extra (turn-on, blocks, noise, band, temperature) and the
//! `warmup` table (block means and the curve, at most 400 rows).

use serde_json::json;

use super::fit::{curve, Shape};
use super::WarmupResult;
use crate::document::{
    Cell, Coefficient, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::units::Unit;

/// The unit of a warm-up coefficient.
pub fn unit_of(name: &str) -> Result<Unit> {
    Ok(match name {
        "drift_per_s" => Unit::Other("output/s".into()),
        n if n.ends_with("_s") => Unit::Other("s".into()),
        _ => Unit::Output,
    })
}

impl WarmupResult {
    /// The `warmup` table: block mean times, means, the curve and the
    /// standardised residuals (every k-th block, at most 400 rows).
    fn table(&self) -> Result<Table> {
        let o = |s: &str| Some(Unit::Other(s.into()));
        let mut t = Table::new(
            "warmup",
            "Warm-up: block means and the fitted curve (time from power-on)",
            &[
                ("time_s", o("s")),
                ("output", Some(Unit::Output)),
                ("model", Some(Unit::Output)),
                ("std_residual", Some(Unit::One)),
            ],
        );
        let p = self.fit.estimates.values().as_slice();
        let model = self.blocks.model(self.shape, p);
        let time = self.blocks.time();
        let n = time.len();
        let every = n.div_ceil(400).max(1);
        for k in (0..n).step_by(every) {
            t.push(vec![
                Cell::num(time[k]),
                Cell::num(self.blocks.mean[k]),
                Cell::num(model[k]),
                Cell::num(self.fit.residuals[k]),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let p = self.fit.estimates.values().as_slice();
        let mut b = DocumentBuilder::new(
            Procedure::Warmup,
            format!(
                "Warm-up: turn-on at {:.3} s, settled value {:.6}, tau {:.1} s ({} curve)",
                self.turn_on.time_s,
                p[0],
                p[2],
                self.shape.name()
            ),
        );
        b.estimates(&self.coefficients, "", unit_of)?;
        b.coefficient(
            "turn_on_time_s",
            Coefficient::new(
                "turn_on_time_s",
                self.turn_on.time_s,
                self.turn_on.u_s,
                Unit::Other("s".into()),
                f64::INFINITY,
            )?,
        )?;
        b.fit(FitSummary::of("warmup", &self.fit, Unit::One));
        b.decision(
            DecisionCode::ModelDegree,
            format!("warm-up curve: {}", self.shape_reason),
        );
        b.decision(
            DecisionCode::VarianceSource,
            format!(
                "block means of {} rows ({:.6} s) weighted by the long-run variance of one sample, {:.4e} (output units squared, {:.0} degrees of freedom): batch means, {} or more over the longest valid run, of the residuals of the richest curve that fits; noise correlated over a batch is in u and in the lack-of-fit test",
                self.blocks.rows,
                self.blocks.rows as f64 / self.rate_hz,
                self.var_lr.0,
                self.var_lr.1,
                super::fit::BATCHES
            ),
        );
        b.warnings(self.fit.quality_warnings(
            "a warm-up that is not exponential, a temperature that moves, or steps in the output",
        ));
        b.warnings(self.warnings.clone());
        b.extra("warmup", self.extra())?;
        b.table(self.table()?);
        Ok(b.finish())
    }

    /// The `warmup` extra.
    fn extra(&self) -> serde_json::Value {
        let p = self.fit.estimates.values().as_slice();
        let settled_at_end = curve(self.shape, p, *self.blocks.t.last().unwrap_or(&0.0));
        json!({
            "power_on_s": self.options.power_on_s,
            "turn_on_row": self.turn_on.row,
            "first_valid_s": self.turn_on.first_valid_s,
            "valid_at_start": self.turn_on.valid_at_start,
            "shape": self.shape,
            "block_rows": self.blocks.rows,
            "block_s": self.blocks.rows as f64 / self.rate_hz,
            "blocks": self.blocks.mean.len(),
            "samples": self.samples.0,
            "samples_left_out": self.samples.1,
            "noise_long_run_sd": self.var_lr.0.sqrt(),
            "noise_edf": self.var_lr.1,
            "settle_band": self.settle_band,
            "first_window_s": self.options.first_window_s,
            "curve_at_end": settled_at_end,
            "two_exponentials": self.shape == Shape::Exp2 || self.shape == Shape::Exp2Drift,
            "temperature_c": self.temperature_c.map(|(m, lo, hi)| json!({"mean": m, "min": lo, "max": hi})),
        })
    }
}
