//! The one result document of every procedure (schema `incal.result/1`).
//!
//! Every reducing procedure turns its result into a [`ResultDocument`]:
//! the coefficients as one flat map of typed parameters (value, standard
//! uncertainty u, unit, degrees of freedom, coverage factor k95 and
//! U95 = k95·u), their correlation matrix, the fits' diagnostics, the
//! procedure's tables as data, typed warnings and the decisions the tool
//! made. Consumers (the text renderer, `compare`, records, reports) are
//! written once against this shape, for every procedure.
//!
//! # Conventions
//! * Values are SI- or g-based (accelerations in local g, angles in rad,
//!   lengths in m) and each carries its [`Unit`] string; the text renderer
//!   converts to engineering units with [`Unit::engineering`].
//! * `u` is the standard uncertainty (JCGM 100 §2.3.1); `k95` the Student-t
//!   quantile `t_{0.975, ν}` for the coefficient's effective degrees of
//!   freedom ν (JCGM 100 Annex G; the normal 1.960 when ν is infinite,
//!   written `"dof": null`); `U95 = k95·u`.
//! * The correlation matrix covers every coefficient, in the order of
//!   `coefficients`. Blocks added separately ([`DocumentBuilder::estimates`])
//!   are independent (zero correlation between blocks); a procedure whose
//!   blocks share an input adds them as one joint block.
//! * No number in a document is non-finite: a value that is not available
//!   is `null` (in tables and optional fields) or absent.
//!
//! The JSON Schema of this type is checked into the repository at
//! `schema/result.schema.json` ([`json_schema`]).

pub mod compare;
pub mod file;
pub mod finish;
pub mod limits;
pub use crate::procedures::misalign::document as misalign;
/// The noise result document (lives with its procedure).
pub use crate::procedures::noise::document as noise;
mod builder;
mod check;
pub mod plan;
mod table;
pub use builder::*;
pub use table::*;

use std::collections::BTreeMap;

use nalgebra::DMatrix;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Error, Result};
use crate::estimation::{coverage_factor, Estimates, Fit, VarianceSource};
use crate::units::Unit;
pub use crate::warning::{Warning, WarningCode};

/// The schema identifier written in every document.
pub const SCHEMA: &str = "incal.result/1";

pub use crate::procedures::registry::Procedure;

/// Who the result is about. Extra `key: value` pairs (from `--meta`) sit
/// beside `serial` and `model`.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct Instrument {
    /// Serial number (`null` when not given).
    pub serial: Option<String>,
    /// Model or part number (`null` when not given).
    pub model: Option<String>,
    /// Further identity and conditions (`--meta key=value`).
    #[serde(flatten)]
    pub meta: BTreeMap<String, String>,
}

/// One input file: the path as given and the SHA-256 of its bytes, so a
/// result can be traced to its raw data.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct InputFile {
    /// What the file is to the procedure (`input`, `calibration`,
    /// `geometry`, `from`).
    pub role: String,
    /// The path as given on the command line (`-` for standard input).
    pub path: String,
    /// SHA-256 of the file's bytes, lower-case hex.
    pub sha256: String,
    /// Data rows used (`null` when not a table).
    pub rows: Option<u64>,
}

/// One estimated coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Coefficient {
    /// Estimate.
    pub value: f64,
    /// Standard uncertainty u (same unit).
    pub u: f64,
    /// Unit of `value`, `u` and `U95`.
    pub unit: Unit,
    /// Effective degrees of freedom of u; `null` = infinite (known variance).
    pub dof: Option<f64>,
    /// Coverage factor for 95 % (Student t with `dof`).
    pub k95: f64,
    /// Expanded uncertainty `U95 = k95 · u`.
    #[serde(rename = "U95")]
    pub u95: f64,
}

impl Coefficient {
    /// A coefficient from value, u, unit and degrees of freedom
    /// (`f64::INFINITY` or anything above 1e6 for a known variance).
    /// Fails when value or u is not finite or u is negative.
    pub fn new(name: &str, value: f64, u: f64, unit: Unit, dof: f64) -> Result<Self> {
        if !value.is_finite() || !u.is_finite() || u < 0.0 {
            return Err(Error::InvalidValue {
                what: format!("coefficient {name} (value, u)"),
                value: format!("{value}, {u}"),
            });
        }
        let k95 = coverage_factor(dof, 0.95);
        let dof = (dof.is_finite() && dof < 1e6).then_some(dof);
        Ok(Self {
            value,
            u,
            unit,
            dof,
            k95,
            u95: k95 * u,
        })
    }

