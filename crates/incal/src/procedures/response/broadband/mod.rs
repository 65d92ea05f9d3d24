//! Dynamic response from a broadband excitation (random, chirp or
//! multisine): the H1 estimator by Welch averaging, the coherence, the
//! random errors of gain and phase, and the low-pass model with delay
//! fitted over the coherent frequencies (docs/src/response.md).
//!
//! # Model
//! With the spectra of [`welch`], at each bin `f_k > 0`:
//!
//! * `H1 = P_xy/P_xx` (unbiased by output noise; biased low by
//!   `1/(1 + P_nn/P_xx)` by noise on the reference);
//! * coherence `γ² = |P_xy|²/(P_xx P_yy)`;
//! * the normalised random error of `|H1|` and the standard deviation of
//!   its phase (rad), both `ε = √(1 − γ²)/(|γ| √(2 n_d))` with `n_d` the
//!   independent averages (Bendat J. S., Piersol A. G., *Random Data:
//!   Analysis and Measurement Procedures*, 4th ed., Wiley 2010, §9.2.4,
//!   Table 9.6), plus the reference's type-B terms as for a dwell.
//!
//! A reference on its own clock, `δ` late ([`input`]), is put back into
//! each bin's phase, `H = H_meas e^{j2πfδ}`. A rectangular window (for a
//! multisine whose period divides the segment) takes no smoothing term.
//!
//! Bins with `γ² < min_coherence` are flagged in the table and not fitted
//! (their errors are no longer small and `γ²` is biased up). The model
//! ([`super::fit::ModelPart`]) is fitted to the coherent bins within
//! `f_min_hz..f_max_hz`. Neighbouring bins of a Hann window are not
//! independent: the model's covariance is multiplied by the window's
//! equivalent noise bandwidth in bins (1.5), the number of bins one
//! independent estimate spans.

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;
pub use crate::spectral::welch;

use crate::error::{Error, Result};
use crate::warning::{Warning, WarningCode};

use nalgebra::{DMatrix, DVector};
use realfft::num_complex::Complex64;

use super::fit::{self, ModelOptions, ModelPart};
use super::model::{self, Point};
use input::Record;
use plan::{coherence, segment};
use welch::{Spectra, Welch, Window};

/// Options of the broadband reduction. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BroadbandOptions {
    /// Sampling rate (Hz) when the file has no `time_s` column.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Samples per Welch segment (default 1024): the resolution is
    /// `rate_hz/segment_samples`.
    #[serde(default = "segment")]
    pub segment_samples: usize,
    /// Overlap of the segments (samples; default half a segment).
    #[serde(default)]
    pub overlap_samples: Option<usize>,
    /// Bins below this coherence γ² are not fitted (default 0.9).
    #[serde(default = "coherence")]
    pub min_coherence: f64,
    /// Lowest frequency fitted (Hz; default the first bin above 0).
    #[serde(default)]
    pub f_min_hz: Option<f64>,
    /// Highest frequency fitted (Hz; default the last bin below Nyquist).
    #[serde(default)]
    pub f_max_hz: Option<f64>,
    /// Align the output to the reference by the latency before the
    /// spectra (default `latency`; `none`: the plain H1, as
    /// `scipy.signal.csd`/`welch` give it).
    #[serde(default)]
    pub align: Align,
    /// The window of each segment (default hann; rectangular for a
    /// multisine whose period divides the segment).
    #[serde(default)]
    pub window: Window,
    /// The model, the scale, the reference's type-B terms.
    #[serde(flatten)]
    pub model: ModelOptions,
}

/// Whether the output is aligned to the reference before the spectra.
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
pub enum Align {
    /// Shifted by the whole samples of a first pass's latency (module docs).
    #[default]
    Latency,
    /// Not shifted.
    None,
}

impl Default for BroadbandOptions {
    fn default() -> Self {
        Self {
            rate_hz: None,
            segment_samples: segment(),
            overlap_samples: None,
            min_coherence: coherence(),
            f_min_hz: None,
            f_max_hz: None,
            align: Align::Latency,
            window: Window::Hann,
            model: ModelOptions::default(),
        }
    }
}

