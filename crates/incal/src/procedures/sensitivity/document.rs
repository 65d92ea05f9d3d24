//! The result document of a sensitivity session: the sensitivities as
//! coefficients (one block per output column); the `sensitivity` extra
//! (kind, rig, units, the noise model and the order rule per column);
//! the `sensitivity_runs` table (each run's stimulus, mean, u, fit and
//! residual) and, for shocks, the `shock` table (each shift with U95 and
//! En against the runs before it).

use serde_json::json;

use super::{coefficient_name, ColumnResult, Kind, SensitivityResult};
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::units::Unit;

impl SensitivityResult {
    /// The unit of a coefficient of column `c`.
    pub fn unit_of(&self, c: &ColumnResult, name: &str) -> Result<Unit> {
        let term = c
            .fit
            .terms
            .iter()
            .find(|t| coefficient_name(&t.name, c.label.as_deref()) == name);
        let Some(t) = term else {
            return Ok(Unit::One);
        };
        let top = if t.sf {
            "ppm"
        } else {
            self.options.report_unit()
        };
        Ok(Unit::Other(if t.per.is_empty() {
            top.to_string()
        } else {
            format!("{top}/{}", t.per)
        }))
    }

    /// The stimulus columns of the runs table.
    fn stimulus_columns(&self) -> Vec<(&'static str, Option<Unit>)> {
        let g = || Some(Unit::Other("g".into()));
        let mt = || Some(Unit::Other("mT".into()));
        match self.record.kind {
            Kind::Vibration => vec![
                ("vib_g_rms", g()),
                ("vib_freq_hz", Some(Unit::Other("Hz".into()))),
                ("vib_angle_deg", Some(Unit::Deg)),
            ],
            Kind::Magnetic => vec![
                ("field_x_mt", mt()),
                ("field_y_mt", mt()),
                ("field_z_mt", mt()),
            ],
            Kind::Shock | Kind::Auto => vec![("shock_g", g())],
        }
    }

    /// The `sensitivity_runs` table.
    fn runs_table(&self) -> Result<Table> {
        let out = || Some(Unit::Other(self.options.report_unit().into()));
        let mut cols: Vec<(String, Option<Unit>)> = vec![
            ("run".into(), None),
            ("start_s".into(), Some(Unit::Other("s".into()))),
            ("duration_s".into(), Some(Unit::Other("s".into()))),
            ("dropped".into(), Some(Unit::One)),
        ];
        cols.extend(
            self.stimulus_columns()
                .into_iter()
                .map(|(n, u)| (n.to_string(), u)),
        );
        let with_input = self.record.runs.iter().any(|r| r.input.is_some());
        if with_input {
            cols.push((
                "input".into(),
                Some(Unit::Other(self.options.input_unit().into())),
            ));
        }
        for c in &self.columns {
            let l = c
                .label
                .as_deref()
                .map_or(String::new(), |l| format!("_{l}"));
            for k in ["mean", "u", "fitted", "residual"] {
                cols.push((format!("{k}{l}"), out()));
            }
        }
        let spec: Vec<(&str, Option<Unit>)> =
            cols.iter().map(|(n, u)| (n.as_str(), u.clone())).collect();
        let mut t = Table::new(
            "sensitivity_runs",
            "Each run: its stimulus, its mean (the bias at that level) with u (the Allan deviation at the run's length), the fitted value and the residual",
            &spec,
        );
        for (i, r) in self.record.runs.iter().enumerate() {
            let s = &r.stimulus;
            let mut row = vec![
                Cell::text(&r.label),
                Cell::num(r.start_s),
                Cell::num(r.duration_s),
                Cell::num(r.dropped as f64),
            ];
            match self.record.kind {
                Kind::Vibration => row.extend([
                    Cell::num(s.vib_g_rms),
                    Cell::num(s.vib_freq_hz.unwrap_or(0.0)),
                    Cell::num(s.vib_angle_deg),
                ]),
                Kind::Magnetic => row.extend(s.field_mt.iter().map(|v| Cell::num(*v))),
                Kind::Shock | Kind::Auto => row.push(Cell::num(s.shock_g)),
            }
            if with_input {
                row.push(Cell::num(r.input.unwrap_or(0.0)));
            }
            for c in &self.columns {
                row.extend([
                    Cell::num(c.fit.y[i]),
                    Cell::num(c.noise.avar(r.duration_s).sqrt()),
                    Cell::num(c.fit.fitted[i]),
                    Cell::num(c.fit.y[i] - c.fit.fitted[i]),
                ]);
            }
            t.push(row)?;
        }
        Ok(t)
    }

