//! Threshold simulator: a gyro on a rate table, or an accelerometer on a
//! dividing head, stepped about zero and about a base input, with a dead
//! band at zero, a dead band about the base input (stiction about the
//! operating point), white and Gauss–Markov noise and an output quantizer.
//!
//! The commanded sequence: a plateau at zero, then for each step size Δ
//! the plateaus `+Δ, 0, −Δ, 0`; then (with a base input `u_B`) a plateau
//! at `u_B` and for each Δ `u_B+Δ, u_B, u_B−Δ, u_B`; each `dwell_s` long.
//! An accelerometer's tilt is `asin(u)` (deg), so its steps are exact in
//! g. The output `y = bias + K·f(u) + w + g`, rounded to `quantum` when it
//! is not 0, with `f(u) = db(u, D₀)` and, within `|u_B|/2` of the base,
//! `f(u) = db(u_B, D₀) + db(u − u_B, D_B)`, where
//! `db(x, D) = sign(x)·max(|x| − D, 0)`. A dead band reaches 50 % of the
//! response at `2D`; against the K1 the reduction measures (the secant
//! `K(1 − D₀/u_B)`) at `D/(1 − 0.5(1 − D₀/u_B))`: the truth written.
//! With `quantum` at most the noise, the noise dithers the quantizer and
//! the plateau means stay linear. Deterministic for a seed.

use super::input::{write, Record, Sensor};
use crate::error::Result;
use crate::options::{check_range, invalid};
use crate::sim::{normal, rng};

/// The instrument simulated.
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
pub enum SimSensor {
    /// A gyro on a rate table (`rate_deg_s`, deg/s).
    #[default]
    Gyro,
    /// An accelerometer on a dividing head (`tilt_deg`, inputs in g).
    Accel,
}

impl From<SimSensor> for Sensor {
    fn from(s: SimSensor) -> Sensor {
        match s {
            SimSensor::Gyro => Sensor::Gyro,
            SimSensor::Accel => Sensor::Accel,
        }
    }
}

/// Options of `incal simulate threshold`, in engineering units (inputs in
/// deg/s for a gyro, g for an accelerometer; the base input in the input
/// column's units: deg/s, or deg of tilt).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThresholdSimOptions {
    /// Gyro or accelerometer (default gyro).
    #[serde(default)]
    pub sensor: SimSensor,
    /// Sampling rate (Hz; default 10).
    #[serde(default = "ten")]
    pub rate_hz: f64,
    /// Length of each plateau (s; default 30).
    #[serde(default = "thirty")]
    pub dwell_s: f64,
    /// Step sizes (input units; default gyro 0.001..0.05 deg/s,
    /// accelerometer 2e-6..1e-4 g).
    #[serde(default)]
    pub steps: Option<Vec<f64>>,
    /// Base input (deg/s, or deg of tilt; default 10 deg/s or 30 deg; 0:
    /// no steps at a base input).
    #[serde(default)]
    pub base_input: Option<f64>,
    /// Scale factor K (output per deg/s or per g; default 1).
    #[serde(default = "one")]
    pub scale_factor: f64,
    /// Bias (output units; default 0.01).
    #[serde(default = "hundredth")]
    pub bias: f64,
    /// Half-width of the dead band at zero `D₀` (input units; default
    /// 0.004 deg/s or 1e-5 g).
    #[serde(default)]
    pub dead_band: Option<f64>,
    /// Half-width of the dead band about the base input `D_B` (input
    /// units; default 0.002 deg/s or 5e-6 g).
    #[serde(default)]
    pub resolution_band: Option<f64>,
    /// White noise σ of one sample (output units; default 0.002 or 1e-5).
    #[serde(default)]
    pub noise: Option<f64>,
    /// Gauss–Markov noise σ (output units; default 0).
    #[serde(default)]
    pub gm_sigma: f64,
    /// Gauss–Markov correlation time (s; default 2).
    #[serde(default = "two")]
    pub gm_tau_s: f64,
    /// Output quantum (output units; default 0: none).
    #[serde(default)]
    pub quantum: f64,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

