//! IMU session simulator: three accelerometers and three gyros with a known
//! bias, scale-and-misalignment and g-sensitivity, in a Ferraris sequence,
//! at known orientations (multi-position) or at random orientations joined
//! by smooth rotations (autocalibration).
//!
//! # Sensor model (the truth)
//! `a_raw = A_a f + b_a + n_a`, `ω_raw = A_g ω + K_ga f + b_g + n_g`, with
//! `f` the specific force in the IMU frame (m/s²; `+g` along the axis that
//! points up) and `ω` the angular rate (rad/s). [`ImuTruth`] converts this
//! truth into imucal's (`K_a, R_a, …`) and imu_tk's (`T, K, b`) parameters.
//!
//! # Motion
//! Navigation frame east-north-up: `f_nav = (0, 0, g)`, Earth rate
//! `Ω (0, cos φ, sin φ)` (only with a latitude). An attitude is the matrix
//! `C` (IMU → nav); a rotation of angle Θ about the IMU-fixed axis `a`
//! takes `T_m` seconds with `θ(t) = Θ (τ − sin 2πτ / 2π)`, `τ = t/T_m`, so
//! the rate `θ̇ a` starts and ends at zero and `C(t) = C_k Rot(a, θ(t))`
//! exactly (the gyro sees `ω = θ̇ a`).

use rand_distr::{Distribution, Uniform};

use super::ferraris::FerrarisMatrices;
use super::{M3, V3};
use crate::error::{Error, Result};
use crate::sim::{normal, rng};
use crate::units::EARTH_RATE_RAD_S;

pub use super::sim_options::{ImuSimOptions, ImuSimulator, SequenceKind, DEFAULT_POSITIONS};

/// The sensor truth (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ImuTruth {
    /// Accelerometer scale-and-misalignment `A_a` (output per m/s²).
    pub acc_a: M3,
    /// Accelerometer bias (output).
    pub acc_b: V3,
    /// Gyro scale-and-misalignment `A_g` (output per rad/s).
    pub gyr_a: M3,
    /// Gyro g-sensitivity `K_ga` (output per m/s²).
    pub gyr_k_ga: M3,
    /// Gyro bias (output).
    pub gyr_b: V3,
}

/// imu_tk's triad parameters: `calibrated = T K (raw − b)` with
/// `T = [[1, −m_yz, m_zy], [m_xz, 1, −m_zx], [−m_xy, m_yx, 1]]` and
/// `K = diag(s)` (the accelerometer has `m_xz = m_xy = m_yx = 0`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriadParams {
    /// `m_yz, m_zy, m_zx, m_xz, m_xy, m_yx`.
    pub mis: [f64; 6],
    /// Scales `s_x, s_y, s_z`.
    pub scale: [f64; 3],
    /// Biases `b_x, b_y, b_z` (raw units).
    pub bias: [f64; 3],
}

impl TriadParams {
    /// The misalignment matrix T.
    pub fn t(&self) -> M3 {
        let [yz, zy, zx, xz, xy, yx] = self.mis;
        M3::new(1.0, -yz, zy, xz, 1.0, -zx, -xy, yx, 1.0)
    }
    /// The scale matrix K.
    pub fn k(&self) -> M3 {
        M3::from_diagonal(&V3::from(self.scale))
    }
    /// Calibrated sample `T K (raw − b)`.
    pub fn apply(&self, raw: &V3) -> V3 {
        self.t() * self.k() * (raw - V3::from(self.bias))
    }
    /// Parameters from `M = T K` (any M with a non-zero diagonal) and `b`.
    pub fn from_tk(m: &M3, b: &V3) -> TriadParams {
        let s = [m[(0, 0)], m[(1, 1)], m[(2, 2)]];
        let t = M3::from_fn(|i, j| m[(i, j)] / s[j]);
        TriadParams {
            mis: [
                -t[(0, 1)],
                t[(0, 2)],
                -t[(1, 2)],
                t[(1, 0)],
                -t[(2, 0)],
                t[(2, 1)],
            ],
            scale: s,
            bias: [b[0], b[1], b[2]],
        }
    }
}

