//! The Allan plots of a noise result (module docs of `plots`): per
//! channel, OADEV against τ on log–log axes with its confidence bounds,
//! the fitted IEEE Std 952 model and its terms, and the other deviations
//! of the same unit.

use incal::document::ResultDocument;
use serde_json::Value;

use super::{Plot, Pt, Series, Style, XAxis};
use crate::format::trimmed;

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
    let conf = doc
        .options
        .get("confidence")
        .and_then(|v| v.as_f64())
        .unwrap_or(0.683);
    super::channel_plots(doc, |name, c| allan_plot(doc, name, c, conf))
}

/// The Allan plot of channel `name` (`c`: its object in `channels`), with
/// bounds at confidence `conf`; `None` without an OADEV to plot.
fn allan_plot(doc: &ResultDocument, name: &str, c: &Value, conf: f64) -> Option<Plot> {
    let taus = positive(&c["taus_s"]);
    let unit = c["unit"].as_str().unwrap_or("").to_string();
    let mut series = oadev_series(c, &taus)?;
    let mut legend = vec![format!("OADEV with {} % bounds", trimmed(100.0 * conf, 3))];
    let fit = log_points(&positive(&c["fit_oadev"]), &taus);
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
            let pts = log_points(&positive(v), &taus);
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
    other_deviations(c, &mut legend, &mut series);
    clip_term_lines(&mut series);
    Some(Plot {
        kind: "allan",
        source: name.to_string(),
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
        heat: None,
    })
}

/// The positive numbers of a JSON array, `None` for any other element
/// (empty for what is not an array).
fn positive(v: &Value) -> Vec<Option<f64>> {
    v.as_array()
        .map(|a| a.iter().map(|x| x.as_f64().filter(|x| *x > 0.0)).collect())
        .unwrap_or_default()
}

/// `(log10 τ, log10 y)` where both are given.
fn log_points(ys: &[Option<f64>], taus: &[Option<f64>]) -> Vec<Pt> {
    ys.iter()
        .zip(taus)
        .filter_map(|(y, t)| {
            Some(Pt {
                x: t.as_ref()?.log10(),
                y: y.as_ref()?.log10(),
                bar: None,
            })
        })
        .collect()
}

/// Legend entry 0: a vertical line from the lower to the upper bound at
/// each τ, then the OADEV values as dots (log10 of each); `None` without
/// a value.
fn oadev_series(c: &Value, taus: &[Option<f64>]) -> Option<Vec<Series>> {
    let (val, lo, hi) = (
        positive(&c["oadev"]["value"]),
        positive(&c["oadev"]["lo"]),
        positive(&c["oadev"]["hi"]),
    );
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
        if let (Some(l), Some(h)) = (lo.get(k).copied().flatten(), hi.get(k).copied().flatten()) {
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
        return None;
    }
    series.push(Series {
        key: 0,
        style: Style::Dots,
        points: dots,
    });
    Some(series)
}

/// The other deviations of the same unit, as dashed lines with their own
/// legend entries (TDEV, in the unit times s, has its own axis in the
/// tables).
fn other_deviations(c: &Value, legend: &mut Vec<String>, series: &mut Vec<Series>) {
    for dev in ["mdev", "ohdev", "totdev"] {
        let d = &c[dev];
        let pts = log_points(&positive(&d["value"]), &positive(&d["taus_s"]));
        if pts.len() >= 2 {
            legend.push(dev.to_uppercase());
            series.push(Series {
                key: legend.len() - 1,
                style: Style::Dashed,
                points: pts,
            });
        }
    }
}

/// Term lines far below the data would squash the plot: keep them within
/// two decades under the lowest deviation (entry 0), and drop the series
/// left empty.
fn clip_term_lines(series: &mut Vec<Series>) {
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
}
