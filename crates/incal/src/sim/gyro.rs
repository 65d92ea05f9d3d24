//! Gyro rate-table and dividing-head simulators, from a truth to the input
//! of [`crate::procedures::gyro`].
//!
//! The kinematics are computed here from vectors (frame x north, y east,
//! z up; head axis `d`, `h = z × d`, `IA = cos θ h + sin θ z`,
//! `P = −sin θ h + cos θ z`; Earth rate `Ω_e (cos φ, 0, sin φ)`; specific
//! force `(0, 0, 1)` g), not from the closed forms the reduction uses, so a
//! round trip checks the reduction's kinematics as well as its statistics.

use super::{normal, rng};
use crate::procedures::gyro::positions::{Axial, PositionObservation};
use crate::procedures::gyro::rate::{InputAxis, RateObservation};
use crate::units::EARTH_RATE_RAD_S;

/// Truth and plan of a simulated rate-transfer test.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroRateSim {
    /// Scale factor for positive input rates (output/(deg/s)).
    pub k1_pos: f64,
    /// Scale factor for negative input rates (output/(deg/s)).
    pub k1_neg: f64,
    /// Bias (deg/h).
    pub b_deg_h: f64,
    /// K2 (1/(deg/s)).
    pub k2: f64,
    /// K3 (1/(deg/s)²).
    pub k3: f64,
    /// Latitude (rad).
    pub latitude_rad: f64,
    /// Input axis up or down.
    pub ia: InputAxis,
    /// Table rates (deg/s), in test order.
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    pub samples: usize,
    /// Output noise per sample (output units).
    pub noise: f64,
    /// Number of runs (1: no run column).
    pub runs: usize,
    /// Run-to-run scatter of K1 (ppm, standard deviation), one draw per run.
    pub run_scatter_ppm: f64,
    /// Seed.
    pub seed: u64,
}

/// Simulate a rate-transfer test: `E = K1± (ω_in + B + K2 ω_in² + K3 ω_in³) + n`
/// with `ω_in` the table rate plus the Earth rate projected on IA.
pub fn simulate_rate(cfg: &GyroRateSim) -> Vec<RateObservation> {
    let mut r = rng(cfg.seed);
    let we = EARTH_RATE_RAD_S.to_degrees();
    let axis = [0.0, 0.0, cfg.ia.sign()];
    let mut out = Vec::new();
    for run in 0..cfg.runs.max(1) {
        let scale = 1.0 + normal(&mut r, cfg.run_scatter_ppm * 1e-6);
        let label = (cfg.runs > 1).then(|| format!("run{}", run + 1));
        for &rate in &cfg.rates_deg_s {
            // Total rate (deg/s) in the local frame: Earth plus the table about z.
            let w = [
                we * cfg.latitude_rad.cos(),
                0.0,
                we * cfg.latitude_rad.sin() + rate,
            ];
            let w_in: f64 = (0..3).map(|k| w[k] * axis[k]).sum();
            let k1 = if w_in >= 0.0 { cfg.k1_pos } else { cfg.k1_neg } * scale;
            let e0 =
                k1 * (w_in + cfg.b_deg_h / 3600.0 + cfg.k2 * w_in * w_in + cfg.k3 * w_in.powi(3));
            for _ in 0..cfg.samples.max(1) {
                out.push(RateObservation {
                    rate_deg_s: rate,
                    output: e0 + normal(&mut r, cfg.noise),
                    run: label.clone(),
                });
            }
        }
    }
    out
}

/// Drift-model truth (deg/h, deg/h/g, deg/h/g²), IEEE Std 517 / 1431.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DriftTruth {
    /// B.
    pub b: f64,
    /// D_I.
    pub d_i: f64,
    /// D_O.
    pub d_o: f64,
    /// D_S.
    pub d_s: f64,
    /// D_II.
    pub d_ii: f64,
    /// D_IO.
    pub d_io: f64,
    /// D_IS.
    pub d_is: f64,
    /// D_OO.
    pub d_oo: f64,
    /// D_SS.
    pub d_ss: f64,
}

impl DriftTruth {
    /// Value of a term by its name (`B`, `D_I`, …), 0 when unknown.
    pub fn get(&self, name: &str) -> f64 {
        match name {
            "B" => self.b,
            "D_I" => self.d_i,
            "D_O" => self.d_o,
            "D_S" => self.d_s,
            "D_II" => self.d_ii,
            "D_IO" => self.d_io,
            "D_IS" => self.d_is,
            "D_OO" => self.d_oo,
            "D_SS" => self.d_ss,
            _ => 0.0,
        }
    }
    /// Drift (deg/h) at specific-force components `(a_I, a_O, a_S)`.
    pub fn drift(&self, a: [f64; 3]) -> f64 {
        let [i, o, s] = a;
        self.b
            + self.d_i * i
            + self.d_o * o
            + self.d_s * s
            + self.d_ii * i * i
            + self.d_io * i * o
            + self.d_is * i * s
            + self.d_oo * o * o
            + self.d_ss * s * s
    }
}

/// Truth and plan of a simulated multi-position test.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroPositionsSim {
    /// Scale factor (output/(deg/s)).
    pub k1: f64,
    /// Drift truth.
    pub drift: DriftTruth,
    /// Latitude (rad).
    pub latitude_rad: f64,
    /// Azimuths of the head axis (rad); each gets every angle.
    pub azimuths_rad: Vec<f64>,
    /// Which gyro axis is along the head axis.
    pub axial: Axial,
    /// Head angles (deg).
    pub angles_deg: Vec<f64>,
    /// Samples per position.
    pub samples: usize,
    /// Output noise per sample.
    pub noise: f64,
    /// Seed.
    pub seed: u64,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Simulate a multi-position test (module docs).
pub fn simulate_positions(cfg: &GyroPositionsSim) -> Vec<PositionObservation> {
    let mut r = rng(cfg.seed);
    let we_deg_h = EARTH_RATE_RAD_S.to_degrees() * 3600.0;
    let omega = [
        we_deg_h * cfg.latitude_rad.cos(),
        0.0,
        we_deg_h * cfg.latitude_rad.sin(),
    ];
    let z = [0.0, 0.0, 1.0];
    let f = [0.0, 0.0, 1.0];
    let mut out = Vec::new();
    for &az in &cfg.azimuths_rad {
        let d = [az.cos(), az.sin(), 0.0];
        // h = z × d
        let h = [
            z[1] * d[2] - z[2] * d[1],
            z[2] * d[0] - z[0] * d[2],
            z[0] * d[1] - z[1] * d[0],
        ];
        for &deg in &cfg.angles_deg {
            let th = deg.to_radians();
            let (s, c) = th.sin_cos();
            let ia = [
                c * h[0] + s * z[0],
                c * h[1] + s * z[1],
                c * h[2] + s * z[2],
            ];
            let p = [
                -s * h[0] + c * z[0],
                -s * h[1] + c * z[1],
                -s * h[2] + c * z[2],
            ];
            let (oa, sa) = match cfg.axial {
                Axial::Sa => (p, d),
                Axial::Oa => (d, p),
            };
            let a = [dot(f, ia), dot(f, oa), dot(f, sa)];
            let rate_deg_h = dot(omega, ia) + cfg.drift.drift(a);
            let e0 = cfg.k1 * rate_deg_h / 3600.0;
            for _ in 0..cfg.samples.max(1) {
                out.push(PositionObservation {
                    angle_rad: th,
                    azimuth_rad: az,
                    output: e0 + normal(&mut r, cfg.noise),
                });
            }
        }
    }
    out
}
