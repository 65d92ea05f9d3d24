//! Thermal calibration: coefficients as polynomials in temperature.
//!
//! # Model
//! A coefficient `y` (a bias, a scale factor, a misalignment, any
//! coefficient a reducing procedure reports) follows
//!
//! `y(T) = Σ_{k=0..d} c_k (T − T_ref)^k`                        (1)
//!
//! with `T` in °C, `T_ref` the reference temperature (25 °C unless
//! given) and `c_k` in the coefficient's unit per °C^k. IEEE Std 1293
//! (accelerometers) and IEEE Std 952 (FOG) define the temperature
//! sensitivity of bias and scale factor as `c_1`; PX4 and ArduPilot
//! compensate with polynomials of degree ≤ 3 in `(T − T_ref)` and clamp `T`
//! to the calibrated range; Niu X., Li Y., Zhang H., Wang Q., Ban Y., "Fast
//! thermal calibration of low-grade inertial sensors and inertial
//! measurement units", Sensors 13(9), 2013, fit bias, scale factor and
//! non-orthogonality against temperature from heating and cooling ramps.
//!
//! # Fit
//! The points `(T_i, y_i, u_i)` (one per plateau, or per block of a ramp)
//! are fitted by weighted least squares (weights `1/u_i²`, the one solver
//! of [`crate::estimation::linear`]) on the scaled variable
//! `x = (T − T_ref)/s`, `s = max(1 °C, max_i |T_i − T_ref|)`, so the
//! columns of the design stay of order one; `c_k = a_k / s^k`. The
//! variance factor follows incal's one lack-of-fit rule
//! ([`crate::estimation::linear::Variance::AtLeast`]): stated u unless the
//! residuals exceed them at the 5 % level.
//!
//! # Degree rule (`--degree auto`)
//! The smallest `d` in `0..=d_max` whose fit passes the lack-of-fit test
//! (`P(χ²_{n−p} ≥ Σ w r²) ≥ 0.05`, with `n − p ≥ 1`), where
//! `d_max = min(3, m − 2)` for `m` distinct temperatures: a polynomial is
//! never given more terms than the plateaus can both fit and check. When no
//! degree passes, `d_max` is taken and u is scaled by the residual scatter
//! (warning `lack-of-fit`). A true term whose effect over the range is
//! several times the points' u is found; one below u is missed (see the
//! tests for the measured rates).

pub mod apply;
pub mod document;
pub mod export;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod ramp;
pub mod sim;
pub mod soak;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::estimation::linear::{fit, Design, Fit, FitOptions, Variance, LACK_OF_FIT_ALPHA};
use crate::units::Unit;

/// The thermal calibration's test plan (soak plateaus or a chamber ramp,
/// [`plan`]) as one [`crate::procedures::Plan`]; the reductions are
/// [`ramp::Ramp`] (a recording) and [`soak::fit_documents`] (result
/// documents).
#[derive(Debug, Clone, Copy, Default)]
pub struct Thermal;

/// Highest polynomial degree incal fits (the flight stacks' cubic).
pub const MAX_DEGREE: usize = 3;

/// Default reference temperature, °C.
pub const DEFAULT_T_REF_C: f64 = 25.0;

/// Two temperatures closer than this (°C) are one plateau when counting
/// what a polynomial can be fitted to.
pub const SAME_PLATEAU_C: f64 = 0.05;

/// The degree of the temperature polynomials: chosen by the degree rule
/// (module docs) or fixed. At the edges `"auto"` or a whole number 0…3
/// (`"2"` is read as 2).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(into = "DegreeText", try_from = "DegreeText")]
pub enum Degree {
    /// The degree rule picks it, per coefficient.
    #[default]
    Auto,
    /// This degree for every coefficient (0..=3).
    Fixed(usize),
}

/// [`Degree`] as written: a whole number, or a word (`auto`, or a number
/// in a string).
#[derive(Debug, Clone, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(untagged)]
enum DegreeText {
    /// A fixed degree, 0 to 3.
    Number(usize),
    /// `auto` (or a degree in a string).
    Word(String),
}

impl From<Degree> for DegreeText {
    fn from(d: Degree) -> Self {
        match d {
            Degree::Auto => DegreeText::Word("auto".into()),
            Degree::Fixed(d) => DegreeText::Number(d),
        }
    }
}

impl TryFrom<DegreeText> for Degree {
    type Error = String;

