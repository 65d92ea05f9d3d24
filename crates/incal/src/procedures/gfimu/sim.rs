//! Gyro-free unit simulator (docs/src/gfimu.md): static positions for the
//! calibration and a rigid-body motion on a rate table for the motion
//! solution, with every accelerometer's truth K0, Ks and white output noise.
//!
//! Output of accelerometer j: `E_j = K0_j + Ks_jᵀ f_j + n`, `n ~ N(0, σ²)`,
//! `f_j = f0 + (ω̇ × r_j + ω × (ω × r_j))/g` ([`crate::models::gfimu`]).
//!
//! [`GfimuSim`] is one simulated test as a front end asks for it: its
//! checks ([`GfimuSim::validate`]) and its CSV ([`GfimuSim::write`], the
//! input formats of [`super::input`]).

use std::io::Write;

use nalgebra::Vector3;

use super::input::{shown, ArrayGeometry};
use crate::error::{Error, Result};
use crate::models::gfimu::{cross_axes, Geometry};
use crate::procedures::gfimu::{CalibratedAccelerometer, StaticSample};
use crate::sim::{normal, rng};

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

    /// The truth as an exact calibration (u = 0) with a known output
    /// noise σ per sample, for solving motions with the true coefficients.
    pub fn calibration(&self, noise_output: Option<f64>) -> Vec<CalibratedAccelerometer> {
        self.k0
            .iter()
            .zip(&self.ks)
            .map(|(k0, ks)| CalibratedAccelerometer::new(*k0, *ks, noise_output))
            .collect()
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

/// Which frame the specific force at the origin `f0_g` is fixed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum F0Frame {
    /// Fixed in the unit frame: f0 does not turn with the unit (gravity
    /// along the rotation axis, the paper's rate-table case).
    #[default]
    Unit,
    /// Fixed in the table (local-level) frame, given at t = 0: as the unit
    /// turns by θ(t) about the axis n, f0 appears in the unit frame as
    /// `R(−θ) f0 = f0 cos θ − (n × f0) sin θ + n (n·f0)(1 − cos θ)`
    /// (Rodrigues), so gravity off the axis rotates through the unit.
    Table,
}

/// A rate-table motion: rotation about a fixed axis n with a rate along n
/// of `α·min(t, T_s) + A sin(2π f_o t)` (spin-up with constant angular
/// acceleration α for `spin_up_s`, then constant rate, plus an optional
/// sinusoidal oscillation of amplitude A at f_o), on top of
/// `omega0_rad_s`, and a specific force at the origin fixed in the unit or
/// the table frame ([`F0Frame`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionProfile {
    /// Rotation axis (unit frame; normalised).
    pub axis: Vector3<f64>,
    /// Angular acceleration during spin-up (rad/s²).
    pub angular_accel_rad_s2: f64,
    /// Spin-up duration (s).
    pub spin_up_s: f64,
    /// Rate at t = 0 (rad/s, unit frame); along the axis for
    /// [`F0Frame::Table`].
    pub omega0_rad_s: Vector3<f64>,
    /// Specific force at the origin (g; unit frame, or table frame at t = 0).
    pub f0_g: Vector3<f64>,
    /// Frame `f0_g` is fixed in.
    pub f0_frame: F0Frame,
    /// Amplitude A of the sinusoidal rate oscillation about the axis (rad/s).
    pub oscillation_amplitude_rad_s: f64,
    /// Frequency f_o of the oscillation (Hz); 0 with A = 0.
    pub oscillation_hz: f64,
    /// Record length (s).
    pub duration_s: f64,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Local gravity defining the g unit (m/s²).
    pub gravity_m_s2: f64,
}

impl MotionProfile {
    /// A spin-up about z at 2 rad/s² for 1.005 s (ends halfway between
    /// samples at 100 Hz, where the trapezoid integration of a step in ω̇
    /// is exact), f0 = (0.05, 0, 1) g in the unit frame, 2 s at 100 Hz: the
    /// defaults of `incal simulate gfimu --kind motion`.
    pub fn rate_table() -> Self {
        MotionProfile {
            axis: Vector3::z(),
            angular_accel_rad_s2: 2.0,
            spin_up_s: 1.005,
            omega0_rad_s: Vector3::zeros(),
            f0_g: Vector3::new(0.05, 0.0, 1.0),
            f0_frame: F0Frame::Unit,
            oscillation_amplitude_rad_s: 0.0,
            oscillation_hz: 0.0,
            duration_s: 2.0,
            rate_hz: 100.0,
            gravity_m_s2: crate::units::STANDARD_GRAVITY_M_S2,
        }
    }

