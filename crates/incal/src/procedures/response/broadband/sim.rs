//! Broadband simulator: a random, chirp or multisine excitation through a
//! known low-pass with delay ([`crate::procedures::response::model`]).
//!
//! The true motion `m_n` (`n = 0 … N−1`, `N = duration·rate`, `t = n/rate`)
//! of RMS `A` is
//!
//! * random: `m_n ~ N(0, A²)`;
//! * chirp: `m = √2 A sin 2π(f_lo t + (f_hi − f_lo) t²/(2T))`, a linear
//!   sweep over the record of length `T`;
//! * multisine: `m = Σ_j a cos(2π k_j n/P + φ_j)` over every bin `k_j` of
//!   the period `P = period_samples` with `f_lo ≤ k rate/P ≤ f_hi`, equal
//!   amplitudes `a = A √(2/K)` and Schroeder's phases
//!   `φ_j = −π j(j−1)/K` (a low crest factor), repeated over the record.
//!
//! It is filtered in the frequency domain over the whole record,
//! `y = IDFT(H(f_k) DFT(m))` (the steady-state response of the periodic
//! extension; the Nyquist bin takes `Re H`), and the rows hold
//! `reference = m + n_r` and `output = b + y + n_y`, `n_r ~ N(0, σ_r²)`,
//! `n_y ~ N(0, σ_y²)`; deterministic for a seed. A reference on its own
//! clock (`reference_clock_offset_s` δ) is recorded as `m(t + δ)` (the
//! phase `e^{j2πfδ}` in the same frequency domain) with stamps `t + δ` in
//! a `time_ref_s` column.

use std::f64::consts::{PI, TAU};

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
    /// The excitation (default random).
    #[serde(default)]
    pub excitation: Excitation,
    /// Lowest frequency of a chirp or multisine (Hz; default 0.5).
    #[serde(default = "half")]
    pub f_low_hz: f64,
    /// Highest frequency of a chirp or multisine (Hz; default 0.4 of the
    /// sampling rate).
    #[serde(default)]
    pub f_high_hz: Option<f64>,
    /// Period of a multisine (samples; default 1024: give the reduction's
    /// `segment_samples` the same, so each bin holds one sine).
    #[serde(default = "period")]
    pub period_samples: usize,
    /// The reference sampled on its own clock, this much later than the
    /// output (s; default 0: one clock). Not 0: a `time_ref_s` column.
    #[serde(default)]
    pub reference_clock_offset_s: f64,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn seed_one() -> u64 {
    1
}

fn half() -> f64 {
    0.5
}

fn period() -> usize {
    1024
}

/// The excitation of a simulated broadband test (module docs).
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
pub enum Excitation {
    /// White Gaussian noise.
    #[default]
    Random,
    /// A linear sweep from `f_low_hz` to `f_high_hz` over the record.
    Chirp,
    /// Equal sines at the bins of `period_samples` in the band, Schroeder
    /// phases.
    Multisine,
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
            excitation: Excitation::Random,
            f_low_hz: half(),
            f_high_hz: None,
            period_samples: period(),
            reference_clock_offset_s: 0.0,
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
        crate::procedures::response::plan::check_clock_offset(self.reference_clock_offset_s)?;
        let (_, hi) = self.band();
        check_range("f_high_hz", hi, 1e-9, self.rate_hz / 2.0, "Hz")?;
        check_range("f_low_hz", self.f_low_hz, 0.0, hi, "Hz")?;
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

    /// The chirp's or multisine's band `(f_lo, f_hi)` (Hz).
    fn band(&self) -> (f64, f64) {
        (self.f_low_hz, self.f_high_hz.unwrap_or(0.4 * self.rate_hz))
    }