    /// Degrees of freedom as a number (`f64::INFINITY` for `null`).
    pub fn dof_value(&self) -> f64 {
        self.dof.unwrap_or(f64::INFINITY)
    }
}

/// The coefficients, in the procedure's order; serialized as one JSON
/// object `{NAME: Coefficient}` in that order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Coefficients(Vec<(String, Coefficient)>);

impl Coefficients {
    /// Number of coefficients.
    pub fn len(&self) -> usize {
        self.0.len()
    }
    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    /// The coefficient called `name`.
    pub fn get(&self, name: &str) -> Option<&Coefficient> {
        self.0.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }
    /// `(name, coefficient)` in order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &Coefficient)> {
        self.0.iter().map(|(n, c)| (n.as_str(), c))
    }
    /// Names in order.
    pub fn names(&self) -> Vec<String> {
        self.0.iter().map(|(n, _)| n.clone()).collect()
    }
    fn push(&mut self, name: String, c: Coefficient) -> Result<()> {
        if self.get(&name).is_some() {
            return Err(Error::Unsupported(format!(
                "result document: coefficient {name} given twice"
            )));
        }
        self.0.push((name, c));
        Ok(())
    }
}

impl Serialize for Coefficients {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (n, c) in &self.0 {
            m.serialize_entry(n, c)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for Coefficients {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Coefficients;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object of coefficients {NAME: {value, u, unit, dof, k95, U95}}")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut a: A,
            ) -> std::result::Result<Coefficients, A::Error> {
                let mut out: Vec<(String, Coefficient)> = Vec::new();
                while let Some((k, v)) = a.next_entry::<String, Coefficient>()? {
                    if out.iter().any(|(n, _)| *n == k) {
                        return Err(serde::de::Error::custom(format!(
                            "coefficient {k} appears twice"
                        )));
                    }
                    out.push((k, v));
                }
                Ok(Coefficients(out))
            }
        }
        d.deserialize_map(V)
    }
}

impl JsonSchema for Coefficients {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Coefficients".into()
    }
    fn json_schema(g: &mut schemars::SchemaGenerator) -> schemars::Schema {
        let c = g.subschema_for::<Coefficient>();
        schemars::json_schema!({
            "type": "object",
            "description": "Every estimated coefficient by name, in the procedure's order.",
            "additionalProperties": c
        })
    }
}

/// Correlation matrix `ρ_jk = C_jk/(u_j u_k)` of the coefficients.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Correlation {
    /// Coefficient names, in the order of the rows and columns.
    pub names: Vec<String>,
    /// Symmetric matrix with unit diagonal (row-major lists).
    pub matrix: Vec<Vec<f64>>,
}

/// Diagnostics of one least-squares fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FitSummary {
    /// Which fit (`main`, a station, an accelerometer, …).
    pub label: String,
    /// Observations (position means).
    pub observations: usize,
    /// Fitted parameters.
    pub parameters: usize,
    /// Residual degrees of freedom `n − p`.
    pub dof: usize,
    /// Numerical rank of the design.
    pub rank: usize,
    /// Condition number of the column-equilibrated design.
    pub condition_number: Option<f64>,
    /// `Σ w r²` (χ² when the weights are inverse variances).
    pub chi2: Option<f64>,
    /// Lack-of-fit p-value `P(χ²_{n−p} ≥ Σ w r²)` (with known or scatter σ).
    pub chi2_p_value: Option<f64>,
    /// Where the variance factor came from.
    pub variance_source: VarianceSource,
    /// `sqrt(Σ r²/(n − p))` of the unweighted residuals (`null` when n = p).
    pub residual_rms: Option<f64>,
    /// Unit of the residuals.
    pub residual_unit: Unit,
    /// The combination of terms the design determines worst.
    pub weakest_combination: String,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

