//! The plan document (`incal.plan/1`): what `incal plan …` prints, one
//! typed document for every procedure, as the result document is for
//! reductions.
//!
//! ```json
//! {"schema": "incal.plan/1", "procedure": "tumble", "title": "…",
//!  "options": {…}, "predicted_u": {"K0": 1.7e-8, …}, "units": {"K0": "g", …},
//!  "notes": […], …the plan's own keys (angles_deg, step_deg, …)}
//! ```
//!
//! `predicted_u` maps each term to its predicted standard uncertainty in
//! the SI/g unit of `units` (engineering units only when rendered for
//! people); it is absent when the plan was asked without the inputs a
//! prediction needs. The plan's own keys (the positions, speeds or rates
//! chosen, the largest input, …) sit at the top level, as they always did.

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::Procedure;
use crate::error::{Error, Result};

/// Schema id of the plan document.
pub const PLAN_SCHEMA: &str = "incal.plan/1";

/// A test plan and the uncertainty it predicts (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct PlanDocument {
    /// Always `incal.plan/1`.
    pub schema: String,
    /// The procedure the plan is for.
    pub procedure: Procedure,
    /// One line for people.
    pub title: String,
    /// The options that shaped the plan (snake_case keys).
    pub options: BTreeMap<String, Value>,
    /// Predicted standard uncertainty of each term (the unit in `units`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub predicted_u: Option<BTreeMap<String, f64>>,
    /// Unit of each term of `predicted_u`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<BTreeMap<String, String>>,
    /// Degrees of freedom the reduction of this plan will give the
    /// coefficients: `P (S − 1)` from the pooled scatter of `S > 1`
    /// samples at each of `P` positions, else `P − p` from the residuals
    /// of the `p`-term fit ([`PlanDocument::expect_dof`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub predicted_dof: Option<f64>,
    /// Predicted expanded uncertainty `U95 = k95 u` of each term, with k95
    /// the Student t quantile for `predicted_dof` (JCGM 100 Annex G).
    #[serde(
        rename = "predicted_U95",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub predicted_u95: Option<BTreeMap<String, f64>>,
    /// Notes for the operator (what was assumed, what is not predicted).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// The plan's own keys (positions, speeds, rates, largest input, …).
    #[serde(flatten)]
    pub plan: BTreeMap<String, Value>,
}

/// Keys a plan's own fields may not take.
const RESERVED: &[&str] = &[
    "schema",
    "procedure",
    "title",
    "options",
    "predicted_u",
    "units",
    "predicted_dof",
    "predicted_U95",
    "notes",
];

impl PlanDocument {
    /// An empty plan document of `procedure`.
    pub fn new(procedure: Procedure, title: impl Into<String>) -> Self {
        Self {
            schema: PLAN_SCHEMA.to_string(),
            procedure,
            title: title.into(),
            options: BTreeMap::new(),
            predicted_u: None,
            units: None,
            predicted_dof: None,
            predicted_u95: None,
            notes: Vec::new(),
            plan: BTreeMap::new(),
        }
    }

    /// Set one of the plan's own keys.
    pub fn set(&mut self, key: &str, value: Value) -> Result<&mut Self> {
        if RESERVED.contains(&key) {
            return Err(Error::Unsupported(format!(
                "plan document: '{key}' is a reserved key"
            )));
        }
        self.plan.insert(key.to_string(), value);
        Ok(self)
    }

    /// Set the options (any value that serialises to a JSON object).
    pub fn with_options<T: Serialize>(&mut self, options: &T) -> Result<&mut Self> {
        self.options = crate::procedures::options_map(options)?;
        Ok(self)
    }

    /// Add the predicted u of one term; refuses a u that is not a positive
    /// finite number, naming the term (a plan never predicts 0 or inf).
    pub fn predict(&mut self, term: &str, u: f64, unit: &str) -> Result<&mut Self> {
        if !(u.is_finite() && u > 0.0) {
            return Err(Error::InvalidValue {
                what: format!("predicted u of {term} (the plan cannot determine it)"),
                value: u.to_string(),
            });
        }
        self.predicted_u
            .get_or_insert_with(BTreeMap::new)
            .insert(term.to_string(), u);
        self.units
            .get_or_insert_with(BTreeMap::new)
            .insert(term.to_string(), unit.to_string());
        Ok(self)
    }

