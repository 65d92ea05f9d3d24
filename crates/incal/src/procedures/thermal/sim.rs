//! Thermal simulator: a chamber profile, a sensor that lags it, and
//! channels whose bias follows known polynomials in the sensor's
//! temperature with hysteresis, written in the input format of
//! [`super::ramp`] (`incal simulate thermal`).
//!
//! # Profile
//! The chamber holds each of its set points `hold_s` and moves between
//! them at `ramp_c_per_min`: a ramp is low, high, low; a soak sequence
//! steps through plateaus (and may return). The
//! sensor follows as a first-order lag `dT_s/dt = (T_c − T_s)/τ`,
//! integrated exactly per sample for a chamber linear over the step:
//! `T_s ← T_c − sτ + (T_s0 − T_c0 + sτ) e^{−Δt/τ}`, `s` the chamber's
//! slope over the step.
//!
//! # Channels
//! `y = Σ c_k (T_s − T_ref)^k + (h/2) b + n`, `n ~ N(0, σ²)`, where the
//! branch `b` is +1 once the sensor heats faster than a quarter of the
//! ramp rate, −1 once it cools as fast, and keeps its value through a
//! hold (0 before the first movement). The written `temperature_c` is
//! `T_s` plus `N(0, σ_T²)`.

use std::io::Write;

use schemars::JsonSchema;
use serde::Serialize;

use super::poly;
use crate::error::{Error, Result};
use crate::sim::{normal, rng};

/// The truth of one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelTruth {
    /// Column name.
    pub name: String,
    /// `c_0…c_d` about `T_ref` (unit per °C^k).
    pub c: Vec<f64>,
    /// Heating branch minus cooling branch.
    pub hysteresis: f64,
    /// White noise σ of one sample.
    pub noise: f64,
}

/// A simulated chamber ramp.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RampSim {
    /// Channels.
    pub channels: Vec<ChannelTruth>,
    /// Unit of the channels (for the truth file).
    pub unit: String,
    /// `T_ref` of the truth polynomials, °C.
    pub t_ref_c: f64,
    /// The chamber's set points in order, °C: held `hold_s` each, moved
    /// between at `ramp_c_per_min`. A ramp is `[low, high, low]`; a soak
    /// sequence the plateaus (`[-40, -10, 25, 60, 85, 25]`).
    pub waypoints_c: Vec<f64>,
    /// Ramp rate of the chamber, °C/min.
    pub ramp_c_per_min: f64,
    /// Hold at each end, s.
    pub hold_s: f64,
    /// Sensor lag τ behind the chamber, s.
    pub lag_s: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Noise of the temperature reading, °C.
    pub temperature_noise_c: f64,
    /// Random seed.
    pub seed: u64,
}

impl RampSim {
    /// The profile's segments: `(start_s, duration_s, from_c, to_c)`,
    /// holds (from = to) and moves alternating.
    fn segments(&self) -> Vec<(f64, f64, f64, f64)> {
        let mut out = Vec::new();
        let mut t = 0.0;
        for (i, &w) in self.waypoints_c.iter().enumerate() {
            if i > 0 {
                let from = self.waypoints_c[i - 1];
                let d = (w - from).abs() / (self.ramp_c_per_min / 60.0);
                out.push((t, d, from, w));
                t += d;
            }
            out.push((t, self.hold_s, w, w));
            t += self.hold_s;
        }
        out
    }

    /// Duration of the profile, s.
    pub fn duration_s(&self) -> f64 {
        self.segments()
            .last()
            .map_or(0.0, |(start, d, _, _)| start + d)
    }

    /// Rows the simulation writes.
    pub fn rows(&self) -> u64 {
        (self.duration_s() * self.rate_hz).floor() as u64
    }

