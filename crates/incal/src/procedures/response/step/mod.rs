//! Step response: a rate step on a rate table or a tilt step on a
//! dividing head, the instrument's output fitted in the time domain by the
//! same low-pass model with delay as the frequency methods
//! (docs/src/response.md).
//!
//! # Model
//! The reference steps from `r₀` to `r₁` (`A = r₁ − r₀`) at `t₀`, the
//! time it crosses `(r₀ + r₁)/2` (linear interpolation between the two
//! samples around the crossing; `r₀`, `r₁` the means before and after the
//! samples within a tenth of the record of the crossing). The output
//!
//! `y(t) = y₀ + K A s(t − t₀ − τ)`, `s = 0` for negative time,
//!
//! with `s` the unit step response of the low-pass part
//! ([`unit_step`]): `1 − e^{−ω_c t}` (first order); for the second order
//! `1 − e^{−ζω_n t}(cos ω_d t + ζω_n/ω_d sin ω_d t)`, `ω_d = ω_n√(1 − ζ²)`
//! (and its critically and over-damped forms). Parameters
//! `(y₀, K, f_c|f_n, [ζ], τ)` by damped Gauss–Newton on the estimation
//! core, each sample weighted by the output's scatter before the step
//! (`σ`, with `n_pre − 1` degrees of freedom; the one statistics rule
//! scales u when the residuals exceed it). The order is chosen by the same
//! rule as in the frequency methods.
//!
//! The step's time is known only to within the sample interval `Δt` where
//! the reference jumps in one sample: `u²(t₀) = Δt²/12` (rectangular) is
//! added to the delay's and latency's variance.
//!
//! # Derived (u through the Jacobian)
//! `rise_time_s` (10 % to 90 % of the model's step), `overshoot_pct`
//! (second order with ζ < 1: `100 e^{−πζ/√(1−ζ²)}`), `settling_time_s`
//! (the last time the model's step leaves ±`settling_band_pct` of its
//! final value, from the step), `delay_s`, `latency_s`, `bandwidth_hz`
//! and, first order, `time_constant_s = 1/(2πf_c)`.

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

use std::f64::consts::TAU;

use nalgebra::{DMatrix, DVector};

use super::broadband::input::Record;
use super::model::{self, Order};
use super::OrderChoice;
use crate::error::{Error, Result};
use crate::estimation::gauss_newton::{gauss_newton, NonlinearModel};
use crate::estimation::{numeric_jacobian, Estimates, Fit};

/// Options of the step reduction. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct StepOptions {
    /// Sampling rate (Hz) when the file has no `time_s` column.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Model order (default auto: the one statistics rule).
    #[serde(default)]
    pub order: OrderChoice,
    /// Half-width of the settling band (% of the step; default 2).
    #[serde(default = "two")]
    pub settling_band_pct: f64,
}

fn two() -> f64 {
    2.0
}

impl Default for StepOptions {
    fn default() -> Self {
        Self {
            rate_hz: None,
            order: OrderChoice::Auto,
            settling_band_pct: 2.0,
        }
    }
}

impl StepOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        use crate::options::check_range;
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-3, 1e7, "Hz")?;
        }
        check_range("settling_band_pct", self.settling_band_pct, 0.01, 50.0, "%")
    }
}

/// The unit step response of the low-pass part at `t_s` (s) for model
/// parameters `x` (`K` and the delay not applied).
pub fn unit_step(order: Order, x: &[f64], t_s: f64) -> f64 {
    if t_s <= 0.0 {
        return 0.0;
    }
    match order {
        Order::First => 1.0 - (-TAU * x[1] * t_s).exp(),
        Order::Second => {
            let (wn, z) = (TAU * x[1], x[2]);
            if (z - 1.0).abs() < 1e-6 {
                1.0 - (-wn * t_s).exp() * (1.0 + wn * t_s)
            } else if z < 1.0 {
                let wd = wn * (1.0 - z * z).sqrt();
                1.0 - (-z * wn * t_s).exp() * ((wd * t_s).cos() + z * wn / wd * (wd * t_s).sin())
            } else {
                let r = (z * z - 1.0).sqrt();
                let (p1, p2) = (wn * (z - r), wn * (z + r));
                1.0 - (p2 * (-p1 * t_s).exp() - p1 * (-p2 * t_s).exp()) / (p2 - p1)
            }
        }
    }
}

