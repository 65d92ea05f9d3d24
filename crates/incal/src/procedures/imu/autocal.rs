//! Autocalibration of an IMU triad without a fixture (Tedaldi, Pretto &
//! Menegatti, ICRA 2014), in imu_tk's conventions.
//!
//! # Model
//! `calibrated = T K (raw − b)`, `K = diag(s_x, s_y, s_z)`,
//! `T = [[1, −m_yz, m_zy], [m_xz, 1, −m_zx], [−m_xy, m_yx, 1]]`; the
//! accelerometer defines the IMU frame (`m_xz = m_xy = m_yx = 0`), so its
//! calibrated output is in the unit of g (m/s²); the gyro's is rad/s.
//!
//! # Accelerometer (Tedaldi eq. 10)
//! In every still interval the calibrated specific force has magnitude g:
//! minimise `Σ (g − ‖T K (a − b)‖)²` over the nine parameters
//! (`m_yz, m_zy, m_zx, s, b`) by Gauss–Newton with an analytic Jacobian
//! (a step-halving line search keeps it descending from a far start).
//!
//! # Gyro (Tedaldi eq. 15)
//! Between consecutive still intervals the calibrated rates, integrated
//! with imu_tk's RK4 quaternion step (`q̇ = ½ Ω(ω) q`), rotate the gravity
//! direction of the first interval into that of the second:
//! residual `R(q)ᵀ ĝ₀ − ĝ₁`; nine parameters (six misalignments, three
//! scales); the bias is the mean over the initial still interval.
//!
//! # Methods
//! * [`Method::Tedaldi`] reproduces imu_tk's `MultiPosCalibration` step
//!   by step: thresholds `k·‖var(initial interval)‖` for k = 2…10 (window
//!   101 samples), intervals of at least 100 samples of which the first
//!   100 enter the accelerometer fit (unweighted), a k with fewer than 12
//!   intervals skipped, the k of the smallest cost ½Σr² kept; gravity
//!   directions from the means of whole intervals; gyro residuals of three
//!   components, unweighted. Its covariance is the plain least-squares one
//!   (`s²(JᵀJ)⁻¹`, s² from the residuals).
//! * [`Method::Incal`]: the k giving the most usable intervals (the
//!   smallest such k on a tie); every sample of each interval with
//!   `settle_s` trimmed from both ends; the accelerometer fitted on the
//!   interval means weighted by `n / σ²` (σ the scatter of the interval's
//!   residual about its mean), with the prior variance kept unless the
//!   residuals show lack of fit (χ², 5 %); the gyro residual projected on
//!   the two directions normal to ĝ₁ (the third component carries no
//!   information); the gyro parameters' covariance includes the
//!   propagated accelerometer and gyro-bias uncertainty
//!   (`A C Aᵀ` with `A = −(JᵀJ)⁻¹ Jᵀ ∂r/∂θ`).

use nalgebra::{DMatrix, DVector, Matrix4, Vector4};

use super::detect::{self, Interval};
use super::sim::TriadParams;
use super::{check_gravity, M3, V3};
use crate::error::{Error, Result};
use crate::estimation::{fit, propagate, Design, Estimates, Fit, FitOptions, Variance};
use crate::warning::{Warning, WarningCode};

/// Which autocalibration (`incal` or `tedaldi` in documents).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// incal's weighted form with full covariance (default).
    Incal,
    /// imu_tk's exact steps, for comparison.
    Tedaldi,
}

impl Method {
    /// `incal` or `tedaldi`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Incal => "incal",
            Method::Tedaldi => "tedaldi",
        }
    }
}

/// Initial values of the fits (imu_tk's `setInitAccCalibration` and
/// `setInitGyroCalibration`), for exact comparisons with imu_tk; each
/// absent value comes from the data (the accelerometer's from an ellipsoid
/// through the still-interval means, the gyro scale from the rotation
/// angles over the raw integrals). In the document as `init_acc_bias`,
/// `init_acc_scale`, `init_gyro_scale` (raw units; scales in calibrated
/// unit per raw unit) when given.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Initial {
    /// Accelerometer bias (raw units), e.g. 32768 for 16-bit offset counts.
    pub acc_bias: Option<[f64; 3]>,
    /// Accelerometer scale (m/s² per raw unit).
    pub acc_scale: Option<[f64; 3]>,
    /// Gyro scale (rad/s per raw unit), e.g. 1/6258 for an Xsens in counts.
    pub gyro_scale: Option<[f64; 3]>,
}

impl Initial {
    /// Refuse a non-finite value or a scale of 0, naming the option.
    pub fn validate(&self) -> Result<()> {
        for (key, v, scale) in [
            ("init_acc_bias", self.acc_bias, false),
            ("init_acc_scale", self.acc_scale, true),
            ("init_gyro_scale", self.gyro_scale, true),
        ] {
            let Some(v) = v else { continue };
            for x in v {
                if !x.is_finite() || (scale && x == 0.0) || x.abs() > 1e12 {
                    let need = if scale {
                        "must be finite, non-zero and within 1e12"
                    } else {
                        "must be finite and within 1e12"
                    };
                    return Error::invalid(format!("{key} ({need})"), x);
                }
            }
        }
        Ok(())
    }
}

/// Options of [`autocal`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutocalOptions {
    /// Gravity magnitude (m/s²).
    pub gravity: f64,
    /// Duration of the initial still interval (s; imu_tk's default 50… the
    /// app sets 50, the library 30).
    pub init_static_s: f64,
    /// Method.
    pub method: Method,
    /// Variance window (samples, odd, ≥ 11).
    pub window: usize,
    /// Samples an interval needs (imu_tk: 100).
    pub min_samples: usize,
    /// Intervals a threshold needs (imu_tk: 12).
    pub min_intervals: usize,
    /// Time trimmed from both ends of each interval (incal method, s).
    pub settle_s: f64,
    /// Initial values given by the user.
    pub init: Initial,
}

impl AutocalOptions {
    /// imu_tk's settings (method tedaldi) or incal's, with an initial
    /// still interval of `init_static_s`.
    pub fn new(method: Method, gravity: f64, init_static_s: f64) -> Self {
        Self {
            gravity,
            init_static_s,
            method,
            window: 101,
            min_samples: 100,
            min_intervals: 12,
            settle_s: if method == Method::Incal { 0.1 } else { 0.0 },
            init: Initial::default(),
        }
    }
}

/// Options of the [`Autocal`] procedure (a record read from a file). In
/// the document: `{"rate_hz", "method", "gravity_m_s2", "init_static_s",
/// "settle_s", "window_samples", "min_samples"}` (`settle_s` as used: 0 for
/// method `tedaldi`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutocalSessionOptions {
    /// Sample rate (Hz); the record's `time_s`, when present, gives the
    /// time steps instead.
    pub rate_hz: f64,
    /// Method.
    pub method: Method,
    /// Gravity magnitude (m/s², > 0): the calibrated accelerometer output
    /// is in this unit.
    pub gravity_m_s2: f64,
    /// Duration of the still start (s).
    pub init_static_s: f64,
    /// Time trimmed from both ends of every still interval (s; method
    /// `incal` only).
    pub settle_s: f64,
    /// Initial values of the fits (absent: from the data).
    pub init: Initial,
    /// Put rows that are out of time order in order instead of refusing
    /// them (warning `time-sorted`).
    pub sort_time: bool,
}

