//! The noise record's power spectral density (`psd: true`): Welch's
//! estimate of every channel with χ² bounds, the white level of a band
//! and its angle (velocity) random walk beside the Allan fit's
//! ([`crate::spectral::psd`] for the formulas).
//!
//! In the document, per channel, `channels.NAME.psd` holds `freq_hz`,
//! `density` (unit²/Hz), `asd` (unit/√Hz), `lo` and `hi` (the density's
//! bounds), `confidence`, `edf` (`2 K_eff`), `segments`,
//! `segment_samples`, `overlap_samples`, `window`, and `white`
//! (`{density, u_density, asd, u_asd, dof, band_hz, n_equivalent,
//! u_n_equivalent, n_unit}`) when the band holds three independent bins;
//! the coefficient `NAME.white_asd` (unit/√Hz) is the white level's square
//! root. A `noise-inconsistent` warning names a channel whose PSD's N and
//! the Allan fit's N differ beyond the U95 of their difference. `model`
//! holds the one-sided PSD of each IEEE Std 952 term the Allan fit
//! identified (`terms.Q` … `terms.R`) and their sum (`total`), at
//! `freq_hz` (the consistency check of the two analyses;
//! [`crate::noise::terms::term_psd`]).
//!
//! `tones` lists the lines standing above the local floor
//! ([`crate::spectral::tones`]), strongest first: `frequency_hz`,
//! `u_frequency_hz`, `amplitude_rms` and `u_amplitude_rms` (input unit),
//! `dof`, `k95` (the coverage factor of both), `peak_to_floor`,
//! `floor_asd` (input unit/√Hz) and `bin`; `tone_search` says how they
//! were searched: `false_alarm` (per spectrum), `threshold_ratio`, `bins`,
//! `band_hz`, `more` (lines beyond the 16 estimated) and `unfitted_hz`.
//! The white level leaves out the lines' lobes.

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::error::Result;
use crate::spectral::psd::{psd_of_phase, Psd, White};
use crate::spectral::tones::{self, Search, Tone};
use crate::spectral::welch::Window;

/// The PSD's options (flattened into the noise options).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct SpectrumOptions {
    /// Also the power spectral density of every channel.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub psd: bool,
    /// Samples per Welch segment (default: the largest power of two with
    /// at least 8 segments, from 16 to 65536): the resolution is
    /// rate/segment.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd_segment_samples: Option<usize>,
    /// Overlap of the segments (samples; default half a segment).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd_overlap_samples: Option<usize>,
    /// The window of each segment (default hann).
    #[serde(default, skip_serializing_if = "is_hann")]
    pub psd_window: Window,
    /// Confidence of the PSD's χ² bounds (default 0.95).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd_confidence: Option<f64>,
    /// The band (Hz, two numbers) of the white level (default 5 % to 25 %
    /// of the sampling rate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd_white_band_hz: Option<Vec<f64>>,
    /// The tone search's false-alarm rate per spectrum (default 0.01):
    /// at most this many false lines per channel's spectrum, on average.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub psd_false_alarm: Option<f64>,
}

fn is_hann(w: &Window) -> bool {
    *w == Window::Hann
}

/// One channel's spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSpectrum {
    /// The estimate (internal rate unit).
    pub psd: Psd,
    /// The white level, when the band holds enough bins.
    pub white: Option<White>,
    /// Segment and overlap used (samples).
    pub segment: (usize, usize),
    /// The window used.
    pub window: Window,
    /// Where it comes from when not the whole record (gaps).
    pub note: Option<String>,
    /// The sample period (s).
    pub tau0_s: f64,
    /// The tone search.
    pub search: Search,
    /// The lines found and estimated, strongest first.
    pub tones: Vec<Tone>,
    /// Lines found whose fit did not converge (their bins).
    pub unfitted: Vec<usize>,
}

impl SpectrumOptions {
    /// Range checks (names the key).
    pub fn validate(&self) -> Result<()> {
        use crate::options::invalid;
        if let Some(l) = self.psd_segment_samples {
            if !(8..=1 << 24).contains(&l) {
                return invalid(
                    "psd_segment_samples",
                    format!("from 8 to 16777216, got {l}"),
                );
            }
            if self.psd_overlap_samples.is_some_and(|o| o >= l) {
                return invalid("psd_overlap_samples", "must be below psd_segment_samples");
            }
        }
        if let Some(c) = self.psd_confidence {
            if !(c > 0.0 && c < 1.0) {
                return invalid("psd_confidence", format!("between 0 and 1, got {c}"));
            }
        }
        if let Some(a) = self.psd_false_alarm {
            if !(a > 0.0 && a <= 0.5) {
                return invalid("psd_false_alarm", format!("above 0, at most 0.5, got {a}"));
            }
        }
        if let Some(b) = &self.psd_white_band_hz {
            if b.len() != 2 || !(b[0] >= 0.0 && b[1] > b[0] && b[1].is_finite()) {
                return invalid(
                    "psd_white_band_hz",
                    "two frequencies, the lower first, at or above 0 Hz",
                );
            }
        }
        Ok(())
    }

    /// The segment and overlap for a record of `rows` samples.
    fn segment(&self, rows: usize) -> (usize, usize) {
        let l = self.psd_segment_samples.unwrap_or_else(|| {
            let mut l = 16usize;
            while l * 2 <= rows / 8 && l < 65536 {
                l *= 2;
            }
            l
        });
        (l, self.psd_overlap_samples.unwrap_or(l / 2))
    }