/// The located step: `t₀`, the levels and `u(t₀)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Located {
    /// Step time (s from the first sample).
    pub t0_s: f64,
    /// Reference before and after.
    pub r0: f64,
    /// Reference after.
    pub r1: f64,
    /// `u(t₀)` (s).
    pub u_t0_s: f64,
    /// Samples before the step.
    pub pre: usize,
}

/// Find the step of the reference (module docs); refused when it does
/// not step beyond its noise or steps too near either end.
pub fn locate(rec: &Record) -> Result<Located> {
    let r = &rec.reference;
    let n = r.len();
    // The largest jump over a tenth of the record marks the region.
    let w = (n / 10).max(1);
    let (mut k_best, mut jump) = (0, 0.0f64);
    for k in 0..n.saturating_sub(w) {
        let d = (r[k + w] - r[k]).abs();
        if d > jump {
            jump = d;
            k_best = k;
        }
    }
    let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len().max(1) as f64;
    let (before, after) = (&r[..k_best.max(1)], &r[(k_best + w).min(n - 1)..]);
    let (r0, r1) = (mean(before), mean(after));
    let sd = |s: &[f64], m: f64| {
        (s.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (s.len().max(2) - 1) as f64).sqrt()
    };
    let noise = sd(before, r0).max(sd(after, r1));
    if jump <= 0.0 {
        return Err(Error::Unsupported(format!(
            "the reference does not step: it holds {:.6e} throughout",
            r[0]
        )));
    }
    if before.len() < 10 || after.len() < 10 {
        return Err(Error::Unsupported(
            "the reference steps within a tenth of the record of its start or end: record at least 10 samples before and after the step".into(),
        ));
    }
    if (r1 - r0).abs() <= 10.0 * noise.max(1e-12 * r0.abs().max(r1.abs())) {
        return Err(Error::Unsupported(format!(
            "the reference does not step beyond its noise (from {r0:.6e} to {r1:.6e}, noise {noise:.3e})"
        )));
    }
    let mid = 0.5 * (r0 + r1);
    let up = r1 > r0;
    let i = (k_best..n - 1)
        .find(|&i| (r[i] < mid) == up && (r[i + 1] >= mid) == up)
        .unwrap_or(k_best);
    let dt = 1.0 / rec.rate_hz;
    let frac = ((mid - r[i]) / (r[i + 1] - r[i])).clamp(0.0, 1.0);
    let width = (r[i + 1] - r[i]).abs() / (r1 - r0).abs();
    Ok(Located {
        // The reference's sample of row n is taken δ after the output's.
        t0_s: (i as f64 + frac) * dt + rec.reference_offset_s,
        r0,
        r1,
        // A jump within one sample: the time is anywhere in it.
        u_t0_s: if width > 0.5 { dt / 12f64.sqrt() } else { 0.0 },
        pre: i + 1,
    })
}

/// The whitened residuals of the step model.
struct StepResiduals<'a> {
    order: Order,
    rec: &'a Record,
    at: Located,
    sigma: f64,
}

impl StepResiduals<'_> {
    fn names(&self) -> Vec<String> {
        let mut v = vec!["y0".to_string()];
        v.extend(self.order.names());
        v
    }

    fn model(&self, p: &[f64], t: f64) -> f64 {
        let x = &p[1..];
        let a = self.at.r1 - self.at.r0;
        p[0] + x[0] * a * unit_step(self.order, x, t - self.at.t0_s - x[x.len() - 1])
    }
}

impl NonlinearModel for StepResiduals<'_> {
    fn names(&self) -> Vec<String> {
        StepResiduals::names(self)
    }

    fn predict(&self, p: &DVector<f64>) -> DVector<f64> {
        let dt = 1.0 / self.rec.rate_hz;
        DVector::from_iterator(
            self.rec.output.len(),
            self.rec
                .output
                .iter()
                .enumerate()
                .map(|(k, y)| (self.model(p.as_slice(), k as f64 * dt) - y) / self.sigma),
        )
    }

    fn jacobian(&self, p: &DVector<f64>) -> DMatrix<f64> {
        let steps: Vec<f64> = p.iter().map(|v| 1e-7 * v.abs().max(1e-9)).collect();
        numeric_jacobian(&|z: &DVector<f64>| self.predict(z), p, &steps)
    }
}

