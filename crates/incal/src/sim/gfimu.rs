//! Gyro-free unit simulator (methods.md §4): static positions for the
//! calibration and a rigid-body motion on a rate table for the motion
//! solution, with every accelerometer's truth K0, Ks and white output noise.
//!
//! Output of accelerometer j: `E_j = K0_j + Ks_jᵀ f_j + n`, `n ~ N(0, σ²)`,
//! `f_j = f0 + (ω̇ × r_j + ω × (ω × r_j))/g` ([`crate::models::gfimu`]).

use nalgebra::Vector3;

use super::{normal, rng};
use crate::error::{Error, Result};
use crate::models::gfimu::{cross_axes, Geometry};
use crate::procedures::gfimu::StaticSample;

/// Truth of every accelerometer, geometry order.
#[derive(Debug, Clone, PartialEq)]
pub struct GfimuTruth {
    /// Equivalent bias K0 (output).
    pub k0: Vec<f64>,
    /// Equivalent sensitive vector Ks (output/g).
    pub ks: Vec<Vector3<f64>>,
}

impl GfimuTruth {
    /// A deterministic, realistic truth: scale factor `k1_out_per_g·(1 + ε_j)`
    /// with ε_j of a few 1e-3, biases of a few 1e-3·k1, and misalignments of
    /// 1–3 mrad about both cross axes (distinct for each accelerometer so a
    /// swapped column shows).
    pub fn typical(geometry: &Geometry, k1_out_per_g: f64) -> Self {
        let mut k0 = Vec::new();
        let mut ks = Vec::new();
        for (j, a) in geometry.accelerometers().iter().enumerate() {
            let s = (j % 7) as f64 - 3.0; // −3..3
            let (p, q) = cross_axes(&a.direction);
            k0.push(k1_out_per_g * 1e-3 * (2.0 + 0.7 * s));
            let dir = a.direction + p * (1e-3 * (1.0 + 0.3 * s)) - q * (1e-3 * (2.0 - 0.2 * s));
            ks.push(dir * (k1_out_per_g * (1.0 + 1e-3 * s)));
        }
        Self { k0, ks }
    }

    fn check(&self, geometry: &Geometry) -> Result<()> {
        if self.k0.len() != geometry.len() || self.ks.len() != geometry.len() {
            return Err(Error::Unsupported(format!(
                "truth for {} / {} accelerometers, geometry has {}",
                self.k0.len(),
                self.ks.len(),
                geometry.len()
            )));
        }
        Ok(())
    }

    /// Noise-free outputs at the specific forces `f_j` (g) of every
    /// accelerometer.
    pub fn outputs(&self, forces: &[Vector3<f64>]) -> Vec<f64> {
        self.k0
            .iter()
            .zip(&self.ks)
            .zip(forces)
            .map(|((k0, ks), f)| k0 + ks.dot(f))
            .collect()
    }
}

/// The six-position plan: `+x, −x, +y, −y, +z, −z` (1 g up along each axis).
pub fn six_positions() -> Vec<Vector3<f64>> {
    let mut v = Vec::new();
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let mut f = Vector3::zeros();
            f[k] = sign;
            v.push(f);
        }
    }
    v
}

/// Static samples: `samples` per position, noise σ `noise` (output).
pub fn simulate_static(
    geometry: &Geometry,
    truth: &GfimuTruth,
    positions_g: &[Vector3<f64>],
    samples: usize,
    noise: f64,
    seed: u64,
) -> Result<Vec<StaticSample>> {
    truth.check(geometry)?;
    let mut r = rng(seed);
    let mut out = Vec::with_capacity(positions_g.len() * samples);
    for f in positions_g {
        let forces = vec![*f; geometry.len()];
        let e0 = truth.outputs(&forces);
        for _ in 0..samples.max(1) {
            out.push(StaticSample {
                specific_force_g: *f,
                outputs: e0.iter().map(|e| e + normal(&mut r, noise)).collect(),
            });
        }
    }
    Ok(out)
}

/// A rate-table motion: rotation about a fixed axis with constant angular
/// acceleration for `spin_up_s`, then constant rate, and a constant
/// specific force at the origin in the unit frame (gravity along the
/// rotation axis plus a constant acceleration, so f0 does not turn with the
/// unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionProfile {
    /// Rotation axis (unit frame; normalised).
    pub axis: Vector3<f64>,
    /// Angular acceleration during spin-up (rad/s²).
    pub angular_accel_rad_s2: f64,
    /// Spin-up duration (s).
    pub spin_up_s: f64,
    /// Rate at t = 0 (rad/s, unit frame).
    pub omega0_rad_s: Vector3<f64>,
    /// Specific force at the origin (g, unit frame).
    pub f0_g: Vector3<f64>,
    /// Record length (s).
    pub duration_s: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Local gravity defining the g unit (m/s²).
    pub gravity_m_s2: f64,
}

/// Truth of the motion at time t: `(f0 [g], ω̇ [rad/s²], ω [rad/s])`.
/// ω̇ switches off at `t > spin_up_s`.
pub fn motion_truth(m: &MotionProfile, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let n = m.axis.try_normalize(0.0).unwrap_or_else(Vector3::z);
    let wd = if t <= m.spin_up_s {
        n * m.angular_accel_rad_s2
    } else {
        Vector3::zeros()
    };
    let w = m.omega0_rad_s + n * (m.angular_accel_rad_s2 * t.min(m.spin_up_s));
    (m.f0_g, wd, w)
}

/// Simulated motion record: times `t_k = k / rate_hz` and every output.
pub fn simulate_motion(
    geometry: &Geometry,
    truth: &GfimuTruth,
    m: &MotionProfile,
    noise: f64,
    seed: u64,
) -> Result<Vec<(f64, Vec<f64>)>> {
    truth.check(geometry)?;
    for (what, v) in [
        ("sample rate (Hz)", m.rate_hz),
        ("duration (s)", m.duration_s),
        ("gravity (m/s^2)", m.gravity_m_s2),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::InvalidValue {
                what: what.into(),
                value: v.to_string(),
            });
        }
    }
    let count = (m.duration_s * m.rate_hz).floor() as usize + 1;
    if count > 10_000_000 {
        return Err(Error::InvalidValue {
            what: "number of samples (duration x rate, at most 1e7)".into(),
            value: count.to_string(),
        });
    }
    let mut r = rng(seed);
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let t = k as f64 / m.rate_hz;
        let (f0, wd, w) = motion_truth(m, t);
        let forces: Vec<Vector3<f64>> = geometry
            .accelerometers()
            .iter()
            .map(|a| {
                let p = a.position_m;
                f0 + (wd.cross(&p) + w.cross(&w.cross(&p))) / m.gravity_m_s2
            })
            .collect();
        let e = truth
            .outputs(&forces)
            .into_iter()
            .map(|e| e + normal(&mut r, noise))
            .collect();
        out.push((t, e));
    }
    Ok(out)
}
