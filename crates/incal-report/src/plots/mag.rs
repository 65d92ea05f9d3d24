//! The plots of a magnetometer calibration (a top-level `mag` object and
//! the `mag_points` table): the raw readings projected on the x–y, x–z
//! and y–z planes with the outline of the fitted ellipsoid, and the
//! calibrated field's magnitude along the session with its target.
//!
//! The ellipsoid is `{h + F S⁻¹ u : |u| = 1}` (`F` the calibrated
//! magnitude); its outline on the plane of axes `a, b` is the ellipse
//! `c + M^{1/2} (cos t, sin t)` with `M` the `a, b` block of
//! `F² S⁻¹ S⁻ᵀ` and `c` the hard iron there.

use incal::document::{ResultDocument, Table};
use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2};

use super::{number, HLine, Plot, Pt, Series, Style, XAxis};

/// The `mag_points` column `name`, one number per row.
fn column(t: &Table, name: &str) -> Option<Vec<f64>> {
    let k = t.columns.iter().position(|c| c.name == name)?;
    t.rows.iter().map(|r| number(&r[k])).collect()
}

/// The magnetometer plots of `doc` (none without `mag` and `mag_points`).
pub fn mag_plots(doc: &ResultDocument) -> Vec<Plot> {
    let Some(extra) = doc.extra.get("mag") else {
        return Vec::new();
    };
    let Some(t) = doc.tables.iter().find(|t| t.id == "mag_points") else {
        return Vec::new();
    };
    let c = |n: &str| doc.coefficients.get(n).map(|c| c.value);
    let (Some(raw), Some(mag), Some(line)) = (
        ["raw_x", "raw_y", "raw_z"]
            .iter()
            .map(|n| column(t, n))
            .collect::<Option<Vec<_>>>(),
        column(t, "magnitude"),
        column(t, "row"),
    ) else {
        return Vec::new();
    };
    let soft: Option<Vec<f64>> = [
        "soft_iron_xx",
        "soft_iron_xy",
        "soft_iron_xz",
        "soft_iron_yy",
        "soft_iron_yz",
        "soft_iron_zz",
    ]
    .iter()
    .map(|n| c(n))
    .collect();
    let hard: Option<Vec<f64>> = ["hard_iron_x", "hard_iron_y", "hard_iron_z"]
        .iter()
        .map(|n| c(n))
        .collect();
    let (Some(s), Some(h)) = (soft, hard) else {
        return Vec::new();
    };
    let s = Matrix3::new(s[0], s[1], s[2], s[1], s[3], s[4], s[2], s[4], s[5]);
    let target = extra["field_reference_ut"]
        .as_f64()
        .or_else(|| c("field_raw"))
        .unwrap_or(f64::NAN);
    let raw_unit = extra["unit"].as_str().unwrap_or("raw");
    let out_unit = extra["output_unit"].as_str().unwrap_or("raw");
    let mut plots = Vec::new();
    if let Some(a) = s.try_inverse() {
        let cov = a * a.transpose() * target * target;
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            plots.push(projection(&raw, &h, &cov, (i, j), raw_unit));
        }
    }
    plots.push(magnitude(&line, &mag, target, out_unit));
    plots
}

/// The readings on the plane of axes `i, j` and the ellipsoid's outline
/// there (a closed line).
fn projection(
    raw: &[Vec<f64>],
    h: &[f64],
    cov: &Matrix3<f64>,
    (i, j): (usize, usize),
    unit: &str,
) -> Plot {
    let axes = ["x", "y", "z"];
    let m = Matrix2::new(cov[(i, i)], cov[(i, j)], cov[(j, i)], cov[(j, j)]);
    let e = SymmetricEigen::new(m);
    let root = e.eigenvectors
        * Matrix2::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0).sqrt()))
        * e.eigenvectors.transpose();
    let centre = Vector2::new(h[i], h[j]);
    let outline: Vec<Pt> = (0..=180)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / 180.0;
            let p = centre + root * Vector2::new(t.cos(), t.sin());
            Pt {
                x: p.x,
                y: p.y,
                bar: None,
            }
        })
        .collect();
    let dots: Vec<Pt> = raw[i]
        .iter()
        .zip(&raw[j])
        .map(|(x, y)| Pt {
            x: *x,
            y: *y,
            bar: None,
        })
        .collect();
    Plot {
        kind: "mag",
        source: "mag_points".into(),
        title: format!("Raw field, {}-{} plane, and the fitted ellipsoid", axes[i], axes[j]),
        x_desc: format!("mag_{} ({unit})", axes[i]),
        y_desc: format!("mag_{} ({unit})", axes[j]),
        x_axis: XAxis::Numeric,
        dodge: false,
        series: vec![
            Series {
                key: 0,
                style: Style::Dots,
                points: dots,
            },
            Series {
                key: 1,
                style: Style::Line,
                points: outline,
            },
        ],
        legend: vec![
            "raw readings (table mag_points)".into(),
            "outline of the fitted ellipsoid".into(),
        ],
        hlines: Vec::new(),
        caption: format!(
            "The raw readings projected on the {a}-{b} plane, with the outline of the fitted ellipsoid (hard iron at its centre, the soft iron's inverse its shape): points off the outline are noise, motion, or a field that is not uniform.",
            a = axes[i],
            b = axes[j]
        ),
        log_log: false,
        heat: None,
    }
}

/// The calibrated magnitude of each reading along the session.
fn magnitude(line: &[f64], mag: &[f64], target: f64, unit: &str) -> Plot {
    Plot {
        kind: "mag",
        source: "mag_points".into(),
        title: "Calibrated field magnitude along the session".into(),
        x_desc: "row of the session (from 0)".into(),
        y_desc: format!("|b| ({unit})"),
        x_axis: XAxis::Numeric,
        dodge: false,
        series: vec![Series {
            key: 0,
            style: Style::Dots,
            points: line
                .iter()
                .zip(mag)
                .map(|(x, y)| Pt {
                    x: *x,
                    y: *y,
                    bar: None,
                })
                .collect(),
        }],
        legend: vec!["|S (m - h)| of a reading".into()],
        hlines: if target.is_finite() {
            vec![HLine {
                y: target,
                limit: false,
            }]
        } else {
            Vec::new()
        },
        caption: "The calibrated field's magnitude of each reading of table mag_points against its row in the session, with the magnitude the calibration is scaled to (grey): a calibrated session scatters about it by the noise alone; a drift or a step along the session is a field that changed.".into(),
        log_log: false,
        heat: None,
    }
}
