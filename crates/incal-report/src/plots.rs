//! Plots as inline SVG, chosen from the shape of the document only (no
//! per-procedure code):
//!
//! * every table with a `residual` column: the residual at each row
//!   against the table's abscissa, with ±U95 bars of the row's mean, and,
//!   when the table also has `mean`, the data (mean) against the fitted
//!   model (mean − residual);
//! * coefficients named `GROUP.NAME` (one block per accelerometer, …):
//!   for every `NAME` shared by two or more groups in one unit, its value
//!   ±U95 across the groups;
//! * when neither gives a plot: every coefficient's value ±U95, one plot
//!   per unit;
//! * the history of a coefficient over the calibrations of an instrument,
//!   with its limits;
//! * a top-level `channels` object with `taus_s` and `oadev` (the noise
//!   result): the Allan plot of each channel, log–log, with its bounds and
//!   the fitted IEEE 952 lines ([`allan_plots`]).
//!
//! The abscissa of a table is its numeric column, before the statistics
//! columns (`n`, `mean`, `std`, `residual`, …), with the most distinct
//! values (the later one on a tie); the other columns before the
//! statistics name the series (a pass, a configuration, a station and
//! polarity). Plots are drawn by `plotters` with its SVG backend only: text
//! is SVG `<text>` in the generic `sans-serif` family, so nothing is
//! loaded from outside the file.

use incal::document::{Cell, ResultDocument, Table};
use incal::estimation::coverage_factor;
use incal::units::Unit;
use plotters::prelude::*;

use crate::format::{esc, trimmed};
use crate::{HistorySeries, ReportError};

/// Columns that hold statistics of a row, not its coordinates.
const STAT_COLUMNS: [&str; 6] = [
    "n",
    "mean",
    "std",
    "residual",
    "standardized_residual",
    "fitted",
];

/// Colours of the series (Tableau 10), also used by the HTML legend.
pub const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// `#rrggbb` of series `k`.
pub fn colour_hex(k: usize) -> String {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// One point, with an optional half-width of its error bar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pt {
    /// Abscissa (display units).
    pub x: f64,
    /// Ordinate (display units).
    pub y: f64,
    /// Half-width of the bar (display units).
    pub bar: Option<f64>,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Dots (with their bars).
    Dots,
    /// A line through the points in the order of x.
    Line,
    /// A thin dashed line (a band's edge).
    Dashed,
}

/// A series of a plot; series with the same `key` share a colour and one
/// entry of the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Index of the legend entry (colour).
    pub key: usize,
    /// How it is drawn.
    pub style: Style,
    /// Points.
    pub points: Vec<Pt>,
}

/// The abscissa: numbers, or categories at 0, 1, 2, …
#[derive(Debug, Clone, PartialEq)]
pub enum XAxis {
    /// Numbers.
    Numeric,
    /// Named positions 0, 1, …
    Categories(Vec<String>),
}

/// A horizontal reference line (zero, a limit).
#[derive(Debug, Clone, PartialEq)]
pub struct HLine {
    /// Ordinate (display units).
    pub y: f64,
    /// A limit (red) or a reference (grey).
    pub limit: bool,
}

/// One plot, independent of how it is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// `residual`, `fitted`, `coefficients` or `history`.
    pub kind: &'static str,
    /// What it is drawn from: a table id, a coefficient name or group.
    pub source: String,
    /// Title (plain text).
    pub title: String,
    /// Axis descriptions (plain text).
    pub x_desc: String,
    /// Axis descriptions (plain text).
    pub y_desc: String,
    /// Abscissa.
    pub x_axis: XAxis,
    /// Shift the dots of series apart along x so that points at the same
    /// abscissa stay visible.
    pub dodge: bool,
    /// Series.
    pub series: Vec<Series>,
    /// Legend entries by key (empty: no legend).
    pub legend: Vec<String>,
    /// Reference lines.
    pub hlines: Vec<HLine>,
    /// What the plot shows and how the bars are computed (plain text).
    pub caption: String,
    /// Coordinates are log10 of the values (Allan plots): ticks are
    /// labelled with the values.
    pub log_log: bool,
}

/// Display scale and label for numbers of `unit` of magnitude up to
/// `magnitude`: the engineering unit of [`Unit::engineering_for`], except
/// that g-based values of 0.1 g or more (a centrifuge output in g) read in
/// g rather than in millions of µg.
pub fn display_unit(unit: Option<&Unit>, magnitude: f64) -> (f64, String) {
    match unit {
        None => (1.0, String::new()),
        Some(Unit::G) if magnitude.abs() >= 0.1 => (1.0, "g".into()),
        Some(u) => {
            let (s, l) = u.engineering_for(magnitude);
            (
                s,
                if l == "1" {
                    String::new()
                } else {
                    l.to_string()
                },
            )
        }
    }
}

/// `name (unit)`, or the name alone for a unit-less quantity.
pub fn with_unit(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    }
}

fn number(c: &Cell) -> Option<f64> {
    match c {
        Cell::Number(x) if x.is_finite() => Some(*x),
        _ => None,
    }
}

fn column(t: &Table, name: &str) -> Option<usize> {
    t.columns.iter().position(|c| c.name == name)
}

/// A cell as a series label part: text as it is, a number as
/// `name value unit` in the column's engineering unit; `None` for null.
fn label_part(t: &Table, k: usize, c: &Cell) -> Option<String> {
    match c {
        Cell::Text(s) => Some(s.clone()),
        Cell::Number(x) => {
            let (scale, unit) = display_unit(t.columns[k].unit.as_ref(), *x);
            let v = trimmed(x * scale, 4);
            Some(if unit.is_empty() {
                format!("{} {v}", t.columns[k].name)
            } else {
                format!("{} {v} {unit}", t.columns[k].name)
            })
        }
        Cell::Null => None,
    }
}

/// Series in one plot before a table is split into panels.
const MAX_SERIES: usize = 6;

/// How the rows of a table are plotted: abscissa, series and panels.
struct Layout {
    /// Column of the abscissa (`None`: the row number).
    x_col: Option<usize>,
    /// Display scale and unit of the abscissa.
    x_scale: f64,
    /// Axis description of the abscissa.
    x_desc: String,
    /// Lead columns that name the series.
    series_cols: Vec<usize>,
}

/// The numeric lead column with the most distinct values (the later one
/// on a tie).
fn abscissa(t: &Table, lead_end: usize) -> Option<usize> {
    let mut best: Option<(usize, usize)> = None;
    for k in 0..lead_end {
        let mut vals: Vec<f64> = Vec::new();
        let mut numeric = true;
        for row in &t.rows {
            match &row[k] {
                Cell::Number(x) => vals.push(*x),
                Cell::Text(_) => numeric = false,
                Cell::Null => {}
            }
        }
        if !numeric || vals.is_empty() {
            continue;
        }
        vals.sort_by(f64::total_cmp);
        vals.dedup();
        if best.is_none_or(|(_, d)| vals.len() >= d) {
            best = Some((k, vals.len()));
        }
    }
    best.map(|(k, _)| k)
}