impl FitSummary {
    /// Summary of `fit` with residuals in `residual_unit`.
    pub fn of(label: &str, fit: &Fit, residual_unit: Unit) -> FitSummary {
        let rms = if fit.dof > 0 {
            (fit.residuals.norm_squared() / fit.dof as f64).sqrt()
        } else {
            f64::NAN
        };
        FitSummary {
            label: label.to_string(),
            observations: fit.diagnostics.n_obs,
            parameters: fit.diagnostics.n_params,
            dof: fit.dof,
            rank: fit.diagnostics.rank,
            condition_number: finite(fit.diagnostics.condition),
            chi2: finite(fit.weighted_rss),
            chi2_p_value: fit.chi2_p_value.and_then(finite),
            variance_source: fit.variance_source,
            residual_rms: finite(rms),
            residual_unit,
            weakest_combination: fit.diagnostics.weakest.combination(),
        }
    }
}

/// Why the tool decided something the user did not ask for explicitly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DecisionCode {
    /// Where the variance behind u came from (sample scatter, residuals,
    /// known noise).
    VarianceSource,
    /// A term not modelled that the plan cannot separate: the fitted
    /// coefficients absorb it.
    Absorbed,
    /// An error source estimated from the residuals and included in u
    /// (e.g. the dividing head's index-angle error).
    ExcessVariance,
    /// A coefficient the data cannot give, and why.
    NotDetermined,
    /// An input taken from another result (`--from`).
    ChainedInput,
    /// Terms the model fixes by construction (e.g. the off-diagonal
    /// elements of a diagonal gain matrix): not estimated, so not listed
    /// as coefficients.
    FixedByModel,
    /// The degree of a model chosen from the data (the thermal
    /// polynomials' degree rule), with the tests behind it.
    ModelDegree,
}

/// A decision the tool made, with its reason.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Decision {
    /// Stable code.
    pub code: DecisionCode,
    /// What was decided and why.
    pub message: String,
}

/// The result document of every procedure (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct ResultDocument {
    /// Always `incal.result/1` for this version of the shape.
    #[schemars(extend("const" = "incal.result/1"))]
    pub schema: String,
    /// The procedure.
    pub procedure: Procedure,
    /// A one-line title for people.
    pub title: String,
    /// Version of incal that wrote the document.
    pub incal_version: String,
    /// The instrument.
    pub instrument: Instrument,
    /// Input files with their hashes.
    pub inputs: Vec<InputFile>,
    /// The options that shaped the result (names with units, as on the
    /// command line without the leading dashes).
    pub options: BTreeMap<String, Value>,
    /// Every estimated coefficient.
    pub coefficients: Coefficients,
    /// Correlation of the coefficients.
    pub correlation: Correlation,
    /// Diagnostics of the fits behind the coefficients.
    pub fits: Vec<FitSummary>,
    /// The procedure's tables.
    pub tables: Vec<Table>,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// Decisions the tool made.
    pub decisions: Vec<Decision>,
    /// Each limited coefficient judged against its limits (with
    /// `--limits`; see [`limits`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdicts: Option<BTreeMap<String, limits::CoefficientVerdict>>,
    /// The overall verdict: the worst of `verdicts`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verdict: Option<limits::Verdict>,
    /// The decision rule behind the verdicts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decision_rule: Option<limits::DecisionRule>,
    /// The Monte Carlo propagation of distributions (JCGM 101), with
    /// `--monte-carlo` ([`crate::montecarlo`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<crate::montecarlo::MonteCarlo>,
    /// Procedure-specific top-level objects kept for their established
    /// contracts (`radius`, `alignment` of the centrifuge, `angles` of the
    /// misalignment tests, `accelerometers` of the gyro-free unit, …).
    #[serde(flatten)]
    pub extra: BTreeMap<String, Value>,
}

