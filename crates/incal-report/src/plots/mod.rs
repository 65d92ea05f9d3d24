//! Plots as inline SVG, chosen from the shape of the document only (no
//! per-procedure code):
//!
//! * every table with a `residual` column: the residual at each row
//!   against the table's abscissa, with ±U95 bars of the row's mean, and,
//!   when the table also has `mean`, the data (mean) against the fitted
//!   model (mean − residual);
//! * coefficients named `GROUP.NAME` (one block per accelerometer, …):
//!   for every `NAME` shared by two or more groups in one unit, its value
//!   ±U95 across the groups;
//! * when neither gives a plot: every coefficient's value ±U95, one plot
//!   per unit;
//! * the history of a coefficient over the calibrations of an instrument,
//!   with its limits;
//! * a top-level `channels` object with `taus_s` and `oadev` (the noise
//!   result): the Allan plot of each channel, log–log, with its bounds and
//!   the fitted IEEE 952 lines ([`allan_plots`]), and with `psd` its
//!   amplitude spectral density with χ² bounds and white level
//!   ([`psd_plots`]), and with `davar` the dynamic Allan deviation as a
//!   heat map over time and τ ([`davar_plots`]), and with `temperature`
//!   each term against temperature with its polynomial
//!   ([`noise_temperature_plots`]);
//! * a top-level `mag` object (a magnetometer calibration): the raw
//!   readings on each plane with the fitted ellipsoid's outline, and the
//!   calibrated magnitude along the session ([`mag_plots`]);
//! * a top-level `bode` object (the dynamic response): gain in dB and phase
//!   in degrees against log frequency, the measured points with U95 bars
//!   from the table holding `gain_db`, the fitted model with its U95 band
//!   ([`bode_plots`]);
//! * a `monte_carlo` section: per coefficient the trials' histogram with
//!   both Monte Carlo intervals and the GUM interval
//!   ([`monte_carlo_plots`]).
//!
//! The abscissa of a table is its numeric column, before the statistics
//! columns (`n`, `mean`, `std`, `residual`, …), with the most distinct
//! values (the later one on a tie); the other columns before the
//! statistics name the series (a pass, a configuration, a station and
//! polarity). Plots are drawn by `plotters` with its SVG backend only: text
//! is SVG `<text>` in the generic `sans-serif` family, so nothing is
//! loaded from outside the file.
//!
//! One file per plot kind: `table` and `rows` (the residual and fitted
//! plots of a table), `coefficients`, `history`, `allan`, `bode` and `thermal`;
//! `svg` draws any of them. This file holds what they share: the plot
//! model ([`Plot`], [`Series`], [`Pt`]), the colours and the display
//! units.

mod allan;
mod bode;
mod coefficients;
mod davar;
mod history;
mod mag;
mod montecarlo;
mod psd;
mod rows;
mod svg;
mod table;
mod thermal;

use incal::document::{Cell, Table};
use incal::units::Unit;

pub use allan::allan_plots;
pub use bode::bode_plots;
pub use coefficients::{coefficient_plots, Limits};
pub use davar::davar_plots;
pub use history::history_plot;
pub use mag::mag_plots;
pub use montecarlo::monte_carlo_plots;
pub use psd::psd_plots;
pub use svg::{figure_html, render_svg};
pub use table::{model_curve, table_plots, table_plots_with, Curve};
pub use thermal::{noise_temperature_plots, thermal_plots};

/// Colours of the series (Tableau 10), also used by the HTML legend.
pub const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// One plot per channel of a noise result (`extra.channels`), where
/// `plot(name, channel)` draws one (none without `channels`).
fn channel_plots(
    doc: &incal::document::ResultDocument,
    plot: impl Fn(&str, &serde_json::Value) -> Option<Plot>,
) -> Vec<Plot> {
    doc.extra
        .get("channels")
        .and_then(|c| c.as_object())
        .map(|chans| chans.iter().filter_map(|(n, c)| plot(n, c)).collect())
        .unwrap_or_default()
}

/// `#rrggbb` of series `k`.
pub fn colour_hex(k: usize) -> String {
    let (r, g, b) = PALETTE[k % PALETTE.len()];
    format!("#{r:02x}{g:02x}{b:02x}")
}

/// One point, with an optional half-width of its error bar.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pt {
    /// Abscissa (display units).
    pub x: f64,
    /// Ordinate (display units).
    pub y: f64,
    /// Half-width of the bar (display units).
    pub bar: Option<f64>,
}

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Dots (with their bars).
    Dots,
    /// A line through the points in the order of x.
    Line,
    /// A thin dashed line (a band's edge).
    Dashed,
}