/// Rows grouped by the label of `cols` (in order of appearance): labels
/// and row indices.
fn group_rows(t: &Table, rows: &[usize], cols: &[usize]) -> (Vec<String>, Vec<Vec<usize>>) {
    let mut labels: Vec<String> = Vec::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for &i in rows {
        let label = cols
            .iter()
            .filter_map(|&k| label_part(t, k, &t.rows[i][k]))
            .collect::<Vec<_>>()
            .join(", ");
        match labels.iter().position(|l| *l == label) {
            Some(g) => groups[g].push(i),
            None => {
                labels.push(label);
                groups.push(vec![i]);
            }
        }
    }
    (labels, groups)
}

/// The residual plot and, with a `mean` column, the fitted-against-data
/// plot of a table (module docs); nothing for a table without `residual`.
/// A table with more than six series is split into panels by its first
/// series column (e.g. one pair of plots per centrifuge station).
pub fn table_plots(t: &Table) -> Vec<Plot> {
    table_plots_with(t, None)
}

/// A fitted model evaluated on a fine grid of a table's abscissa, in the
/// table's units: `(x, y, U95 of y)` (a result's `model_curves.TABLE`).
pub type Curve = Vec<(f64, f64, f64)>;

/// The model curve a result gives for table `id` (`model_curves.ID`:
/// `{"x": [...], "y": [...], "U95": [...]}`), if any.
pub fn model_curve(doc: &ResultDocument, id: &str) -> Option<Curve> {
    let c = doc.extra.get("model_curves")?.get(id)?;
    let arr = |k: &str| -> Option<Vec<f64>> {
        c.get(k)?.as_array()?.iter().map(|v| v.as_f64()).collect()
    };
    let (x, y, u) = (arr("x")?, arr("y")?, arr("U95")?);
    (x.len() == y.len() && y.len() == u.len() && x.len() >= 2).then(|| {
        x.into_iter()
            .zip(y)
            .zip(u)
            .map(|((x, y), u)| (x, y, u))
            .collect()
    })
}

/// As [`table_plots`], with the fitted model drawn as `curve` (the model
/// on a fine grid, with its U95 band) instead of straight lines between
/// the fitted values.
pub fn table_plots_with(t: &Table, curve: Option<&Curve>) -> Vec<Plot> {
    if column(t, "residual").is_none() {
        return Vec::new();
    }
    let lead_end = t
        .columns
        .iter()
        .position(|c| STAT_COLUMNS.contains(&c.name.as_str()))
        .unwrap_or(t.columns.len());
    let x_col = abscissa(t, lead_end);
    let x_mag = x_col.map_or(0.0, |k| {
        t.rows
            .iter()
            .filter_map(|r| number(&r[k]))
            .fold(0.0, |m, x| f64::max(m, x.abs()))
    });
    let (x_scale, x_label) = display_unit(x_col.and_then(|k| t.columns[k].unit.as_ref()), x_mag);
    let x_desc = match x_col {
        Some(k) => with_unit(&t.columns[k].name, &x_label),
        None => "row".to_string(),
    };
    let all: Vec<usize> = (0..t.rows.len()).collect();
    // A lead column with a different value on every row (the nominal rate
    // beside the measured input rate) is another name for the abscissa,
    // not a series: as series it would give one single-point plot per row.
    let series_cols: Vec<usize> = (0..lead_end)
        .filter(|&k| Some(k) != x_col)
        .filter(|&k| t.rows.len() < 2 || group_rows(t, &all, &[k]).1.iter().any(|g| g.len() > 1))
        .collect();
    let (labels, _) = group_rows(t, &all, &series_cols);
    let layout = Layout {
        x_col,
        x_scale,
        x_desc,
        series_cols: series_cols.clone(),
    };
    if labels.len() <= MAX_SERIES || series_cols.len() < 2 {
        return rows_plots(t, &all, &layout, None, curve);
    }
    let panel_col = series_cols[0];
    let (panels, panel_rows) = group_rows(t, &all, &[panel_col]);
    let layout = Layout {
        series_cols: series_cols[1..].to_vec(),
        ..layout
    };
    panels
        .iter()
        .zip(&panel_rows)
        .flat_map(|(p, rows)| rows_plots(t, rows, &layout, Some(p.as_str()), None))
        .collect()
}