impl AutocalSessionOptions {
    /// Refuse options the method cannot use, naming the option: a sample
    /// rate outside (0, 1e6] Hz, a gravity outside (0, 100], a still start
    /// outside (0, 1e6] s, a settling time outside [0, 1000] s.
    pub fn validate(&self) -> Result<()> {
        super::check_rate_hz(self.rate_hz)?;
        super::check_gravity_magnitude(self.gravity_m_s2)?;
        if !(self.init_static_s.is_finite()
            && self.init_static_s > 0.0
            && self.init_static_s <= 1e6)
        {
            return Err(Error::InvalidValue {
                what: "init_static_s (must be > 0 and <= 1e6 s)".into(),
                value: self.init_static_s.to_string(),
            });
        }
        if !(self.settle_s.is_finite() && (0.0..=1e3).contains(&self.settle_s)) {
            return Err(Error::InvalidValue {
                what: "settle_s (must be within 0..1000 s)".into(),
                value: self.settle_s.to_string(),
            });
        }
        self.init.validate()
    }

    /// The options of [`autocal`]: the method's settings
    /// ([`AutocalOptions::new`]) with the settling time for method `incal`.
    pub fn model(&self) -> AutocalOptions {
        let mut o = AutocalOptions::new(self.method, self.gravity_m_s2, self.init_static_s);
        if self.method == Method::Incal {
            o.settle_s = self.settle_s;
        }
        o.init = self.init;
        o
    }
}

impl serde::Serialize for AutocalSessionOptions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let o = self.model();
        let mut m = s.serialize_map(None)?;
        m.serialize_entry("method", &o.method)?;
        m.serialize_entry("gravity_m_s2", &o.gravity)?;
        m.serialize_entry("init_static_s", &o.init_static_s)?;
        m.serialize_entry("window_samples", &o.window)?;
        m.serialize_entry("min_samples", &o.min_samples)?;
        m.serialize_entry("settle_s", &o.settle_s)?;
        m.serialize_entry("rate_hz", &self.rate_hz)?;
        if self.sort_time {
            m.serialize_entry("sort_time", &true)?;
        }
        for (key, v) in [
            ("init_acc_bias", o.init.acc_bias),
            ("init_acc_scale", o.init.acc_scale),
            ("init_gyro_scale", o.init.gyro_scale),
        ] {
            if let Some(v) = v {
                m.serialize_entry(key, &v)?;
            }
        }
        m.end()
    }
}

/// The autocalibration as one [`crate::procedures::Procedure`]: a record
/// CSV ([`super::input::read_autocal`]) into the result document
/// ([`AutocalResult::document`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Autocal;

impl crate::procedures::Procedure for Autocal {
    const ID: crate::document::Procedure = crate::document::Procedure::ImuAutocal;
    type Options = AutocalSessionOptions;
    type Input = super::input::AutocalInput;

    fn validate(o: &AutocalSessionOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &AutocalSessionOptions,
    ) -> Result<Self::Input> {
        super::input::read_autocal(rows, o.rate_hz, o.sort_time)
    }

    fn reduce(
        input: &Self::Input,
        o: &AutocalSessionOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        // imu_tk's method takes its time steps from the stamps as they are
        // (repeats give zero steps); incal's from the time-stamp policy.
        let time = match (o.method, &input.stamps) {
            (Method::Tedaldi, Some(stamps)) => stamps,
            _ => &input.time,
        };
        let mut doc = autocal(time, &input.acc, input.gyr.as_deref(), &o.model())?.document()?;
        if input.sorted > 0 {
            doc.warnings.push(crate::timebase::sorted_warning(
                input.sorted,
                input.acc.len(),
            ));
        }
        if let Some(tb) = &input.timebase {
            doc.warnings.extend(tb.warnings());
        }
        Ok(doc)
    }
}

/// Names of the accelerometer parameters.
pub const ACC_PARAMS: [&str; 9] = [
    "m_yz", "m_zy", "m_zx", "s_x", "s_y", "s_z", "b_x", "b_y", "b_z",
];
/// Names of the gyro parameters fitted (the bias comes from the start).
pub const GYR_PARAMS: [&str; 9] = [
    "m_yz", "m_zy", "m_zx", "m_xz", "m_xy", "m_yx", "s_x", "s_y", "s_z",
];

/// One still interval used.
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalReport {
    /// Detected interval (sample indices).
    pub interval: Interval,
    /// Start and end time (s).
    pub start_s: f64,
    /// End time (s).
    pub end_s: f64,
    /// Samples entering the accelerometer fit.
    pub used: usize,
    /// Raw accelerometer mean over the used samples.
    pub mean: [f64; 3],
    /// Raw accelerometer standard deviation over the used samples.
    pub std: [f64; 3],
}

/// One threshold tried.
#[derive(Debug, Clone, PartialEq)]
pub struct ThresholdTrial {
    /// Multiplier k.
    pub k: f64,
    /// Usable intervals found.
    pub intervals: usize,
    /// Final cost ½Σr² of the accelerometer fit (None when skipped).
    pub cost: Option<f64>,
}

/// Result of [`autocal`].
#[derive(Debug, Clone)]
pub struct AutocalResult {
    /// Accelerometer parameters.
    pub acc: TriadParams,
    /// Gyro parameters (bias from the initial interval), when gyro data.
    pub gyr: Option<TriadParams>,
    /// `acc.*` and `gyr.*` with their joint covariance.
    pub estimates: Estimates,
    /// Accelerometer fit at the solution.
    pub acc_fit: Fit,
    /// Gyro fit at the solution.
    pub gyr_fit: Option<Fit>,
    /// Intervals used.
    pub intervals: Vec<IntervalReport>,
    /// Every threshold tried.
    pub trials: Vec<ThresholdTrial>,
    /// Threshold multiplier kept.
    pub k: f64,
    /// Threshold (variance norm) kept.
    pub threshold: f64,
    /// Initial still interval.
    pub init: Interval,
    /// Distinct orientations (gravity directions more than 10° apart).
    pub orientations: usize,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// Options used.
    pub options: AutocalOptions,
}

