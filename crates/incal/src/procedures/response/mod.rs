//! Dynamic response by stepped sine (dwells): gain, phase, bandwidth and
//! delay of a gyro or accelerometer on a rate table in its angular
//! vibration mode or on a shaker (IEEE Std 1431-2004 §12.15, IEEE Std
//! 952-2020, IEEE Std 1293-2018; ISO 16063-21 for comparison with a
//! reference accelerometer; docs/src/response.md).
//!
//! # Model
//! At each dwell of frequency `f` the reference `r(t)` and the output
//! `y(t)` are fitted by sines at `f` ([`sine`], IEEE Std 1057-2017 three
//! parameter fit, with harmonics and drift): amplitudes `R_r, R_y`, phases
//! `φ_r, φ_y`. The dwell's
//!
//! * gain `G = R_y/R_r` (output per reference unit), with
//!   `u²(G)/G² = u²(R_y)/R_y² + u²(R_r)/R_r² + u_ref²` (`u_ref` the
//!   reference's relative amplitude uncertainty, type B, one draw per
//!   dwell);
//! * phase `Δφ = φ_y − φ_r`, with `u²(Δφ) = u²(φ_y) + u²(φ_r) + u²_ref,φ`.
//!
//! A low-pass model with a pure delay ([`model`]) is fitted to all
//! dwells' gain and phase; its order is chosen by the one statistics rule
//! (the first order unless its fit fails the 5 % lack-of-fit test); the
//! half-power bandwidth, phase frequency and latency follow with u
//! through the Jacobian. A model-free bandwidth interpolates the
//! normalised gain in dB against `ln f` between the two dwells that
//! bracket −3.01 dB.
//!
//! # Uncertainty
//! The sine fits take their variance from their residuals (white noise
//! within a dwell; the drift term absorbs a slow wander). Gain and phase
//! are taken as uncorrelated (exact for whole cycles and equal variances
//! of the cosine and sine coefficients). The reference's type-B terms are
//! independent between dwells, which is conservative for the bandwidth
//! (a common sensitivity error scales `K` only).

pub mod broadband;
pub mod document;
pub mod find;
pub mod fit;
pub mod input;
pub mod model;
mod montecarlo;
pub mod plan;
pub mod sim;
pub mod sine;
pub mod step;

use std::f64::consts::PI;

use crate::error::{Error, Result};
use crate::warning::{Warning, WarningCode};
use fit::{ModelOptions, ModelPart};
use input::Dwell;
use model::Point;
use sine::{ChannelFit, SineDesign};

/// Which model order (`auto`: the one statistics rule).
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
#[serde(rename_all = "lowercase")]
pub enum OrderChoice {
    /// First order unless it fails the lack-of-fit test, then second.
    #[default]
    Auto,
    /// First-order low-pass with delay.
    First,
    /// Second-order low-pass with delay.
    Second,
}

impl From<model::Order> for OrderChoice {
    /// A fixed order.
    fn from(o: model::Order) -> OrderChoice {
        match o {
            model::Order::First => OrderChoice::First,
            model::Order::Second => OrderChoice::Second,
        }
    }
}

/// The slow terms fitted beside the sines in each dwell.
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
#[serde(rename_all = "lowercase")]
pub enum Drift {
    /// An offset and a linear drift.
    #[default]
    Linear,
    /// An offset only.
    None,
}

/// Which bandwidth is the headline `bandwidth_hz`.
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
#[serde(rename_all = "lowercase")]
pub enum BandwidthMethod {
    /// The fitted model's half-power frequency (the interpolated one is
    /// given beside it as `bandwidth_interp_hz` when the dwells bracket it).
    #[default]
    Model,
    /// Interpolated between the dwells bracketing −3.01 dB; refused when
    /// no two dwells bracket it.
    Interpolated,
}

