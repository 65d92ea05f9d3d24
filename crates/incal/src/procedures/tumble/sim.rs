//! Dividing-head tumble simulator: a truth model, a mount and a plan give
//! observations in the input format of [`crate::procedures::tumble`].
//!
//! Each visit of a position draws one index-angle error `ε ~ N(0, σ_ε²)`
//! (the head stops at θ + ε), then `samples` outputs
//! `E = E_truth(θ + ε) + n`, `n ~ N(0, σ_n²)`. With two passes the second
//! visits the angles in reverse order (counter-clockwise) with fresh index
//! errors, labelled `cw` and `ccw` as in seed 000 §2.2.

use crate::models::AccelerometerModel;
use crate::procedures::tumble::Observation;
use crate::rigs::Mount;
use crate::sim::{normal, rng};

/// Configuration of a simulated tumble test.
#[derive(Debug, Clone, PartialEq)]
pub struct TumbleSim {
    /// True instrument.
    pub truth: AccelerometerModel,
    /// Mount on the head.
    pub mount: Mount,
    /// Nominal head angles (deg), in test order.
    pub angles_deg: Vec<f64>,
    /// Samples per position (≥ 1).
    pub samples: usize,
    /// Output noise σ of one sample (output units).
    pub noise: f64,
    /// Index-angle error σ (rad), one draw per visit.
    pub index_error_rad: f64,
    /// Number of passes: 1, or 2 (cw then ccw).
    pub passes: usize,
    /// Random seed.
    pub seed: u64,
}

/// Simulate the observations (deterministic for a given seed).
pub fn simulate(cfg: &TumbleSim) -> Vec<Observation> {
    let mut r = rng(cfg.seed);
    let mut out = Vec::with_capacity(cfg.angles_deg.len() * cfg.samples.max(1) * cfg.passes.max(1));
    for pass in 0..cfg.passes.max(1) {
        let label = match (cfg.passes > 1, pass) {
            (false, _) => None,
            (true, 0) => Some("cw".to_string()),
            (true, 1) => Some("ccw".to_string()),
            (true, k) => Some(format!("pass{}", k + 1)),
        };
        let order: Vec<f64> = if pass % 2 == 0 {
            cfg.angles_deg.clone()
        } else {
            cfg.angles_deg.iter().rev().copied().collect()
        };
        for angle_deg in order {
            let theta = angle_deg.to_radians();
            let eps = normal(&mut r, cfg.index_error_rad);
            let e0 = cfg.truth.output(&cfg.mount.specific_force(theta + eps));
            for _ in 0..cfg.samples.max(1) {
                out.push(Observation {
                    angle_rad: theta,
                    output: e0 + normal(&mut r, cfg.noise),
                    pass: label.clone(),
                });
            }
        }
    }
    out
}
