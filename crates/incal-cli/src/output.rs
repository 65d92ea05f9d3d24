//! Output: the one text renderer of every result document, the common
//! result options (`--json`, `--output`, instrument identity) and plain
//! text tables. Engineering units (µg, µg/g², arcsec, mm) come from
//! [`incal::units::Unit::engineering`], the one place that chooses them.

use std::path::PathBuf;

use incal::document::{Cell, InputFile, ResultDocument, Table};
use sha2::{Digest, Sha256};

use crate::error::{usage, CliResult};

/// Options every reducing command shares: output form and destination,
/// and the identity of the instrument.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ResultArgs {
    /// Print the result document as one JSON object (schema incal.result/1) instead of the readable report.
    #[arg(long)]
    pub json: bool,
    /// Write the result to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Serial number of the instrument (recorded in the result).
    #[arg(long)]
    pub serial: Option<String>,
    /// Model or part number of the instrument (recorded in the result).
    #[arg(long)]
    pub model: Option<String>,
    /// Further identity or conditions, KEY=VALUE (repeatable), e.g. --meta operator=lee --meta temperature_c=23.
    #[arg(long = "meta", value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
    /// Limits file (TOML): judge every limited coefficient (pass, fail, conditional-pass, conditional-fail).
    #[arg(long, value_name = "FILE")]
    pub limits: Option<PathBuf>,
}

/// Judge `doc` against the limits file `path` (its hash joins the inputs).
pub fn apply_limits(doc: &mut ResultDocument, path: &std::path::Path) -> CliResult<()> {
    let (name, text) = crate::io::read_text(path)?;
    let limits = incal::document::limits::Limits::parse(&text)
        .map_err(|e| crate::error::CliError::Input(format!("{name}: {e}")))?;
    incal::document::limits::apply(doc, &limits)
        .map_err(|e| crate::error::CliError::Input(format!("{name}: {e}")))?;
    let shown = if name == "<stdin>" {
        "-"
    } else {
        name.as_str()
    };
    doc.inputs.push(input_file(
        "limits",
        shown,
        sha256_hex(text.as_bytes()),
        None,
    ));
    Ok(())
}

impl ResultArgs {
    /// Put the instrument identity into `doc`, render it (JSON or text)
    /// and write it to `--output` or standard output.
    pub fn emit(&self, mut doc: ResultDocument) -> CliResult<()> {
        doc.instrument.serial = self.serial.clone();
        doc.instrument.model = self.model.clone();
        for kv in &self.meta {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| usage(format!("--meta: '{kv}' is not KEY=VALUE")))?;
            let k = k.trim();
            if k.is_empty() || k == "serial" || k == "model" {
                return Err(usage(format!(
                    "--meta: '{kv}' needs a key other than serial and model (use --serial, --model)"
                )));
            }
            doc.instrument
                .meta
                .insert(k.to_string(), v.trim().to_string());
        }
        if let Some(l) = &self.limits {
            apply_limits(&mut doc, l)?;
        }
        let text = if self.json {
            format!("{}\n", doc.to_json())
        } else {
            render(&doc)
        };
        write_text(self.output.as_deref(), &text)
    }
}

/// SHA-256 of `bytes`, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lower-case hexadecimal of a digest.
pub fn hex(digest: &[u8]) -> String {
    digest.iter().map(|b| format!("{b:02x}")).collect()
}

/// The record of one input file of a result.
pub fn input_file(role: &str, path: &str, bytes_sha256: String, rows: Option<usize>) -> InputFile {
    InputFile {
        role: role.to_string(),
        path: path.to_string(),
        sha256: bytes_sha256,
        rows: rows.map(|r| r as u64),
    }
}

pub use crate::io::write_text;

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
            let mut row = vec![
                name.to_string(),
                sig(c.value * scale, 7),
                sig(c.u * scale, 3),
                sig(c.u95 * scale, 3),
                dof_text(c.dof),
                format!("{:.3}", c.k95),
                label.to_string(),
            ];
            if let Some(v) = verdicts {
                row.push(v.get(name).map_or(String::new(), |v| {
                    let lim =
                        |x: Option<f64>| x.map_or("-".to_string(), |x| cell_number(x * scale));
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
    s.push_str(
        "u: standard uncertainty; U95 = k95 u covers the value with 95 % probability (k95: Student t for dof; inf: known variance)\n",
    );
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

/// Degrees of freedom for people: whole numbers from 10 up (an effective
/// dof of 80.3 reads 80), one decimal below, `inf` for a known variance.
pub fn dof_text(dof: Option<f64>) -> String {
    match dof {
        None => "inf".into(),
        Some(d) if d.fract() == 0.0 || d >= 10.0 => format!("{d:.0}"),
        Some(d) => format!("{d:.1}"),
    }
}

/// A number in a table: 6 significant digits, trailing zeros dropped
/// (`30.0000` → `30`, `0.110000` → `0.11`).
fn cell_number(x: f64) -> String {
    let s = sig(x, 6);
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        None if s.contains('.') => s.trim_end_matches('0').trim_end_matches('.').to_string(),
        _ => s,
    }
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
                        cell_number(x * scale)
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

/// Pretty JSON of any serializable value, with a final newline.
pub fn json_text(v: &serde_json::Value) -> String {
    format!(
        "{}\n",
        serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string())
    )
}

/// A value echoed in a message, clipped to 40 characters (a 100k-character
/// cell or a 301-digit number is shown by its start).
pub fn clip(s: &str) -> String {
    const MAX: usize = 40;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        let head: String = s.chars().take(MAX).collect();
        format!("{head}... ({} characters)", s.chars().count())
    }
}

/// A number echoed in a message: as typed when short, else in scientific notation.
pub fn num(x: f64) -> String {
    let s = format!("{x}");
    if s.len() > 24 {
        format!("{x:.6e}")
    } else {
        s
    }
}

/// Options every plan command shares: output form and destination.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct PlanOut {
    /// Print the plan document as one JSON object (schema incal.plan/1) instead of the readable plan.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

impl PlanOut {
    /// Render the plan document (JSON or text) and write it.
    pub fn emit(&self, doc: &incal::document::plan::PlanDocument) -> CliResult<()> {
        let text = if self.json {
            json_text(&serde_json::to_value(doc).unwrap_or(serde_json::Value::Null))
        } else {
            render_plan(doc)
        };
        write_text(self.output.as_deref(), &text)
    }
}

/// A plan value for people: numbers as typed, lists joined by commas,
/// anything else as compact JSON.
fn plan_value(v: &serde_json::Value) -> String {
    use serde_json::Value;
    match v {
        Value::Null => "-".into(),
        Value::String(s) => s.clone(),
        Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => cell_number(x),
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
pub fn render_plan(doc: &incal::document::plan::PlanDocument) -> String {
    let mut s = format!("{}\n", doc.title);
    for (k, v) in &doc.plan {
        s.push_str(&format!("{k}: {}\n", plan_value(v)));
    }
    if let (Some(u), Some(units)) = (&doc.predicted_u, &doc.units) {
        s.push_str("\nPredicted standard uncertainty\n");
        let rows: Vec<Vec<String>> = u
            .iter()
            .map(|(name, &u)| {
                let unit = incal::units::Unit::parse(units.get(name).map_or("", |s| s.as_str()));
                let (scale, label) = unit.engineering_for(u);
                vec![name.clone(), sig(u * scale, 3), label.to_string()]
            })
            .collect();
        s.push_str(&table(&["term", "predicted u", "unit"], &rows));
    }
    for n in &doc.notes {
        s.push_str(&format!("note: {n}\n"));
    }
    s
}