    /// Refuse a profile the simulator cannot represent, naming the field.
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str, v: f64| Error::invalid(what, v);
        for (what, v) in [
            ("sample rate (Hz)", self.rate_hz),
            ("duration (s)", self.duration_s),
            ("gravity (m/s^2)", self.gravity_m_s2),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return bad(what, v);
            }
        }
        if !(self.axis.iter().all(|x| x.is_finite()) && self.axis.norm() > 0.0) {
            return bad("rotation axis (a non-zero finite vector)", self.axis.norm());
        }
        for (what, v) in [
            ("angular acceleration (rad/s^2)", self.angular_accel_rad_s2),
            (
                "oscillation amplitude (rad/s)",
                self.oscillation_amplitude_rad_s,
            ),
        ] {
            if !v.is_finite() {
                return bad(what, v);
            }
        }
        if !(self.spin_up_s.is_finite() && self.spin_up_s >= 0.0) {
            return bad("spin-up time (s, >= 0)", self.spin_up_s);
        }
        let f = self.oscillation_hz;
        if !(f.is_finite() && f >= 0.0 && f < self.rate_hz / 2.0) {
            return bad("oscillation frequency (Hz, 0 <= f < rate/2)", f);
        }
        if self.oscillation_amplitude_rad_s != 0.0 && f == 0.0 {
            return bad("oscillation frequency (Hz, > 0 with an amplitude)", f);
        }
        if self.omega0_rad_s.iter().any(|x| !x.is_finite()) {
            return bad("initial angular rate (rad/s)", self.omega0_rad_s.norm());
        }
        if self.f0_g.iter().any(|x| !x.is_finite()) {
            return bad("specific force at the origin (g)", self.f0_g.norm());
        }
        if self.f0_frame == F0Frame::Table && !self.omega0_along_axis() {
            return bad(
                "initial angular rate across the axis (rad/s; a table-frame f0 needs the rate along the axis)",
                self.omega0_across_axis_rad_s(),
            );
        }
        Ok(())
    }

    /// `|ω0 − n (n·ω0)|` (rad/s): the part of the initial rate across the
    /// rotation axis n.
    pub fn omega0_across_axis_rad_s(&self) -> f64 {
        let n = self.axis.try_normalize(0.0).unwrap_or_else(Vector3::z);
        let w0 = self.omega0_rad_s;
        (w0 - n * n.dot(&w0)).norm()
    }

    /// True when the initial rate lies along the axis (to round-off), so
    /// the unit turns about that one axis, as a table-frame f0 needs.
    pub fn omega0_along_axis(&self) -> bool {
        self.omega0_across_axis_rad_s() <= 1e-12 * self.omega0_rad_s.norm().max(1.0)
    }
}

/// Truth of the motion at time t: `(f0 [g], ω̇ [rad/s²], ω [rad/s])`, all
/// in the unit frame. With α the spin-up acceleration, A and f_o the
/// oscillation, w_o = 2π f_o:
/// `ω = ω0 + n (α min(t, T_s) + A sin(w_o t))`,
/// `ω̇ = n (α [t ≤ T_s] + A w_o cos(w_o t))`, and the angle turned about n
/// `θ = (n·ω0) t + α (t ≤ T_s ? t²/2 : T_s²/2 + T_s (t − T_s)) + A (1 − cos(w_o t))/w_o`
/// rotates a table-frame f0 into the unit frame ([`F0Frame::Table`]).
pub fn motion_truth(m: &MotionProfile, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
    let n = m.axis.try_normalize(0.0).unwrap_or_else(Vector3::z);
    let alpha = m.angular_accel_rad_s2;
    let wo = 2.0 * std::f64::consts::PI * m.oscillation_hz;
    let amp = m.oscillation_amplitude_rad_s;
    let (osc_rate, osc_accel, osc_angle) = if wo > 0.0 {
        (
            amp * (wo * t).sin(),
            amp * wo * (wo * t).cos(),
            amp * (1.0 - (wo * t).cos()) / wo,
        )
    } else {
        (0.0, 0.0, 0.0)
    };
    let wd = n * (if t <= m.spin_up_s { alpha } else { 0.0 } + osc_accel);
    let w = m.omega0_rad_s + n * (alpha * t.min(m.spin_up_s) + osc_rate);
    let f0 = match m.f0_frame {
        F0Frame::Unit => m.f0_g,
        F0Frame::Table => {
            let ts = m.spin_up_s;
            let spin = if t <= ts {
                0.5 * alpha * t * t
            } else {
                alpha * ts * (0.5 * ts + (t - ts))
            };
            let theta = n.dot(&m.omega0_rad_s) * t + spin + osc_angle;
            let v = m.f0_g;
            let (s, c) = theta.sin_cos();
            v * c - n.cross(&v) * s + n * (n.dot(&v) * (1.0 - c))
        }
    };
    (f0, wd, w)
}