/// The residual and fitted plots of `rows` of a table.
fn rows_plots(
    t: &Table,
    rows: &[usize],
    lay: &Layout,
    panel: Option<&str>,
    curve: Option<&Curve>,
) -> Vec<Plot> {
    let Some(res) = column(t, "residual") else {
        return Vec::new();
    };
    let mean = column(t, "mean");
    let (mut legend, groups) = group_rows(t, rows, &lay.series_cols);
    if legend.len() == 1 && legend[0].is_empty() {
        legend.clear();
    }
    // Pooled sample scatter of the rows plotted: (s_p, dof = Σ(n − 1)).
    let (n_col, std_col) = (column(t, "n"), column(t, "std"));
    let pooled = n_col.zip(std_col).and_then(|(nc, sc)| {
        let (mut ss, mut dof) = (0.0, 0.0);
        for &i in rows {
            if let (Some(s), Some(n)) = (number(&t.rows[i][sc]), number(&t.rows[i][nc])) {
                if n >= 2.0 {
                    ss += (n - 1.0) * s * s;
                    dof += n - 1.0;
                }
            }
        }
        (dof > 0.0 && ss.is_finite()).then(|| ((ss / dof).sqrt(), dof))
    });
    let k95 = pooled.map_or(f64::NAN, |(_, dof)| coverage_factor(dof, 0.95));
    let bar = |i: usize| -> Option<f64> {
        let (sp, _) = pooled?;
        let n = number(&t.rows[i][n_col?])?;
        (n >= 1.0).then(|| k95 * sp / n.sqrt())
    };
    let x_of = |i: usize| -> f64 {
        match lay.x_col {
            Some(k) => number(&t.rows[i][k]).map_or(f64::NAN, |x| x * lay.x_scale),
            None => i as f64,
        }
    };
    let bar_text = match pooled {
        Some((sp, dof)) => {
            let (s, l) = display_unit(t.columns[res].unit.as_ref(), sp);
            format!(
                "Bars: ±U95 of each mean, U95 = t95·s_p/√n, with s_p = {} {l} the pooled sample scatter of the rows plotted (ν = Σ(n−1) = {dof:.0}, t95 = {k95:.3}); the fit's uncertainty policy may raise it (see Fits).",
                trimmed(sp * s, 3)
            )
        }
        None => "No bars: no repeated samples (n < 2).".to_string(),
    };
    let series_text = if legend.is_empty() {
        String::new()
    } else {
        format!(
            " One colour per {}.",
            lay.series_cols
                .iter()
                .map(|&k| t.columns[k].name.clone())
                .collect::<Vec<_>>()
                .join(" and ")
        )
    };
    let (in_panel, panel_title) = match panel {
        Some(p) => (format!(" ({p})"), format!(" — {p}")),
        None => (String::new(), String::new()),
    };
    let source = match panel {
        Some(p) => format!("{}: {p}", t.id),
        None => t.id.clone(),
    };
    let x_desc = &lay.x_desc;
    let magnitude = |col: usize| {
        rows.iter()
            .filter_map(|&i| number(&t.rows[i][col]))
            .fold(0.0, |m, x| f64::max(m, x.abs()))
    };

    let mut out = Vec::new();
    let (rs, rl) = display_unit(t.columns[res].unit.as_ref(), magnitude(res));
    let series: Vec<Series> = groups
        .iter()
        .enumerate()
        .map(|(key, rows)| Series {
            key,
            style: Style::Dots,
            points: rows
                .iter()
                .filter_map(|&i| {
                    let y = number(&t.rows[i][res])?;
                    Some(Pt {
                        x: x_of(i),
                        y: y * rs,
                        bar: bar(i).map(|b| b * rs),
                    })
                })
                .filter(|p| p.x.is_finite())
                .collect(),
        })
        .collect();
    out.push(Plot {
        kind: "residual",
        source: source.clone(),
        title: format!("Residuals: {}{panel_title}", t.title),
        x_desc: x_desc.clone(),
        y_desc: with_unit("residual", &rl),
        x_axis: XAxis::Numeric,
        dodge: series.len() > 1,
        series,
        legend: legend.clone(),
        hlines: vec![HLine {
            y: 0.0,
            limit: false,
        }],
        caption: format!(
            "Residual (data − fitted model) of every row of table {}{in_panel} against {x_desc}.{series_text} {bar_text}",
            t.id
        ),
        log_log: false,
    });

    if let Some(mean) = mean {
        let (ms, ml) = display_unit(t.columns[mean].unit.as_ref(), magnitude(mean));
        let mut series = Vec::new();
        for (key, rows) in groups.iter().enumerate() {
            let mut data = Vec::new();
            let mut fitted = Vec::new();
            for &i in rows {
                let (Some(m), x) = (number(&t.rows[i][mean]), x_of(i)) else {
                    continue;
                };
                if !x.is_finite() {
                    continue;
                }
                data.push(Pt {
                    x,
                    y: m * ms,
                    bar: bar(i).map(|b| b * ms),
                });
                if let Some(r) = number(&t.rows[i][res]) {
                    fitted.push(Pt {
                        x,
                        y: (m - r) * ms,
                        bar: None,
                    });
                }
            }
            fitted.sort_by(|a, b| a.x.total_cmp(&b.x));
            if curve.is_none() {
                series.push(Series {
                    key,
                    style: Style::Line,
                    points: fitted,
                });
            }
            series.push(Series {
                key,
                style: Style::Dots,
                points: data,
            });
        }
        let mut legend = legend;
        let line_text = match curve {
            Some(c) => {
                let key = legend.len().max(1);
                if legend.is_empty() {
                    legend.push("data".into());
                }
                legend.push("fitted model +- U95".into());
                let pts = |f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Pt> {
                    c.iter()
                        .map(|p| Pt {
                            x: p.0 * lay.x_scale,
                            y: f(p) * ms,
                            bar: None,
                        })
                        .collect()
                };
                series.push(Series {
                    key,
                    style: Style::Line,
                    points: pts(&|p| p.1),
                });
                series.push(Series {
                    key,
                    style: Style::Dashed,
                    points: pts(&|p| p.1 + p.2),
                });
                series.push(Series {
                    key,
                    style: Style::Dashed,
                    points: pts(&|p| p.1 - p.2),
                });
                "the fitted model evaluated on a fine grid of the abscissa (its curve), dashed: its ±U95 band"
            }
            None => "the fitted model (line through mean − residual at the same abscissae, in order of the abscissa; straight between them, not the model's curve)",
        };
        out.push(Plot {
            kind: "fitted",
            source,
            title: format!("Fitted model and data: {}{panel_title}", t.title),
            x_desc: x_desc.clone(),
            y_desc: with_unit("mean", &ml),
            x_axis: XAxis::Numeric,
            dodge: false,
            series,
            legend,
            hlines: Vec::new(),
            caption: format!(
                "Data (dots: the mean of each row of table {}{in_panel}) against {x_desc} and {line_text}.{series_text} {bar_text}",
                t.id
            ),
            log_log: false,
        });
    }
    out
}

/// Limits `(min, max)` of a coefficient, when a verdict gives them.
pub type Limits = (Option<f64>, Option<f64>);

/// Value ±U95 of `names` (all in one unit) as categories.
fn coefficient_plot(
    doc: &ResultDocument,
    names: &[&str],
    labels: Vec<String>,
    limits: Option<Limits>,
    source: String,
    title: String,
    caption: String,
) -> Option<Plot> {
    let coefs: Vec<_> = names
        .iter()
        .filter_map(|n| doc.coefficients.get(n))
        .collect();
    let first = coefs.first()?;
    let mag = coefs.iter().fold(0.0, |m, c| f64::max(m, c.value.abs()));
    let (s, l) = display_unit(Some(&first.unit), mag);
    let points = coefs
        .iter()
        .enumerate()
        .map(|(i, c)| Pt {
            x: i as f64,
            y: c.value * s,
            bar: Some(c.u95 * s),
        })
        .collect();
    let mut hlines = Vec::new();
    if let Some((lo, hi)) = limits {
        hlines.extend(lo.into_iter().chain(hi).map(|y| HLine {
            y: y * s,
            limit: true,
        }));
    }
    Some(Plot {
        kind: "coefficients",
        source,
        title: title.clone(),
        x_desc: String::new(),
        y_desc: with_unit(&title, &l),
        x_axis: XAxis::Categories(labels),
        dodge: false,
        series: vec![Series {
            key: 0,
            style: Style::Dots,
            points,
        }],
        legend: Vec::new(),
        hlines,
        caption,
        log_log: false,
    })
}

