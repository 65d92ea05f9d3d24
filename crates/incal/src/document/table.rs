//! Tables of a result document: typed cells, columns with units, rows
//! with stable ids.

use super::*;

/// A table cell: a number, a text or `null` (not available).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum Cell {
    /// A finite number.
    Number(f64),
    /// A label.
    Text(String),
    /// Not available.
    Null,
}

impl Cell {
    /// A number, or `Null` when not finite.
    pub fn num(x: f64) -> Cell {
        if x.is_finite() {
            Cell::Number(x)
        } else {
            Cell::Null
        }
    }
    /// An optional number.
    pub fn opt(x: Option<f64>) -> Cell {
        x.map_or(Cell::Null, Cell::num)
    }
    /// A text.
    pub fn text(s: impl Into<String>) -> Cell {
        Cell::Text(s.into())
    }
}

/// A column of a [`Table`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Column {
    /// Column name (snake case, units not in the name: see `unit`).
    pub name: String,
    /// Unit of the numbers in the column (`null` for labels and counts).
    pub unit: Option<Unit>,
}

/// A procedure's table as data (positions and residuals, stations,
/// budgets, per-accelerometer blocks, …).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Table {
    /// Stable identifier (`positions`, `stations`, `budget.K_ip`, …).
    pub id: String,
    /// Title for people.
    pub title: String,
    /// Columns.
    pub columns: Vec<Column>,
    /// Rows, each with one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    /// An empty table with columns `(name, unit)`.
    pub fn new(id: &str, title: &str, columns: &[(&str, Option<Unit>)]) -> Table {
        Table {
            id: id.to_string(),
            title: title.to_string(),
            columns: columns
                .iter()
                .map(|(n, u)| Column {
                    name: n.to_string(),
                    unit: u.clone(),
                })
                .collect(),
            rows: Vec::new(),
        }
    }
    /// Append a row (must have one cell per column).
    pub fn push(&mut self, row: Vec<Cell>) -> Result<()> {
        if row.len() != self.columns.len() {
            return Err(Error::Unsupported(format!(
                "table {}: row of {} cells for {} columns",
                self.id,
                row.len(),
                self.columns.len()
            )));
        }
        self.rows.push(row);
        Ok(())
    }
}

/// The columns every position table ends with: samples, mean and scatter
/// of the output, residual of the fit and standardized residual.
pub(crate) const POSITION_STATS: [(&str, Option<Unit>); 5] = [
    ("n", None),
    ("mean", Some(Unit::Output)),
    ("std", Some(Unit::Output)),
    ("residual", Some(Unit::Output)),
    ("standardized_residual", Some(Unit::One)),
];

/// Describe where the variance behind u came from.
pub(crate) fn variance_decision(
    source: crate::estimation::VarianceSource,
    known_noise: bool,
) -> &'static str {
    match (source, known_noise) {
        (crate::estimation::VarianceSource::Residuals, _) => {
            "variance from the residuals (significant lack of fit, or no repeated samples)"
        }
        (crate::estimation::VarianceSource::Prior, true) => {
            "variance from the known noise (--noise)"
        }
        (crate::estimation::VarianceSource::Prior, false) => {
            "variance from the pooled scatter of repeated samples"
        }
    }
}

/// The cells of [`POSITION_STATS`] for one position.
pub(crate) fn position_stats(
    stats: &crate::estimation::PositionStats,
    residual: f64,
    standardized_residual: f64,
) -> [Cell; 5] {
    [
        Cell::num(stats.n as f64),
        Cell::num(stats.mean),
        Cell::num(stats.std),
        Cell::num(residual),
        Cell::num(standardized_residual),
    ]
}

/// A fitted linear model on a grid, for the report's model curve
/// (`model_curves.TABLE`): at each abscissa `x_i` (in the table's unit)
/// the design row `a_i` gives `y = a_iᵀ x̂` and
/// `U95 = k95 sqrt(a_iᵀ C a_i)` of the fit's estimates `e`.
pub(crate) fn model_curve(x: &[f64], design: &crate::estimation::Design, e: &Estimates) -> Value {
    let k = e.coverage_factor(0.95);
    let (mut xs, mut ys, mut us) = (Vec::new(), Vec::new(), Vec::new());
    for (i, &xi) in x.iter().enumerate() {
        let row = design.matrix().row(i).transpose();
        let y = (row.transpose() * e.values())[(0, 0)];
        let var = (row.transpose() * e.covariance() * &row)[(0, 0)];
        if xi.is_finite() && y.is_finite() && var.is_finite() {
            xs.push(xi);
            ys.push(y);
            us.push(k * var.max(0.0).sqrt());
        }
    }
    serde_json::json!({"x": xs, "y": ys, "U95": us})
}

/// `n` points from `lo` to `hi`.
pub(crate) fn grid(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo + (hi - lo) * i as f64 / (n.max(2) - 1) as f64)
        .collect()
}

/// A table whose columns are `lead` then [`POSITION_STATS`].
pub(crate) fn position_table(id: &str, title: &str, lead: &[(&str, Option<Unit>)]) -> Table {
    let cols: Vec<(&str, Option<Unit>)> = lead.iter().cloned().chain(POSITION_STATS).collect();
    Table::new(id, title, &cols)
}
