//! The gyro fit (Tedaldi eq. 15): the bias from the initial still
//! interval, the motions between consecutive still intervals with their
//! gravity directions, the residual `R(q)ᵀ ĝ₀ − ĝ₁` of the calibrated
//! rates integrated over each motion (incal: projected on the two
//! directions normal to ĝ₁), the starting scale from the rotation angles,
//! and the fit (tedaldi: plain least squares; incal: generalised least
//! squares, [`super::gyro_gls`]).

use nalgebra::{DMatrix, DVector};

use super::super::detect::{self, Interval};
use super::super::sim::TriadParams;
use super::super::{screen, V3};
use super::accel::acc_params;
use super::kinematics::{integrate, unit_basis, Motion};
use super::session::Session;
use super::{gyro_gls, minimize, Method, GYR_PARAMS};
use crate::error::Result;
use crate::estimation::{fit, Design, Fit, FitOptions, NonlinearModel};

/// Names of the fitted gyro parameters in the result (`gyr.m_yz`, …).
pub(super) fn gyr_names() -> Vec<String> {
    GYR_PARAMS.iter().map(|n| format!("gyr.{n}")).collect()
}

/// The gyro's [`TriadParams`] of the parameter vector `x` ([`GYR_PARAMS`]
/// order) with the bias `bias`.
pub(super) fn gyr_params(x: &DVector<f64>, bias: [f64; 3]) -> TriadParams {
    TriadParams {
        mis: [x[0], x[1], x[2], x[3], x[4], x[5]],
        scale: [x[6], x[7], x[8]],
        bias,
    }
}

/// The residuals `R(q)ᵀ ĝ₀ − ĝ₁` of every motion: three components each,
/// or (`project`) the two along the motion's basis normal to ĝ₁.
pub(super) fn gyro_residuals(
    x: &DVector<f64>,
    bias: &V3,
    motions: &[Motion],
    project: bool,
) -> DVector<f64> {
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

/// `R(q)ᵀ ĝ₀ − ĝ₁` of one motion (unprojected).
pub(super) fn quat_free_diff(x: &DVector<f64>, bias: &V3, m: &Motion) -> V3 {
    let p = gyr_params(x, [0.0; 3]);
    let rot = integrate(m, &(p.t() * p.k()), bias);
    rot.transpose() * m.g0 - m.g1
}

/// Central-difference Jacobian of `f` at `x`, steps `1e-6·max(|x_k|,
/// scale_k)`.
pub(super) fn central_jacobian(
    f: &dyn Fn(&DVector<f64>) -> DVector<f64>,
    x: &DVector<f64>,
    scale: &[f64],
) -> DMatrix<f64> {
    let steps: Vec<f64> = (0..x.len())
        .map(|k| 1e-6 * x[k].abs().max(scale[k]))
        .collect();
    crate::estimation::numeric_jacobian(&f, x, &steps)
}

/// The gyro residuals ([`gyro_residuals`]) as a model of zero
/// observations ([`crate::estimation::minimize`]), with a
/// central-difference Jacobian ([`central_jacobian`]).
pub(super) struct GyroModel<'a> {
    /// Gyro bias (raw units).
    pub bias: V3,
    /// The motions.
    pub motions: &'a [Motion],
    /// Residuals projected normal to ĝ₁ (incal).
    pub project: bool,
    /// Jacobian step scale of each parameter.
    pub scale: Vec<f64>,
}

impl GyroModel<'_> {
    /// Number of residuals.
    pub fn len(&self) -> usize {
        (if self.project { 2 } else { 3 }) * self.motions.len()
    }
}

impl NonlinearModel for GyroModel<'_> {
    fn names(&self) -> Vec<String> {
        gyr_names()
    }
    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        gyro_residuals(x, &self.bias, self.motions, self.project)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        central_jacobian(&|z| self.predict(z), x, &self.scale)
    }
}

