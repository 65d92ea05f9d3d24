//! Magnetometer session simulator: a unit with a magnetometer and an
//! accelerometer held still in `orientations` orientations (uniformly
//! random, or turned about the vertical only: `planar`), moved between
//! them, in a uniform field of magnitude `field_ut` and inclination
//! `inclination_deg`.
//!
//! In the local frame (north, east, down) the field is
//! `F (cos I, 0, sin I)` and the specific force at rest `(0, 0, −g)`; in
//! the accelerometer's axes each is turned by the orientation `Q`. The
//! magnetometer's axes are turned from the accelerometer's by `Rᵀ`,
//! `R = exp([φ]×)` (`alignment_*_deg`), and its raw reading is
//! `m = (S⁻¹ Rᵀ Q b + w + g) / k + h`: `S` the symmetric soft iron
//! (dimensionless), `k` the unit's µT per raw unit, `h` the hard iron
//! (raw units), `w` white noise (σ `noise_ut` per axis) and `g` a
//! first-order Gauss–Markov noise (σ `gm_ut`, correlation time
//! `gm_tau_s`). Between orientations the unit turns along the shortest
//! rotation for `move_s` seconds while accelerated along the vertical
//! (up to 0.3 g, so those rows are not at rest). Deterministic for a
//! seed.

use nalgebra::{Quaternion, UnitQuaternion};

use super::fit::{self, rotation, M3, V3};
use super::input::{write, Record};
use super::MagUnit;
use crate::error::Result;
use crate::options::{check_range, invalid};
use crate::sim::{normal, rng};

/// How the simulated unit is turned.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Motion {
    /// Orientations uniformly random over all rotations.
    #[default]
    Random,
    /// Turned about the vertical only, level (a session on a table:
    /// the soft iron about the vertical cannot be separated).
    Planar,
}

/// Options of `incal simulate mag` (the truth in the keys).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MagSimOptions {
    /// Hard iron, x (raw units; default 12).
    #[serde(default = "hx")]
    pub hard_iron_x: f64,
    /// Hard iron, y (raw units; default −8).
    #[serde(default = "hy")]
    pub hard_iron_y: f64,
    /// Hard iron, z (raw units; default 25).
    #[serde(default = "hz")]
    pub hard_iron_z: f64,
    /// Soft iron `S`, xx (dimensionless; default 1.05).
    #[serde(default = "sxx")]
    pub soft_iron_xx: f64,
    /// Soft iron, yy (default 0.97).
    #[serde(default = "syy")]
    pub soft_iron_yy: f64,
    /// Soft iron, zz (default 1.02).
    #[serde(default = "szz")]
    pub soft_iron_zz: f64,
    /// Soft iron, xy (default 0.02).
    #[serde(default = "sxy")]
    pub soft_iron_xy: f64,
    /// Soft iron, xz (default −0.015).
    #[serde(default = "sxz")]
    pub soft_iron_xz: f64,
    /// Soft iron, yz (default 0.01).
    #[serde(default = "syz")]
    pub soft_iron_yz: f64,
    /// Alignment to the accelerometer, rotation vector x (degrees;
    /// default 1.5).
    #[serde(default = "ax")]
    pub alignment_x_deg: f64,
    /// Alignment, y (degrees; default −2).
    #[serde(default = "ay")]
    pub alignment_y_deg: f64,
    /// Alignment, z (degrees; default 3).
    #[serde(default = "az")]
    pub alignment_z_deg: f64,
    /// The field's magnitude (µT; default 50).
    #[serde(default = "fifty")]
    pub field_ut: f64,
    /// The field's inclination (degrees, down positive; default 60).
    #[serde(default = "sixty")]
    pub inclination_deg: f64,
    /// The raw unit (default uT).
    #[serde(default)]
    pub unit: MagUnit,
    /// Orientations held (default 36).
    #[serde(default = "thirty_six")]
    pub orientations: usize,
    /// Seconds held in each (default 2).
    #[serde(default = "two")]
    pub dwell_s: f64,
    /// Seconds moving between two (default 1).
    #[serde(default = "one")]
    pub move_s: f64,
    /// Sampling rate (Hz; default 50).
    #[serde(default = "fifty")]
    pub rate_hz: f64,
    /// How the unit is turned (default random).
    #[serde(default)]
    pub motion: Motion,
    /// White noise per axis (µT; default 0.3).
    #[serde(default = "noise")]
    pub noise_ut: f64,
    /// Gauss–Markov noise σ per axis (µT; default 0).
    #[serde(default)]
    pub gm_ut: f64,
    /// Gauss–Markov correlation time (s; default 1).
    #[serde(default = "one")]
    pub gm_tau_s: f64,
    /// Leave the accelerometer out (default false).
    #[serde(default)]
    pub no_accelerometer: bool,
    /// Accelerometer white noise (m/s²; default 0.02).
    #[serde(default = "acc_noise")]
    pub acc_noise: f64,
    /// Seed (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn hx() -> f64 {
    12.0
}
fn hy() -> f64 {
    -8.0
}
fn hz() -> f64 {
    25.0
}
fn sxx() -> f64 {
    1.05
}
fn syy() -> f64 {
    0.97
}
fn szz() -> f64 {
    1.02
}
fn sxy() -> f64 {
    0.02
}
fn sxz() -> f64 {
    -0.015
}
fn syz() -> f64 {
    0.01
}
fn ax() -> f64 {
    1.5
}
fn ay() -> f64 {
    -2.0
}
fn az() -> f64 {
    3.0
}
pub(super) fn fifty() -> f64 {
    50.0
}
pub(super) fn sixty() -> f64 {
    60.0
}
pub(super) fn thirty_six() -> usize {
    36
}
pub(super) fn two() -> f64 {
    2.0
}
pub(super) fn one() -> f64 {
    1.0
}
pub(super) fn noise() -> f64 {
    0.3
}
pub(super) fn acc_noise() -> f64 {
    0.02
}
pub(super) fn seed_one() -> u64 {
    1
}

