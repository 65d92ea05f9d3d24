//! Turn-on time and warm-up: a recording from power-on at constant
//! temperature reduced to the turn-on time, the warm-up curve, the
//! settled value, the settling time and the warm-up drift
//! (docs/src/warmup.md; IEEE Std 952-1997 and IEEE Std 1431-2004 turn-on
//! and warm-up tests, GJB 2426A start-up time).
//!
//! # Turn-on
//! A row is valid when its output cell holds a number, within
//! `[valid_min, valid_max]` when given, and its `status` is not 0 when
//! the file has that column. Time runs from power-on (`power_on_s` on the
//! file's clock). The turn-on time is the first valid row's time less
//! half a sample interval `Δt`, with `u = Δt/√12` (the output became
//! valid somewhere within the interval before it).
//!
//! # Warm-up curve
//! `B(t) = B∞ + A e^{−t/τ} [+ A₂ e^{−t/τ₂}] [+ D t]` (t from power-on;
//! `τ ≥ τ₂`), fitted by damped Gauss–Newton to the means of blocks of
//! `M` rows after turn-on (the model averaged over each block's samples,
//! so the block's length biases nothing; `M` at most τ/10 and a 400th of
//! the record). Each block mean is weighted by `σ²_LR / n_b`, with
//! `σ²_LR` the long-run variance of one sample: the residuals of the
//! richest curve that fits (two exponentials and a drift, else the next
//! simpler), over the longest valid run, in 20 batches of `m_n` samples,
//! `σ²_LR = m_n Σ r̄ⱼ² / (20 − p)` with `20 − p` degrees of freedom
//! (batch means: noise correlated over a batch, a Gauss–Markov bias or
//! flicker at that scale, is in u, not `σ/√n`). The one lack-of-fit rule
//! of incal ([`crate::estimation::linear::LACK_OF_FIT_ALPHA`]), at the
//! batch scale against that pure error ([`fit::Fits::lack_of_fit`]: the
//! extra-sum-of-squares F test), chooses the shape: the first of `exp1`,
//! `exp1-drift`, `exp2`, `exp2-drift` that passes with τ at most a third
//! of the record (a longer τ cannot be told from a drift); u is scaled by
//! the ratio of the mean squares where none passes.
//!
//! # Derived (u through the Jacobian)
//! `settling_time_s`: the last time, from power-on, the transient
//! `|Σ Aᵢ e^{−t/τᵢ}|` exceeds the band (`settle_band`, output units;
//! default 1 % of `|Σ Aᵢ|`), never before turn-on. `warmup_drift`: the
//! transient's mean over the first `first_window_s` after turn-on, the
//! mean output of the first minute against the settled curve.

pub mod document;
pub mod fit;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

use nalgebra::DVector;

use crate::error::{Error, Result};
use crate::estimation::linear::LACK_OF_FIT_ALPHA;
use crate::estimation::{numeric_jacobian, Estimates, Fit};
use crate::warning::{Warning, WarningCode};
use fit::{Blocks, Shape};
use input::Record;

/// Which warm-up curve (`auto`: the lack-of-fit rule, module docs).
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
pub enum CurveChoice {
    /// The simplest shape that passes the lack-of-fit test.
    #[default]
    Auto,
    /// One exponential.
    Exp1,
    /// One exponential and a linear drift.
    Exp1Drift,
    /// Two exponentials.
    Exp2,
    /// Two exponentials and a linear drift.
    Exp2Drift,
}

impl CurveChoice {
    /// The shape asked for, `None` for `auto`.
    pub fn shape(self) -> Option<Shape> {
        match self {
            CurveChoice::Auto => None,
            CurveChoice::Exp1 => Some(Shape::Exp1),
            CurveChoice::Exp1Drift => Some(Shape::Exp1Drift),
            CurveChoice::Exp2 => Some(Shape::Exp2),
            CurveChoice::Exp2Drift => Some(Shape::Exp2Drift),
        }
    }
}