/// The gyro bias from the initial still interval.
pub(super) struct StartBias {
    /// Mean (raw units).
    pub mean: [f64; 3],
    /// Sample variance (raw units²).
    pub var: [f64; 3],
    /// Samples kept.
    pub n: f64,
    /// Samples left out as spikes (incal).
    pub dropped: usize,
}

/// The gyro bias: the still start's mean (incal: its spikes left out).
fn start_bias(s: &Session, gy: &[[f64; 3]]) -> StartBias {
    let start = &gy[s.init.start..=s.init.end];
    let (kept, dropped) = match s.opts.method {
        Method::Incal => screen::without_spikes(start),
        Method::Tedaldi => (start.to_vec(), 0),
    };
    let all = Interval {
        start: 0,
        end: kept.len() - 1,
    };
    StartBias {
        mean: detect::mean(&kept, all),
        var: detect::variance(&kept, all),
        n: kept.len() as f64,
        dropped,
    }
}

/// incal: gyro samples that stand out in motion (between the still
/// intervals) are reported, not changed (a knock and a bad sample look
/// alike); tedaldi: none.
fn in_motion_spikes(s: &Session, gy: &[[f64; 3]], intervals: &[Interval]) -> usize {
    if s.opts.method != Method::Incal {
        return 0;
    }
    let scale = screen::triad_scale(&gy[s.init.start..=s.init.end], 0);
    let flags = screen::hampel_flags(gy, scale);
    intervals
        .windows(2)
        .map(|w| flags[w[0].end..w[1].start].iter().filter(|f| **f).count())
        .sum()
}

/// The gravity direction of an interval under the accelerometer
/// parameters `xa`: the calibrated mean of the whole interval (tedaldi)
/// or of its used samples (incal).
fn gravity_direction(s: &Session, xa: &DVector<f64>, iv: &Interval) -> V3 {
    let p = acc_params(xa);
    let span = match s.opts.method {
        Method::Tedaldi => *iv,
        Method::Incal => s.used(iv).unwrap_or(*iv),
    };
    let m = detect::mean(&s.acc, span);
    p.apply(&V3::from(m)).normalize()
}

/// Gyro samples at a converter's rail ([`super::super::screen::GyroRails`]).
pub(super) fn clipped_samples(gy: &[[f64; 3]]) -> Vec<bool> {
    super::super::screen::GyroRails::of(gy.iter().copied())
        .flags(gy)
        .0
}

/// The motions (index among the intervals' gaps) that hold a clipped gyro
/// sample ([`clipped_samples`]).
pub(super) fn clipped_motions(gy: &[[f64; 3]], intervals: &[Interval]) -> Vec<usize> {
    let clipped = clipped_samples(gy);
    if !clipped.contains(&true) {
        return Vec::new();
    }
    intervals
        .windows(2)
        .enumerate()
        .filter(|(_, w)| clipped[w[0].end..w[1].start].contains(&true))
        .map(|(k, _)| k)
        .collect()
}

/// The motions between consecutive still intervals, with gravity
/// directions under the accelerometer parameters `xa`; a motion across a
/// time gap, or holding a clipped gyro sample, is left out.
pub(super) fn motions(
    s: &Session,
    gy: &[[f64; 3]],
    intervals: &[Interval],
    xa: &DVector<f64>,
) -> Vec<Motion> {
    let clipped = clipped_motions(gy, intervals);
    intervals
        .windows(2)
        .enumerate()
        .filter(|(k, w)| !s.spans_gap(w[0].end, w[1].start) && !clipped.contains(k))
        .map(|(from, w)| {
            let (i0, i1) = (w[0].end, w[1].start - 1);
            let g0 = gravity_direction(s, xa, &w[0]);
            let g1 = gravity_direction(s, xa, &w[1]);
            Motion {
                gyr: (i0..=i1).map(|i| V3::from(gy[i])).collect(),
                dt: (i0..i1).map(|i| s.time[i + 1] - s.time[i]).collect(),
                g0,
                g1,
                basis: unit_basis(&g1),
                from,
            }
        })
        .collect()
}