    /// The true motion of `n` samples (module docs).
    fn motion(&self, n: usize, r: &mut rand::rngs::ChaCha8Rng) -> Result<Vec<f64>> {
        let a = self.amplitude;
        let (lo, hi) = self.band();
        let dt = 1.0 / self.rate_hz;
        Ok(match self.excitation {
            Excitation::Random => (0..n).map(|_| normal(r, a)).collect(),
            Excitation::Chirp => {
                let t_len = n as f64 * dt;
                (0..n)
                    .map(|i| {
                        let t = i as f64 * dt;
                        let phase = lo * t + (hi - lo) * t * t / (2.0 * t_len);
                        std::f64::consts::SQRT_2 * a * (TAU * phase).sin()
                    })
                    .collect()
            }
            Excitation::Multisine => {
                let p = self.period_samples;
                if !(16..=n).contains(&p) {
                    return crate::options::invalid(
                        "period_samples",
                        format!("{p}: from 16 to the record's {n} samples"),
                    );
                }
                let df = self.rate_hz / p as f64;
                let bins: Vec<usize> = (1..=p / 2)
                    .filter(|k| (lo..=hi).contains(&(*k as f64 * df)))
                    .collect();
                if bins.is_empty() {
                    return crate::options::invalid(
                        "f_low_hz",
                        format!("no bin of a {p}-sample period ({df:.6} Hz apart) lies between f_low_hz and f_high_hz"),
                    );
                }
                let kk = bins.len() as f64;
                let amp = a * (2.0 / kk).sqrt();
                let one: Vec<f64> = (0..p)
                    .map(|i| {
                        bins.iter()
                            .enumerate()
                            .map(|(j, k)| {
                                let j = (j + 1) as f64;
                                let phi = -PI * j * (j - 1.0) / kk;
                                amp * (TAU * (*k * i) as f64 / p as f64 + phi).cos()
                            })
                            .sum()
                    })
                    .collect();
                (0..n).map(|i| one[i % p]).collect()
            }
        })
    }

    /// The simulated record in memory.
    pub fn record(&self) -> Result<Record> {
        let n = self.samples()?;
        let x = self.model.x()?;
        let mut r = rng(self.seed);
        let m = self.motion(n, &mut r)?;
        let mut planner = RealFftPlanner::<f64>::new();
        let (fwd, inv) = (planner.plan_fft_forward(n), planner.plan_fft_inverse(n));
        let mut buf = m.clone();
        let mut spec_m = fwd.make_output_vec();
        fwd.process(&mut buf, &mut spec_m)
            .map_err(|e| Error::Unsupported(format!("FFT: {e}")))?;
        let last = spec_m.len() - 1;
        // Each bin times `h` (a real value at 0 and Nyquist), back in time.
        let filtered = |h: &dyn Fn(f64) -> Complex64| -> Result<Vec<f64>> {
            let mut spec: Vec<Complex64> = spec_m
                .iter()
                .enumerate()
                .map(|(k, z)| {
                    let hk = h(k as f64 * self.rate_hz / n as f64);
                    z * if k == 0 || (n % 2 == 0 && k == last) {
                        Complex64::new(hk.re, 0.0)
                    } else {
                        hk
                    }
                })
                .collect();
            let mut y = inv.make_output_vec();
            inv.process(&mut spec, &mut y)
                .map_err(|e| Error::Unsupported(format!("inverse FFT: {e}")))?;
            Ok(y.iter().map(|v| v / n as f64).collect())
        };
        let y = filtered(&|f| {
            let (mag, ph) = response(self.model.order, &x, f);
            Complex64::from_polar(mag, ph)
        })?;
        let delta = self.reference_clock_offset_s;
        let seen = if delta != 0.0 {
            filtered(&|f| Complex64::from_polar(1.0, TAU * f * delta))?
        } else {
            m
        };
        let reference: Vec<f64> = seen
            .iter()
            .map(|v| v + normal(&mut r, self.reference_noise))
            .collect();
        let output: Vec<f64> = y
            .iter()
            .map(|v| self.bias + v + normal(&mut r, self.noise))
            .collect();
        Ok(Record {
            rate_hz: self.rate_hz,
            reference,
            output,
            reference_offset_s: delta,
        })
    }

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
