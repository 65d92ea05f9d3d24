//! Compensation and angular-motion solution of a gyro-free unit
//! (methods.md §4; the seed's paper stops after writing the six equations).
//!
//! # Model
//! With calibrated `K0_j, Ks_j` and the geometry, accelerometer j reads
//!
//! ```text
//! E_j = K0_j + Ks_jᵀ f0 + (r_j × Ks_j)ᵀ ω̇ / g + Ks_jᵀ (ω × (ω × r_j)) / g
//! ```
//!
//! (`f0` g, `ω̇` rad/s², `ω` rad/s, `r_j` m, `g` the local gravity in m/s²
//! that defines the g unit). Unknowns per sample: `x = (f0, ω̇)`.
//!
//! # Integration of ω
//! `ω_k = ω_{k−1} + (ω̇_{k−1} + ω̇_k)(t_k − t_{k−1})/2` (trapezoid), with
//! `ω_0` given at the first sample. The centripetal term at sample k thus
//! depends on the unknown `ω̇_k`; each sample is solved by
//! [`crate::estimation::gauss_newton`] (analytic Jacobian), started from the
//! previous sample's solution. The trapezoid is exact for ω̇ piecewise
//! linear between samples; a step in ω̇ between two samples leaves an ω
//! error of up to `|Δω̇| Δt / 2`.
//!
//! # Uncertainty
//! When the calibration gives every accelerometer's sample noise σ_j, the
//! weights are `1/σ_j²` and each sample's f0, ω̇ get `u` from the fit
//! (calibration uncertainty of K0, Ks not included, nor the error of the
//! integrated ω: it enters f0 through the centripetal term as about
//! `2|ω||δω| r/g`, which grows with the random walk of δω and must stay
//! below the noise for u to be complete). With N > 6 and no σ,
//! the residuals give the variance. With N = 6 and no σ no u is reported.

use nalgebra::{DMatrix, DVector, Vector3};

use crate::error::{Error, Result};
use crate::estimation::{
    gauss_newton, Diagnostics, FitOptions, GaussNewtonOptions, NonlinearModel, Variance,
};
use crate::models::gfimu::{Geometry, MOTION_TERMS};

/// Calibrated coefficients of one accelerometer, geometry order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedAccelerometer {
    /// Equivalent bias K0 (output).
    pub k0: f64,
    /// Equivalent sensitive vector Ks (output/g).
    pub ks: Vector3<f64>,
    /// Standard deviation of one output sample (output), if known.
    pub noise_output: Option<f64>,
}

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveOptions {
    /// Angular rate at the first sample (rad/s, unit frame).
    pub omega0_rad_s: Vector3<f64>,
    /// Local gravity defining the g unit (m/s²).
    pub gravity_m_s2: f64,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            omega0_rad_s: Vector3::zeros(),
            gravity_m_s2: crate::units::STANDARD_GRAVITY_M_S2,
        }
    }
}

/// Solution at one sample time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionSample {
    /// Sample time (s).
    pub time_s: f64,
    /// Specific force at the unit's origin (g, unit frame).
    pub f0_g: Vector3<f64>,
    /// Angular acceleration (rad/s²).
    pub omega_dot_rad_s2: Vector3<f64>,
    /// Angular rate integrated from ω̇ (rad/s).
    pub omega_rad_s: Vector3<f64>,
    /// Standard uncertainty of f0 (g), when the noise is known (module docs).
    pub u_f0_g: Option<Vector3<f64>>,
    /// Standard uncertainty of ω̇ (rad/s²), when the noise is known.
    pub u_omega_dot_rad_s2: Option<Vector3<f64>>,
}

/// Result of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct MotionSolution {
    /// One solution per input sample.
    pub samples: Vec<MotionSample>,
    /// Rank and condition of the calibrated N×6 system.
    pub diagnostics: Diagnostics,
    /// Warnings (weak geometry).
    pub warnings: Vec<crate::Warning>,
}

/// The measurement model of one sample (module docs), for Gauss–Newton.
struct SampleModel<'a> {
    geometry: &'a Geometry,
    cal: &'a [CalibratedAccelerometer],
    omega_prev: Vector3<f64>,
    omega_dot_prev: Vector3<f64>,
    half_dt: f64,
    g: f64,
}

impl SampleModel<'_> {
    fn omega(&self, omega_dot: &Vector3<f64>) -> Vector3<f64> {
        self.omega_prev + (self.omega_dot_prev + omega_dot) * self.half_dt
    }
    fn split(x: &DVector<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (
            Vector3::new(x[0], x[1], x[2]),
            Vector3::new(x[3], x[4], x[5]),
        )
    }
}

impl NonlinearModel for SampleModel<'_> {
    fn names(&self) -> Vec<String> {
        MOTION_TERMS.iter().map(|s| s.to_string()).collect()
    }

    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        let (f0, wd) = Self::split(x);
        let w = self.omega(&wd);
        DVector::from_iterator(
            self.cal.len(),
            self.geometry
                .accelerometers()
                .iter()
                .zip(self.cal)
                .map(|(a, c)| {
                    let r = a.position_m;
                    c.k0 + c
                        .ks
                        .dot(&(f0 + (wd.cross(&r) + w.cross(&w.cross(&r))) / self.g))
                }),
        )
    }

    /// `∂E_j/∂f0 = Ks_j`; `∂E_j/∂ω̇ = [r_j × Ks_j + (Δt/2) ∇_ω]/g` with
    /// `∇_ω Ksᵀ(ω×(ω×r)) = Ks(ωᵀr) + r(Ksᵀω) − 2(Ksᵀr)ω`.
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let (_, wd) = Self::split(x);
        let w = self.omega(&wd);
        let mut j = DMatrix::zeros(self.cal.len(), 6);
        for (i, (a, c)) in self
            .geometry
            .accelerometers()
            .iter()
            .zip(self.cal)
            .enumerate()
        {
            let r = a.position_m;
            let s = c.ks;
            let grad = s * w.dot(&r) + r * s.dot(&w) - w * (2.0 * s.dot(&r));
            let m = (r.cross(&s) + grad * self.half_dt) / self.g;
            for k in 0..3 {
                j[(i, k)] = s[k];
                j[(i, 3 + k)] = m[k];
            }
        }
        j
    }
}

