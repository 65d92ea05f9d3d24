//! Step simulator: a reference step through a known low-pass with delay.
//!
//! The reference steps by `A` at `t_s = step_s + U(0, 1/rate)` (the step
//! falls anywhere within a sample interval, so the reduction's `u(t₀)` is
//! exercised); the rows hold `reference = A·[t ≥ t_s] + n_r` and
//! `output = b + K A s(t − t_s − τ) + n_y` with `s` the model's unit step
//! ([`super::unit_step`]); deterministic for a seed. A reference on its
//! own clock (`reference_clock_offset_s` δ) samples row n at `t_n + δ`
//! (its stamps in a `time_ref_s` column): it shows the step `δ` earlier.

use rand::RngExt;

use super::input::{write, Record};
use super::unit_step;
use crate::error::Result;
use crate::options::check_range;
use crate::procedures::response::plan::ModelGuess;
use crate::sim::{normal, rng};

/// Options of `incal simulate response-step`, in engineering units.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct StepSimOptions {
    /// The true response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Record length (s; default 1).
    #[serde(default = "one")]
    pub duration_s: f64,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// Time of the step (s; default 0.3), plus up to one sample.
    #[serde(default = "step")]
    pub step_s: f64,
    /// Step of the reference `A` (reference units; default 10).
    #[serde(default = "ten")]
    pub amplitude: f64,
    /// Output noise σ of one sample (default 0.02).
    #[serde(default = "noise")]
    pub noise: f64,
    /// Reference noise σ of one sample (default 0.005).
    #[serde(default = "reference_noise")]
    pub reference_noise: f64,
    /// Output bias `b` (default 0).
    #[serde(default)]
    pub bias: f64,
    /// The reference sampled on its own clock, this much later than the
    /// output (s; default 0: one clock). Not 0: a `time_ref_s` column.
    #[serde(default)]
    pub reference_clock_offset_s: f64,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

pub(super) fn one() -> f64 {
    1.0
}
pub(super) fn thousand() -> f64 {
    1000.0
}
pub(super) fn step() -> f64 {
    0.3
}
pub(super) fn ten() -> f64 {
    10.0
}
pub(super) fn noise() -> f64 {
    0.02
}
pub(super) fn reference_noise() -> f64 {
    0.005
}
fn seed_one() -> u64 {
    1
}

impl Default for StepSimOptions {
    fn default() -> Self {
        Self {
            model: ModelGuess::default(),
            duration_s: one(),
            rate_hz: thousand(),
            step_s: step(),
            amplitude: ten(),
            noise: noise(),
            reference_noise: reference_noise(),
            bias: 0.0,
            reference_clock_offset_s: 0.0,
            seed: 1,
        }
    }
}

impl StepSimOptions {
    /// Every range check; the number of samples.
    pub fn samples(&self) -> Result<usize> {
        check_range("rate_hz", self.rate_hz, 1e-3, 1e7, "Hz")?;
        check_range("duration_s", self.duration_s, 1e-3, 1e8, "s")?;
        check_range("step_s", self.step_s, 0.0, self.duration_s, "s")?;
        check_range("amplitude", self.amplitude, -1e12, 1e12, "")?;
        if self.amplitude == 0.0 {
            return crate::options::invalid("amplitude", "a step of 0 is no step");
        }
        check_range("noise", self.noise, 0.0, 1e12, "")?;
        check_range("reference_noise", self.reference_noise, 0.0, 1e12, "")?;
        check_range("bias", self.bias, -1e12, 1e12, "")?;
        crate::procedures::response::plan::check_clock_offset(self.reference_clock_offset_s)?;
        self.model.x()?;
        let n = (self.duration_s * self.rate_hz).round();
        crate::sim::check_rows(&[("duration_s x rate_hz", n)])?;
        if n < 40.0 {
            return crate::options::invalid("duration_s", format!("{n} samples: at least 40"));
        }
        Ok(n as usize)
    }

    /// The simulated record and the true step time (s).
    pub fn record(&self) -> Result<(Record, f64)> {
        let n = self.samples()?;
        let x = self.model.x()?;
        let mut r = rng(self.seed);
        let dt = 1.0 / self.rate_hz;
        let t_step = self.step_s + dt * r.random::<f64>();
        let delay = x[x.len() - 1];
        let (mut reference, mut output) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for k in 0..n {
            let t = k as f64 * dt;
            let seen = t + self.reference_clock_offset_s;
            let a = if seen >= t_step { self.amplitude } else { 0.0 };
            reference.push(a + normal(&mut r, self.reference_noise));
            let s = unit_step(self.model.order, &x, t - t_step - delay);
            output.push(self.bias + x[0] * self.amplitude * s + normal(&mut r, self.noise));
        }
        Ok((
            Record {
                rate_hz: self.rate_hz,
                reference,
                output,
                reference_offset_s: self.reference_clock_offset_s,
            },
            t_step,
        ))
    }

    /// The truth as JSON: the model, its derived quantities and step
    /// metrics (2 % band), and the true step time.
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        let mut t = self.model.truth()?;
        let x = self.model.x()?;
        let (rise, over, settle) = super::metrics(self.model.order, &x, 2.0);
        t.insert("rise_time_s".into(), rise.into());
        t.insert("overshoot_pct".into(), over.into());
        t.insert("settling_time_s".into(), settle.into());
        t.insert("step_time_s".into(), self.record()?.1.into());
        Ok(serde_json::Value::Object(t))
    }
}

impl crate::procedures::Simulate for super::ResponseStep {
    type Options = StepSimOptions;

    fn validate(o: &StepSimOptions) -> Result<()> {
        o.samples().map(|_| ())
    }

    fn simulate(o: &StepSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.record()?.0, out)?;
        Ok(())
    }

    fn truth(o: &StepSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