/// Minimise `½ Σ w r(x)²` by Gauss–Newton with step halving; `jac` is
/// `∂r/∂x`. Returns `x̂`.
fn minimize(
    names: &[String],
    res: &dyn Fn(&DVector<f64>) -> DVector<f64>,
    jac: &dyn Fn(&DVector<f64>) -> DMatrix<f64>,
    x0: DVector<f64>,
    weights: Option<&DVector<f64>>,
) -> Result<DVector<f64>> {
    let cost = |r: &DVector<f64>| match weights {
        Some(w) => r.iter().zip(w.iter()).map(|(a, b)| a * a * b).sum::<f64>(),
        None => r.norm_squared(),
    };
    let mut x = x0;
    let mut r = res(&x);
    let mut c = cost(&r);
    if !c.is_finite() {
        return Err(Error::Unsupported(
            "the starting point gives a non-finite residual".into(),
        ));
    }
    let opts = FitOptions {
        weights: weights.cloned(),
        ..FitOptions::default()
    };
    let mut polishing = 0;
    for _ in 0..200 {
        let design = Design::new(names.to_vec(), jac(&x))?;
        let step = fit(&design, &(-&r), &opts)?;
        let delta = step.estimates.values().clone();
        let within = |f: f64| (0..x.len()).all(|j| delta[j].abs() <= f * step.estimates.u_at(j));
        if within(1e-10) {
            return Ok(x + delta);
        }
        if within(1e-3) {
            // Near the minimum the cost changes below its rounding: take
            // the full Gauss–Newton step (it solves Jᵀr = 0, which is
            // resolved far better than the cost) and stop when the steps
            // no longer shrink.
            x += &delta;
            r = res(&x);
            c = cost(&r);
            polishing += 1;
            if polishing >= 8 {
                return Ok(x);
            }
            continue;
        }
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let xn = &x + &delta * alpha;
            let rn = res(&xn);
            let cn = cost(&rn);
            if cn.is_finite() && cn <= c {
                x = xn;
                r = rn;
                c = cn;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            // No descent left at machine precision: the minimum.
            return Ok(x);
        }
    }
    Err(Error::Unsupported(
        "autocalibration: Gauss-Newton did not converge in 200 iterations".into(),
    ))
}

fn acc_params(x: &DVector<f64>) -> TriadParams {
    TriadParams {
        mis: [x[0], x[1], x[2], 0.0, 0.0, 0.0],
        scale: [x[3], x[4], x[5]],
        bias: [x[6], x[7], x[8]],
    }
}

fn gyr_params(x: &DVector<f64>, bias: [f64; 3]) -> TriadParams {
    TriadParams {
        mis: [x[0], x[1], x[2], x[3], x[4], x[5]],
        scale: [x[6], x[7], x[8]],
        bias,
    }
}

/// Residuals `g − ‖T K (a − b)‖` of the samples `a`.
fn acc_residuals(x: &DVector<f64>, samples: &[[f64; 3]], g: f64) -> DVector<f64> {
    let p = acc_params(x);
    let tk = p.t() * p.k();
    let b = V3::from(p.bias);
    DVector::from_iterator(
        samples.len(),
        samples.iter().map(|a| g - (tk * (V3::from(*a) - b)).norm()),
    )
}

/// `∂r/∂x` of [`acc_residuals`] (analytic).
fn acc_jacobian(x: &DVector<f64>, samples: &[[f64; 3]]) -> DMatrix<f64> {
    let p = acc_params(x);
    let t = p.t();
    let s = p.scale;
    let b = V3::from(p.bias);
    let mut j = DMatrix::zeros(samples.len(), 9);
    for (i, a) in samples.iter().enumerate() {
        let v = V3::from(*a) - b;
        let c = t * V3::new(s[0] * v[0], s[1] * v[1], s[2] * v[2]);
        let n = c.norm();
        if n == 0.0 {
            continue;
        }
        let ch = c / n;
        let dc: [V3; 9] = [
            V3::new(-s[1] * v[1], 0.0, 0.0),
            V3::new(s[2] * v[2], 0.0, 0.0),
            V3::new(0.0, -s[2] * v[2], 0.0),
            t.column(0) * v[0],
            t.column(1) * v[1],
            t.column(2) * v[2],
            -t.column(0) * s[0],
            -t.column(1) * s[1],
            -t.column(2) * s[2],
        ];
        for k in 0..9 {
            j[(i, k)] = -ch.dot(&dc[k]);
        }
    }
    j
}

/// imu_tk's `Ω(ω)` of the quaternion derivative `q̇ = ½ Ω(ω) q`, q = (w, x, y, z).
fn omega_skew(w: &V3) -> Matrix4<f64> {
    Matrix4::new(
        0.0, -w[0], -w[1], -w[2], //
        w[0], 0.0, w[2], -w[1], //
        w[1], -w[2], 0.0, w[0], //
        w[2], w[1], -w[0], 0.0,
    )
}

/// One RK4 quaternion step from rate `w0` to `w1` over `dt` (imu_tk's
/// `quatIntegrationStepRK4`), normalised.
pub fn rk4_step(q: &Vector4<f64>, w0: &V3, w1: &V3, dt: f64) -> Vector4<f64> {
    let w01 = (w0 + w1) * 0.5;
    let k1 = omega_skew(w0) * q * 0.5;
    let k2 = omega_skew(&w01) * (q + k1 * (0.5 * dt)) * 0.5;
    let k3 = omega_skew(&w01) * (q + k2 * (0.5 * dt)) * 0.5;
    let k4 = omega_skew(w1) * (q + k3 * dt) * 0.5;
    let r = q + (k1 / 6.0 + k2 / 3.0 + k3 / 3.0 + k4 / 6.0) * dt;
    r / r.norm()
}

/// Rotation matrix of a unit quaternion (w, x, y, z) (ceres'
/// `QuaternionToRotation`).
pub fn quat_to_rotation(q: &Vector4<f64>) -> M3 {
    let (a, b, c, d) = (q[0], q[1], q[2], q[3]);
    let s = 1.0 / (a * a + b * b + c * c + d * d);
    M3::new(
        a * a + b * b - c * c - d * d,
        2.0 * (b * c - a * d),
        2.0 * (a * c + b * d),
        2.0 * (a * d + b * c),
        a * a - b * b + c * c - d * d,
        2.0 * (c * d - a * b),
        2.0 * (b * d - a * c),
        2.0 * (a * b + c * d),
        a * a - b * b - c * c + d * d,
    ) * s
}

/// One motion between still intervals: the raw gyro samples (bias not yet
/// removed), their time steps, and the gravity directions before and after.
struct Motion {
    gyr: Vec<V3>,
    dt: Vec<f64>,
    g0: V3,
    g1: V3,
    /// Two unit vectors normal to g1 (incal's projection).
    basis: [V3; 2],
    /// Index of the still interval it starts from.
    from: usize,
}

/// Integrate the calibrated rates of a motion: `R(q)` from the start.
fn integrate(m: &Motion, tk: &M3, bias: &V3) -> M3 {
    let mut q = Vector4::new(1.0, 0.0, 0.0, 0.0);
    let mut w_prev = tk * (m.gyr[0] - bias);
    for i in 0..m.dt.len() {
        let w_next = tk * (m.gyr[i + 1] - bias);
        q = rk4_step(&q, &w_prev, &w_next, m.dt[i]);
        w_prev = w_next;
    }
    quat_to_rotation(&q)
}

