//! Misalignment simulators (Li et al. 2012): a gyro on a rate table with Earth
//! rate, and an accelerometer on a vertical reference face. The kinematics
//! are the exact rotation chains of [`crate::rigs::rate_table`], not the
//! linearised model the procedures fit, so a round trip also checks the
//! linearisation.
//!
//! Gyro: for each configuration, rate magnitude, sign and record, the table
//! turns `turns` revolutions from a random start angle, sampled
//! `samples_per_turn` times per turn at equal angle steps; each sample is
//! `V = V0 + b_c + kI ω_I + n`, `n ~ N(0, σ²)`, with `b_c ~ N(0, σ_b²)` one
//! bias shift per configuration (re-mounting). The reduced file holds the
//! plain mean of each record ([`TurnPolicy::All`]), so a non-whole number
//! of turns shows the Earth-rate error.
//!
//! Accelerometer: `V = V0 + kI a_I(β) + n` at each β, `samples` per angle.

use crate::error::{Error, Result};
use crate::procedures::misalign::accel::AccelObservation;
use crate::procedures::misalign::averaging::{average_records, RawSample, Record, TurnPolicy};
use crate::procedures::misalign::gyro::{GyroConfig, GyroObservation};
use crate::rigs::rate_table::{
    face_specific_force_g, gyro_rates_deg_s, FaceMounting, GyroMounting,
};
use crate::sim::{check_rows, normal, rng};
use rand::RngExt;

/// Configuration of a simulated gyro misalignment test.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroSim {
    /// True mounting angles (rad).
    pub mounting: GyroMounting,
    /// Scale factor kI (output per °/s).
    pub scale_factor: f64,
    /// Bias V0 (output).
    pub bias: f64,
    /// σ of the bias shift per configuration (output).
    pub bias_shift: f64,
    /// Configurations, in test order.
    pub configs: Vec<GyroConfig>,
    /// Rate magnitudes (°/s); each is run forward then reverse.
    pub rates_deg_s: Vec<f64>,
    /// Records per configuration and signed rate.
    pub records: usize,
    /// Revolutions per record (need not be whole).
    pub turns: f64,
    /// Samples per revolution.
    pub samples_per_turn: usize,
    /// Output noise σ of one sample.
    pub noise: f64,
    /// Latitude φ (rad).
    pub latitude_rad: f64,
    /// Random seed.
    pub seed: u64,
}

/// Largest angle of a plan (deg, in magnitude): beyond it an angle is a typo.
pub const MAX_PLAN_ANGLE_DEG: f64 = 1e4;

/// Largest number of table revolutions per simulated record.
pub const MAX_TURNS: f64 = 1000.0;

fn finite_all(values: &[(&str, f64)]) -> Result<()> {
    for (n, v) in values {
        if !v.is_finite() {
            return Error::invalid(format!("{n} (a finite number)"), v);
        }
    }
    Ok(())
}

fn plan_angle(what: &str, rad: f64) -> Result<()> {
    let d = rad.to_degrees();
    if d.is_finite() && d.abs() <= MAX_PLAN_ANGLE_DEG {
        Ok(())
    } else {
        Error::invalid(format!("{what} (|angle| <= 1e4 deg)"), d)
    }
}

fn non_negative(what: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Error::invalid(format!("{what} (a non-negative number)"), v)
    }
}

impl GyroSim {
    /// Samples in one record: `max(2, round(turns · samples_per_turn))`.
    pub fn samples_per_record(&self) -> usize {
        ((self.turns.max(0.0) * self.samples_per_turn.max(2) as f64).round() as usize).max(2)
    }

    /// Refuse a configuration that cannot be simulated: a negative noise or
    /// bias shift, no configuration or rate, a rate magnitude not positive,
    /// turns not within (0, 1000], no record, fewer than 2 samples per
    /// turn, a latitude beyond ±90°, a non-finite truth, or more than
    /// [`crate::sim::MAX_SIM_ROWS`] samples (held in memory, whichever
    /// layout is written).
    pub fn validate(&self) -> Result<()> {
        non_negative("noise", self.noise)?;
        non_negative("bias_shift", self.bias_shift)?;
        if self.configs.is_empty() {
            return Error::invalid("configs (at least one ALPHA:BETA)", "none");
        }
        for c in &self.configs {
            plan_angle("configs", c.alpha_rad)?;
            plan_angle("configs", c.beta_rad)?;
        }
        if self.rates_deg_s.is_empty() {
            return Error::invalid("rates_deg_s (at least one rate)", "none");
        }
        for r in &self.rates_deg_s {
            if !(r.is_finite() && *r > 0.0) {
                return Error::invalid("rates_deg_s (rate magnitudes must be positive)", r);
            }
        }
        if !(self.turns.is_finite() && self.turns > 0.0 && self.turns <= MAX_TURNS) {
            return Error::invalid(
                "turns (revolutions per record, positive, at most 1000)",
                self.turns,
            );
        }
        if self.records == 0 {
            return Error::invalid("records (at least 1)", 0);
        }
        if self.samples_per_turn < 2 {
            return Error::invalid("samples_per_turn (at least 2)", self.samples_per_turn);
        }
        let lat = self.latitude_rad.to_degrees();
        if !(lat.is_finite() && lat.abs() <= 90.0) {
            return Error::invalid("latitude_deg (within -90..90)", lat);
        }
        if self.scale_factor == 0.0 {
            return Error::invalid("scale_factor (non-zero: a dead instrument)", 0);
        }
        let m = &self.mounting;
        finite_all(&[
            ("scale_factor", self.scale_factor),
            ("bias", self.bias),
            ("dtheta_x0", m.dtheta_x0),
            ("dtheta_y0", m.dtheta_y0),
            ("dtheta_y1", m.dtheta_y1),
            ("dtheta_z1", m.dtheta_z1),
            ("dtheta_y2", m.dtheta_y2),
            ("dtheta_z2", m.dtheta_z2),
        ])?;
        check_rows(&[
            ("configurations", self.configs.len() as f64),
            ("rates x 2 signs", 2.0 * self.rates_deg_s.len() as f64),
            ("records", self.records as f64),
            (
                "samples per record",
                (self.turns * self.samples_per_turn as f64).round().max(2.0),
            ),
        ])
    }
}