impl ImuTruth {
    /// A truth from imu_tk parameters (accelerometer: `m_xz = m_xy = m_yx`
    /// must be 0 for the accelerometer's frame to be the IMU frame).
    pub fn from_imu_tk(acc: &TriadParams, gyr: &TriadParams, k_ga: M3) -> Option<ImuTruth> {
        Some(ImuTruth {
            acc_a: (acc.t() * acc.k()).try_inverse()?,
            acc_b: V3::from(acc.bias),
            gyr_a: (gyr.t() * gyr.k()).try_inverse()?,
            gyr_k_ga: k_ga,
            gyr_b: V3::from(gyr.bias),
        })
    }

    /// The truth in imu_tk's parameters (accelerometer, gyro; the gyro's
    /// g-sensitivity is outside imu_tk's model).
    pub fn imu_tk(&self) -> Option<(TriadParams, TriadParams)> {
        let a = self.acc_a.try_inverse()?;
        let g = self.gyr_a.try_inverse()?;
        Some((
            TriadParams::from_tk(&a, &self.acc_b),
            TriadParams::from_tk(&g, &self.gyr_b),
        ))
    }

    /// The truth in imucal's definitions (gyro in deg/s).
    pub fn ferraris(&self) -> FerrarisMatrices {
        let (k_a, r_a) = scale_rows(&self.acc_a);
        let a_deg = self.gyr_a * std::f64::consts::PI / 180.0;
        let (k_g, r_g) = scale_rows(&a_deg);
        FerrarisMatrices {
            k_a,
            r_a,
            b_a: self.acc_b,
            k_g,
            r_g,
            k_ga: self.gyr_k_ga,
            b_g: self.gyr_b,
        }
    }

    /// Raw accelerometer and gyro outputs (noise-free) for `f`, `ω`.
    pub fn raw(&self, f: &V3, w: &V3) -> (V3, V3) {
        (
            self.acc_a * f + self.acc_b,
            self.gyr_a * w + self.gyr_k_ga * f + self.gyr_b,
        )
    }

    /// A typical MEMS IMU in raw counts: about 2000 counts/g and 940
    /// counts/(rad/s) (16.4 counts/(deg/s)), biases of tens of counts,
    /// misalignments of a few mrad, g-sensitivity of 0.01 counts/(m/s²)…
    pub fn mems_counts() -> ImuTruth {
        let acc = TriadParams {
            mis: [0.004, -0.003, 0.002, 0.0, 0.0, 0.0],
            scale: [1.0 / 208.5, 1.0 / 208.0, 1.0 / 214.8],
            bias: [-6.0, -48.3, -29.0],
        };
        let gyr = TriadParams {
            mis: [0.003, -0.002, 0.004, -0.001, 0.002, -0.003],
            scale: [1.0 / 955.5, 1.0 / 927.5, 1.0 / 931.2],
            bias: [1.96, -4.47, -3.65],
        };
        let k_ga = M3::new(
            0.002, 0.014, -0.009, -0.016, 0.005, 0.008, 0.018, -0.009, -0.004,
        );
        ImuTruth::from_imu_tk(&acc, &gyr, k_ga).expect("invertible")
    }

    /// A random truth around [`ImuTruth::mems_counts`]: every scale within
    /// ±5 %, biases ±50 counts, misalignments ±10 mrad, K_ga ±0.02.
    pub fn random_around_mems(seed: u64) -> ImuTruth {
        let mut r = rng(seed);
        let base = ImuTruth::mems_counts();
        let (mut acc, mut gyr) = base.imu_tk().expect("invertible");
        let u = |r: &mut rand::rngs::ChaCha8Rng, h: f64| {
            Uniform::new(-h, h).map_or(0.0, |d| d.sample(r))
        };
        for k in 0..3 {
            acc.scale[k] *= 1.0 + u(&mut r, 0.05);
            gyr.scale[k] *= 1.0 + u(&mut r, 0.05);
            acc.bias[k] += u(&mut r, 50.0);
            gyr.bias[k] += u(&mut r, 10.0);
            acc.mis[k] = u(&mut r, 0.01);
        }
        for k in 0..6 {
            gyr.mis[k] = u(&mut r, 0.01);
        }
        let k_ga = M3::from_fn(|_, _| u(&mut r, 0.02));
        ImuTruth::from_imu_tk(&acc, &gyr, k_ga).expect("invertible")
    }

