//! The model part every response method shares: the low-pass model's
//! order by the one statistics rule, its coefficients and derived
//! quantities, the normalising scale, the model-free bandwidth and the
//! gain flatness, from points of gain and phase with their u (dwells of a
//! stepped sine, bins of a broadband spectrum).

use super::model::{self, ModelFit, Order, Point};
use super::{BandwidthMethod, OrderChoice};
use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::warning::{Warning, WarningCode};

/// The options of the model part, flattened into each response method's
/// options (the same keys everywhere).
#[derive(
    Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct ModelOptions {
    /// Model order (default auto: the one statistics rule).
    #[serde(default)]
    pub order: OrderChoice,
    /// Scale factor the gains are normalised to (output per reference
    /// unit); default: the fitted `k_dc`.
    #[serde(default)]
    pub k1: Option<f64>,
    /// Standard uncertainty of `k1`.
    #[serde(default)]
    pub u_k1: Option<f64>,
    /// The reference's relative amplitude uncertainty (%, type B).
    #[serde(default)]
    pub u_reference_pct: f64,
    /// The reference's phase uncertainty (deg, type B).
    #[serde(default)]
    pub u_reference_phase_deg: f64,
    /// Which bandwidth `bandwidth_hz` is (default model).
    #[serde(default)]
    pub bandwidth: BandwidthMethod,
    /// Upper end of the gain-flatness band (Hz): `flatness_db` is
    /// reported only with it (a band up to the bandwidth would hold the
    /// −3 dB point itself).
    #[serde(default)]
    pub flatness_to_hz: Option<f64>,
    /// The rig whose reference standard the reference channel is (the
    /// certificate's traceability; default rate-table).
    #[serde(default)]
    pub rig: Rig,
}

/// A frequency in a message, to a micro-hertz (an estimated dwell's has
/// sixteen digits).
fn fmax_text(f_hz: f64) -> String {
    crate::error::short_f64((f_hz * 1e6).round() / 1e6)
}

/// The rig of a dynamic-response test: its reference standard makes the
/// result traceable (the table's encoder or rate sensor, or the shaker's
/// reference accelerometer or laser vibrometer, ISO 16063-21/-11).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Rig {
    /// A rate table in its angular-vibration mode.
    #[default]
    RateTable,
    /// A vibration exciter (shaker).
    Shaker,
}

impl ModelOptions {
    /// The range checks of these options.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, check_range, invalid};
        if let Some(k) = self.k1 {
            if !(k.is_finite() && k != 0.0) {
                return invalid("k1", "must be a finite number other than 0");
            }
        }
        if let Some(u) = self.u_k1 {
            if self.k1.is_none() {
                return invalid("u_k1", "given without `k1`");
            }
            check_range("u_k1", u, 0.0, f64::MAX, "")?;
        }
        super::check_reference_u(self.u_reference_pct, self.u_reference_phase_deg)?;
        if let Some(f) = self.flatness_to_hz {
            check_positive("flatness_to_hz", f)?;
        }
        Ok(())
    }
}

