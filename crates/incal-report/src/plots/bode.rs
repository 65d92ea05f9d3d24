//! The Bode plots of a dynamic-response result (module docs of `plots`):
//! gain in dB and phase in degrees against log10 of the frequency, the
//! measured dwells or bins with their U95 bars (from the table holding
//! `gain_db`), and the fitted model's curve with its U95 band (`bode` in
//! the document).

use incal::document::{Cell, ResultDocument, Table};
use serde_json::Value;

use super::{Plot, Pt, Series, Style, XAxis};

/// The numbers of a JSON array (NaN for what is not a number).
fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
        .unwrap_or_default()
}

/// The column `name` of table `t` as numbers (NaN where a cell is not).
fn column(t: &Table, name: &str) -> Option<Vec<f64>> {
    let k = t.columns.iter().position(|c| c.name == name)?;
    Some(
        t.rows
            .iter()
            .map(|r| match r.get(k) {
                Some(Cell::Number(x)) => *x,
                _ => f64::NAN,
            })
            .collect(),
    )
}

/// The measured points `(log10 f, y ± 1.96 u)` of a table, the fitted
/// ones only when it has a `fitted` column.
fn measured(t: &Table, y: &str, u: &str) -> Vec<Pt> {
    let (Some(f), Some(v), Some(s)) = (column(t, "freq_hz"), column(t, y), column(t, u)) else {
        return Vec::new();
    };
    let fitted = column(t, "fitted");
    (0..f.len())
        .filter(|&i| fitted.as_ref().is_none_or(|c| c[i] == 1.0))
        .filter(|&i| f[i] > 0.0 && v[i].is_finite() && s[i].is_finite())
        .map(|i| Pt {
            x: f[i].log10(),
            y: v[i],
            bar: Some(1.96 * s[i]),
        })
        .collect()
}

/// One Bode plot: the measured points, the model and its band.
fn plot(doc: &ResultDocument, bode: &Value, which: (&str, &str, &str, &str)) -> Option<Plot> {
    let (y, u95, u, desc) = which;
    let f = numbers(&bode["freq_hz"]);
    let m = numbers(&bode[y]);
    let b = numbers(&bode[u95]);
    if f.is_empty() || f.len() != m.len() || m.len() != b.len() {
        return None;
    }
    let table = doc
        .tables
        .iter()
        .find(|t| t.columns.iter().any(|c| c.name == "gain_db"))?;
    let curve = |sign: f64| -> Vec<Pt> {
        (0..f.len())
            .filter(|&i| f[i] > 0.0 && m[i].is_finite() && b[i].is_finite())
            .map(|i| Pt {
                x: f[i].log10(),
                y: m[i] + sign * b[i],
                bar: None,
            })
            .collect()
    };
    let series = vec![
        Series {
            key: 0,
            style: Style::Dots,
            points: measured(table, y, u),
        },
        Series {
            key: 1,
            style: Style::Line,
            points: curve(0.0),
        },
        Series {
            key: 2,
            style: Style::Dashed,
            points: curve(1.0),
        },
        Series {
            key: 2,
            style: Style::Dashed,
            points: curve(-1.0),
        },
    ];
    Some(Plot {
        kind: "bode",
        source: table.id.clone(),
        title: format!("Frequency response: {desc}"),
        x_desc: "frequency (Hz)".into(),
        y_desc: desc.into(),
        x_axis: XAxis::Log10,
        dodge: false,
        series,
        legend: vec![
            format!("measured ({}) with U95", table.id),
            "fitted model".into(),
            "model U95 band".into(),
        ],
        hlines: Vec::new(),
        caption: format!(
            "{desc} against frequency on a log axis: the measured points with bars of 1.96 u, the fitted low-pass model with delay and its U95 band (first-order propagation of the model's covariance)."
        ),
        log_log: false,
        heat: None,
    })
}

/// The gain and phase plots of a document with a `bode` object.
pub fn bode_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(bode) = doc.extra.get("bode") else {
        return Vec::new();
    };
    [
        ("gain_db", "u95_gain_db", "u_gain_db", "gain (dB)"),
        ("phase_deg", "u95_phase_deg", "u_phase_deg", "phase (deg)"),
    ]
    .into_iter()
    .filter_map(|w| plot(doc, bode, w))
    .collect()
}
