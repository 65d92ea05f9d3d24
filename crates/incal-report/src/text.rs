//! The one text renderer of incal's documents: the readable report of
//! any result document (`incal.result/1`) and of any plan document
//! (`incal.plan/1`), in engineering units chosen by
//! [`incal::units::Unit::engineering`]. Every front end (the CLI, Python)
//! prints documents through it.

use incal::document::plan::PlanDocument;
use incal::document::{Cell, ResultDocument, Table};

use crate::format::{dof_text, measured, shown_name, sig, trimmed};

/// The thermal model's ranges, hysteresis and lag (a thermal result's
/// `thermal` and `lag`), one line each; empty for other results.
fn thermal_text(doc: &ResultDocument) -> String {
    let mut s = String::new();
    let vu = |v: &serde_json::Value| -> Option<String> {
        let (x, u, u95) = (
            v.get("value")?.as_f64()?,
            v.get("u")?.as_f64()?,
            v.get("U95")?.as_f64()?,
        );
        let (x, u, u95) = measured(x, u, u95);
        Some(format!(
            "{x} (u {u}, U95 {u95}) {}",
            v.get("unit").and_then(|u| u.as_str()).unwrap_or("")
        ))
    };
    if let Some(m) = doc.extra.get("thermal").and_then(|m| m.as_object()) {
        s.push_str(
            "
Thermal model
",
        );
        for (name, e) in m {
            let num = |k: &str| e.get(k).and_then(|v| v.as_f64()).unwrap_or(f64::NAN);
            s.push_str(&format!(
                "{name}: degree {}, T_ref {} degC, valid {} to {} degC",
                e.get("degree").and_then(|d| d.as_u64()).unwrap_or(0),
                trimmed(num("t_ref_c"), 4),
                trimmed(num("t_min_c"), 4),
                trimmed(num("t_max_c"), 4)
            ));
            if let Some(h) = e.get("hysteresis").and_then(vu) {
                s.push_str(&format!("; hysteresis (heating - cooling) {h}"));
            }
            if let Some(r) = e.get("rate_term").and_then(vu) {
                s.push_str(&format!("; dT/dt term {r}"));
            }
            s.push('\n');
        }
    }
    if let Some(l) = doc.extra.get("lag").and_then(vu) {
        s.push_str(&format!("sensor lag behind the chamber: {l}\n"));
    }
    s
}