    /// The simulators' sensor: [`ImuTruth::mems_counts`] for `truth_seed`
    /// 0, else [`ImuTruth::random_around_mems`] with that seed; without
    /// `g_sensitivity` the gyro's K_ga is zero (the autocalibration's model).
    pub fn of_seed(truth_seed: u64, g_sensitivity: bool) -> ImuTruth {
        let mut t = if truth_seed == 0 {
            ImuTruth::mems_counts()
        } else {
            ImuTruth::random_around_mems(truth_seed)
        };
        if !g_sensitivity {
            t.gyr_k_ga = M3::zeros();
        }
        t
    }

    /// The truth as the JSON a simulator writes beside its session:
    /// `imucal` (imucal's `K_a, R_a, b_a, K_g, R_g, K_ga, b_g`, lists of
    /// rows, gyro in deg/s), `imu_tk` (`acc`, `gyr` as `{"T", "K", "b"}`)
    /// and `model` (`acc_A`, `acc_b`, `gyr_A`, `gyr_K_ga`, `gyr_b` of the
    /// sensor model above, with their `units`). Fails when the truth is
    /// singular.
    pub fn to_json(&self) -> Result<serde_json::Value> {
        use super::rows;
        use serde_json::json;
        let f = self.ferraris();
        let mut imucal = serde_json::Map::new();
        for q in super::ferraris::QUANTITIES {
            let v = match f.matrix(q) {
                Some(m) => json!(rows(&m)),
                None => {
                    let b = if q == "b_a" { f.b_a } else { f.b_g };
                    json!([b[0], b[1], b[2]])
                }
            };
            imucal.insert(q.to_string(), v);
        }
        let tk = self
            .imu_tk()
            .ok_or_else(|| Error::Unsupported("the truth is singular".into()))?;
        let triad = |p: &TriadParams| json!({"T": rows(&p.t()), "K": rows(&p.k()), "b": p.bias});
        Ok(json!({
            "imucal": imucal,
            "imu_tk": {"acc": triad(&tk.0), "gyr": triad(&tk.1)},
            "model": {
                "acc_A": rows(&self.acc_a), "acc_b": [self.acc_b[0], self.acc_b[1], self.acc_b[2]],
                "gyr_A": rows(&self.gyr_a), "gyr_K_ga": rows(&self.gyr_k_ga),
                "gyr_b": [self.gyr_b[0], self.gyr_b[1], self.gyr_b[2]],
                "units": "acc_A output/(m/s^2), gyr_A output/(rad/s), gyr_K_ga output/(m/s^2), biases output"
            }
        }))
    }
}

/// `A = K R` with `K = diag(‖row_i(A)‖)` and unit-norm rows in R.
fn scale_rows(a: &M3) -> (M3, M3) {
    let k = M3::from_diagonal(&V3::new(a.row(0).norm(), a.row(1).norm(), a.row(2).norm()));
    let r = M3::from_fn(|i, j| a[(i, j)] / k[(i, i)]);
    (k, r)
}

/// One sample of a simulated session.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuSample {
    /// Time (s).
    pub time_s: f64,
    /// Section label (`x_p`, …; empty when none).
    pub part: String,
    /// Raw accelerometer output.
    pub acc: V3,
    /// Raw gyro output.
    pub gyr: V3,
    /// True specific-force direction (unit vector, IMU frame) when static.
    pub up: Option<V3>,
    /// True north direction (unit vector, IMU frame) when static.
    pub north: Option<V3>,
}

/// The sequence of a simulated session.
#[derive(Debug, Clone, PartialEq)]
pub enum Sequence {
    /// imucal's nine sections: `x_p, x_a, y_p, y_a, z_p, z_a` static,
    /// then `x_rot, y_rot, z_rot`, each one rotation of `rotation_deg`
    /// (deg, imucal's sign: −360 is clockwise seen from the tip) about the
    /// axis pointing up, lasting `rotation_s` seconds.
    Ferraris {
        /// Rotation angle (deg).
        rotation_deg: f64,
        /// Duration of one rotation (s).
        rotation_s: f64,
    },
    /// A still start of `init_s` seconds, then `positions` random
    /// orientations joined by rotations about horizontal axes (45–135°,
    /// `move_s` seconds each).
    Random {
        /// Orientations after the start.
        positions: usize,
        /// Duration of the still start (s).
        init_s: f64,
        /// Duration of one rotation (s).
        move_s: f64,
    },
    /// As [`Sequence::Random`], but every turn is 90° about a horizontal
    /// axis of the sensor, so the sensor visits the six faces of a cube
    /// again and again: a hand-held session on a cube-shaped fixture (the
    /// RealSense T265 recording published with imu_tk has 41 still
    /// intervals on 6 faces).
    Faces {
        /// Orientations after the start.
        positions: usize,
        /// Duration of the still start (s).
        init_s: f64,
        /// Duration of one rotation (s).
        move_s: f64,
    },
    /// Static positions with the given up directions (IMU frame, unit
    /// vectors), each at a heading; no motion between them.
    Positions {
        /// Up direction of each position.
        up: Vec<V3>,
        /// Then rotations `x_rot, y_rot, z_rot` of this angle (deg) and
        /// duration (s), as in the Ferraris sequence.
        rotations: Option<(f64, f64)>,
    },
}