/// A step reduced.
#[derive(Debug, Clone)]
pub struct StepResult {
    /// The located step.
    pub located: Located,
    /// The output's scatter before the step.
    pub sigma: f64,
    /// The order fitted and why.
    pub order: Order,
    /// Why that order.
    pub order_reason: String,
    /// The fit (estimates `y0` and the model's parameters).
    pub fit: Fit,
    /// Model parameters, derived quantities and step metrics.
    pub coefficients: Estimates,
    /// The sampling rate (Hz).
    pub rate_hz: f64,
    /// The record, for the document's curve.
    pub record: Record,
    /// The options.
    pub options: StepOptions,
}

/// Fit one order from the frequency-method starts adapted to the step.
fn fit_order(order: Order, rec: &Record, at: Located, sigma: f64, dof: f64) -> Result<Fit> {
    let m = StepResiduals {
        order,
        rec,
        at,
        sigma,
    };
    let dt = 1.0 / rec.rate_hz;
    let n = rec.output.len();
    let mean = |a: usize, b: usize| rec.output[a..b].iter().sum::<f64>() / (b - a).max(1) as f64;
    let y0 = mean(0, at.pre);
    let y1 = mean(n - n / 10, n);
    let k = (y1 - y0) / (at.r1 - at.r0);
    // Time to half the change, after the step: a corner and a delay.
    let half = (at.pre..n)
        .find(|&i| ((rec.output[i] - y0) / (y1 - y0)) >= 0.5)
        .map_or(10.0 * dt, |i| (i as f64 * dt - at.t0_s).max(dt));
    let corner = 0.11 / half;
    let starts: Vec<Vec<f64>> = match order {
        Order::First => vec![vec![y0, k, corner, 0.0]],
        Order::Second => [0.4, 0.7, 1.0]
            .iter()
            .map(|z| vec![y0, k, corner * 1.5, *z, 0.0])
            .collect(),
    };
    let opts = model::gauss_newton_options(dof);
    let y = DVector::zeros(n);
    let mut best: Option<(f64, Fit)> = None;
    let mut last = None;
    for s in starts {
        match gauss_newton(&m, &y, DVector::from_vec(s), &opts) {
            Ok((f, _)) => {
                let v = f.estimates.values();
                let ok = v[2] > 0.0 && (order == Order::First || v[3] > 0.0);
                let cost = f.residuals.norm_squared();
                if ok && best.as_ref().is_none_or(|b| cost < b.0) {
                    best = Some((cost, f));
                }
            }
            Err(e) => last = Some(e.to_string()),
        }
    }
    best.map(|b| b.1).ok_or_else(|| {
        Error::Unsupported(format!(
            "the {} order step model does not fit ({})",
            order.name(),
            last.unwrap_or_else(|| "a corner or damping that is not positive".into())
        ))
    })
}

/// The step metrics of the model (module docs) at parameters `x` (the
/// model's, without `y0`).
pub fn metrics(order: Order, x: &[f64], band_pct: f64) -> (f64, f64, f64) {
    let corner = x[1];
    let horizon = 50.0 / (TAU * corner)
        * if order == Order::Second {
            1.0 / x[2].min(1.0)
        } else {
            1.0
        };
    let n = 20_000;
    let h = horizon / n as f64;
    let s: Vec<f64> = (0..=n).map(|k| unit_step(order, x, k as f64 * h)).collect();
    let cross = |level: f64| {
        (1..=n).find(|&k| s[k] >= level).map_or(f64::NAN, |k| {
            let f = (level - s[k - 1]) / (s[k] - s[k - 1]);
            (k as f64 - 1.0 + f) * h
        })
    };
    let rise = cross(0.9) - cross(0.1);
    let overshoot = s.iter().cloned().fold(0.0, f64::max).max(1.0) * 100.0 - 100.0;
    let b = band_pct / 100.0;
    let settle = (0..=n)
        .rev()
        .find(|&k| (s[k] - 1.0).abs() > b)
        .map_or(0.0, |k| {
            let k1 = (k + 1).min(n);
            let (e0, e1) = ((s[k] - 1.0).abs(), (s[k1] - 1.0).abs());
            let f = if e0 != e1 { (e0 - b) / (e0 - e1) } else { 0.0 };
            (k as f64 + f.clamp(0.0, 1.0)) * h
        });
    (rise, overshoot, settle + x[x.len() - 1])
}