/// Standard gravity (m/s²).
const G0: f64 = 9.80665;

impl Default for MagSimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

impl MagSimOptions {
    /// The soft iron `S` (dimensionless).
    pub fn soft(&self) -> M3 {
        fit::sym(&[
            self.soft_iron_xx,
            self.soft_iron_yy,
            self.soft_iron_zz,
            self.soft_iron_xy,
            self.soft_iron_xz,
            self.soft_iron_yz,
        ])
    }

    /// The alignment's rotation vector (rad).
    pub fn phi(&self) -> V3 {
        V3::new(
            self.alignment_x_deg,
            self.alignment_y_deg,
            self.alignment_z_deg,
        )
        .map(f64::to_radians)
    }

    /// Check the options; the number of rows.
    pub fn rows(&self) -> Result<usize> {
        for (k, v) in [
            ("hard_iron_x", self.hard_iron_x),
            ("hard_iron_y", self.hard_iron_y),
            ("hard_iron_z", self.hard_iron_z),
        ] {
            check_range(k, v, -1e9, 1e9, "")?;
        }
        for (k, v) in [
            ("soft_iron_xx", self.soft_iron_xx),
            ("soft_iron_yy", self.soft_iron_yy),
            ("soft_iron_zz", self.soft_iron_zz),
            ("soft_iron_xy", self.soft_iron_xy),
            ("soft_iron_xz", self.soft_iron_xz),
            ("soft_iron_yz", self.soft_iron_yz),
        ] {
            check_range(k, v, -10.0, 10.0, "")?;
        }
        if fit::sqrt_pd(&self.soft()).is_none() {
            return invalid(
                "soft_iron_xx",
                "the soft-iron matrix is not positive definite",
            );
        }
        for (k, v) in [
            ("alignment_x_deg", self.alignment_x_deg),
            ("alignment_y_deg", self.alignment_y_deg),
            ("alignment_z_deg", self.alignment_z_deg),
        ] {
            check_range(k, v, -30.0, 30.0, "deg")?;
        }
        check_range("field_ut", self.field_ut, 1e-3, 1e7, "uT")?;
        check_range("inclination_deg", self.inclination_deg, -89.0, 89.0, "deg")?;
        if self.unit == MagUnit::Counts {
            return invalid(
                "unit",
                "counts has no scale to simulate: use ut, nt, gauss or mgauss",
            );
        }
        check_range("orientations", self.orientations as f64, 1.0, 1e5, "")?;
        check_range("dwell_s", self.dwell_s, 1e-3, 1e6, "s")?;
        check_range("move_s", self.move_s, 0.0, 1e6, "s")?;
        check_range("rate_hz", self.rate_hz, 1e-2, 1e5, "Hz")?;
        check_range("noise_ut", self.noise_ut, 0.0, 1e6, "uT")?;
        check_range("gm_ut", self.gm_ut, 0.0, 1e6, "uT")?;
        check_range("gm_tau_s", self.gm_tau_s, 1e-6, 1e9, "s")?;
        check_range("acc_noise", self.acc_noise, 0.0, 1e3, "m/s^2")?;
        let dwell = (self.dwell_s * self.rate_hz).round();
        let moving = (self.move_s * self.rate_hz).round();
        let n = self.orientations as f64 * (dwell + moving);
        crate::sim::check_rows(&[("orientations x (dwell_s + move_s) x rate_hz", n)])?;
        if dwell < 1.0 {
            return invalid("dwell_s", "under one sample per orientation");
        }
        Ok(n as usize)
    }