    fn try_from(t: DegreeText) -> std::result::Result<Self, String> {
        match t {
            DegreeText::Number(d) => Degree::parse(&d.to_string()),
            DegreeText::Word(w) => Degree::parse(&w),
        }
    }
}

impl Degree {
    /// Parse `auto` or `0`..`3`.
    pub fn parse(s: &str) -> std::result::Result<Degree, String> {
        let s = s.trim();
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Degree::Auto);
        }
        match s.parse::<usize>() {
            Ok(d) if d <= MAX_DEGREE => Ok(Degree::Fixed(d)),
            _ => Err(format!(
                "degree '{s}': give auto or a whole number from 0 to {MAX_DEGREE}"
            )),
        }
    }
}

impl std::fmt::Display for Degree {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Degree::Auto => f.write_str("auto"),
            Degree::Fixed(d) => write!(f, "{d}"),
        }
    }
}

/// The unit of `c_k` for a coefficient in `unit`: `unit` for k = 0,
/// `unit/degC` for k = 1, `unit/degC^k` beyond.
pub fn power_unit(unit: &Unit, k: usize) -> Unit {
    match k {
        0 => unit.clone(),
        1 => Unit::Other(format!("{}/degC", unit.as_str())),
        k => Unit::Other(format!("{}/degC^{k}", unit.as_str())),
    }
}

/// Number of distinct temperatures (closer than [`SAME_PLATEAU_C`] count
/// once).
pub fn distinct_temperatures(t_c: &[f64]) -> usize {
    let mut t: Vec<f64> = t_c.iter().copied().filter(|v| v.is_finite()).collect();
    t.sort_by(f64::total_cmp);
    let mut n = 0;
    let mut last = f64::NEG_INFINITY;
    for v in t {
        if v - last > SAME_PLATEAU_C {
            n += 1;
            last = v;
        }
    }
    n
}

/// A weighted polynomial fit (1) in `T − T_ref`, with extra regressors
/// (hysteresis, `dT/dt`) after the powers.
#[derive(Debug, Clone)]
pub struct PolyFit {
    /// Degree `d`.
    pub degree: usize,
    /// `T_ref`, °C.
    pub t_ref_c: f64,
    /// Names: `c0`…`cd`, then the extra regressors'.
    pub names: Vec<String>,
    /// `c_0`…`c_d` (unit per °C^k), then the extra coefficients.
    pub values: DVector<f64>,
    /// Covariance of `values` (variance factor applied).
    pub covariance: DMatrix<f64>,
    /// Gain `G` with `values = G y`: `G = (AᵀWA)⁻¹AᵀW` in the units of
    /// the coefficients (for covariances with other fits on the same
    /// points: `Cov(a, b) = G_a Σ_ab G_bᵀ`).
    pub gain: DMatrix<f64>,
    /// Variance factor `s²` applied (1 unless lack of fit).
    pub variance_factor: f64,
    /// The solver's fit (diagnostics, residuals, χ²).
    pub fit: Fit,
    /// Lowest and highest temperature of the points, °C.
    pub t_range_c: (f64, f64),
}

impl PolyFit {
    /// `y(T)` of (1) without the extra regressors, and its standard
    /// uncertainty `sqrt(gᵀ C g)`, `g_k = (T − T_ref)^k`.
    pub fn eval(&self, t_c: f64) -> (f64, f64) {
        let g = self.powers(t_c);
        let p = self.degree + 1;
        let c = self.covariance.view((0, 0), (p, p));
        let v = (0..p).map(|k| self.values[k] * g[k]).sum();
        let var = (&g.transpose() * c * &g)[(0, 0)];
        (v, var.max(0.0).sqrt())
    }

    fn powers(&self, t_c: f64) -> DVector<f64> {
        let dt = t_c - self.t_ref_c;
        DVector::from_fn(self.degree + 1, |k, _| dt.powi(k as i32))
    }

    /// Residual degrees of freedom of the fit.
    pub fn dof(&self) -> usize {
        self.fit.dof
    }

    /// The lack-of-fit p-value (None when n = p).
    pub fn p_value(&self) -> Option<f64> {
        self.fit.chi2_p_value
    }
}

/// Evaluate (1) for coefficients `c` at `t_c`.
pub fn poly(c: &[f64], t_ref_c: f64, t_c: f64) -> f64 {
    let dt = t_c - t_ref_c;
    c.iter().rev().fold(0.0, |acc, ck| acc * dt + ck)
}