/// The reduction (module docs).
pub fn calibrate(rec: &Record, o: &StepOptions) -> Result<StepResult> {
    o.validate()?;
    let at = locate(rec)?;
    let pre = &rec.output[..at.pre];
    let m = pre.iter().sum::<f64>() / pre.len() as f64;
    let sigma = (pre.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (pre.len() - 1) as f64).sqrt();
    if sigma <= 0.0 || !sigma.is_finite() {
        return Err(Error::Unsupported(
            "the output does not scatter before the step: its noise, which weights the fit, is zero".into(),
        ));
    }
    let dof = (at.pre - 1) as f64;
    let (order, fit, reason) = super::fit::choose_order(
        o.order,
        |order| fit_order(order, rec, at, sigma, dof),
        |f: &Fit| f.chi2_p_value.unwrap_or(1.0),
    )?;
    let coefficients = derive(order, &fit.estimates, at.u_t0_s, o.settling_band_pct)?;
    Ok(StepResult {
        located: at,
        sigma,
        order,
        order_reason: reason,
        fit,
        coefficients,
        rate_hz: rec.rate_hz,
        record: rec.clone(),
        options: o.clone(),
    })
}

/// The model's parameters (without `y0`), the frequency-domain derived
/// quantities and the step metrics, with `u(t₀)` added to the delay's
/// variance (module docs).
fn derive(order: Order, e: &Estimates, u_t0: f64, band_pct: f64) -> Result<Estimates> {
    let names: Vec<String> = e.names()[1..].to_vec();
    let idx: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut x = e.select(&idx)?;
    if u_t0 > 0.0 {
        let mut c = x.covariance().clone();
        let k = c.nrows() - 1;
        c[(k, k)] += u_t0 * u_t0;
        x = Estimates::new(names, x.values().clone(), c, x.dof())?;
    }
    let all = model::derived(order, &x)?;
    let mut extra = vec!["rise_time_s".to_string(), "settling_time_s".to_string()];
    let under = order == Order::Second && x.values()[2] < 1.0;
    if under {
        extra.push("overshoot_pct".into());
    }
    if order == Order::First {
        extra.push("time_constant_s".into());
    }
    let n = x.len();
    let g = move |v: &DVector<f64>| {
        let s = &v.as_slice()[..n];
        let (rise, over, settle) = metrics(order, s, band_pct);
        let mut out = vec![rise, settle];
        if under {
            out.push(over);
        }
        if order == Order::First {
            out.push(1.0 / (TAU * s[1]));
        }
        DVector::from_vec(out)
    };
    let steps: Vec<f64> = (0..all.len())
        .map(|k| 1e-6 * all.values()[k].abs().max(all.u_at(k)).max(1e-12))
        .collect();
    let j = numeric_jacobian(&g, all.values(), &steps);
    all.augment(extra, g, |_| j.clone())
}

/// Step response as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ResponseStep;

impl crate::procedures::Procedure for ResponseStep {
    const ID: crate::document::Procedure = crate::document::Procedure::ResponseStep;
    type Options = StepOptions;
    type Input = Record;

    fn example() -> StepOptions {
        StepOptions::default()
    }

    fn validate(o: &StepOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(rows: &mut incal_io::Reader<R>, o: &StepOptions) -> Result<Record> {
        input::read(rows, o.rate_hz)
    }

    fn reduce(
        rec: &Record,
        o: &StepOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(rec, o)?.document()
    }

    fn synthesis(
        rec: &Record,
        o: &StepOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
