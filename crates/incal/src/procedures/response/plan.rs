//! Stepped-sine plans: the dwells, and the predicted u of every dwell's
//! gain and phase and of the model's coefficients before any data.
//!
//! For `N` samples of white noise σ over whole cycles, the three-parameter
//! sine fit gives `u(A) = u(B) = σ√(2/N)`, so `u(R) = σ√(2/N)` and
//! `u(φ) = σ√(2/N)/R` (IEEE Std 1057-2017 §4.1.3.1). With the guessed
//! model these give each dwell's `u(G)` and `u(Δφ)`
//! ([`super::dwell_u`], the reduction's formulas), and the model fit's own Jacobian
//! at the guess gives the covariance of `k_dc, f_c|f_n, ζ, τ` and, through
//! [`super::model::derived`], of the bandwidth, phase frequency and
//! latency: plan and reduction share one design.

use nalgebra::DVector;
use serde_json::json;

use super::model::{self, response, Order, Point};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};
use crate::estimation::Design;
use crate::options::{check_positive, check_range, invalid};

/// Which dwells, and how long each lasts.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct DwellChoice {
    /// The dwell frequencies (Hz), in test order; default a log-spaced
    /// sweep from `f_min_hz` to `f_max_hz`.
    #[serde(default)]
    pub dwells_hz: Option<Vec<f64>>,
    /// Lowest dwell of the log-spaced sweep (Hz; default 1).
    #[serde(default = "f_min")]
    pub f_min_hz: f64,
    /// Highest dwell of the log-spaced sweep (Hz; default 200).
    #[serde(default = "f_max")]
    pub f_max_hz: f64,
    /// Dwells of the log-spaced sweep (default 12).
    #[serde(default = "twelve")]
    pub dwells: usize,
    /// Seconds per dwell (default 2), lengthened to `min_cycles`.
    #[serde(default = "two")]
    pub seconds_per_dwell: f64,
    /// Fewest cycles per dwell (default 10; at least 2).
    #[serde(default = "ten")]
    pub min_cycles: f64,
}

fn f_min() -> f64 {
    1.0
}
fn f_max() -> f64 {
    200.0
}
fn twelve() -> usize {
    12
}
fn two() -> f64 {
    2.0
}
fn ten() -> f64 {
    10.0
}

impl Default for DwellChoice {
    fn default() -> Self {
        Self {
            dwells_hz: None,
            f_min_hz: f_min(),
            f_max_hz: f_max(),
            dwells: twelve(),
            seconds_per_dwell: two(),
            min_cycles: ten(),
        }
    }
}

impl DwellChoice {
    /// The dwells `(freq_hz, seconds)` in test order.
    pub fn schedule(&self) -> Result<Vec<(f64, f64)>> {
        check_range("seconds_per_dwell", self.seconds_per_dwell, 1e-3, 1e6, "s")?;
        check_range("min_cycles", self.min_cycles, 2.0, 1e6, "")?;
        let freqs = match &self.dwells_hz {
            Some(v) => {
                if v.is_empty() || v.len() > 10_000 {
                    return invalid("dwells_hz", "give 1 to 10000 frequencies");
                }
                for f in v {
                    check_range("dwells_hz", *f, 1e-4, 1e7, "Hz")?;
                }
                v.clone()
            }
            None => {
                check_range("f_min_hz", self.f_min_hz, 1e-4, 1e7, "Hz")?;
                check_range("f_max_hz", self.f_max_hz, 1e-4, 1e7, "Hz")?;
                if self.f_max_hz <= self.f_min_hz {
                    return invalid("f_max_hz", "must be above `f_min_hz`");
                }
                if !(2..=10_000).contains(&self.dwells) {
                    return invalid("dwells", format!("from 2 to 10000, got {}", self.dwells));
                }
                let (a, b) = (self.f_min_hz.ln(), self.f_max_hz.ln());
                let n = self.dwells - 1;
                (0..=n)
                    .map(|k| {
                        let f = (a + (b - a) * k as f64 / n as f64).exp();
                        // Four significant digits: a table can set it.
                        format!("{f:.3e}").parse().unwrap_or(f)
                    })
                    .collect()
            }
        };
        Ok(freqs
            .into_iter()
            .map(|f| (f, self.seconds_per_dwell.max(self.min_cycles / f)))
            .collect())
    }
}

