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
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// incal's weighted form with full covariance (default).
    #[default]
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
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
pub struct Initial {
    /// Accelerometer bias (raw units), e.g. 32768 for 16-bit offset counts.
    #[serde(
        rename = "init_acc_bias",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub acc_bias: Option<[f64; 3]>,
    /// Accelerometer scale (m/s² per raw unit).
    #[serde(
        rename = "init_acc_scale",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub acc_scale: Option<[f64; 3]>,
    /// Gyro scale (rad/s per raw unit), e.g. 1/6258 for an Xsens in counts.
    #[serde(
        rename = "init_gyro_scale",
        default,
        skip_serializing_if = "Option::is_none"
    )]
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
                    return crate::options::invalid(
                        key,
                        format!("{need}, got {}", crate::error::short_number(&x.to_string())),
                    );
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
/// method `tedaldi`), `sort_time` when true and the initial values
/// (`init_acc_bias`, `init_acc_scale`, `init_gyro_scale`) when given.
/// Defaults (JSON callers, as the CLI): method `incal`, g 9.80665 m/s², a
/// still start of 50 s, `settle_s` 0.1 s, imu_tk's window of 101 samples
/// and intervals of at least 100 samples.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct AutocalSessionOptions {
    /// Sample rate (Hz); the record's `time_s`, when present, gives the
    /// time steps instead (and the rate when this is `None`; given, it
    /// must agree with them). Needed without `time_s`.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Method.
    #[serde(default)]
    pub method: Method,
    /// Gravity magnitude (m/s², > 0): the calibrated accelerometer output
    /// is in this unit.
    #[serde(default = "standard_gravity")]
    pub gravity_m_s2: f64,
    /// Duration of the still start (s).
    #[serde(default = "default_init_static_s")]
    pub init_static_s: f64,
    /// Time trimmed from both ends of every still interval (s; method
    /// `incal` only).
    #[serde(default = "default_settle_s")]
    pub settle_s: f64,
    /// Moving-variance window of the static detector (samples, odd,
    /// ≥ 11; imu_tk: 101).
    #[serde(default = "default_window_samples")]
    pub window_samples: usize,
    /// Samples a still interval needs (imu_tk: 100).
    #[serde(default = "default_min_samples")]
    pub min_samples: usize,
    /// Initial values of the fits (absent: from the data).
    #[serde(flatten)]
    pub init: Initial,
    /// Put rows that are out of time order in order instead of refusing
    /// them (warning `time-sorted`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sort_time: bool,
}

fn standard_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}

fn default_init_static_s() -> f64 {
    50.0
}

fn default_settle_s() -> f64 {
    0.1
}

fn default_window_samples() -> usize {
    101
}

fn default_min_samples() -> usize {
    100
}

impl AutocalSessionOptions {
    /// The defaults (type docs) at a sample rate, with a method.
    pub fn new(rate_hz: f64, method: Method) -> Self {
        Self {
            rate_hz: Some(rate_hz),
            method,
            gravity_m_s2: standard_gravity(),
            init_static_s: default_init_static_s(),
            settle_s: default_settle_s(),
            window_samples: default_window_samples(),
            min_samples: default_min_samples(),
            init: Initial::default(),
            sort_time: false,
        }
    }