    /// The degrees of freedom the reduction will have, from `positions`
    /// (distinct settings), `samples` per position and `parameters`
    /// fitted: `positions (samples − 1)` when `samples > 1` (the pooled
    /// scatter), else `positions − parameters` (the residuals). Sets
    /// `predicted_dof` and every term's `predicted_U95`; call it after the
    /// last [`PlanDocument::predict`].
    pub fn expect_dof(&mut self, positions: usize, samples: usize, parameters: usize) -> &mut Self {
        let dof = if samples > 1 {
            (positions * (samples - 1)) as f64
        } else {
            positions.saturating_sub(parameters) as f64
        };
        self.set_dof(dof)
    }

    /// The run sheet of the plan, for the operator: the settings in the
    /// order they are run (`step` from 1, then the procedure's settings and
    /// the samples to take), from the plan's own keys by the procedure's
    /// registry entry ([`crate::procedures::registry::Entry::run_sheet`]).
    /// `None` for a plan that lists no settings.
    pub fn run_sheet(&self) -> Option<(Vec<String>, Vec<Vec<String>>)> {
        let sheet = crate::procedures::registry::of(self.procedure).find_map(|e| e.run_sheet)?;
        let (columns, rows) = sheet(self);
        if rows.is_empty() {
            return None;
        }
        let samples = self
            .plan
            .get("samples")
            .or_else(|| self.options.get("samples"))
            .and_then(Value::as_u64)
            .unwrap_or(1)
            .to_string();
        let mut header = vec!["step".to_string()];
        header.extend(columns.iter().map(|c| c.to_string()));
        header.push("samples".into());
        let rows = rows
            .into_iter()
            .enumerate()
            .map(|(k, mut r)| {
                r.insert(0, (k + 1).to_string());
                r.push(samples.clone());
                r
            })
            .collect();
        Some((header, rows))
    }

    /// The run sheet ([`Self::run_sheet`]) as CSV text, quoted as every
    /// CSV incal writes; `InvalidOption` (`run_sheet`) for a plan that lists
    /// no settings to run.
    pub fn run_sheet_csv(&self) -> Result<String> {
        let Some((header, rows)) = self.run_sheet() else {
            return crate::options::invalid(
                "run_sheet",
                format!("a {} plan lists no settings to run", self.procedure),
            );
        };
        let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
        let bytes = (|| {
            let mut w = incal_io::writer::CsvWriter::new(Vec::new(), &hdr)?;
            for r in &rows {
                for c in r {
                    w.cell(incal_io::writer::Cell::Text(c))?;
                }
                w.end_row()?;
            }
            w.finish()
        })()
        .map_err(|e| Error::Write(format!("run sheet: {e}")))?;
        String::from_utf8(bytes).map_err(|e| Error::Write(format!("run sheet: {e}")))
    }

    /// Set the degrees of freedom the reduction will have and every
    /// term's `predicted_U95 = k95 u` (k95 the Student t quantile for
    /// `dof`, JCGM 100 Annex G); nothing for `dof < 1`. Call it after the
    /// last [`PlanDocument::predict`].
    pub fn set_dof(&mut self, dof: f64) -> &mut Self {
        if dof.is_nan() || dof < 1.0 {
            return self;
        }
        let k = crate::estimation::coverage_factor(dof, 0.95);
        self.predicted_dof = Some(dof);
        self.predicted_u95 = self
            .predicted_u
            .as_ref()
            .map(|u| u.iter().map(|(n, &x)| (n.clone(), k * x)).collect());
        self
    }

    /// Add a note for the operator.
    pub fn note(&mut self, text: impl Into<String>) -> &mut Self {
        self.notes.push(text.into());
        self
    }

    /// Compact JSON text.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
}

/// The JSON Schema of the plan document.
pub fn plan_json_schema() -> Value {
    let s = schemars::schema_for!(PlanDocument);
    serde_json::to_value(s).unwrap_or(Value::Null)
}

/// The numbers of the array `key` of `from` (a plan's own keys or its
/// options); empty when absent. For the procedures' run sheets.
pub fn values(from: &BTreeMap<String, Value>, key: &str) -> Vec<f64> {
    from.get(key)
        .and_then(Value::as_array)
        .map(|a| a.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

/// The texts of the array `key` of `from` (a non-string item as its JSON).
pub fn texts(from: &BTreeMap<String, Value>, key: &str) -> Vec<String> {
    from.get(key)
        .and_then(Value::as_array)
        .map(|a| {
            a.iter()
                .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
                .collect()
        })
        .unwrap_or_default()
}

/// A setting as a run sheet writes it: as Rust prints it, `-0` as `0`.
pub fn sheet_number(x: f64) -> String {
    let s = format!("{x}");
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}