/// The readable report of any result document: title, instrument and
/// inputs, coefficients (value, u, U95, dof in engineering units), fits,
/// decisions, warnings, then every table of the procedure.
pub fn render(doc: &ResultDocument) -> String {
    let mut s = format!("{}\n", doc.title);
    let inst = &doc.instrument;
    let mut ids: Vec<String> = Vec::new();
    if let Some(x) = &inst.serial {
        ids.push(format!("serial {x}"));
    }
    if let Some(x) = &inst.model {
        ids.push(format!("model {x}"));
    }
    ids.extend(inst.meta.iter().map(|(k, v)| format!("{k} {v}")));
    if !ids.is_empty() {
        s.push_str(&format!("instrument: {}\n", ids.join(", ")));
    }
    for i in &doc.inputs {
        let rows = i.rows.map_or(String::new(), |r| format!(", {r} rows"));
        s.push_str(&format!(
            "{}: {} (sha256 {}{rows})\n",
            i.role,
            i.path,
            &i.sha256[..i.sha256.len().min(16)]
        ));
    }
    s.push_str("\nCoefficients\n");
    let verdicts = doc.verdicts.as_ref();
    let rows: Vec<Vec<String>> = doc
        .coefficients
        .iter()
        .map(|(name, c)| {
            let (scale, label) = c.unit.engineering_for(c.value);
            let (value, u, u95) = measured(c.value * scale, c.u * scale, c.u95 * scale);
            let mut row = vec![
                shown_name(name, label),
                value,
                u,
                u95,
                dof_text(c.dof),
                format!("{:.3}", c.k95),
                label.to_string(),
            ];
            if let Some(v) = verdicts {
                row.push(v.get(name).map_or(String::new(), |v| {
                    let lim = |x: Option<f64>| x.map_or("-".to_string(), |x| trimmed(x * scale, 6));
                    format!("{} [{}, {}]", v.verdict, lim(v.min), lim(v.max))
                }));
            }
            row
        })
        .collect();
    let mut header = vec!["name", "value", "u", "U95", "dof", "k95", "unit"];
    if verdicts.is_some() {
        header.push("verdict [min, max]");
    }
    s.push_str(&table(&header, &rows));
    // Limits on terms this result does not report: no row above.
    for (name, v) in verdicts
        .into_iter()
        .flatten()
        .filter(|(n, _)| doc.coefficients.get(n).is_none())
    {
        s.push_str(&format!(
            "{name}: {} (limited, but not reported by this result)\n",
            v.verdict
        ));
    }
    s.push_str(
        "u: standard uncertainty; U95 = k95 u covers the value with 95 % probability (k95: Student t for dof; inf: known variance)\n",
    );
    s.push_str(&thermal_text(doc));
    s.push_str(&crate::montecarlo::text(doc));
    if let (Some(v), Some(rule)) = (doc.verdict, doc.decision_rule) {
        let rule = match rule {
            incal::document::limits::DecisionRule::Simple => {
                "simple acceptance: value against the limits"
            }
            incal::document::limits::DecisionRule::GuardBand => {
                "guard band: value +- U95 against the limits (ILAC-G8)"
            }
        };
        s.push_str(&format!("verdict: {v} ({rule})\n"));
    }
    if !doc.fits.is_empty() {
        s.push_str("\nFits\n");
        let rows: Vec<Vec<String>> = doc
            .fits
            .iter()
            .map(|f| {
                let (scale, label) = f.residual_unit.engineering();
                vec![
                    f.label.clone(),
                    f.observations.to_string(),
                    f.parameters.to_string(),
                    f.dof.to_string(),
                    f.condition_number.map_or("-".into(), |c| sig(c, 3)),
                    f.chi2_p_value.map_or("-".into(), |p| sig(p, 2)),
                    match f.variance_source {
                        incal::estimation::VarianceSource::Prior => "scatter/known".into(),
                        incal::estimation::VarianceSource::Residuals => "residuals".into(),
                    },
                    f.residual_rms
                        .map_or("-".into(), |r| format!("{} {label}", sig(r * scale, 3))),
                ]
            })
            .collect();
        s.push_str(&table(
            &[
                "fit",
                "n",
                "p",
                "dof",
                "condition",
                "chi2 p",
                "variance",
                "residual rms",
            ],
            &rows,
        ));
    }
    if !doc.decisions.is_empty() || !doc.warnings.is_empty() {
        s.push('\n');
    }
    for d in &doc.decisions {
        s.push_str(&format!("note: {}\n", d.message));
    }
    for w in &doc.warnings {
        s.push_str(&format!("warning [{}]: {}\n", w.code, w.message));
    }
    for t in &doc.tables {
        s.push('\n');
        s.push_str(&render_table(t));
    }
    s
}

/// One document table in engineering units. A column with a unit is
/// converted by it (its header says the unit shown); in a table with a
/// `unit` column, the unit-less number columns are in each row's unit and
/// are converted row by row.
pub fn render_table(t: &Table) -> String {
    let unit_col = t.columns.iter().position(|c| c.name == "unit");
    let header: Vec<String> = t
        .columns
        .iter()
        .map(|c| match &c.unit {
            Some(u) if !u.engineering().1.is_empty() && u.engineering().1 != "1" => {
                format!("{} ({})", c.name, u.engineering().1)
            }
            _ => c.name.clone(),
        })
        .collect();
    let rows: Vec<Vec<String>> = t
        .rows
        .iter()
        .map(|row| {
            let row_unit = unit_col.and_then(|k| match &row[k] {
                Cell::Text(u) => Some(incal::units::Unit::parse(u)),
                _ => None,
            });
            row.iter()
                .enumerate()
                .map(|(k, cell)| match cell {
                    Cell::Null => "-".into(),
                    Cell::Text(x) if Some(k) == unit_col => row_unit
                        .as_ref()
                        .map_or(x.clone(), |u| u.engineering().1.to_string()),
                    Cell::Text(x) => x.clone(),
                    Cell::Number(x) => {
                        let scale = match (&t.columns[k].unit, &row_unit) {
                            (Some(u), _) => u.engineering().0,
                            (None, Some(u)) => u.engineering().0,
                            (None, None) => 1.0,
                        };
                        trimmed(x * scale, 6)
                    }
                })
                .collect()
        })
        .collect();
    let hdr: Vec<&str> = header.iter().map(String::as_str).collect();
    format!("{}\n{}", t.title, table(&hdr, &rows))
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

/// A plan value for people: numbers as typed, lists joined by commas,
/// anything else as compact JSON.
fn plan_value(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => trimmed(x, 6),
            _ => n.to_string(),
        },
        Value::Bool(b) => b.to_string(),
        Value::Array(a) if a.iter().all(|x| !x.is_object() && !x.is_array()) => {
            a.iter().map(plan_value).collect::<Vec<_>>().join(", ")
        }
        other => other.to_string(),
    }
}