    /// Refuse what cannot be simulated.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &str, v: f64| {
            Err(Error::InvalidValue {
                what: what.into(),
                value: v.to_string(),
            })
        };
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return bad("rate_hz (above 0)", self.rate_hz);
        }
        if !(self.ramp_c_per_min.is_finite() && self.ramp_c_per_min > 0.0) {
            return bad("ramp_c_per_min (above 0)", self.ramp_c_per_min);
        }
        if !(self.hold_s.is_finite() && self.hold_s >= 0.0) {
            return bad("hold_s (0 or more)", self.hold_s);
        }
        if !(self.lag_s.is_finite() && self.lag_s >= 0.0) {
            return bad("lag_s (0 or more)", self.lag_s);
        }
        if !(self.temperature_noise_c.is_finite() && self.temperature_noise_c >= 0.0) {
            return bad("temperature noise (0 or more)", self.temperature_noise_c);
        }
        for &t in self.waypoints_c.iter().chain([&self.t_ref_c]) {
            if !(t.is_finite() && (-273.15..=1000.0).contains(&t)) {
                return bad("temperature (degC)", t);
            }
        }
        if self.waypoints_c.len() < 2 {
            return Err(Error::TooFew {
                what: "chamber set points".into(),
                needed: 2,
                got: self.waypoints_c.len(),
            });
        }
        if self.channels.is_empty() {
            return Err(Error::TooFew {
                what: "channels".into(),
                needed: 1,
                got: 0,
            });
        }
        for c in &self.channels {
            if c.c.is_empty() || c.c.len() > super::MAX_DEGREE + 1 {
                return Err(Error::Unsupported(format!(
                    "channel {}: 1 to {} polynomial coefficients",
                    c.name,
                    super::MAX_DEGREE + 1
                )));
            }
            if c.c.iter().any(|v| !v.is_finite()) || !c.hysteresis.is_finite() {
                return bad("truth coefficient", f64::NAN);
            }
            if !(c.noise.is_finite() && c.noise > 0.0) {
                return bad("channel noise (above 0)", c.noise);
            }
        }
        crate::sim::check_rows(&[
            ("`duration_s`", self.duration_s()),
            ("`rate_hz`", self.rate_hz),
        ])
    }

    /// The chamber temperature at time `t` (s).
    pub fn chamber_c(&self, t: f64) -> f64 {
        let segs = self.segments();
        for &(start, d, from, to) in &segs {
            if t < start + d {
                return if d > 0.0 {
                    from + (to - from) * ((t - start) / d).clamp(0.0, 1.0)
                } else {
                    to
                };
            }
        }
        self.waypoints_c.last().copied().unwrap_or(0.0)
    }

    /// Write the recording (`time_s,chamber_c,temperature_c,<channels>`).
    pub fn write<W: Write>(&self, out: W) -> Result<()> {
        self.validate()?;
        let io = Error::from;
        let mut header = vec!["time_s", "chamber_c", "temperature_c"];
        header.extend(self.channels.iter().map(|c| c.name.as_str()));
        let mut w = incal_io::writer::CsvWriter::new(out, &header).map_err(io)?;
        let mut r = rng(self.seed);
        let dt = 1.0 / self.rate_hz;
        let decay = if self.lag_s > 0.0 {
            (-dt / self.lag_s).exp()
        } else {
            0.0
        };
        let threshold = 0.25 * self.ramp_c_per_min / 60.0;
        let mut ts = self.waypoints_c[0];
        let mut branch = 0.0;
        let mut cells = Vec::with_capacity(header.len());
        for i in 0..self.rows() {
            let t = i as f64 * dt;
            let tc = self.chamber_c(t);
            if i > 0 {
                let before = ts;
                // Exact for a chamber linear over the step (first-order
                // hold): T_s = T_c − sτ + (T_s0 − T_c0 + sτ) e^{−Δt/τ}.
                let tc0 = self.chamber_c(t - dt);
                let s_tau = (tc - tc0) / dt * self.lag_s;
                ts = tc - s_tau + (ts - tc0 + s_tau) * decay;
                let rate = (ts - before) / dt;
                if rate > threshold {
                    branch = 1.0;
                } else if rate < -threshold {
                    branch = -1.0;
                }
            }
            cells.clear();
            let reading = ts + normal(&mut r, self.temperature_noise_c);
            cells.extend([t, tc, reading]);
            for c in &self.channels {
                let y = poly(&c.c, self.t_ref_c, ts)
                    + 0.5 * c.hysteresis * branch
                    + normal(&mut r, c.noise);
                cells.push(y);
            }
            let row: Vec<incal_io::writer::Cell> = cells
                .iter()
                .map(|&x| incal_io::writer::Cell::Num(x))
                .collect();
            w.row(&row).map_err(io)?;
        }
        w.finish().map_err(io)?;
        Ok(())
    }

    /// The truth as JSON (`--truth-out`): `t_ref_c`, `lag_s`, `unit` and
    /// per channel `c`, `hysteresis`, `noise`.
    pub fn truth_json(&self) -> serde_json::Value {
        let channels: serde_json::Map<String, serde_json::Value> = self
            .channels
            .iter()
            .map(|c| {
                (
                    c.name.clone(),
                    serde_json::json!({"c": c.c, "hysteresis": c.hysteresis, "noise": c.noise}),
                )
            })
            .collect();
        serde_json::json!({
            "t_ref_c": self.t_ref_c,
            "lag_s": self.lag_s,
            "unit": self.unit,
            "channels": channels,
        })
    }
}