/// The model part of a response result (module docs).
#[derive(Debug, Clone)]
pub struct ModelPart {
    /// The model chosen.
    pub model: ModelFit,
    /// Why that order (the decision's message).
    pub order_reason: String,
    /// Model parameters and derived quantities (one correlation block).
    pub coefficients: Estimates,
    /// The normalising scale: value, u and where it came from.
    pub scale: (f64, f64, &'static str),
    /// Model-free bandwidth `(value, u)` (Hz), or why there is none.
    pub interpolated: std::result::Result<(f64, f64), String>,
    /// The interpolation's own error in that u (Hz, a method error; the
    /// Monte Carlo draws it), 0 without a model-free bandwidth.
    pub interpolation_u_hz: f64,
    /// Gain flatness `(max |dB|, u, at Hz, band Hz)`, if a point is in the band.
    pub flatness: Option<(f64, f64, f64, f64)>,
    /// Which bandwidth is the headline.
    pub bandwidth: BandwidthMethod,
    /// Lowest and highest frequency fitted (Hz).
    pub range_hz: (f64, f64),
    /// The model's warnings.
    pub warnings: Vec<Warning>,
}

impl ModelPart {
    /// Fit the model to `points` (`prior_dof`: the degrees of freedom of
    /// their u) and derive the rest.
    pub fn fit(
        points: &[Point],
        c: &ModelOptions,
        prior_dof: f64,
        smoothing: Option<model::Smoothing>,
    ) -> Result<Self> {
        let (model, order_reason) = choose_model(points, c, prior_dof, smoothing)?;
        let coefficients = model::coefficients(&model)?;
        let (k_dc, u_k_dc) = coefficients.get("k_dc").unwrap_or((1.0, 0.0));
        let scale = match c.k1 {
            Some(k) => (k, c.u_k1.unwrap_or(0.0), "k1"),
            None => (k_dc, u_k_dc, "k_dc"),
        };
        let u_scale_db = 20.0 / std::f64::consts::LN_10 * scale.1 / scale.0.abs();
        let levels = levels_db(points, scale.0);
        let parts = interpolated_parts(&levels, u_scale_db);
        let interpolation_u_hz = parts.as_ref().map_or(0.0, |p| p.2);
        let interpolated = parts.map(|p| (p.0, p.1));
        if c.bandwidth == BandwidthMethod::Interpolated {
            if let Err(gap) = &interpolated {
                return Err(Error::Unsupported(format!(
                    "no model-free bandwidth: {gap}"
                )));
            }
        }
        let flatness = c.flatness_to_hz.and_then(|band| {
            levels
                .iter()
                .filter(|l| l.0 <= band)
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                .map(|l| (l.1.abs(), l.2.hypot(u_scale_db), l.0, band))
        });
        let range_hz = levels.iter().fold((f64::INFINITY, 0.0f64), |(a, b), l| {
            (a.min(l.0), b.max(l.0))
        });
        let mut part = ModelPart {
            model,
            order_reason,
            coefficients,
            scale,
            interpolated,
            interpolation_u_hz,
            flatness,
            bandwidth: c.bandwidth,
            range_hz,
            warnings: Vec::new(),
        };
        part.warnings = part.model_warnings(c);
        Ok(part)
    }

    /// Replace the model's covariance (and its degrees of freedom) by one
    /// estimated otherwise (the broadband jackknife), and the derived
    /// quantities with it; `var_interp` adds to the model-free bandwidth's
    /// variance.
    pub fn set_covariance(
        &mut self,
        cov: nalgebra::DMatrix<f64>,
        dof: f64,
        var_interp: Option<f64>,
    ) -> Result<()> {
        let e = &self.model.fit.estimates;
        self.model.fit.estimates =
            Estimates::new(e.names().to_vec(), e.values().clone(), cov, dof)?;
        self.coefficients = model::coefficients(&self.model)?;
        if let (Ok((_, u)), Some(v)) = (&mut self.interpolated, var_interp) {
            *u = (*u * *u + v).sqrt();
        }
        Ok(())
    }

