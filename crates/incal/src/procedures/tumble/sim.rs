//! Dividing-head tumble simulator: a truth model, a mount and a plan give
//! observations in the input format of [`crate::procedures::tumble`].
//!
//! Each visit of a position draws one index-angle error `ε ~ N(0, σ_ε²)`
//! (the head stops at θ + ε), then `samples` outputs
//! `E = E_truth(θ + ε) + n`, `n ~ N(0, σ_n²)`. With two passes the second
//! visits the angles in reverse order (counter-clockwise) with fresh index
//! errors, labelled `cw` and `ccw` as in Wu et al. 2015 §2.2.

use crate::error::{Error, Result};
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

impl TumbleSim {
    /// Refuse a configuration that cannot be simulated: no samples, a pass
    /// count other than 1 or 2, a negative or non-finite noise or index
    /// error, more than [`crate::sim::MAX_SIM_ROWS`] rows, or a truth whose
    /// output is not finite at some angle.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &str, v: String| {
            Err(Error::InvalidValue {
                what: what.into(),
                value: v,
            })
        };
        if self.samples == 0 {
            return bad("samples (at least 1 per position)", "0".into());
        }
        if !(1..=2).contains(&self.passes) {
            return bad("passes (1 or 2)", self.passes.to_string());
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return bad("noise (a non-negative number)", self.noise.to_string());
        }
        if !(self.index_error_rad.is_finite() && self.index_error_rad >= 0.0) {
            return bad(
                "index error (a non-negative number)",
                self.index_error_rad.to_string(),
            );
        }
        if self.angles_deg.is_empty() {
            return bad("angles (at least one)", "none".into());
        }
        crate::sim::check_rows(&[
            ("samples", self.samples as f64),
            ("angles", self.angles_deg.len() as f64),
            ("passes", self.passes as f64),
        ])?;
        self.truth.validate()?;
        for a in &self.angles_deg {
            let e = self
                .truth
                .output(&self.mount.specific_force(a.to_radians()));
            if !e.is_finite() {
                return bad("truth (its output is not finite)", format!("at {a} deg"));
            }
        }
        Ok(())
    }
}

/// Simulate the observations (deterministic for a given seed).
pub fn simulate(cfg: &TumbleSim) -> Vec<Observation> {
    let mut out = Vec::with_capacity(cfg.angles_deg.len() * cfg.samples.max(1) * cfg.passes.max(1));
    let _ = for_each(cfg, |o| {
        out.push(o);
        Ok(())
    });
    out
}

/// Each simulated observation in turn, in the order [`simulate`] gives
/// them, without holding them: a simulation of any allowed size in
/// constant memory. Stops at the first error of `f`.
pub fn for_each(
    cfg: &TumbleSim,
    mut f: impl FnMut(Observation) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let mut r = rng(cfg.seed);
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
                f(Observation {
                    angle_rad: theta,
                    output: e0 + normal(&mut r, cfg.noise),
                    pass: label.clone(),
                })?;
            }
        }
    }
    Ok(())
}