/// Coefficient plots (module docs): one per `NAME` of `GROUP.NAME`
/// coefficients shared by two or more groups in one unit; when `fallback`,
/// and there are none, one per unit over every coefficient. `limits` gives
/// a coefficient's limits, if any.
pub fn coefficient_plots(
    doc: &ResultDocument,
    fallback: bool,
    limits: &dyn Fn(&str) -> Option<Limits>,
) -> Vec<Plot> {
    // Groups in the order of first appearance: a matrix or vector
    // (`R_a.xy`, `b_a.x`: axis components) is one group per name, its
    // diagonal apart from its off-diagonal elements; any other
    // `GROUP.NAME` (`gx.ARW`, `a.K0`) is one group per NAME across groups.
    // Each in one unit.
    struct Group<'a> {
        key: String,
        title: String,
        by_prefix: bool,
        unit: Unit,
        names: Vec<&'a str>,
    }
    let axis =
        |s: &str| (1..=2).contains(&s.len()) && s.chars().all(|c| matches!(c, 'x' | 'y' | 'z'));
    let mut groups: Vec<Group> = Vec::new();
    for (name, c) in doc.coefficients.iter() {
        let Some((prefix, suffix)) = name.rsplit_once('.') else {
            continue;
        };
        let (key, title, by_prefix) = if axis(suffix) {
            let part = match suffix.len() {
                1 => "",
                _ if suffix[..1] == suffix[1..] => " (diagonal)",
                _ => " (off-diagonal)",
            };
            (format!("{prefix}.{part}"), format!("{prefix}{part}"), true)
        } else {
            (format!("*.{suffix}"), suffix.to_string(), false)
        };
        match groups.iter_mut().find(|g| g.key == key && g.unit == c.unit) {
            Some(g) => g.names.push(name),
            None => groups.push(Group {
                key,
                title,
                by_prefix,
                unit: c.unit.clone(),
                names: vec![name],
            }),
        }
    }
    // Values decades apart (a sensing axis near 1 beside cross-axis terms
    // near 1e-3) are not read on one axis: split where sorted magnitudes
    // jump by more than 1.5 decades.
    let mut split: Vec<Group> = Vec::new();
    for g in groups {
        let mut order: Vec<(f64, &str)> = g
            .names
            .iter()
            .filter_map(|n| {
                doc.coefficients
                    .get(n)
                    .map(|c| (c.value.abs().max(1e-300).log10(), *n))
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut cuts = vec![0];
        for i in 1..order.len() {
            if order[i].0 - order[i - 1].0 > 1.5 {
                cuts.push(i);
            }
        }
        if cuts.len() == 1 {
            split.push(g);
            continue;
        }
        cuts.push(order.len());
        for w in cuts.windows(2) {
            let members: Vec<&str> = order[w[0]..w[1]].iter().map(|(_, n)| *n).collect();
            // Keep the document's order within each part.
            let names: Vec<&str> = g
                .names
                .iter()
                .copied()
                .filter(|n| members.contains(n))
                .collect();
            let top = order[w[1] - 1].0.round() as i64;
            split.push(Group {
                key: format!("{} ~1e{top}", g.key),
                title: format!("{} (about 1e{top})", g.title),
                by_prefix: g.by_prefix,
                unit: g.unit.clone(),
                names,
            });
        }
    }
    let common_limits = |names: &[&str]| -> Option<Limits> {
        let first = limits(names.first()?)?;
        names
            .iter()
            .all(|n| limits(n) == Some(first))
            .then_some(first)
    };
    let mut out: Vec<Plot> = split
        .iter()
        .filter(|g| g.names.len() >= 2)
        .filter_map(|g| {
            let names = &g.names;
            let part = |n: &&str| -> String {
                match n.rsplit_once('.') {
                    Some((p, s)) => if g.by_prefix { s } else { p }.to_string(),
                    None => n.to_string(),
                }
            };
            let labels: Vec<String> = names.iter().map(part).collect();
            coefficient_plot(
                doc,
                names,
                labels.clone(),
                common_limits(names),
                g.key.clone(),
                g.title.clone(),
                format!(
                    "{} {} with their ±U95 (k95·u of each coefficient){}.",
                    if g.by_prefix { "The elements" } else { "Every" },
                    if g.by_prefix {
                        format!("{} of {}", labels.join(", "), g.title)
                    } else {
                        format!("{} of {}", g.title, labels.join(", "))
                    },
                    if common_limits(names).is_some() {
                        "; red lines: its limits"
                    } else {
                        ""
                    }
                ),
            )
        })
        .collect();
    if out.is_empty() && fallback {
        let mut units: Vec<(Unit, Vec<&str>)> = Vec::new();
        for (name, c) in doc.coefficients.iter() {
            match units.iter_mut().find(|(u, _)| *u == c.unit) {
                Some(g) => g.1.push(name),
                None => units.push((c.unit.clone(), vec![name])),
            }
        }
        out = units
            .iter()
            .filter_map(|(unit, names)| {
                coefficient_plot(
                    doc,
                    names,
                    names.iter().map(|n| n.to_string()).collect(),
                    common_limits(names),
                    format!("unit {unit}"),
                    "value".into(),
                    format!(
                        "Every coefficient in {unit} with its ±U95 (k95·u); no table of this result has residuals to plot."
                    ),
                )
            })
            .collect();
    }
    out
}

/// The history plot of one coefficient: value ±U95 of each calibration
/// against its date (days since the first calibration), with the drift
/// line and its ±U95 band when there is one, and the limits. Without
/// readable dates the calibrations are spaced evenly, by record id.
pub fn history_plot(h: &HistorySeries) -> Plot {
    let mag = h.points.iter().fold(0.0, |m, p| f64::max(m, p.value.abs()));
    let (s, l) = display_unit(Some(&h.unit), mag);
    let first = h
        .points
        .first()
        .map(|p| p.created_utc.clone())
        .unwrap_or_default();
    let days: Option<Vec<f64>> = h
        .points
        .iter()
        .map(|p| {
            let a = incal_records::time::parse_utc(&first).ok()?;
            let b = incal_records::time::parse_utc(&p.created_utc).ok()?;
            Some((b - a) as f64 / 86_400.0)
        })
        .collect();
    let dated = days.as_ref().is_some_and(|d| d.iter().any(|x| *x != 0.0));
    let x_of = |i: usize| match (&days, dated) {
        (Some(d), true) => d[i],
        _ => i as f64,
    };
    let points = h
        .points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.value.is_finite())
        .map(|(i, p)| Pt {
            x: x_of(i),
            y: p.value * s,
            bar: p.u95.is_finite().then_some(p.u95 * s),
        })
        .collect();
    let hlines = [h.min, h.max]
        .into_iter()
        .flatten()
        .filter(|y| y.is_finite())
        .map(|y| HLine {
            y: y * s,
            limit: true,
        })
        .collect();
    let mut series = Vec::new();
    let mut drift_note = String::new();
    match (&h.drift, dated) {
        (Some(d), true) => {
            let t_end = days
                .as_ref()
                .map_or(0.0, |v| v.iter().fold(0.0, |m, x| f64::max(m, *x)));
            let line = |t: f64| d.intercept + d.rate_per_day * t;
            let half = |t: f64| {
                let c = &d.covariance;
                d.k95
                    * (c[0][0] + 2.0 * t * c[0][1] + t * t * c[1][1])
                        .max(0.0)
                        .sqrt()
            };
            let ts: Vec<f64> = (0..=40).map(|k| t_end * k as f64 / 40.0).collect();
            let curve = |f: &dyn Fn(f64) -> f64| -> Vec<Pt> {
                ts.iter()
                    .map(|&t| Pt {
                        x: t,
                        y: f(t) * s,
                        bar: None,
                    })
                    .filter(|p| p.y.is_finite())
                    .collect()
            };
            series.push(Series {
                key: 1,
                style: Style::Line,
                points: curve(&line),
            });
            for sign in [-1.0, 1.0] {
                series.push(Series {
                    key: 1,
                    style: Style::Dashed,
                    points: curve(&|t| line(t) + sign * half(t)),
                });
            }
            drift_note = format!(
                "; line: the drift, {} {l}/day, dashed: its ±U95 band",
                trimmed(d.rate_per_day * s, 3)
            );
        }
        _ => series.push(Series {
            key: 0,
            style: Style::Line,
            points: h
                .points
                .iter()
                .enumerate()
                .filter(|(_, p)| p.value.is_finite())
                .map(|(i, p)| Pt {
                    x: x_of(i),
                    y: p.value * s,
                    bar: None,
                })
                .collect(),
        }),
    }
    series.push(Series {
        key: 0,
        style: Style::Dots,
        points,
    });
    let (x_desc, x_axis) = if dated {
        (
            format!(
                "days since the first calibration ({})",
                first.chars().take(10).collect::<String>()
            ),
            XAxis::Numeric,
        )
    } else {
        (
            "calibration (record id)".to_string(),
            XAxis::Categories(h.points.iter().map(|p| format!("#{}", p.id)).collect()),
        )
    };
    Plot {
        kind: "history",
        source: h.coefficient.clone(),
        title: format!("History of {}", h.coefficient),
        x_desc,
        y_desc: with_unit(&h.coefficient, &l),
        x_axis,
        dodge: false,
        series,
        legend: Vec::new(),
        hlines,
        caption: format!(
            "{} of this instrument in every stored calibration, by date, with ±U95 bars{drift_note}{}.",
            h.coefficient,
            match (h.min, h.max) {
                (None, None) => "; no limits given".to_string(),
                _ => format!(
                    "; red lines: the limits ({})",
                    [
                        h.min.map(|v| format!("min {} {l}", trimmed(v * s, 4))),
                        h.max.map(|v| format!("max {} {l}", trimmed(v * s, 4)))
                    ]
                    .into_iter()
                    .flatten()
                    .collect::<Vec<_>>()
                    .join(", ")
                ),
            }
        ),
        log_log: false,
    }
}

