//! Dividing-head simulator of the multi-position test: a drift truth and
//! a plan give observations in the input format of
//! [`crate::procedures::gyro::positions`].
//!
//! The kinematics are computed here from vectors (frame x north, y east,
//! z up; head axis `d`, `h = z × d`, `IA = cos θ h + sin θ z`,
//! `P = −sin θ h + cos θ z`; Earth rate `Ω_e (cos φ, 0, sin φ)`; specific
//! force `(0, 0, 1)` g), not from the closed forms the reduction uses, so a
//! round trip checks the reduction's kinematics as well as its statistics.

use super::{Axial, PositionObservation, ALL_TERMS};
use crate::error::{Error, Result};
use crate::procedures::gyro::rate::sim::{MAX_SIM_K1, MAX_SIM_NOISE};
use crate::sim::{normal, rng};
use crate::units::EARTH_RATE_RAD_S;

/// Largest drift term of a simulated truth (deg/h, deg/h/g, deg/h/g²).
pub const MAX_SIM_DRIFT: f64 = 1e7;

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

impl GyroPositionsSim {
    /// Refuse a configuration that cannot be simulated: a drift term that
    /// is not finite or beyond 1e7, a K1 that is zero or beyond 1e9, a
    /// latitude outside ±90°, no angles or azimuths or one beyond 1e4 deg,
    /// no samples, more than [`crate::sim::MAX_SIM_ROWS`] rows, a noise
    /// outside 0…1e9.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String, v: f64| Error::invalid(what, v);
        for t in ALL_TERMS {
            let v = self.drift.get(t.name());
            if !(v.is_finite() && v.abs() <= MAX_SIM_DRIFT) {
                return bad(
                    format!("{} truth (finite, at most 1e7 in magnitude)", t.name()),
                    v,
                );
            }
        }
        if !(self.k1.is_finite() && self.k1 != 0.0 && self.k1.abs() <= MAX_SIM_K1) {
            return bad("k1 (non-zero, at most 1e9 in magnitude)".into(), self.k1);
        }
        crate::options::check_latitude_deg(self.latitude_rad.to_degrees())?;
        super::check_angles_deg("angles_deg", &self.angles_deg)?;
        if self.azimuths_rad.is_empty() {
            return super::check_angles_deg("azimuths_deg", &[]);
        }
        let max_rad = super::MAX_ANGLE_DEG.to_radians();
        if let Some(z) = self
            .azimuths_rad
            .iter()
            .find(|z| !(z.is_finite() && z.abs() <= max_rad))
        {
            return bad(
                "azimuths_deg (an angle, |angle| <= 1e4 deg)".into(),
                z.to_degrees(),
            );
        }
        if self.samples == 0 {
            return bad("samples (at least 1 per position)".into(), 0.0);
        }
        crate::sim::check_rows(&[
            ("angles_deg", self.angles_deg.len() as f64),
            ("azimuths_deg", self.azimuths_rad.len() as f64),
            ("samples", self.samples as f64),
        ])?;
        if !(self.noise.is_finite() && (0.0..=MAX_SIM_NOISE).contains(&self.noise)) {
            return bad(
                "noise (a non-negative number, at most 1e9)".into(),
                self.noise,
            );
        }
        Ok(())
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Simulate a multi-position test (module docs; deterministic for a given
/// seed).
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

/// Options of the multi-position simulator (`incal simulate
/// gyro-positions`), in engineering units; a key not given takes the
/// command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct GyroPositionsSimOptions {
    /// Scale factor K1 (output/(deg/s)).
    pub k1: f64,
    /// Bias B (deg/h).
    pub b_deg_h: f64,
    /// D_I (deg/h/g).
    pub d_i_deg_h_g: f64,
    /// D_O (deg/h/g).
    pub d_o_deg_h_g: f64,
    /// D_S (deg/h/g).
    pub d_s_deg_h_g: f64,
    /// D_II (deg/h/g²).
    pub d_ii_deg_h_g2: f64,
    /// D_IO (deg/h/g²).
    pub d_io_deg_h_g2: f64,
    /// D_IS (deg/h/g²).
    pub d_is_deg_h_g2: f64,
    /// D_OO (deg/h/g²).
    pub d_oo_deg_h_g2: f64,
    /// D_SS (deg/h/g²).
    pub d_ss_deg_h_g2: f64,
    /// Latitude (deg).
    pub latitude_deg: f64,
    /// Azimuths of the head axis (deg); two or more add an `azimuth_deg` column.
    pub azimuths_deg: Vec<f64>,
    /// Gyro axis along the head axis.
    pub axial: Axial,
    /// Head angles (deg; default 0, 30, …, 330).
    pub angles_deg: Vec<f64>,
    /// Samples per position.
    pub samples: usize,
    /// Output noise of one sample (output units).
    pub noise: f64,
    /// Random seed (same seed, same file).
    pub seed: u64,
}

impl Default for GyroPositionsSimOptions {
    fn default() -> Self {
        Self {
            k1: 0.02,
            b_deg_h: 3.0,
            d_i_deg_h_g: 0.8,
            d_o_deg_h_g: -0.5,
            d_s_deg_h_g: 0.4,
            d_ii_deg_h_g2: 0.0,
            d_io_deg_h_g2: 0.0,
            d_is_deg_h_g2: 0.0,
            d_oo_deg_h_g2: 0.0,
            d_ss_deg_h_g2: 0.0,
            latitude_deg: 45.0,
            azimuths_deg: vec![0.0],
            axial: Axial::Sa,
            angles_deg: super::default_angles_deg(),
            samples: 10,
            noise: 2e-5,
            seed: 1,
        }
    }
}

impl GyroPositionsSimOptions {
    /// The simulator's configuration (angles in rad: the one conversion),
    /// refused as [`GyroPositionsSim::validate`] refuses.
    pub fn config(&self) -> Result<GyroPositionsSim> {
        crate::options::check_latitude_deg(self.latitude_deg)?;
        let cfg = GyroPositionsSim {
            k1: self.k1,
            drift: DriftTruth {
                b: self.b_deg_h,
                d_i: self.d_i_deg_h_g,
                d_o: self.d_o_deg_h_g,
                d_s: self.d_s_deg_h_g,
                d_ii: self.d_ii_deg_h_g2,
                d_io: self.d_io_deg_h_g2,
                d_is: self.d_is_deg_h_g2,
                d_oo: self.d_oo_deg_h_g2,
                d_ss: self.d_ss_deg_h_g2,
            },
            latitude_rad: self.latitude_deg.to_radians(),
            azimuths_rad: self.azimuths_deg.iter().map(|z| z.to_radians()).collect(),
            axial: self.axial,
            angles_deg: self.angles_deg.clone(),
            samples: self.samples,
            noise: self.noise,
            seed: self.seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

impl crate::procedures::Simulate for super::GyroPositions {
    type Options = GyroPositionsSimOptions;

    fn validate(o: &GyroPositionsSimOptions) -> Result<()> {
        o.config().map(|_| ())
    }

    fn simulate(o: &GyroPositionsSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let obs = simulate_positions(&o.config()?);
        super::input::write(&obs, o.azimuths_deg.len() > 1, out)?;
        Ok(())
    }
}
