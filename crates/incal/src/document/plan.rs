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