/// Range `[lo, hi]` of `values`, widened by 6 % (a span of zero becomes
/// ±10 % of the value, or ±1).
fn padded(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= f64::EPSILON * hi.abs().max(lo.abs()) || span == 0.0 {
        let d = if hi.abs() > 0.0 { 0.1 * hi.abs() } else { 1.0 };
        return (lo - d, hi + d);
    }
    (lo - 0.06 * span, hi + 0.06 * span)
}

fn plot_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> ReportError {
    ReportError::Plot(e.to_string())
}

/// Width and height of a plot (px; the CSS scales it to the page):
/// lower for category plots (coefficients, history).
fn size(p: &Plot) -> (u32, u32) {
    match p.x_axis {
        XAxis::Numeric => (760, 380),
        XAxis::Categories(_) => (760, 300),
    }
}

/// A tick label: enough significant digits that neighbouring ticks (about
/// an eighth of the span apart) read differently — at least 4, so a
/// coefficient at 618.79″ spanning 0.004″ reads 618.7915, 618.7920, …
/// rather than "618.8" on every tick — and 0 for a tick within a
/// millionth of the span of zero (not `-1.1e-19`).
fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-6 * span.abs() {
        return "0".into();
    }
    let step = span.abs() / 8.0;
    let digits = if step > 0.0 && step.is_finite() {
        let lead = v.abs().max(step).log10().floor();
        (lead - step.log10().floor() + 1.0).clamp(4.0, 10.0) as usize
    } else {
        4
    };
    trimmed(v, digits)
}