fn gyro_residuals(x: &DVector<f64>, bias: &V3, motions: &[Motion], project: bool) -> DVector<f64> {
    let p = gyr_params(x, [0.0; 3]);
    let tk = p.t() * p.k();
    let per = if project { 2 } else { 3 };
    let mut r = DVector::zeros(per * motions.len());
    for (k, m) in motions.iter().enumerate() {
        let rot = integrate(m, &tk, bias);
        let d = rot.transpose() * m.g0 - m.g1;
        if project {
            r[2 * k] = m.basis[0].dot(&d);
            r[2 * k + 1] = m.basis[1].dot(&d);
        } else {
            r[3 * k] = d[0];
            r[3 * k + 1] = d[1];
            r[3 * k + 2] = d[2];
        }
    }
    r
}

fn central_jacobian(
    f: &dyn Fn(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    scale: &[f64],
) -> DMatrix<f64> {
    let steps: Vec<f64> = (0..x.len())
        .map(|k| 1e-6 * x[k].abs().max(scale[k]))
        .collect();
    crate::estimation::numeric_jacobian(&f, x, &steps)
}

fn unit_basis(g: &V3) -> [V3; 2] {
    let k = (0..3)
        .min_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
        .unwrap_or(0);
    let mut e = V3::zeros();
    e[k] = 1.0;
    let u = (e - g * g.dot(&e)).normalize();
    [u, g.cross(&u)]
}

/// The smallest tilt off the sensor axes that separates an accelerometer
/// misalignment: `max_k |ĝ_i ĝ_j| ≥ 0.02` (about 1.1°) over the still
/// intervals for the pair of axes `i, j` of the term.
pub const MISALIGNMENT_SEPARATION: f64 = 0.02;

/// Name the accelerometer misalignments a session's gravity directions
/// cannot separate at first order (the error, for a refusal when the fit
/// then cannot converge, and for the warning when it can). The autocalibration sees the
/// accelerometer through the gravity norm only, and `|T v|` with `v` along
/// a sensor axis changes with the misalignments of `T` at second order: a
/// session whose still intervals all lie on the six faces (a precise cube
/// fixture) leaves them undetermined at first order (the fit then wanders
/// along a flat valley). `m_yz` needs gravity on x and y together, `m_zy`
/// on x and z, `m_zx` on y and z ([`MISALIGNMENT_SEPARATION`]); directions
/// from the starting calibration `x` ([`acc_start`]).
fn check_separation(
    acc: &[[f64; 3]],
    ivs: &[Interval],
    used: &dyn Fn(&Interval) -> Option<Interval>,
    x: &DVector<f64>,
) -> Result<()> {
    let p = acc_params(x);
    let mut most = [0.0f64; 3];
    for iv in ivs {
        let u = used(iv).unwrap_or(*iv);
        let d = p.apply(&V3::from(detect::mean(acc, u))).normalize();
        for (k, (i, j)) in [(0, 1), (0, 2), (1, 2)].into_iter().enumerate() {
            most[k] = most[k].max((d[i] * d[j]).abs());
        }
    }
    let names = ["acc.m_yz", "acc.m_zy", "acc.m_zx"];
    // `most` starts at 0 and f64::max skips NaN: a plain comparison.
    let weak: Vec<usize> = (0..3)
        .filter(|&k| most[k] < MISALIGNMENT_SEPARATION)
        .collect();
    let missing: Vec<&str> = weak.iter().map(|&k| names[k]).collect();
    if missing.is_empty() {
        return Ok(());
    }
    Err(Error::Unsupported(format!(
        "plan cannot separate {}: every still interval has gravity within {:.1} deg of a sensor axis for {} (largest |g_i g_j| {:.4}), where the gravity norm changes with misalignment only at second order; hold some orientations tilted 10 deg or more between the faces (on an edge or a corner)",
        missing.join(", "),
        ((2.0 * MISALIGNMENT_SEPARATION).asin() / 2.0).to_degrees(),
        if missing.len() == 1 { "its axes" } else { "their axes" },
        weak.iter().map(|&k| most[k]).fold(0.0, f64::max)
    )))
}

/// Count gravity directions more than 10° apart (greedy clustering).
fn distinct_orientations(dirs: &[V3]) -> usize {
    let mut reps: Vec<V3> = Vec::new();
    for d in dirs {
        if !reps.iter().any(|r| r.dot(d) > 10f64.to_radians().cos()) {
            reps.push(*d);
        }
    }
    reps.len()
}

/// Autocalibrate from a record: `time` (s, increasing), raw accelerometer
/// samples and, optionally, raw gyro samples of the same instants.
pub fn autocal(
    time: &[f64],
    acc: &[[f64; 3]],
    gyr: Option<&[[f64; 3]]>,
    opts: &AutocalOptions,
) -> Result<AutocalResult> {
    check_gravity(opts.gravity)?;
    let g = opts.gravity.abs();
    if !(opts.init_static_s.is_finite() && opts.init_static_s > 0.0) {
        return Err(Error::InvalidValue {
            what: "initial still duration (s, > 0)".into(),
            value: opts.init_static_s.to_string(),
        });
    }
    if time.len() != acc.len() || gyr.is_some_and(|v| v.len() != acc.len()) {
        return Err(Error::Unsupported(
            "time and triads differ in length".into(),
        ));
    }
    if acc.len() < opts.window.max(11) + 1 {
        return Err(Error::TooFew {
            what: format!("samples for a {}-sample variance window", opts.window),
            needed: opts.window.max(11) + 1,
            got: acc.len(),
        });
    }
    let init = detect::initial_interval(time, opts.init_static_s);
    if init.len() < 3 {
        return Err(Error::TooFew {
            what: "samples in the initial still interval (--init-static-s)".into(),
            needed: 3,
            got: init.len(),
        });
    }
    let mut checked = Vec::new();
    let mut channels = super::screen::ChannelCheck::<6>::default();
    for (i, a) in acc.iter().enumerate() {
        let w = gyr.map_or([0.0; 3], |g| g[i]);
        channels.push(&[a[0], a[1], a[2], w[0], w[1], w[2]]);
    }
    channels.finish(
        &super::screen::session_channels(gyr.is_some()),
        &mut checked,
    )?;
    // incal: accelerometer spikes mended by a Hampel filter scaled by the
    // still start's robust scatter before the detector and the means;
    // tedaldi: imu_tk's steps, as read.
    let screened;
    let (acc, spike_flags) = if opts.method == Method::Incal {
        let scale = super::screen::triad_scale(&acc[init.start..=init.end], 0);
        let (a, f) = super::screen::hampel(acc, scale);
        screened = a;
        (&screened[..], f)
    } else {
        (acc, Vec::new())
    };
    let norm_th = detect::norm3(detect::variance(acc, init));
    if norm_th.is_nan() || norm_th <= 0.0 {
        return Err(Error::Unsupported(
            "the initial still interval has zero accelerometer variance: the threshold k*||var|| is 0 and nothing is still (a noise-free or saturated record?)".into(),
        ));
    }
    // incal: the time-stamp policy's gaps (a still interval never spans
    // one; a motion across one is left out of the gyro fit). tedaldi:
    // imu_tk's steps, no gap handling.
    let gaps: Vec<usize> = if opts.method == Method::Incal {
        crate::timebase::gap_indices(time)
    } else {
        Vec::new()
    };
    let spans_gap = |end: usize, start: usize| gaps.iter().any(|&g| g > end && g <= start);
    let mut norms = detect::variance_norms(acc, opts.window);
    for &g in &gaps {
        // Both samples beside a gap read as moving: intervals end there.
        norms[g - 1] = Some(f64::INFINITY);
        norms[g] = Some(f64::INFINITY);
    }
    let dt_mean = (time[time.len() - 1] - time[0]) / (time.len() - 1) as f64;
    let trim = if opts.method == Method::Incal {
        (opts.settle_s / dt_mean).round() as usize
    } else {
        0
    };
    // The samples an interval contributes (tedaldi: its first
    // `min_samples`; incal: all, trimmed by the settle time).
    let used = |iv: &Interval| -> Option<Interval> {
        if iv.len() < opts.min_samples {
            return None;
        }
        match opts.method {
            Method::Tedaldi => Some(Interval {
                start: iv.start,
                end: iv.start + opts.min_samples - 1,
            }),
            Method::Incal => (iv.len() >= opts.min_samples + 2 * trim).then_some(Interval {
                start: iv.start + trim,
                end: iv.end - trim,
            }),
        }
    };
    let g_est = {
        // Starting scale: g over the typical magnitude of interval means.
        let iv = detect::intervals_from_norms(&norms, 2.0 * norm_th);
        let mut mags: Vec<f64> = iv
            .iter()
            .filter(|i| i.len() >= 3)
            .map(|i| detect::norm3(detect::mean(acc, *i)))
            .collect();
        mags.sort_by(f64::total_cmp);
        if mags.is_empty() {
            detect::norm3(detect::mean(acc, init))
        } else {
            mags[mags.len() / 2]
        }
    };
    let s0 = if g_est > 0.0 { g / g_est } else { 1.0 };
    let x0 = DVector::from_vec(vec![0.0, 0.0, 0.0, s0, s0, s0, 0.0, 0.0, 0.0]);
    let acc_names: Vec<String> = ACC_PARAMS.iter().map(|n| format!("acc.{n}")).collect();

    struct Candidate {
        k: f64,
        separation: Option<Error>,
        intervals: Vec<Interval>,
        x: DVector<f64>,
        cost: f64,
    }
    let mut trials = Vec::new();
    let mut best: Option<Candidate> = None;
    let mut most_found = 0;
    for k in 2..=10 {
        let k = k as f64;
        let ivs: Vec<Interval> = detect::intervals_from_norms(&norms, k * norm_th)
            .into_iter()
            .filter(|iv| used(iv).is_some())
            .collect();
        most_found = most_found.max(ivs.len());
        let needed = match opts.method {
            Method::Tedaldi => opts.min_intervals,
            Method::Incal => 9,
        };
        if ivs.len() < needed {
            trials.push(ThresholdTrial {
                k,
                intervals: ivs.len(),
                cost: None,
            });
            continue;
        }
        if opts.method == Method::Incal {
            // Most intervals wins, the smallest k on a tie: fit only when
            // this k beats the best so far.
            if best
                .as_ref()
                .is_some_and(|b| b.intervals.len() >= ivs.len())
            {
                trials.push(ThresholdTrial {
                    k,
                    intervals: ivs.len(),
                    cost: None,
                });
                continue;
            }
        }
        let (samples, weights) = acc_observations(acc, &ivs, &used, opts, None)?;
        let start = acc_start(acc, &ivs, &used, g, &x0, &opts.init);
        // A session that cannot separate a misalignment at first order
        // is named: refused when the fit cannot converge, else warned.
        let separation = check_separation(acc, &ivs, &used, &start).err();
        let x = minimize(
            &acc_names,
            &|x| acc_residuals(x, &samples, g),
            &|x| acc_jacobian(x, &samples),
            start,
            weights.as_ref(),
        )
        .map_err(|e| separation.clone().unwrap_or(e))?;
        let r = acc_residuals(&x, &samples, g);
        let cost = 0.5 * r.norm_squared();
        trials.push(ThresholdTrial {
            k,
            intervals: ivs.len(),
            cost: Some(cost),
        });
        let better = match (&best, opts.method) {
            (None, _) => true,
            (Some(b), Method::Tedaldi) => cost < b.cost,
            (Some(b), Method::Incal) => ivs.len() > b.intervals.len(),
        };
        if better {
            best = Some(Candidate {
                k,
                separation,
                intervals: ivs,
                x,
                cost,
            });
        }
    }
    let needed = match opts.method {
        Method::Tedaldi => opts.min_intervals,
        Method::Incal => 9,
    };
    let Some(best) = best else {
        return Err(Error::TooFew {
            what: format!(
                "still intervals of at least {} samples (thresholds k = 2..10 times the initial variance norm {:.3e}; the most found was {most_found}): record more orientations, hold each longer, or check --init-static-s covers a still start",
                opts.min_samples + 2 * trim,
                norm_th
            ),
            needed,
            got: most_found,
        });
    };

    // Final accelerometer fit with its covariance.
    let (x_acc, acc_fit, samples_info) = {
        let (samples, mut weights) = acc_observations(acc, &best.intervals, &used, opts, None)?;
        let mut x = best.x.clone();
        if opts.method == Method::Incal {
            // Weights from each interval's residual scatter at the solution.
            let (s2, w) = acc_observations(acc, &best.intervals, &used, opts, Some(&x))?;
            weights = w;
            x = minimize(
                &acc_names,
                &|x| acc_residuals(x, &s2, g),
                &|x| acc_jacobian(x, &s2),
                x,
                weights.as_ref(),
            )
            .map_err(|e| best.separation.clone().unwrap_or(e))?;
        }
        let variance = match opts.method {
            Method::Tedaldi => Variance::FromResiduals,
            Method::Incal => Variance::AtLeast {
                dof: best
                    .intervals
                    .iter()
                    .filter_map(&used)
                    .map(|u| (u.len() - 1) as f64)
                    .sum(),
            },
        };
        let r = acc_residuals(&x, &samples, g);
        let j = acc_jacobian(&x, &samples);
        let design = Design::new(acc_names.clone(), j)?;
        let f = fit(
            &design,
            &(-&r),
            &FitOptions {
                weights,
                variance,
                ..FitOptions::default()
            },
        )?;
        (x, f, samples.len())
    };
    let _ = samples_info;
    let acc_p = acc_params(&x_acc);
    let acc_cov = acc_fit.estimates.covariance().clone();

    let mut reports = Vec::new();
    let mut dirs = Vec::new();
    for iv in &best.intervals {
        let u = used(iv).unwrap_or(*iv);
        let m = detect::mean(acc, u);
        let v = detect::variance(acc, u);
        dirs.push(acc_p.apply(&V3::from(m)).normalize());
        reports.push(IntervalReport {
            interval: *iv,
            start_s: time[iv.start],
            end_s: time[iv.end],
            used: u.len(),
            mean: m,
            std: v.map(|a| a.max(0.0).sqrt()),
        });
    }
    let orientations = distinct_orientations(&dirs);
    let mut warnings = checked;
    if let Some(e) = &best.separation {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!(
                "{}; the values and u of these terms rest on second-order effects and the gyro misalignments are relative to them",
                e.to_string().replacen("plan cannot separate", "this session hardly separates", 1)
            ),
        ));
    }
    warnings.extend(acc_fit.quality_warnings(
        "the sensor is not still in some intervals, or the model (scale, three misalignments, bias) does not hold",
    ));
    let mut spikes: Vec<(String, usize)> = Vec::new();
    let mut gyro_spikes = 0;
    let mut gyro_in_motion = 0;
    if !spike_flags.is_empty() {
        for iv in &best.intervals {
            let u = used(iv).unwrap_or(*iv);
            let n = spike_flags[u.start..=u.end].iter().filter(|f| **f).count();
            spikes.push((format!("acc {:.2}-{:.2} s", time[u.start], time[u.end]), n));
        }
    }

    // Gyro.
    let mut names = acc_names.clone();
    let mut values: Vec<f64> = x_acc.iter().copied().collect();
    let (gyr_p, gyr_fit, cov) = match gyr {
        None => (None, None, acc_cov.clone()),
        Some(gy) => {
            // incal: gyro samples that stand out in motion are reported,
            // not changed (a knock and a bad sample look alike).
            if opts.method == Method::Incal {
                let scale = super::screen::triad_scale(&gy[init.start..=init.end], 0);
                let flags = super::screen::hampel_flags(gy, scale);
                gyro_in_motion = best
                    .intervals
                    .windows(2)
                    .map(|w| flags[w[0].end..w[1].start].iter().filter(|f| **f).count())
                    .sum();
            }
            // The gyro bias: the still start's mean (incal: its spikes
            // left out).
            let start = &gy[init.start..=init.end];
            let (kept, dropped) = match opts.method {
                Method::Incal => super::screen::without_spikes(start),
                Method::Tedaldi => (start.to_vec(), 0),
            };
            gyro_spikes = dropped;
            let all = Interval {
                start: 0,
                end: kept.len() - 1,
            };
            let gi = detect::mean(&kept, all);
            let gv = detect::variance(&kept, all);
            let bias = V3::from(gi);
            let n_init = kept.len() as f64;
            // Gravity directions: calibrated means of whole intervals
            // (tedaldi) or of the used samples (incal).
            let gdir = |xa: &DVector<f64>, iv: &Interval| -> V3 {
                let p = acc_params(xa);
                let span = match opts.method {
                    Method::Tedaldi => *iv,
                    Method::Incal => used(iv).unwrap_or(*iv),
                };
                let m = detect::mean(acc, span);
                p.apply(&V3::from(m)).normalize()
            };
            let build = |xa: &DVector<f64>| -> Vec<Motion> {
                best.intervals
                    .windows(2)
                    .enumerate()
                    .filter(|(_, w)| !spans_gap(w[0].end, w[1].start))
                    .map(|(from, w)| {
                        let (i0, i1) = (w[0].end, w[1].start - 1);
                        let g0 = gdir(xa, &w[0]);
                        let g1 = gdir(xa, &w[1]);
                        Motion {
                            gyr: (i0..=i1).map(|i| V3::from(gy[i])).collect(),
                            dt: (i0..i1).map(|i| time[i + 1] - time[i]).collect(),
                            g0,
                            g1,
                            basis: unit_basis(&g1),
                            from,
                        }
                    })
                    .collect()
            };
            let motions = build(&x_acc);
            let project = opts.method == Method::Incal;
            // Starting scale: the gravity turn over the raw integral.
            let mut ratios: Vec<f64> = motions
                .iter()
                .filter_map(|m| {
                    let mut s = V3::zeros();
                    for i in 0..m.dt.len() {
                        s += (m.gyr[i] + m.gyr[i + 1] - 2.0 * bias) * 0.5 * m.dt[i];
                    }
                    let angle = m.g0.dot(&m.g1).clamp(-1.0, 1.0).acos();
                    (s.norm() > 0.0 && angle > 0.05).then(|| angle / s.norm())
                })
                .collect();
            ratios.sort_by(f64::total_cmp);
            let sg = ratios.get(ratios.len() / 2).copied().unwrap_or(1.0);
            let s0 = opts.init.gyro_scale.unwrap_or([sg; 3]);
            let xg0 = DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, s0[0], s0[1], s0[2]]);
            let gnames: Vec<String> = GYR_PARAMS.iter().map(|n| format!("gyr.{n}")).collect();
            let scale: Vec<f64> = (0..9).map(|k| if k < 6 { 1.0 } else { sg.abs() }).collect();
            let res = |x: &DVector<f64>| gyro_residuals(x, &bias, &motions, project);
            let jac = |x: &DVector<f64>| central_jacobian(&res, x, &scale);
            let mut xg = minimize(&gnames, &res, &jac, xg0, None)?;
            let n_a = 9;
            let mut c = DMatrix::zeros(21, 21);
            c.view_mut((0, 0), (n_a, n_a)).copy_from(&acc_cov);
            let mut cb = DMatrix::zeros(3, 3);
            if init.len() > 1 {
                for k in 0..3 {
                    cb[(k, k)] = gv[k] / n_init;
                }
            }
            c.view_mut((18, 18), (3, 3)).copy_from(&cb);
            let (gf, cg) = if project {
                // incal: generalised least squares. The residual covariance
                // V = D + B_a C_a B_aᵀ + B_b C_b B_bᵀ holds the random part D
                // (gyro white noise integrated over each motion, noise of
                // the two gravity directions) and the systematic parts
                // shared by every motion (accelerometer parameters through
                // the gravity directions, the gyro bias from the start).
                let acc_tk = acc_p.t() * acc_p.k();
                let spans: Vec<(V3, f64)> = best
                    .intervals
                    .iter()
                    .map(|iv| {
                        let u = used(iv).unwrap_or(*iv);
                        (V3::from(detect::variance(acc, u)), u.len() as f64)
                    })
                    .collect();
                let gdir_cov = |k: usize| -> M3 {
                    let (v, n) = spans[k];
                    acc_tk * M3::from_diagonal(&(v / n)) * acc_tk.transpose() / (g * g)
                };
                let p = gyr_params(&xg, [0.0; 3]);
                let tk = p.t() * p.k();
                let cw = tk * M3::from_diagonal(&V3::from(gv)) * tk.transpose();
                let nr = 2 * motions.len();
                let mut v = DMatrix::zeros(nr, nr);
                for (k, m) in motions.iter().enumerate() {
                    let dt2: f64 = m.dt.iter().map(|d| d * d).sum();
                    let c_phi = cw * dt2;
                    let rot = integrate(m, &tk, &bias);
                    let c0 = rot.transpose() * gdir_cov(m.from) * rot;
                    let c1 = gdir_cov(m.from + 1);
                    for a in 0..2 {
                        let e = m.basis[a];
                        let vv = e.cross(&m.g1);
                        let var =
                            (vv.transpose() * c_phi * vv)[0] + (e.transpose() * (c0 + c1) * e)[0];
                        if !(var > 0.0 && var.is_finite()) {
                            return Err(Error::Unsupported(
                                "the initial still interval has no gyro scatter: the weights of the gyro fit are undefined (a noise-free or clipped record?)".into(),
                            ));
                        }
                        v[(2 * k + a, 2 * k + a)] = var;
                    }
                }
                // ∂r/∂θ_a (gravity directions rebuilt, projection basis
                // kept) and ∂r/∂b.
                let ra = |xa: &DVector<f64>| {
                    let m = build(xa);
                    let mut out = DVector::zeros(nr);
                    for (k, (mm, m0)) in m.iter().zip(&motions).enumerate() {
                        let d = quat_free_diff(&xg, &bias, mm);
                        out[2 * k] = m0.basis[0].dot(&d);
                        out[2 * k + 1] = m0.basis[1].dot(&d);
                    }
                    out
                };
                let ascale: Vec<f64> = (0..9)
                    .map(|k| acc_fit.estimates.u_at(k).max(1e-12))
                    .collect();
                let ja = central_jacobian(&ra, &x_acc, &ascale);
                let rb = |b: &DVector<f64>| {
                    gyro_residuals(&xg, &V3::new(b[0], b[1], b[2]), &motions, true)
                };
                let bvec = DVector::from_vec(gi.to_vec());
                let bscale: Vec<f64> = (0..3).map(|k| cb[(k, k)].sqrt().max(1e-12)).collect();
                let jb = central_jacobian(&rb, &bvec, &bscale);
                v += propagate(&acc_cov, &ja) + propagate(&cb, &jb);
                let Some(chol) = v.clone().cholesky() else {
                    return Err(Error::Unsupported(
                        "gyro fit: the residual covariance is not positive definite".into(),
                    ));
                };
                let l_inv = chol
                    .l()
                    .solve_lower_triangular(&DMatrix::identity(nr, nr))
                    .ok_or_else(|| Error::Unsupported("gyro fit: singular whitening".into()))?;
                let res_w = |x: &DVector<f64>| &l_inv * res(x);
                let jac_w = |x: &DVector<f64>| &l_inv * jac(x);
                xg = minimize(&gnames, &res_w, &jac_w, xg, None)?;
                let jw = jac_w(&xg);
                let gf = fit(
                    &Design::new(gnames.clone(), jw.clone())?,
                    &(-res_w(&xg)),
                    &FitOptions {
                        variance: Variance::AtLeast {
                            dof: (init.len() - 1) as f64,
                        },
                        ..FitOptions::default()
                    },
                )?;
                // Cross-covariances: θ̂_g − θ_g = −(J'ᵀJ')⁻¹ J'ᵀ L⁻¹ (… + B δθ).
                let Some(inv) = (jw.transpose() * &jw).try_inverse() else {
                    return Err(Error::Unsupported(
                        "gyro fit: singular normal matrix".into(),
                    ));
                };
                let pinv = inv * jw.transpose() * &l_inv;
                let cga = -(&pinv * &ja) * &acc_cov;
                let cgb = -(&pinv * &jb) * &cb;
                c.view_mut((n_a, 0), (9, 9)).copy_from(&cga);
                c.view_mut((0, n_a), (9, 9)).copy_from(&cga.transpose());
                c.view_mut((n_a, 18), (9, 3)).copy_from(&cgb);
                c.view_mut((18, n_a), (3, 9)).copy_from(&cgb.transpose());
                let cg = gf.estimates.covariance().clone();
                (gf, cg)
            } else {
                let gf = fit(
                    &Design::new(gnames.clone(), jac(&xg))?,
                    &(-res(&xg)),
                    &FitOptions::default(),
                )?;
                let cg = gf.estimates.covariance().clone();
                (gf, cg)
            };
            warnings.extend(gf.quality_warnings(
                "the sensor moves in the still intervals, rotates too fast for the sample rate, or the gyro model (scale, six misalignments, bias from the start) does not hold",
            ));
            let gp = gyr_params(&xg, [gi[0], gi[1], gi[2]]);
            names.extend(gnames.iter().cloned());
            names.extend(["gyr.b_x", "gyr.b_y", "gyr.b_z"].map(String::from));
            values.extend(xg.iter().copied());
            values.extend(gi);
            c.view_mut((n_a, n_a), (9, 9)).copy_from(&cg);
            (Some(gp), Some(gf), c)
        }
    };
    warnings.extend(super::screen::spikes_warning(
        &spikes,
        super::screen::REPLACED,
    ));
    warnings.extend(super::screen::spikes_warning(
        &[("gyro still start".into(), gyro_spikes)],
        super::screen::LEFT_OUT,
    ));
    warnings.extend(super::screen::spikes_warning(
        &[("gyro between still intervals".into(), gyro_in_motion)],
        super::screen::NOT_CHANGED,
    ));
    let across = best
        .intervals
        .windows(2)
        .filter(|w| spans_gap(w[0].end, w[1].start))
        .count();
    if gyr.is_some() && across > 0 {
        warnings.push(Warning::new(
            WarningCode::TimeGaps,
            format!(
                "{across} of {} motions between still intervals span a time gap and are left out of the gyro fit (a rotation cannot be integrated across missing samples)",
                best.intervals.len() - 1
            ),
        ));
    }
    let dof = match &gyr_fit {
        Some(gf) => acc_fit.estimates.dof().min(gf.estimates.dof()),
        None => acc_fit.estimates.dof(),
    };
    if cov.iter().any(|v| !v.is_finite()) || values.iter().any(|v| !v.is_finite()) {
        return Err(Error::Unsupported(
            "autocalibration gave a non-finite result".into(),
        ));
    }
    let estimates = Estimates::new(names, DVector::from_vec(values), cov, dof)?;
    if orientations < 9 {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!(
                "only {orientations} distinct orientations (gravity directions more than 10 deg apart) among {} intervals: the scale and misalignment terms rest on few directions",
                best.intervals.len()
            ),
        ));
    }
    Ok(AutocalResult {
        acc: acc_p,
        gyr: gyr_p,
        estimates,
        acc_fit,
        gyr_fit,
        intervals: reports,
        trials,
        k: best.k,
        threshold: best.k * norm_th,
        init,
        orientations,
        warnings,
        options: *opts,
    })
}

