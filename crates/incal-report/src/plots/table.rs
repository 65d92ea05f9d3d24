//! Which plots a table gives (module docs of `plots`): its abscissa and
//! the columns that name its series, panels for a table with many series,
//! and the model curve a result gives for a table; `rows` draws them.

use incal::document::{Cell, ResultDocument, Table};

use super::rows::rows_plots;
use super::{column, display_unit, number, with_unit, Plot};
use crate::format::trimmed;

/// Columns that hold statistics of a row, not its coordinates.
const STAT_COLUMNS: [&str; 6] = [
    "n",
    "mean",
    "std",
    "residual",
    "standardized_residual",
    "fitted",
];

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
pub(super) struct Layout {
    /// Column of the abscissa (`None`: the row number).
    pub(super) x_col: Option<usize>,
    /// Display scale and unit of the abscissa.
    pub(super) x_scale: f64,
    /// Axis description of the abscissa.
    pub(super) x_desc: String,
    /// Lead columns that name the series.
    pub(super) series_cols: Vec<usize>,
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
pub(super) fn group_rows(
    t: &Table,
    rows: &[usize],
    cols: &[usize],
) -> (Vec<String>, Vec<Vec<usize>>) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plots::{render_svg, Style};
    use incal::document::Column;
    use incal::estimation::coverage_factor;
    use incal::units::Unit;

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
}