/// The plot as one `<svg>` element (no XML declaration, no namespace
/// URL: inline SVG in HTML needs neither).
pub fn render_svg(p: &Plot) -> Result<String, ReportError> {
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size(p)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let (x0, x1) = match &p.x_axis {
            XAxis::Numeric => padded(p.series.iter().flat_map(|s| s.points.iter().map(|q| q.x))),
            XAxis::Categories(c) => (-0.5, c.len().max(1) as f64 - 0.5),
        };
        let (y0, y1) = padded(
            p.series
                .iter()
                .flat_map(|s| s.points.iter())
                .flat_map(|q| {
                    let b = q.bar.unwrap_or(0.0);
                    [q.y - b, q.y + b]
                })
                .chain(p.hlines.iter().map(|h| h.y)),
        );
        let mut chart = ChartBuilder::on(&root)
            .margin(14)
            .x_label_area_size(if p.x_desc.is_empty() { 30 } else { 46 })
            .y_label_area_size(84)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(plot_err)?;
        let categories = match &p.x_axis {
            XAxis::Categories(c) => Some(c.clone()),
            XAxis::Numeric => None,
        };
        let log_log = p.log_log;
        let x_fmt = |x: &f64| match &categories {
            Some(c) => {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < c.len() {
                    c[i as usize].clone()
                } else {
                    String::new()
                }
            }
            None if log_log => trimmed(10f64.powf(*x), 3),
            None => tick(*x, x1 - x0),
        };
        let y_fmt = |y: &f64| {
            if log_log {
                trimmed(10f64.powf(*y), 3)
            } else {
                tick(*y, y1 - y0)
            }
        };
        let n_x_labels = categories.as_ref().map_or(10, |c| c.len().clamp(1, 24));
        chart
            .configure_mesh()
            .x_desc(p.x_desc.as_str())
            .y_desc(p.y_desc.as_str())
            .x_labels(n_x_labels)
            .y_labels(8)
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .bold_line_style(BLACK.mix(0.12))
            .light_line_style(BLACK.mix(0.04))
            .draw()
            .map_err(plot_err)?;
        for h in &p.hlines {
            let style = if h.limit {
                RGBColor(200, 0, 0).stroke_width(2)
            } else {
                BLACK.mix(0.45).stroke_width(1)
            };
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, h.y), (x1, h.y)],
                    style,
                )))
                .map_err(plot_err)?;
        }
        let cap = 0.008 * (x1 - x0);
        let keys = p.series.iter().map(|s| s.key + 1).max().unwrap_or(1);
        for s in &p.series {
            // Dodged series sit side by side, 1 % of the span apart.
            let shift = if p.dodge {
                0.01 * (x1 - x0) * (s.key as f64 - 0.5 * (keys as f64 - 1.0))
            } else {
                0.0
            };
            let moved: Vec<Pt> = s
                .points
                .iter()
                .map(|q| Pt {
                    x: q.x + shift,
                    ..*q
                })
                .collect();
            let (r, g, b) = PALETTE[s.key % PALETTE.len()];
            let colour = RGBColor(r, g, b);
            match s.style {
                Style::Line => {
                    chart
                        .draw_series(LineSeries::new(
                            s.points.iter().map(|q| (q.x, q.y)),
                            colour.stroke_width(2),
                        ))
                        .map_err(plot_err)?;
                }
                Style::Dashed => {
                    chart
                        .draw_series(DashedLineSeries::new(
                            s.points.iter().map(|q| (q.x, q.y)),
                            6,
                            4,
                            colour.stroke_width(1),
                        ))
                        .map_err(plot_err)?;
                }
                Style::Dots => {
                    for q in &moved {
                        if let Some(b) = q.bar.filter(|b| *b > 0.0 && b.is_finite()) {
                            let segs = [
                                vec![(q.x, q.y - b), (q.x, q.y + b)],
                                vec![(q.x - cap, q.y - b), (q.x + cap, q.y - b)],
                                vec![(q.x - cap, q.y + b), (q.x + cap, q.y + b)],
                            ];
                            chart
                                .draw_series(
                                    segs.into_iter()
                                        .map(|v| PathElement::new(v, colour.stroke_width(1))),
                                )
                                .map_err(plot_err)?;
                        }
                    }
                    chart
                        .draw_series(
                            moved
                                .iter()
                                .map(|q| Circle::new((q.x, q.y), 4, colour.filled())),
                        )
                        .map_err(plot_err)?;
                }
            }
        }
        root.present().map_err(plot_err)?;
    }
    // Inline SVG in HTML takes its namespace from the parser: drop the
    // xmlns URL so that the file names no address at all.
    Ok(buf.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

/// The plot as an HTML `<figure>`: title, the SVG, a legend in HTML (one
/// swatch per series colour) and the caption.
pub fn figure_html(p: &Plot, index: usize) -> Result<String, ReportError> {
    let svg = render_svg(p)?;
    let mut s = format!(
        "<figure class=\"plot\" id=\"plot-{index}\" data-plot=\"{}\" data-source=\"{}\">\n<h3>{}</h3>\n",
        esc(p.kind),
        esc(&p.source),
        esc(&p.title)
    );
    s.push_str(&svg);
    if !p.legend.is_empty() {
        s.push_str("<p class=\"legend\">");
        for (k, l) in p.legend.iter().enumerate() {
            s.push_str(&format!(
                "<span class=\"key\"><span class=\"swatch\" style=\"background-color:{}\"></span>{}</span> ",
                colour_hex(k),
                esc(l)
            ));
        }
        s.push_str("</p>\n");
    }
    s.push_str(&format!(
        "<figcaption>{}</figcaption>\n</figure>\n",
        esc(&p.caption)
    ));
    Ok(s)
}

/// The legend of an IEEE Std 952 term line: its letter, and the term as
/// the result reports it, in the term's unit with U95 (`N: ARW 0.0500
/// +- 0.0005 deg/sqrt(h)`).
fn term_legend(doc: &ResultDocument, channel: &str, letter: &str) -> String {
    let names: &[&str] = match letter {
        "Q" => &["quantization", "Q"],
        "N" => &["ARW", "VRW", "N"],
        "B" => &["bias_instability", "B"],
        "K" => &["RRW", "acceleration_random_walk", "K"],
        "R" => &["rate_ramp", "acceleration_ramp", "R"],
        _ => &[],
    };
    for n in names {
        if let Some(c) = doc.coefficients.get(&format!("{channel}.{n}")) {
            let (scale, label) = c.unit.engineering_for(c.value);
            let (v, _, u95) = crate::format::measured(c.value * scale, c.u * scale, c.u95 * scale);
            return format!("term {letter}: {n} {v} +- {u95} {label} (U95)");
        }
    }
    format!("term {letter}")
}

/// The Allan plot of each channel of a noise result (`channels` in the
/// document): OADEV against τ on log–log axes with its confidence bounds as
/// bars, the fitted IEEE 952 model and each identified term's line.
pub fn allan_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(chans) = doc.extra.get("channels").and_then(|c| c.as_object()) else {
        return Vec::new();
    };
    let conf = doc
        .options
        .get("confidence")
        .and_then(|v| v.as_f64())
        .unwrap_or(0.683);
    let nums = |v: &serde_json::Value| -> Vec<Option<f64>> {
        v.as_array()
            .map(|a| a.iter().map(|x| x.as_f64().filter(|x| *x > 0.0)).collect())
            .unwrap_or_default()
    };
    let mut out = Vec::new();
    for (name, c) in chans {
        let taus = nums(&c["taus_s"]);
        let (val, lo, hi) = (
            nums(&c["oadev"]["value"]),
            nums(&c["oadev"]["lo"]),
            nums(&c["oadev"]["hi"]),
        );
        let unit = c["unit"].as_str().unwrap_or("").to_string();
        let mut series = Vec::new();
        let mut dots = Vec::new();
        for (k, t) in taus.iter().enumerate() {
            let (Some(t), Some(v)) = (t, val.get(k).copied().flatten()) else {
                continue;
            };
            dots.push(Pt {
                x: t.log10(),
                y: v.log10(),
                bar: None,
            });
            if let (Some(l), Some(h)) = (lo.get(k).copied().flatten(), hi.get(k).copied().flatten())
            {
                series.push(Series {
                    key: 0,
                    style: Style::Line,
                    points: vec![
                        Pt {
                            x: t.log10(),
                            y: l.log10(),
                            bar: None,
                        },
                        Pt {
                            x: t.log10(),
                            y: h.log10(),
                            bar: None,
                        },
                    ],
                });
            }
        }
        if dots.is_empty() {
            continue;
        }
        series.push(Series {
            key: 0,
            style: Style::Dots,
            points: dots,
        });
        let line = |v: &serde_json::Value| -> Vec<Pt> {
            nums(v)
                .iter()
                .zip(&taus)
                .filter_map(|(y, t)| {
                    Some(Pt {
                        x: t.as_ref()?.log10(),
                        y: y.as_ref()?.log10(),
                        bar: None,
                    })
                })
                .collect()
        };
        let mut legend = vec![format!("OADEV with {} % bounds", trimmed(100.0 * conf, 3))];
        let fit = line(&c["fit_oadev"]);
        if !fit.is_empty() {
            legend.push("fitted IEEE 952 model".into());
            series.push(Series {
                key: legend.len() - 1,
                style: Style::Line,
                points: fit,
            });
        }
        if let Some(terms) = c["fit_terms_oadev"].as_object() {
            for (t, v) in terms {
                let pts = line(v);
                if !pts.is_empty() {
                    legend.push(term_legend(doc, name, t));
                    series.push(Series {
                        key: legend.len() - 1,
                        style: Style::Line,
                        points: pts,
                    });
                }
            }
        }
        // The other deviations of the same unit, as lines (TDEV, in the
        // unit times s, has its own axis in the tables).
        for dev in ["mdev", "ohdev", "totdev"] {
            let d = &c[dev];
            let taus_d = nums(&d["taus_s"]);
            let pts: Vec<Pt> = nums(&d["value"])
                .iter()
                .zip(&taus_d)
                .filter_map(|(y, t)| {
                    Some(Pt {
                        x: t.as_ref()?.log10(),
                        y: y.as_ref()?.log10(),
                        bar: None,
                    })
                })
                .collect();
            if pts.len() >= 2 {
                legend.push(dev.to_uppercase());
                series.push(Series {
                    key: legend.len() - 1,
                    style: Style::Dashed,
                    points: pts,
                });
            }
        }
        // Term lines far below the data would squash the plot: keep them
        // within two decades under the lowest deviation.
        let floor = series
            .iter()
            .filter(|s| s.key == 0)
            .flat_map(|s| s.points.iter().map(|p| p.y))
            .fold(f64::INFINITY, f64::min)
            - 2.0;
        for s in series.iter_mut().filter(|s| s.key > 1) {
            s.points.retain(|p| p.y >= floor);
        }
        series.retain(|s| !s.points.is_empty());
        out.push(Plot {
            kind: "allan",
            source: name.clone(),
            title: format!("{name}: Allan deviation"),
            x_desc: "averaging time tau (s)".into(),
            y_desc: format!("deviation ({unit})"),
            x_axis: XAxis::Numeric,
            dodge: false,
            series,
            legend,
            hlines: Vec::new(),
            caption: format!(
                "Overlapping Allan deviation against averaging time, log-log; bars: chi-square bounds at {} % confidence with the equivalent degrees of freedom of the identified noise (Greenhall & Riley); lines: the IEEE Std 952 model fitted by weighted least squares and each identified term (its value in the term's unit in the legend); dashed: the other deviations of the same unit (MDEV, OHDEV, TOTDEV).",
                trimmed(100.0 * conf, 3)
            ),
            log_log: true,
        });
    }
    out
}