    /// The orientations (local frame to the accelerometer's axes).
    fn attitudes(&self, r: &mut rand::rngs::ChaCha8Rng) -> Vec<UnitQuaternion<f64>> {
        (0..self.orientations)
            .map(|_| match self.motion {
                Motion::Random => UnitQuaternion::from_quaternion(Quaternion::new(
                    normal(r, 1.0),
                    normal(r, 1.0),
                    normal(r, 1.0),
                    normal(r, 1.0),
                )),
                Motion::Planar => {
                    let yaw = std::f64::consts::PI * (2.0 * rand::RngExt::random::<f64>(r) - 1.0);
                    UnitQuaternion::from_euler_angles(0.0, 0.0, yaw)
                }
            })
            .collect()
    }

    /// The session.
    pub fn record(&self) -> Result<Record> {
        let n = self.rows()?;
        let mut r = rng(self.seed);
        let k = self.unit.ut().unwrap_or(1.0);
        let dt = 1.0 / self.rate_hz;
        let incl = self.inclination_deg.to_radians();
        let b_n = self.field_ut * V3::new(incl.cos(), 0.0, incl.sin());
        let f_n = V3::new(0.0, 0.0, -G0);
        let s_inv = self.soft().try_inverse().unwrap_or_else(M3::identity);
        let rt = rotation(&self.phi()).transpose();
        let h = V3::new(self.hard_iron_x, self.hard_iron_y, self.hard_iron_z);
        let att = self.attitudes(&mut r);
        let dwell = (self.dwell_s * self.rate_hz).round() as usize;
        let moving = (self.move_s * self.rate_hz).round() as usize;
        let phi_gm = (-dt / self.gm_tau_s).exp();
        let drive = self.gm_ut * (1.0 - phi_gm * phi_gm).sqrt();
        let mut gm = V3::from_fn(|_, _| normal(&mut r, self.gm_ut));
        let mut rec = Record {
            acc: (!self.no_accelerometer).then(|| Vec::with_capacity(n)),
            time_s: Some(Vec::with_capacity(n)),
            ..Record::default()
        };
        for (i, q) in att.iter().enumerate() {
            let next = att.get(i + 1).unwrap_or(q);
            for s in 0..dwell + moving {
                let (q_now, push) = if s < dwell {
                    (*q, 0.0)
                } else {
                    let t = (s - dwell + 1) as f64 / (moving + 1) as f64;
                    (q.slerp(next, t), 0.3 * (std::f64::consts::PI * t).sin())
                };
                let rot = q_now.to_rotation_matrix();
                let b_a = rot.inverse() * b_n;
                let f_a = rot.inverse() * f_n * (1.0 + push);
                gm = gm * phi_gm + V3::from_fn(|_, _| normal(&mut r, drive));
                let w = V3::from_fn(|_, _| normal(&mut r, self.noise_ut));
                let m = (s_inv * (rt * b_a) + w + gm) / k + h;
                let row = rec.mag.len();
                rec.mag.push([m.x, m.y, m.z]);
                if let Some(a) = rec.acc.as_mut() {
                    let e = V3::from_fn(|_, _| normal(&mut r, self.acc_noise));
                    let f = f_a + e;
                    a.push([f.x, f.y, f.z]);
                }
                if let Some(t) = rec.time_s.as_mut() {
                    t.push(row as f64 * dt);
                }
                rec.lines.push(row + 2);
            }
        }
        Ok(rec)
    }

    /// The truth, as the reduction reports it with `field_ut` and the
    /// unit given ([`super`] module docs).
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        self.rows()?;
        let k = self.unit.ut().unwrap_or(1.0);
        let s = self.soft() * k;
        let mut t = serde_json::Map::new();
        for (name, v) in
            fit::HARD
                .iter()
                .zip([self.hard_iron_x, self.hard_iron_y, self.hard_iron_z])
        {
            t.insert(name.to_string(), v.into());
        }
        for (name, (i, j)) in fit::SOFT.iter().zip(fit::PAIRS) {
            t.insert(name.to_string(), s[(i, j)].into());
        }
        let radius = self.field_ut / s.determinant().powf(1.0 / 3.0);
        t.insert("field_raw".into(), radius.into());
        t.insert("field_ut".into(), (k * radius).into());
        for (name, v) in ["alignment_x_deg", "alignment_y_deg", "alignment_z_deg"]
            .iter()
            .zip([
                self.alignment_x_deg,
                self.alignment_y_deg,
                self.alignment_z_deg,
            ])
        {
            t.insert(name.to_string(), v.into());
        }
        t.insert("inclination_deg".into(), self.inclination_deg.into());
        Ok(serde_json::Value::Object(t))
    }
}

impl crate::procedures::Simulate for super::Mag {
    type Options = MagSimOptions;

    fn validate(o: &MagSimOptions) -> Result<()> {
        o.rows().map(|_| ())
    }

    fn simulate(o: &MagSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.record()?, out)?;
        Ok(())
    }

    fn truth(o: &MagSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
