//! Precision-centrifuge simulator: a truth instrument, a true rig (R+, R−,
//! tilt, latitude, sense) and a plan give observations in the input format
//! of [`crate::procedures::centrifuge`].
//!
//! For every position (in plan order) and every rate (in plan order; 0 =
//! at rest), `samples` outputs `E = K1·(model at the specific force of
//! [`Centrifuge::specific_force`]) + n`, `n ~ N(0, σ_n²)`, are drawn. The
//! specific force includes the ECM radius and alignment error of each
//! position, the IA tilt and the Earth-rate term.

use super::{normal, rng};
use crate::models::AccelerometerModel;
use crate::procedures::centrifuge::Observation;
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};

/// Configuration of a simulated centrifuge test.
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeSim {
    /// True instrument.
    pub truth: AccelerometerModel,
    /// True rig and mounting.
    pub rig: Centrifuge,
    /// Positions, in test order.
    pub positions: Vec<Position>,
    /// Table rates (rad/s), in test order; include 0 for the at-rest rows.
    pub rates_rad_s: Vec<f64>,
    /// Samples per point (≥ 1).
    pub samples: usize,
    /// Output noise σ of one sample (output units).
    pub noise: f64,
    /// Random seed.
    pub seed: u64,
}

/// The standard plan of seed 001: IA radial (`ip,0`), PA radial (`ip,90`),
/// OA radial (`io,90`) and the 45° cross positions `ip,45`, `io,45`,
/// `po,45`, each in both polarities.
pub fn standard_positions() -> Vec<Position> {
    let list = [
        (Plane::Ip, 0.0),
        (Plane::Ip, 90.0),
        (Plane::Io, 90.0),
        (Plane::Ip, 45.0),
        (Plane::Io, 45.0),
        (Plane::Po, 45.0),
    ];
    let mut out = Vec::new();
    for (plane, deg) in list {
        for polarity in [1, -1] {
            out.push(Position {
                plane,
                phi_rad: f64::to_radians(deg),
                polarity,
            });
        }
    }
    out
}

/// Rates (rad/s) giving the nominal inputs `levels_g` (g) at radius `r_m`
/// with local gravity `g_m_s2`: `ω = sqrt(level·g/R)` (the Earth-rate term
/// is left to the procedure).
pub fn rates_for_levels(levels_g: &[f64], r_m: f64, g_m_s2: f64) -> Vec<f64> {
    levels_g
        .iter()
        .map(|l| (l.max(0.0) * g_m_s2 / r_m).sqrt())
        .collect()
}

/// Simulate the observations (deterministic for a given seed).
pub fn simulate(cfg: &CentrifugeSim) -> Vec<Observation> {
    let mut r = rng(cfg.seed);
    let mut out = Vec::with_capacity(cfg.positions.len() * cfg.rates_rad_s.len() * cfg.samples);
    for pos in &cfg.positions {
        for &w in &cfg.rates_rad_s {
            let e0 = cfg.truth.output(&cfg.rig.specific_force(pos, w));
            for _ in 0..cfg.samples.max(1) {
                out.push(Observation {
                    position: *pos,
                    omega_rad_s: w,
                    output: e0 + normal(&mut r, cfg.noise),
                });
            }
        }
    }
    out
}

/// The plan of a centrifuge test: the reduction itself run on noise-free
/// outputs with a deterministic scatter of exactly `cfg.noise` (sample
/// standard deviation) at every point, the output noise known to the fits.
/// The u it reports are the predicted standard uncertainties of the plan
/// (every fit's u scales with the noise; the static radius and tilt take
/// the scatter of the samples, which is exactly σ here). Needs at least 2
/// samples per point.
pub fn plan(
    cfg: &CentrifugeSim,
    opts: &crate::procedures::centrifuge::CentrifugeOptions,
) -> crate::error::Result<crate::procedures::centrifuge::CentrifugeResult> {
    let n = cfg.samples;
    if n < 2 || !(cfg.noise.is_finite() && cfg.noise > 0.0) {
        return Err(crate::error::Error::InvalidValue {
            what: "plan: samples per point (>= 2) and noise (> 0)".into(),
            value: format!("{n}, {}", cfg.noise),
        });
    }
    // z_i: zero mean, sample standard deviation exactly 1.
    let c = (n as f64 - 1.0) / 2.0;
    let ss: f64 = (0..n).map(|i| (i as f64 - c).powi(2)).sum();
    let scale = ((n as f64 - 1.0) / ss).sqrt();
    let mut quiet = cfg.clone();
    quiet.noise = 0.0;
    let mut obs = simulate(&quiet);
    for (k, o) in obs.iter_mut().enumerate() {
        o.output += cfg.noise * (k % n) as f64 * scale - cfg.noise * c * scale;
    }
    let mut o = opts.clone();
    o.noise = crate::estimation::Noise::Known { sigma: cfg.noise };
    crate::procedures::centrifuge::calibrate(&obs, &o)
}
