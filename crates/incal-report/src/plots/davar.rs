//! The dynamic Allan deviation of a noise result (`channels.NAME.davar`)
//! as a heat map: window centre (s) across, τ (log) up, each cell coloured
//! by how far its ADEV lies from the median of the windows at that τ.

use serde_json::Value;

use super::{Heat, Plot, Pt, Series, Style, XAxis};
use crate::format::trimmed;
use incal::document::ResultDocument;

/// The full colour scale, decades: a window's ADEV twice (or half) the
/// median of its τ is drawn at full red (blue).
const SCALE_DECADES: f64 = std::f64::consts::LOG10_2;

/// One heat map per channel that has `davar` (none without it).
pub fn davar_plots(doc: &ResultDocument) -> Vec<Plot> {
    super::channel_plots(doc, davar_plot)
}

/// The median of the finite positive values (`None` without any).
fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite() && *x > 0.0);
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

fn numbers(v: &Value) -> Vec<Option<f64>> {
    v.as_array()
        .map(|a| a.iter().map(Value::as_f64).collect())
        .unwrap_or_default()
}

fn davar_plot(name: &str, c: &Value) -> Option<Plot> {
    let d = c.get("davar").filter(|d| d.is_object())?;
    let taus: Vec<f64> = numbers(&d["taus_s"]).into_iter().flatten().collect();
    let starts: Vec<f64> = numbers(&d["start_s"]).into_iter().flatten().collect();
    let adev: Vec<Vec<Option<f64>>> = d["adev"].as_array()?.iter().map(numbers).collect();
    let (window, step) = (d["window_s"].as_f64()?, d["step_s"].as_f64()?);
    if taus.is_empty() || starts.is_empty() || adev.len() != starts.len() {
        return None;
    }
    let half = 0.5 * std::f64::consts::LOG10_2;
    let mut cells = Vec::new();
    for (k, tau) in taus.iter().enumerate() {
        let Some(med) = median(
            adev.iter()
                .filter_map(|w| w.get(k).copied().flatten())
                .collect(),
        ) else {
            continue;
        };
        for (start, w) in starts.iter().zip(&adev) {
            let Some(v) = w.get(k).copied().flatten().filter(|v| *v > 0.0) else {
                continue;
            };
            let centre = start + 0.5 * window;
            cells.push([
                centre - 0.5 * step.min(window),
                centre + 0.5 * step.min(window),
                tau.log10() - half,
                tau.log10() + half,
                (v / med).log10() / SCALE_DECADES,
            ]);
        }
    }
    if cells.is_empty() {
        return None;
    }
    // The τ at which the stationarity test rejects, marked at the left edge.
    let threshold = d["test"]["p_threshold"].as_f64().unwrap_or(0.0);
    let x_left = cells.iter().map(|c| c[0]).fold(f64::INFINITY, f64::min);
    let marks: Vec<Pt> = d["test"]["taus"]
        .as_array()
        .map(|t| {
            t.iter()
                .filter(|t| t["p_value"].as_f64().is_some_and(|p| p < threshold))
                .filter_map(|t| t["tau_s"].as_f64())
                .map(|tau| Pt {
                    x: x_left,
                    y: tau.log10(),
                    bar: None,
                })
                .collect()
        })
        .unwrap_or_default();
    let mut legend = Vec::new();
    let mut series = Vec::new();
    if !marks.is_empty() {
        legend.push(format!(
            "tau where the windows disagree ({} of {})",
            marks.len(),
            d["test"]["taus"].as_array().map_or(0, Vec::len)
        ));
        series.push(Series {
            key: 3,
            style: Style::Dots,
            points: marks,
        });
    }
    let verdict = match d["test"]["non_stationary"].as_bool() {
        Some(true) => "the windows disagree beyond their bounds (warning non-stationary)".to_string(),
        Some(false) => format!(
            "the windows agree within their bounds (Bartlett's test over {} windows that do not overlap, false-alarm rate {} per channel)",
            d["test"]["windows_compared"].as_u64().unwrap_or(0),
            trimmed(d["test"]["false_alarm"].as_f64().unwrap_or(0.01), 2)
        ),
        None => "too few windows that do not overlap for a test".to_string(),
    };
    Some(Plot {
        kind: "davar",
        source: name.to_string(),
        title: format!("{name}: dynamic Allan deviation"),
        x_desc: "window centre (s)".into(),
        y_desc: "tau (s)".into(),
        x_axis: XAxis::Numeric,
        dodge: false,
        series,
        legend,
        hlines: Vec::new(),
        caption: format!(
            "The overlapping Allan deviation of {} windows of {} s, one every {} s (table davar.{name}); each cell's colour is its ADEV against the median of the windows at that tau: white equal, red up to twice, blue down to half or beyond; {verdict}.",
            starts.len(),
            trimmed(window, 4),
            trimmed(step, 4),
        ),
        log_log: false,
        heat: Some(Heat { cells }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_coloured_against_the_median_of_their_tau() {
        let c = serde_json::json!({"davar": {
            "window_s": 100.0, "step_s": 50.0, "taus_s": [1.0, 2.0],
            "start_s": [0.0, 50.0, 100.0],
            "adev": [[1.0, 0.5], [1.0, null], [2.0, 0.5]],
            "test": {"p_threshold": 0.005, "non_stationary": true, "windows_compared": 2,
                     "taus": [{"tau_s": 1.0, "p_value": 1e-4}, {"tau_s": 2.0, "p_value": 0.5}]}}});
        let p = davar_plot("gx", &c).unwrap();
        let cells = &p.heat.as_ref().unwrap().cells;
        assert_eq!(cells.len(), 5);
        // The last window at tau = 1 s is twice the median: full red.
        let last = cells.iter().find(|c| c[0] == 125.0 && c[2] < 0.0).unwrap();
        assert!((last[4] - 1.0).abs() < 1e-12, "{last:?}");
        assert_eq!(super::super::heat_colour(last[4]), (178, 24, 43));
        assert_eq!(super::super::heat_colour(0.0), (255, 255, 255));
        assert_eq!(p.series[0].points.len(), 1);
        assert!(p.caption.contains("disagree"));
        let svg = super::super::render_svg(&p).unwrap();
        assert!(
            svg.contains("#B2182B") || svg.contains("#b2182b"),
            "red cell drawn"
        );
    }

    #[test]
    fn a_document_without_davar_or_with_a_broken_one_draws_nothing() {
        assert!(davar_plot("gx", &serde_json::json!({})).is_none());
        let c = serde_json::json!({"davar": {"window_s": 1.0, "step_s": 1.0,
            "taus_s": [1.0], "start_s": [0.0, 1.0], "adev": [[1.0]]}});
        assert!(davar_plot("gx", &c).is_none());
    }
}