/// A series of a plot; series with the same `key` share a colour and one
/// entry of the legend.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Index of the legend entry (colour).
    pub key: usize,
    /// How it is drawn.
    pub style: Style,
    /// Points.
    pub points: Vec<Pt>,
}

/// The abscissa: numbers, or categories at 0, 1, 2, …
#[derive(Debug, Clone, PartialEq)]
pub enum XAxis {
    /// Numbers.
    Numeric,
    /// Named positions 0, 1, …
    Categories(Vec<String>),
    /// Numbers drawn as their log10 (the points' x are log10 of the
    /// value): ticks are labelled with the values (a Bode plot).
    Log10,
}

/// A horizontal reference line (zero, a limit).
#[derive(Debug, Clone, PartialEq)]
pub struct HLine {
    /// Ordinate (display units).
    pub y: f64,
    /// A limit (red) or a reference (grey).
    pub limit: bool,
}

/// One plot, independent of how it is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct Plot {
    /// `residual`, `fitted`, `coefficients` or `history`.
    pub kind: &'static str,
    /// What it is drawn from: a table id, a coefficient name or group.
    pub source: String,
    /// Title (plain text).
    pub title: String,
    /// Axis descriptions (plain text).
    pub x_desc: String,
    /// Axis descriptions (plain text).
    pub y_desc: String,
    /// Abscissa.
    pub x_axis: XAxis,
    /// Shift the dots of series apart along x so that points at the same
    /// abscissa stay visible.
    pub dodge: bool,
    /// Series.
    pub series: Vec<Series>,
    /// Legend entries by key (empty: no legend).
    pub legend: Vec<String>,
    /// Reference lines.
    pub hlines: Vec<HLine>,
    /// What the plot shows and how the bars are computed (plain text).
    pub caption: String,
    /// Coordinates are log10 of the values (Allan plots): ticks are
    /// labelled with the values.
    pub log_log: bool,
    /// A heat map drawn under the series (its ordinate is log10, labelled
    /// with the values).
    pub heat: Option<Heat>,
}

/// A heat map: rectangles coloured by a value from −1 (blue) through 0
/// (white) to +1 (red), what the value means said in the caption.
#[derive(Debug, Clone, PartialEq)]
pub struct Heat {
    /// Each cell as `[x0, x1, y0, y1, z]` (display units; z clipped to
    /// [−1, 1] when drawn).
    pub cells: Vec<[f64; 5]>,
}

/// The colour of a heat map's value `z` (clipped to [−1, 1]): white at 0,
/// towards blue (33, 102, 172) below and red (178, 24, 43) above.
pub fn heat_colour(z: f64) -> (u8, u8, u8) {
    let z = if z.is_finite() {
        z.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let to = if z < 0.0 {
        (33.0, 102.0, 172.0)
    } else {
        (178.0, 24.0, 43.0)
    };
    let a = z.abs();
    let mix = |c: f64| (255.0 + (c - 255.0) * a).round() as u8;
    (mix(to.0), mix(to.1), mix(to.2))
}

/// Display scale and label for numbers of `unit` of magnitude up to
/// `magnitude`: the engineering unit of [`Unit::engineering_for`], except
/// that g-based values of 0.1 g or more (a centrifuge output in g) read in
/// g rather than in millions of µg.
pub fn display_unit(unit: Option<&Unit>, magnitude: f64) -> (f64, String) {
    match unit {
        None => (1.0, String::new()),
        Some(Unit::G) if magnitude.abs() >= 0.1 => (1.0, "g".into()),
        Some(u) => {
            let (s, l) = u.engineering_for(magnitude);
            (
                s,
                if l == "1" {
                    String::new()
                } else {
                    l.to_string()
                },
            )
        }
    }
}

/// `name (unit)`, or the name alone for a unit-less quantity.
pub fn with_unit(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_string()
    } else {
        format!("{name} ({unit})")
    }
}

/// A finite number cell's value (`None` for text, null or a non-finite
/// number).
fn number(c: &Cell) -> Option<f64> {
    match c {
        Cell::Number(x) if x.is_finite() => Some(*x),
        _ => None,
    }
}

/// Index of column `name` of a table.
fn column(t: &Table, name: &str) -> Option<usize> {
    t.columns.iter().position(|c| c.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centrifuge_outputs_in_g_read_in_g() {
        assert_eq!(display_unit(Some(&Unit::G), 25.0), (1.0, "g".into()));
        assert_eq!(display_unit(Some(&Unit::G), 1e-4), (1e6, "ug".into()));
        assert_eq!(display_unit(Some(&Unit::One), 1.0), (1.0, String::new()));
    }
}
