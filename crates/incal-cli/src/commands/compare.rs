//! `incal compare A.json B.json`: coefficient-by-coefficient comparison of
//! two results (seed 000 compares methods in ‰; seed 001 Table 5 uses the
//! normalized error).
//!
//! For every coefficient present in both files:
//! `d = x_A − x_B`, relative difference `d / |x_B|` (‰) and
//! `En = d / sqrt(U_A² + U_B²)` with expanded uncertainties `U = 2u`
//! (ISO/IEC 17043 B.3.1.3); `|En| ≤ 1` is satisfactory.

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};

use crate::error::{CliError, CliResult};
use crate::output::{num, print_json, sig, table};

/// Options of `incal compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// First result (JSON written by an incal command with --json).
    pub a: PathBuf,
    /// Second result (the reference for the relative difference).
    pub b: PathBuf,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// A coefficient read from a result file.
#[derive(Debug, Clone, PartialEq)]
struct Coef {
    value: f64,
    u: f64,
    unit: String,
}

/// Every `{"value", "u"}` object under the top-level maps `coefficients`
/// and `angles` (and their names), in file order.
fn read_coefficients(path: &Path) -> CliResult<Vec<(String, Coef)>> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::Input(format!("{name}: cannot read: {e}")))?;
    if text.trim().is_empty() {
        return Err(CliError::Input(format!("{name}: empty file")));
    }
    let doc: Value = serde_json::from_str(&text)
        .map_err(|e| CliError::Input(format!("{name}:{}: not valid JSON: {e}", e.line())))?;
    let mut out = Vec::new();
    for section in ["coefficients", "angles"] {
        let Some(map) = doc.get(section).and_then(Value::as_object) else {
            continue;
        };
        for (k, v) in map {
            let value = v.get("value").and_then(Value::as_f64);
            let u = v.get("u").and_then(Value::as_f64);
            match (value, u) {
                (Some(value), Some(u)) if value.is_finite() && u.is_finite() && u >= 0.0 => {
                    let unit = v
                        .get("unit")
                        .and_then(Value::as_str)
                        .unwrap_or("")
                        .to_string();
                    out.push((k.clone(), Coef { value, u, unit }));
                }
                _ => {
                    return Err(CliError::Input(format!(
                        "{name}: {section}.{k} has no numeric \"value\" and non-negative \"u\""
                    )))
                }
            }
        }
    }
    if out.is_empty() {
        return Err(CliError::Input(format!(
            "{name}: no \"coefficients\" or \"angles\" object with value/u entries"
        )));
    }
    Ok(out)
}

/// `incal compare`.
pub fn run(a: &Args) -> CliResult<()> {
    let ca = read_coefficients(&a.a)?;
    let cb = read_coefficients(&a.b)?;
    let mut rows = Vec::new();
    let mut m = Map::new();
    for (name, x) in &ca {
        let Some((_, y)) = cb.iter().find(|(n, _)| n == name) else {
            continue;
        };
        if !x.unit.is_empty() && !y.unit.is_empty() && x.unit != y.unit {
            return Err(CliError::Input(format!(
                "{name}: unit '{}' in {} but '{}' in {}",
                x.unit,
                a.a.display(),
                y.unit,
                a.b.display()
            )));
        }
        let d = x.value - y.value;
        let rel = if y.value != 0.0 {
            1e3 * d / y.value.abs()
        } else {
            f64::NAN
        };
        let big_u = 2.0 * (x.u * x.u + y.u * y.u).sqrt();
        let en = if big_u > 0.0 { d / big_u } else { f64::NAN };
        m.insert(
            name.clone(),
            json!({
                "a": x.value, "u_a": x.u, "b": y.value, "u_b": y.u,
                "difference": d, "relative_per_mille": num(rel), "En": num(en),
                "unit": if x.unit.is_empty() { &y.unit } else { &x.unit },
            }),
        );
        rows.push(vec![
            name.clone(),
            sig(x.value, 7),
            sig(y.value, 7),
            sig(d, 3),
            sig(rel, 3),
            sig(en, 3),
            if en.abs() <= 1.0 { "ok" } else { "DIFFERS" }.to_string(),
        ]);
    }
    if m.is_empty() {
        return Err(CliError::Input(format!(
            "{} and {} have no coefficient in common",
            a.a.display(),
            a.b.display()
        )));
    }
    if a.json {
        print_json(&json!({
            "a": a.a.display().to_string(),
            "b": a.b.display().to_string(),
            "convention": "difference = a - b; relative_per_mille = 1000*difference/|b|; En = difference/sqrt(U_a^2 + U_b^2), U = 2u",
            "comparisons": Value::Object(m),
        }));
    } else {
        println!("a = {}, b = {}", a.a.display(), a.b.display());
        print!(
            "{}",
            table(
                &["name", "a", "b", "a - b", "per mille", "En", "|En|<=1"],
                &rows
            )
        );
        println!("En = (a - b) / sqrt(U_a^2 + U_b^2), U = 2u; per mille relative to b");
    }
    Ok(())
}
