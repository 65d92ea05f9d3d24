//! Warm-up simulator: an instrument switched on at a known time whose
//! output settles along a known curve, with white and Gauss–Markov noise.
//!
//! Power-on at `t = 0`; the output becomes valid at
//! `t_on = turn_on_s + U(0, Δt)` (so the reduction's `u` of the turn-on
//! time is exercised): before it the output cell is empty and `status`
//! 0. After it `output = B(t) + w + g` with `B` the curve
//! ([`super::fit::curve`]), `w` white (σ `noise`) and `g` a first-order
//! Gauss–Markov process (σ `gm_sigma`, correlation time `gm_tau_s`,
//! started stationary). `temperature_c` holds the chamber's constant
//! temperature with its sensor's white noise. Deterministic for a seed.

use rand::RngExt;

use super::fit::{curve, Shape};
use super::input::{write, Record};
use crate::error::Result;
use crate::options::check_range;
use crate::sim::{normal, rng};
use rand::rngs::ChaCha8Rng;

/// Options of `incal simulate warmup`, in engineering units.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WarmupSimOptions {
    /// Sampling rate (Hz; default 10).
    #[serde(default = "ten")]
    pub rate_hz: f64,
    /// Record length from power-on (s; default 3600).
    #[serde(default = "hour")]
    pub duration_s: f64,
    /// Turn-on time (s; default 2), plus up to one sample interval.
    #[serde(default = "two")]
    pub turn_on_s: f64,
    /// The settled value `B∞` (output units; default 0.5).
    #[serde(default = "half")]
    pub bias_settled: f64,
    /// The transient at power-on `A` (output units; default 0.2).
    #[serde(default = "fifth")]
    pub amplitude: f64,
    /// Its time constant `τ` (s; default 300).
    #[serde(default = "three_hundred")]
    pub tau_s: f64,
    /// A second transient `A₂` (output units; default 0: none).
    #[serde(default)]
    pub amplitude_2: f64,
    /// Its time constant `τ₂` (s; default 30).
    #[serde(default = "thirty")]
    pub tau_2_s: f64,
    /// Linear drift `D` (output units per s; default 0).
    #[serde(default)]
    pub drift_per_s: f64,
    /// White noise σ of one sample (output units; default 0.01).
    #[serde(default = "hundredth")]
    pub noise: f64,
    /// Gauss–Markov noise σ (output units; default 0).
    #[serde(default)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time (s; default 5).
    #[serde(default = "five")]
    pub gm_tau_s: f64,
    /// Chamber temperature (°C; default 25).
    #[serde(default = "twenty_five")]
    pub temperature_c: f64,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

pub(super) fn ten() -> f64 {
    10.0
}
pub(super) fn hour() -> f64 {
    3600.0
}
pub(super) fn two() -> f64 {
    2.0
}
pub(super) fn half() -> f64 {
    0.5
}
pub(super) fn fifth() -> f64 {
    0.2
}
pub(super) fn three_hundred() -> f64 {
    300.0
}
fn thirty() -> f64 {
    30.0
}
pub(super) fn hundredth() -> f64 {
    0.01
}
pub(super) fn five() -> f64 {
    5.0
}
fn twenty_five() -> f64 {
    25.0
}
pub(super) fn seed_one() -> u64 {
    1
}

impl Default for WarmupSimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

impl WarmupSimOptions {
    /// Every range check; the number of rows.
    pub fn rows(&self) -> Result<usize> {
        check_range("rate_hz", self.rate_hz, 1e-3, 1e6, "Hz")?;
        check_range("duration_s", self.duration_s, 1e-3, 1e8, "s")?;
        check_range("turn_on_s", self.turn_on_s, 0.0, self.duration_s, "s")?;
        check_range("bias_settled", self.bias_settled, -1e12, 1e12, "")?;
        check_range("amplitude", self.amplitude, -1e12, 1e12, "")?;
        check_range("tau_s", self.tau_s, 1e-6, 1e9, "s")?;
        check_range("amplitude_2", self.amplitude_2, -1e12, 1e12, "")?;
        check_range("tau_2_s", self.tau_2_s, 1e-6, 1e9, "s")?;
        check_range("drift_per_s", self.drift_per_s, -1e9, 1e9, "")?;
        check_range("noise", self.noise, 0.0, 1e12, "")?;
        check_range("gm_sigma", self.gm_sigma, 0.0, 1e12, "")?;
        check_range("gm_tau_s", self.gm_tau_s, 1e-6, 1e9, "s")?;
        check_range("temperature_c", self.temperature_c, -273.15, 1e4, "°C")?;
        let n = (self.duration_s * self.rate_hz).round();
        crate::sim::check_rows(&[("duration_s x rate_hz", n)])?;
        if n < 20.0 {
            return crate::options::invalid("duration_s", format!("{n} rows: at least 20"));
        }
        Ok(n as usize)
    }