/// The plots of a thermal model: per coefficient or channel, its points
/// (plateaus or ramp blocks, bars ±U95 of each) against temperature with
/// the fitted polynomial drawn as a curve and its ±U95 band (from the
/// `model.NAME` table), then the residuals against temperature.
pub fn thermal_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(map) = doc.extra.get("thermal").and_then(|m| m.as_object()) else {
        return Vec::new();
    };
    let find = |id: &str| doc.tables.iter().find(|t| t.id == id);
    let mut out = Vec::new();
    for name in map.keys() {
        let points = find(&format!("plateaus.{name}")).or_else(|| find(&format!("ramp.{name}")));
        let model = find(&format!("model.{name}"));
        let (Some(pts), Some(model)) = (points, model) else {
            continue;
        };
        let (Some(pt_t), Some(pt_u), Some(pt_r)) = (
            column(pts, "temperature_c"),
            column(pts, "u"),
            column(pts, "residual"),
        ) else {
            continue;
        };
        let Some(pt_y) = column(pts, "value").or_else(|| column(pts, "mean")) else {
            continue;
        };
        let (Some(m_t), Some(m_y), Some(m_u95)) = (
            column(model, "temperature_c"),
            column(model, "polynomial"),
            column(model, "U95"),
        ) else {
            continue;
        };
        let unit = pts.columns[pt_y].unit.clone();
        let k = incal::estimation::coverage_factor(f64::INFINITY, 0.95);
        let rows: Vec<(f64, f64, f64, f64)> = pts
            .rows
            .iter()
            .filter_map(|r| {
                Some((
                    number(&r[pt_t])?,
                    number(&r[pt_y])?,
                    number(&r[pt_u])?,
                    number(&r[pt_r])?,
                ))
            })
            .collect();
        let curve: Vec<(f64, f64, f64)> = model
            .rows
            .iter()
            .filter_map(|r| Some((number(&r[m_t])?, number(&r[m_y])?, number(&r[m_u95])?)))
            .collect();
        if rows.is_empty() || curve.is_empty() {
            continue;
        }
        let mag = rows.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
        let (scale, label) = display_unit(unit.as_ref(), mag);
        let line = |f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Pt> {
            curve
                .iter()
                .map(|c| Pt {
                    x: c.0,
                    y: f(c) * scale,
                    bar: None,
                })
                .collect()
        };
        let series = vec![
            Series {
                key: 0,
                style: Style::Dots,
                points: rows
                    .iter()
                    .map(|r| Pt {
                        x: r.0,
                        y: r.1 * scale,
                        bar: Some(k * r.2 * scale),
                    })
                    .collect(),
            },
            Series {
                key: 1,
                style: Style::Line,
                points: line(&|c| c.1),
            },
            Series {
                key: 2,
                style: Style::Dashed,
                points: line(&|c| c.1 + c.2),
            },
            Series {
                key: 2,
                style: Style::Dashed,
                points: line(&|c| c.1 - c.2),
            },
        ];
        out.push(Plot {
            kind: "fitted",
            source: name.clone(),
            title: format!("{name} against temperature"),
            x_desc: "temperature (degC)".into(),
            y_desc: with_unit(name, &label),
            x_axis: XAxis::Numeric,
            dodge: false,
            series,
            legend: vec![
                format!("{} (bars: +-U95)", pts.title),
                "fitted polynomial".into(),
                "polynomial +- U95".into(),
            ],
            hlines: Vec::new(),
            caption: format!(
                "{name} at each point of table {} against temperature, bars +-U95 of the point; the polynomial of degree {} fitted to them, drawn as a curve over the valid range, with its expanded uncertainty band (table {}).",
                pts.id,
                map[name]["degree"].as_u64().unwrap_or(0),
                model.id
            ),
            log_log: false,
        });
        let rmag = rows.iter().map(|r| r.3.abs().max(r.2)).fold(0.0, f64::max);
        let (rs, rl) = display_unit(unit.as_ref(), rmag);
        out.push(Plot {
            kind: "residual",
            source: pts.id.clone(),
            title: format!("{name}: residual after compensation"),
            x_desc: "temperature (degC)".into(),
            y_desc: with_unit("residual", &rl),
            x_axis: XAxis::Numeric,
            dodge: false,
            series: vec![Series {
                key: 0,
                style: Style::Dots,
                points: rows
                    .iter()
                    .map(|r| Pt {
                        x: r.0,
                        y: r.3 * rs,
                        bar: Some(k * r.2 * rs),
                    })
                    .collect(),
            }],
            legend: Vec::new(),
            hlines: vec![HLine {
                y: 0.0,
                limit: false,
            }],
            caption: format!(
                "What is left of {name} after the polynomial is taken off (point minus model) over the valid range, bars +-U95 of the point: the compensation's residual."
            ),
            log_log: false,
        });
    }
    out
}

#[cfg(test)]
mod tests {

    /// A table whose nominal and measured abscissae both differ on every
    /// row (gyro rate: `rate`, `input_rate`) gives one residual and one
    /// fitted plot, not one single-point panel per rate.
    #[test]
    fn a_column_unique_per_row_is_not_a_series() {
        let mut t = Table::new(
            "positions",
            "Positions",
            &[
                ("rate", None),
                ("input_rate", None),
                ("run", None),
                ("n", None),
                ("mean", None),
                ("std", None),
                ("residual", None),
            ],
        );
        for k in 0..10 {
            let r = (k as f64 - 4.5) * 20.0;
            t.push(vec![
                Cell::num(r),
                Cell::num(r * 0.99998),
                Cell::Null,
                Cell::num(4.0),
                Cell::num(r * 0.02),
                Cell::num(1e-5),
                Cell::num(1e-6 * (k as f64 - 5.0)),
            ])
            .unwrap();
        }
        let plots = table_plots(&t);
        assert_eq!(
            plots.len(),
            2,
            "{:?}",
            plots.iter().map(|p| &p.title).collect::<Vec<_>>()
        );
        assert!(plots
            .iter()
            .all(|p| p.series.iter().map(|s| s.points.len()).sum::<usize>() >= 10));
    }

