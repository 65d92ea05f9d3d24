//! Stepped-sine simulator: a known low-pass with delay ([`super::model`])
//! driven by a sine at each dwell, in steady state.
//!
//! Dwell `i` at `f_i` starts at `t_i` (the previous dwell's end) and lasts
//! its scheduled seconds at `rate_hz`. The table runs at
//! `f = f_i (1 + frequency_error_pct/100)` (its oscillator's error; the
//! `freq_hz` column holds `f_i`, or is left out with `no_freq_column`).
//! With `t' = t − t_i` and the true motion `m = A sin 2πf t'`, the rows
//! hold
//!
//! * `reference = (1 + e_i) m(t' + δ) + n_r`, `e_i ~ N(0, (reference_error_pct/100)²)`
//!   once per dwell (the reference standard's amplitude error),
//!   `n_r ~ N(0, σ_r²)`, `δ` = `reference_clock_offset_s` (the reference
//!   sampled by its own clock, its stamps in a `time_ref_s` column);
//! * `output = b + |H| A [sin(2πf t' + ∠H) + d sin(2(2πf t' + ∠H))] + n_y`,
//!   `d = distortion_pct/100` (a second harmonic), `n_y ~ N(0, σ_y²)`,
//!
//! deterministic for a seed. The truth ([`crate::procedures::Simulate::truth`]):
//! the model, its bandwidth, phase frequency and latency, and each dwell's
//! true frequency, `|H|/k_dc` in dB and `∠H` in degrees.

use std::f64::consts::TAU;

use serde_json::json;

use super::input::{write_each, Sample};
use super::model::response;
use super::plan::{amplitude, noise, reference_noise, thousand, DwellChoice, ModelGuess};
use crate::error::Result;
use crate::options::check_range;
use crate::sim::{normal, rng};

/// Options of `incal simulate response-sine`, in engineering units.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ResponseSimOptions {
    /// The dwells.
    #[serde(flatten)]
    pub dwells: DwellChoice,
    /// The true response.
    #[serde(flatten)]
    pub model: ModelGuess,
    /// Sampling rate (Hz; default 1000).
    #[serde(default = "thousand")]
    pub rate_hz: f64,
    /// Reference amplitude `A` (reference units; default 10).
    #[serde(default = "amplitude")]
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
    /// Second harmonic of the output (% of the fundamental; default 0).
    #[serde(default)]
    pub distortion_pct: f64,
    /// σ of the reference's amplitude error, drawn once per dwell (%).
    #[serde(default)]
    pub reference_error_pct: f64,
    /// The reference sampled on its own clock, this much later than the
    /// output (s; default 0: one clock). Not 0: a `time_ref_s` column.
    #[serde(default)]
    pub reference_clock_offset_s: f64,
    /// The table's frequency error (%, −10..10; default 0): it runs at
    /// `freq_hz (1 + frequency_error_pct/100)`.
    #[serde(default)]
    pub frequency_error_pct: f64,
    /// Write no `freq_hz` column (the reduction then finds the dwells
    /// from the reference).
    #[serde(default)]
    pub no_freq_column: bool,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn seed_one() -> u64 {
    1
}

impl Default for ResponseSimOptions {
    fn default() -> Self {
        Self {
            dwells: DwellChoice::default(),
            model: ModelGuess::default(),
            rate_hz: thousand(),
            amplitude: amplitude(),
            noise: noise(),
            reference_noise: reference_noise(),
            bias: 0.0,
            distortion_pct: 0.0,
            reference_error_pct: 0.0,
            reference_clock_offset_s: 0.0,
            frequency_error_pct: 0.0,
            no_freq_column: false,
            seed: 1,
        }
    }
}

impl ResponseSimOptions {
    /// Every range check; the schedule `(freq_hz, seconds)`.
    pub fn schedule(&self) -> Result<Vec<(f64, f64)>> {
        check_range("amplitude", self.amplitude, 1e-12, 1e12, "")?;
        check_range("bias", self.bias, -1e12, 1e12, "")?;
        check_range("distortion_pct", self.distortion_pct, 0.0, 100.0, "%")?;
        check_range(
            "reference_error_pct",
            self.reference_error_pct,
            0.0,
            50.0,
            "%",
        )?;
        super::plan::check_clock_offset(self.reference_clock_offset_s)?;
        check_range(
            "frequency_error_pct",
            self.frequency_error_pct,
            -10.0,
            10.0,
            "%",
        )?;
        super::plan::check_test(
            &self.dwells,
            &self.model,
            self.rate_hz,
            [self.noise, self.reference_noise],
            [0.0, 0.0],
        )
    }