/// Fit (1) of degree `degree`, with `extra` regressors `(name, column)`,
/// to `y` with standard uncertainties `u`; `prior_dof` is the degrees of
/// freedom behind the `u` (∞ when known).
pub fn fit_poly(
    t_c: &[f64],
    y: &[f64],
    u: &[f64],
    extra: &[(String, Vec<f64>)],
    t_ref_c: f64,
    degree: usize,
    prior_dof: f64,
) -> Result<PolyFit> {
    let n = t_c.len();
    if y.len() != n || u.len() != n || extra.iter().any(|(_, c)| c.len() != n) {
        return Err(Error::Unsupported(
            "thermal fit: temperatures, values and uncertainties differ in length".into(),
        ));
    }
    if let Some(t) = t_c.iter().find(|t| !t.is_finite()) {
        return Err(Error::InvalidValue {
            what: "temperature".into(),
            value: t.to_string(),
        });
    }
    let s = t_c
        .iter()
        .map(|t| (t - t_ref_c).abs())
        .fold(1.0_f64, f64::max);
    let p = degree + 1 + extra.len();
    let mut names: Vec<String> = (0..=degree).map(|k| format!("c{k}")).collect();
    names.extend(extra.iter().map(|(n, _)| n.clone()));
    let a = DMatrix::from_fn(n, p, |i, j| {
        if j <= degree {
            ((t_c[i] - t_ref_c) / s).powi(j as i32)
        } else {
            extra[j - degree - 1].1[i]
        }
    });
    let design = Design::new(names.clone(), a.clone())?;
    let w = DVector::from_fn(n, |i, _| 1.0 / (u[i] * u[i]));
    let f = fit(
        &design,
        &DVector::from_column_slice(y),
        &FitOptions {
            weights: Some(w.clone()),
            variance: Variance::AtLeast { dof: prior_dof },
            ..FitOptions::default()
        },
    )?;
    // Back from the scaled powers: c_k = a_k / s^k.
    let scale = DVector::from_fn(p, |j, _| {
        if j <= degree {
            s.powi(-(j as i32))
        } else {
            1.0
        }
    });
    let jac = DMatrix::from_diagonal(&scale);
    let values = f.estimates.values().component_mul(&scale);
    let covariance = &jac * f.estimates.covariance() * &jac;
    let unit_cov = f.estimates.covariance() / f.variance_factor;
    let mut aw = a.transpose();
    for (i, mut col) in aw.column_iter_mut().enumerate() {
        col *= w[i];
    }
    let gain_a = &unit_cov * aw;
    let gain = &jac * gain_a;
    let lo = t_c.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = t_c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok(PolyFit {
        degree,
        t_ref_c,
        names,
        values,
        covariance,
        gain,
        variance_factor: f.variance_factor,
        fit: f,
        t_range_c: (lo, hi),
    })
}

/// One step of the degree rule: the degree tried, its χ², dof and p.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DegreeTrial {
    /// Degree tried.
    pub degree: usize,
    /// `Σ w r²`.
    pub chi2: f64,
    /// `n − p`.
    pub dof: usize,
    /// Lack-of-fit p-value.
    pub p_value: Option<f64>,
}

/// The highest degree the points support: `min(3, m − 2)` for `m`
/// distinct temperatures and `extras` extra regressors (one residual
/// degree of freedom left to check the fit), or `None` when even degree 0
/// cannot be checked.
pub fn supported_degree(t_c: &[f64], extras: usize) -> Option<usize> {
    let m = distinct_temperatures(t_c);
    let n = t_c.len();
    let by_plateaus = m.checked_sub(2)?;
    let by_points = n.checked_sub(2 + extras)?;
    Some(MAX_DEGREE.min(by_plateaus).min(by_points))
}