/// The model assumed (a plan's guess, a simulation's truth).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ModelGuess {
    /// Model order (default second).
    #[serde(default = "second")]
    pub order: Order,
    /// Low-frequency gain `k_dc` (output per reference unit; default 1).
    #[serde(default = "one")]
    pub k_dc: f64,
    /// Corner `f_c` or natural frequency `f_n` (Hz; default 80).
    #[serde(default = "eighty")]
    pub corner_hz: f64,
    /// Damping ratio ζ of the second order (default 0.6).
    #[serde(default = "zeta")]
    pub zeta: f64,
    /// Pure delay τ (s; default 0.002).
    #[serde(default = "delay")]
    pub delay_s: f64,
}

fn second() -> Order {
    Order::Second
}
fn one() -> f64 {
    1.0
}
fn eighty() -> f64 {
    80.0
}
fn zeta() -> f64 {
    0.6
}
fn delay() -> f64 {
    0.002
}

impl Default for ModelGuess {
    fn default() -> Self {
        Self {
            order: second(),
            k_dc: 1.0,
            corner_hz: 80.0,
            zeta: 0.6,
            delay_s: 0.002,
        }
    }
}

impl ModelGuess {
    /// The model as a simulation's truth: `order`, `k_dc`, `corner_hz`,
    /// `zeta` (second order), `delay_s`, `bandwidth_hz`, `phase_freq_hz`,
    /// `latency_s`.
    pub fn truth(&self) -> Result<serde_json::Map<String, serde_json::Value>> {
        let x = self.x()?;
        let order = self.order;
        let v = json!({
            "order": order.name(),
            "k_dc": x[0],
            "corner_hz": x[1],
            "zeta": (order == Order::Second).then_some(x[2]),
            "delay_s": x[x.len() - 1],
            "bandwidth_hz": model::bandwidth_hz(order, &x),
            "phase_freq_hz": model::phase_freq_hz(order, &x),
            "latency_s": model::latency_s(order, &x),
        });
        match v {
            serde_json::Value::Object(m) => Ok(m),
            _ => Ok(serde_json::Map::new()),
        }
    }

    /// The parameter vector `x` of [`model`], checked.
    pub fn x(&self) -> Result<Vec<f64>> {
        if !(self.k_dc.is_finite() && self.k_dc != 0.0 && self.k_dc.abs() <= 1e12) {
            return invalid("k_dc", "must be a finite number other than 0");
        }
        check_range("corner_hz", self.corner_hz, 1e-4, 1e7, "Hz")?;
        check_range("delay_s", self.delay_s, -10.0, 10.0, "s")?;
        Ok(match self.order {
            Order::First => vec![self.k_dc, self.corner_hz, self.delay_s],
            Order::Second => {
                check_range("zeta", self.zeta, 1e-3, 100.0, "")?;
                vec![self.k_dc, self.corner_hz, self.zeta, self.delay_s]
            }
        })
    }
}

/// Options of `incal plan response-sine`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ResponsePlanOptions {
    /// The dwells.
    #[serde(flatten)]
    pub dwells: DwellChoice,
    /// The expected response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// Reference amplitude (reference units; default 10).
    #[serde(default = "amplitude")]
    pub amplitude: f64,
    /// Output noise σ of one sample (output units; default 0.02).
    #[serde(default = "noise")]
    pub noise: f64,
    /// Reference noise σ of one sample (reference units; default 0.005).
    #[serde(default = "reference_noise")]
    pub reference_noise: f64,
    /// The reference's relative amplitude uncertainty (%, type B).
    #[serde(default)]
    pub u_reference_pct: f64,
    /// The reference's phase uncertainty (deg, type B).
    #[serde(default)]
    pub u_reference_phase_deg: f64,
}

