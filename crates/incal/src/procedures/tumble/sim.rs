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
        use crate::options::invalid;
        if self.samples == 0 {
            return invalid("samples", "at least 1 per position, got 0");
        }
        if !(1..=2).contains(&self.passes) {
            return invalid("passes", format!("1 or 2, got {}", self.passes));
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return invalid(
                "noise",
                format!("must be a non-negative number, got {}", self.noise),
            );
        }
        if !(self.index_error_rad.is_finite() && self.index_error_rad >= 0.0) {
            return invalid(
                "index_error_arcsec",
                format!(
                    "must be a non-negative number, got {}",
                    crate::units::rad_to_arcsec(self.index_error_rad)
                ),
            );
        }
        if self.angles_deg.is_empty() {
            return invalid("angles_deg", "at least one angle, got none");
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
                return invalid("truth", format!("its output is not finite at {a} deg"));
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

/// The true instrument of a simulated tumble test, in engineering units
/// (misalignments in arcsec); a key not given takes the instrument of Wu et
/// al. 2015 (δp −300″ and K_io 5e-7 g/g² added so the gate mount sees them).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct TumbleTruth {
    /// Bias K0 (g).
    pub k0_g: f64,
    /// Scale factor K1 (output/g).
    pub k1: f64,
    /// K2 (g/g²).
    pub k2: f64,
    /// K3 (g/g³).
    pub k3: f64,
    /// Misalignment δo (arcsec).
    pub delta_o_arcsec: f64,
    /// Misalignment δp (arcsec).
    pub delta_p_arcsec: f64,
    /// Cross-coupling K_ip (g/g²).
    pub k_ip: f64,
    /// Cross-coupling K_io (g/g²).
    pub k_io: f64,
    /// Cross-coupling K_po (g/g²).
    pub k_po: f64,
    /// Cross-axis nonlinearity K_pp (g/g²).
    pub k_pp: f64,
    /// Cross-axis nonlinearity K_oo (g/g²).
    pub k_oo: f64,
    /// Odd quadratic K_oq (g/g²).
    pub k_oq: f64,
}

impl Default for TumbleTruth {
    fn default() -> Self {
        Self {
            k0_g: 8e-3,
            k1: 10.0,
            k2: 1e-6,
            k3: 5e-5,
            delta_o_arcsec: 618.794,
            delta_p_arcsec: -300.0,
            k_ip: 3e-7,
            k_io: 5e-7,
            k_po: 0.0,
            k_pp: 0.0,
            k_oo: 0.0,
            k_oq: 0.0,
        }
    }
}

impl TumbleTruth {
    /// The model (misalignments in rad: the one conversion), refusing a
    /// non-finite coefficient or K1 = 0.
    pub fn model(&self) -> Result<AccelerometerModel> {
        let arcsec = crate::units::arcsec_to_rad;
        let m = AccelerometerModel {
            k0_g: self.k0_g,
            k1_out_per_g: self.k1,
            k2: self.k2,
            k3: self.k3,
            delta_o_rad: arcsec(self.delta_o_arcsec),
            delta_p_rad: arcsec(self.delta_p_arcsec),
            k_ip: self.k_ip,
            k_io: self.k_io,
            k_po: self.k_po,
            k_pp: self.k_pp,
            k_oo: self.k_oo,
            k_oq: self.k_oq,
        };
        m.validate().map_err(|e| Error::InvalidOption {
            key: "truth".into(),
            message: e.to_string(),
        })?;
        Ok(m)
    }
}

/// Options of the tumble simulator (`incal simulate tumble`), in
/// engineering units; a key not given takes the command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct TumbleSimOptions {
    /// Mount on the head (default pendulum).
    #[serde(default = "pendulum")]
    pub mount: Mount,
    /// Which angles (default: the GJB 12-point plan).
    #[serde(flatten)]
    pub plan: super::plan::TumblePlanChoice,
    /// The true instrument.
    #[serde(flatten)]
    pub truth: TumbleTruth,
    /// Samples per position (default 10).
    #[serde(default = "ten")]
    pub samples: usize,
    /// Output noise σ of one sample (output units; default 1e-6).
    #[serde(default = "micro")]
    pub noise: f64,
    /// Index-angle error σ of the head (arcsec), one draw per visit.
    #[serde(default)]
    pub index_error_arcsec: f64,
    /// Passes: 1, or 2 (cw then ccw, labelled in a `pass` column).
    #[serde(default = "one")]
    pub passes: usize,
    /// Random seed (same seed, same file; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn pendulum() -> Mount {
    Mount::Pendulum
}
fn ten() -> usize {
    10
}
fn micro() -> f64 {
    1e-6
}
fn one() -> usize {
    1
}
fn seed_one() -> u64 {
    1
}

impl TumbleSimOptions {
    /// The simulator's configuration: the plan's angles, the truth model,
    /// the index error in rad; refused as [`TumbleSim::validate`] refuses.
    pub fn config(&self) -> Result<TumbleSim> {
        let cfg = TumbleSim {
            truth: self.truth.model()?,
            mount: self.mount,
            angles_deg: self.plan.plan()?.angles_deg,
            samples: self.samples,
            noise: self.noise,
            index_error_rad: crate::units::arcsec_to_rad(self.index_error_arcsec),
            passes: self.passes,
            seed: self.seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

impl crate::procedures::Simulate for super::Tumble {
    type Options = TumbleSimOptions;

    fn validate(o: &TumbleSimOptions) -> Result<()> {
        o.config().map(|_| ())
    }

    /// Streamed: rows are written as they are drawn, in constant memory.
    fn simulate(o: &TumbleSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let cfg = o.config()?;
        super::input::write_each(cfg.passes > 1, out, |row| for_each(&cfg, row))?;
        Ok(())
    }
}