/// Fit with the degree `degree` (fixed, refused when the distinct
/// temperatures cannot give it, naming `what.c<d>`) or chosen by the
/// degree rule (module docs). Returns the fit and the trials.
#[allow(clippy::too_many_arguments)]
pub fn fit_with_degree(
    what: &str,
    t_c: &[f64],
    y: &[f64],
    u: &[f64],
    extra: &[(String, Vec<f64>)],
    t_ref_c: f64,
    degree: Degree,
    prior_dof: f64,
) -> Result<(PolyFit, Vec<DegreeTrial>)> {
    let m = distinct_temperatures(t_c);
    match degree {
        Degree::Fixed(d) => {
            if d + 1 > m {
                return Err(Error::Unsupported(format!(
                    "{m} distinct temperature(s) cannot separate {what}.c{d}: a polynomial of degree {d} needs at least {} plateaus",
                    d + 1
                )));
            }
            let f = fit_poly(t_c, y, u, extra, t_ref_c, d, prior_dof)?;
            let trial = DegreeTrial {
                degree: d,
                chi2: f.fit.weighted_rss,
                dof: f.fit.dof,
                p_value: f.fit.chi2_p_value,
            };
            Ok((f, vec![trial]))
        }
        Degree::Auto => {
            let Some(d_max) = supported_degree(t_c, extra.len()) else {
                return Err(Error::Unsupported(format!(
                    "{m} distinct temperature(s) cannot separate {what}.c1 (the temperature sensitivity) and check the fit: the degree rule needs at least 2 plateaus; give --degree 0 for a mean"
                )));
            };
            let mut trials = Vec::new();
            let mut last = None;
            for d in 0..=d_max {
                let f = fit_poly(t_c, y, u, extra, t_ref_c, d, prior_dof)?;
                trials.push(DegreeTrial {
                    degree: d,
                    chi2: f.fit.weighted_rss,
                    dof: f.fit.dof,
                    p_value: f.fit.chi2_p_value,
                });
                let passes =
                    f.fit.dof > 0 && f.fit.chi2_p_value.is_some_and(|p| p >= LACK_OF_FIT_ALPHA);
                if passes {
                    return Ok((f, trials));
                }
                last = Some(f);
            }
            let f = last.ok_or_else(|| Error::Unsupported("thermal fit: no degree".into()))?;
            Ok((f, trials))
        }
    }
}

/// The `"thermal"` entry of one coefficient or channel in a thermal
/// result document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThermalEntry {
    /// Degree `d` of (1).
    pub degree: usize,
    /// `T_ref`, °C.
    pub t_ref_c: f64,
    /// Lowest temperature of the data: the valid range starts here, °C.
    pub t_min_c: f64,
    /// Highest temperature of the data, °C.
    pub t_max_c: f64,
    /// The coefficient's unit (of `c_0`).
    pub unit: String,
    /// Heating branch minus cooling branch (ramps with both branches).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hysteresis: Option<ValueU>,
    /// Coefficient of `dT/dt` (ramps with `--rate-term`), unit per °C/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_term: Option<ValueU>,
}

/// A value with its standard uncertainty, dof and expanded uncertainty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValueU {
    /// Value.
    pub value: f64,
    /// Standard uncertainty.
    pub u: f64,
    /// Expanded uncertainty (95 %).
    #[serde(rename = "U95")]
    pub u95: f64,
    /// Unit.
    pub unit: String,
}

impl ValueU {
    /// Value, u, unit and dof (for U95).
    pub fn new(value: f64, u: f64, unit: &str, dof: f64) -> ValueU {
        ValueU {
            value,
            u,
            u95: crate::estimation::coverage_factor(dof, 0.95) * u,
            unit: unit.to_string(),
        }
    }
}

/// The thermal model of a result document: its `"thermal"` map and the
/// coefficients `NAME.c0…` of every entry.
#[derive(Debug, Clone)]
pub struct Model {
    /// Per coefficient or channel: its entry and `c_0…c_d`.
    pub entries: Vec<(String, ThermalEntry, Vec<f64>)>,
}

