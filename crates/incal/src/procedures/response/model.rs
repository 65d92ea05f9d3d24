//! Low-pass models with a pure delay, fitted to the dwells' gain and phase.
//!
//! `H(f) = K · L(f) · e^{−j2πfτ}` with
//!
//! * first order: `L = 1/(1 + j f/f_c)`, `|L| = 1/√(1 + (f/f_c)²)`,
//!   `∠L = −atan(f/f_c)`; parameters `x = (K, f_c, τ)`;
//! * second order: `L = 1/(1 − r² + j 2ζr)`, `r = f/f_n`,
//!   `|L| = 1/√((1 − r²)² + (2ζr)²)`, `∠L = −atan2(2ζr, 1 − r²)`;
//!   parameters `x = (K, f_n, ζ, τ)`.
//!
//! A negative `K` (an instrument whose output falls as the input rises)
//! adds π to the phase. The fit minimises
//! `Σ_i [(|K||L_i| − G_i)/u(G_i)]² + [wrap(∠H_i − Δφ_i)/u(Δφ_i)]²` by damped
//! Gauss–Newton on the estimation core
//! ([`crate::estimation::gauss_newton()`]); the phase residual is wrapped into
//! (−π, π], so no unwrapping of the data enters the fit. The variance
//! follows the one statistics rule ([`Variance::AtLeast`]): the dwells' u
//! stand unless the residuals show lack of fit at 5 %.
//!
//! Derived quantities (first-order propagation through a numerical
//! Jacobian, JCGM 100 §5.1.2):
//!
//! * half-power (−3.01 dB) bandwidth: `f_c`, or
//!   `f_n √(1 − 2ζ² + √((1 − 2ζ²)² + 1))`;
//! * the phase frequency, where the phase lag including the delay reaches
//!   45° (first order) or 90° (second order);
//! * the latency, the group delay at zero frequency: `τ + 1/(2πf_c)` or
//!   `τ + ζ/(πf_n)`.
//!
//! Source: the frequency-response test of IEEE Std 1431-2004 §12.15 and
//! IEEE Std 1293-2018; the models are the standard first- and second-order
//! low-pass responses (e.g. Ogata, *Modern Control Engineering*, 5th ed.,
//! Prentice Hall 2010, §7.2).

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

use nalgebra::{DMatrix, DVector};

use super::sine::wrap_pi;
use crate::error::{Error, Result};
use crate::estimation::gauss_newton::{gauss_newton, GaussNewtonOptions, NonlinearModel};
use crate::estimation::{numeric_jacobian, Estimates, Fit, FitOptions, StepControl, Variance};

/// The order of the low-pass model.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Order {
    /// First-order low-pass with delay: `K, f_c, τ`.
    First,
    /// Second-order low-pass with delay: `K, f_n, ζ, τ`.
    Second,
}

impl Order {
    /// `first` or `second`.
    pub fn name(self) -> &'static str {
        match self {
            Order::First => "first",
            Order::Second => "second",
        }
    }

    /// The parameter names of the model, in the order of `x`.
    pub fn names(self) -> Vec<String> {
        let v: &[&str] = match self {
            Order::First => &["k_dc", "fc_hz", "delay_s"],
            Order::Second => &["k_dc", "fn_hz", "zeta", "delay_s"],
        };
        v.iter().map(|s| s.to_string()).collect()
    }

    /// The phase lag at the phase frequency (45° or 90°).
    pub fn phase_lag_rad(self) -> f64 {
        match self {
            Order::First => FRAC_PI_4,
            Order::Second => FRAC_PI_2,
        }
    }
}

/// `(|L(f)|, ∠L(f))` of the low-pass part at `f_hz` for parameters `x`.
pub fn low_pass(order: Order, x: &[f64], f_hz: f64) -> (f64, f64) {
    match order {
        Order::First => {
            let r = f_hz / x[1];
            (1.0 / (1.0 + r * r).sqrt(), -r.atan())
        }
        Order::Second => {
            let r = f_hz / x[1];
            let (re, im) = (1.0 - r * r, 2.0 * x[2] * r);
            (1.0 / re.hypot(im), -im.atan2(re))
        }
    }
}