impl BroadbandOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, check_range, invalid};
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-3, 1e7, "Hz")?;
        }
        if !(8..=1 << 24).contains(&self.segment_samples) {
            return invalid(
                "segment_samples",
                format!("from 8 to 16777216, got {}", self.segment_samples),
            );
        }
        if let Some(v) = self.overlap_samples {
            if v >= self.segment_samples {
                return invalid("overlap_samples", "must be below `segment_samples`");
            }
        }
        check_range("min_coherence", self.min_coherence, 0.0, 1.0, "")?;
        for (k, v) in [("f_min_hz", self.f_min_hz), ("f_max_hz", self.f_max_hz)] {
            if let Some(f) = v {
                check_positive(k, f)?;
            }
        }
        if let (Some(a), Some(b)) = (self.f_min_hz, self.f_max_hz) {
            if b <= a {
                return invalid("f_max_hz", "must be above `f_min_hz`");
            }
        }
        self.model.validate()
    }

    /// The overlap used (samples).
    pub fn overlap(&self) -> usize {
        self.overlap_samples.unwrap_or(self.segment_samples / 2)
    }
}

/// One frequency bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bin {
    /// Coherence γ².
    pub coherence: f64,
    /// `|H1|`, `∠H1` and their u.
    pub point: Point,
    /// Whether the model was fitted to it.
    pub fitted: bool,
}

/// Everything a broadband reduction produces.
#[derive(Debug, Clone)]
pub struct BroadbandResult {
    /// The spectra.
    pub spectra: Spectra,
    /// Bins `k = 1 … ⌊L/2⌋` (the DC bin left out).
    pub bins: Vec<Bin>,
    /// The model part.
    pub part: ModelPart,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// Where the model's covariance came from (a decision).
    pub covariance: String,
    /// The output's shift against the reference (samples; `align`).
    pub shift_samples: isize,
    /// The options used.
    pub options: BroadbandOptions,
}

impl Window {
    /// The model's smoothing by the window: the Hann window's kernel on a
    /// random excitation's spectrum (module docs); none without a window
    /// (a periodic excitation on the bins leaks nothing).
    fn smoothing(self, s: model::Smoothing) -> Option<model::Smoothing> {
        (self == Window::Hann).then_some(s)
    }
}

/// Groups of the delete-a-group jackknife (module docs).
pub const JACKKNIFE_GROUPS: usize = 20;

/// The bins of spectra `(P_xx, P_yy, P_xy)` at `freq_hz` with their u for
/// `n_d` independent averages (module docs); the fitted flag from the band
/// and the coherence.
fn bins(
    freq_hz: &[f64],
    (pxx, pyy, pxy): (&[f64], &[f64], &[Complex64]),
    n_d: f64,
    shift_s: f64,
    o: &BroadbandOptions,
) -> Vec<Bin> {
    let nyquist = *freq_hz.last().unwrap_or(&0.0);
    let lo = o.f_min_hz.unwrap_or(0.0);
    let hi = o.f_max_hz.unwrap_or(nyquist);
    (1..freq_hz.len())
        .map(|k| {
            let f = freq_hz[k];
            let h =
                pxy[k] / pxx[k] * Complex64::from_polar(1.0, -std::f64::consts::TAU * f * shift_s);
            let g2 = (pxy[k].norm_sqr() / (pxx[k] * pyy[k])).clamp(0.0, 1.0);
            let eps = ((1.0 - g2).max(0.0) / (2.0 * n_d * g2.max(f64::MIN_POSITIVE))).sqrt();
            let (u_gain, u_phase) = super::dwell_u(
                h.norm(),
                [(1.0, eps, eps), (1.0, 0.0, 0.0)],
                o.model.u_reference_pct,
                o.model.u_reference_phase_deg,
            );
            let usable = h.norm().is_finite() && h.norm() > 0.0 && g2.is_finite();
            Bin {
                coherence: if g2.is_finite() { g2 } else { 0.0 },
                point: Point {
                    freq_hz: f,
                    gain: if usable { h.norm() } else { 0.0 },
                    u_gain,
                    phase_rad: if usable { h.arg() } else { 0.0 },
                    u_phase_rad: u_phase,
                },
                fitted: usable
                    && g2 >= o.min_coherence
                    && f >= lo
                    && f <= hi
                    && (k + 1 < freq_hz.len() || freq_hz.len() < 3),
            }
        })
        .collect()
}