impl Model {
    /// Read the model from a thermal result document.
    pub fn of(doc: &crate::document::ResultDocument) -> Result<Model> {
        if doc.procedure != crate::document::Procedure::Thermal {
            return Err(Error::Unsupported(format!(
                "a thermal model is a result of incal thermal fit or ramp, not of {}",
                doc.procedure
            )));
        }
        let map = doc
            .extra
            .get("thermal")
            .and_then(|m| m.as_object())
            .ok_or_else(|| Error::Unsupported("$.thermal: missing".into()))?;
        let mut entries = Vec::new();
        for (name, v) in map {
            let e: ThermalEntry = serde_json::from_value(v.clone())
                .map_err(|e| Error::Unsupported(format!("$.thermal.{name}: {e}")))?;
            if input::NOT_CHANNELS.contains(&name.as_str()) {
                return Err(Error::Unsupported(format!(
                    "$.thermal.{name}: {name} is the recording's time or temperature, not a channel a model corrects"
                )));
            }
            if e.degree > MAX_DEGREE {
                return Err(Error::Unsupported(format!(
                    "$.thermal.{name}.degree: {} is above {MAX_DEGREE}",
                    e.degree
                )));
            }
            let in_range = |t: f64| crate::units::check_temperature_c("t", t).is_ok();
            if !(in_range(e.t_min_c) && in_range(e.t_max_c) && e.t_min_c <= e.t_max_c) {
                return Err(Error::Unsupported(format!(
                    "$.thermal.{name}: t_min_c and t_max_c are not a range of temperatures (absolute zero to 1000 degC, min <= max)"
                )));
            }
            let c = (0..=e.degree)
                .map(|k| {
                    doc.coefficients
                        .get(&format!("{name}.c{k}"))
                        .map(|c| c.value)
                        .ok_or_else(|| {
                            Error::Unsupported(format!("$.coefficients.{name}.c{k}: missing"))
                        })
                })
                .collect::<Result<Vec<f64>>>()?;
            // The degree says how many coefficients there are: one more
            // is a model read wrong.
            let extra = format!("{name}.c{}", e.degree + 1);
            if doc.coefficients.get(&extra).is_some() {
                return Err(Error::Unsupported(format!(
                    "$.thermal.{name}.degree: {} but the document has {extra}",
                    e.degree
                )));
            }
            if let Some(k) = c.iter().position(|x| !x.is_finite()) {
                return Err(Error::Unsupported(format!(
                    "$.coefficients.{name}.c{k}: not a finite number"
                )));
            }
            entries.push((name.clone(), e, c));
        }
        if entries.is_empty() {
            return Err(Error::Unsupported("$.thermal: no entry".into()));
        }
        Ok(Model { entries })
    }

