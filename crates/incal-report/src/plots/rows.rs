//! The two plots of some rows of a table (module docs of `plots`): the
//! residual of each row, and the mean of each row against the fitted
//! model, with the ±U95 bar of each mean from the pooled scatter of the
//! rows plotted.

use incal::document::Table;
use incal::estimation::coverage_factor;

use super::table::{group_rows, Curve, Layout};
use super::{column, display_unit, number, with_unit, HLine, Plot, Pt, Series, Style, XAxis};
use crate::format::trimmed;

/// The residual and fitted plots of `rows` of a table.
pub(super) fn rows_plots(
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
    let n_col = column(t, "n");
    let pooled = pooled_scatter(t, rows, n_col, column(t, "std"));
    let d = Rows {
        t,
        rows,
        lay,
        n_col,
        pooled,
        k95: pooled.map_or(f64::NAN, |(_, dof)| coverage_factor(dof, 0.95)),
    };
    let texts = Texts::new(&d, res, panel, &legend);
    let mut out = vec![residual_plot(&d, res, &groups, legend.clone(), &texts)];
    if let Some(mean) = mean {
        out.push(fitted_plot(&d, mean, res, &groups, legend, curve, &texts));
    }
    out
}

/// Pooled sample scatter of `rows` from their `n` and `std` columns:
/// `(s_p, ν)` with s_p² = Σ(n − 1)·s² / ν and ν = Σ(n − 1) over the rows
/// with n ≥ 2; `None` without repeated samples.
fn pooled_scatter(
    t: &Table,
    rows: &[usize],
    n_col: Option<usize>,
    std_col: Option<usize>,
) -> Option<(f64, f64)> {
    let (nc, sc) = n_col.zip(std_col)?;
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
}

/// The rows of a table being plotted, with what their residual and fitted
/// plots share: each row's abscissa and the ±U95 bar of its mean.
struct Rows<'a> {
    /// The table.
    t: &'a Table,
    /// The rows plotted (a panel's, or all).
    rows: &'a [usize],
    /// Abscissa and series of the table.
    lay: &'a Layout,
    /// Column `n` (samples averaged in a row), if any.
    n_col: Option<usize>,
    /// Pooled sample scatter and its dof ([`pooled_scatter`]).
    pooled: Option<(f64, f64)>,
    /// t95 of the pooled dof (NaN without it).
    k95: f64,
}

impl Rows<'_> {
    /// Half-width of the bar of row `i`'s mean: U95 = t95·s_p/√n (table
    /// units).
    fn bar(&self, i: usize) -> Option<f64> {
        let (sp, _) = self.pooled?;
        let n = number(&self.t.rows[i][self.n_col?])?;
        (n >= 1.0).then(|| self.k95 * sp / n.sqrt())
    }

    /// Abscissa of row `i` in display units (its index without an
    /// abscissa column; NaN for a missing value).
    fn x(&self, i: usize) -> f64 {
        match self.lay.x_col {
            Some(k) => number(&self.t.rows[i][k]).map_or(f64::NAN, |x| x * self.lay.x_scale),
            None => i as f64,
        }
    }

    /// Largest |value| of column `col` over the rows plotted.
    fn magnitude(&self, col: usize) -> f64 {
        self.rows
            .iter()
            .filter_map(|&i| number(&self.t.rows[i][col]))
            .fold(0.0, |m, x| f64::max(m, x.abs()))
    }
}

/// The texts the residual and fitted plots of some rows share.
struct Texts {
    /// The plot's source: the table id, with the panel.
    source: String,
    /// ` (PANEL)` for a caption.
    in_panel: String,
    /// ` — PANEL` for a title.
    panel_title: String,
    /// What the colours are (empty for one series).
    series_text: String,
    /// How the bars are computed.
    bar_text: String,
}