/// `(|H(f)|, ∠H(f))` of the whole model, the phase continuous in `f`
/// (not wrapped), π added for a negative `K`.
pub fn response(order: Order, x: &[f64], f_hz: f64) -> (f64, f64) {
    let (m, p) = low_pass(order, x, f_hz);
    let delay = x[x.len() - 1];
    let sign = if x[0] < 0.0 { PI } else { 0.0 };
    (x[0].abs() * m, p - TAU * f_hz * delay + sign)
}

/// One dwell as the model fit sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    /// Dwell frequency (Hz).
    pub freq_hz: f64,
    /// Gain `G` (output per reference unit).
    pub gain: f64,
    /// u of the gain.
    pub u_gain: f64,
    /// Phase difference output − reference (rad; any branch).
    pub phase_rad: f64,
    /// u of the phase (rad).
    pub u_phase_rad: f64,
}

/// The smoothing of a Welch estimate by its Hann window (the broadband
/// method): the expected estimate is the transform of `h(s) ρ_w(s − d)`,
/// `ρ_w` the window's normalised autocorrelation
/// `ρ_w(s) = ⅔(1 + ½ cos 2πs/T) ≈ 1 − (2π²/3)(s/T)²` over a segment of
/// `T` seconds and `d` the output's alignment shift, so to second order
///
/// `E[Ĥ](ω) ≈ H(ω) + (2π²/(3T²)) e^{−jωd} ∂²/∂ω² [e^{jωd} H(ω)]`
///
/// (the time-delay bias of Bendat & Piersol 2010 §9.1.4, carried over the
/// impulse response's spread). Fitting the model through it leaves the
/// parameters free of that bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Smoothing {
    /// Segment duration `T` (s).
    pub segment_s: f64,
    /// Alignment shift `d` (s).
    pub shift_s: f64,
}

impl Smoothing {
    /// `(|E[Ĥ]|, arg E[Ĥ])` at `f_hz` (module docs).
    pub fn response(&self, order: Order, x: &[f64], f_hz: f64) -> (f64, f64) {
        use realfft::num_complex::Complex64;
        let g = |f: f64| {
            let (m, p) = response(order, x, f);
            Complex64::from_polar(m, p + TAU * f * self.shift_s)
        };
        let h = 1e-3 * x[1].abs().max(1e-6);
        let d2 = (g(f_hz + h) - g(f_hz) * 2.0 + g(f_hz - h)) / (TAU * h).powi(2);
        let a = 2.0 * PI * PI / (3.0 * self.segment_s * self.segment_s);
        let (m, p) = response(order, x, f_hz);
        let e =
            Complex64::from_polar(m, p) + d2 * Complex64::from_polar(a, -TAU * f_hz * self.shift_s);
        (e.norm(), p + wrap_pi(e.arg() - p))
    }
}

/// The whitened residuals of the model at the points.
struct Residuals<'a> {
    order: Order,
    points: &'a [Point],
    smoothing: Option<Smoothing>,
}

impl NonlinearModel for Residuals<'_> {
    fn names(&self) -> Vec<String> {
        self.order.names()
    }

    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        let n = self.points.len();
        let mut r = DVector::zeros(2 * n);
        for (i, p) in self.points.iter().enumerate() {
            let (m, ph) = match self.smoothing {
                Some(s) => s.response(self.order, x.as_slice(), p.freq_hz),
                None => response(self.order, x.as_slice(), p.freq_hz),
            };
            r[2 * i] = (m - p.gain) / p.u_gain;
            r[2 * i + 1] = wrap_pi(ph - p.phase_rad) / p.u_phase_rad;
        }
        r
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let steps: Vec<f64> = x.iter().map(|v| 1e-7 * v.abs().max(1e-9)).collect();
        numeric_jacobian(&|z: &DVector<f64>| self.predict(z), x, &steps)
    }
}

/// The Gauss–Newton options of every response model fit: damped by step
/// halving, the variance by the one statistics rule
/// ([`Variance::AtLeast`] with the data's `prior_dof`).
pub fn gauss_newton_options(prior_dof: f64) -> GaussNewtonOptions {
    GaussNewtonOptions {
        fit: FitOptions {
            variance: Variance::AtLeast { dof: prior_dof },
            ..FitOptions::default()
        },
        max_iter: 200,
        step: StepControl::Halving {
            halvings: 40,
            polish: 1e-3,
            polish_steps: 8,
        },
        ..GaussNewtonOptions::default()
    }
}