/// Options of the warm-up reduction. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WarmupOptions {
    /// Sampling rate (Hz) when the file has no `time_s` column.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// The output column (default `output`).
    #[serde(default = "output")]
    pub column: String,
    /// Power-on on the file's clock (s; default 0): rows before it are
    /// left out.
    #[serde(default)]
    pub power_on_s: f64,
    /// A valid output is at least this (output units).
    #[serde(default)]
    pub valid_min: Option<f64>,
    /// A valid output is at most this (output units).
    #[serde(default)]
    pub valid_max: Option<f64>,
    /// The warm-up curve (default auto).
    #[serde(default)]
    pub curve: CurveChoice,
    /// Half-width of the settling band (output units; default 1 % of the
    /// transient at power-on).
    #[serde(default)]
    pub settle_band: Option<f64>,
    /// The warm-up drift's window after turn-on (s; default 60).
    #[serde(default = "sixty")]
    pub first_window_s: f64,
    /// Block length (s; default chosen from the record, module docs).
    #[serde(default)]
    pub block_s: Option<f64>,
    /// Largest temperature span before a warning (°C; default 1).
    #[serde(default = "one")]
    pub max_temperature_span_c: f64,
}

fn output() -> String {
    "output".into()
}
fn sixty() -> f64 {
    60.0
}
fn one() -> f64 {
    1.0
}

impl Default for WarmupOptions {
    fn default() -> Self {
        Self {
            rate_hz: None,
            column: output(),
            power_on_s: 0.0,
            valid_min: None,
            valid_max: None,
            curve: CurveChoice::Auto,
            settle_band: None,
            first_window_s: 60.0,
            block_s: None,
            max_temperature_span_c: 1.0,
        }
    }
}

impl WarmupOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, check_range, invalid};
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-3, 1e7, "Hz")?;
        }
        if self.column.is_empty() {
            return invalid("column", "an empty column name");
        }
        check_range("power_on_s", self.power_on_s, -1e12, 1e12, "s")?;
        for (k, v) in [("valid_min", self.valid_min), ("valid_max", self.valid_max)] {
            if let Some(v) = v {
                check_range(k, v, -1e15, 1e15, "")?;
            }
        }
        if let (Some(a), Some(b)) = (self.valid_min, self.valid_max) {
            if a >= b {
                return invalid(
                    "valid_min",
                    format!("{a} is not below the largest valid output {b}"),
                );
            }
        }
        if let Some(b) = self.settle_band {
            check_positive("settle_band", b)?;
            check_range("settle_band", b, 0.0, 1e15, "")?;
        }
        check_range("first_window_s", self.first_window_s, 1e-6, 1e9, "s")?;
        if let Some(b) = self.block_s {
            check_range("block_s", b, 1e-9, 1e9, "s")?;
        }
        check_range(
            "max_temperature_span_c",
            self.max_temperature_span_c,
            0.0,
            1e3,
            "°C",
        )
    }
}

/// The turn-on found in a record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurnOn {
    /// Row of the first valid sample.
    pub row: usize,
    /// Its time from power-on (s).
    pub first_valid_s: f64,
    /// The turn-on time (s from power-on) and its u.
    pub time_s: f64,
    /// `u` of the turn-on time (s).
    pub u_s: f64,
    /// The first row at or after power-on was already valid.
    pub valid_at_start: bool,
}

/// A warm-up reduced.
#[derive(Debug, Clone)]
pub struct WarmupResult {
    /// The turn-on.
    pub turn_on: TurnOn,
    /// The shape fitted.
    pub shape: Shape,
    /// Why that shape.
    pub shape_reason: String,
    /// The fit on block means.
    pub fit: Fit,
    /// The blocks.
    pub blocks: Blocks,
    /// Long-run variance of one sample and its EDF.
    pub var_lr: (f64, f64),
    /// The curve's parameters and the derived quantities.
    pub coefficients: Estimates,
    /// Settling band used (output units).
    pub settle_band: f64,
    /// Valid samples after turn-on, and those left out.
    pub samples: (usize, usize),
    /// Temperature mean, min and max after turn-on (°C), if recorded.
    pub temperature_c: Option<(f64, f64, f64)>,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// The options.
    pub options: WarmupOptions,
    /// The sampling rate (Hz).
    pub rate_hz: f64,
}

