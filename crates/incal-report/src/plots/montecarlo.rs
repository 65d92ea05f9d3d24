//! The Monte Carlo plots of a result with `monte_carlo` (JCGM 101): per
//! coefficient, the trials' histogram with the probabilistically
//! symmetric and the shortest 95 % intervals and the GUM interval
//! `y ± U95` as vertical lines, in the coefficient's engineering unit.

use incal::document::ResultDocument;
use incal::montecarlo::McCoefficient;

use super::{display_unit, with_unit, Plot, Pt, Series, Style, XAxis};

/// The histogram's outline as a staircase: up at each bin's left edge,
/// across its top, down at the last edge (display units).
fn staircase(c: &McCoefficient, scale: f64) -> Vec<Pt> {
    let h = &c.histogram;
    let n = h.counts.len();
    if n == 0 {
        return Vec::new();
    }
    let width = (h.high - h.low) / n as f64;
    let edge = |k: usize| (h.low + width * k as f64) * scale;
    let pt = |x: f64, y: f64| Pt { x, y, bar: None };
    let mut out = vec![pt(edge(0), 0.0)];
    for (k, &count) in h.counts.iter().enumerate() {
        out.push(pt(edge(k), count as f64));
        out.push(pt(edge(k + 1), count as f64));
    }
    out.push(pt(edge(n), 0.0));
    out
}

/// Two vertical lines (one series each, the same legend entry `key`) at
/// the ends of `interval`, as high as `top`.
fn ends(key: usize, interval: [f64; 2], scale: f64, top: f64) -> Vec<Series> {
    interval
        .iter()
        .map(|&x| Series {
            key,
            style: Style::Dashed,
            points: vec![
                Pt {
                    x: x * scale,
                    y: 0.0,
                    bar: None,
                },
                Pt {
                    x: x * scale,
                    y: top,
                    bar: None,
                },
            ],
        })
        .collect()
}

/// One plot per coefficient of the Monte Carlo, in the document's order
/// (none without `monte_carlo`).
pub fn monte_carlo_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(mc) = &doc.monte_carlo else {
        return Vec::new();
    };
    doc.coefficients
        .iter()
        .filter_map(|(name, coef)| {
            let c = mc.coefficients.get(name)?;
            let (scale, label) = display_unit(Some(&coef.unit), coef.value);
            let top = c.histogram.counts.iter().copied().max().unwrap_or(0) as f64;
            let mut series = vec![Series {
                key: 0,
                style: Style::Line,
                points: staircase(c, scale),
            }];
            series.extend(ends(1, c.symmetric, scale, top));
            series.extend(ends(2, c.shortest, scale, top));
            series.extend(ends(3, c.gum, scale, top));
            Some(Plot {
                kind: "monte-carlo",
                source: name.to_string(),
                title: format!("{name}: {} Monte Carlo trials ({})", mc.trials, c.decision),
                x_desc: with_unit(name, &label),
                y_desc: "trials per bin".into(),
                x_axis: XAxis::Numeric,
                dodge: false,
                series,
                legend: vec![
                    "trials".into(),
                    "symmetric 95 %".into(),
                    "shortest 95 %".into(),
                    "GUM y ± U95".into(),
                ],
                hlines: Vec::new(),
                caption: format!(
                    "The distribution of {name} over the Monte Carlo trials (JCGM 101), with its probabilistically symmetric and shortest 95 % coverage intervals and the GUM interval y ± U95; validation at δ = {} (u to {} significant digit{}).",
                    crate::format::sig(c.delta * scale, 2),
                    mc.digits,
                    if mc.digits == 1 { "" } else { "s" }
                ),
                log_log: false,
                heat: None,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use incal::montecarlo::{run, MonteCarloOptions, Trials};
    use incal::procedures::tumble::sim::{simulate, TumbleSim};
    use incal::procedures::tumble::{Tumble, TumbleOptions};
    use incal::procedures::{Procedure, Silent};

    #[test]
    fn one_histogram_per_coefficient_with_three_intervals() {
        let obs = simulate(&TumbleSim {
            truth: incal::models::AccelerometerModel::default(),
            mount: incal::rigs::Mount::Pendulum,
            angles_deg: (0..12).map(|k| f64::from(k) * 30.0).collect(),
            samples: 5,
            noise: 1e-3,
            index_error_rad: 0.0,
            passes: 1,
            seed: 1,
        });
        let o = TumbleOptions {
            mount: incal::rigs::Mount::Pendulum,
            terms: vec![incal::models::Term::K0, incal::models::Term::K1],
            noise: incal::estimation::Noise::Auto,
        };
        let mut doc = Tumble::reduce(&obs, &o, &Silent).unwrap();
        assert!(monte_carlo_plots(&doc).is_empty());
        let mc = MonteCarloOptions::new(Trials::Fixed(500));
        doc.monte_carlo = Some(run::<Tumble>(&obs, &o, &doc, &mc, &Silent).unwrap().0);
        let plots = monte_carlo_plots(&doc);
        assert_eq!(plots.len(), 2);
        let k1 = &plots[1];
        assert_eq!(k1.source, "K1");
        // The staircase holds every counted trial; three intervals, two
        // ends each, inside the histogram's range.
        let h = &doc.monte_carlo.as_ref().unwrap().coefficients["K1"].histogram;
        assert_eq!(h.counts.len(), incal::montecarlo::HISTOGRAM_BINS);
        assert!(h.counts.iter().sum::<u64>() >= 499);
        assert_eq!(k1.series.len(), 7);
        let xs: Vec<f64> = k1.series[1..].iter().map(|s| s.points[0].x).collect();
        let first = &k1.series[0].points;
        let (lo, hi) = (first[0].x, first[first.len() - 1].x);
        assert!(
            xs.iter().all(|x| *x >= lo && *x <= hi),
            "{xs:?} in [{lo}, {hi}]"
        );
        // It renders.
        assert!(crate::plots::render_svg(k1).unwrap().contains("<svg"));
    }
}