    /// A matrix is plotted per matrix, its diagonal apart from its
    /// off-diagonal elements; a term shared by units is split where its
    /// values are decades apart (a sensing axis beside cross-axis terms).
    #[test]
    fn coefficients_decades_apart_or_of_a_matrix_get_their_own_axis() {
        use incal::document::{Coefficient, DocumentBuilder, Procedure};
        let mut b = DocumentBuilder::new(Procedure::ImuFerraris, "t");
        for (n, v) in [
            ("R.xx", 1.0),
            ("R.yy", 0.999),
            ("R.xy", 1e-3),
            ("R.yx", -2e-3),
            ("a.Ks_x", 1.0),
            ("b.Ks_x", 1e-3),
            ("c.Ks_x", -2e-3),
        ] {
            b.coefficient(n, Coefficient::new(n, v, 1e-5, Unit::One, 10.0).unwrap())
                .unwrap();
        }
        let doc = b.finish();
        let titles: Vec<String> = coefficient_plots(&doc, false, &|_| None)
            .into_iter()
            .map(|p| p.title)
            .collect();
        assert_eq!(
            titles,
            ["R (diagonal)", "R (off-diagonal)", "Ks_x (about 1e-3)"],
            "{titles:?}"
        );
    }

    /// With the model on a grid, the fitted plot draws the model's curve
    /// and its band, not straight lines between the fitted values.
    #[test]
    fn the_fitted_plot_draws_the_model_curve_when_given() {
        let mut t = Table::new(
            "positions",
            "Positions",
            &[
                ("angle", Some(Unit::Deg)),
                ("n", None),
                ("mean", Some(Unit::Output)),
                ("std", Some(Unit::Output)),
                ("residual", Some(Unit::Output)),
            ],
        );
        for k in 0..12 {
            let a = 30.0 * k as f64;
            t.push(vec![
                Cell::num(a),
                Cell::num(4.0),
                Cell::num(10.0 * a.to_radians().sin()),
                Cell::num(1e-6),
                Cell::num(0.0),
            ])
            .unwrap();
        }
        let curve: Curve = (0..=110)
            .map(|i| {
                let a = 3.0 * i as f64;
                (a, 10.0 * a.to_radians().sin(), 1e-6)
            })
            .collect();
        let without = table_plots(&t);
        let with = table_plots_with(&t, Some(&curve));
        let fitted = |ps: &[Plot]| ps.iter().find(|p| p.kind == "fitted").cloned().unwrap();
        let (a, b) = (fitted(&without), fitted(&with));
        let longest = |p: &Plot| {
            p.series
                .iter()
                .filter(|s| s.style == Style::Line)
                .map(|s| s.points.len())
                .max()
                .unwrap_or(0)
        };
        assert_eq!(longest(&a), 12, "lines between the 12 fitted values");
        assert_eq!(longest(&b), 111, "the curve");
        assert_eq!(
            b.series.iter().filter(|s| s.style == Style::Dashed).count(),
            2
        );
        assert!(b.caption.contains("its curve"), "{}", b.caption);
        assert!(b.legend.iter().any(|l| l.contains("fitted model")));
    }

    #[test]
    fn ticks_of_a_narrow_span_read_differently() {
        let span = 0.004;
        let labels: Vec<String> = (0..8)
            .map(|k| tick(618.7900 + k as f64 * 0.0005, span))
            .collect();
        let mut unique = labels.clone();
        unique.dedup();
        assert_eq!(unique.len(), labels.len(), "{labels:?}");
        assert_eq!(labels[3], "618.7915");
        // A wide span keeps 4 digits; a tick at zero reads 0.
        assert_eq!(tick(1234.5678, 5000.0), "1235");
        assert_eq!(tick(1e-19, 1.0), "0");
    }

    use super::*;
    use incal::document::Column;

    fn table() -> Table {
        Table {
            id: "positions".into(),
            title: "Positions".into(),
            columns: vec![
                Column {
                    name: "angle".into(),
                    unit: Some(Unit::Deg),
                },
                Column {
                    name: "pass".into(),
                    unit: None,
                },
                Column {
                    name: "n".into(),
                    unit: None,
                },
                Column {
                    name: "mean".into(),
                    unit: Some(Unit::Output),
                },
                Column {
                    name: "std".into(),
                    unit: Some(Unit::Output),
                },
                Column {
                    name: "residual".into(),
                    unit: Some(Unit::Output),
                },
            ],
            rows: vec![
                vec![
                    Cell::Number(0.0),
                    Cell::Text("cw".into()),
                    Cell::Number(4.0),
                    Cell::Number(1.0),
                    Cell::Number(0.1),
                    Cell::Number(0.01),
                ],
                vec![
                    Cell::Number(90.0),
                    Cell::Text("cw".into()),
                    Cell::Number(4.0),
                    Cell::Number(2.0),
                    Cell::Number(0.1),
                    Cell::Number(-0.01),
                ],
                vec![
                    Cell::Number(0.0),
                    Cell::Text("ccw".into()),
                    Cell::Number(4.0),
                    Cell::Number(1.1),
                    Cell::Number(0.1),
                    Cell::Number(0.02),
                ],
            ],
        }
    }

    #[test]
    fn a_table_with_residuals_gives_residual_and_fitted_plots() {
        let plots = table_plots(&table());
        assert_eq!(plots.len(), 2);
        let (r, f) = (&plots[0], &plots[1]);
        assert_eq!(r.kind, "residual");
        assert_eq!(r.x_desc, "angle (deg)");
        assert_eq!(r.legend, ["cw", "ccw"]);
        assert_eq!(r.series.len(), 2);
        // Pooled s_p = 0.1 on 9 dof; bar = t95(9)·0.1/2.
        let b = r.series[0].points[0].bar.unwrap();
        assert!((b - coverage_factor(9.0, 0.95) * 0.05).abs() < 1e-12);
        assert_eq!(f.kind, "fitted");
        let fitted = &f.series[0];
        assert_eq!(fitted.style, Style::Line);
        assert_eq!(fitted.points[1].y, 2.0 + 0.01);
        assert!(render_svg(f).unwrap().starts_with("<svg"));
    }

    #[test]
    fn tables_without_residuals_give_no_plot() {
        let mut t = table();
        t.columns[5].name = "difference".into();
        assert!(table_plots(&t).is_empty());
    }

    #[test]
    fn centrifuge_outputs_in_g_read_in_g() {
        assert_eq!(display_unit(Some(&Unit::G), 25.0), (1.0, "g".into()));
        assert_eq!(display_unit(Some(&Unit::G), 1e-4), (1e6, "ug".into()));
        assert_eq!(display_unit(Some(&Unit::One), 1.0), (1.0, String::new()));
    }

    #[test]
    fn flat_ranges_are_widened() {
        assert_eq!(padded([2.0, 2.0].into_iter()), (1.8, 2.2));
        assert_eq!(padded(std::iter::empty()), (-1.0, 1.0));
        let (lo, hi) = padded([0.0, 1.0].into_iter());
        assert!(lo < 0.0 && hi > 1.0);
    }
}
