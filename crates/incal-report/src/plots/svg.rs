//! Drawing a plot: inline SVG by `plotters` (axes, ticks, reference
//! lines, dots with error bars, lines and dashed lines), and the HTML
//! `<figure>` with its legend and caption.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{colour_hex, heat_colour, Plot, Pt, Series, Style, XAxis, PALETTE};
use crate::format::{esc, trimmed};
use crate::ReportError;

/// Range `[lo, hi]` of `values`, widened by 6 % (a span of zero becomes
/// ±10 % of the value, or ±1).
fn padded(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= f64::EPSILON * hi.abs().max(lo.abs()) || span == 0.0 {
        let d = if hi.abs() > 0.0 { 0.1 * hi.abs() } else { 1.0 };
        return (lo - d, hi + d);
    }
    (lo - 0.06 * span, hi + 0.06 * span)
}

/// A drawing error as the report's.
fn plot_err<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> ReportError {
    ReportError::Plot(e.to_string())
}

/// Width and height of a plot (px; the CSS scales it to the page):
/// lower for category plots (coefficients, history).
fn size(p: &Plot) -> (u32, u32) {
    match p.x_axis {
        XAxis::Numeric | XAxis::Log10 => (760, 380),
        XAxis::Categories(_) => (760, 300),
    }
}

/// A tick label: enough significant digits that neighbouring ticks (about
/// an eighth of the span apart) read differently — at least 4, so a
/// coefficient at 618.79″ spanning 0.004″ reads 618.7915, 618.7920, …
/// rather than "618.8" on every tick — and 0 for a tick within a
/// millionth of the span of zero (not `-1.1e-19`).
fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-6 * span.abs() {
        return "0".into();
    }
    let step = span.abs() / 8.0;
    let digits = if step > 0.0 && step.is_finite() {
        let lead = v.abs().max(step).log10().floor();
        (lead - step.log10().floor() + 1.0).clamp(4.0, 10.0) as usize
    } else {
        4
    };
    trimmed(v, digits)
}