impl Sequence {
    /// Static positions given by their labels (see
    /// [`super::input::position_direction`]: `x_p`, `x_p+y_a`, …), then the
    /// rotations `x_rot, y_rot, z_rot` of `(deg, s)` when given. A label
    /// that is not a position is refused naming it.
    pub fn positions<S: AsRef<str>>(
        labels: &[S],
        rotations: Option<(f64, f64)>,
    ) -> Result<Sequence> {
        let up = labels
            .iter()
            .map(|l| {
                super::input::position_direction(l.as_ref())
                    .map_err(|e| Error::Unsupported(format!("positions: {e}")))
            })
            .collect::<Result<Vec<V3>>>()?;
        Ok(Sequence::Positions { up, rotations })
    }
}

/// The columns a simulated session is written with (the input format of
/// the procedure it is for; see [`super::input::write`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// `time_s, part, acc_x … gyr_z` (input of `imu ferraris`).
    Ferraris,
    /// `time_s, acc_x … gyr_z` (input of `imu autocal`).
    Random,
    /// `time_s, position, fx, fy, fz[, nx, ny, nz], acc_x … gyr_z` (input of
    /// `imu multipos`); `labels` name the positions in order.
    Positions {
        /// Label of every position ([`Sequence::positions`]).
        labels: Vec<String>,
        /// Write the north direction (a latitude was simulated).
        north: bool,
    },
}

/// Options of [`simulate`].
#[derive(Debug, Clone, PartialEq)]
pub struct ImuSim {
    /// The sensor.
    pub truth: ImuTruth,
    /// The sequence.
    pub sequence: Sequence,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Duration of each static position (s).
    pub static_s: f64,
    /// Gravity (m/s²).
    pub gravity: f64,
    /// Accelerometer white noise per sample (output units).
    pub noise_acc: f64,
    /// Gyro white noise per sample (output units).
    pub noise_gyr: f64,
    /// Latitude (deg) for the Earth rate; `None` leaves it out.
    pub latitude_deg: Option<f64>,
    /// Seed.
    pub seed: u64,
}