    /// The `shock` table: each shift with U95 and En (shock sessions).
    fn shock_table(&self) -> Result<Option<Table>> {
        if self.record.kind != Kind::Shock {
            return Ok(None);
        }
        let mut t = Table::new(
            "shock",
            "The change across each shock against the runs before it, in the row's unit (the bias's, or ppm of the scale factor): En = |shift| / U95 (above 1: the shock moved it)",
            &[
                ("coefficient", None),
                ("shock_g", Some(Unit::Other("g".into()))),
                ("shift", None),
                ("u", None),
                ("U95", None),
                ("unit", None),
                ("En", Some(Unit::One)),
            ],
        );
        let levels: Vec<f64> = {
            let mut v: Vec<f64> = Vec::new();
            for r in &self.record.runs {
                if v.last() != Some(&r.stimulus.shock_g) {
                    v.push(r.stimulus.shock_g);
                }
            }
            v
        };
        for c in &self.columns {
            let e = &c.coefficients;
            let k = e.coverage_factor(0.95);
            for n in e.names() {
                let Some((v, u)) = e.get(n) else { continue };
                let p: usize = n
                    .trim_start_matches("shock_shift_")
                    .split('_')
                    .next()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(0);
                let big = k * u;
                let unit = if n.ends_with("_sf") {
                    "ppm"
                } else {
                    self.options.report_unit()
                };
                t.push(vec![
                    Cell::text(n),
                    Cell::num(levels.get(p).copied().unwrap_or(0.0)),
                    Cell::num(v),
                    Cell::num(u),
                    Cell::num(big),
                    Cell::text(unit),
                    Cell::num(if big > 0.0 { v.abs() / big } else { 0.0 }),
                ])?;
            }
        }
        Ok(Some(t))
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let o = &self.options;
        let summary: Vec<String> = self
            .columns
            .iter()
            .flat_map(|c| {
                let k = c.coefficients.coverage_factor(0.95);
                c.coefficients
                    .names()
                    .iter()
                    .take(3)
                    .map(|n| {
                        let (v, u) = c.coefficients.get(n).unwrap_or((0.0, 0.0));
                        format!("{n} = {v:.4} ± {:.2} (U95)", k * u)
                    })
                    .collect::<Vec<_>>()
            })
            .take(3)
            .collect();
        let mut b = DocumentBuilder::new(
            Procedure::Sensitivity,
            format!(
                "{} sensitivity ({} runs): {}",
                match self.record.kind {
                    Kind::Vibration => "Vibration",
                    Kind::Magnetic => "Magnetic",
                    Kind::Shock | Kind::Auto => "Shock",
                },
                self.record.runs.len(),
                summary.join(", ")
            ),
        );
        for c in &self.columns {
            b.estimates(&c.coefficients, "", |n| self.unit_of(c, n))?;
            let label = c.label.clone().unwrap_or_else(|| "runs".into());
            b.fit(FitSummary::of(&label, &c.fit.fit, Unit::One));
            b.warnings(c.fit.fit.quality_warnings(
                "the runs scatter about the model more than the noise allows: a stimulus level not held, the unit's temperature following the stimulus, or a higher order",
            ));
        }
        let first = &self.columns[0].noise;
        b.decision(
            DecisionCode::VarianceSource,
            format!(
                "run means weighted by their joint covariance from the output's noise (white, flicker and random walk fitted to the Allan variance pooled over the runs: bias instability {:.3e} {u}, white {:.3e} {u}·√s; {:.0} degrees of freedom), not sigma/sqrt(n)",
                first.bias_instability(),
                first.white.sqrt(),
                first.dof,
                u = o.report_unit()
            ),
        );
        let chosen: Vec<String> = self
            .columns
            .iter()
            .map(|c| {
                let t = c.fit.trials.last();
                match t {
                    Some(t) if !t.extras.is_empty() => {
                        format!("{} added by the lack-of-fit rule", t.extras.join(", "))
                    }
                    _ => "the base model passed the lack-of-fit test".into(),
                }
            })
            .collect();
        b.decision(DecisionCode::ModelDegree, chosen.join("; "));
        b.warnings(self.warnings.clone());
        b.extra("sensitivity", self.extra())?;
        b.table(self.runs_table()?);
        if let Some(t) = self.shock_table()? {
            b.table(t);
        }
        Ok(b.finish())
    }

    /// The `sensitivity` extra.
    fn extra(&self) -> serde_json::Value {
        let o = &self.options;
        json!({
            "kind": self.record.kind.as_str(),
            "sensor": o.sensor,
            "rig": o.rig,
            "unit": o.report_unit(),
            "input_unit": o.input_unit(),
            "sample_interval_s": self.record.dt_s,
            "runs": self.record.runs.len(),
            "columns": self.columns.iter().map(|c| json!({
                "column": c.column,
                "label": c.label,
                "noise": {
                    "white": c.noise.white,
                    "flicker": c.noise.flicker,
                    "walk": c.noise.walk,
                    "bias_instability": c.noise.bias_instability(),
                    "dof": c.noise.dof,
                    "allan": c.noise.points,
                },
                "order_rule": c.fit.trials,
                "terms": c.fit.terms.iter().map(|t| t.name.clone()).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
        })
    }
}