/// Simulated motion record: times `t_k = k / rate_hz` and every output.
/// The whole record in memory; [`motion_samples`] streams it.
pub fn simulate_motion(
    geometry: &Geometry,
    truth: &GfimuTruth,
    m: &MotionProfile,
    noise: f64,
    seed: u64,
) -> Result<Vec<(f64, Vec<f64>)>> {
    Ok(motion_samples(geometry, truth, m, noise, seed)?.collect())
}

/// Most samples one simulated motion may have (duration × rate): 10⁷.
pub const MAX_MOTION_SAMPLES: usize = 10_000_000;

/// The simulated motion record one sample at a time (constant memory;
/// the same numbers, in the same order, as [`simulate_motion`]).
pub fn motion_samples<'a>(
    geometry: &'a Geometry,
    truth: &'a GfimuTruth,
    m: &'a MotionProfile,
    noise: f64,
    seed: u64,
) -> Result<MotionSamples<'a>> {
    truth.check(geometry)?;
    m.check()?;
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Error::InvalidValue {
            what: "output noise (>= 0)".into(),
            value: noise.to_string(),
        });
    }
    let count = (m.duration_s * m.rate_hz).floor() + 1.0;
    if count > MAX_MOTION_SAMPLES as f64 {
        return Err(Error::InvalidValue {
            what: "number of samples (duration x rate, at most 1e7)".into(),
            value: count.to_string(),
        });
    }
    Ok(MotionSamples {
        geometry,
        truth,
        m,
        noise,
        r: rng(seed),
        k: 0,
        count: count as usize,
    })
}

/// Iterator of [`motion_samples`]: `(t_k, outputs)`.
pub struct MotionSamples<'a> {
    geometry: &'a Geometry,
    truth: &'a GfimuTruth,
    m: &'a MotionProfile,
    noise: f64,
    r: rand::rngs::ChaCha8Rng,
    k: usize,
    count: usize,
}

impl Iterator for MotionSamples<'_> {
    type Item = (f64, Vec<f64>);

    fn next(&mut self) -> Option<Self::Item> {
        if self.k >= self.count {
            return None;
        }
        let m = self.m;
        let t = self.k as f64 / m.rate_hz;
        self.k += 1;
        let (f0, wd, w) = motion_truth(m, t);
        let forces: Vec<Vector3<f64>> = self
            .geometry
            .accelerometers()
            .iter()
            .map(|a| {
                let p = a.position_m;
                f0 + (wd.cross(&p) + w.cross(&w.cross(&p))) / m.gravity_m_s2
            })
            .collect();
        let r = &mut self.r;
        let noise = self.noise;
        let e = self
            .truth
            .outputs(&forces)
            .into_iter()
            .map(|e| e + normal(r, noise))
            .collect();
        Some((t, e))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.count - self.k;
        (n, Some(n))
    }
}

/// What a simulated test records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SimKind {
    /// The six-position static test ([`six_positions`]), `samples` per
    /// position: the input of `gfimu calibrate`.
    Static {
        /// Samples per position (at least 1).
        samples: usize,
    },
    /// A rate-table motion: the input of `gfimu solve`.
    Motion(MotionProfile),
}

