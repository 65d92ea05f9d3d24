//! History of one coefficient of one instrument across calibrations:
//! drift rate, repeatability and the normalized error of the latest
//! calibration against the one before.
//!
//! # Drift
//! The points `(t_i, x_i, u_i)` (t in days since the first calibration,
//! x the coefficient's value, u its standard uncertainty) are fitted with
//! the straight line `x = a + b·t` by weighted least squares on the core
//! ([`incal::estimation::fit`]) with weights `w_i = 1/u_i²`. With
//! `S = Σw`, `S_t = Σw t`, `S_tt = Σw t²`, `Δ = S·S_tt − S_t²` the slope is
//! `b = Σ c_i x_i`, `c_i = w_i (S t_i − S_t)/Δ`, and `u²(b) = S/Δ`.
//!
//! * n = 2: the line goes through both points; `u(b)` comes from the two
//!   u only (`Variance::Known`).
//! * n > 2: `Variance::AtLeast`: the calibrations' own u are the floor;
//!   when the residuals scatter beyond them (χ² test at 5 %, i.e. the
//!   instrument is less stable than one calibration's u says, or it does
//!   not drift linearly), `u²(b)` is scaled by `χ²/(n − 2)` and has
//!   `n − 2` degrees of freedom.
//! * Degrees of freedom of `u(b)` from the u_i: Welch–Satterthwaite
//!   (JCGM 100 G.2b), `ν = u⁴(b) / Σ (c_i u_i)⁴/ν_i` (`null` = infinite).
//!
//! The drift rate is in the coefficient's unit per day.
//!
//! # Repeatability
//! The sample standard deviation of the values,
//! `s = sqrt(Σ (x_i − x̄)²/(n − 1))`, with `n − 1` degrees of freedom. It
//! contains any drift over the period as well as the calibrations' own
//! scatter.
//!
//! # En of the latest
//! `En = (x_n − x_{n−1}) / sqrt(U_n² + U_{n−1}²)` with each calibration's
//! own `U95` (as `incal compare`); `|En| ≤ 1` means the latest agrees
//! with the previous one.

use incal::estimation::{fit, Design, FitOptions, Variance, VarianceSource};
use incal::units::Unit;
use nalgebra::DVector;
use serde::Serialize;

/// One calibration of the coefficient.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HistoryPoint {
    /// Record id.
    pub id: i64,
    /// When the record was made (`YYYY-MM-DDTHH:MM:SSZ`): the
    /// calibration's date on the time axis.
    pub created_utc: String,
    /// Value.
    pub value: f64,
    /// Standard uncertainty.
    pub u: f64,
    /// Expanded uncertainty `U95 = k95·u`.
    #[serde(rename = "U95")]
    pub u95: f64,
    /// Degrees of freedom of u (`None` = infinite).
    pub dof: Option<f64>,
    /// Unit of value, u and U95.
    pub unit: Unit,
    /// The temperature the calibration was made at, °C (its
    /// `temperature_c`: `--meta` or the recording's column), when known.
    pub temperature_c: Option<f64>,
}

/// The drift rate (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Drift {
    /// Slope `b`, unit per day.
    pub value: f64,
    /// Standard uncertainty of the slope.
    pub u: f64,
    /// Degrees of freedom of u (`None` = infinite).
    pub dof: Option<f64>,
    /// The slope's unit (`g/day`, …).
    pub unit: String,
    /// `prior` (the calibrations' own u) or `residuals` (their scatter
    /// exceeded the u).
    pub variance_source: VarianceSource,
    /// Lack-of-fit p-value `P(χ²_{n−2} ≥ Σ w r²)` (n > 2 only).
    pub chi2_p_value: Option<f64>,
    /// The line's value at the first calibration (the value's unit).
    #[serde(skip)]
    pub intercept: f64,
    /// Covariance of (intercept, slope), for the line's band.
    #[serde(skip)]
    pub covariance: [[f64; 2]; 2],
}

/// The repeatability (module docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Repeatability {
    /// Standard deviation of the values.
    pub value: f64,
    /// `n − 1`.
    pub dof: f64,
}

/// Drift, repeatability and En of a history, with a note for each one
/// that cannot be given.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Analysis {
    /// Drift rate per day.
    pub drift: Option<Drift>,
    /// Standard deviation of the values.
    pub repeatability: Option<Repeatability>,
    /// En of the latest calibration against the previous.
    pub en_latest: Option<f64>,
    /// Why something is missing.
    pub notes: Vec<String>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Days between two RFC 3339 times of the stored form.
fn days_between(from: &str, to: &str) -> Option<f64> {
    let a = crate::time::parse_utc(from).ok()?;
    let b = crate::time::parse_utc(to).ok()?;
    Some((b - a) as f64 / 86_400.0)
}