/// The chart a plot is drawn on: numeric x and y (category i at x = i).
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// The plot as one `<svg>` element (no XML declaration, no namespace
/// URL: inline SVG in HTML needs neither).
pub fn render_svg(p: &Plot) -> Result<String, ReportError> {
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, size(p)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_err)?;
        let cells = p.heat.as_ref().map_or(&[][..], |h| h.cells.as_slice());
        let (x0, x1) = match &p.x_axis {
            XAxis::Numeric | XAxis::Log10 => padded(
                p.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|q| q.x))
                    .chain(cells.iter().flat_map(|c| [c[0], c[1]])),
            ),
            XAxis::Categories(c) => (-0.5, c.len().max(1) as f64 - 0.5),
        };
        let (y0, y1) = padded(
            p.series
                .iter()
                .flat_map(|s| s.points.iter())
                .flat_map(|q| {
                    let b = q.bar.unwrap_or(0.0);
                    [q.y - b, q.y + b]
                })
                .chain(p.hlines.iter().map(|h| h.y))
                .chain(cells.iter().flat_map(|c| [c[2], c[3]])),
        );
        let mut chart = chart(&root, p, (x0, x1), (y0, y1))?;
        chart
            .draw_series(cells.iter().map(|c| {
                let (r, g, b) = heat_colour(c[4]);
                Rectangle::new([(c[0], c[2]), (c[1], c[3])], RGBColor(r, g, b).filled())
            }))
            .map_err(plot_err)?;
        for h in &p.hlines {
            let style = if h.limit {
                RGBColor(200, 0, 0).stroke_width(2)
            } else {
                BLACK.mix(0.45).stroke_width(1)
            };
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x0, h.y), (x1, h.y)],
                    style,
                )))
                .map_err(plot_err)?;
        }
        let cap = 0.008 * (x1 - x0);
        let keys = p.series.iter().map(|s| s.key + 1).max().unwrap_or(1);
        for s in &p.series {
            // Dodged series sit side by side, 1 % of the span apart.
            let shift = if p.dodge {
                0.01 * (x1 - x0) * (s.key as f64 - 0.5 * (keys as f64 - 1.0))
            } else {
                0.0
            };
            draw_series(&mut chart, s, shift, cap)?;
        }
        root.present().map_err(plot_err)?;
    }
    // Inline SVG in HTML takes its namespace from the parser: drop the
    // xmlns URL so that the file names no address at all.
    Ok(buf.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

/// The chart of plot `p` on `root` over `x` and `y`, with its mesh drawn:
/// axis descriptions, ticks labelled with [`tick`] (the category names,
/// or the values themselves on log–log axes) and a light grid.
fn chart<'a, 'b>(
    root: &'a DrawingArea<SVGBackend<'b>, Shift>,
    p: &Plot,
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> Result<Chart<'a, 'b>, ReportError> {
    let mut chart = ChartBuilder::on(root)
        .margin(14)
        .x_label_area_size(if p.x_desc.is_empty() { 30 } else { 46 })
        .y_label_area_size(84)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(plot_err)?;
    let categories = match &p.x_axis {
        XAxis::Categories(c) => Some(c.clone()),
        XAxis::Numeric | XAxis::Log10 => None,
    };
    let log_log = p.log_log;
    let log_x = log_log || p.x_axis == XAxis::Log10;
    let x_fmt = |x: &f64| match &categories {
        Some(c) => {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < c.len() {
                c[i as usize].clone()
            } else {
                String::new()
            }
        }
        None if log_x => trimmed(10f64.powf(*x), 3),
        None => tick(*x, x1 - x0),
    };
    let log_y = log_log || p.heat.is_some();
    let y_fmt = |y: &f64| {
        if log_y {
            trimmed(10f64.powf(*y), 3)
        } else {
            tick(*y, y1 - y0)
        }
    };
    let n_x_labels = categories.as_ref().map_or(10, |c| c.len().clamp(1, 24));
    chart
        .configure_mesh()
        .x_desc(p.x_desc.as_str())
        .y_desc(p.y_desc.as_str())
        .x_labels(n_x_labels)
        .y_labels(8)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .bold_line_style(BLACK.mix(0.12))
        .light_line_style(BLACK.mix(0.04))
        .draw()
        .map_err(plot_err)?;
    Ok(chart)
}

/// One series in its colour: a line, a dashed line, or dots (moved by
/// `shift` along x) with their error bars, capped `cap` either side.
fn draw_series(chart: &mut Chart, s: &Series, shift: f64, cap: f64) -> Result<(), ReportError> {
    let (r, g, b) = PALETTE[s.key % PALETTE.len()];
    let colour = RGBColor(r, g, b);
    match s.style {
        Style::Line => {
            chart
                .draw_series(LineSeries::new(
                    s.points.iter().map(|q| (q.x, q.y)),
                    colour.stroke_width(2),
                ))
                .map_err(plot_err)?;
        }
        Style::Dashed => {
            chart
                .draw_series(DashedLineSeries::new(
                    s.points.iter().map(|q| (q.x, q.y)),
                    6,
                    4,
                    colour.stroke_width(1),
                ))
                .map_err(plot_err)?;
        }
        Style::Dots => {
            let moved: Vec<Pt> = s
                .points
                .iter()
                .map(|q| Pt {
                    x: q.x + shift,
                    ..*q
                })
                .collect();
            for q in &moved {
                if let Some(b) = q.bar.filter(|b| *b > 0.0 && b.is_finite()) {
                    let segs = [
                        vec![(q.x, q.y - b), (q.x, q.y + b)],
                        vec![(q.x - cap, q.y - b), (q.x + cap, q.y - b)],
                        vec![(q.x - cap, q.y + b), (q.x + cap, q.y + b)],
                    ];
                    chart
                        .draw_series(
                            segs.into_iter()
                                .map(|v| PathElement::new(v, colour.stroke_width(1))),
                        )
                        .map_err(plot_err)?;
                }
            }
            chart
                .draw_series(
                    moved
                        .iter()
                        .map(|q| Circle::new((q.x, q.y), 4, colour.filled())),
                )
                .map_err(plot_err)?;
        }
    }
    Ok(())
}

/// The plot as an HTML `<figure>`: title, the SVG, a legend in HTML (one
/// swatch per series colour) and the caption.
pub fn figure_html(p: &Plot, index: usize) -> Result<String, ReportError> {
    let svg = render_svg(p)?;
    let mut s = format!(
        "<figure class=\"plot\" id=\"plot-{index}\" data-plot=\"{}\" data-source=\"{}\">\n<h3>{}</h3>\n",
        esc(p.kind),
        esc(&p.source),
        esc(&p.title)
    );
    s.push_str(&svg);
    if !p.legend.is_empty() {
        s.push_str("<p class=\"legend\">");
        for (k, l) in p.legend.iter().enumerate() {
            s.push_str(&format!(
                "<span class=\"key\"><span class=\"swatch\" style=\"background-color:{}\"></span>{}</span> ",
                colour_hex(k),
                esc(l)
            ));
        }
        s.push_str("</p>\n");
    }
    s.push_str(&format!(
        "<figcaption>{}</figcaption>\n</figure>\n",
        esc(&p.caption)
    ));
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_of_a_narrow_span_read_differently() {
        let span = 0.004;
        let labels: Vec<String> = (0..8)
            .map(|k| tick(618.7900 + k as f64 * 0.0005, span))
            .collect();
        let mut unique = labels.clone();
        unique.dedup();
        assert_eq!(unique.len(), labels.len(), "{labels:?}");
        assert_eq!(labels[3], "618.7915");
        // A wide span keeps 4 digits; a tick at zero reads 0.
        assert_eq!(tick(1234.5678, 5000.0), "1235");
        assert_eq!(tick(1e-19, 1.0), "0");
    }

    #[test]
    fn flat_ranges_are_widened() {
        assert_eq!(padded([2.0, 2.0].into_iter()), (1.8, 2.2));
        assert_eq!(padded(std::iter::empty()), (-1.0, 1.0));
        let (lo, hi) = padded([0.0, 1.0].into_iter());
        assert!(lo < 0.0 && hi > 1.0);
    }
}