/// A fitted model: its order, the fit (estimates `x̂` and the lack-of-fit
/// test) and the cost `Σ r²`.
#[derive(Debug, Clone)]
pub struct ModelFit {
    /// The order fitted.
    pub order: Order,
    /// The fit on the core (estimates named by [`Order::names`]).
    pub fit: Fit,
    /// `Σ r²` at the minimum (whitened).
    pub cost: f64,
}

/// Fit `order` to `points` from the start values `starts` (the lowest
/// cost that converges wins). `prior_dof`: degrees of freedom of the
/// points' u; `smoothing`: the window's, for spectral estimates. Refuses
/// fewer points than `n − p ≥ 1` needs.
pub fn fit_model(
    order: Order,
    points: &[Point],
    starts: &[Vec<f64>],
    prior_dof: f64,
    smoothing: Option<Smoothing>,
) -> Result<ModelFit> {
    let p = order.names().len();
    if 2 * points.len() < p + 1 {
        return Err(Error::TooFew {
            what: format!(
                "dwells for the {} order model ({p} parameters, checked by lack of fit)",
                order.name()
            ),
            needed: (p + 2) / 2,
            got: points.len(),
        });
    }
    let model = Residuals {
        order,
        points,
        smoothing,
    };
    let opts = gauss_newton_options(prior_dof);
    let y = DVector::zeros(2 * points.len());
    let mut best: Option<ModelFit> = None;
    let mut last_err = None;
    for x0 in starts {
        match gauss_newton(&model, &y, DVector::from_column_slice(x0), &opts) {
            Ok((f, _)) => {
                let f = normalised(order, f)?;
                let cost = f.residuals.norm_squared();
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(ModelFit {
                        order,
                        fit: f,
                        cost,
                    });
                }
            }
            Err(e) => last_err = Some(e),
        }
    }
    best.ok_or_else(|| {
        Error::Unsupported(format!(
            "the {} order model does not fit these dwells ({})",
            order.name(),
            last_err.map_or_else(|| "no start".into(), |e| e.to_string())
        ))
    })
}

/// `(f_n, ζ)` and `(−f_n, −ζ)` are one second-order model: the one with
/// `f_n > 0` is kept. A corner or damping that is not positive is refused.
fn normalised(order: Order, mut f: Fit) -> Result<Fit> {
    let v = f.estimates.values().clone();
    if order == Order::Second && v[1] < 0.0 {
        let j = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, -1.0, -1.0, 1.0]));
        f.estimates = f.estimates.map(order.names(), |x| &j * x, |_| j.clone())?;
    }
    let v = f.estimates.values();
    let bad = match order {
        Order::First => v[1] <= 0.0,
        Order::Second => v[1] <= 0.0 || v[2] <= 0.0,
    };
    if bad {
        return Err(Error::Unsupported(format!(
            "the {} order fit gives a corner or damping that is not positive",
            order.name()
        )));
    }
    Ok(f)
}

/// Half-power bandwidth of the model (Hz).
pub fn bandwidth_hz(order: Order, x: &[f64]) -> f64 {
    match order {
        Order::First => x[1],
        Order::Second => {
            let a = 1.0 - 2.0 * x[2] * x[2];
            x[1] * (a + (a * a + 1.0).sqrt()).sqrt()
        }
    }
}

/// Group delay at zero frequency (s).
pub fn latency_s(order: Order, x: &[f64]) -> f64 {
    let delay = x[x.len() - 1];
    match order {
        Order::First => delay + 1.0 / (TAU * x[1]),
        Order::Second => delay + x[2] / (PI * x[1]),
    }
}