/// Solve every sample `(t_k, E_k)` of a time series for f0, ω̇ and ω
/// (module docs). Times must increase strictly.
pub fn solve(
    geometry: &Geometry,
    cal: &[CalibratedAccelerometer],
    series: &[(f64, Vec<f64>)],
    opts: &SolveOptions,
) -> Result<MotionSolution> {
    let n = geometry.len();
    if cal.len() != n {
        return Err(Error::Unsupported(format!(
            "{} calibrated accelerometers for a geometry of {n}",
            cal.len()
        )));
    }
    let g = opts.gravity_m_s2;
    if !(g.is_finite() && g > 0.0) {
        return Err(Error::InvalidValue {
            what: "gravity (m/s^2)".into(),
            value: g.to_string(),
        });
    }
    if let Some(v) = opts.omega0_rad_s.iter().find(|v| !v.is_finite()) {
        return Err(Error::InvalidValue {
            what: "initial angular rate".into(),
            value: v.to_string(),
        });
    }
    for (j, c) in cal.iter().enumerate() {
        if !(c.k0.is_finite() && c.ks.iter().all(|v| v.is_finite())) {
            return Err(Error::InvalidValue {
                what: format!("calibration of accelerometer {}", j + 1),
                value: format!("K0 {} Ks {:?}", c.k0, c.ks.as_slice()),
            });
        }
        if let Some(s) = c.noise_output {
            if !(s.is_finite() && s > 0.0) {
                return Err(Error::InvalidValue {
                    what: format!("noise of accelerometer {}", j + 1),
                    value: s.to_string(),
                });
            }
        }
    }
    // The calibrated system must separate f0 and ω̇ (names the weak term).
    let ks: Vec<Vector3<f64>> = cal.iter().map(|c| c.ks).collect();
    let design = geometry.motion_design(&ks, g)?;
    let diagnostics = design.diagnose(None, crate::estimation::DEFAULT_COND_LIMIT);
    if !diagnostics.aliases.is_empty() {
        return Err(Error::Unseparable {
            aliases: diagnostics.aliases,
        });
    }
    let mut warnings = Vec::new();
    if diagnostics.condition > crate::estimation::WARN_COND {
        warnings.push(crate::Warning::new(
            crate::WarningCode::WeakConditioning,
            format!(
                "weak calibrated geometry (condition number {:.2e}): {} is poorly determined",
                diagnostics.condition,
                diagnostics.weakest.combination()
            ),
        ));
    }
    let sigmas: Option<Vec<f64>> = cal.iter().map(|c| c.noise_output).collect();
    let (weights, variance, report_u) = match &sigmas {
        Some(s) => (
            Some(DVector::from_iterator(n, s.iter().map(|s| 1.0 / (s * s)))),
            Variance::Known { dof: f64::INFINITY },
            true,
        ),
        None if n > 6 => (None, Variance::FromResiduals, true),
        // Exactly determined, noise unknown: unit weights, no u.
        None => (None, Variance::Known { dof: f64::INFINITY }, false),
    };
    let gn = GaussNewtonOptions {
        fit: FitOptions {
            weights,
            variance,
            ..FitOptions::default()
        },
        max_iter: 50,
        tol: 1e-9,
    };
    let mut out: Vec<MotionSample> = Vec::with_capacity(series.len());
    let mut x = DVector::zeros(6);
    for (k, (t, e)) in series.iter().enumerate() {
        if e.len() != n {
            return Err(Error::Unsupported(format!(
                "sample {}: {} outputs for {n} accelerometers",
                k + 1,
                e.len()
            )));
        }
        if let Some(v) = std::iter::once(t).chain(e.iter()).find(|v| !v.is_finite()) {
            return Err(Error::InvalidValue {
                what: format!("sample {}", k + 1),
                value: v.to_string(),
            });
        }
        let (omega_prev, omega_dot_prev, half_dt) = match out.last() {
            None => (opts.omega0_rad_s, Vector3::zeros(), 0.0),
            Some(p) => {
                if *t <= p.time_s {
                    return Err(Error::InvalidValue {
                        what: format!("time of sample {} (times must increase)", k + 1),
                        value: t.to_string(),
                    });
                }
                (p.omega_rad_s, p.omega_dot_rad_s2, 0.5 * (t - p.time_s))
            }
        };
        let model = SampleModel {
            geometry,
            cal,
            omega_prev,
            omega_dot_prev,
            half_dt,
            g,
        };
        let y = DVector::from_column_slice(e);
        let (fit, _) = gauss_newton(&model, &y, x.clone(), &gn)?;
        x = fit.estimates.values().clone();
        let (f0, wd) = SampleModel::split(&x);
        let u = |k0: usize| Vector3::from_fn(|k, _| fit.estimates.u_at(k0 + k));
        out.push(MotionSample {
            time_s: *t,
            f0_g: f0,
            omega_dot_rad_s2: wd,
            omega_rad_s: model.omega(&wd),
            u_f0_g: report_u.then(|| u(0)),
            u_omega_dot_rad_s2: report_u.then(|| u(3)),
        });
    }
    Ok(MotionSolution {
        samples: out,
        diagnostics,
        warnings,
    })
}
