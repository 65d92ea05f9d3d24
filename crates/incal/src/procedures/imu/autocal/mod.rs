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
//!
//! # Layout
//! [`autocal`] runs the steps in order, one file each: `session` (checks,
//! screening, the detector's variance norms), `threshold` (static
//! detection and the threshold kept), `accel` (the accelerometer fit),
//! `gyro` and `gyro_gls` (the gyro fit; `kinematics` holds the quaternion
//! integration), `assemble` (estimates, reports and warnings). Every fit
//! minimises with the crate's one Gauss–Newton,
//! [`crate::estimation::minimize`].

mod accel;
mod assemble;
mod gyro;
mod gyro_gls;
mod kinematics;
mod session;
mod threshold;

pub use accel::{ellipsoid_start, MISALIGNMENT_SEPARATION};
pub use kinematics::{quat_to_rotation, rk4_step};

use nalgebra::DVector;

use super::detect::Interval;
use super::sim::TriadParams;
use crate::error::{Error, Result};
use crate::estimation::{
    Estimates, Fit, FitOptions, GaussNewtonOptions, NonlinearModel, StepControl, Stop,
};
use crate::warning::Warning;

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

/// Minimise `Σ w r(x)²` for the `n` residuals `r` of `model` (a model of
/// zero observations) from `x0`, with the crate's Gauss–Newton
/// ([`crate::estimation::minimize`]) damped by step halving: steps within
/// 1e-10 standard uncertainties converge, steps within 1e-3 are taken in
/// full for at most 8 iterations, at most 40 halvings and 200
/// iterations. Returns `x̂`.
fn minimize(
    model: &impl NonlinearModel,
    n: usize,
    x0: DVector<f64>,
    weights: Option<&DVector<f64>>,
) -> Result<DVector<f64>> {
    let opts = GaussNewtonOptions {
        fit: FitOptions {
            weights: weights.cloned(),
            ..FitOptions::default()
        },
        max_iter: 200,
        tol: 1e-10,
        rel_tol: None,
        step: StepControl::Halving {
            halvings: 40,
            polish: 1e-3,
            polish_steps: 8,
        },
    };
    let m = crate::estimation::minimize(model, &DVector::zeros(n), x0, &opts)?;
    if m.stop == Stop::MaxIterations {
        return Err(Error::Unsupported(
            "autocalibration: Gauss-Newton did not converge in 200 iterations".into(),
        ));
    }
    Ok(m.x)
}

/// Autocalibrate from a record: `time` (s, increasing), raw accelerometer
/// samples and, optionally, raw gyro samples of the same instants.
pub fn autocal(
    time: &[f64],
    acc: &[[f64; 3]],
    gyr: Option<&[[f64; 3]]>,
    opts: &AutocalOptions,
) -> Result<AutocalResult> {
    let s = session::Session::prepare(time, acc, gyr, opts)?;
    let (best, trials) = threshold::search(&s)?;
    let (x_acc, acc_fit) = accel::final_fit(&s, &best)?;
    let gyro = match gyr {
        Some(gy) => Some(gyro::gyro_fit(&s, gy, &best.intervals, &x_acc, &acc_fit)?),
        None => None,
    };
    assemble::assemble(s, best, trials, x_acc, acc_fit, gyro)
}