/// Simulate raw records (deterministic for a given seed).
pub fn simulate_gyro_records(cfg: &GyroSim) -> Vec<Record> {
    let mut r = rng(cfg.seed);
    let per_turn = cfg.samples_per_turn.max(2);
    let m = cfg.samples_per_record();
    let mut out = Vec::new();
    for c in &cfg.configs {
        let shift = normal(&mut r, cfg.bias_shift);
        for &w in &cfg.rates_deg_s {
            for sign in [1.0, -1.0] {
                let rate = sign * w.abs();
                for _ in 0..cfg.records.max(1) {
                    let start = r.random::<f64>() * std::f64::consts::TAU;
                    let step = sign * std::f64::consts::TAU / per_turn as f64;
                    let dt = step.to_degrees() / rate;
                    let samples = (0..m)
                        .map(|k| {
                            let gamma = start + k as f64 * step;
                            let wi = gyro_rates_deg_s(
                                &cfg.mounting,
                                c.alpha_rad,
                                c.beta_rad,
                                gamma,
                                rate,
                                cfg.latitude_rad,
                            )[0];
                            RawSample {
                                time_s: k as f64 * dt,
                                table_angle_rad: gamma.rem_euclid(std::f64::consts::TAU),
                                output: cfg.bias
                                    + shift
                                    + cfg.scale_factor * wi
                                    + normal(&mut r, cfg.noise),
                            }
                        })
                        .collect();
                    out.push(Record {
                        config: *c,
                        rate_deg_s: rate,
                        samples,
                    });
                }
            }
        }
    }
    out
}

/// Simulate record means (plain mean of every sample, module docs).
pub fn simulate_gyro(cfg: &GyroSim) -> Result<Vec<GyroObservation>> {
    Ok(
        average_records(&simulate_gyro_records(cfg), TurnPolicy::All)?
            .into_iter()
            .map(|m| m.observation)
            .collect(),
    )
}

/// Configuration of a simulated accelerometer test on a vertical face.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelSim {
    /// True mounting angles (rad).
    pub mounting: FaceMounting,
    /// Scale factor kI (output per g).
    pub scale_factor: f64,
    /// Bias V0 (output).
    pub bias: f64,
    /// Angles β (rad), in test order.
    pub betas_rad: Vec<f64>,
    /// Samples per angle.
    pub samples: usize,
    /// Output noise σ of one sample.
    pub noise: f64,
    /// Random seed.
    pub seed: u64,
}

impl AccelSim {
    /// Refuse a configuration that cannot be simulated: a negative noise,
    /// no angle or an angle beyond 1e4 deg, no sample, a non-finite truth,
    /// or more than [`crate::sim::MAX_SIM_ROWS`] rows.
    pub fn validate(&self) -> Result<()> {
        non_negative("noise", self.noise)?;
        if self.betas_rad.is_empty() {
            return Error::invalid("betas_deg (at least one angle)", "none");
        }
        for b in &self.betas_rad {
            plan_angle("betas_deg", *b)?;
        }
        if self.samples == 0 {
            return Error::invalid("samples (at least 1 per angle)", 0);
        }
        if self.scale_factor == 0.0 {
            return Error::invalid("scale_factor (non-zero: a dead instrument)", 0);
        }
        let m = &self.mounting;
        finite_all(&[
            ("scale_factor", self.scale_factor),
            ("bias", self.bias),
            ("dtheta_y0", m.dtheta_y0),
            ("dtheta_y1", m.dtheta_y1),
            ("dtheta_y2", m.dtheta_y2),
            ("dtheta_z2", m.dtheta_z2),
        ])?;
        check_rows(&[
            ("angles", self.betas_rad.len() as f64),
            ("samples", self.samples as f64),
        ])
    }
}

/// Simulate accelerometer outputs (deterministic for a given seed).
pub fn simulate_accel(cfg: &AccelSim) -> Vec<AccelObservation> {
    let mut r = rng(cfg.seed);
    let mut out = Vec::new();
    for &b in &cfg.betas_rad {
        let a_i = face_specific_force_g(&cfg.mounting, b)[0];
        for _ in 0..cfg.samples.max(1) {
            out.push(AccelObservation {
                beta_rad: b,
                output: cfg.bias + cfg.scale_factor * a_i + normal(&mut r, cfg.noise),
            });
        }
    }
    out
}