/// Find the turn-on (module docs); refused when no row is valid.
pub fn turn_on(rec: &Record, o: &WarmupOptions) -> Result<TurnOn> {
    let dt = 1.0 / rec.rate_hz;
    let first = rec
        .time_s
        .iter()
        .position(|t| *t >= o.power_on_s)
        .ok_or_else(|| {
            Error::Unsupported(format!(
                "power_on_s {} s is after the last row ({} s)",
                o.power_on_s,
                rec.time_s[rec.time_s.len() - 1]
            ))
        })?;
    let row = (first..rec.output.len())
        .find(|&k| valid(rec, o, k))
        .ok_or_else(|| {
            Error::Unsupported(format!(
                "the output is never valid after power-on ({}): no turn-on",
                validity(o, rec.status.is_some())
            ))
        })?;
    let t = rec.time_s[row] - o.power_on_s;
    // Valid from the first row after power-on: the turn-on lies anywhere
    // in [0, t]; else within the sample interval before the row.
    let step = if row == first { t } else { dt.min(t) };
    Ok(TurnOn {
        row,
        first_valid_s: t,
        time_s: t - step / 2.0,
        u_s: step / 12f64.sqrt(),
        valid_at_start: row == first,
    })
}

/// Whether row `k` is valid (module docs).
pub fn valid(rec: &Record, o: &WarmupOptions, k: usize) -> bool {
    let Some(y) = rec.output[k] else {
        return false;
    };
    o.valid_min.is_none_or(|a| y >= a)
        && o.valid_max.is_none_or(|b| y <= b)
        && rec.status.as_ref().is_none_or(|s| s[k] != 0.0)
}

/// The validity rule in words.
fn validity(o: &WarmupOptions, status: bool) -> String {
    let mut v = vec!["an output number".to_string()];
    if let Some(a) = o.valid_min {
        v.push(format!("at least {a}"));
    }
    if let Some(b) = o.valid_max {
        v.push(format!("at most {b}"));
    }
    if status {
        v.push("status not 0".into());
    }
    v.join(", ")
}

