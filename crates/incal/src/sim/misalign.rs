//! Misalignment simulators (seed 003): a gyro on a rate table with Earth
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

use super::{normal, rng};
use crate::error::Result;
use crate::procedures::misalign::accel::AccelObservation;
use crate::procedures::misalign::averaging::{average_records, RawSample, Record, TurnPolicy};
use crate::procedures::misalign::gyro::{GyroConfig, GyroObservation};
use crate::rigs::rate_table::{
    face_specific_force_g, gyro_rates_deg_s, FaceMounting, GyroMounting,
};
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

/// Simulate raw records (deterministic for a given seed).
pub fn simulate_gyro_records(cfg: &GyroSim) -> Vec<Record> {
    let mut r = rng(cfg.seed);
    let per_turn = cfg.samples_per_turn.max(2);
    let m = ((cfg.turns.max(0.0) * per_turn as f64).round() as usize).max(2);
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
