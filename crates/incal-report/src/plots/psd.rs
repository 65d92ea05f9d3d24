//! The power spectral density plots of a noise result run with `psd`:
//! per channel, the amplitude spectral density (unit/√Hz) against
//! frequency on log–log axes, its χ² bounds as dashed lines, the white
//! level of its band and the Allan fit's terms as a PSD.

use incal::document::ResultDocument;
use serde_json::Value;

use super::{Plot, Pt, Series, Style, XAxis};
use crate::format::trimmed;

/// The PSD plot of each channel holding `psd` in `channels`.
pub fn psd_plots(doc: &ResultDocument) -> Vec<Plot> {
    super::channel_plots(doc, psd_plot)
}

/// Bins drawn at most: a long segment's thousands of bins are shown at
/// log-spaced frequencies (each a bin's own value, none averaged).
const DRAWN: usize = 400;

/// `(log10 f, log10 √g)` of the bins above 0 Hz with a positive value,
/// at most [`DRAWN`] of them, log-spaced.
fn curve(p: &Value, key: &str) -> Vec<Pt> {
    let (Some(f), Some(g)) = (p["freq_hz"].as_array(), p[key].as_array()) else {
        return Vec::new();
    };
    let pts: Vec<Pt> = f
        .iter()
        .zip(g)
        .filter_map(|(f, g)| {
            let (f, g) = (f.as_f64()?, g.as_f64()?);
            (f > 0.0 && g > 0.0).then(|| Pt {
                x: f.log10(),
                y: 0.5 * g.log10(),
                bar: None,
            })
        })
        .collect();
    if pts.len() <= DRAWN {
        return pts;
    }
    let (a, b) = (pts[0].x, pts[pts.len() - 1].x);
    let mut out: Vec<Pt> = Vec::with_capacity(DRAWN);
    let mut j = 0;
    for k in 0..DRAWN {
        let target = a + (b - a) * k as f64 / (DRAWN - 1) as f64;
        while j + 1 < pts.len() && (pts[j + 1].x - target).abs() <= (pts[j].x - target).abs() {
            j += 1;
        }
        if out.last().is_none_or(|p: &Pt| p.x < pts[j].x) {
            out.push(pts[j]);
        }
    }
    out
}

/// The lines of `psd.tones` as points at their frequency and the ASD
/// of their peak bin.
fn tone_marks(p: &Value) -> Vec<Pt> {
    let (Some(tones), Some(g)) = (p["tones"].as_array(), p["density"].as_array()) else {
        return Vec::new();
    };
    tones
        .iter()
        .filter_map(|t| {
            let f = t["frequency_hz"].as_f64()?;
            let v = g.get(usize::try_from(t["bin"].as_u64()?).ok()?)?.as_f64()?;
            (f > 0.0 && v > 0.0).then(|| Pt {
                x: f.log10(),
                y: 0.5 * v.log10(),
                bar: None,
            })
        })
        .collect()
}

