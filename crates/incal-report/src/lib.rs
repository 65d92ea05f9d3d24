//! One self-contained HTML report — a printable calibration certificate —
//! of any incal result document (`incal.result/1`), for every procedure
//! through the one document shape.
//!
//! [`render_html`] writes, in one HTML file with inline CSS and inline SVG
//! and nothing loaded from outside (no script, no stylesheet link, no
//! font, no image file, no URL):
//!
//! * a header: title, procedure, instrument (serial, model and every
//!   `--meta` pair), incal version, report date (UTC), overall verdict when
//!   there is one, the input files with their full SHA-256, and the options;
//! * `coefficients`: value, u, U95, dof, k95 and unit (engineering units,
//!   as the text report) and the verdict against the limits, when given;
//! * `fits`: the diagnostics of every least-squares fit;
//! * `notes`: warnings (with their codes) and decisions;
//! * `tables`: every table of the document, in engineering units;
//! * `plots` ([`plots`] says which): residuals with ±U95 bars and the
//!   fitted model against the data for every table with residuals,
//!   coefficient values ±U95 across the blocks of a multi-instrument
//!   result;
//! * `history` (when given): each limited coefficient over the stored
//!   calibrations of the instrument, ±U95, with its limits.
//!
//! A print stylesheet makes it an A4 certificate: 15 mm margins, each
//! section on a new page, table headers repeated, plots not split.
//! Every text from the document is escaped. The renderer is pure: no file,
//! no network (it reads the clock only for the default date).

pub mod certificate;
pub mod dcc;
pub mod format;
pub mod montecarlo;
pub mod pdf;
pub mod plots;
pub mod records;
pub mod stored;
pub mod text;

use incal::document::{Cell, ResultDocument, Table};
use incal::units::Unit;
use serde_json::Value;

use format::{dof_text, esc, measured, shown_name, sig, trimmed};

/// One stored calibration of an instrument: a point of a history plot.
#[derive(Debug, Clone, PartialEq)]
pub struct HistoryPoint {
    /// Record id in the store.
    pub id: i64,
    /// When the record was stored (UTC, as the store writes it).
    pub created_utc: String,
    /// Value, in the coefficient's JSON unit.
    pub value: f64,
    /// Expanded uncertainty U95, same unit.
    pub u95: f64,
}

/// The history of one coefficient of an instrument, oldest first, with
/// its limits (JSON unit; plotted in engineering units).
#[derive(Debug, Clone, PartialEq)]
pub struct HistorySeries {
    /// Coefficient name.
    pub coefficient: String,
    /// Unit of the values, limits and U95.
    pub unit: Unit,
    /// The calibrations, oldest first.
    pub points: Vec<HistoryPoint>,
    /// Lower limit, if any.
    pub min: Option<f64>,
    /// Upper limit, if any.
    pub max: Option<f64>,
    /// The drift line fitted to the points, if any.
    pub drift: Option<DriftLine>,
}

/// A drift line `y(t) = intercept + rate·t`, `t` in days since the first
/// calibration, with the covariance of (intercept, rate) and the coverage
/// factor of its band (JSON unit per day for the rate).
#[derive(Debug, Clone, PartialEq)]
pub struct DriftLine {
    /// Value at the first calibration.
    pub intercept: f64,
    /// Slope per day.
    pub rate_per_day: f64,
    /// Covariance of (intercept, rate).
    pub covariance: [[f64; 2]; 2],
    /// k95 of the band (Student t for the drift's dof).
    pub k95: f64,
}

/// Why a report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A plot could not be drawn.
    #[error("cannot draw a plot: {0}")]
    Plot(String),
}

/// Options of [`render_html_with`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RenderOptions {
    /// The report date as printed; `None`: now, `YYYY-MM-DD HH:MM UTC`.
    pub date: Option<String>,
    /// The records store the report was checked against, if any.
    pub record: Option<RecordStamp>,
    /// Render as a calibration certificate (laboratory, number, dates,
    /// traceability, decision rule, authorisation; [`certificate`]).
    pub certificate: Option<certificate::Certificate>,
}