/// The reduction (module docs).
pub fn calibrate(rec: &Record, o: &WarmupOptions) -> Result<WarmupResult> {
    o.validate()?;
    let on = turn_on(rec, o)?;
    let n = rec.output.len();
    let (mut t, mut y, mut row) = (Vec::new(), Vec::new(), Vec::new());
    for k in on.row..n {
        if valid(rec, o, k) {
            t.push(rec.time_s[k] - o.power_on_s);
            y.push(rec.output[k].unwrap_or_default());
            row.push(k - on.row);
        }
    }
    if t.len() < 20 {
        return Err(Error::Unsupported(format!(
            "{} valid samples after turn-on: a warm-up curve needs at least 20",
            t.len()
        )));
    }
    let run = longest_run(&row);
    let m = block_length(&t, &y, &row, &y[run.0..run.1], rec.rate_hz, o)?;
    let blocks = Blocks::new(&t, &y, &row, m);
    let mut fits = fit::Fits::new(&blocks, &y[run.0..run.1])?;
    let var_lr = fits.noise(run)?;
    let span = t[t.len() - 1] - on.time_s;
    let (shape, fit, reason) = choose(o.curve, &mut fits, var_lr, span)?;
    let p = fit.estimates.values().clone();
    let tau = p[2];
    if span < 3.0 * tau {
        return Err(Error::Unsupported(format!(
            "the record covers {span:.1} s after turn-on and the warm-up's time constant is about {tau:.1} s: too short to see tau against the settled value; record at least 3 tau ({:.0} s) after turn-on",
            3.0 * tau
        )));
    }
    let band = settle_band(shape, p.as_slice(), o.settle_band);
    let coefficients = derive(
        shape,
        &fit.estimates,
        on.time_s,
        o.settle_band,
        o.first_window_s,
    )?;
    let mut warnings = Vec::new();
    significance(shape, &coefficients, o.curve, &mut warnings);
    let dropped = n - on.row - t.len();
    if dropped > 0 {
        warnings.push(Warning::new(
            WarningCode::MissingSamples,
            format!(
                "{dropped} rows after turn-on are not valid ({}) and were left out of the fit",
                validity(o, rec.status.is_some())
            ),
        ));
    }
    if on.valid_at_start && on.first_valid_s > 0.0 {
        warnings.push(Warning::new(
            WarningCode::ShortRecord,
            format!("the output is valid from the first row after power-on ({:.6} s): the turn-on time is known only to lie within [0, {:.6}] s; record from before power-on", on.first_valid_s, on.first_valid_s),
        ));
    }
    let settle = coefficients.value("settling_time_s").unwrap_or(0.0);
    let end = t[t.len() - 1];
    if settle > end {
        warnings.push(Warning::new(
            WarningCode::ShortRecord,
            format!("settling_time_s {settle:.1} s lies beyond the record's end ({end:.1} s): extrapolated along the fitted curve"),
        ));
    }
    if span < 5.0 * tau {
        warnings.push(Warning::new(
            WarningCode::ShortRecord,
            format!("the record covers {:.1} tau after turn-on: B_inf and tau are strongly correlated below 5 tau", span / tau),
        ));
    }
    let temperature_c = rec.temperature_c.as_ref().map(|c| {
        let c = &c[on.row..];
        let mean = c.iter().sum::<f64>() / c.len() as f64;
        let (lo, hi) = c
            .iter()
            .fold((f64::MAX, f64::MIN), |a, v| (a.0.min(*v), a.1.max(*v)));
        (mean, lo, hi)
    });
    if let Some((_, lo, hi)) = temperature_c {
        if hi - lo > o.max_temperature_span_c {
            warnings.push(Warning::new(
                WarningCode::TemperatureNotConstant,
                format!("the temperature spans {:.3} °C after turn-on (limit {} °C): the output's temperature sensitivity mixes into the warm-up curve", hi - lo, o.max_temperature_span_c),
            ));
        }
    }
    Ok(WarmupResult {
        turn_on: on,
        shape,
        shape_reason: reason,
        fit,
        blocks,
        var_lr,
        coefficients,
        settle_band: band,
        samples: (t.len(), dropped),
        temperature_c,
        warnings,
        options: o.clone(),
        rate_hz: rec.rate_hz,
    })
}

/// The sample range of the longest run of consecutive valid rows.
fn longest_run(row: &[usize]) -> (usize, usize) {
    let (mut best, mut start) = ((0, 0), 0);
    for k in 1..=row.len() {
        if k == row.len() || row[k] != row[k - 1] + 1 {
            if k - start > best.1 - best.0 {
                best = (start, k);
            }
            start = k;
        }
    }
    best
}

/// The block length `M` (rows; module docs): at most τ/10 (τ from a
/// first one-exponential fit on about 200 blocks) and at most a 400th of
/// the record, at least one row and at least a 5000th of the record.
fn block_length(
    t: &[f64],
    y: &[f64],
    row: &[usize],
    run: &[f64],
    rate_hz: f64,
    o: &WarmupOptions,
) -> Result<usize> {
    let most = fit::noise_scale(run.len())?;
    let last = row[row.len() - 1];
    match o.block_s {
        Some(b) => {
            let m = (b * rate_hz).round().max(1.0) as usize;
            if m > most {
                return crate::options::invalid(
                    "block_s",
                    format!(
                        "{b} s is {m} rows: at most {most} (a twentieth of the longest valid run)"
                    ),
                );
            }
            Ok(m)
        }
        None => {
            let first = Blocks::new(t, y, row, (last / 200).max(1));
            let (v1, _) = fit::long_run_variance(run, 1).unwrap_or((1.0, 1.0));
            let tau = fit::fit_shape(Shape::Exp1, &first, v1.max(f64::MIN_POSITIVE), 1e9, None)
                .map(|f| f.estimates.values()[2])
                .unwrap_or_else(|_| fit::start(&first).2);
            let by_tau = (tau * rate_hz / 10.0).floor().max(1.0) as usize;
            Ok(by_tau.min(last / 400).max(last / 5000).max(1))
        }
    }
}