/// The delete-a-group jackknife of the model (module docs): the model
/// refitted to the spectra without each group of segments, on the same
/// bins, from the full fit's estimate. Its covariance
/// `(G−1)/G Σ (θ_g − θ̄)(θ_g − θ̄)ᵀ` with `G − 1` degrees of freedom, and
/// the jackknife variance of the model-free bandwidth when every group has
/// one; `None` when a refit fails.
fn jackknife(
    w: &Welch,
    smoothing: model::Smoothing,
    full: &[Bin],
    part: &ModelPart,
    o: &BroadbandOptions,
) -> Option<(DMatrix<f64>, f64, Option<f64>)> {
    let g = w.groups.len();
    if g < 4 {
        return None;
    }
    let x0 = part.model.fit.estimates.values().as_slice().to_vec();
    let order = part.model.order;
    let mut thetas: Vec<DVector<f64>> = Vec::with_capacity(g);
    let mut interp: Vec<f64> = Vec::with_capacity(g);
    for k in 0..g {
        let (xx, yy, xy) = w.leave_out(k);
        let b = bins(
            &w.spectra.freq_hz,
            (&xx, &yy, &xy),
            w.spectra.effective,
            smoothing.shift_s,
            o,
        );
        let points: Vec<Point> = b
            .iter()
            .zip(full)
            .filter(|(_, f)| f.fitted)
            .map(|(b, _)| b.point)
            .collect();
        let m = model::fit_model(
            order,
            &points,
            std::slice::from_ref(&x0),
            f64::INFINITY,
            o.window.smoothing(smoothing),
        )
        .ok()?;
        thetas.push(m.fit.estimates.values().clone());
        if let Ok((f, _)) = fit::interpolated_bandwidth(&fit::levels_db(&points, part.scale.0), 0.0)
        {
            interp.push(f);
        }
    }
    let n = g as f64;
    let mean = thetas.iter().fold(DVector::zeros(x0.len()), |a, t| a + t) / n;
    let mut cov = DMatrix::zeros(x0.len(), x0.len());
    for t in &thetas {
        let d = t - &mean;
        cov += &d * d.transpose();
    }
    cov *= (n - 1.0) / n;
    let var_interp = (interp.len() == g).then(|| {
        let m = interp.iter().sum::<f64>() / n;
        (n - 1.0) / n * interp.iter().map(|f| (f - m).powi(2)).sum::<f64>()
    });
    Some((cov, n - 1.0, var_interp))
}

/// The reduction (module docs): a first pass, then, with `align:
/// latency`, a second with the output shifted by the first pass's latency
/// in whole samples (at most a quarter segment).
pub fn calibrate(rec: &Record, o: &BroadbandOptions) -> Result<BroadbandResult> {
    o.validate()?;
    // The first pass gives the latency only: its jackknife (which moves
    // no estimate) runs when it is the result.
    let first = reduce_shifted(rec, o, 0, o.align == Align::None)?;
    if o.align == Align::None {
        return Ok(first);
    }
    let latency = first.part.coefficients.value("latency_s").unwrap_or(0.0);
    let limit = (o.segment_samples / 4) as f64;
    // The data's misalignment: the latency plus the reference clock's offset.
    let d = ((latency + rec.reference_offset_s) * rec.rate_hz)
        .round()
        .clamp(-limit, limit) as isize;
    reduce_shifted(rec, o, d, true)
}

