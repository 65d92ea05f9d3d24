//! The result document of a step response: the model's coefficients and
//! the step metrics, the located step, and the `step` table (the output
//! and the model around the step, at most 400 rows).

use serde_json::json;

use super::StepResult;
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::procedures::response::document::unit_of;
use crate::units::Unit;

impl StepResult {
    /// The `step` table: every k-th sample (at most 400 rows), time from
    /// the step, output, model and standardised residual.
    fn step_table(&self) -> Result<Table> {
        let o = |s: &str| Some(Unit::Other(s.into()));
        let mut t = Table::new(
            "step",
            "Step: output and model (time from the step)",
            &[
                ("time_s", o("s")),
                ("output", Some(Unit::Output)),
                ("model", Some(Unit::Output)),
                ("std_residual", Some(Unit::One)),
            ],
        );
        let n = self.record.output.len();
        let every = n.div_ceil(400).max(1);
        let p = self.fit.estimates.values();
        let r = &self.fit.residuals;
        let x = &p.as_slice()[1..];
        let a = self.located.r1 - self.located.r0;
        for k in (0..n).step_by(every) {
            let t_rel = k as f64 / self.rate_hz - self.located.t0_s;
            let m = p[0] + x[0] * a * super::unit_step(self.order, x, t_rel - x[x.len() - 1]);
            t.push(vec![
                Cell::num(t_rel),
                Cell::num(self.record.output[k]),
                Cell::num(m),
                Cell::num(r[k]),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::ResponseStep,
            format!(
                "Step response: a step of {:.6} at {:.6} s, {} order model with delay",
                self.located.r1 - self.located.r0,
                self.located.t0_s,
                self.order.name()
            ),
        );
        let unit = |n: &str| {
            if n.ends_with("_pct") {
                Ok(Unit::Other("%".into()))
            } else {
                unit_of(n)
            }
        };
        b.estimates(&self.coefficients, "", unit)?;
        b.fit(FitSummary::of("step", &self.fit, Unit::One));
        b.decision(
            DecisionCode::ModelDegree,
            format!("model order: {}", self.order_reason),
        );
        b.decision(
            DecisionCode::VarianceSource,
            format!(
                "each sample weighted by the output's scatter before the step ({:.4e}, {} samples); u(t0) = {:.3e} s from the reference's jump within one sample is in delay_s and latency_s",
                self.sigma, self.located.pre, self.located.u_t0_s
            ),
        );
        b.warnings(self.fit.quality_warnings(
            "the model order, a second step or drift in the record, or noise that changes after the step",
        ));
        b.extra(
            "step",
            json!({
                "t0_s": self.located.t0_s,
                "u_t0_s": self.located.u_t0_s,
                "reference_before": self.located.r0,
                "reference_after": self.located.r1,
                "output_sd": self.sigma,
                "settling_band_pct": self.options.settling_band_pct,
                "order": self.order.name(),
            }),
        )?;
        b.table(self.step_table()?);
        Ok(b.finish())
    }
}