    /// The entries' names, comma separated (for messages).
    pub fn names(&self) -> String {
        self.entries
            .iter()
            .map(|(n, _, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The entry called `name`.
    pub fn get(&self, name: &str) -> Option<(&ThermalEntry, &[f64])> {
        self.entries
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, e, c)| (e, c.as_slice()))
    }
}

/// The polynomial of `c` (in `T − from`) re-expanded about `to`:
/// `Σ c_k (T − from)^k = Σ d_j (T − to)^j` (binomial shift).
pub fn shift_reference(c: &[f64], from: f64, to: f64) -> Vec<f64> {
    let h = to - from;
    let n = c.len();
    let mut d = vec![0.0; n];
    for (k, ck) in c.iter().enumerate() {
        // (T − from)^k = ((T − to) + h)^k = Σ_j C(k, j) h^{k−j} (T − to)^j
        let mut binom = 1.0;
        for (j, dj) in d.iter_mut().enumerate().take(k + 1) {
            *dj += ck * binom * h.powi((k - j) as i32);
            binom = binom * (k - j) as f64 / (j + 1) as f64;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifting_the_reference_keeps_the_polynomial() {
        let c = [0.3, -2e-3, 4e-5, -6e-7];
        let d = shift_reference(&c, 25.0, 35.0);
        for t in [-40.0, 0.0, 25.0, 35.0, 85.0] {
            let a = poly(&c, 25.0, t);
            let b = poly(&d, 35.0, t);
            assert!((a - b).abs() < 1e-12, "{t}: {a} {b}");
        }
    }

    #[test]
    fn distinct_temperatures_count_plateaus_once() {
        assert_eq!(distinct_temperatures(&[25.0, 25.01, 60.0, -10.0]), 3);
        assert_eq!(supported_degree(&[25.0, 60.0, -10.0], 0), Some(1));
        assert_eq!(supported_degree(&[25.0], 0), None);
    }

    #[test]
    fn a_fixed_degree_beyond_the_plateaus_is_refused_naming_the_term() {
        let t = [-20.0, 25.0, 70.0];
        let e = fit_with_degree(
            "K0",
            &t,
            &[1.0, 2.0, 3.0],
            &[0.1; 3],
            &[],
            25.0,
            Degree::Fixed(3),
            f64::INFINITY,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("K0.c3"), "{e}");
    }

    #[test]
    fn an_exact_quadratic_is_recovered_with_its_covariance() {
        let t: Vec<f64> = (0..7).map(|i| -40.0 + 20.0 * i as f64).collect();
        let c = [1e-3, 2e-5, -3e-7];
        let y: Vec<f64> = t.iter().map(|&t| poly(&c, 25.0, t)).collect();
        let f = fit_poly(&t, &y, &[1e-6; 7], &[], 25.0, 2, f64::INFINITY).unwrap();
        for (k, ck) in c.iter().enumerate() {
            assert!((f.values[k] - ck).abs() < 1e-9 * ck.abs().max(1e-12) + 1e-15);
        }
        // G Σ Gᵀ is the covariance when the variance factor is 1.
        let sigma = DMatrix::from_diagonal_element(7, 7, 1e-12);
        let cov = &f.gain * sigma * f.gain.transpose();
        for j in 0..3 {
            let r = cov[(j, j)] / f.covariance[(j, j)];
            assert!((r - 1.0).abs() < 1e-6, "{r}");
        }
    }

    fn key_of<T: std::fmt::Debug>(r: Result<T>) -> String {
        crate::options::refused_key(r)
    }

    #[test]
    fn ramp_options_round_trip_and_name_a_bad_key() {
        use crate::options::from_json;
        use crate::procedures::Procedure;
        let o: ramp::RampOptions = from_json(&serde_json::json!({"rate_hz": 2.0})).unwrap();
        assert_eq!(o.block_s, 10.0);
        assert_eq!(o.t_ref_c, DEFAULT_T_REF_C);
        let given = serde_json::json!({
            "rate_hz": 1.0, "quantity": "gyro", "t_ref_c": 20.0,
            "degree": 2, "block_s": 30.0, "rate_term": true
        });
        let o: ramp::RampOptions = from_json(&given).unwrap();
        assert_eq!(o.degree, Degree::Fixed(2));
        let shown = serde_json::to_value(&o).unwrap();
        assert_eq!(shown, given);
        assert_eq!(from_json::<ramp::RampOptions>(&shown).unwrap(), o);
        let auto = serde_json::to_value(ramp::RampOptions::default()).unwrap();
        assert_eq!(auto["degree"], "auto");
        assert_eq!(
            from_json::<ramp::RampOptions>(&serde_json::json!({"rate_hz": 1.0, "degree": "3"}))
                .unwrap()
                .degree,
            Degree::Fixed(3)
        );
        assert_eq!(
            key_of(from_json::<ramp::RampOptions>(
                &serde_json::json!({"rate_hz": 1.0, "degree": 4})
            )),
            "degree"
        );
        assert_eq!(
            key_of(from_json::<ramp::RampOptions>(
                &serde_json::json!({"rate_hz": 1.0, "block": 4})
            )),
            "block"
        );
        let bad = ramp::RampOptions {
            block_s: 0.0,
            ..Default::default()
        };
        assert_eq!(key_of(ramp::Ramp::validate(&bad)), "block_s");
        let bad = ramp::RampOptions {
            t_ref_c: -300.0,
            ..Default::default()
        };
        assert_eq!(key_of(ramp::Ramp::validate(&bad)), "t_ref_c");
        let bad = ramp::RampOptions {
            block_s: 1e-320,
            ..Default::default()
        };
        assert_eq!(key_of(ramp::Ramp::validate(&bad)), "block_s");
    }

    #[test]
    fn plan_options_round_trip_and_name_a_bad_key() {
        use crate::options::from_json;
        use crate::procedures::Plan;
        let given = serde_json::json!({"plateaus_c": [-20.0, 25.0, 70.0], "u": 1e-3, "degree": 1});
        let o: plan::ThermalPlanOptions = from_json(&given).unwrap();
        assert_eq!((o.rate_hz, o.hold_s, o.t_ref_c), (10.0, 1800.0, 25.0));
        let shown = serde_json::to_value(&o).unwrap();
        assert!(shown.get("noise").is_none(), "{shown}");
        assert_eq!(from_json::<plan::ThermalPlanOptions>(&shown).unwrap(), o);
        let d = Thermal::plan(&o).unwrap();
        assert_eq!(serde_json::to_value(&d.options).unwrap(), shown);
        let bad = plan::ThermalPlanOptions {
            degree: 4,
            ..o.clone()
        };
        assert_eq!(key_of(Thermal::plan(&bad)), "degree");
        let bad = plan::ThermalPlanOptions { u: Some(0.0), ..o };
        assert_eq!(key_of(Thermal::plan(&bad)), "u");
    }
}