/// Starting scale: the median over the motions turning more than 0.05 rad
/// of the gravity turn over the raw integral (1 when none).
fn scale_start(motions: &[Motion], bias: &V3) -> f64 {
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
    ratios.get(ratios.len() / 2).copied().unwrap_or(1.0)
}

/// The gyro fit and what the result needs of it.
pub(super) struct GyroFit {
    /// Gyro parameters (bias from the initial interval).
    pub params: TriadParams,
    /// Fit at the solution.
    pub fit: Fit,
    /// The nine fitted parameters ([`GYR_PARAMS`]).
    pub x: DVector<f64>,
    /// Bias (raw units).
    pub bias: [f64; 3],
    /// Joint covariance of `acc.*` (9), `gyr.*` (9) and the gyro bias (3).
    pub cov: DMatrix<f64>,
    /// Gyro samples of the still start left out (incal).
    pub start_spikes: usize,
    /// Gyro samples standing out between the still intervals (incal).
    pub in_motion: usize,
    /// Motions left out for clipped gyro samples ([`clipped_motions`]).
    pub clipped: Vec<usize>,
}

/// The gyro fit (module docs) on the kept still `intervals`, with the
/// accelerometer parameters `x_acc` and their fit.
pub(super) fn gyro_fit(
    s: &Session,
    gy: &[[f64; 3]],
    intervals: &[Interval],
    x_acc: &DVector<f64>,
    acc_fit: &Fit,
) -> Result<GyroFit> {
    let in_motion = in_motion_spikes(s, gy, intervals);
    let start = start_bias(s, gy);
    let bias = V3::from(start.mean);
    let motions = motions(s, gy, intervals, x_acc);
    if motions.len() < 3 {
        return Err(crate::Error::Unsupported(format!(
            "{} of {} motions between still intervals can be integrated (the others span a time gap or hold gyro samples at a converter's rail): the gyro needs at least 3",
            motions.len(),
            intervals.len().saturating_sub(1)
        )));
    }
    let project = s.opts.method == Method::Incal;
    let sg = scale_start(&motions, &bias);
    let s0 = s.opts.init.gyro_scale.unwrap_or([sg; 3]);
    let xg0 = DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, s0[0], s0[1], s0[2]]);
    let model = GyroModel {
        bias,
        motions: &motions,
        project,
        scale: (0..9).map(|k| if k < 6 { 1.0 } else { sg.abs() }).collect(),
    };
    let xg = minimize(&model, model.len(), xg0, None)?;
    let acc_cov = acc_fit.estimates.covariance();
    let n_a = 9;
    let mut c = DMatrix::zeros(21, 21);
    c.view_mut((0, 0), (n_a, n_a)).copy_from(acc_cov);
    let mut cb = DMatrix::zeros(3, 3);
    if s.init.len() > 1 {
        for k in 0..3 {
            cb[(k, k)] = start.var[k] / start.n;
        }
    }
    c.view_mut((18, 18), (3, 3)).copy_from(&cb);
    let (xg, gf) = if project {
        let ctx = gyro_gls::Context {
            s,
            gy,
            intervals,
            x_acc,
            acc_fit,
            model: &model,
            start: &start,
            cb: &cb,
        };
        gyro_gls::gls_fit(&ctx, xg, &mut c)?
    } else {
        let gf = fit(
            &Design::new(gyr_names(), model.jacobian(&xg))?,
            &(-model.predict(&xg)),
            &FitOptions::default(),
        )?;
        (xg, gf)
    };
    c.view_mut((n_a, n_a), (9, 9))
        .copy_from(gf.estimates.covariance());
    Ok(GyroFit {
        params: gyr_params(&xg, start.mean),
        fit: gf,
        x: xg,
        bias: start.mean,
        cov: c,
        start_spikes: start.dropped,
        in_motion,
        clipped: clipped_motions(gy, intervals),
    })
}