/// The drift rate of `points` (in time order) by weighted least squares
/// (module docs), or why there is none.
pub fn drift(points: &[HistoryPoint]) -> Result<Drift, String> {
    let n = points.len();
    if n < 2 {
        return Err("drift needs two calibrations or more".into());
    }
    if let Some(p) = points.iter().find(|p| !(p.u.is_finite() && p.u > 0.0)) {
        return Err(format!(
            "no drift: record {} has u = {} (weights 1/u^2 need u > 0)",
            p.id, p.u
        ));
    }
    let first = &points[0].created_utc;
    let t: Vec<f64> = points
        .iter()
        .map(|p| days_between(first, &p.created_utc))
        .collect::<Option<_>>()
        .ok_or("no drift: a record's created_utc does not read as a time")?;
    if t.iter().all(|ti| *ti == t[0]) {
        return Err("no drift: every calibration has the same date".into());
    }
    let w = DVector::from_iterator(n, points.iter().map(|p| 1.0 / (p.u * p.u)));
    let x = DVector::from_iterator(n, points.iter().map(|p| p.value));
    // Welch–Satterthwaite over c_i = w_i (S t_i − S_t)/Δ.
    let s: f64 = w.iter().sum();
    let st: f64 = w.iter().zip(&t).map(|(w, t)| w * t).sum();
    let stt: f64 = w.iter().zip(&t).map(|(w, t)| w * t * t).sum();
    let delta = s * stt - st * st;
    let u2_b = s / delta;
    let mut denom = 0.0;
    for (i, p) in points.iter().enumerate() {
        let ci_ui = w[i] * (s * t[i] - st) / delta * p.u;
        if let Some(nu) = p.dof.filter(|d| d.is_finite() && *d > 0.0) {
            denom += ci_ui.powi(4) / nu;
        }
    }
    let nu = if denom > 0.0 {
        u2_b * u2_b / denom
    } else {
        f64::INFINITY
    };
    let nu = if nu.is_finite() { nu } else { f64::INFINITY };
    let design = Design::from_rows(
        vec!["intercept".into(), "rate".into()],
        &t.iter().map(|ti| vec![1.0, *ti]).collect::<Vec<_>>(),
    )
    .map_err(|e| format!("no drift: {e}"))?;
    let variance = if n == 2 {
        Variance::Known { dof: nu }
    } else {
        Variance::AtLeast { dof: nu }
    };
    let f = fit(
        &design,
        &x,
        &FitOptions {
            weights: Some(w),
            variance,
            ..FitOptions::default()
        },
    )
    .map_err(|e| format!("no drift: {e}"))?;
    let value = f.estimates.values()[1];
    let u = f.estimates.u_at(1);
    if !(value.is_finite() && u.is_finite()) {
        return Err("no drift: the fit gave no finite slope".into());
    }
    let dof = f.estimates.dof();
    Ok(Drift {
        value,
        u,
        dof: (dof.is_finite() && dof < 1e6).then_some(dof),
        unit: format!("{}/day", points[0].unit),
        variance_source: f.variance_source,
        chi2_p_value: f.chi2_p_value.and_then(finite),
        intercept: f.estimates.values()[0],
        covariance: {
            let c = f.estimates.covariance();
            [[c[(0, 0)], c[(0, 1)]], [c[(1, 0)], c[(1, 1)]]]
        },
    })
}

/// Sample standard deviation of the values, `n − 1` dof (module docs).
pub fn repeatability(points: &[HistoryPoint]) -> Option<Repeatability> {
    let n = points.len();
    if n < 2 {
        return None;
    }
    let mean = points.iter().map(|p| p.value).sum::<f64>() / n as f64;
    let ss: f64 = points.iter().map(|p| (p.value - mean).powi(2)).sum();
    let value = finite((ss / (n - 1) as f64).sqrt())?;
    Some(Repeatability {
        value,
        dof: (n - 1) as f64,
    })
}

/// En of the last point against the one before (module docs); `None`
/// with fewer than two points or when both U95 are zero.
pub fn en_latest(points: &[HistoryPoint]) -> Option<f64> {
    let [.., prev, last] = points else {
        return None;
    };
    // Scaled by the largest magnitude so nothing overflows.
    let s = [last.value.abs(), prev.value.abs(), last.u95, prev.u95]
        .into_iter()
        .fold(0.0, f64::max);
    if !(s > 0.0 && s.is_finite()) {
        return None;
    }
    let big_u = (last.u95 / s).hypot(prev.u95 / s);
    (big_u > 0.0)
        .then(|| (last.value / s - prev.value / s) / big_u)
        .and_then(finite)
}

