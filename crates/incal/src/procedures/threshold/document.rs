//! The result document of a threshold test: the threshold and the
//! resolution (and K1 when measured) as coefficients, the `threshold`
//! extra (sensor, levels, scale factor, noise, brackets) and the `steps`
//! table (each size's output change, response ratio and test).

use serde_json::json;

use super::input::Sensor;
use super::ThresholdResult;
use crate::document::{
    Cell, Coefficient, DecisionCode, DocumentBuilder, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::units::Unit;

/// The input's unit.
pub fn input_unit(s: Sensor) -> Unit {
    match s {
        Sensor::Gyro => Unit::DegPerS,
        Sensor::Accel => Unit::G,
    }
}

/// The unit of the scale factor.
pub fn scale_unit(s: Sensor) -> Unit {
    match s {
        Sensor::Gyro => Unit::OutputPerDegS,
        Sensor::Accel => Unit::OutputPerG,
    }
}

impl ThresholdResult {
    /// The `steps` table.
    fn table(&self) -> Result<Table> {
        let input = Some(input_unit(self.sensor));
        let mut t = Table::new(
            "steps",
            "Step sizes about each level: output change per unit input, response ratio to K1 and the one-sided test",
            &[
                ("level", None),
                ("size", input),
                ("transitions", Some(Unit::One)),
                ("change_per_input", Some(scale_unit(self.sensor))),
                ("ratio", Some(Unit::One)),
                ("u_ratio", Some(Unit::One)),
                ("p_value", Some(Unit::One)),
                ("passes", None),
            ],
        );
        for r in &self.responses {
            t.push(vec![
                Cell::text(match r.step.group {
                    super::levels::Group::Zero => "zero",
                    super::levels::Group::Base => "base",
                }),
                Cell::num(r.step.size),
                Cell::num(r.step.transitions.len() as f64),
                Cell::num(r.change_per_input),
                Cell::num(r.ratio.0),
                Cell::num(r.ratio.1),
                Cell::num(r.p_value),
                Cell::text(if r.passes { "yes" } else { "no" }),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let unit = self.sensor.unit();
        let found: Vec<String> = self
            .crossings
            .iter()
            .map(|c| format!("{} {:.3e} {unit}", c.group.name(), c.value.0))
            .collect();
        let mut b = DocumentBuilder::new(
            Procedure::Threshold,
            format!("Threshold test: {}", found.join(", ")),
        );
        for c in &self.crossings {
            let name = format!("{}_{}", c.group.name(), self.sensor.suffix());
            b.coefficient(
                &name,
                Coefficient::new(&name, c.value.0, c.value.1, input_unit(self.sensor), c.dof)?,
            )?;
        }
        if self.scale.coef.is_some() {
            b.coefficient(
                "K1",
                Coefficient::new(
                    "K1",
                    self.scale.value,
                    self.scale_u(),
                    scale_unit(self.sensor),
                    self.noise.dof,
                )?,
            )?;
        }
        b.decision(
            DecisionCode::VarianceSource,
            format!(
                "plateau means of n samples with variance s^2/n, s = {:.4e} (output units, {:.1} degrees of freedom) from {} differences between consecutive visits of the same level (zero or the base input): a two-sample variance at the plateaus' own length, drift between visits included",
                self.noise.var_long.sqrt(),
                self.noise.dof,
                self.noise.pairs
            ),
        );
        for c in &self.crossings {
            b.decision(
                DecisionCode::ModelDegree,
                format!(
                    "{}: every step from {:.4e} {unit} up passes the one-sided {} % test for reaching {:.0} % of K1 times the step, {:.4e} {unit} does not; {} {:.4e} and {:.4e} {unit}",
                    c.group.name(),
                    c.bracket.1,
                    100.0 * self.options.test_level,
                    100.0 * self.options.response_fraction,
                    c.bracket.0,
                    if c.interpolated {
                        "the 50 % point interpolated linearly in 1/step between the ratios that straddle it, at"
                    } else {
                        "the middle, with the rectangular u of their distance, of"
                    },
                    c.pair.0,
                    c.pair.1
                ),
            );
        }
        b.warnings(self.warnings.clone());
        b.extra("threshold", self.extra())?;
        b.table(self.table()?);
        Ok(b.finish())
    }

    /// The `threshold` extra.
    fn extra(&self) -> serde_json::Value {
        let brackets: serde_json::Map<String, serde_json::Value> = self
            .crossings
            .iter()
            .map(|c| {
                (
                    c.group.name().to_string(),
                    json!({
                        "largest_failing": c.bracket.0,
                        "smallest_passing": c.bracket.1,
                        "interpolated_between": [c.pair.0, c.pair.1],
                        "at_fraction": c.at_fraction,
                        "interval_95": [c.interval.0, c.interval.1],
                        "interpolated": c.interpolated,
                    }),
                )
            })
            .collect();
        json!({
            "sensor": self.sensor,
            "input_unit": self.sensor.unit(),
            "base_input": self.base_command,
            "scale_factor": {
                "value": self.scale.value,
                "u": self.scale_u(),
                "source": if self.scale.coef.is_some() { "measured" } else { "given" },
            },
            "plateaus": self.plateaus.len(),
            "noise_long_sd": self.noise.var_long.sqrt(),
            "noise_short_sd": self.noise.var_short.sqrt(),
            "noise_dof": self.noise.dof,
            "noise_pairs": self.noise.pairs,
            "brackets": brackets,
        })
    }
}
