//! Output helpers: JSON value/uncertainty objects and readable tables in
//! the units engineers expect (µg, ppm, arcsec).

use incal::estimation::Estimates;
use incal::models::Term;
use incal::units::ARCSEC_PER_RAD;
use serde_json::{json, Map, Value};

/// `{"value": v, "u": u, "unit": unit}`.
pub fn vu_unit(value: f64, u: f64, unit: &str) -> Value {
    json!({"value": value, "u": u, "unit": unit})
}

/// JSON number, or null when not finite (JSON has no NaN).
pub fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

/// `{"NAME": {"value", "u", "unit"}}` for every estimate, with units from
/// `unit_of`.
pub fn coefficients_json(e: &Estimates, unit_of: impl Fn(&str) -> String) -> Value {
    let mut m = Map::new();
    for (k, name) in e.names().iter().enumerate() {
        m.insert(
            name.clone(),
            vu_unit(e.values()[k], e.u_at(k), &unit_of(name)),
        );
    }
    Value::Object(m)
}

/// Unit string of an accelerometer coefficient name.
pub fn term_unit(name: &str) -> String {
    Term::parse(name).map_or_else(|_| String::new(), |t| t.unit().to_string())
}

/// Display scale and unit for an accelerometer term in readable output.
pub fn display_scale(term: Term) -> (f64, &'static str) {
    match term {
        Term::K0 => (1e6, "ug"),
        Term::K1 => (1.0, "output/g"),
        Term::K3 => (1e6, "ug/g^3"),
        Term::DeltaO | Term::DeltaP => (ARCSEC_PER_RAD, "arcsec"),
        _ => (1e6, "ug/g^2"),
    }
}

/// A plain text table with right-aligned columns after the first.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let ncol = header.len();
    let mut width: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (k, c) in r.iter().enumerate().take(ncol) {
            width[k] = width[k].max(c.chars().count());
        }
    }
    let fmt_row = |cells: Vec<String>| {
        let mut s = String::new();
        for (k, c) in cells.iter().enumerate() {
            let pad = width[k].saturating_sub(c.chars().count());
            if k == 0 {
                s.push_str(c);
                s.push_str(&" ".repeat(pad));
            } else {
                s.push_str("  ");
                s.push_str(&" ".repeat(pad));
                s.push_str(c);
            }
        }
        s.trim_end().to_string()
    };
    let mut out = fmt_row(header.iter().map(|h| h.to_string()).collect());
    out.push('\n');
    out.push_str(&"-".repeat(width.iter().sum::<usize>() + 2 * (ncol - 1)));
    out.push('\n');
    for r in rows {
        out.push_str(&fmt_row(r.clone()));
        out.push('\n');
    }
    out
}

/// A number with `sig` significant digits, plain or scientific as fits.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if (-3..6).contains(&e) {
        let dec = (digits as i32 - 1 - e).max(0) as usize;
        format!("{x:.dec$}")
    } else {
        format!("{x:.prec$e}", prec = digits.saturating_sub(1))
    }
}

/// Print JSON to stdout, pretty.
pub fn print_json(v: &Value) {
    match serde_json::to_string_pretty(v) {
        Ok(s) => println!("{s}"),
        Err(_) => println!("{v}"),
    }
}