impl ImuSim {
    /// Refuse a session that cannot be simulated or is too large to
    /// write, naming the option: a sample rate outside (0, 1e5] Hz, a
    /// static duration outside (0, 1e5] s, a gravity outside (0, 100], a
    /// noise outside [0, 1e6]; rotations of zero or more than 3600 deg or
    /// lasting outside (0, 1e4] s; a still start outside (0, 1e5] s, moves
    /// outside (0, 1e4] s, 0 or more than 10 000 orientations; 0 or more
    /// than 1000 positions; more than [`crate::sim::MAX_SIM_ROWS`] rows.
    pub fn validate(&self) -> Result<()> {
        let range = |what: &str, x: f64, lo_open: bool, hi: f64| -> Result<()> {
            let lo_ok = if lo_open { x > 0.0 } else { x >= 0.0 };
            if x.is_finite() && lo_ok && x <= hi {
                Ok(())
            } else {
                crate::options::invalid(
                    what,
                    format!(
                        "must be {} 0 and <= {hi}, got {}",
                        if lo_open { ">" } else { ">=" },
                        crate::error::short_number(&x.to_string())
                    ),
                )
            }
        };
        range("rate_hz", self.rate_hz, true, 1e5)?;
        range("static_s", self.static_s, true, 1e5)?;
        range("gravity_m_s2", self.gravity, true, 100.0)?;
        range("noise_acc", self.noise_acc, false, 1e6)?;
        range("noise_gyr", self.noise_gyr, false, 1e6)?;
        if let Some(lat) = self.latitude_deg {
            crate::options::check_latitude_deg(lat)?;
        }
        let rotation = |deg: f64, dur: f64| -> Result<()> {
            if !(deg.is_finite() && deg != 0.0 && deg.abs() <= 3600.0) {
                return crate::options::invalid(
                    "rotation_deg",
                    format!(
                        "must be non-zero with |A| <= 3600 deg, got {}",
                        crate::error::short_number(&deg.to_string())
                    ),
                );
            }
            range("rotation_s", dur, true, 1e4)
        };
        let (rate, stat) = (self.rate_hz, self.static_s);
        match &self.sequence {
            Sequence::Ferraris {
                rotation_deg,
                rotation_s,
            } => {
                rotation(*rotation_deg, *rotation_s)?;
                crate::sim::check_rows(&[(
                    "(6 x `static_s` + 3 x `rotation_s`) x `rate_hz`",
                    (6.0 * stat + 3.0 * rotation_s) * rate,
                )])
            }
            Sequence::Random {
                positions,
                init_s,
                move_s,
            }
            | Sequence::Faces {
                positions,
                init_s,
                move_s,
            } => {
                range("init_static_s", *init_s, true, 1e5)?;
                range("move_s", *move_s, true, 1e4)?;
                if !(1..=10_000).contains(positions) {
                    return crate::options::invalid(
                        "orientations",
                        format!("must be within 1..10000, got {positions}"),
                    );
                }
                crate::sim::check_rows(&[(
                    "(`init_static_s` + orientations x (`static_s` + `move_s`)) x `rate_hz`",
                    (init_s + *positions as f64 * (stat + move_s)) * rate,
                )])
            }
            Sequence::Positions { up, rotations } => {
                if up.is_empty() || up.len() > 1000 {
                    return crate::options::invalid(
                        "positions",
                        format!("must be 1 to 1000 labels, got {}", up.len()),
                    );
                }
                let mut rot_s = 0.0;
                if let Some((deg, dur)) = rotations {
                    rotation(*deg, *dur)?;
                    rot_s = 3.0 * dur;
                }
                crate::sim::check_rows(&[(
                    "(positions x `static_s` + 3 x `rotation_s`) x `rate_hz`",
                    (up.len() as f64 * stat + rot_s) * rate,
                )])
            }
        }
    }
}

/// Standard deviation of the tilt of each face visit in
/// [`Sequence::Faces`] (deg): a hand-held fixture (the T265 recording's
/// faces lie 2.5–4.5° off the sensor axes).
pub const FACE_TILT_DEG: f64 = 3.0;

/// Rotation by `angle` (rad) about the unit `axis` (Rodrigues).
pub fn rotation(axis: &V3, angle: f64) -> M3 {
    let k = axis.cross_matrix();
    M3::identity() + k * angle.sin() + k * k * (1.0 - angle.cos())
}

/// An attitude (IMU → nav, ENU) with `up` (IMU frame) pointing up; the
/// heading is fixed by the IMU axis most horizontal.
fn attitude_up(up: &V3) -> M3 {
    let u = up.normalize();
    let k = (0..3)
        .min_by(|&a, &b| u[a].abs().total_cmp(&u[b].abs()))
        .unwrap_or(0);
    let mut e = V3::zeros();
    e[k] = 1.0;
    let north = (e - u * u.dot(&e)).normalize();
    let east = north.cross(&u);
    // Rows of C are the nav axes (east, north, up) in the IMU frame.
    M3::from_rows(&[east.transpose(), north.transpose(), u.transpose()])
}