impl ResultDocument {
    /// Parse a document from JSON text, checking the schema id.
    /// Errors name the JSON path where possible.
    pub fn from_json(text: &str) -> std::result::Result<ResultDocument, String> {
        let v: Value = serde_json::from_str(text)
            .map_err(|e| format!("line {}: not valid JSON: {e}", e.line()))?;
        match v.get("schema").and_then(Value::as_str) {
            Some(SCHEMA) => {}
            Some(other) => {
                return Err(format!(
                    "$.schema: '{other}' is not a schema this version reads ({SCHEMA})"
                ))
            }
            None => return Err(format!("$.schema: missing: not an incal result ({SCHEMA})")),
        }
        // From the text, not the Value: the coefficients keep their order.
        let de = &mut serde_json::Deserializer::from_str(text);
        let doc: ResultDocument = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let path = if path == "." {
                "$".to_string()
            } else {
                format!("$.{path}")
            };
            let why = short_serde_message(&e.inner().to_string());
            format!("{path}: not a valid {SCHEMA} document: {why}")
        })?;
        doc.check()?;
        Ok(doc)
    }

    /// The largest magnitude a number of a document may have: beyond it,
    /// differences and plot ranges overflow (a report axis from −1e308 to
    /// 1e308 has an infinite span).
    pub const MAX_MAGNITUDE: f64 = 1e250;

    /// What the schema cannot say: every u and U95 not negative, U95 =
    /// k95·u (to 1e-9 relative, for rounding), k95 at least 1, dof
    /// positive, no number beyond [`Self::MAX_MAGNITUDE`], every table
    /// row as wide as its header, the correlation matrix square over
    /// distinct coefficients, symmetric with unit diagonal and |ρ| ≤ 1, and
    /// the recorded environment with min ≤ mean ≤ max. The error names the
    /// JSON path.
    pub fn check(&self) -> std::result::Result<(), String> {
        let big = |x: f64| x.is_nan() || x.abs() > Self::MAX_MAGNITUDE;
        for (name, c) in self.coefficients.iter() {
            let at = format!("$.coefficients.{name}");
            if big(c.value) {
                return Err(format!(
                    "{at}.value: {:e} is beyond 1e250 in magnitude",
                    c.value
                ));
            }
            if c.u < 0.0 || big(c.u) {
                return Err(format!(
                    "{at}.u: {:e} is not a standard uncertainty (0 to 1e250)",
                    c.u
                ));
            }
            if c.k95 < 1.0 || big(c.k95) {
                return Err(format!(
                    "{at}.k95: {} is not a coverage factor (at least 1)",
                    c.k95
                ));
            }
            if c.u95 < 0.0 || (c.u95 - c.k95 * c.u).abs() > 1e-9 * c.u95.abs().max(c.k95 * c.u) {
                return Err(format!(
                    "{at}.U95: {:e} is not k95 x u = {:e}",
                    c.u95,
                    c.k95 * c.u
                ));
            }
            if let Some(d) = c.dof {
                if d.is_nan() || d <= 0.0 {
                    return Err(format!(
                        "{at}.dof: {d} is not a positive number of degrees of freedom"
                    ));
                }
            }
        }
        for (t, table) in self.tables.iter().enumerate() {
            for (r, row) in table.rows.iter().enumerate() {
                if row.len() != table.columns.len() {
                    return Err(format!(
                        "$.tables[{t}].rows[{r}]: {} cells for {} columns",
                        row.len(),
                        table.columns.len()
                    ));
                }
                for (k, cell) in row.iter().enumerate() {
                    if let Cell::Number(x) = cell {
                        if big(*x) {
                            return Err(format!(
                                "$.tables[{t}].rows[{r}][{k}]: {x:e} is beyond 1e250 in magnitude"
                            ));
                        }
                    }
                }
            }
        }
        check::correlation(self)?;
        check::environment(self)
    }

    /// Pretty JSON text (ends without a newline).
    pub fn to_json(&self) -> String {
        // Serializing plain data with string keys cannot fail.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The covariance of two coefficients from the correlation matrix.
    pub fn covariance(&self, a: &str, b: &str) -> Option<f64> {
        let ia = self.correlation.names.iter().position(|n| n == a)?;
        let ib = self.correlation.names.iter().position(|n| n == b)?;
        let (ca, cb) = (self.coefficients.get(a)?, self.coefficients.get(b)?);
        // A document read from a file may hold a matrix of another size.
        let r = *self.correlation.matrix.get(ia)?.get(ib)?;
        Some(r * ca.u * cb.u)
    }

    /// Declare the instrument's output unit (`--output-unit V`): every
    /// unit that names the generic `output` (`output`, `output/g`,
    /// `output/(deg/s)`, …) in the coefficients, the fits' residuals, the
    /// tables' columns and the procedure objects is written with `unit`
    /// instead (`V`, `V/g`, `V/(deg/s)`), and `options.output_unit`
    /// records it. Values are unchanged: the recording was already in that
    /// unit; only its name is now known, so limits in it (`V/g`, `mV/g`)
    /// apply. Refuses an empty unit, one with spaces, commas or quotes, and
    /// a document whose output unit is already declared otherwise.
    pub fn declare_output_unit(&mut self, unit: &str) -> std::result::Result<(), String> {
        let ok = !unit.is_empty()
            && unit.len() <= 24
            && unit
                .chars()
                .all(|c| c.is_alphanumeric() || "%/._^()-*µ".contains(c));
        if !ok {
            return Err(format!(
                "--output-unit '{}': a unit such as V, mA, counts or LSB (letters, digits and % / . _ ^ ( ) - *, at most 24)",
                incal_io::clip(unit)
            ));
        }
        if let Some(had) = self.options.get("output_unit").and_then(Value::as_str) {
            if had != unit {
                return Err(format!(
                    "--output-unit {unit}: the result already has output unit {had}"
                ));
            }
            return Ok(());
        }
        let swap = |u: &Unit| -> Option<Unit> {
            let s = u.as_str();
            contains_word(s, "output").then(|| Unit::parse(&replace_word(s, "output", unit)))
        };
        for (_, c) in self.coefficients.0.iter_mut() {
            if let Some(n) = swap(&c.unit) {
                c.unit = n;
            }
        }
        for f in &mut self.fits {
            if let Some(n) = swap(&f.residual_unit) {
                f.residual_unit = n;
            }
        }
        for t in &mut self.tables {
            for c in &mut t.columns {
                if let Some(n) = c.unit.as_ref().and_then(swap) {
                    c.unit = Some(n);
                }
            }
        }
        fn walk(v: &mut Value, unit: &str) {
            match v {
                Value::Object(m) => {
                    for (k, x) in m.iter_mut() {
                        match x {
                            Value::String(s) if k == "unit" && contains_word(s, "output") => {
                                *s = replace_word(s, "output", unit);
                            }
                            _ => walk(x, unit),
                        }
                    }
                }
                Value::Array(a) => a.iter_mut().for_each(|x| walk(x, unit)),
                _ => {}
            }
        }
        for v in self.extra.values_mut() {
            walk(v, unit);
        }
        self.options
            .insert("output_unit".into(), Value::String(unit.to_string()));
        Ok(())
    }
}

