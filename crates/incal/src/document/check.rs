//! What a result document read from a file must hold beyond its schema,
//! for the parts that other commands compute with: the correlation matrix
//! (square over distinct coefficients, symmetric, unit diagonal, every
//! |ρ| ≤ 1) and the recorded environment (finite, min ≤ mean ≤ max). Each
//! error names the JSON path ([`super::ResultDocument::check`]).

use serde_json::Value;

use super::ResultDocument;

/// A number as a message shows it: at most 7 significant digits.
fn shown(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) {
        format!("{}", (x * 1e6).round() / 1e6)
            .chars()
            .take(12)
            .collect()
    } else {
        format!("{x:.6e}")
    }
}

/// Slack for round-off in a matrix written by incal.
const TOL: f64 = 1e-9;

/// The correlation matrix of `doc` (module docs).
pub(super) fn correlation(doc: &ResultDocument) -> Result<(), String> {
    let c = &doc.correlation;
    let n = c.names.len();
    for (i, name) in c.names.iter().enumerate() {
        if doc.coefficients.get(name).is_none() {
            return Err(format!(
                "$.correlation.names[{i}]: '{}' is not a coefficient of the document",
                incal_io::clip(name)
            ));
        }
        if c.names[..i].contains(name) {
            return Err(format!(
                "$.correlation.names[{i}]: '{}' is named twice",
                incal_io::clip(name)
            ));
        }
    }
    if c.matrix.len() != n {
        return Err(format!(
            "$.correlation.matrix: {} rows for {n} names",
            c.matrix.len()
        ));
    }
    for (j, row) in c.matrix.iter().enumerate() {
        if row.len() != n {
            return Err(format!(
                "$.correlation.matrix[{j}]: {} entries for {n} names",
                row.len()
            ));
        }
        for (k, &r) in row.iter().enumerate() {
            let at = format!("$.correlation.matrix[{j}][{k}]");
            if !(r.is_finite() && r.abs() <= 1.0 + TOL) {
                return Err(format!("{at}: {} is not a correlation (-1 to 1)", shown(r)));
            }
            if j == k && (r - 1.0).abs() > TOL {
                return Err(format!("{at}: {} on the diagonal (must be 1)", shown(r)));
            }
            if (r - c.matrix[k][j]).abs() > TOL {
                return Err(format!(
                    "{at}: {} differs from [{k}][{j}] = {} (the matrix is symmetric)",
                    shown(r),
                    shown(c.matrix[k][j])
                ));
            }
        }
    }
    Ok(())
}

/// The environment the recording recorded (`environment`: per quantity
/// `mean`, `min`, `max`, `count`), if any.
pub(super) fn environment(doc: &ResultDocument) -> Result<(), String> {
    let Some(env) = doc.extra.get("environment") else {
        return Ok(());
    };
    let Some(env) = env.as_object() else {
        return Err("$.environment: not an object of quantities".into());
    };
    for (name, q) in env {
        let at = format!("$.environment.{}", incal_io::clip(name));
        let num = |key: &str| -> Result<f64, String> {
            q.get(key)
                .and_then(Value::as_f64)
                .filter(|x| x.is_finite() && x.abs() <= ResultDocument::MAX_MAGNITUDE)
                .ok_or_else(|| format!("{at}.{key}: missing or not a finite number"))
        };
        let (mean, min, max, count) = (num("mean")?, num("min")?, num("max")?, num("count")?);
        if min > max {
            return Err(format!(
                "{at}: min {} is above max {}",
                shown(min),
                shown(max)
            ));
        }
        if !(min - TOL * min.abs().max(1.0) <= mean && mean <= max + TOL * max.abs().max(1.0)) {
            return Err(format!(
                "{at}.mean: {} is outside min {} to max {}",
                shown(mean),
                shown(min),
                shown(max)
            ));
        }
        if count < 1.0 || count.fract() != 0.0 {
            return Err(format!(
                "{at}.count: {} is not a number of samples",
                shown(count)
            ));
        }
    }
    Ok(())
}
