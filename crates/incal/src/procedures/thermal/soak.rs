//! Soak (plateau) calibration: result documents of one instrument and one
//! procedure, each at its own temperature, into polynomials (1) of the
//! module docs, one per coefficient (`incal thermal fit`).
//!
//! Each input's temperature is `instrument.meta.temperature_c` (given
//! with `--meta temperature_c=T` when it was reduced) or else the mean of
//! the `temperature_c` column its reduction summarised
//! (`environment.temperature_c.mean`, written by every reduction whose
//! recording has that column).
//!
//! # Uncertainty
//! Each coefficient NAME is fitted to its plateau values with weights
//! `1/u_i²`; its polynomial `c = G y` has `C = s² G Σ Gᵀ`. Coefficients of
//! one run are correlated (their `correlation` matrix), so the
//! polynomials of two coefficients A and B are too:
//! `Cov(c_A, c_B) = s_A s_B G_A Σ_AB G_Bᵀ` with `Σ_AB = diag(ρ_i u_iA u_iB)`
//! (JCGM 100 §5.2, the linear propagation of the joint input covariance).
//! The compensated value at any T has `u² = gᵀ C g`, `g_k = (T − T_ref)^k`.

use serde_json::{json, Value};

pub use super::document::{compensated_table, degree_reason};
use super::document::{joint_estimates, plateau_table};
use super::{fit_with_degree, Degree, PolyFit, ThermalEntry, DEFAULT_T_REF_C};
use crate::document::{
    DecisionCode, DocumentBuilder, FitSummary, InputFile, Procedure, ResultDocument,
};
use crate::error::{Error, Result};
use crate::units::Unit;

/// Options of a soak fit. In the document: `t_ref_c`, `degree`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct SoakOptions {
    /// Reference temperature `T_ref`, °C.
    #[serde(default = "super::ramp::default_t_ref_c")]
    pub t_ref_c: f64,
    /// Degree of every polynomial, or the degree rule.
    #[serde(default)]
    pub degree: Degree,
}

impl Default for SoakOptions {
    fn default() -> Self {
        Self {
            t_ref_c: DEFAULT_T_REF_C,
            degree: Degree::Auto,
        }
    }
}

/// One input: its name (for messages and `inputs`), the SHA-256 of its
/// bytes, and the document.
#[derive(Debug, Clone)]
pub struct SoakInput {
    /// File name as given.
    pub name: String,
    /// SHA-256 of the file, hex.
    pub sha256: String,
    /// The result document.
    pub doc: ResultDocument,
}

/// The temperature a result document was obtained at, °C:
/// `instrument.meta.temperature_c`, else the mean of its recording's
/// `temperature_c` column (`environment.temperature_c.mean`).
pub fn temperature_of(doc: &ResultDocument) -> std::result::Result<f64, String> {
    if let Some(t) = doc.instrument.meta.get("temperature_c") {
        return t
            .trim()
            .parse::<f64>()
            .ok()
            .filter(|t| crate::units::check_temperature_c("temperature_c", *t).is_ok())
            .ok_or_else(|| {
                format!(
                    "$.instrument.temperature_c: '{}' is not a temperature in degC (absolute zero to 1000)",
                    incal_io::clip(t)
                )
            });
    }
    doc.extra
        .get("environment")
        .and_then(|e| e.get("temperature_c"))
        .and_then(|t| t.get("mean"))
        .and_then(Value::as_f64)
        .filter(|t| crate::units::check_temperature_c("temperature_c", *t).is_ok())
        .ok_or_else(|| {
            "no temperature: reduce it with --meta temperature_c=T, or from a recording with a temperature_c column"
                .to_string()
        })
}

/// Fit every coefficient of the inputs against temperature (module docs).
pub fn fit_documents(inputs: &[SoakInput], o: &SoakOptions) -> Result<ResultDocument> {
    let (first, temps) = check_inputs(inputs, o)?;
    let procedure = first.doc.procedure;
    let mut b = DocumentBuilder::new(
        Procedure::Thermal,
        format!("Thermal model of the {procedure} coefficients (soak)"),
    );
    let mut names = Vec::new();
    let mut fits: Vec<(String, Unit, PolyFit)> = Vec::new();
    let mut thermal = serde_json::Map::new();
    let mut selection = serde_json::Map::new();
    for (name, c0) in first.doc.coefficients.iter() {
        let Some(Plateaus { y, u, dof }) = plateau_values(inputs, first, name, &c0.unit)? else {
            b.decision(
                DecisionCode::NotDetermined,
                format!("{name}: not reported with a non-zero u by every input: no thermal model"),
            );
            continue;
        };
        let (f, trials) = fit_with_degree(name, &temps, &y, &u, &[], o.t_ref_c, o.degree, dof)?;
        b.decision(
            DecisionCode::ModelDegree,
            degree_reason(name, &f, o.degree, &trials),
        );
        b.warnings(
            f.fit
                .quality_warnings("the plateaus scatter about the polynomial more than their u (a higher degree, or drift between plateaus)")
                .into_iter()
                .map(|w| w.prefixed(name)),
        );
        b.fit(FitSummary::of(name, &f.fit, c0.unit.clone()));
        let entry = ThermalEntry {
            degree: f.degree,
            t_ref_c: o.t_ref_c,
            t_min_c: f.t_range_c.0,
            t_max_c: f.t_range_c.1,
            unit: c0.unit.as_str().to_string(),
            hysteresis: None,
            rate_term: None,
        };
        thermal.insert(
            name.to_string(),
            serde_json::to_value(&entry).unwrap_or(Value::Null),
        );
        selection.insert(name.to_string(), json!(trials));
        names.push((name.to_string(), y, u));
        fits.push((name.to_string(), c0.unit.clone(), f));
    }
    if fits.is_empty() {
        return Err(Error::Unsupported(format!(
            "{}: no coefficient with a non-zero u in every input",
            first.name
        )));
    }
    joint_estimates(&mut b, inputs, &fits)?;
    for ((name, unit, f), (_, y, u)) in fits.iter().zip(&names) {
        b.table(plateau_table(name, unit, f, &temps, y, u)?);
        b.table(compensated_table(name, unit, f)?);
    }
    b.extra("thermal", Value::Object(thermal))?;
    b.extra("degree_selection", Value::Object(selection))?;
    b.option("t_ref_c", json!(o.t_ref_c));
    b.option("degree", json!(o.degree));
    let mut doc = b.finish();
    doc.instrument = first.doc.instrument.clone();
    doc.instrument.meta.remove("temperature_c");
    doc.instrument
        .meta
        .insert("procedure".into(), procedure.as_str().into());
    doc.inputs = inputs
        .iter()
        .zip(&temps)
        .map(|(i, t)| InputFile {
            role: format!("result at {t} degC"),
            path: i.name.clone(),
            sha256: i.sha256.clone(),
            rows: None,
        })
        .collect();
    Ok(doc)
}