/// The frequency where the phase lag (low-pass and delay) reaches
/// [`Order::phase_lag_rad`], by bisection up to 1000 corners; `None` when
/// the lag does not reach it there.
pub fn phase_freq_hz(order: Order, x: &[f64]) -> Option<f64> {
    let target = order.phase_lag_rad();
    let lag = |f: f64| {
        let (_, p) = low_pass(order, x, f);
        -p + TAU * f * x[x.len() - 1]
    };
    let (mut lo, mut hi) = (0.0, 1000.0 * x[1].abs());
    let top = lag(hi);
    if top.is_nan() || top < target {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if lag(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let f = 0.5 * (lo + hi);
    (f.is_finite() && f > 0.0).then_some(f)
}

/// The model's parameters and derived quantities with their joint
/// covariance: `k_dc`, the corner (`fc_hz` or `fn_hz`), `zeta`,
/// `delay_s`, then `bandwidth_hz`, `phase_freq_hz` (when the lag reaches
/// its target) and `latency_s`.
pub fn coefficients(m: &ModelFit) -> Result<Estimates> {
    derived(m.order, &m.fit.estimates)
}

/// [`coefficients`] of parameter estimates `e` of a model of `order`
/// (a fit's, or a plan's predicted covariance at a guessed truth).
pub fn derived(order: Order, e: &Estimates) -> Result<Estimates> {
    let x = e.values().as_slice().to_vec();
    let with_phase = phase_freq_hz(order, &x).is_some();
    let mut names = vec!["bandwidth_hz".to_string()];
    if with_phase {
        names.push("phase_freq_hz".into());
    }
    names.push("latency_s".into());
    let g = move |x: &DVector<f64>| {
        let s = x.as_slice();
        let mut out = vec![bandwidth_hz(order, s)];
        if with_phase {
            out.push(phase_freq_hz(order, s).unwrap_or(f64::NAN));
        }
        out.push(latency_s(order, s));
        DVector::from_vec(out)
    };
    let steps: Vec<f64> = (0..e.len())
        .map(|k| 1e-6 * e.values()[k].abs().max(e.u_at(k)).max(1e-12))
        .collect();
    let j = numeric_jacobian(&g, e.values(), &steps);
    e.augment(names, g, |_| j.clone())
}

/// The Jacobian of the whitened residuals at `x` (the plan's design).
pub fn jacobian(order: Order, points: &[Point], x: &[f64]) -> DMatrix<f64> {
    Residuals {
        order,
        points,
        smoothing: None,
    }
    .jacobian(&DVector::from_column_slice(x))
}

/// Start values of the fits from the data: `K` from the lowest dwell, the
/// corner where the normalised gain first falls below 1/√2 (or 3× the
/// highest dwell), the delay from the phase left after the low-pass part;
/// for the second order, three dampings.
pub fn starts(order: Order, points: &[Point]) -> Vec<Vec<f64>> {
    let mut sorted: Vec<Point> = points.to_vec();
    sorted.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let Some(first) = sorted.first() else {
        return Vec::new();
    };
    let negative = wrap_pi(first.phase_rad).abs() > FRAC_PI_2;
    let k = if negative { -first.gain } else { first.gain };
    let f_max = sorted.last().map_or(1.0, |p| p.freq_hz);
    let half = std::f64::consts::FRAC_1_SQRT_2;
    let corner = sorted
        .windows(2)
        .find(|w| w[0].gain / k.abs() >= half && w[1].gain / k.abs() < half)
        .map_or(3.0 * f_max, |w| {
            let (g0, g1) = (w[0].gain / k.abs(), w[1].gain / k.abs());
            let s = (g0 - half) / (g0 - g1);
            (w[0].freq_hz.ln() + s * (w[1].freq_hz.ln() - w[0].freq_hz.ln())).exp()
        });
    // Phase relative to the sign, unwrapped from the lowest dwell.
    let sign = if negative { PI } else { 0.0 };
    let mut prev = 0.0;
    let (mut num, mut den) = (0.0, 0.0);
    for p in &sorted {
        let ph = prev + wrap_pi(p.phase_rad - sign - prev);
        prev = ph;
        let w = TAU * p.freq_hz;
        let lp = -(p.freq_hz / corner).atan();
        num += (lp - ph) * w;
        den += w * w;
    }
    let delay = if den > 0.0 { num / den } else { 0.0 };
    match order {
        Order::First => vec![vec![k, corner, delay]],
        Order::Second => [0.3, 0.7, 1.0]
            .iter()
            .map(|z| vec![k, corner, *z, delay])
            .collect(),
    }
}