/// Where the reported document is kept: its record in a store, and the
/// head of the store's hash chain when the report was written (checked
/// whole). The head printed on the certificate lets anyone check later,
/// with `incal record verify --head HEX`, that the store still holds
/// every record up to this one.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordStamp {
    /// The store as named (its path).
    pub store: String,
    /// The record holding this very document (`None`: not stored there).
    pub id: Option<i64>,
    /// Records in the chain.
    pub records: i64,
    /// `record_hash` of the chain's last record.
    pub head: String,
}

/// The plots of `doc`'s certificate, in its order: the tables' (or the
/// thermal model's), the deviations', the coefficients' with their
/// limits, then the Monte Carlo's distributions.
pub fn figures(doc: &ResultDocument) -> Vec<plots::Plot> {
    let mut figures: Vec<plots::Plot> = if doc.procedure == incal::document::Procedure::Thermal {
        plots::thermal_plots(doc)
    } else {
        // A noise result's terms against temperature are drawn as a
        // thermal model's coefficients (below), not as tables.
        doc.tables
            .iter()
            .filter(|t| !t.id.starts_with("noise_temperature"))
            .flat_map(|t| plots::table_plots_with(t, plots::model_curve(doc, &t.id).as_ref()))
            .collect()
    };
    figures.extend(plots::allan_plots(doc));
    figures.extend(plots::psd_plots(doc));
    figures.extend(plots::davar_plots(doc));
    figures.extend(plots::noise_temperature_plots(doc));
    figures.extend(plots::bode_plots(doc));
    figures.extend(plots::mag_plots(doc));
    let limits = |n: &str| verdict_of(doc, Some(n)).map(|j| (j.min, j.max));
    figures.extend(plots::coefficient_plots(doc, figures.is_empty(), &limits));
    figures.extend(plots::monte_carlo_plots(doc));
    figures
}

/// The certificate's plots of `doc` as SVG documents (a notebook shows
/// them inline).
pub fn figures_svg(doc: &ResultDocument) -> Result<Vec<String>, ReportError> {
    figures(doc).iter().map(plots::render_svg).collect()
}

/// The report of `doc`, dated now (UTC), with the `history` plots (none
/// when empty). See the crate docs.
pub fn render_html(doc: &ResultDocument, history: &[HistorySeries]) -> Result<String, ReportError> {
    render_html_with(doc, history, &RenderOptions::default())
}

/// The verdict of a coefficient (`Some(name)`) or of the whole result
/// (`None`) against its limits: the verdict word (`pass`, `fail`,
/// `conditional-pass`, `conditional-fail`) and, for a coefficient, its
/// limits (JSON unit).
#[derive(Debug, Clone, PartialEq)]
struct Judged {
    verdict: String,
    min: Option<f64>,
    max: Option<f64>,
}

/// The one place that reads verdicts from a document. For now they sit
/// in `extra` (`"verdicts": {NAME: {"min", "max", "verdict"}}`, `"verdict"`)
/// until the result type carries them.
fn verdict_of(doc: &ResultDocument, name: Option<&str>) -> Option<Judged> {
    match name {
        None => Some(Judged {
            verdict: doc.verdict?.as_str().to_string(),
            min: None,
            max: None,
        }),
        Some(n) => {
            let v = doc.verdicts.as_ref()?.get(n)?;
            Some(Judged {
                verdict: v.verdict.as_str().to_string(),
                min: v.min,
                max: v.max,
            })
        }
    }
}

/// A verdict word as HTML with a class for its colour (only the four known
/// words get one).
fn verdict_html(v: &str) -> String {
    let class = match v {
        "pass" | "fail" | "conditional-pass" | "conditional-fail" | "not-determined" => v,
        _ => "other",
    };
    format!("<span class=\"verdict verdict-{class}\">{}</span>", esc(v))
}