/// A simulator's `reference_clock_offset_s` (s): from −1 to 1.
pub fn check_clock_offset(s: f64) -> Result<()> {
    check_range("reference_clock_offset_s", s, -1.0, 1.0, "s")
}

pub(super) fn thousand() -> f64 {
    1000.0
}
pub(super) fn amplitude() -> f64 {
    10.0
}
pub(super) fn noise() -> f64 {
    0.02
}
pub(super) fn reference_noise() -> f64 {
    0.005
}

/// The checks a plan and a simulation share: the noises, the reference's
/// type-B terms, the model and the dwells; the schedule `(freq_hz,
/// seconds)`, each dwell below the Nyquist frequency of `rate_hz`.
pub fn check_test(
    dwells: &DwellChoice,
    model: &ModelGuess,
    rate_hz: f64,
    noises: [f64; 2],
    u_reference: [f64; 2],
) -> Result<Vec<(f64, f64)>> {
    check_range("rate_hz", rate_hz, 1e-3, 1e7, "Hz")?;
    check_range("noise", noises[0], 0.0, 1e12, "")?;
    check_range("reference_noise", noises[1], 0.0, 1e12, "")?;
    super::check_reference_u(u_reference[0], u_reference[1])?;
    model.x()?;
    let s = dwells.schedule()?;
    if let Some((f, _)) = s.iter().find(|(f, _)| *f >= rate_hz / 2.0) {
        return invalid(
            "dwells_hz",
            format!(
                "{f} Hz is at or above the Nyquist frequency ({} Hz) of rate_hz",
                rate_hz / 2.0
            ),
        );
    }
    crate::sim::check_rows(&[(
        "samples of all dwells",
        s.iter()
            .map(|(_, sec)| (sec * rate_hz).round())
            .sum::<f64>(),
    )])?;
    Ok(s)
}

impl ResponsePlanOptions {
    /// Range checks; the schedule `(freq_hz, seconds)`.
    pub fn validate(&self) -> Result<Vec<(f64, f64)>> {
        check_positive("amplitude", self.amplitude)?;
        check_test(
            &self.dwells,
            &self.model,
            self.rate_hz,
            [self.noise, self.reference_noise],
            [self.u_reference_pct, self.u_reference_phase_deg],
        )
    }

    /// Each dwell's predicted point (gain and phase of the guess, with u).
    pub fn points(&self, schedule: &[(f64, f64)]) -> Result<Vec<Point>> {
        let x = self.model.x()?;
        Ok(schedule
            .iter()
            .map(|&(f, sec)| {
                let n = (sec * self.rate_hz).round().max(1.0);
                let (m, ph) = response(self.model.order, &x, f);
                let ry = m * self.amplitude;
                let ur = self.reference_noise * (2.0 / n).sqrt();
                let uy = self.noise * (2.0 / n).sqrt();
                let (u_gain, u_phase_rad) = super::dwell_u(
                    m,
                    [(ry, uy, uy / ry), (self.amplitude, ur, ur / self.amplitude)],
                    self.u_reference_pct,
                    self.u_reference_phase_deg,
                );
                Point {
                    freq_hz: f,
                    gain: m,
                    u_gain,
                    phase_rad: ph,
                    u_phase_rad,
                }
            })
            .collect())
    }
}

impl crate::procedures::Plan for super::ResponseSine {
    type Options = ResponsePlanOptions;