/// The accelerometer fit's starting point: the user's initial values
/// where given ([`Initial`]), the rest from an ellipsoid through the
/// intervals' means ([`ellipsoid_start`]), or `fallback` (bias 0, scale g
/// over the median mean magnitude) when the means do not define one.
fn acc_start(
    acc: &[[f64; 3]],
    ivs: &[Interval],
    used: &dyn Fn(&Interval) -> Option<Interval>,
    g: f64,
    fallback: &DVector<f64>,
    init: &Initial,
) -> DVector<f64> {
    let means: Vec<[f64; 3]> = ivs
        .iter()
        .filter_map(used)
        .map(|u| detect::mean(acc, u))
        .collect();
    let mut x = fallback.clone();
    if let Some((scale, bias)) = ellipsoid_start(&means, g) {
        for k in 0..3 {
            x[3 + k] = scale[k];
            x[6 + k] = bias[k];
        }
    }
    if let Some(s) = init.acc_scale {
        for k in 0..3 {
            x[3 + k] = s[k];
        }
    }
    if let Some(b) = init.acc_bias {
        for k in 0..3 {
            x[6 + k] = b[k];
        }
    }
    x
}

/// Scale and bias of the axis-aligned ellipsoid `Σ_j (s_j (m_j − b_j))² = g²`
/// through the still-interval means `m` (raw units), or `None` when fewer
/// than 7 means or they do not define an ellipsoid (too few directions).
///
/// Why: on raw counts (offsets of ~32768, scales of ~1e-4) a start at
/// bias 0 lies in the basin where the bias runs off to infinity with the
/// scale to zero; the ellipsoid lands next to the minimum in any unit.
/// Fitted linearly: `[u², v², w², u, v, w, 1]·p = 0` on the means centred
/// and scaled to unit spread, `p` the right singular vector of the
/// smallest singular value.
pub fn ellipsoid_start(means: &[[f64; 3]], g: f64) -> Option<([f64; 3], [f64; 3])> {
    let n = means.len();
    if n < 7 {
        return None;
    }
    let mut c = [0.0; 3];
    for m in means {
        for k in 0..3 {
            c[k] += m[k] / n as f64;
        }
    }
    let spread = (means
        .iter()
        .map(|m| (0..3).map(|k| (m[k] - c[k]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / n as f64)
        .sqrt();
    if !(spread.is_finite() && spread > 0.0) {
        return None;
    }
    let mut a = DMatrix::zeros(n, 7);
    for (i, m) in means.iter().enumerate() {
        for k in 0..3 {
            let u = (m[k] - c[k]) / spread;
            a[(i, k)] = u * u;
            a[(i, 3 + k)] = u;
        }
        a[(i, 6)] = 1.0;
    }
    let svd = crate::estimation::bounded_svd(a, false, true)?;
    let vt = svd.v_t?;
    let (j, _) = svd.singular_values.argmin();
    let mut p: Vec<f64> = vt.row(j).iter().copied().collect();
    if p[0] < 0.0 {
        p.iter_mut().for_each(|v| *v = -*v);
    }
    if !(p[0] > 0.0 && p[1] > 0.0 && p[2] > 0.0) {
        return None;
    }
    let u0: Vec<f64> = (0..3).map(|k| -p[3 + k] / (2.0 * p[k])).collect();
    let r = (0..3).map(|k| p[k] * u0[k] * u0[k]).sum::<f64>() - p[6];
    if r.is_nan() || r <= 0.0 {
        return None;
    }
    let mut scale = [0.0; 3];
    let mut bias = [0.0; 3];
    for k in 0..3 {
        scale[k] = g * (p[k] / r).sqrt() / spread;
        bias[k] = c[k] + spread * u0[k];
    }
    (scale.iter().chain(&bias).all(|v| v.is_finite())).then_some((scale, bias))
}

/// `R(q)ᵀ ĝ₀ − ĝ₁` of one motion (unprojected).
fn quat_free_diff(x: &DVector<f64>, bias: &V3, m: &Motion) -> V3 {
    let p = gyr_params(x, [0.0; 3]);
    let rot = integrate(m, &(p.t() * p.k()), bias);
    rot.transpose() * m.g0 - m.g1
}

/// Accelerometer observations and their weights.
type AccObservations = (Vec<[f64; 3]>, Option<DVector<f64>>);

/// The accelerometer observations: tedaldi, the used samples (no
/// weights); incal, the interval means with weights `n/σ²` where σ is the
/// scatter of the interval's residuals at `at` (equal weights before).
fn acc_observations(
    acc: &[[f64; 3]],
    ivs: &[Interval],
    used: &dyn Fn(&Interval) -> Option<Interval>,
    opts: &AutocalOptions,
    at: Option<&DVector<f64>>,
) -> Result<AccObservations> {
    match opts.method {
        Method::Tedaldi => {
            let mut s = Vec::new();
            for iv in ivs {
                if let Some(u) = used(iv) {
                    s.extend_from_slice(&acc[u.start..=u.end]);
                }
            }
            Ok((s, None))
        }
        Method::Incal => {
            let mut means = Vec::new();
            let mut w = Vec::new();
            for iv in ivs {
                let Some(u) = used(iv) else { continue };
                means.push(detect::mean(acc, u));
                let n = u.len() as f64;
                match at {
                    None => w.push(n),
                    Some(x) => {
                        let r = acc_residuals(x, &acc[u.start..=u.end], opts.gravity.abs());
                        let m = r.mean();
                        let var = r.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
                        if var.is_nan() || var <= 0.0 {
                            return Err(Error::Unsupported(format!(
                                "still interval at samples {}..{} has no scatter: its weight is undefined (a noise-free or clipped record?)",
                                u.start, u.end
                            )));
                        }
                        w.push(n / var);
                    }
                }
            }
            Ok((means, Some(DVector::from_vec(w))))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gravity on the six faces only leaves the three accelerometer
    /// misalignments unseparated (named); one edge between x and y
    /// separates `acc.m_yz` and only it.
    #[test]
    fn faces_alone_cannot_separate_the_accelerometer_misalignments() {
        let mut acc = Vec::new();
        let mut ivs = Vec::new();
        fn block(d: [f64; 3], acc: &mut Vec<[f64; 3]>, ivs: &mut Vec<Interval>) {
            let start = acc.len();
            acc.extend(std::iter::repeat_n(d, 50));
            ivs.push(Interval {
                start,
                end: acc.len() - 1,
            });
        }
        for d in [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.005, -1.0],
        ] {
            block(d, &mut acc, &mut ivs);
        }
        let x = DVector::from_vec(vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        let used = |iv: &Interval| Some(*iv);
        let e = check_separation(&acc, &ivs, &used, &x)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("plan cannot separate acc.m_yz, acc.m_zy, acc.m_zx: every still interval has gravity within 1.1 deg"),
            "{e}"
        );
        let h = std::f64::consts::FRAC_1_SQRT_2;
        block([h, h, 0.0], &mut acc, &mut ivs);
        let e = check_separation(&acc, &ivs, &used, &x)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("plan cannot separate acc.m_zy, acc.m_zx:"),
            "{e}"
        );
        block([h, 0.0, h], &mut acc, &mut ivs);
        block([0.0, 0.1, 1.0], &mut acc, &mut ivs);
        check_separation(&acc, &ivs, &used, &x).unwrap();
    }

    #[test]
    fn rk4_integrates_a_constant_rate() {
        let w = V3::new(0.0, 0.0, 1.0);
        let mut q = Vector4::new(1.0, 0.0, 0.0, 0.0);
        for _ in 0..100 {
            q = rk4_step(&q, &w, &w, 0.01);
        }
        let r = quat_to_rotation(&q);
        // One radian about z: body x turns towards y.
        assert!(
            (r[(0, 0)] - 1f64.cos()).abs() < 1e-9,
            "{}",
            r[(0, 0)] - 1f64.cos()
        );
        assert!((r[(1, 0)] - 1f64.sin()).abs() < 1e-9);
    }
}