/// Simulate a session. Fails on non-finite or out-of-range options.
pub fn simulate(cfg: &ImuSim) -> Result<Vec<ImuSample>> {
    let bad = |what: &str, v: f64| Error::invalid_value(what, v);
    if !(cfg.rate_hz.is_finite() && cfg.rate_hz > 0.0 && cfg.rate_hz <= 1e5) {
        return Err(bad("sample rate (0 < Hz <= 1e5)", cfg.rate_hz));
    }
    if !(cfg.static_s.is_finite() && cfg.static_s > 0.0) {
        return Err(bad("static duration (s, > 0)", cfg.static_s));
    }
    super::check_gravity_magnitude(cfg.gravity)?;
    let mut r = rng(cfg.seed);
    let g = cfg.gravity;
    let n_static = (cfg.static_s * cfg.rate_hz).round().max(1.0) as usize;
    let mut w = Writer {
        cfg,
        r: &mut r,
        out: Vec::new(),
        dt: 1.0 / cfg.rate_hz,
    };
    match &cfg.sequence {
        Sequence::Ferraris {
            rotation_deg,
            rotation_s,
        } => {
            let ok_angle = rotation_deg.is_finite() && rotation_deg.abs() <= 36000.0;
            let ok_time = rotation_s.is_finite() && *rotation_s > 0.0;
            if !ok_angle || !ok_time {
                return Err(bad("rotation (deg, s)", *rotation_deg));
            }
            let labels = ["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"];
            for (k, l) in labels.iter().enumerate() {
                let mut up = V3::zeros();
                up[k / 2] = if k % 2 == 0 { 1.0 } else { -1.0 };
                let c = attitude_up(&(up * g.signum()));
                for _ in 0..n_static {
                    w.push(l, &c, &V3::zeros(), true);
                }
            }
            for (k, l) in ["x_rot", "y_rot", "z_rot"].iter().enumerate() {
                let mut up = V3::zeros();
                up[k] = 1.0;
                let c = attitude_up(&(up * g.signum()));
                w.rotate(l, &c, &up, rotation_deg.to_radians(), *rotation_s);
            }
        }
        Sequence::Random {
            positions,
            init_s,
            move_s,
        }
        | Sequence::Faces {
            positions,
            init_s,
            move_s,
        } => {
            let faces = matches!(cfg.sequence, Sequence::Faces { .. });
            if !(init_s.is_finite() && *init_s > 0.0 && move_s.is_finite() && *move_s > 0.0) {
                return Err(bad("init/move duration (s)", *init_s));
            }
            let mut c = attitude_up(&V3::new(0.0, 0.0, 1.0));
            let n_init = (init_s * cfg.rate_hz).round().max(1.0) as usize;
            for _ in 0..n_init {
                w.push("", &c, &V3::zeros(), true);
            }
            let ang = Uniform::new(45f64.to_radians(), 135f64.to_radians())
                .map_err(|e| Error::Unsupported(e.to_string()))?;
            // Faces: each visit tilted off the face by a few degrees (a hand
            // on a fixture), undone before the next quarter turn.
            let mut tilt: Option<(V3, f64)> = None;
            for _ in 0..*positions {
                if let Some((ax, th)) = tilt.take() {
                    c = w.rotate("", &c, &ax, -th, move_s / 3.0);
                }
                let up = c.row(2).transpose();
                let v = V3::new(normal(w.r, 1.0), normal(w.r, 1.0), normal(w.r, 1.0));
                let (axis, angle) = if faces {
                    // The sensor axis nearest the random horizontal one, by
                    // a quarter turn either way.
                    let h = up.cross(&v);
                    let i = (0..3)
                        .filter(|&i| up[i].abs() < 0.5)
                        .max_by(|&a, &b| h[a].abs().total_cmp(&h[b].abs()))
                        .unwrap_or(0);
                    let mut e = V3::zeros();
                    e[i] = 1.0;
                    (e, std::f64::consts::FRAC_PI_2 * h[i].signum())
                } else {
                    (up.cross(&v).normalize(), ang.sample(w.r))
                };
                if faces {
                    c = w.rotate("", &c, &axis, angle, move_s / 3.0);
                    let up = c.row(2).transpose();
                    let v = V3::new(normal(w.r, 1.0), normal(w.r, 1.0), normal(w.r, 1.0));
                    let ax = up.cross(&v).normalize();
                    let th = normal(w.r, FACE_TILT_DEG.to_radians());
                    c = w.rotate("", &c, &ax, th, move_s / 3.0);
                    tilt = Some((ax, th));
                } else {
                    c = w.rotate("", &c, &axis, angle, *move_s);
                }
                for _ in 0..n_static {
                    w.push("", &c, &V3::zeros(), true);
                }
            }
        }
        Sequence::Positions { up, rotations } => {
            for (k, u) in up.iter().enumerate() {
                if !(u.iter().all(|v| v.is_finite()) && u.norm() > 0.0) {
                    return Err(bad("position up direction", k as f64));
                }
                let c = attitude_up(&(u.normalize() * g.signum()));
                let label = format!("p{}", k + 1);
                for _ in 0..n_static {
                    w.push(&label, &c, &V3::zeros(), true);
                }
            }
            if let Some((deg, dur)) = rotations {
                if !(deg.is_finite() && dur.is_finite() && *dur > 0.0) {
                    return Err(bad("rotation (deg, s)", *deg));
                }
                for (k, l) in ["x_rot", "y_rot", "z_rot"].iter().enumerate() {
                    let mut axis = V3::zeros();
                    axis[k] = 1.0;
                    let c = attitude_up(&(axis * g.signum()));
                    w.rotate(l, &c, &axis, deg.to_radians(), *dur);
                }
            }
        }
    }
    Ok(w.out)
}