/// One pass with the output shifted by `d` samples (`y'_n = y_{n+d}`),
/// the shift put back into each bin's phase; the model's covariance by the
/// jackknife when `jackknifed`.
fn reduce_shifted(
    rec: &Record,
    o: &BroadbandOptions,
    d: isize,
    jackknifed: bool,
) -> Result<BroadbandResult> {
    let n = rec.reference.len().min(rec.output.len());
    let a = d.unsigned_abs().min(n);
    let (x, y) = if d >= 0 {
        (&rec.reference[..n - a], &rec.output[a..n])
    } else {
        (&rec.reference[a..n], &rec.output[..n - a])
    };
    // The output shifted by d samples against a reference whose samples
    // are taken δ late: against true time, the output moves d/rate − δ.
    let shift_s = d as f64 / rec.rate_hz - rec.reference_offset_s;
    let w = welch::welch(
        x,
        y,
        rec.rate_hz,
        o.segment_samples,
        o.overlap(),
        JACKKNIFE_GROUPS,
        o.window,
    )?;
    let spectra = &w.spectra;
    if spectra.pxx.iter().skip(1).all(|p| *p <= 0.0) {
        return Err(Error::Unsupported(
            "the reference does not move: its spectrum is zero at every frequency".into(),
        ));
    }
    let bins = bins(
        &spectra.freq_hz,
        (&spectra.pxx, &spectra.pyy, &spectra.pxy),
        spectra.effective,
        shift_s,
        o,
    );
    let points: Vec<Point> = bins.iter().filter(|b| b.fitted).map(|b| b.point).collect();
    let (lo, hi) = (
        o.f_min_hz.unwrap_or(0.0),
        o.f_max_hz.unwrap_or(f64::INFINITY),
    );
    if points.len() < 3 {
        return Err(Error::Unsupported(format!(
            "{} of {} bins between {lo} and {} Hz have a coherence of at least {} (min_coherence): too few to fit a model; excite more strongly, average longer or lower min_coherence",
            points.len(),
            bins.len(),
            hi.min(*spectra.freq_hz.last().unwrap_or(&0.0)),
            o.min_coherence
        )));
    }
    // Welch estimates have about 2 n_d degrees of freedom.
    let smoothing = model::Smoothing {
        segment_s: o.segment_samples as f64 / rec.rate_hz,
        shift_s,
    };
    let mut part = ModelPart::fit(
        &points,
        &o.model,
        2.0 * spectra.effective,
        o.window.smoothing(smoothing),
    )?;
    let mut warnings = part.warnings.clone();
    let method = if !jackknifed {
        "the model fit's own covariance (a first pass, for the latency)".to_string()
    } else if let Some((cov, dof, var_interp)) = jackknife(&w, smoothing, &bins, &part, o) {
        part.set_covariance(cov, dof, var_interp)?;
        format!(
            "delete-a-group jackknife over {} groups of segments",
            w.groups.len()
        )
    } else {
        warnings.push(Warning::new(
            WarningCode::PartFailed,
            "the jackknife of the model could not run (fewer than 4 groups of segments, or a refit failed): u is the fit's own, which takes neighbouring bins as independent",
        ));
        "the model fit's own covariance".to_string()
    };
    let skipped = bins
        .iter()
        .filter(|b| !b.fitted && b.point.freq_hz >= lo && b.point.freq_hz <= hi)
        .count();
    if skipped > 0 {
        warnings.push(Warning::new(
            WarningCode::WeakSignal,
            format!(
                "{skipped} bins in the band have a coherence below {} and are not fitted (flagged in the spectrum table)",
                o.min_coherence
            ),
        ));
    }
    Ok(BroadbandResult {
        spectra: w.spectra.clone(),
        bins,
        part,
        warnings,
        covariance: method,
        shift_samples: d,
        options: o.clone(),
    })
}

/// Broadband dynamic response as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct ResponseBroadband;

impl crate::procedures::Procedure for ResponseBroadband {
    const ID: crate::document::Procedure = crate::document::Procedure::ResponseBroadband;
    type Options = BroadbandOptions;
    type Input = Record;

    /// Segments of 256 samples: a short worked case.
    fn example() -> BroadbandOptions {
        BroadbandOptions {
            segment_samples: 256,
            ..BroadbandOptions::default()
        }
    }

    fn validate(o: &BroadbandOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &BroadbandOptions,
    ) -> Result<Record> {
        input::read(rows, o.rate_hz)
    }

    fn reduce(
        rec: &Record,
        o: &BroadbandOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(rec, o)?.document()
    }

    fn synthesis(
        rec: &Record,
        o: &BroadbandOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