    fn plan(o: &ResponsePlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document: the dwells and the predicted u of every dwell's
/// gain (dB) and phase (deg) and of the model's coefficients. Refused when
/// no dwell reaches the expected bandwidth (the corner is then not
/// determined) or the model's design cannot separate its terms.
pub fn plan_document(o: &ResponsePlanOptions) -> Result<PlanDocument> {
    let schedule = o.validate()?;
    let x = o.model.x()?;
    let order = o.model.order;
    let bw = model::bandwidth_hz(order, &x);
    let f_top = schedule.iter().map(|s| s.0).fold(0.0, f64::max);
    if f_top < bw {
        return Err(Error::InvalidOption {
            key: "dwells_hz".into(),
            message: format!("bandwidth_hz is not determined: no dwell at or above the expected bandwidth ({bw:.4} Hz); the highest is {f_top} Hz"),
        });
    }
    let points = o.points(&schedule)?;
    if 2 * points.len() < order.names().len() + 1 {
        return Err(Error::TooFew {
            what: format!("dwells for the {} order model", order.name()),
            needed: (order.names().len() + 2) / 2,
            got: points.len(),
        });
    }
    let j = model::jacobian(order, &points, &x);
    let cov =
        Design::new(order.names(), j)?.predict(&DVector::from_element(2 * points.len(), 1.0))?;
    let e = crate::estimation::Estimates::new(
        order.names(),
        DVector::from_vec(x.clone()),
        cov.covariance().clone(),
        f64::INFINITY,
    )?;
    let all = model::derived(order, &e)?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::ResponseSine,
        format!(
            "Stepped-sine plan: {} dwells from {} to {} Hz, {} order model",
            schedule.len(),
            schedule.first().map_or(0.0, |s| s.0),
            f_top,
            order.name()
        ),
    );
    d.with_options(o)?;
    d.set(
        "dwells_hz",
        json!(schedule.iter().map(|s| s.0).collect::<Vec<_>>()),
    )?;
    d.set(
        "seconds",
        json!(schedule.iter().map(|s| s.1).collect::<Vec<_>>()),
    )?;
    d.set("amplitude", json!(o.amplitude))?;
    for (k, n) in all.names().iter().enumerate() {
        d.predict(n, all.u_at(k), super::document::unit_of(n)?.as_str())?;
    }
    let c = 20.0 / std::f64::consts::LN_10;
    for p in &points {
        let f = crate::error::short_number(&p.freq_hz.to_string());
        d.predict(&format!("gain_db@{f}Hz"), c * p.u_gain / p.gain, "dB")?;
        d.predict(
            &format!("phase_deg@{f}Hz"),
            p.u_phase_rad.to_degrees(),
            "deg",
        )?;
    }
    d.note("predicted u for white noise of the stated σ on both channels and whole cycles per dwell; the reduction takes the noise from each dwell's residuals");
    Ok(d)
}

/// Records simulated and reduced by a plan that predicts by simulation
/// (the broadband and step plans).
pub const PLAN_RECORDS: u64 = 4;

/// The root mean square over the reductions of `runs` (each the
/// coefficients of one simulated record) of every coefficient's u, in the
/// order of the first: what a plan by simulation predicts.
pub fn rms_u(
    runs: impl IntoIterator<Item = Result<crate::estimation::Estimates>>,
) -> Result<Vec<(String, f64)>> {
    let mut sums: Vec<(String, f64)> = Vec::new();
    let mut n = 0usize;
    for e in runs {
        let e = e?;
        n += 1;
        for (i, name) in e.names().iter().enumerate() {
            match sums.iter_mut().find(|s| &s.0 == name) {
                Some(s) => s.1 += e.u_at(i).powi(2),
                None => sums.push((name.clone(), e.u_at(i).powi(2))),
            }
        }
    }
    let n = n.max(1) as f64;
    Ok(sums.into_iter().map(|(k, v)| (k, (v / n).sqrt())).collect())
}

/// The run sheet: each dwell's frequency, duration, cycles and amplitude.
pub fn run_sheet(d: &PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let f = values(&d.plan, "dwells_hz");
    let s = values(&d.plan, "seconds");
    let a = d
        .plan
        .get("amplitude")
        .and_then(|v| v.as_f64())
        .unwrap_or(f64::NAN);
    (
        vec!["freq_hz", "seconds", "cycles", "amplitude"],
        f.iter()
            .zip(s.iter())
            .map(|(f, s)| vec![num(*f), num(*s), num(f * s), num(a)])
            .collect(),
    )
}