/// The session being written: one sample at a time, or a rotation.
struct Writer<'a> {
    cfg: &'a ImuSim,
    r: &'a mut rand::rngs::ChaCha8Rng,
    out: Vec<ImuSample>,
    dt: f64,
}

impl Writer<'_> {
    /// One sample at attitude `c` (IMU → nav) with body rate `w`.
    fn push(&mut self, part: &str, c: &M3, w: &V3, still: bool) {
        let cfg = self.cfg;
        let g = cfg.gravity;
        let earth = match cfg.latitude_deg {
            Some(lat) => {
                let p = lat.to_radians();
                c.transpose() * V3::new(0.0, p.cos(), p.sin()) * EARTH_RATE_RAD_S
            }
            None => V3::zeros(),
        };
        let f = c.transpose() * V3::new(0.0, 0.0, g);
        let (a, gy) = cfg.truth.raw(&f, &(w + earth));
        let r = &mut *self.r;
        let acc = a + V3::new(
            normal(r, cfg.noise_acc),
            normal(r, cfg.noise_acc),
            normal(r, cfg.noise_acc),
        );
        let gyr = gy
            + V3::new(
                normal(r, cfg.noise_gyr),
                normal(r, cfg.noise_gyr),
                normal(r, cfg.noise_gyr),
            );
        let t = self.out.len() as f64 * self.dt;
        self.out.push(ImuSample {
            time_s: t,
            part: part.to_string(),
            acc,
            gyr,
            up: still.then(|| c.row(2).transpose() * g.signum()),
            north: still.then(|| c.row(1).transpose()),
        });
    }

    /// A rotation of `angle` (rad) about the IMU axis `axis` from attitude
    /// `c0`, lasting `dur` seconds; returns the final attitude.
    fn rotate(&mut self, part: &str, c0: &M3, axis: &V3, angle: f64, dur: f64) -> M3 {
        use std::f64::consts::TAU;
        let n = (dur * self.cfg.rate_hz).round().max(2.0) as usize;
        let tm = n as f64 * self.dt;
        for i in 0..n {
            let tau = i as f64 * self.dt / tm;
            let th = angle * (tau - (TAU * tau).sin() / TAU);
            let rate = angle / tm * (1.0 - (TAU * tau).cos());
            let c = c0 * rotation(axis, th);
            self.push(part, &c, &(axis * rate), false);
        }
        c0 * rotation(axis, angle)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imu_tk_parameters_round_trip() {
        let t = ImuTruth::random_around_mems(3);
        let (a, g) = t.imu_tk().unwrap();
        let back = ImuTruth::from_imu_tk(&a, &g, t.gyr_k_ga).unwrap();
        assert!((back.acc_a - t.acc_a).abs().max() < 1e-12 * t.acc_a.abs().max());
        assert!((back.gyr_a - t.gyr_a).abs().max() < 1e-12 * t.gyr_a.abs().max());
        // The accelerometer frame is the IMU frame: no lower misalignments.
        assert_eq!(&a.mis[3..], &[0.0; 3]);
    }

    #[test]
    fn rotation_profile_ends_at_the_angle() {
        let cfg = ImuSim {
            truth: ImuTruth::mems_counts(),
            sequence: Sequence::Random {
                positions: 3,
                init_s: 1.0,
                move_s: 1.0,
            },
            rate_hz: 100.0,
            static_s: 1.0,
            gravity: 9.81,
            noise_acc: 0.0,
            noise_gyr: 0.0,
            latitude_deg: None,
            seed: 1,
        };
        let s = simulate(&cfg).unwrap();
        // Static samples read the truth at |f| = g.
        let last = s.last().unwrap();
        let f = cfg.truth.acc_a.try_inverse().unwrap() * (last.acc - cfg.truth.acc_b);
        assert!((f.norm() - 9.81).abs() < 1e-9);
        assert_eq!(s.len(), 100 + 3 * 200);
    }
}