pub(super) fn ten() -> f64 {
    10.0
}
pub(super) fn thirty() -> f64 {
    30.0
}
pub(super) fn one() -> f64 {
    1.0
}
fn hundredth() -> f64 {
    0.01
}
pub(super) fn two() -> f64 {
    2.0
}
pub(super) fn seed_one() -> u64 {
    1
}

impl Default for ThresholdSimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

/// `sign(x)·max(|x| − d, 0)`.
pub fn dead_band(x: f64, d: f64) -> f64 {
    x.signum() * (x.abs() - d).max(0.0)
}

/// The settled values of a simulation's options (sensor defaults filled).
#[derive(Debug, Clone, PartialEq)]
pub struct Settled {
    /// Step sizes (input units).
    pub steps: Vec<f64>,
    /// Base input as commanded (deg/s or deg), 0 for none.
    pub base_command: f64,
    /// Base input (deg/s or g).
    pub base: f64,
    /// Dead bands at zero and about the base (input units).
    pub bands: (f64, f64),
    /// White noise σ.
    pub noise: f64,
}

impl ThresholdSimOptions {
    /// The options with the sensor's defaults filled, every range checked.
    pub fn settled(&self) -> Result<Settled> {
        let gyro = self.sensor == SimSensor::Gyro;
        let steps = self.steps.clone().unwrap_or_else(|| {
            let s = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0];
            let f = if gyro { 1e-3 } else { 2e-6 };
            s.iter().map(|v| v * f).collect()
        });
        let base_command = self.base_input.unwrap_or(if gyro { 10.0 } else { 30.0 });
        let limit = if gyro { 1e4 } else { 1.0 };
        if steps.is_empty() || steps.len() > 50 {
            return invalid("steps", format!("{} sizes: 1 to 50", steps.len()));
        }
        for s in &steps {
            check_range("steps", *s, 1e-12, limit / 4.0, "")?;
        }
        check_range(
            "base_input",
            base_command,
            if gyro { -1e4 } else { -80.0 },
            if gyro { 1e4 } else { 80.0 },
            "",
        )?;
        let base = if gyro {
            base_command
        } else {
            base_command.to_radians().sin()
        };
        let largest = steps.iter().fold(0.0f64, |a, b| a.max(*b));
        if base != 0.0 && largest >= base.abs() / 2.0 {
            return invalid("steps", format!("the largest step {largest} reaches half the base input {base}: the two levels' steps would overlap"));
        }
        if !gyro && base.abs() + largest >= 1.0 {
            return invalid("steps", "the base tilt plus the largest step passes 1 g");
        }
        let d0 = self.dead_band.unwrap_or(if gyro { 0.004 } else { 1e-5 });
        let db = self
            .resolution_band
            .unwrap_or(if gyro { 0.002 } else { 5e-6 });
        check_range("dead_band", d0, 0.0, limit, "")?;
        check_range("resolution_band", db, 0.0, limit, "")?;
        let noise = self.noise.unwrap_or(if gyro { 0.002 } else { 1e-5 });
        check_range("noise", noise, 0.0, 1e12, "")?;
        check_range("rate_hz", self.rate_hz, 1e-3, 1e6, "Hz")?;
        check_range("dwell_s", self.dwell_s, 1e-3, 1e7, "s")?;
        check_range("scale_factor", self.scale_factor, -1e12, 1e12, "")?;
        if self.scale_factor == 0.0 {
            return invalid("scale_factor", "zero");
        }
        check_range("bias", self.bias, -1e12, 1e12, "")?;
        check_range("gm_sigma", self.gm_sigma, 0.0, 1e12, "")?;
        check_range("gm_tau_s", self.gm_tau_s, 1e-6, 1e9, "s")?;
        check_range("quantum", self.quantum, 0.0, 1e12, "")?;
        let rows = (self.dwell_s * self.rate_hz).round();
        if rows < 4.0 {
            return invalid("dwell_s", format!("{rows} rows a plateau: at least 4"));
        }
        let plateaus = 1.0 + 4.0 * steps.len() as f64 * if base != 0.0 { 2.0 } else { 1.0 } + 1.0;
        crate::sim::check_rows(&[("plateaus x dwell_s x rate_hz", plateaus * rows)])?;
        Ok(Settled {
            steps,
            base_command,
            base,
            bands: (d0, db),
            noise,
        })
    }

    /// The commanded inputs, plateau by plateau (input units).
    fn sequence(&self, s: &Settled) -> Vec<f64> {
        let mut u = vec![0.0];
        for d in &s.steps {
            u.extend([*d, 0.0, -d, 0.0]);
        }
        if s.base != 0.0 {
            u.push(s.base);
            for d in &s.steps {
                u.extend([s.base + d, s.base, s.base - d, s.base]);
            }
        }
        u
    }

    /// The response `f(u)` (module docs).
    fn response(&self, s: &Settled, u: f64) -> f64 {
        if s.base != 0.0 && (u - s.base).abs() < s.base.abs() / 2.0 {
            dead_band(s.base, s.bands.0) + dead_band(u - s.base, s.bands.1)
        } else {
            dead_band(u, s.bands.0)
        }
    }

    /// The simulated record.
    pub fn record(&self) -> Result<Record> {
        let s = self.settled()?;
        let sensor: Sensor = self.sensor.into();
        let rows = (self.dwell_s * self.rate_hz).round() as usize;
        let dt = 1.0 / self.rate_hz;
        let mut r = rng(self.seed);
        let phi = (-dt / self.gm_tau_s).exp();
        let drive = self.gm_sigma * (1.0 - phi * phi).sqrt();
        let mut g = normal(&mut r, self.gm_sigma);
        let mut rec = Record {
            sensor,
            command: Vec::new(),
            output: Vec::new(),
            time_s: Some(Vec::new()),
            lines: Vec::new(),
        };
        for u in self.sequence(&s) {
            let command = match sensor {
                Sensor::Gyro => u,
                // The base plateaus keep the commanded tilt as given.
                Sensor::Accel if s.base != 0.0 && u == s.base => s.base_command,
                Sensor::Accel => u.asin().to_degrees(),
            };
            let input = match sensor {
                Sensor::Gyro => u,
                Sensor::Accel => command.to_radians().sin(),
            };
            let level = self.bias + self.scale_factor * self.response(&s, input);
            for _ in 0..rows {
                let k = rec.output.len();
                g = phi * g + normal(&mut r, drive);
                let mut y = level + normal(&mut r, s.noise) + g;
                if self.quantum > 0.0 {
                    y = self.quantum * (y / self.quantum).round();
                }
                if let Some(t) = rec.time_s.as_mut() {
                    t.push(k as f64 * dt);
                }
                rec.command.push(command);
                rec.output.push(y);
                rec.lines.push(k + 2);
            }
        }
        Ok(rec)
    }

    /// The truth as JSON: the 50 % points the reduction estimates with
    /// its measured K1 (module docs), the dead bands, the scale factor
    /// and the measured secant.
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        let s = self.settled()?;
        let sensor: Sensor = self.sensor.into();
        let eps = if s.base != 0.0 {
            s.bands.0 / s.base.abs()
        } else {
            0.0
        };
        let at = |d: f64| d / (1.0 - 0.5 * (1.0 - eps));
        let mut t = serde_json::Map::new();
        let sfx = sensor.suffix();
        t.insert(format!("threshold_{sfx}"), at(s.bands.0).into());
        if s.base != 0.0 {
            t.insert(format!("resolution_{sfx}"), at(s.bands.1).into());
            t.insert("K1".into(), (self.scale_factor * (1.0 - eps)).into());
        }
        t.insert("dead_band".into(), s.bands.0.into());
        t.insert("resolution_band".into(), s.bands.1.into());
        t.insert("scale_factor".into(), self.scale_factor.into());
        Ok(serde_json::Value::Object(t))
    }
}

impl crate::procedures::Simulate for super::Threshold {
    type Options = ThresholdSimOptions;

    fn validate(o: &ThresholdSimOptions) -> Result<()> {
        o.settled().map(|_| ())
    }

    fn simulate(o: &ThresholdSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.record()?, out)?;
        Ok(())
    }

    fn truth(o: &ThresholdSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