/// Options of the stepped-sine reduction. In the document: every key
/// (the model's flattened beside the dwells').
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ResponseOptions {
    /// Sampling rate (Hz) when the file has no `time_s` column.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Harmonic order fitted (1: the fundamental only; default 3). THD is
    /// reported from 2 on.
    #[serde(default = "three")]
    pub harmonics: usize,
    /// The slow terms of each dwell (default linear: offset and drift).
    #[serde(default)]
    pub drift: Drift,
    /// Seconds left out at the start of every dwell (the transient).
    #[serde(default)]
    pub settle_s: f64,
    /// Estimate each dwell's frequency from the reference (IEEE Std 1057
    /// four-parameter fit, `freq_hz` its start) instead of taking
    /// `freq_hz` as exact. Always so when the file has no `freq_hz`.
    #[serde(default)]
    pub estimate_frequency: bool,
    /// Window (s) of the dwell search when the file has no `freq_hz`
    /// (default 1): dwells must last about three windows and differ by
    /// more than a quarter of `1/dwell_window_s` Hz.
    #[serde(default = "one")]
    pub dwell_window_s: f64,
    /// The model, the scale, the reference's type-B terms.
    #[serde(flatten)]
    pub model: ModelOptions,
}

fn three() -> usize {
    3
}

fn one() -> f64 {
    1.0
}

impl Default for ResponseOptions {
    /// 3 harmonics, a linear drift, no settle time, the model's defaults.
    fn default() -> Self {
        Self {
            rate_hz: None,
            harmonics: 3,
            drift: Drift::Linear,
            settle_s: 0.0,
            estimate_frequency: false,
            dwell_window_s: 1.0,
            model: ModelOptions::default(),
        }
    }
}

impl ResponseOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_range, invalid};
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-3, 1e7, "Hz")?;
        }
        if !(1..=10).contains(&self.harmonics) {
            return invalid(
                "harmonics",
                format!("a whole number from 1 to 10, got {}", self.harmonics),
            );
        }
        check_range("settle_s", self.settle_s, 0.0, 1e6, "s")?;
        check_range("dwell_window_s", self.dwell_window_s, 1e-3, 1e5, "s")?;
        self.model.validate()
    }
}

/// The reference's type-B terms: `u_reference_pct` (0..100 %) and
/// `u_reference_phase_deg` (0..180 deg).
pub fn check_reference_u(pct: f64, phase_deg: f64) -> Result<()> {
    crate::options::check_range("u_reference_pct", pct, 0.0, 100.0, "%")?;
    crate::options::check_range("u_reference_phase_deg", phase_deg, 0.0, 180.0, "deg")
}

/// `(u(G), u(Δφ))` of a dwell's gain `gain` from both channels'
/// `(R, u(R), u(φ))` (output first) and the reference's type-B terms
/// (module docs): `u²(G)/G² = Σ u²(R)/R² + (pct/100)²`,
/// `u²(Δφ) = Σ u²(φ) + phase²`, never 0, the phase's at most π.
pub fn dwell_u(gain: f64, ch: [(f64, f64, f64); 2], pct: f64, phase_deg: f64) -> (f64, f64) {
    let rel: f64 = ch
        .iter()
        .map(|(r, u, _)| (u / r.max(f64::MIN_POSITIVE)).powi(2))
        .sum::<f64>()
        + (pct / 100.0).powi(2);
    let ph: f64 = ch.iter().map(|c| c.2 * c.2).sum::<f64>() + phase_deg.to_radians().powi(2);
    (
        (gain * rel.sqrt()).max(f64::MIN_POSITIVE),
        ph.sqrt().clamp(f64::MIN_POSITIVE, PI),
    )
}

/// One dwell reduced.
#[derive(Debug, Clone, PartialEq)]
pub struct DwellResult {
    /// Dwell frequency (Hz): as given, or estimated.
    pub freq_hz: f64,
    /// Standard uncertainty of an estimated frequency (Hz), `None` when
    /// `freq_hz` was given and taken as exact.
    pub u_freq_hz: Option<f64>,
    /// Samples fitted (after the settle time).
    pub samples: usize,
    /// Whole and part cycles fitted.
    pub cycles: f64,
    /// Sampling rate of the dwell (Hz).
    pub rate_hz: f64,
    /// The reference's fundamental.
    pub reference: ChannelFit,
    /// The output's fundamental.
    pub output: ChannelFit,
    /// Gain and phase for the model fit (type B included).
    pub point: Point,
    /// File lines of the dwell.
    pub lines: (usize, usize),
}

