//! The result document of a repeatability analysis: the mean, the
//! turn-on-to-turn-on and day-to-day standard deviations and
//! the standards' simple formula as coefficients (names the limits use:
//! `turn_on_repeatability`, `day_repeatability`, …), the `repeatability`
//! extra (method, the within-run part `√ū²` the runs bring, mean
//! squares, days) and the `runs` table.

use serde_json::json;

use super::{Component, Method, RepeatResult};
use crate::document::{
    Cell, Coefficient, DecisionCode, DocumentBuilder, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::units::Unit;
use crate::warning::{Warning, WarningCode};

impl RepeatResult {
    fn unit(&self) -> Unit {
        Unit::parse(&self.options.unit)
    }

    fn push(&self, b: &mut DocumentBuilder, name: &str, c: &Component) -> Result<()> {
        b.coefficient(name, Coefficient::new(name, c.sd, c.u, self.unit(), c.dof)?)?;
        Ok(())
    }

    /// The `runs` table: each run's day, value and u.
    fn table(&self) -> Result<Table> {
        let mut t = Table::new(
            "runs",
            "Runs: each turn-on's value and its own u",
            &[
                ("day", None),
                ("value", Some(self.unit())),
                ("u", Some(self.unit())),
            ],
        );
        for r in &self.runs {
            t.push(vec![
                Cell::Text(r.day.clone().unwrap_or_default()),
                Cell::num(r.value),
                Cell::num(r.u),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let mut b = DocumentBuilder::new(
            Procedure::Repeatability,
            format!(
                "Repeatability of {}: {} runs over {} day(s)",
                o.coefficient,
                self.runs.len(),
                self.days.len()
            ),
        );
        let n = self.runs.len() as f64;
        let dof_mean = if self.day.is_some() {
            self.days.len() as f64 - 1.0
        } else {
            n - 1.0
        };
        b.coefficient(
            "mean",
            Coefficient::new("mean", self.mean.0, self.mean.1, self.unit(), dof_mean)?,
        )?;
        if let Some(c) = &self.turn_on {
            self.push(&mut b, "turn_on_repeatability", c)?;
        }
        if let Some(c) = &self.day {
            self.push(&mut b, "day_repeatability", c)?;
        }
        self.push(&mut b, "repeatability_simple", &self.simple)?;
        let how = match self.method {
            Method::Anova => format!("nested analysis of variance (method of moments): the runs' u are within a factor of {:.2} of each other (at most 3)", self.u_ratio),
            Method::Weighted => format!("weighted: the runs' u differ by a factor of {:.2} (more than 3), so each level is weighted by 1/(u^2 + its component) (Paule-Mandel)", self.u_ratio),
        };
        b.decision(DecisionCode::VarianceSource, format!("{how}; each run's own u is its within-run variance; u of each standard deviation s/sqrt(2 nu) with nu by Satterthwaite"));
        if self.turn_on.is_none() {
            let msg = if self.day.is_some() {
                "turn_on_repeatability: every day has one run, so turn-on and day variation are one; day_repeatability holds both"
            } else {
                "turn_on_repeatability: not determined"
            };
            b.decision(DecisionCode::NotDetermined, msg);
        }
        if self.day.is_none() {
            b.decision(
                DecisionCode::NotDetermined,
                "day_repeatability: the runs carry no day (label them: a day column, --meta day=..., or the store's record dates)",
            );
        }
        let mut w = Vec::new();
        for (name, c) in [
            ("turn_on_repeatability", &self.turn_on),
            ("day_repeatability", &self.day),
        ] {
            if let Some(c) = c {
                if c.variance <= 0.0 {
                    w.push(Warning::new(WarningCode::NotSignificant, format!("{name}: its variance estimate {:.3e} is not above zero: reported as 0, not distinguishable from zero with these runs", c.variance)));
                }
            }
        }
        b.warnings(w);
        b.extra("repeatability", self.extra())?;
        b.table(self.table()?);
        Ok(b.finish())
    }

    fn extra(&self) -> serde_json::Value {
        let days: Vec<serde_json::Value> = self
            .days
            .iter()
            .map(|(d, ix)| {
                let m = ix.iter().map(|&k| self.runs[k].value).sum::<f64>() / ix.len() as f64;
                json!({"day": d, "runs": ix.len(), "mean": m})
            })
            .collect();
        let var = |c: &Option<Component>| c.map(|c| json!({"variance": c.variance, "dof": c.dof}));
        json!({
            "coefficient": self.options.coefficient,
            "method": self.method,
            "u_ratio": self.u_ratio,
            "ms_turn_on": self.anova.0.is_finite().then_some(self.anova.0),
            "ms_day": self.anova.1,
            "t0": (self.method == Method::Anova).then_some(self.anova.2),
            "within_run_sd": self.within.sd,
            "within_run_dof": self.within.dof.is_finite().then_some(self.within.dof),
            "turn_on": var(&self.turn_on),
            "day": var(&self.day),
            "days": days,
        })
    }
}
