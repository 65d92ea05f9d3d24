//! Broadband simulator: white Gaussian excitation through a known
//! low-pass with delay ([`crate::procedures::response::model`]).
//!
//! The true motion `m_n ~ N(0, A²)` (`n = 0 … N−1`, `N = duration·rate`)
//! is filtered in the frequency domain over the whole record,
//! `y = IDFT(H(f_k) DFT(m))` (the steady-state response of the periodic
//! extension; the Nyquist bin takes `Re H`), and the rows hold
//! `reference = m + n_r` and `output = b + y + n_y`, `n_r ~ N(0, σ_r²)`,
//! `n_y ~ N(0, σ_y²)`; deterministic for a seed.

use realfft::num_complex::Complex64;
use realfft::RealFftPlanner;

use super::input::{write, Record};
use super::plan::{noise, sixty, ten, thousand};
use crate::error::{Error, Result};
use crate::options::check_range;
use crate::procedures::response::model::response;
use crate::procedures::response::plan::ModelGuess;
use crate::sim::{normal, rng};

/// Options of `incal simulate response-broadband`, in engineering units.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct BroadbandSimOptions {
    /// The true response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Record length (s; default 60).
    #[serde(default = "sixty")]
    pub duration_s: f64,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// RMS of the reference motion `A` (reference units; default 10).
    #[serde(default = "ten")]
    pub amplitude: f64,
    /// Output noise σ of one sample (default 0.02).
    #[serde(default = "noise")]
    pub noise: f64,
    /// Reference noise σ of one sample (default 0; it biases H1 low by
    /// `1/(1 + σ_r²/A²)`).
    #[serde(default)]
    pub reference_noise: f64,
    /// Output bias `b` (default 0).
    #[serde(default)]
    pub bias: f64,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn seed_one() -> u64 {
    1
}

impl Default for BroadbandSimOptions {
    fn default() -> Self {
        Self {
            model: ModelGuess::default(),
            duration_s: sixty(),
            rate_hz: thousand(),
            amplitude: ten(),
            noise: noise(),
            reference_noise: 0.0,
            bias: 0.0,
            seed: 1,
        }
    }
}

impl BroadbandSimOptions {
    /// Every range check; the number of samples.
    pub fn samples(&self) -> Result<usize> {
        check_range("rate_hz", self.rate_hz, 1e-3, 1e7, "Hz")?;
        check_range("duration_s", self.duration_s, 1e-3, 1e8, "s")?;
        check_range("amplitude", self.amplitude, 1e-12, 1e12, "")?;
        check_range("noise", self.noise, 0.0, 1e12, "")?;
        check_range("reference_noise", self.reference_noise, 0.0, 1e12, "")?;
        check_range("bias", self.bias, -1e12, 1e12, "")?;
        self.model.x()?;
        let n = (self.duration_s * self.rate_hz).round();
        crate::sim::check_rows(&[("duration_s x rate_hz", n)])?;
        if n < 16.0 {
            return crate::options::invalid(
                "duration_s",
                format!("{n} samples at rate_hz: at least 16"),
            );
        }
        Ok(n as usize)
    }

    /// The simulated record in memory.
    pub fn record(&self) -> Result<Record> {
        let n = self.samples()?;
        let x = self.model.x()?;
        let mut r = rng(self.seed);
        let m: Vec<f64> = (0..n).map(|_| normal(&mut r, self.amplitude)).collect();
        let mut planner = RealFftPlanner::<f64>::new();
        let (fwd, inv) = (planner.plan_fft_forward(n), planner.plan_fft_inverse(n));
        let mut buf = m.clone();
        let mut spec = fwd.make_output_vec();
        fwd.process(&mut buf, &mut spec)
            .map_err(|e| Error::Unsupported(format!("FFT: {e}")))?;
        let last = spec.len() - 1;
        for (k, z) in spec.iter_mut().enumerate() {
            let f = k as f64 * self.rate_hz / n as f64;
            let (mag, ph) = response(self.model.order, &x, f);
            let h = Complex64::from_polar(mag, ph);
            *z *= if k == 0 || (n % 2 == 0 && k == last) {
                Complex64::new(h.re, 0.0)
            } else {
                h
            };
        }
        let mut y = inv.make_output_vec();
        inv.process(&mut spec, &mut y)
            .map_err(|e| Error::Unsupported(format!("inverse FFT: {e}")))?;
        let scale = 1.0 / n as f64;
        let reference: Vec<f64> = m
            .iter()
            .map(|v| v + normal(&mut r, self.reference_noise))
            .collect();
        let output: Vec<f64> = y
            .iter()
            .map(|v| self.bias + v * scale + normal(&mut r, self.noise))
            .collect();
        Ok(Record {
            rate_hz: self.rate_hz,
            reference,
            output,
        })
    }

    /// The truth as JSON: the model, its bandwidth, phase frequency and
    /// latency.
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        self.model.truth().map(serde_json::Value::Object)
    }
}

impl crate::procedures::Simulate for super::ResponseBroadband {
    type Options = BroadbandSimOptions;

    fn validate(o: &BroadbandSimOptions) -> Result<()> {
        o.samples().map(|_| ())
    }

    fn simulate(o: &BroadbandSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.record()?, out)?;
        Ok(())
    }

    fn truth(o: &BroadbandSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