/// Everything a stepped-sine reduction produces.
#[derive(Debug, Clone)]
pub struct ResponseResult {
    /// The dwells in file order.
    pub dwells: Vec<DwellResult>,
    /// The model, its coefficients, bandwidths and flatness.
    pub part: ModelPart,
    /// Warnings (the model's and the dwells').
    pub warnings: Vec<Warning>,
    /// The options used.
    pub options: ResponseOptions,
}

/// Fit one dwell's sines; refuse a dwell the fit cannot use, naming it.
fn reduce_dwell(k: usize, d: &Dwell, o: &ResponseOptions) -> Result<DwellResult> {
    let name = || d.label(k);
    let start = d.time_s.first().copied().unwrap_or(0.0) + o.settle_s;
    let skip = d.time_s.partition_point(|t| *t < start);
    let t = &d.time_s[skip..];
    let n = t.len();
    let span = match (t.first(), t.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    if n < 8 || span <= 0.0 {
        return Err(Error::Unsupported(format!(
            "{}: {n} samples over {span} s after the settle time: too few to fit a sine",
            name()
        )));
    }
    let rate = (n - 1) as f64 / span;
    if d.freq_hz >= rate / 2.0 {
        return Err(Error::Unsupported(format!(
            "{}: the frequency is at or above the Nyquist frequency ({:.6} Hz of a {:.6} Hz sampling)",
            name(),
            rate / 2.0,
            rate
        )));
    }
    let cycles = d.freq_hz * n as f64 / rate;
    if cycles < 2.0 {
        return Err(Error::Unsupported(format!(
            "{}: {cycles:.3} cycles fitted; a dwell needs at least 2",
            name()
        )));
    }
    let drift = o.drift == Drift::Linear;
    let (freq_hz, u_freq_hz) = if o.estimate_frequency || d.found {
        let t_ref = if d.time_ref_s.len() == d.time_s.len() {
            &d.time_ref_s[skip..]
        } else {
            t
        };
        // The start: the reference's spectral peak within 10 % (and two
        // bins) of the nominal frequency, which may be off by many bins.
        let reach = 0.1 * d.freq_hz + 2.0 * rate / n as f64;
        let start = find::peak_freq_hz(
            &d.reference[skip..],
            rate,
            d.freq_hz - reach,
            d.freq_hz + reach,
        )
        .unwrap_or(d.freq_hz);
        let (f, u) = sine::fit_frequency(
            t_ref,
            start,
            o.harmonics,
            drift,
            rate / 2.0,
            &d.reference[skip..],
        )
        .map_err(|e| Error::Unsupported(format!("{}: {e}", name())))?;
        (f, Some(u))
    } else {
        (d.freq_hz, None)
    };
    let design = SineDesign::new(t, t[0], freq_hz, o.harmonics, drift, rate / 2.0)?;
    let output = design.fit(&d.output[skip..])?;
    // A reference on its own clock: fitted at its own stamps, one origin.
    let reference = if d.time_ref_s.len() == d.time_s.len() {
        SineDesign::new(
            &d.time_ref_s[skip..],
            t[0],
            freq_hz,
            o.harmonics,
            drift,
            rate / 2.0,
        )?
        .fit(&d.reference[skip..])?
    } else {
        design.fit(&d.reference[skip..])?
    };
    // Still within its noise, or within rounding of its own offset.
    let floor = (10.0 * reference.u_amplitude).max(1e-9 * reference.offset.abs());
    if reference.amplitude.is_nan() || reference.amplitude <= floor {
        return Err(Error::Unsupported(format!(
            "{}: the reference does not move (amplitude {:.3e}, u {:.3e}): no gain or phase can be referred to it",
            name(),
            reference.amplitude,
            reference.u_amplitude
        )));
    }
    let gain = output.amplitude / reference.amplitude;
    let (u_gain, u_phase) = dwell_u(
        gain,
        [
            (output.amplitude, output.u_amplitude, output.u_phase_rad),
            (
                reference.amplitude,
                reference.u_amplitude,
                reference.u_phase_rad,
            ),
        ],
        o.model.u_reference_pct,
        o.model.u_reference_phase_deg,
    );
    Ok(DwellResult {
        freq_hz,
        u_freq_hz,
        samples: n,
        cycles: freq_hz * n as f64 / rate,
        rate_hz: rate,
        reference,
        output,
        point: Point {
            freq_hz,
            gain,
            u_gain,
            phase_rad: sine::wrap_pi(output.phase_rad - reference.phase_rad),
            u_phase_rad: u_phase,
        },
        lines: (d.first_line, d.last_line),
    })
}

/// The reduction (module docs).
pub fn calibrate(dwells: &[Dwell], o: &ResponseOptions) -> Result<ResponseResult> {
    o.validate()?;
    if dwells.is_empty() {
        return Err(Error::TooFew {
            what: "dwells".into(),
            needed: 2,
            got: 0,
        });
    }
    let reduced: Vec<DwellResult> = dwells
        .iter()
        .enumerate()
        .map(|(k, d)| reduce_dwell(k, d, o))
        .collect::<Result<_>>()?;
    let mut amplitudes: Vec<f64> = reduced.iter().map(|d| d.reference.amplitude).collect();
    amplitudes.sort_by(f64::total_cmp);
    let median = amplitudes[amplitudes.len() / 2];
    if let Some(k) = reduced
        .iter()
        .position(|d| d.reference.amplitude < 1e-6 * median)
    {
        return Err(Error::Unsupported(format!(
            "{}: the reference does not move (amplitude {:.3e}, a millionth of the other dwells' {median:.3e}): no gain or phase can be referred to it",
            dwells[k].label(k),
            reduced[k].reference.amplitude
        )));
    }
    let points: Vec<Point> = reduced.iter().map(|d| d.point).collect();
    let dof = reduced
        .iter()
        .map(|d| d.reference.dof.min(d.output.dof) as f64)
        .fold(f64::INFINITY, f64::min);
    let part = ModelPart::fit(&points, &o.model, dof, None)?;
    let mut warnings = part.warnings.clone();
    for (k, d) in reduced.iter().enumerate() {
        if d.output.amplitude < 3.0 * d.output.u_amplitude {
            warnings.push(Warning::new(
                WarningCode::WeakSignal,
                format!("dwell {} ({} Hz): the output amplitude is within 3 u of zero: its gain is biased up and its phase is noise", k + 1, d.freq_hz),
            ));
        }
    }
    Ok(ResponseResult {
        dwells: reduced,
        part,
        warnings,
        options: o.clone(),
    })
}

/// Stepped-sine dynamic response as one [`super::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ResponseSine;

impl super::Procedure for ResponseSine {
    const ID: crate::document::Procedure = crate::document::Procedure::ResponseSine;
    type Options = ResponseOptions;
    type Input = input::Recorded;

    fn example() -> ResponseOptions {
        ResponseOptions::default()
    }

    fn validate(o: &ResponseOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &ResponseOptions,
    ) -> Result<input::Recorded> {
        input::read(rows, o.rate_hz, o.dwell_window_s)
    }

    fn reduce(
        rec: &input::Recorded,
        o: &ResponseOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let mut r = calibrate(&rec.dwells, o)?;
        r.warnings.extend(rec.warnings.iter().cloned());
        r.document()
    }

    /// Synthetic dwells from each dwell's fitted sines (this folder's
    /// `montecarlo.rs`).
    fn synthesis(
        rec: &input::Recorded,
        o: &ResponseOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<input::Recorded>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