fn psd_plot(name: &str, c: &Value) -> Option<Plot> {
    let p = c.get("psd").filter(|p| p.is_object())?;
    let unit = c["unit"].as_str().unwrap_or("").to_string();
    let conf = p["confidence"].as_f64().unwrap_or(0.95);
    let asd = curve(p, "density");
    if asd.len() < 2 {
        return None;
    }
    let (x0, x1) = (asd[0].x, asd[asd.len() - 1].x);
    let mut legend = vec![
        "amplitude spectral density".to_string(),
        format!("{} % chi-square bounds", trimmed(100.0 * conf, 3)),
    ];
    let mut series = Vec::new();
    for key in ["lo", "hi"] {
        series.push(Series {
            key: 1,
            style: Style::Dashed,
            points: curve(p, key),
        });
    }
    series.push(Series {
        key: 0,
        style: Style::Line,
        points: asd,
    });
    let model = curve(&p["model"], "total");
    if model.len() >= 2 {
        let names: Vec<&str> = p["model"]["terms"]
            .as_object()
            .map(|t| t.keys().map(String::as_str).collect())
            .unwrap_or_default();
        legend.push(format!(
            "the Allan fit's terms as a PSD ({})",
            names.join(" + ")
        ));
        series.push(Series {
            key: legend.len() - 1,
            style: Style::Line,
            points: model,
        });
    }
    if let Some(w) = p["white"].as_object() {
        if let (Some(a), Some(u)) = (w["asd"].as_f64(), w["u_asd"].as_f64()) {
            legend.push(format!(
                "white level {} +- {} {unit}/sqrt(Hz) (u)",
                trimmed(a, 4),
                trimmed(u, 2)
            ));
            series.push(Series {
                key: legend.len() - 1,
                style: Style::Line,
                points: vec![
                    Pt {
                        x: x0,
                        y: a.log10(),
                        bar: None,
                    },
                    Pt {
                        x: x1,
                        y: a.log10(),
                        bar: None,
                    },
                ],
            });
        }
    }
    let lines = tone_marks(p);
    if !lines.is_empty() {
        legend.push(format!("lines above the noise floor ({})", lines.len()));
        series.push(Series {
            key: legend.len() - 1,
            style: Style::Dots,
            points: lines,
        });
    }
    Some(Plot {
        kind: "psd",
        source: name.to_string(),
        title: format!("{name}: amplitude spectral density"),
        x_desc: "frequency (Hz)".into(),
        y_desc: format!("ASD ({unit}/sqrt(Hz))"),
        x_axis: XAxis::Numeric,
        dodge: false,
        series,
        legend,
        hlines: Vec::new(),
        caption: format!(
            "One-sided amplitude spectral density by Welch's method ({} segments of {} samples, {} window), log-log, drawn at up to 400 log-spaced bins; dashed: chi-square bounds at {} % confidence with {} equivalent degrees of freedom (Percival & Walden); the flat line: the white level read over {}; the other: the IEEE Std 952 terms of the Allan fit as a one-sided PSD (Annex C), the consistency check of the two analyses; dots: the lines standing above the local noise floor at a false-alarm rate of {} per spectrum (table tones).",
            p["segments"].as_u64().unwrap_or(0),
            p["segment_samples"].as_u64().unwrap_or(0),
            p["window"].as_str().unwrap_or("hann"),
            trimmed(100.0 * conf, 3),
            trimmed(p["edf"].as_f64().unwrap_or(0.0), 3),
            match (p["white"]["band_hz"][0].as_f64(), p["white"]["band_hz"][1].as_f64()) {
                (Some(lo), Some(hi)) => format!("{}-{} Hz", trimmed(lo, 4), trimmed(hi, 4)),
                _ => "no band (too few bins)".into(),
            },
            trimmed(p["tone_search"]["false_alarm"].as_f64().unwrap_or(0.01), 3),
        ),
        log_log: true,
        heat: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hand_edited_white_band_draws_without_a_band_instead_of_failing() {
        let c = serde_json::json!({"unit": "deg/s", "psd": {
            "freq_hz": [0.0, 1.0, 2.0, 3.0], "density": [1.0, 1.0, 1.0, 1.0],
            "lo": [0.5, 0.5, 0.5, 0.5], "hi": [2.0, 2.0, 2.0, 2.0],
            "white": {"asd": 1.0, "u_asd": 0.1, "band_hz": []}}});
        let p = psd_plot("ch1", &c).unwrap();
        assert!(p.caption.contains("no band"), "{}", p.caption);
    }

    #[test]
    fn a_line_is_marked_at_its_peak_and_a_bad_bin_is_skipped() {
        let c = serde_json::json!({"unit": "deg/s", "psd": {
            "freq_hz": [0.0, 1.0, 2.0, 3.0], "density": [1.0, 1.0, 100.0, 1.0],
            "lo": [0.5, 0.5, 0.5, 0.5], "hi": [2.0, 2.0, 2.0, 2.0],
            "tones": [{"frequency_hz": 2.0, "bin": 2}, {"frequency_hz": 3.0, "bin": 99}]}});
        let p = psd_plot("ch1", &c).unwrap();
        let dots: Vec<&Series> = p.series.iter().filter(|s| s.style == Style::Dots).collect();
        assert_eq!(dots.len(), 1);
        assert_eq!(dots[0].points.len(), 1);
        assert!((dots[0].points[0].y - 1.0).abs() < 1e-12);
        assert!(p
            .legend
            .iter()
            .any(|l| l.contains("lines above the noise floor (1)")));
    }
}