/// The options and inputs checked (a sane `T_ref`; at least one input,
/// all of one procedure other than thermal and of one instrument), and
/// the first input with every input's temperature ([`temperature_of`]).
fn check_inputs<'a>(inputs: &'a [SoakInput], o: &SoakOptions) -> Result<(&'a SoakInput, Vec<f64>)> {
    super::ramp::check_t_ref_c(o.t_ref_c)?;
    let Some(first) = inputs.first() else {
        return Err(Error::TooFew {
            what: "result documents".into(),
            needed: 2,
            got: 0,
        });
    };
    let procedure = first.doc.procedure;
    if procedure == Procedure::Thermal {
        return Err(Error::Unsupported(format!(
            "{}: a thermal result cannot be fitted against temperature again",
            first.name
        )));
    }
    let mut temps = Vec::with_capacity(inputs.len());
    for i in inputs {
        if i.doc.procedure != procedure {
            return Err(Error::Unsupported(format!(
                "{}: procedure {} differs from {} of {}: one thermal model is of one procedure",
                i.name, i.doc.procedure, procedure, first.name
            )));
        }
        if let (Some(a), Some(b)) = (&first.doc.instrument.serial, &i.doc.instrument.serial) {
            if a != b {
                return Err(Error::Unsupported(format!(
                    "{}: serial {b} differs from {a} of {}: one thermal model is of one instrument",
                    i.name, first.name
                )));
            }
        }
        temps.push(
            temperature_of(&i.doc).map_err(|m| Error::Unsupported(format!("{}: {m}", i.name)))?,
        );
    }
    Ok((first, temps))
}

/// Coefficient `name`'s value and u in every input, and the smallest of
/// their dof; `None` when an input lacks it or gives it no non-zero
/// finite u; an error when an input gives it in another unit than
/// `unit` (the first input's).
fn plateau_values(
    inputs: &[SoakInput],
    first: &SoakInput,
    name: &str,
    unit: &Unit,
) -> Result<Option<Plateaus>> {
    let mut y = Vec::new();
    let mut u = Vec::new();
    let mut dof = f64::INFINITY;
    let mut usable = true;
    for i in inputs {
        match i.doc.coefficients.get(name) {
            Some(c) if c.unit == *unit && c.u > 0.0 && c.u.is_finite() => {
                // A value a recording can give (the CSV reader's bound), and
                // a u the double precision of that value can carry: else
                // the fit's u would be round-off (0).
                let at = format!("{}: $.coefficients.{name}", i.name);
                let max = incal_io::MAX_ABS_VALUE;
                if !(c.value.abs() <= max && c.u <= max) {
                    return Err(Error::Unsupported(format!(
                        "{at}: value {:e} or u {:e} beyond {max:e} in magnitude (not a plateau incal fits)",
                        c.value, c.u
                    )));
                }
                if c.u < c.value.abs() * 1e-13 {
                    return Err(Error::Unsupported(format!(
                        "{at}.u: {:e} is below the precision of the value {:e} (13 digits)",
                        c.u, c.value
                    )));
                }
                y.push(c.value);
                u.push(c.u);
                dof = dof.min(c.dof_value());
            }
            Some(c) if c.unit != *unit => {
                return Err(Error::Unsupported(format!(
                    "{}: coefficient {name} in {} but {} in {}",
                    i.name, c.unit, unit, first.name
                )));
            }
            _ => usable = false,
        }
    }
    Ok(usable.then_some(Plateaus { y, u, dof }))
}

/// One coefficient at every plateau ([`plateau_values`]).
struct Plateaus {
    /// Its values.
    y: Vec<f64>,
    /// Their standard uncertainties.
    u: Vec<f64>,
    /// The smallest of their dof.
    dof: f64,
}