/// A default truth for `n` channels called `names`: biases with a
/// quadratic temperature dependence and hysteresis, in `unit` at the
/// magnitudes of a MEMS sensor (`deg/s` gyro or `g` accelerometer).
pub fn default_channels(names: &[String], gyro: bool) -> Vec<ChannelTruth> {
    names
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let s = 1.0 + 0.3 * i as f64;
            if gyro {
                ChannelTruth {
                    name: n.clone(),
                    c: vec![0.05 * s, 2e-3 * s, -3e-5 * s],
                    hysteresis: 0.01 * s,
                    noise: 0.02,
                }
            } else {
                ChannelTruth {
                    name: n.clone(),
                    c: vec![1e-3 * s, 5e-5 * s, -6e-7 * s],
                    hysteresis: 2e-4 * s,
                    noise: 5e-4,
                }
            }
        })
        .collect()
}

/// What a simulated chamber ramp measures.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize, JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SimQuantity {
    /// Gyro: channels gx, gy, gz in deg/s.
    #[default]
    Gyro,
    /// Accelerometer: channels ax, ay, az in g.
    Accel,
}

/// The options of `incal simulate thermal`, typed once for every front
/// end (the command line's defaults): the chamber profile (hold, heat,
/// hold, cool, hold between `t_low_c` and `t_high_c`, or a soak sequence
/// `plateaus_c`), the sensor's lag, the sample rate and the seed; the
/// truth is [`default_channels`] of the quantity.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, JsonSchema)]
pub struct ThermalSimOptions {
    /// What the channels measure.
    #[serde(default)]
    pub quantity: SimQuantity,
    /// Low temperature of the ramp profile, °C.
    #[serde(default = "d_t_low")]
    pub t_low_c: f64,
    /// High temperature of the ramp profile, °C.
    #[serde(default = "d_t_high")]
    pub t_high_c: f64,
    /// A soak sequence instead of the ramp: the chamber's plateaus in
    /// order, °C (then `t_low_c` and `t_high_c` are not used).
    #[serde(default)]
    pub plateaus_c: Option<Vec<f64>>,
    /// Ramp rate of the chamber, °C/min.
    #[serde(default = "d_ramp")]
    pub ramp_c_per_min: f64,
    /// Hold at the start, at each turn and at the end, s.
    #[serde(default = "d_hold")]
    pub hold_s: f64,
    /// The sensor's first-order lag behind the chamber, s.
    #[serde(default = "d_lag")]
    pub lag_s: f64,
    /// Sample rate, Hz.
    #[serde(default = "d_rate")]
    pub rate_hz: f64,
    /// Noise of the temperature reading, °C.
    #[serde(default)]
    pub temperature_noise_c: f64,
    /// Reference temperature of the truth polynomials, °C.
    #[serde(default = "d_t_ref")]
    pub t_ref_c: f64,
    /// Random seed.
    pub seed: u64,
}

fn d_t_low() -> f64 {
    -20.0
}
fn d_t_high() -> f64 {
    60.0
}
fn d_ramp() -> f64 {
    1.0
}
fn d_hold() -> f64 {
    1800.0
}
fn d_lag() -> f64 {
    120.0
}
fn d_rate() -> f64 {
    10.0
}
fn d_t_ref() -> f64 {
    super::DEFAULT_T_REF_C
}

/// A chamber's temperature profile as a plan or a simulation gives it.
pub(crate) struct Profile<'a> {
    pub plateaus_c: Option<&'a [f64]>,
    pub t_low_c: f64,
    pub t_high_c: f64,
    pub ramp_c_per_min: Option<f64>,
    pub hold_s: f64,
    pub lag_s: f64,
}