/// The readable form of any plan document: title, the plan's own keys,
/// the predicted standard uncertainty of every term in engineering units,
/// notes.
pub fn render_plan(doc: &PlanDocument) -> String {
    let mut s = format!("{}\n", doc.title);
    for (k, v) in &doc.plan {
        s.push_str(&format!("{k}: {}\n", plan_value(v)));
    }
    if let (Some(u), Some(units)) = (&doc.predicted_u, &doc.units) {
        s.push_str("\nPredicted uncertainty\n");
        let rows: Vec<Vec<String>> = u
            .iter()
            .map(|(name, &u)| {
                let unit = incal::units::Unit::parse(units.get(name).map_or("", |s| s.as_str()));
                let (scale, label) = unit.engineering_for(u);
                let u95 = doc
                    .predicted_u95
                    .as_ref()
                    .and_then(|m| m.get(name))
                    .copied();
                let (_, u_text, u95_text) =
                    measured(0.0, u * scale, u95.map_or(f64::NAN, |x| x * scale));
                vec![
                    shown_name(name, label),
                    u_text,
                    doc.predicted_dof.map_or("-".into(), |d| dof_text(Some(d))),
                    if u95.is_some() { u95_text } else { "-".into() },
                    label.to_string(),
                ]
            })
            .collect();
        s.push_str(&table(&["term", "u", "dof", "U95", "unit"], &rows));
        if doc.predicted_dof.is_some() {
            s.push_str("dof: of the reduction's variance (pooled scatter of repeated samples, else the fit's residuals); U95 = k95 u\n");
        }
    }
    for n in &doc.notes {
        s.push_str(&format!("note: {n}\n"));
    }
    s
}

/// The readable comparison of two results
/// ([`incal::document::compare::compare_documents`]): one row per
/// coefficient in engineering units, `|En| <= 1` judged.
pub fn render_comparison(c: &incal::document::compare::DocumentComparison) -> String {
    let f = |v: &serde_json::Value| v.as_f64();
    let mut rows = Vec::new();
    {
        for (name, r) in &c.rows {
            let (x, y) = (
                f(&r["a"]).unwrap_or(f64::NAN),
                f(&r["b"]).unwrap_or(f64::NAN),
            );
            let unit = incal::units::Unit::parse(r["unit"].as_str().unwrap_or(""));
            let (scale, label) = unit.engineering_for(x.abs().max(y.abs()));
            let en = f(&r["En"]);
            let (ua, ub) = (
                f(&r["u_a"]).unwrap_or(f64::NAN),
                f(&r["u_b"]).unwrap_or(f64::NAN),
            );
            let d = f(&r["difference"]).unwrap_or(f64::NAN);
            rows.push(vec![
                shown_name(name, label),
                measured(x * scale, ua * scale, 0.0).0,
                measured(y * scale, ub * scale, 0.0).0,
                measured(d * scale, ua.hypot(ub) * scale, 0.0).0,
                f(&r["relative_per_mille"]).map_or("-".into(), |v| sig(v, 3)),
                en.map_or("-".into(), |e| sig(e, 3)),
                match en {
                    Some(e) if e.abs() <= 1.0 => "ok",
                    Some(_) => "DIFFERS",
                    None => "-",
                }
                .to_string(),
                label.to_string(),
            ]);
        }
    }
    let mut s = format!("{} results: a = {}, b = {}\n", c.procedure, c.a, c.b);
    s.push_str(&table(
        &[
            "name",
            "a",
            "b",
            "a - b",
            "per mille",
            "En",
            "|En|<=1",
            "unit",
        ],
        &rows,
    ));
    s.push_str("En = (a - b) / sqrt(U95_a^2 + U95_b^2), U95 = k95 u of each result; per mille relative to b\n");
    s
}
