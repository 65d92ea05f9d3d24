//! The history plot of a coefficient (module docs of `plots`): its value
//! ±U95 in every stored calibration of an instrument against the date,
//! with the drift line and its band, and the limits.

use super::{display_unit, with_unit, HLine, Plot, Pt, Series, Style, XAxis};
use crate::format::trimmed;
use crate::{DriftLine, HistorySeries};

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
    let days = days_since(h, &first);
    let dated = days.as_ref().is_some_and(|d| d.iter().any(|x| *x != 0.0));
    let x_of = |i: usize| match (&days, dated) {
        (Some(d), true) => d[i],
        _ => i as f64,
    };
    // Value of each calibration (display units), with or without its bar.
    let values = |bars: bool| -> Vec<Pt> {
        h.points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.value.is_finite())
            .map(|(i, p)| Pt {
                x: x_of(i),
                y: p.value * s,
                bar: if bars {
                    p.u95.is_finite().then_some(p.u95 * s)
                } else {
                    None
                },
            })
            .collect()
    };
    let hlines = [h.min, h.max]
        .into_iter()
        .flatten()
        .filter(|y| y.is_finite())
        .map(|y| HLine {
            y: y * s,
            limit: true,
        })
        .collect();
    let (mut series, drift_note) = match (&h.drift, dated) {
        (Some(d), true) => {
            let t_end = days
                .as_ref()
                .map_or(0.0, |v| v.iter().fold(0.0, |m, x| f64::max(m, *x)));
            drift_series(d, t_end, s, &l)
        }
        _ => (
            vec![Series {
                key: 0,
                style: Style::Line,
                points: values(false),
            }],
            String::new(),
        ),
    };
    series.push(Series {
        key: 0,
        style: Style::Dots,
        points: values(true),
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
        caption: history_caption(h, s, &l, &drift_note),
        log_log: false,
        heat: None,
    }
}

/// Days from `first` to each calibration's time; `None` when a time does
/// not read.
fn days_since(h: &HistorySeries, first: &str) -> Option<Vec<f64>> {
    h.points
        .iter()
        .map(|p| {
            let a = incal_records::time::parse_utc(first).ok()?;
            let b = incal_records::time::parse_utc(&p.created_utc).ok()?;
            Some((b - a) as f64 / 86_400.0)
        })
        .collect()
}

/// The drift line from day 0 to `t_end` (41 points) and the dashed edges
/// of its ±U95 band, k95·√(c₀₀ + 2t·c₀₁ + t²·c₁₁) from the covariance of
/// (intercept, rate), scaled by `s` to unit `l`; and the caption's note.
fn drift_series(d: &DriftLine, t_end: f64, s: f64, l: &str) -> (Vec<Series>, String) {
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
    let mut series = vec![Series {
        key: 1,
        style: Style::Line,
        points: curve(&line),
    }];
    for sign in [-1.0, 1.0] {
        series.push(Series {
            key: 1,
            style: Style::Dashed,
            points: curve(&|t| line(t) + sign * half(t)),
        });
    }
    let note = format!(
        "; line: the drift, {} {l}/day, dashed: its ±U95 band",
        trimmed(d.rate_per_day * s, 3)
    );
    (series, note)
}

/// The caption of the history plot: what it shows, the drift and the
/// limits (scaled by `s` to unit `l`).
fn history_caption(h: &HistorySeries, s: f64, l: &str, drift_note: &str) -> String {
    format!(
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
    )
}