    /// The curve's shape and parameters (`bias, amplitude, tau_s[,
    /// amplitude_2, tau_2_s][, drift_per_s]`).
    pub fn parameters(&self) -> (Shape, Vec<f64>) {
        let two = self.amplitude_2 != 0.0;
        let drift = self.drift_per_s != 0.0;
        let shape = match (two, drift) {
            (false, false) => Shape::Exp1,
            (false, true) => Shape::Exp1Drift,
            (true, false) => Shape::Exp2,
            (true, true) => Shape::Exp2Drift,
        };
        let mut p = vec![self.bias_settled, self.amplitude, self.tau_s];
        if two {
            p.extend([self.amplitude_2, self.tau_2_s]);
        }
        if drift {
            p.push(self.drift_per_s);
        }
        (shape, p)
    }

    /// The true turn-on time (s): the first draw of the seed's stream.
    fn turn_on(&self, r: &mut ChaCha8Rng) -> f64 {
        self.turn_on_s + (1.0 / self.rate_hz) * r.random::<f64>()
    }

    /// The simulated record and the true turn-on time (s).
    pub fn record(&self) -> Result<(Record, f64)> {
        let n = self.rows()?;
        let (shape, p) = self.parameters();
        let mut r = rng(self.seed);
        let dt = 1.0 / self.rate_hz;
        let t_on = self.turn_on(&mut r);
        let phi = (-dt / self.gm_tau_s).exp();
        let drive = self.gm_sigma * (1.0 - phi * phi).sqrt();
        let mut g = normal(&mut r, self.gm_sigma);
        let mut rec = Record {
            rate_hz: self.rate_hz,
            status: Some(Vec::with_capacity(n)),
            temperature_c: Some(Vec::with_capacity(n)),
            ..Record::default()
        };
        for k in 0..n {
            let t = k as f64 * dt;
            g = phi * g + normal(&mut r, drive);
            let w = normal(&mut r, self.noise);
            let on = t >= t_on;
            rec.time_s.push(t);
            rec.output.push(on.then(|| curve(shape, &p, t) + w + g));
            if let Some(s) = rec.status.as_mut() {
                s.push(if on { 1.0 } else { 0.0 });
            }
            let c = self.temperature_c + normal(&mut r, 0.01);
            if let Some(v) = rec.temperature_c.as_mut() {
                v.push(c);
            }
            rec.lines.push(k + 2);
        }
        Ok((rec, t_on))
    }

    /// The truth as JSON: the curve's parameters, the turn-on time, the
    /// settling time (the default band: 1 % of the transient at
    /// power-on) and the warm-up drift over the first 60 s.
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        self.rows()?;
        let (shape, p) = self.parameters();
        let t_on = self.turn_on(&mut rng(self.seed));
        let band = super::settle_band(shape, &p, None);
        let mut t = serde_json::Map::new();
        for (name, v) in shape.names().iter().zip(&p) {
            t.insert(name.clone(), (*v).into());
        }
        t.insert("turn_on_time_s".into(), t_on.into());
        t.insert(
            "settling_time_s".into(),
            super::settling_time(shape, &p, band, t_on).into(),
        );
        t.insert(
            "warmup_drift".into(),
            super::warmup_drift(shape, &p, t_on, 60.0).into(),
        );
        t.insert("shape".into(), shape.name().into());
        Ok(serde_json::Value::Object(t))
    }
}

impl crate::procedures::Simulate for super::Warmup {
    type Options = WarmupSimOptions;

    fn validate(o: &WarmupSimOptions) -> Result<()> {
        o.rows().map(|_| ())
    }

    fn simulate(o: &WarmupSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.record()?.0, out)?;
        Ok(())
    }

    fn truth(o: &WarmupSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
