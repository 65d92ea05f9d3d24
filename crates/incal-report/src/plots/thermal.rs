//! The plots of a thermal model (module docs of `plots`): per coefficient
//! or channel, its points against temperature with the fitted polynomial
//! and its band, then what is left after compensation.

use incal::document::{ResultDocument, Table};
use incal::units::Unit;

use super::{column, display_unit, number, with_unit, HLine, Plot, Pt, Series, Style, XAxis};

/// The plots of a thermal model: per coefficient or channel, its points
/// (plateaus or ramp blocks, bars ±U95 of each) against temperature with
/// the fitted polynomial drawn as a curve and its ±U95 band (from the
/// `model.NAME` table), then the residuals against temperature.
pub fn thermal_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(map) = doc.extra.get("thermal").and_then(|m| m.as_object()) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for name in map.keys() {
        let Some(data) = Thermal::of(doc, name) else {
            continue;
        };
        let degree = map[name]["degree"].as_u64().unwrap_or(0);
        out.push(model_plot(name, &data, degree));
        out.push(residual_plot(name, &data));
    }
    out
}

/// The noise terms against temperature of a noise result binned by
/// temperature (`channels.NAME.temperature.models`): per term, as
/// [`thermal_plots`] draws a coefficient, from its `noise_temperature.*`
/// tables.
pub fn noise_temperature_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(chans) = doc.extra.get("channels").and_then(|c| c.as_object()) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for (ch, c) in chans {
        let Some(models) = c["temperature"]["models"].as_object() else {
            continue;
        };
        for (term, m) in models {
            let name = format!("{ch}.{term}");
            if let Some(data) = Thermal::of(doc, &name) {
                out.push(model_plot(&name, &data, m["degree"].as_u64().unwrap_or(0)));
            }
        }
    }
    out
}

/// What the plots of one coefficient or channel are drawn from.
struct Thermal<'a> {
    /// Its points: the `plateaus.NAME` or `ramp.NAME` table.
    pts: &'a Table,
    /// The polynomial on a grid: the `model.NAME` table.
    model: &'a Table,
    /// Unit of the values.
    unit: Option<Unit>,
    /// Each point: (temperature °C, value, u, residual).
    rows: Vec<(f64, f64, f64, f64)>,
    /// The polynomial: (temperature °C, value, U95).
    curve: Vec<(f64, f64, f64)>,
    /// Coverage factor of a point's bar (normal, 95 %).
    k: f64,
}

impl<'a> Thermal<'a> {
    /// The tables of `name` and their columns read; `None` when a table,
    /// a column or every row is missing.
    fn of(doc: &'a ResultDocument, name: &str) -> Option<Thermal<'a>> {
        let find = |id: &str| doc.tables.iter().find(|t| t.id == id);
        let pts = find(&format!("plateaus.{name}"))
            .or_else(|| find(&format!("ramp.{name}")))
            .or_else(|| find(&format!("noise_temperature.{name}")))?;
        let model = find(&format!("model.{name}"))
            .or_else(|| find(&format!("noise_temperature_model.{name}")))?;
        let (pt_t, pt_u, pt_r) = (
            column(pts, "temperature_c")?,
            column(pts, "u")?,
            column(pts, "residual")?,
        );
        let pt_y = column(pts, "value").or_else(|| column(pts, "mean"))?;
        let (m_t, m_y, m_u95) = (
            column(model, "temperature_c")?,
            column(model, "polynomial")?,
            column(model, "U95")?,
        );
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
            return None;
        }
        Some(Thermal {
            pts,
            model,
            unit: pts.columns[pt_y].unit.clone(),
            rows,
            curve,
            k: incal::estimation::coverage_factor(f64::INFINITY, 0.95),
        })
    }
}

/// The points of `name` (bars ±U95) against temperature with the
/// polynomial of degree `degree` and its dashed ±U95 band.
fn model_plot(name: &str, d: &Thermal, degree: u64) -> Plot {
    let mag = d.rows.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
    let (scale, label) = display_unit(d.unit.as_ref(), mag);
    let line = |f: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<Pt> {
        d.curve
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
            points: d
                .rows
                .iter()
                .map(|r| Pt {
                    x: r.0,
                    y: r.1 * scale,
                    bar: Some(d.k * r.2 * scale),
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
    Plot {
        kind: "fitted",
        source: name.to_string(),
        title: format!("{name} against temperature"),
        x_desc: "temperature (degC)".into(),
        y_desc: with_unit(name, &label),
        x_axis: XAxis::Numeric,
        dodge: false,
        series,
        legend: vec![
            format!("{} (bars: +-U95)", d.pts.title),
            "fitted polynomial".into(),
            "polynomial +- U95".into(),
        ],
        hlines: Vec::new(),
        caption: format!(
            "{name} at each point of table {} against temperature, bars +-U95 of the point; the polynomial of degree {degree} fitted to them, drawn as a curve over the valid range, with its expanded uncertainty band (table {}).",
            d.pts.id,
            d.model.id
        ),
        log_log: false,
        heat: None,
    }
}

/// The residual of each point of `name` (point minus model, bars ±U95 of
/// the point) against temperature, around a zero line.
fn residual_plot(name: &str, d: &Thermal) -> Plot {
    let rmag = d
        .rows
        .iter()
        .map(|r| r.3.abs().max(r.2))
        .fold(0.0, f64::max);
    let (rs, rl) = display_unit(d.unit.as_ref(), rmag);
    Plot {
        kind: "residual",
        source: d.pts.id.clone(),
        title: format!("{name}: residual after compensation"),
        x_desc: "temperature (degC)".into(),
        y_desc: with_unit("residual", &rl),
        x_axis: XAxis::Numeric,
        dodge: false,
        series: vec![Series {
            key: 0,
            style: Style::Dots,
            points: d
                .rows
                .iter()
                .map(|r| Pt {
                    x: r.0,
                    y: r.3 * rs,
                    bar: Some(d.k * r.2 * rs),
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
        heat: None,
    }
}