const CSS: &str = r#"
:root { color-scheme: light; }
body { font-family: sans-serif; font-size: 10.5pt; line-height: 1.35; color: #111; background: #fff; margin: 1.5em auto; max-width: 62em; padding: 0 1em; }
h1 { font-size: 1.55em; margin: 0 0 0.2em; }
h1 .sub { display: block; font-size: 0.7em; font-weight: normal; color: #333; }
h2 { font-size: 1.25em; border-bottom: 1px solid #888; padding-bottom: 0.15em; margin-top: 1.6em; }
h3 { font-size: 1.02em; margin: 1.1em 0 0.3em; }
table { border-collapse: collapse; margin: 0.4em 0 1em; font-size: 0.9em; }
table.wide { font-size: 0.78em; }
th, td { border: 1px solid #bbb; padding: 0.12em 0.45em; vertical-align: top; }
th { background: #eee; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
.hash { font-family: monospace; font-size: 0.92em; word-break: break-all; }
.note { font-size: 0.88em; color: #333; }
.verdict { font-weight: bold; }
.verdict-pass { color: #0a6e0a; }
.verdict-fail { color: #b00000; }
.verdict-conditional-pass, .verdict-conditional-fail, .verdict-not-determined { color: #9a5800; }
ul.warnings li { color: #8a3b00; }
figure.plot { margin: 1em 0 1.4em; }
figure.plot svg { display: block; width: 100%; max-width: 760px; height: auto; border: 1px solid #ddd; }
figure.plot figcaption { font-size: 0.86em; color: #333; max-width: 760px; }
p.legend { margin: 0.3em 0; font-size: 0.86em; max-width: 760px; }
.key { white-space: nowrap; margin-right: 0.9em; }
.swatch { display: inline-block; width: 0.8em; height: 0.8em; margin-right: 0.3em; vertical-align: -0.05em; -webkit-print-color-adjust: exact; print-color-adjust: exact; }
footer { margin-top: 2em; font-size: 0.8em; color: #555; border-top: 1px solid #ccc; padding-top: 0.4em; }
@media print {
  @page { size: A4; margin: 15mm; }
  body { margin: 0; max-width: none; padding: 0; font-size: 9pt; }
  section { page-break-before: auto; break-before: auto; margin-top: 1.5em; }
  h2 { margin-top: 0; }
  h2, h3 { page-break-after: avoid; break-after: avoid; }
  thead { display: table-header-group; }
  tr, figure.plot, .doc-table.keep { page-break-inside: avoid; break-inside: avoid; }
  figure.plot svg { max-width: 100%; border: none; }
  table { font-size: 0.85em; }
  table.wide { font-size: 0.72em; }
}
"#;

/// A table of strings: header cells and rows of `(class, html)` cells.
pub(crate) fn html_table(class: &str, header: &[String], rows: &[Vec<(bool, String)>]) -> String {
    let wide = if header.len() > 8 { " wide" } else { "" };
    let mut s = format!("<table class=\"{class}{wide}\">\n<thead><tr>");
    for h in header {
        s.push_str(&format!("<th>{h}</th>"));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for r in rows {
        s.push_str("<tr>");
        for (num, c) in r {
            if *num {
                s.push_str(&format!("<td class=\"num\">{c}</td>"));
            } else {
                s.push_str(&format!("<td>{c}</td>"));
            }
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    s
}

fn text_cell(s: &str) -> (bool, String) {
    (false, esc(s))
}

fn num_cell(s: String) -> (bool, String) {
    (true, esc(&s))
}

/// An HTML id from a document id: letters, digits, `.`, `_`, `-` kept.
fn html_id(prefix: &str, id: &str) -> String {
    let tail: String = id
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '-'
            }
        })
        .collect();
    format!("{prefix}{tail}")
}

/// One document table in engineering units, as the text report converts
/// it: a column with a unit by that unit (its header names the unit
/// shown); in a table with a `unit` column, the unit-less number columns
/// row by row in the row's unit.
fn document_table(t: &Table) -> String {
    let unit_col = t.columns.iter().position(|c| c.name == "unit");
    let header: Vec<String> = t
        .columns
        .iter()
        .map(|c| {
            let label = c.unit.as_ref().map_or("", |u| u.engineering().1);
            esc(&plots::with_unit(
                &c.name,
                if label == "1" { "" } else { label },
            ))
        })
        .collect();
    let rows: Vec<Vec<(bool, String)>> = t
        .rows
        .iter()
        .map(|row| {
            let row_unit = unit_col.and_then(|k| match &row[k] {
                Cell::Text(u) => Some(Unit::parse(u)),
                _ => None,
            });
            row.iter()
                .enumerate()
                .map(|(k, cell)| match cell {
                    Cell::Null => (false, "–".to_string()),
                    Cell::Text(x) if Some(k) == unit_col => {
                        text_cell(row_unit.as_ref().map_or(x.as_str(), |u| u.engineering().1))
                    }
                    Cell::Text(x) => text_cell(x),
                    Cell::Number(x) => {
                        let scale = match (&t.columns[k].unit, &row_unit) {
                            (Some(u), _) => u.engineering().0,
                            (None, Some(u)) => u.engineering().0,
                            (None, None) => 1.0,
                        };
                        num_cell(trimmed(x * scale, 6))
                    }
                })
                .collect()
        })
        .collect();
    format!(
        "<div class=\"doc-table{}\" id=\"{}\" data-table=\"{}\">\n<h3>{}</h3>\n{}</div>\n",
        if t.rows.len() <= 25 { " keep" } else { "" },
        esc(&html_id("table-", &t.id)),
        esc(&t.id),
        esc(&t.title),
        html_table("document", &header, &rows)
    )
}

fn header_html(doc: &ResultDocument, date: &str, record: Option<&RecordStamp>) -> String {
    let mut s = String::from("<header id=\"header\">\n");
    s.push_str(&format!(
        "<h1>Calibration report<span class=\"sub\">{}</span></h1>\n",
        esc(&doc.title)
    ));
    let inst = &doc.instrument;
    let mut rows: Vec<Vec<(bool, String)>> = vec![
        vec![text_cell("procedure"), text_cell(doc.procedure.as_str())],
        vec![
            text_cell("serial"),
            text_cell(inst.serial.as_deref().unwrap_or("–")),
        ],
        vec![
            text_cell("model"),
            text_cell(inst.model.as_deref().unwrap_or("–")),
        ],
    ];
    for (k, v) in &inst.meta {
        rows.push(vec![text_cell(k), text_cell(v)]);
    }
    rows.push(vec![
        text_cell("incal version"),
        text_cell(&doc.incal_version),
    ]);
    rows.push(vec![text_cell("document"), text_cell(&doc.schema)]);
    rows.push(vec![text_cell("report date"), text_cell(date)]);
    if let Some(r) = record {
        let held = match r.id {
            Some(id) => format!("record {id} in {}", r.store),
            None => format!("not stored in {}", r.store),
        };
        rows.push(vec![text_cell("record"), text_cell(&held)]);
        rows.push(vec![
            text_cell("chain head"),
            (
                false,
                format!(
                    "<span class=\"hash\">{}</span> ({} records, checked whole; <code>incal record verify --head</code> checks a store still holds it)",
                    esc(&r.head),
                    r.records
                ),
            ),
        ]);
    }
    if let Some(v) = verdict_of(doc, None) {
        rows.push(vec![
            text_cell("verdict"),
            (false, verdict_html(&v.verdict)),
        ]);
    }
    s.push_str("<div id=\"identity\">\n");
    s.push_str(&html_table(
        "identity",
        &["item".to_string(), "value".to_string()],
        &rows,
    ));
    s.push_str("</div>\n");
    s.push_str(&inputs_options_html(doc));
    s.push_str("</header>\n");
    s
}

/// The input files (path, SHA-256, rows) and the options of a result.
fn inputs_options_html(doc: &ResultDocument) -> String {
    let mut s = String::from("<h3>Inputs</h3>\n");
    if doc.inputs.is_empty() {
        s.push_str("<p class=\"note\">No input file recorded.</p>\n");
    } else {
        let rows: Vec<Vec<(bool, String)>> = doc
            .inputs
            .iter()
            .map(|i| {
                vec![
                    text_cell(&i.role),
                    text_cell(&i.path),
                    (
                        false,
                        format!("<span class=\"hash\">{}</span>", esc(&i.sha256)),
                    ),
                    i.rows
                        .map_or((false, "–".into()), |r| num_cell(r.to_string())),
                ]
            })
            .collect();
        s.push_str(&html_table(
            "inputs",
            &[
                "role".into(),
                "path".into(),
                "SHA-256".into(),
                "rows".into(),
            ],
            &rows,
        ));
    }
    if !doc.options.is_empty() {
        s.push_str("<h3>Options</h3>\n");
        let rows: Vec<Vec<(bool, String)>> = doc
            .options
            .iter()
            .map(|(k, v)| {
                let text = match v {
                    Value::String(x) => x.clone(),
                    Value::Null => "from the data".into(),
                    Value::Array(a) => a
                        .iter()
                        .map(|x| x.as_str().map_or_else(|| x.to_string(), str::to_string))
                        .collect::<Vec<_>>()
                        .join(", "),
                    // Options are typed numbers: no 17-digit float noise.
                    Value::Number(n) if n.is_f64() => {
                        n.as_f64().map_or(n.to_string(), |x| trimmed(x, 10))
                    }
                    other => other.to_string(),
                };
                vec![text_cell(k), text_cell(&text)]
            })
            .collect();
        s.push_str(&html_table(
            "options",
            &["option".into(), "value".into()],
            &rows,
        ));
    }
    s
}

fn coefficients_html(doc: &ResultDocument) -> String {
    let judged: Vec<Option<Judged>> = doc
        .coefficients
        .iter()
        .map(|(n, _)| verdict_of(doc, Some(n)))
        .collect();
    let any_verdict = judged.iter().any(Option::is_some);
    let rows: Vec<Vec<(bool, String)>> = doc
        .coefficients
        .iter()
        .zip(&judged)
        .map(|((name, c), j)| {
            let (scale, label) = c.unit.engineering_for(c.value);
            let (value, u, u95) = measured(c.value * scale, c.u * scale, c.u95 * scale);
            let mut row = vec![
                (
                    false,
                    format!(
                        "<span class=\"name\" data-name=\"{}\">{}</span>",
                        esc(name),
                        esc(&shown_name(name, label))
                    ),
                ),
                num_cell(value),
                num_cell(u),
                num_cell(u95),
                num_cell(dof_text(c.dof)),
                num_cell(format!("{:.3}", c.k95)),
                text_cell(label),
            ];
            if any_verdict {
                let limits = j.as_ref().map_or(String::from("–"), |j| {
                    let f = |v: Option<f64>| v.map_or("–".to_string(), |v| sig(v * scale, 4));
                    format!("{} … {}", f(j.min), f(j.max))
                });
                row.push(text_cell(&limits));
            }
            row.push(match j {
                Some(j) => (false, verdict_html(&j.verdict)),
                None => text_cell("–"),
            });
            row
        })
        .collect();
    let mut header: Vec<String> = ["name", "value", "u", "U95", "dof", "k95", "unit"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    if any_verdict {
        header.push("limits".into());
    }
    header.push("verdict".into());
    let mut s = String::from("<section id=\"coefficients\">\n<h2>Coefficients</h2>\n");
    s.push_str(&html_table("coefficients", &header, &rows));
    // Limits on terms this result does not report: no row above.
    let missing: Vec<String> = doc
        .verdicts
        .iter()
        .flatten()
        .filter(|(n, _)| doc.coefficients.get(n).is_none())
        .map(|(n, v)| {
            format!(
                "<span class=\"name\">{}</span> {}",
                esc(n),
                verdict_html(v.verdict.as_str())
            )
        })
        .collect();
    if !missing.is_empty() {
        s.push_str(&format!(
            "<p class=\"note\">Limited but not reported by this result (not identified): {}.</p>\n",
            missing.join(", ")
        ));
    }
    s.push_str("<p class=\"note\">u: standard uncertainty; U95 = k95·u covers the value with 95 % probability (k95: Student t for dof; inf: known variance). Values in engineering units (ug = µg; angles in arcsec, or deg from 0.1 rad).");
    if !any_verdict {
        s.push_str(" No limits were given: no verdict.");
    }
    s.push_str("</p>\n</section>\n");
    s
}

fn fits_html(doc: &ResultDocument) -> String {
    let mut s = String::from("<section id=\"fits\">\n<h2>Fits</h2>\n");
    if doc.fits.is_empty() {
        s.push_str("<p class=\"note\">No least-squares fit in this result.</p>\n");
    } else {
        let rows: Vec<Vec<(bool, String)>> = doc
            .fits
            .iter()
            .map(|f| {
                let (scale, label) = f.residual_unit.engineering();
                vec![
                    text_cell(&f.label),
                    num_cell(f.observations.to_string()),
                    num_cell(f.parameters.to_string()),
                    num_cell(f.dof.to_string()),
                    num_cell(f.condition_number.map_or("–".into(), |c| sig(c, 3))),
                    num_cell(f.chi2_p_value.map_or("–".into(), |p| sig(p, 2))),
                    text_cell(match f.variance_source {
                        incal::estimation::VarianceSource::Prior => "scatter/known",
                        incal::estimation::VarianceSource::Residuals => "residuals",
                    }),
                    num_cell(
                        f.residual_rms
                            .map_or("–".into(), |r| format!("{} {label}", sig(r * scale, 3))),
                    ),
                    text_cell(&f.weakest_combination),
                ]
            })
            .collect();
        let header: Vec<String> = [
            "fit",
            "n",
            "p",
            "dof",
            "condition",
            "χ² p",
            "variance",
            "residual rms",
            "weakest combination",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        s.push_str(&html_table("fits", &header, &rows));
        s.push_str("<p class=\"note\">n observations (position means), p parameters; χ² p: lack-of-fit p-value; variance: where the variance behind u came from (the sample scatter or a known noise, or the residuals).</p>\n");
    }
    s.push_str("</section>\n");
    s
}

fn notes_html(doc: &ResultDocument) -> String {
    let mut s = String::from(
        "<section id=\"notes\">\n<h2>Warnings and decisions</h2>\n<h3>Warnings</h3>\n",
    );
    if doc.warnings.is_empty() {
        s.push_str("<p class=\"note\" id=\"no-warnings\">No warnings.</p>\n");
    } else {
        s.push_str("<ul class=\"warnings\">\n");
        for w in &doc.warnings {
            s.push_str(&format!(
                "<li><code>{}</code>: {}</li>\n",
                esc(&w.code.to_string()),
                esc(&w.message)
            ));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("<h3>Decisions</h3>\n");
    if doc.decisions.is_empty() {
        s.push_str("<p class=\"note\">No decisions.</p>\n");
    } else {
        s.push_str("<ul class=\"decisions\">\n");
        for d in &doc.decisions {
            let code = serde_json::to_value(d.code)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            s.push_str(&format!(
                "<li><code>{}</code>: {}</li>\n",
                esc(&code),
                esc(&d.message)
            ));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</section>\n");
    s
}

/// As [`render_html`], with options (a fixed date).
pub fn render_html_with(
    doc: &ResultDocument,
    history: &[HistorySeries],
    opts: &RenderOptions,
) -> Result<String, ReportError> {
    let date = opts.date.clone().unwrap_or_else(format::now_utc_text);
    let mut s = String::from("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    let who = doc
        .instrument
        .serial
        .as_deref()
        .map_or(String::new(), |x| format!(" {x}"));
    let cert = opts.certificate.as_ref();
    let css = match cert {
        Some(c) => format!("{CSS}{}", certificate::print_css(&c.number)),
        None => CSS.to_string(),
    };
    let title = match cert {
        Some(c) => format!("Calibration certificate {}{who}: {}", c.number, doc.title),
        None => format!("incal {}{who}: {}", doc.procedure, doc.title),
    };
    s.push_str(&format!(
        "<title>{}</title>\n<style>{css}</style>\n</head>\n<body>\n",
        esc(&title)
    ));
    match cert {
        Some(c) => {
            let record = opts.record.as_ref().map(|r| {
                let held = match r.id {
                    Some(id) => format!("record {id} in {}", esc(&r.store)),
                    None => format!("not stored in {}", esc(&r.store)),
                };
                format!(
                    "{held}; chain head <span class=\"hash\">{}</span> ({} records, checked whole)",
                    esc(&r.head),
                    r.records
                )
            });
            s.push_str(&certificate::front_html(
                doc,
                c,
                &coefficients_html(doc),
                record,
            ));
            s.push_str("<section id=\"annex-inputs\" class=\"annex-start\">\n<h2>Annex A: inputs and options</h2>\n");
            s.push_str(&inputs_options_html(doc));
            s.push_str(&format!(
                "<p class=\"note\">Computed by incal {} ({}).</p>\n</section>\n",
                esc(&doc.incal_version),
                esc(&doc.schema)
            ));
        }
        None => {
            s.push_str(&header_html(doc, &date, opts.record.as_ref()));
            s.push_str(&coefficients_html(doc));
        }
    }
    s.push_str(&montecarlo::html(doc));
    s.push_str(&fits_html(doc));
    s.push_str(&notes_html(doc));

    s.push_str("<section id=\"tables\">\n<h2>Tables</h2>\n");
    if doc.tables.is_empty() {
        s.push_str("<p class=\"note\">This result has no tables.</p>\n");
    }
    for t in &doc.tables {
        s.push_str(&document_table(t));
    }
    s.push_str("</section>\n");

    let figures = figures(doc);
    s.push_str("<section id=\"plots\">\n<h2>Plots</h2>\n");
    let mut index = 0;
    for p in &figures {
        index += 1;
        s.push_str(&plots::figure_html(p, index)?);
    }
    if figures.is_empty() {
        s.push_str("<p class=\"note\">Nothing to plot: this result has no coefficients.</p>\n");
    }
    s.push_str("</section>\n");

    if !history.is_empty() {
        s.push_str("<section id=\"history\">\n<h2>History of this instrument</h2>\n");
        for h in history {
            index += 1;
            s.push_str(&plots::figure_html(&plots::history_plot(h), index)?);
            let mag = h.points.iter().fold(0.0, |m, p| f64::max(m, p.value.abs()));
            let (scale, label) = plots::display_unit(Some(&h.unit), mag);
            let rows: Vec<Vec<(bool, String)>> = h
                .points
                .iter()
                .map(|p| {
                    vec![
                        num_cell(p.id.to_string()),
                        text_cell(&p.created_utc),
                        // Only U95 is kept here: the value to its second digit.
                        num_cell(measured(p.value * scale, p.u95 * scale, 0.0).0),
                        num_cell(measured(0.0, p.u95 * scale, 0.0).1),
                    ]
                })
                .collect();
            s.push_str(&html_table(
                "history",
                &[
                    "record".into(),
                    "stored (UTC)".into(),
                    esc(&plots::with_unit(&h.coefficient, &label)),
                    esc(&plots::with_unit("U95", &label)),
                ],
                &rows,
            ));
        }
        s.push_str("</section>\n");
    } else if let (Some(r), Some(_)) = (&opts.record, &doc.verdicts) {
        // A store was named but holds no earlier calibration to plot: the
        // first certificate of this instrument says so.
        s.push_str(&format!(
            "<section id=\"history\">\n<h2>History of this instrument</h2>\n<p class=\"note\">No history: {} holds fewer than two calibrations of this instrument by this procedure with the limited coefficients.</p>\n</section>\n",
            esc(&r.store)
        ));
    }
    if let Some(c) = cert {
        s.push_str(&format!(
            "<p id=\"end-of-certificate\">End of certificate {}</p>\n",
            esc(&c.number)
        ));
    }
    if cert.is_none() {
        s.push_str(&format!(
            "<footer>Written by incal-report {} from an {} document of incal {}. Self-contained: this file loads nothing from elsewhere.</footer>\n</body>\n</html>\n",
            env!("CARGO_PKG_VERSION"),
            esc(&doc.schema),
            esc(&doc.incal_version)
        ));
    }
    Ok(s)
}
