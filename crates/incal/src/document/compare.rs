//! Comparison of two result documents (`incal compare A.json B.json`):
//! coefficient by coefficient, two results of the same procedure (Wu et al. 2015 compares methods
//! in ‰; He & Yin 2017 Table 5 uses the normalized error).
//!
//! For every coefficient present in both:
//! `d = x_A − x_B`, relative difference `1000·d/|x_B|` (‰) and the
//! normalized error `En = d / sqrt(U_A² + U_B²)` with each side's own
//! expanded uncertainty `U95 = k95·u` (ISO/IEC 17043 B.3.1.3 with the
//! coverage factor of each result's degrees of freedom); `|En| ≤ 1` is
//! satisfactory. Computed in scaled form (every term divided by the
//! largest magnitude involved), so values near the limits of `f64` neither
//! overflow nor lose the answer.

use serde_json::{json, Map, Value};

use super::{Coefficient, ResultDocument};
use crate::error::{Error, Result};

/// What the difference, the relative difference and En mean, as stated in
/// every comparison.
pub const CONVENTION: &str = "difference = a - b; relative_per_mille = 1000*difference/|b|; En = difference/sqrt(U95_a^2 + U95_b^2), U95 = k95*u of each result";

/// One comparison: difference, per mille of |b| and En, in scaled form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    /// `a − b` (infinite only when it truly overflows).
    pub difference: f64,
    /// `1000·(a − b)/|b|` (`None` when b = 0).
    pub relative_per_mille: Option<f64>,
    /// `(a − b)/sqrt(U_a² + U_b²)` (`None` when both U are 0).
    pub en: Option<f64>,
}

/// Compare `a` with the reference `b` (module docs).
pub fn compare(a: &Coefficient, b: &Coefficient) -> Comparison {
    // Scale by the largest magnitude so no intermediate overflows: with
    // s = max(|a|, |b|, U_a, U_b), every quotient below is formed from
    // numbers in [−1, 1] (differences in [−2, 2]).
    let s = [a.value.abs(), b.value.abs(), a.u95, b.u95]
        .into_iter()
        .fold(0.0, f64::max);
    if s == 0.0 {
        return Comparison {
            difference: 0.0,
            relative_per_mille: None,
            en: None,
        };
    }
    let (xa, xb, ua, ub) = (a.value / s, b.value / s, a.u95 / s, b.u95 / s);
    let d = xa - xb;
    let big_u = ua.hypot(ub);
    Comparison {
        difference: d * s,
        relative_per_mille: (xb != 0.0).then(|| 1e3 * d / xb.abs()),
        en: (big_u > 0.0).then(|| d / big_u),
    }
}

/// Two results compared, coefficient by coefficient in the order of `a`.
#[derive(Debug, Clone, PartialEq)]
pub struct DocumentComparison {
    /// The procedure both results are of.
    pub procedure: String,
    /// Name of the first result.
    pub a: String,
    /// Name of the reference result.
    pub b: String,
    /// `(coefficient, its row)`: `{a, u_a, U95_a, b, u_b, U95_b,
    /// difference, relative_per_mille, En, unit}`.
    pub rows: Vec<(String, Value)>,
}

impl DocumentComparison {
    /// The JSON form: `{procedure, a, b, convention, comparisons}`.
    pub fn to_json(&self) -> Value {
        let m: Map<String, Value> = self.rows.iter().cloned().collect();
        json!({
            "procedure": self.procedure,
            "a": self.a,
            "b": self.b,
            "convention": CONVENTION,
            "comparisons": Value::Object(m),
        })
    }
}

/// The comparison of the results `a` (named `name_a`) and `b` (the
/// reference): `{procedure, a, b, convention, comparisons: {name: {a, u_a,
/// U95_a, b, u_b, U95_b, difference, relative_per_mille, En, unit}}}` over
/// the coefficients both hold. Refused: results of different procedures,
/// a unit that differs, a difference that overflows, nothing in common.
pub fn compare_documents(
    name_a: &str,
    a: &ResultDocument,
    name_b: &str,
    b: &ResultDocument,
) -> Result<DocumentComparison> {
    let bad = |m: String| Err(Error::Unsupported(m));
    if a.procedure != b.procedure {
        return bad(format!(
            "{name_a} is a {} result and {name_b} a {} result: compare needs two results of the same procedure",
            a.procedure, b.procedure
        ));
    }
    let mut rows = Vec::new();
    for (name, x) in a.coefficients.iter() {
        let Some(y) = b.coefficients.get(name) else {
            continue;
        };
        if x.unit != y.unit {
            return bad(format!(
                "{name}: unit '{}' in {name_a} but '{}' in {name_b}",
                x.unit, y.unit
            ));
        }
        let c = compare(x, y);
        if !c.difference.is_finite() {
            return bad(format!(
                "{name}: the difference {} - ({}) overflows a double",
                x.value, y.value
            ));
        }
        rows.push((
            name.to_string(),
            json!({
                "a": x.value, "u_a": x.u, "U95_a": x.u95,
                "b": y.value, "u_b": y.u, "U95_b": y.u95,
                "difference": c.difference,
                "relative_per_mille": c.relative_per_mille,
                "En": c.en,
                "unit": x.unit.as_str(),
            }),
        ));
    }
    if rows.is_empty() {
        return bad(format!(
            "{name_a} and {name_b} have no coefficient in common"
        ));
    }
    Ok(DocumentComparison {
        procedure: a.procedure.as_str().to_string(),
        a: name_a.to_string(),
        b: name_b.to_string(),
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::Unit;

    fn c(v: f64, u: f64) -> Coefficient {
        Coefficient::new("x", v, u, Unit::G, f64::INFINITY).unwrap()
    }

    #[test]
    fn en_uses_each_sides_u95() {
        let a = Coefficient::new("x", 1.0, 0.1, Unit::G, 4.0).unwrap();
        let b = c(0.5, 0.1);
        let r = compare(&a, &b);
        let expect = 0.5 / (a.u95.powi(2) + b.u95.powi(2)).sqrt();
        assert!((r.en.unwrap() - expect).abs() < 1e-12);
        assert!((r.relative_per_mille.unwrap() - 1000.0).abs() < 1e-9);
    }

    #[test]
    fn extreme_values_do_not_overflow() {
        let r = compare(&c(1e200, 1e199), &c(-1e200, 1e199));
        assert!((r.en.unwrap() - 2e200 / (2f64.sqrt() * 1.959964e199)).abs() < 1e-3);
        assert_eq!(r.difference, 2e200);
        let r = compare(&c(1.7e308, 1e300), &c(-1.7e308, 1e300));
        assert!(r.en.unwrap() > 1e6, "{r:?}");
        assert!(r.difference.is_infinite());
        let r = compare(&c(1e-300, 1e-310), &c(0.0, 1e-310));
        assert!(r.en.unwrap() > 1.0 && r.en.unwrap().is_finite());
        assert_eq!(r.relative_per_mille, None);
    }
}