    /// The spectrum of the channel whose phase is `x` (`None` without
    /// `psd`).
    pub fn compute(&self, x: &[f64], tau0_s: f64) -> Result<Option<ChannelSpectrum>> {
        if !self.psd {
            return Ok(None);
        }
        let segment = self.segment(x.len().saturating_sub(1));
        let conf = self.psd_confidence.unwrap_or(0.95);
        let psd = psd_of_phase(x, tau0_s, segment, self.psd_window, conf)?;
        let fs = 1.0 / tau0_s;
        let band = match self.psd_white_band_hz.as_deref() {
            Some(&[lo, hi]) => (lo, hi),
            _ => (0.05 * fs, 0.25 * fs),
        };
        let alpha = self.psd_false_alarm.unwrap_or(0.01);
        let (search, found) = tones::search(&psd, self.psd_window, alpha);
        let mut lines = Vec::new();
        let mut unfitted = Vec::new();
        for c in &found {
            match tones::estimate(x, tau0_s, segment.0, c) {
                Some(t) => lines.push(t),
                None => unfitted.push(c.bin),
            }
        }
        let bins: Vec<usize> = found.iter().map(|c| c.bin).collect();
        Ok(Some(ChannelSpectrum {
            white: psd.white_without(band, &bins, tones::lobe(self.psd_window)),
            psd,
            segment,
            window: self.psd_window,
            note: None,
            tau0_s,
            search,
            tones: lines,
            unfitted,
        }))
    }
}

impl ChannelSpectrum {
    /// The `model` object (module docs): each identified term's PSD and
    /// their sum at the bins above 0 Hz, times `f2` (into the input unit).
    fn model_json(&self, fit: &crate::noise::terms::TermFit, tau0_s: f64, f2: f64) -> Value {
        use crate::noise::terms::{term_psd, TERMS};
        let freqs: Vec<f64> = self
            .psd
            .freq_hz
            .iter()
            .copied()
            .filter(|f| *f > 0.0)
            .collect();
        let mut total = vec![0.0; freqs.len()];
        let mut terms = serde_json::Map::new();
        for (j, t) in fit.terms.iter().enumerate() {
            let Some(t) = t else { continue };
            let g: Vec<f64> = freqs
                .iter()
                .map(|f| term_psd(j, t.value, *f, tau0_s) * f2)
                .collect();
            for (a, v) in total.iter_mut().zip(&g) {
                *a += v;
            }
            terms.insert(TERMS[j].into(), json!(g));
        }
        json!({"freq_hz": freqs, "total": total, "terms": terms})
    }

    /// `channels.NAME.psd` (module docs): densities times `f²` (into the
    /// input unit), N times `n_factor` into `n_unit`, the Allan fit's
    /// terms as PSDs (`fit`).
    pub fn json(
        &self,
        f: f64,
        (n_factor, n_unit): (f64, &str),
        fit: &crate::noise::terms::TermFit,
    ) -> Value {
        let p = &self.psd;
        let f2 = f * f;
        let scale = |v: &[f64]| -> Vec<f64> { v.iter().map(|g| g * f2).collect() };
        let white = self.white.map(|w| {
            let (n, un) = w.n_equivalent();
            let (asd, u_asd) = w.asd(f);
            json!({
                "density": w.density * f2,
                "u_density": w.u * f2,
                "asd": asd,
                "u_asd": u_asd,
                "dof": w.dof,
                "band_hz": [w.band_hz.0, w.band_hz.1],
                "n_equivalent": n * n_factor,
                "u_n_equivalent": un * n_factor,
                "n_unit": n_unit,
            })
        });
        json!({
            "freq_hz": p.freq_hz,
            "density": scale(&p.density),
            "asd": p.density.iter().map(|g| (g * f2).sqrt()).collect::<Vec<f64>>(),
            "lo": scale(&p.lo),
            "hi": scale(&p.hi),
            "confidence": p.confidence,
            "edf": 2.0 * p.effective,
            "segments": p.segments,
            "segment_samples": self.segment.0,
            "overlap_samples": self.segment.1,
            "window": self.window,
            "white": white,
            "note": self.note,
            "model": self.model_json(fit, self.tau0_s, f2),
            "tone_search": {
                "false_alarm": self.search.false_alarm,
                "threshold_ratio": self.search.threshold,
                "bins": self.search.bins,
                "band_hz": [self.search.band_hz.0, self.search.band_hz.1],
                "more": self.search.more,
                "unfitted_hz": self.unfitted.iter().map(|k| p.freq_hz[*k]).collect::<Vec<f64>>(),
            },
            "tones": self.tones.iter().map(|t| tone_json(t, f)).collect::<Vec<Value>>(),
        })
    }
}

/// One line of `psd.tones` (module docs), amplitudes times `f`.
fn tone_json(t: &Tone, f: f64) -> Value {
    let k = crate::estimation::coverage_factor(t.dof, 0.95);
    json!({
        "frequency_hz": t.frequency_hz,
        "u_frequency_hz": t.u_frequency_hz,
        "amplitude_rms": t.amplitude_rms * f,
        "u_amplitude_rms": t.u_amplitude_rms * f,
        "dof": t.dof,
        "k95": k,
        "peak_to_floor": t.peak.ratio,
        "floor_asd": (t.peak.floor * f * f).sqrt(),
        "bin": t.peak.bin,
    })
}