    /// What the engineer must be told about the model.
    fn model_warnings(&self, c: &ModelOptions) -> Vec<Warning> {
        let e = &self.coefficients;
        let mut w = self.model.fit.quality_warnings(
            "the model order, a resonance or filter the model lacks, or a reference error beyond u_reference_pct",
        );
        let f_max = self.range_hz.1;
        if let Some(bw) = e.value("bandwidth_hz") {
            if bw > f_max {
                w.push(Warning::new(
                    WarningCode::ModelRange,
                    format!("the model's bandwidth ({bw:.4} Hz) is above the highest frequency fitted ({} Hz): it is extrapolated by the model", fmax_text(f_max)),
                ));
            }
        }
        if let Some(tau) = e.value("delay_s") {
            if f_max > 0.0 && tau.abs() > 1.0 / f_max {
                w.push(Warning::new(
                    WarningCode::PhaseAmbiguous,
                    format!("the delay ({:.4} ms) is longer than one period of the highest frequency fitted ({} Hz, {:.4} ms): its phase is known only up to whole cycles, so the delay rests on the frequencies below", tau * 1e3, fmax_text(f_max), 1e3 / f_max),
                ));
            }
        }
        if c.k1.is_some() && c.u_k1.is_none() {
            w.push(Warning::new(
                WarningCode::MissingUncertainty,
                "k1 given without u_k1: the normalised gains take it as exact",
            ));
        }
        w
    }
}

/// The model fitted at the order the options ask for (the one statistics
/// rule, [`choose_order`]) and the reason for its order.
fn choose_model(
    points: &[Point],
    o: &ModelOptions,
    dof: f64,
    smoothing: Option<model::Smoothing>,
) -> Result<(ModelFit, String)> {
    let fit = |order: Order| {
        model::fit_model(order, points, &model::starts(order, points), dof, smoothing)
    };
    let (_, m, reason) = choose_order(o.order, fit, |m: &ModelFit| {
        m.fit.chi2_p_value.unwrap_or(1.0)
    })?;
    Ok((m, reason))
}

/// The one order rule of every response method: the order asked for, or
/// (`auto`) the first order unless its fit fails the lack-of-fit test at
/// 5 % (`p_of`: the fit's χ² p value), then the second; the first again,
/// with its lack of fit, when the second does not fit. `fit` fits one
/// order. Returns the order, its fit and the reason for the decision.
pub fn choose_order<T>(
    choice: OrderChoice,
    fit: impl Fn(Order) -> Result<T>,
    p_of: impl Fn(&T) -> f64,
) -> Result<(Order, T, String)> {
    match choice {
        OrderChoice::First => {
            let m = fit(Order::First)?;
            let r = format!("first order, as asked (lack-of-fit p = {:.3})", p_of(&m));
            Ok((Order::First, m, r))
        }
        OrderChoice::Second => {
            let m = fit(Order::Second)?;
            let r = format!("second order, as asked (lack-of-fit p = {:.3})", p_of(&m));
            Ok((Order::Second, m, r))
        }
        OrderChoice::Auto => {
            let first = fit(Order::First);
            if let Ok(m) = &first {
                if p_of(m) >= crate::estimation::linear::LACK_OF_FIT_ALPHA {
                    let r = format!(
                        "first order: its fit passes the lack-of-fit test (chi-square p = {:.3} >= 0.05), so no second-order term is needed",
                        p_of(m)
                    );
                    return Ok((Order::First, first?, r));
                }
            }
            let why = match &first {
                Ok(m) if p_of(m) > 0.0 => format!(
                    "the first-order fit fails the lack-of-fit test (p = {:.2e} < 0.05)",
                    p_of(m)
                ),
                Ok(_) => "the first-order fit fails the lack-of-fit test (p < 1e-300)".to_string(),
                Err(e) => format!("the first-order model does not fit ({e})"),
            };
            match fit(Order::Second) {
                Ok(m) => {
                    let r = format!(
                        "second order: {why}; the second-order fit gives p = {:.3}",
                        p_of(&m)
                    );
                    Ok((Order::Second, m, r))
                }
                Err(e2) => match first {
                    Ok(m) => Ok((Order::First, m, format!("first order: {why}, and the second-order model does not fit ({e2}); u is scaled by the residual scatter"))),
                    Err(e) => Err(e),
                },
            }
        }
    }
}

/// The points' gains in dB against `scale`, sorted by frequency:
/// `(f, dB, u_dB)`.
pub fn levels_db(points: &[Point], scale: f64) -> Vec<(f64, f64, f64)> {
    let c = 20.0 / std::f64::consts::LN_10;
    let mut v: Vec<(f64, f64, f64)> = points
        .iter()
        .map(|p| {
            let g = p.gain / scale.abs();
            (p.freq_hz, 20.0 * g.log10(), c * p.u_gain / p.gain)
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// The half-power level in dB, `20 log10(1/√2)`.
pub const HALF_POWER_DB: f64 = -3.010_299_956_639_812;

/// Model-free bandwidth: `ln f` interpolated linearly in dB between the
/// first two dwells that bracket [`HALF_POWER_DB`]. Its u has the
/// dwells' u(dB) and the scale's (which shifts both) and the
/// interpolation's own error: the largest difference `Δ` between the
/// linear crossing and the crossing of a parabola through the pair and
/// one neighbour (below or above), taken as a standard uncertainty
/// `u = |Δ|` (the curvature the dwells show, type B).
/// Err: the gap, for people.
pub fn interpolated_bandwidth(
    levels: &[(f64, f64, f64)],
    u_scale_db: f64,
) -> std::result::Result<(f64, f64), String> {
    interpolated_parts(levels, u_scale_db).map(|p| (p.0, p.1))
}

/// [`interpolated_bandwidth`] with the interpolation's own error `|Δ|`
/// (Hz) apart: `(f, u, |Δ|)`.
fn interpolated_parts(
    levels: &[(f64, f64, f64)],
    u_scale_db: f64,
) -> std::result::Result<(f64, f64, f64), String> {
    let l = HALF_POWER_DB;
    let (Some(lo), Some(hi)) = (levels.first(), levels.last()) else {
        return Err("no dwells".into());
    };
    if lo.1 < l {
        return Err(format!(
            "the gain is below -3.01 dB already at the lowest dwell ({} Hz, {:.2} dB): add dwells below it",
            lo.0, lo.1
        ));
    }
    let Some(i) = levels.windows(2).position(|w| w[0].1 >= l && w[1].1 < l) else {
        return Err(format!(
            "the gain stays above -3.01 dB up to the highest dwell ({} Hz, {:.2} dB): add dwells above it",
            hi.0, hi.1
        ));
    };
    let (f0, d0, u0) = levels[i];
    let (f1, d1, u1) = levels[i + 1];
    let at = |a: f64, b: f64| ((f0.ln()) + (a - l) / (a - b) * (f1.ln() - f0.ln())).exp();
    let f = at(d0, d1);
    let h = 1e-6;
    let g0 = (at(d0 + h, d1) - at(d0 - h, d1)) / (2.0 * h);
    let g1 = (at(d0, d1 + h) - at(d0, d1 - h)) / (2.0 * h);
    let thirds = [
        levels.get(i + 2),
        i.checked_sub(1).and_then(|j| levels.get(j)),
    ];
    let u_interp = thirds
        .iter()
        .flatten()
        .map(|t| (parabola_crossing([(f0, d0), (f1, d1), (t.0, t.1)], l) - f).abs())
        .fold(0.0, f64::max);
    let u = ((g0 * u0).powi(2)
        + (g1 * u1).powi(2)
        + ((g0 + g1) * u_scale_db).powi(2)
        + u_interp.powi(2))
    .sqrt();
    Ok((f, u, u_interp))
}

/// The frequency between the first two points where the parabola in
/// `ln f` through the three points `(f, dB)` crosses `level` (bisection;
/// the first two points bracket it).
fn parabola_crossing(p: [(f64, f64); 3], level: f64) -> f64 {
    let x: Vec<f64> = p.iter().map(|q| q.0.ln()).collect();
    let y = |z: f64| {
        (0..3)
            .map(|i| {
                let mut w = p[i].1;
                for j in (0..3).filter(|j| *j != i) {
                    w *= (z - x[j]) / (x[i] - x[j]);
                }
                w
            })
            .sum::<f64>()
    };
    let (mut a, mut b) = (x[0], x[1]);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if y(m) >= level {
            a = m;
        } else {
            b = m;
        }
    }
    (0.5 * (a + b)).exp()
}