    /// Refuse options the method cannot use ([`crate::Error::InvalidOption`]
    /// naming the key): a sample rate outside (0, 1e6] Hz, a gravity
    /// outside (0, 100], a still start outside (0, 1e6] s, a settling time
    /// outside [0, 1000] s, a window that is even or outside 11..=1e6
    /// samples, intervals of fewer than 3 or more than 1e9 samples, a
    /// non-finite initial value or a zero initial scale.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.rate_hz {
            super::check_rate_hz(r)?;
        }
        super::check_gravity_magnitude(self.gravity_m_s2)?;
        crate::options::check_positive("init_static_s", self.init_static_s)?;
        crate::options::check_range("init_static_s", self.init_static_s, 0.0, 1e6, "s")?;
        crate::options::check_range("settle_s", self.settle_s, 0.0, 1e3, "s")?;
        let w = self.window_samples;
        if !(11..=1_000_001).contains(&w) || w % 2 == 0 {
            return crate::options::invalid(
                "window_samples",
                format!("must be odd and within 11..1000001 samples, got {w}"),
            );
        }
        crate::options::check_range("min_samples", self.min_samples as f64, 3.0, 1e9, "samples")?;
        self.init.validate()
    }

    /// The options as reduced and recorded: `settle_s` as used (0 for
    /// method `tedaldi`, which trims nothing).
    pub fn settled(&self) -> AutocalSessionOptions {
        let mut o = *self;
        if o.method == Method::Tedaldi {
            o.settle_s = 0.0;
        }
        o
    }

    /// The options of [`autocal`]: the method's settings
    /// ([`AutocalOptions::new`]) with the window, the interval length and,
    /// for method `incal`, the settling time given.
    pub fn model(&self) -> AutocalOptions {
        let o = self.settled();
        let mut m = AutocalOptions::new(o.method, o.gravity_m_s2, o.init_static_s);
        m.window = o.window_samples;
        m.min_samples = o.min_samples;
        m.settle_s = o.settle_s;
        m.init = o.init;
        m
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

    fn example() -> AutocalSessionOptions {
        AutocalSessionOptions {
            rate_hz: Some(100.0),
            method: Method::Incal,
            gravity_m_s2: 9.81,
            init_static_s: 3.0,
            settle_s: 0.1,
            init: Default::default(),
            sort_time: false,
            window_samples: 101,
            min_samples: 100,
        }
    }

    fn validate(o: &AutocalSessionOptions) -> Result<()> {
        o.validate()
    }

    fn recorded(
        input: &Self::Input,
        o: &AutocalSessionOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        let mut o = o.settled();
        o.rate_hz = Some(input.rate_hz);
        crate::procedures::options_map(&o)
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

    fn synthesis(
        input: &Self::Input,
        o: &AutocalSessionOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Self::Input>>> {
        super::montecarlo::autocal_synthesis(input, o).map(Some)
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

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn key_of(e: Error) -> String {
        crate::options::refused_key::<()>(Err(e))
    }

    #[test]
    fn options_round_trip_and_a_bad_one_names_its_key() {
        use crate::options::from_json;
        // The document's options, as recorded.
        let doc = json!({"gravity_m_s2": 9.80665, "init_static_s": 3.0, "method": "incal", "min_samples": 100, "rate_hz": 100.0, "settle_s": 0.1, "window_samples": 101});
        let o: AutocalSessionOptions = from_json(&doc).unwrap();
        assert_eq!(serde_json::to_value(o).unwrap(), doc);
        assert_eq!(
            o,
            from_json(&json!({"rate_hz": 100, "init_static_s": 3})).unwrap()
        );
        // tedaldi trims nothing: recorded with settle_s 0; given values
        // and the flag recorded only when set.
        let t = AutocalSessionOptions {
            method: Method::Tedaldi,
            sort_time: true,
            init: Initial {
                acc_bias: Some([32768.0; 3]),
                ..Initial::default()
            },
            ..o
        };
        let v = serde_json::to_value(t.settled()).unwrap();
        assert_eq!(v["settle_s"], 0.0);
        assert_eq!(v["sort_time"], true);
        assert_eq!(v["init_acc_bias"], json!([32768.0, 32768.0, 32768.0]));
        assert!(v.get("init_gyro_scale").is_none(), "{v}");
        assert_eq!(from_json::<AutocalSessionOptions>(&v).unwrap(), t.settled());
        assert_eq!(t.model(), t.settled().model());
        let bad = |v| key_of(from_json::<AutocalSessionOptions>(&v).unwrap_err());
        assert_eq!(bad(json!({"rate_hz": 100, "window": 51})), "window");
        assert_eq!(bad(json!({"rate_hz": 100, "method": "imu_tk"})), "method");
        let invalid = |o: AutocalSessionOptions| key_of(o.validate().unwrap_err());
        assert_eq!(
            invalid(AutocalSessionOptions {
                window_samples: 100,
                ..o
            }),
            "window_samples"
        );
        assert_eq!(
            invalid(AutocalSessionOptions {
                gravity_m_s2: -9.81,
                ..o
            }),
            "gravity_m_s2"
        );
        assert_eq!(
            invalid(AutocalSessionOptions {
                settle_s: -1.0,
                ..o
            }),
            "settle_s"
        );
        assert_eq!(
            invalid(AutocalSessionOptions {
                init: Initial {
                    gyro_scale: Some([0.0, 1.0, 1.0]),
                    ..Initial::default()
                },
                ..o
            }),
            "init_gyro_scale"
        );
    }
}