    /// Each row in turn, without holding them (options checked first).
    pub fn for_each(&self, f: impl FnMut(Sample) -> std::io::Result<()>) -> Result<()> {
        let schedule = self.schedule()?;
        let x = self.model.x()?;
        self.rows(&schedule, &x, f)
            .map_err(|e| crate::Error::Write(e.to_string()))
    }

    fn rows(
        &self,
        schedule: &[(f64, f64)],
        x: &[f64],
        mut f: impl FnMut(Sample) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        let mut r = rng(self.seed);
        let mut t_start = 0.0;
        let d = self.distortion_pct / 100.0;
        for &(nominal, seconds) in schedule {
            let freq = self.true_freq(nominal);
            let n = (seconds * self.rate_hz).round().max(1.0) as usize;
            let (m, ph) = response(self.model.order, x, freq);
            let e = normal(&mut r, self.reference_error_pct / 100.0);
            for k in 0..n {
                let tp = k as f64 / self.rate_hz;
                let w = TAU * freq * tp;
                let offset = self.reference_clock_offset_s;
                let motion = self.amplitude * (TAU * freq * (tp + offset)).sin();
                let reference = (1.0 + e) * motion + normal(&mut r, self.reference_noise);
                let output = self.bias
                    + m * self.amplitude * ((w + ph).sin() + d * (2.0 * (w + ph)).sin())
                    + normal(&mut r, self.noise);
                f(Sample {
                    time_s: t_start + tp,
                    time_ref_s: (offset != 0.0).then_some(t_start + tp + offset),
                    freq_hz: nominal,
                    reference,
                    output,
                })?;
            }
            t_start += n as f64 / self.rate_hz;
        }
        Ok(())
    }

    /// The table's true frequency at a dwell of nominal `freq_hz`.
    fn true_freq(&self, freq_hz: f64) -> f64 {
        freq_hz * (1.0 + self.frequency_error_pct / 100.0)
    }

    /// The truth as JSON (module docs).
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        let x = self.model.x()?;
        let order = self.model.order;
        let dwells: Vec<serde_json::Value> = self
            .schedule()?
            .iter()
            .map(|(nominal, _)| {
                let f = self.true_freq(*nominal);
                let (m, ph) = response(order, &x, f);
                let sign = if x[0] < 0.0 { std::f64::consts::PI } else { 0.0 };
                json!({"freq_hz": f, "gain": m, "gain_db": 20.0 * (m / x[0].abs()).log10(), "phase_deg": (ph - sign).to_degrees()})
            })
            .collect();
        let mut t = self.model.truth()?;
        t.insert("dwells".into(), serde_json::Value::Array(dwells));
        Ok(serde_json::Value::Object(t))
    }
}

impl crate::procedures::Simulate for super::ResponseSine {
    type Options = ResponseSimOptions;

    fn validate(o: &ResponseSimOptions) -> Result<()> {
        o.schedule().map(|_| ())
    }

    /// Streamed: rows are written as they are drawn.
    fn simulate(o: &ResponseSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let schedule = o.schedule()?;
        let x = o.model.x()?;
        let columns = (o.reference_clock_offset_s != 0.0, !o.no_freq_column);
        write_each(out, columns, |row| o.rows(&schedule, &x, row))?;
        Ok(())
    }

    fn truth(o: &ResponseSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}

impl ResponseSimOptions {
    /// The simulated dwells in memory (what [`super::input::read`] makes
    /// of the written CSV, up to its digits).
    pub fn dwells(&self) -> Result<Vec<super::input::Dwell>> {
        let mut v = Vec::new();
        self.for_each(|s| {
            v.push(s);
            Ok(())
        })?;
        Ok(super::input::dwells_from(v))
    }
}