/// One simulated gyro-free unit test: the array, a truth built from a
/// nominal scale factor ([`GfimuTruth::typical`]), white output noise,
/// what is recorded, and the seed (same seed, same file).
#[derive(Debug, Clone, PartialEq)]
pub struct GfimuSim {
    /// The array.
    pub array: ArrayGeometry,
    /// Nominal scale factor of every accelerometer (output/g).
    pub k1_out_per_g: f64,
    /// Output noise σ of one sample (output).
    pub noise: f64,
    /// Static test or motion.
    pub kind: SimKind,
    /// Random seed.
    pub seed: u64,
}

impl GfimuSim {
    /// Refuse a configuration that cannot be simulated, naming the option:
    /// a zero or non-finite `k1`, a negative or non-finite `noise`, no
    /// static samples or more than [`crate::sim::MAX_SIM_ROWS`] rows, and
    /// for a motion a zero axis, a non-finite spin-up, an oscillation at or
    /// above half the sample rate (or an amplitude without a frequency), a
    /// table-frame f0 with a rate across the axis, and everything
    /// [`MotionProfile::check`] refuses.
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Unsupported(msg));
        if !(self.k1_out_per_g.is_finite() && self.k1_out_per_g != 0.0) {
            return bad(format!(
                "k1 must be a finite non-zero number, got {}",
                shown(self.k1_out_per_g)
            ));
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return bad(format!(
                "noise must be a non-negative number, got {}",
                shown(self.noise)
            ));
        }
        match &self.kind {
            SimKind::Static { samples } => {
                if *samples == 0 {
                    return bad("samples must be at least 1".into());
                }
                crate::sim::check_rows(&[
                    ("samples", *samples as f64),
                    ("positions", six_positions().len() as f64),
                ])
            }
            SimKind::Motion(m) => {
                if m.axis.norm() == 0.0 {
                    return bad("axis must not be zero".into());
                }
                if !(m.angular_accel_rad_s2.is_finite()
                    && m.spin_up_s.is_finite()
                    && m.spin_up_s >= 0.0)
                {
                    return bad(
                        "`angular_accel_rad_s2` and `spin_up_s` must be finite (spin-up >= 0)"
                            .into(),
                    );
                }
                if !(m.oscillation_hz.is_finite()
                    && m.oscillation_hz >= 0.0
                    && m.oscillation_hz < m.rate_hz / 2.0)
                {
                    return bad(format!(
                        "`oscillation_hz` must be at least 0 and below half of `rate_hz` ({} Hz), got {}",
                        shown(m.rate_hz / 2.0),
                        shown(m.oscillation_hz)
                    ));
                }
                if !m.oscillation_amplitude_rad_s.is_finite()
                    || (m.oscillation_amplitude_rad_s != 0.0 && m.oscillation_hz == 0.0)
                {
                    return bad(
                        "`oscillation_amplitude_rad_s` must be finite, with `oscillation_hz` > 0 when it is not 0"
                            .into(),
                    );
                }
                if m.f0_frame == F0Frame::Table && !m.omega0_along_axis() {
                    return bad(
                        "f0_frame table: `omega0_rad_s` must lie along axis (the unit turns about that one axis)"
                            .into(),
                    );
                }
                m.check()?;
                let count = (m.duration_s * m.rate_hz).floor() + 1.0;
                if count > MAX_MOTION_SAMPLES as f64 {
                    return Err(Error::InvalidValue {
                        what: "number of samples (duration x rate, at most 1e7)".into(),
                        value: count.to_string(),
                    });
                }
                Ok(())
            }
        }
    }

    /// The truth of every accelerometer ([`GfimuTruth::typical`]).
    pub fn truth(&self) -> GfimuTruth {
        GfimuTruth::typical(&self.array.geometry, self.k1_out_per_g)
    }

    /// The `#` comment lines of the simulated file: the array, the seed,
    /// every accelerometer's truth and, for a motion, the profile.
    pub fn notes(&self) -> Vec<String> {
        let truth = self.truth();
        let mut notes = vec![format!(
            "simulated gyro-free unit ({}), seed {}",
            self.array.label, self.seed
        )];
        for (j, a) in self.array.geometry.accelerometers().iter().enumerate() {
            let ks = truth.ks[j];
            notes.push(format!(
                "truth {}: K0 = {} output, Ks = [{}, {}, {}] output/g",
                a.name, truth.k0[j], ks.x, ks.y, ks.z
            ));
        }
        if let SimKind::Motion(m) = &self.kind {
            notes.push(format!(
                "motion: axis {:?}, {} rad/s^2 for {} s, f0 {:?} g, omega0 {:?} rad/s",
                m.axis.as_slice(),
                m.angular_accel_rad_s2,
                m.spin_up_s,
                m.f0_g.as_slice(),
                m.omega0_rad_s.as_slice()
            ));
            if m.f0_frame == F0Frame::Table || m.oscillation_amplitude_rad_s != 0.0 {
                notes.push(format!(
                    "f0 frame: {}; rate oscillation {} rad/s at {} Hz",
                    if m.f0_frame == F0Frame::Table {
                        "table (turns with the rotation)"
                    } else {
                        "unit"
                    },
                    m.oscillation_amplitude_rad_s,
                    m.oscillation_hz
                ));
            }
        }
        notes
    }

    /// Simulate (deterministic for a given seed) and write the CSV to
    /// `out`: the static format of [`super::input::write_static`] or the
    /// motion format of [`super::input::write_motion`], streamed row by row
    /// (10⁶ motion samples need no memory for the file). Call
    /// [`GfimuSim::validate`] first: a configuration it refuses is an
    /// `InvalidInput` error here.
    pub fn write<W: Write>(&self, out: W) -> std::io::Result<W> {
        let invalid =
            |e: Error| std::io::Error::new(std::io::ErrorKind::InvalidInput, e.to_string());
        self.validate().map_err(invalid)?;
        let g = &self.array.geometry;
        let truth = self.truth();
        // Rows only, so any CSV reader takes the file as it is; the truth
        // is in [`GfimuSim::notes`] (the CLI's --truth-out).
        let notes: Vec<String> = Vec::new();
        match &self.kind {
            SimKind::Static { samples } => {
                let data =
                    simulate_static(g, &truth, &six_positions(), *samples, self.noise, self.seed)
                        .map_err(invalid)?;
                super::input::write_static(&data, g, &notes, out)
            }
            SimKind::Motion(m) => {
                let series =
                    motion_samples(g, &truth, m, self.noise, self.seed).map_err(invalid)?;
                super::input::write_motion(series, g, &notes, out)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table-frame f0 seen from the turning unit keeps its length and
    /// its component along the axis, and obeys ḟ = −ω × f (a vector fixed
    /// outside, seen from a rotating frame); ω̇ is the derivative of ω.
    #[test]
    fn table_frame_f0_turns_with_the_unit() {
        let m = MotionProfile {
            axis: Vector3::new(0.3, -0.2, 1.0),
            omega0_rad_s: Vector3::new(0.3, -0.2, 1.0) * 0.1,
            f0_g: Vector3::new(0.1, 0.2, 1.0),
            f0_frame: F0Frame::Table,
            oscillation_amplitude_rad_s: 0.4,
            oscillation_hz: 0.7,
            ..MotionProfile::rate_table()
        };
        m.check().unwrap();
        let n = m.axis.normalize();
        let h = 1e-6;
        for k in 0..40 {
            let t = 0.05 + k as f64 * 0.1;
            let (f, wd, w) = motion_truth(&m, t);
            assert!((f.norm() - m.f0_g.norm()).abs() < 1e-12);
            assert!((f.dot(&n) - m.f0_g.dot(&n)).abs() < 1e-12);
            let (fp, _, wp) = motion_truth(&m, t + h);
            let (fm, _, wm) = motion_truth(&m, t - h);
            let fdot = (fp - fm) / (2.0 * h);
            assert!((fdot + w.cross(&f)).norm() < 1e-7, "t = {t}: {fdot:?}");
            if (t - m.spin_up_s).abs() > 2.0 * h {
                assert!(((wp - wm) / (2.0 * h) - wd).norm() < 1e-6, "t = {t}");
            }
        }
        // A rate across the axis cannot turn a table-frame f0: refused.
        let bad = MotionProfile {
            omega0_rad_s: Vector3::x(),
            ..m
        };
        assert!(bad.check().is_err());
        // An oscillation at or above Nyquist is refused.
        let bad = MotionProfile {
            oscillation_hz: 50.0,
            ..m
        };
        assert!(bad.check().is_err());
    }
}