/// The physical bounds of a chamber profile, naming the key: every
/// temperature within absolute zero to 1000 °C, `t_low_c` below
/// `t_high_c` (a ramp), a ramp rate above 0 and at most 100 °C/min, a hold
/// and a sensor lag of at most a week.
pub(crate) fn check_profile(p: &Profile<'_>) -> Result<()> {
    use crate::options::{check_range, invalid};
    use crate::units::check_temperature_c;
    check_temperature_c("t_low_c", p.t_low_c)?;
    check_temperature_c("t_high_c", p.t_high_c)?;
    match p.plateaus_c {
        Some(plateaus) => {
            for &t in plateaus {
                check_temperature_c("plateaus_c", t)?;
            }
        }
        None if p.t_low_c >= p.t_high_c => {
            return invalid(
                "t_low_c",
                format!(
                    "{} degC is not below the high temperature {} degC",
                    p.t_low_c, p.t_high_c
                ),
            );
        }
        None => {}
    }
    const WEEK_S: f64 = 7.0 * 86400.0;
    if let Some(r) = p.ramp_c_per_min {
        if !(r.is_finite() && r > 0.0) {
            return invalid("ramp_c_per_min", format!("must be above 0, got {r}"));
        }
        check_range("ramp_c_per_min", r, 0.0, 100.0, "degC/min")?;
    }
    check_range("hold_s", p.hold_s, 0.0, WEEK_S, "s")?;
    check_range("lag_s", p.lag_s, 0.0, WEEK_S, "s")
}

impl ThermalSimOptions {
    /// Physical bounds, naming the key: temperatures not below absolute
    /// zero, `t_low_c` below `t_high_c`, a chamber's ramp rate (0 to
    /// 100 °C/min), a hold and a lag of at most a week, a rate of at most
    /// 10 kHz, and at most 10⁸ samples in all.
    pub fn check(&self) -> Result<()> {
        use crate::options::{check_range, invalid};
        check_profile(&Profile {
            plateaus_c: self.plateaus_c.as_deref(),
            t_low_c: self.t_low_c,
            t_high_c: self.t_high_c,
            ramp_c_per_min: Some(self.ramp_c_per_min),
            hold_s: self.hold_s,
            lag_s: self.lag_s,
        })?;
        crate::units::check_temperature_c("t_ref_c", self.t_ref_c)?;
        check_range("rate_hz", self.rate_hz, 0.0, 1e4, "Hz")?;
        check_range(
            "temperature_noise_c",
            self.temperature_noise_c,
            0.0,
            100.0,
            "degC",
        )?;
        let c = self.config();
        let span: f64 = c.waypoints_c.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
        let duration_s =
            span / self.ramp_c_per_min * 60.0 + self.hold_s * c.waypoints_c.len() as f64;
        if duration_s * self.rate_hz > 1e8 {
            return invalid(
                "rate_hz",
                format!(
                    "{:.3e} samples over the profile's {duration_s:.0} s: at most 1e8",
                    duration_s * self.rate_hz
                ),
            );
        }
        Ok(())
    }

    /// The simulator's configuration ([`RampSim`]).
    pub fn config(&self) -> RampSim {
        let gyro = self.quantity == SimQuantity::Gyro;
        let names: Vec<String> = if gyro {
            ["gx", "gy", "gz"]
        } else {
            ["ax", "ay", "az"]
        }
        .iter()
        .map(|s| s.to_string())
        .collect();
        RampSim {
            channels: default_channels(&names, gyro),
            unit: if gyro { "deg/s" } else { "g" }.into(),
            t_ref_c: self.t_ref_c,
            waypoints_c: match &self.plateaus_c {
                Some(p) => p.clone(),
                None => vec![self.t_low_c, self.t_high_c, self.t_low_c],
            },
            ramp_c_per_min: self.ramp_c_per_min,
            hold_s: self.hold_s,
            lag_s: self.lag_s,
            rate_hz: self.rate_hz,
            temperature_noise_c: self.temperature_noise_c,
            seed: self.seed,
        }
    }
}

impl crate::procedures::Simulate for super::ramp::Ramp {
    type Options = ThermalSimOptions;

    fn validate(o: &ThermalSimOptions) -> Result<()> {
        o.check()?;
        o.config().validate()
    }

    fn simulate(o: &ThermalSimOptions, out: &mut dyn Write) -> Result<()> {
        o.config().write(out)
    }

    /// The truth polynomials, hysteresis and lag ([`RampSim::truth_json`]).
    fn truth(o: &ThermalSimOptions) -> Result<Option<serde_json::Value>> {
        let cfg = o.config();
        cfg.validate()?;
        Ok(Some(cfg.truth_json()))
    }
}