/// The shape by the lack-of-fit rule, or the one asked for. The rule
/// takes the first shape (simplest first) that passes the lack-of-fit
/// test and whose τ is at most a third of the record after turn-on
/// (`span_s`; a longer τ cannot be told from a drift); when none passes,
/// the acceptable fit with the highest p, its u scaled by its residual
/// scatter.
fn choose(
    choice: CurveChoice,
    fits: &mut fit::Fits,
    var_lr: (f64, f64),
    span_s: f64,
) -> Result<(Shape, Fit, String)> {
    let p_of = |f: &Fit| f.chi2_p_value.unwrap_or(1.0);
    let first = fits.get(Shape::Exp1, var_lr);
    let mut fit_one = |s: Shape| fits.get(s, var_lr);
    if let Some(s) = choice.shape() {
        let f = fit_one(s)?;
        let r = format!("{}, as asked (lack-of-fit p = {:.3})", s.name(), p_of(&f));
        return Ok((s, f, r));
    }
    let mut tried: Vec<String> = Vec::new();
    let mut best: Option<(Shape, Fit)> = None;
    for s in Shape::ALL {
        match fit_one(s) {
            Ok(f) => {
                let p = p_of(&f);
                let tau = f.estimates.values()[2];
                if 3.0 * tau > span_s {
                    tried.push(format!(
                        "{} tau = {tau:.1} s, over a third of the record",
                        s.name()
                    ));
                    continue;
                }
                if p >= LACK_OF_FIT_ALPHA {
                    let why = if tried.is_empty() {
                        String::new()
                    } else {
                        format!("; before it {}", tried.join(", "))
                    };
                    let r = format!("{}: the first shape that passes the lack-of-fit test (F test p = {p:.3} >= 0.05){why}", s.name());
                    return Ok((s, f, r));
                }
                tried.push(format!("{} p = {p:.2e}", s.name()));
                if best.as_ref().is_none_or(|(_, b)| p_of(b) <= p) {
                    best = Some((s, f));
                }
            }
            Err(e) => tried.push(format!("{} did not fit ({e})", s.name())),
        }
    }
    let (s, f) = match best {
        Some(x) => x,
        None => match first {
            // Every fit has tau beyond a third of the record: the
            // one-exponential fit, refused by the record's length.
            Ok(f) => (Shape::Exp1, f),
            Err(e) => {
                // One short line: the simplest curve's reason, clipped.
                return Err(Error::Unsupported(format!(
                    "no warm-up curve fits ({} tried); the one-exponential: {}",
                    Shape::ALL.len(),
                    incal_io::clip_to(&e.to_string(), 240)
                )));
            }
        },
    };
    let r = format!(
        "{}: no shape passes the lack-of-fit test ({}); the best is kept and u is scaled by its residual scatter",
        s.name(),
        tried.join(", ")
    );
    Ok((s, f, r))
}

/// The settling band: as given (output units), else 1 % of the
/// transient at power-on at parameters `p`.
pub fn settle_band(shape: Shape, p: &[f64], given: Option<f64>) -> f64 {
    given.unwrap_or_else(|| 0.01 * fit::transient(shape, p, 0.0).abs())
}