impl Texts {
    /// The texts of the plots of `d` (residual column `res`).
    fn new(d: &Rows, res: usize, panel: Option<&str>, legend: &[String]) -> Texts {
        let t = d.t;
        let bar_text = match d.pooled {
            Some((sp, dof)) => {
                let (s, l) = display_unit(t.columns[res].unit.as_ref(), sp);
                format!(
                    "Bars: ±U95 of each mean, U95 = t95·s_p/√n, with s_p = {} {l} the pooled sample scatter of the rows plotted (ν = Σ(n−1) = {dof:.0}, t95 = {:.3}); the fit's uncertainty policy may raise it (see Fits).",
                    trimmed(sp * s, 3),
                    d.k95
                )
            }
            None => "No bars: no repeated samples (n < 2).".to_string(),
        };
        let series_text = if legend.is_empty() {
            String::new()
        } else {
            format!(
                " One colour per {}.",
                d.lay
                    .series_cols
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
        Texts {
            source,
            in_panel,
            panel_title,
            series_text,
            bar_text,
        }
    }
}

/// The residual plot: each row's residual (column `res`) with the bar of
/// its mean, one series per group of rows, around a zero line.
fn residual_plot(
    d: &Rows,
    res: usize,
    groups: &[Vec<usize>],
    legend: Vec<String>,
    tx: &Texts,
) -> Plot {
    let t = d.t;
    let (rs, rl) = display_unit(t.columns[res].unit.as_ref(), d.magnitude(res));
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
                        x: d.x(i),
                        y: y * rs,
                        bar: d.bar(i).map(|b| b * rs),
                    })
                })
                .filter(|p| p.x.is_finite())
                .collect(),
        })
        .collect();
    let x_desc = &d.lay.x_desc;
    Plot {
        kind: "residual",
        source: tx.source.clone(),
        title: format!("Residuals: {}{}", t.title, tx.panel_title),
        x_desc: x_desc.clone(),
        y_desc: with_unit("residual", &rl),
        x_axis: XAxis::Numeric,
        dodge: series.len() > 1,
        series,
        legend,
        hlines: vec![HLine {
            y: 0.0,
            limit: false,
        }],
        caption: format!(
            "Residual (data − fitted model) of every row of table {}{} against {x_desc}.{} {}",
            t.id, tx.in_panel, tx.series_text, tx.bar_text
        ),
        log_log: false,
        heat: None,
    }
}

/// The fitted plot: each row's mean (column `mean`) with its bar against
/// the fitted model, drawn as `curve` with its U95 band when given, else
/// as lines through mean − residual.
fn fitted_plot(
    d: &Rows,
    mean: usize,
    res: usize,
    groups: &[Vec<usize>],
    mut legend: Vec<String>,
    curve: Option<&Curve>,
    tx: &Texts,
) -> Plot {
    let t = d.t;
    let (ms, ml) = display_unit(t.columns[mean].unit.as_ref(), d.magnitude(mean));
    let mut series = data_series(d, mean, res, groups, ms, curve.is_none());
    let line_text = match curve {
        Some(c) => {
            let key = legend.len().max(1);
            if legend.is_empty() {
                legend.push("data".into());
            }
            legend.push("fitted model +- U95".into());
            series.extend(curve_series(c, d.lay.x_scale, ms, key));
            "the fitted model evaluated on a fine grid of the abscissa (its curve), dashed: its ±U95 band"
        }
        None => "the fitted model (line through mean − residual at the same abscissae, in order of the abscissa; straight between them, not the model's curve)",
    };
    let x_desc = &d.lay.x_desc;
    Plot {
        kind: "fitted",
        source: tx.source.clone(),
        title: format!("Fitted model and data: {}{}", t.title, tx.panel_title),
        x_desc: x_desc.clone(),
        y_desc: with_unit("mean", &ml),
        x_axis: XAxis::Numeric,
        dodge: false,
        series,
        legend,
        hlines: Vec::new(),
        caption: format!(
            "Data (dots: the mean of each row of table {}{}) against {x_desc} and {line_text}.{} {}",
            t.id, tx.in_panel, tx.series_text, tx.bar_text
        ),
        log_log: false,
        heat: None,
    }
}

/// Per group of rows: when `lines`, the fitted values (mean − residual) as
/// a line in order of the abscissa, then the means as dots with their bars
/// (scaled by `ms` to display units).
fn data_series(
    d: &Rows,
    mean: usize,
    res: usize,
    groups: &[Vec<usize>],
    ms: f64,
    lines: bool,
) -> Vec<Series> {
    let t = d.t;
    let mut series = Vec::new();
    for (key, rows) in groups.iter().enumerate() {
        let mut data = Vec::new();
        let mut fitted = Vec::new();
        for &i in rows {
            let (Some(m), x) = (number(&t.rows[i][mean]), d.x(i)) else {
                continue;
            };
            if !x.is_finite() {
                continue;
            }
            data.push(Pt {
                x,
                y: m * ms,
                bar: d.bar(i).map(|b| b * ms),
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
        if lines {
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
    series
}

/// The model curve as legend entry `key`: the curve, then its +U95 and
/// −U95 edges dashed (abscissa scaled by `x_scale`, ordinate by `ms`).
fn curve_series(c: &Curve, x_scale: f64, ms: f64, key: usize) -> [Series; 3] {
    let pts = |f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Pt> {
        c.iter()
            .map(|p| Pt {
                x: p.0 * x_scale,
                y: f(p) * ms,
                bar: None,
            })
            .collect()
    };
    [
        Series {
            key,
            style: Style::Line,
            points: pts(&|p| p.1),
        },
        Series {
            key,
            style: Style::Dashed,
            points: pts(&|p| p.1 + p.2),
        },
        Series {
            key,
            style: Style::Dashed,
            points: pts(&|p| p.1 - p.2),
        },
    ]
}