/// Drift, repeatability and En of `points` (in time order).
pub fn analyse(points: &[HistoryPoint]) -> Analysis {
    let mut a = Analysis::default();
    match drift(points) {
        Ok(d) => a.drift = Some(d),
        Err(why) => a.notes.push(why),
    }
    a.repeatability = repeatability(points);
    if a.repeatability.is_none() && points.len() < 2 {
        a.notes
            .push("repeatability needs two calibrations or more".into());
    }
    a.en_latest = en_latest(points);
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(id: i64, day: i64, value: f64, u: f64, dof: Option<f64>) -> HistoryPoint {
        let k95 = incal::estimation::coverage_factor(dof.unwrap_or(f64::INFINITY), 0.95);
        HistoryPoint {
            id,
            created_utc: crate::time::format_utc(1_700_000_000 + day * 86_400),
            value,
            u,
            u95: k95 * u,
            dof,
            unit: Unit::G,
            temperature_c: None,
        }
    }

    #[test]
    fn two_points_give_the_exact_slope_with_both_u() {
        let p = [point(1, 0, 1.0, 0.1, None), point(2, 10, 2.0, 0.1, None)];
        let d = drift(&p).unwrap();
        assert!((d.value - 0.1).abs() < 1e-12);
        assert!((d.u - 0.1 * 2f64.sqrt() / 10.0).abs() < 1e-12);
        assert_eq!(d.dof, None);
        assert_eq!(d.unit, "g/day");
        assert_eq!(d.variance_source, VarianceSource::Prior);
        // Welch–Satterthwaite: equal shares with 4 dof each give 8.
        let p = [
            point(1, 0, 1.0, 0.1, Some(4.0)),
            point(2, 10, 2.0, 0.1, Some(4.0)),
        ];
        assert!((drift(&p).unwrap().dof.unwrap() - 8.0).abs() < 1e-9);
    }

    #[test]
    fn slope_matches_the_closed_form_and_scatter_inflates_u() {
        // Points on a line with small u but large scatter: lack of fit.
        let p: Vec<_> = (0..6)
            .map(|i| {
                let wiggle = if i % 2 == 0 { 1.0 } else { -1.0 };
                point(
                    i,
                    30 * i,
                    5.0 + 0.01 * (30 * i) as f64 + wiggle,
                    0.01,
                    Some(50.0),
                )
            })
            .collect();
        let d = drift(&p).unwrap();
        assert_eq!(d.variance_source, VarianceSource::Residuals);
        assert_eq!(d.dof, Some(4.0));
        assert!(d.u > 0.01 / 30.0, "{d:?}");
        // Unweighted (equal u) slope = Σ(t − t̄)(x − x̄)/Σ(t − t̄)².
        let t: Vec<f64> = (0..6).map(|i| 30.0 * i as f64).collect();
        let tm = t.iter().sum::<f64>() / 6.0;
        let xm = p.iter().map(|q| q.value).sum::<f64>() / 6.0;
        let b = t
            .iter()
            .zip(&p)
            .map(|(t, q)| (t - tm) * (q.value - xm))
            .sum::<f64>()
            / t.iter().map(|t| (t - tm).powi(2)).sum::<f64>();
        assert!((d.value - b).abs() < 1e-12 * b.abs().max(1.0));
    }

    #[test]
    fn what_cannot_be_given_is_said() {
        assert!(drift(&[point(1, 0, 1.0, 0.1, None)]).is_err());
        let same_day = [point(1, 0, 1.0, 0.1, None), point(2, 0, 1.1, 0.1, None)];
        assert!(drift(&same_day).unwrap_err().contains("same date"));
        let exact = [point(1, 0, 1.0, 0.0, None), point(2, 3, 1.1, 0.1, None)];
        assert!(drift(&exact).unwrap_err().contains("record 1"));
        let a = analyse(&[point(1, 0, 1.0, 0.1, None)]);
        assert_eq!(a.drift, None);
        assert_eq!(a.repeatability, None);
        assert_eq!(a.en_latest, None);
        assert_eq!(a.notes.len(), 2);
    }

    #[test]
    fn repeatability_and_en() {
        let p = [
            point(1, 0, 1.0, 0.1, None),
            point(2, 1, 2.0, 0.1, None),
            point(3, 2, 3.0, 0.2, None),
        ];
        let r = repeatability(&p).unwrap();
        assert!((r.value - 1.0).abs() < 1e-12);
        assert_eq!(r.dof, 2.0);
        let en = en_latest(&p).unwrap();
        let expect = 1.0 / (p[2].u95.powi(2) + p[1].u95.powi(2)).sqrt();
        assert!((en - expect).abs() < 1e-12);
    }
}