/// The settling time (s from power-on) of the transient at parameters
/// `p` for `band`, never before `t_on` (module docs).
pub fn settling_time(shape: Shape, p: &[f64], band: f64, t_on: f64) -> f64 {
    let tau = if shape.two() { p[2].max(p[4]) } else { p[2] };
    let horizon = t_on + 60.0 * tau;
    let n = 4000;
    let h = (horizon - t_on) / n as f64;
    let over = |t: f64| fit::transient(shape, p, t).abs() - band;
    let Some(k) = (0..=n).rev().find(|&k| over(t_on + k as f64 * h) > 0.0) else {
        return t_on;
    };
    if k == n {
        return horizon;
    }
    let (mut a, mut b) = (t_on + k as f64 * h, t_on + (k + 1) as f64 * h);
    for _ in 0..80 {
        let c = 0.5 * (a + b);
        if over(c) > 0.0 {
            a = c;
        } else {
            b = c;
        }
    }
    0.5 * (a + b)
}

/// The transient's mean over `[t_on, t_on + w]`.
pub fn warmup_drift(shape: Shape, p: &[f64], t_on: f64, w: f64) -> f64 {
    let term = |a: f64, tau: f64| a * tau * ((-t_on / tau).exp() - (-(t_on + w) / tau).exp()) / w;
    let mut v = term(p[1], p[2]);
    if shape.two() {
        v += term(p[3], p[4]);
    }
    v
}

/// The curve's parameters with `settling_time_s` and `warmup_drift`
/// appended (u by the Jacobian, module docs); the default band, 1 % of
/// the transient at power-on, moves with the parameters.
fn derive(
    shape: Shape,
    e: &Estimates,
    t_on: f64,
    settle_band: Option<f64>,
    w: f64,
) -> Result<Estimates> {
    let g = move |v: &DVector<f64>| {
        let p = v.as_slice();
        let band = self::settle_band(shape, p, settle_band);
        DVector::from_vec(vec![
            settling_time(shape, p, band, t_on),
            warmup_drift(shape, p, t_on, w),
        ])
    };
    let steps: Vec<f64> = (0..e.len())
        .map(|k| 1e-6 * e.values()[k].abs().max(e.u_at(k)).max(1e-12))
        .collect();
    let j = numeric_jacobian(&g, e.values(), &steps);
    e.augment(
        vec!["settling_time_s".into(), "warmup_drift".into()],
        g,
        |_| j.clone(),
    )
}

/// Flag the curve's terms within their U95 of zero when the shape was
/// asked for (the rule includes a term only when the data need it).
fn significance(shape: Shape, e: &Estimates, choice: CurveChoice, out: &mut Vec<Warning>) {
    let k = e.coverage_factor(0.95);
    for name in ["amplitude", "amplitude_2", "drift_per_s"] {
        if let Some((v, u)) = e.get(name) {
            if v.abs() <= k * u {
                let how = if choice == CurveChoice::Auto {
                    "chosen by the rule".to_string()
                } else {
                    format!("the shape {} was asked for", shape.name())
                };
                out.push(Warning::new(
                    WarningCode::NotSignificant,
                    format!("{name} = {v:.4e} is within its U95 ({:.2e}) of zero ({how}): the data do not distinguish it from zero", k * u),
                ));
            }
        }
    }
}

/// Turn-on and warm-up as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Warmup;

impl crate::procedures::Procedure for Warmup {
    const ID: crate::document::Procedure = crate::document::Procedure::Warmup;
    type Options = WarmupOptions;
    type Input = Record;

    fn example() -> WarmupOptions {
        WarmupOptions::default()
    }

    fn validate(o: &WarmupOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(rows: &mut incal_io::Reader<R>, o: &WarmupOptions) -> Result<Record> {
        input::read(rows, o.rate_hz, &o.column)
    }

    fn reduce(
        rec: &Record,
        o: &WarmupOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(rec, o)?.document()
    }

    fn synthesis(
        rec: &Record,
        o: &WarmupOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
