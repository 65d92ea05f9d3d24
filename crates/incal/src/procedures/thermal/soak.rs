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

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use serde_json::{json, Value};

use super::{fit_with_degree, power_unit, Degree, PolyFit, ThermalEntry, DEFAULT_T_REF_C};
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, InputFile, Procedure, ResultDocument, Table,
};
use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::units::Unit;

/// Options of a soak fit.
#[derive(Debug, Clone, Serialize)]
pub struct SoakOptions {
    /// Reference temperature `T_ref`, °C.
    pub t_ref_c: f64,
    /// Degree of every polynomial, or the degree rule.
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
            .filter(|t| t.is_finite() && t.abs() < 1000.0)
            .ok_or_else(|| {
                format!("$.instrument.temperature_c: '{t}' is not a temperature in degC")
            });
    }
    doc.extra
        .get("environment")
        .and_then(|e| e.get("temperature_c"))
        .and_then(|t| t.get("mean"))
        .and_then(Value::as_f64)
        .filter(|t| t.is_finite())
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
    if !o.t_ref_c.is_finite() || o.t_ref_c.abs() > 500.0 {
        return Err(Error::InvalidValue {
            what: "t_ref_c (degC)".into(),
            value: o.t_ref_c.to_string(),
        });
    }
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

/// The polynomials' coefficients `NAME.ck` into the document as one joint
/// block: the polynomials of coefficients of one run are correlated
/// through the runs' own correlations (module docs), each coefficient
/// with its own fit's dof.
fn joint_estimates(
    b: &mut DocumentBuilder,
    inputs: &[SoakInput],
    fits: &[(String, Unit, PolyFit)],
) -> Result<()> {
    let sizes: Vec<usize> = fits.iter().map(|(_, _, f)| f.degree + 1).collect();
    let total: usize = sizes.iter().sum();
    let mut cov = DMatrix::zeros(total, total);
    let mut values = DVector::zeros(total);
    let mut coef_names = Vec::with_capacity(total);
    let mut at = Vec::with_capacity(fits.len());
    let mut pos = 0;
    for (name, _, f) in fits {
        at.push(pos);
        for k in 0..=f.degree {
            values[pos + k] = f.values[k];
            coef_names.push(format!("{name}.c{k}"));
        }
        pos += f.degree + 1;
    }
    for (ia, (na, _, fa)) in fits.iter().enumerate() {
        for (ib, (nb, _, fb)) in fits.iter().enumerate() {
            let (pa, pb) = (fa.degree + 1, fb.degree + 1);
            let block = if ia == ib {
                fa.covariance.view((0, 0), (pa, pa)).into_owned()
            } else {
                let s = DVector::from_fn(inputs.len(), |i, _| {
                    inputs[i].doc.covariance(na, nb).unwrap_or(0.0)
                });
                let ga = fa.gain.rows(0, pa);
                let gb = fb.gain.rows(0, pb);
                (ga * DMatrix::from_diagonal(&s) * gb.transpose())
                    * (fa.variance_factor * fb.variance_factor).sqrt()
            };
            cov.view_mut((at[ia], at[ib]), (pa, pb)).copy_from(&block);
        }
    }
    let dof_of: BTreeMap<String, f64> = fits
        .iter()
        .flat_map(|(name, _, f)| {
            let d = f.fit.estimates.dof();
            (0..=f.degree).map(move |k| (format!("{name}.c{k}"), d))
        })
        .collect();
    let unit_of: BTreeMap<String, Unit> = fits
        .iter()
        .flat_map(|(name, unit, f)| {
            (0..=f.degree).map(move |k| (format!("{name}.c{k}"), power_unit(unit, k)))
        })
        .collect();
    let e = Estimates::new(coef_names, values, cov, f64::INFINITY)?;
    b.estimates_dof(
        &e,
        "",
        |n| {
            unit_of
                .get(n)
                .cloned()
                .ok_or_else(|| Error::Unsupported(format!("no unit for {n}")))
        },
        |n| dof_of.get(n).copied().unwrap_or(f64::INFINITY),
    )?;
    Ok(())
}

/// Why a polynomial got its degree.
pub fn degree_reason(
    name: &str,
    f: &PolyFit,
    asked: Degree,
    trials: &[super::DegreeTrial],
) -> String {
    let tried: Vec<String> = trials
        .iter()
        .map(|t| match t.p_value {
            Some(p) => format!(
                "degree {}: chi2 {:.3} on {} dof, p {:.3}",
                t.degree, t.chi2, t.dof, p
            ),
            None => format!("degree {}: no residual dof", t.degree),
        })
        .collect();
    let how = match asked {
        Degree::Fixed(d) => format!("degree {d} as asked"),
        Degree::Auto => format!(
            "degree {} by the degree rule (smallest degree whose lack-of-fit p >= 0.05, at most min(3, plateaus - 2))",
            f.degree
        ),
    };
    format!("{name}: {how}; {}", tried.join("; "))
}

fn plateau_table(
    name: &str,
    unit: &Unit,
    f: &PolyFit,
    t: &[f64],
    y: &[f64],
    u: &[f64],
) -> Result<Table> {
    let mut tab = Table::new(
        &format!("plateaus.{name}"),
        &format!("{name} at each plateau: value, polynomial and residual"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("value", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("polynomial", Some(unit.clone())),
            ("residual", Some(unit.clone())),
            ("normalized_residual", Some(Unit::One)),
        ],
    );
    for i in 0..t.len() {
        let (p, _) = f.eval(t[i]);
        tab.push(vec![
            Cell::num(t[i]),
            Cell::num(y[i]),
            Cell::num(u[i]),
            Cell::num(p),
            Cell::num(y[i] - p),
            Cell::num((y[i] - p) / u[i]),
        ])?;
    }
    Ok(tab)
}

/// The compensated value over the valid range: `y(T)` with u and U95 at
/// eleven temperatures from `t_min` to `t_max`.
pub fn compensated_table(name: &str, unit: &Unit, f: &PolyFit) -> Result<Table> {
    let mut tab = Table::new(
        &format!("model.{name}"),
        &format!("{name} from the polynomial over the valid range, with its uncertainty"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("polynomial", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("U95", Some(unit.clone())),
        ],
    );
    let (lo, hi) = f.t_range_c;
    let k = crate::estimation::coverage_factor(f.fit.estimates.dof(), 0.95);
    for i in 0..=10 {
        let t = lo + (hi - lo) * i as f64 / 10.0;
        let (v, u) = f.eval(t);
        tab.push(vec![
            Cell::num(t),
            Cell::num(v),
            Cell::num(u),
            Cell::num(k * u),
        ])?;
    }
    Ok(tab)
}