/// True when `word` appears in `s` as a whole word (not inside a longer
/// identifier).
fn contains_word(s: &str, word: &str) -> bool {
    replace_word(s, word, "\u{0}") != s
}

/// `s` with every whole-word `word` replaced by `by`.
fn replace_word(s: &str, word: &str, by: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(i) = rest.find(word) {
        let before = rest[..i].chars().next_back();
        let after = rest[i + word.len()..].chars().next();
        let edge = |c: Option<char>| c.is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        out.push_str(&rest[..i]);
        if edge(before) && edge(after) {
            out.push_str(by);
        } else {
            out.push_str(word);
        }
        rest = &rest[i + word.len()..];
    }
    out.push_str(rest);
    out
}

/// The JSON Schema of [`ResultDocument`] (the file
/// `schema/result.schema.json` is this, pretty-printed).
pub fn json_schema() -> Value {
    let s = schemars::schema_for!(ResultDocument);
    serde_json::to_value(s).unwrap_or(Value::Null)
}

/// serde's message with a long list of expected names cut to its first
/// few: an unknown `procedure` would otherwise list every procedure and
/// the message outgrow one line.
fn short_serde_message(m: &str) -> String {
    const SHOWN: usize = 6;
    let Some(at) = m.find("expected one of ") else {
        return m.to_string();
    };
    let (head, list) = m.split_at(at + "expected one of ".len());
    let names: Vec<&str> = list.split(", ").collect();
    if names.len() <= SHOWN {
        return m.to_string();
    }
    format!(
        "{head}{}, … ({} in all)",
        names[..SHOWN].join(", "),
        names.len()
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DVector;

    fn block() -> Estimates {
        Estimates::new(
            vec!["K0".into(), "K1".into()],
            DVector::from_vec(vec![1e-3, 10.0]),
            DMatrix::from_row_slice(2, 2, &[1e-12, 5e-13, 5e-13, 1e-12]),
            6.0,
        )
        .unwrap()
    }

    #[test]
    fn a_declared_output_unit_renames_only_whole_words() {
        assert_eq!(replace_word("output/(deg/s)", "output", "V"), "V/(deg/s)");
        assert_eq!(replace_word("outputs/g", "output", "V"), "outputs/g");
        assert!(!contains_word("g/g^2", "output"));
        let mut b = DocumentBuilder::new(Procedure::Tumble, "t");
        b.estimates(&block(), "", term_unit).unwrap();
        let mut doc = b.finish();
        doc.declare_output_unit("mA").unwrap();
        assert_eq!(doc.coefficients.get("K1").unwrap().unit.as_str(), "mA/g");
        assert_eq!(doc.coefficients.get("K0").unwrap().unit.as_str(), "g");
        assert!(doc.declare_output_unit("V").is_err(), "already mA");
        assert!(doc.declare_output_unit("mA").is_ok());
        let mut d2 = doc.clone();
        d2.options.clear();
        assert!(d2.declare_output_unit("two words").is_err());
    }

    #[test]
    fn coefficients_carry_k95_and_u95_and_keep_their_order() {
        let mut b = DocumentBuilder::new(Procedure::Tumble, "t");
        b.estimates(&block(), "", term_unit).unwrap();
        let doc = b.finish();
        assert_eq!(doc.coefficients.names(), ["K0", "K1"]);
        let k0 = doc.coefficients.get("K0").unwrap();
        assert!((k0.k95 - 2.447).abs() < 1e-3);
        assert!((k0.u95 - k0.k95 * 1e-6).abs() < 1e-18);
        assert_eq!(k0.dof, Some(6.0));
        assert_eq!(doc.correlation.matrix[0][1], 0.5);
        let text = doc.to_json();
        let back = ResultDocument::from_json(&text).unwrap();
        assert_eq!(back, doc);
        // Order survives the round trip (K1 before K0 would be alphabetical).
        let v: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(v["schema"], SCHEMA);
        assert_eq!(v["coefficients"]["K0"]["U95"].as_f64(), Some(k0.u95));
    }

    #[test]
    fn non_finite_and_duplicate_coefficients_are_refused() {
        assert!(Coefficient::new("x", f64::NAN, 1.0, Unit::G, 1.0).is_err());
        assert!(Coefficient::new("x", 1.0, f64::INFINITY, Unit::G, 1.0).is_err());
        let mut b = DocumentBuilder::new(Procedure::Tumble, "t");
        b.estimates(&block(), "", term_unit).unwrap();
        assert!(b.estimates(&block(), "", term_unit).is_err());
        assert!(b.extra("coefficients", Value::Null).is_err());
    }

    #[test]
    fn infinite_dof_is_null_with_the_normal_quantile() {
        let c = Coefficient::new("x", 1.0, 0.1, Unit::G, f64::INFINITY).unwrap();
        assert_eq!(c.dof, None);
        assert!((c.k95 - 1.95996).abs() < 1e-4);
    }

    #[test]
    fn other_documents_are_refused_with_a_path() {
        assert!(ResultDocument::from_json("{}")
            .unwrap_err()
            .contains("$.schema"));
        assert!(ResultDocument::from_json(r#"{"schema": "x/2"}"#)
            .unwrap_err()
            .contains("x/2"));
    }

    /// Strict reading: an unknown key inside a coefficient, a fit or a
    /// warning is refused at its JSON path; the top level keeps
    /// procedure-specific objects.
    #[test]
    fn unknown_fields_are_refused_at_their_path() {
        let mut b = DocumentBuilder::new(Procedure::Tumble, "t");
        b.estimates(&block(), "", term_unit).unwrap();
        b.warnings([Warning::new(crate::WarningCode::ModelRange, "w")]);
        let text = b.finish().to_json();
        let v: Value = serde_json::from_str(&text).unwrap();
        let edit = |f: &dyn Fn(&mut Value)| {
            let mut w = v.clone();
            f(&mut w);
            ResultDocument::from_json(&w.to_string())
        };
        let e = edit(&|w| w["coefficients"]["K1"]["bogus"] = Value::from(1)).unwrap_err();
        assert!(e.starts_with("$.coefficients.K1.bogus: "), "{e}");
        let e = edit(&|w| w["warnings"][0]["extra"] = Value::from("x")).unwrap_err();
        assert!(e.starts_with("$.warnings[0].extra: "), "{e}");
        let e = edit(&|w| w["coefficients"]["K0"]["u"] = Value::from("x")).unwrap_err();
        assert!(e.starts_with("$.coefficients.K0.u: "), "{e}");
        assert!(edit(&|w| w["radius"] = Value::from(1.0)).is_ok());
        // An unknown procedure: serde's list of every name is cut short.
        let e = edit(&|w| w["procedure"] = Value::from("\u{feff}thermal")).unwrap_err();
        assert!(e.starts_with("$.procedure: "), "{e}");
        assert!(e.contains("in all)") && e.chars().count() < 300, "{e}");
    }
}
