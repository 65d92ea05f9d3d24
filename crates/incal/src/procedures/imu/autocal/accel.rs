//! The accelerometer fit (Tedaldi eq. 10): the model `g − ‖T K (a − b)‖`
//! with its analytic Jacobian, the starting point (the user's values, an
//! ellipsoid through the interval means, or a scale from the mean
//! magnitude), the observations of each method (samples, or weighted
//! interval means), the check that the gravity directions separate the
//! misalignments, and the final fit with its covariance.

use nalgebra::{DMatrix, DVector};

use super::super::detect::{self, Interval};
use super::super::sim::TriadParams;
use super::super::V3;
use super::session::Session;
use super::threshold::Candidate;
use super::{minimize, AutocalOptions, Initial, Method, ACC_PARAMS};
use crate::error::{Error, Result};
use crate::estimation::{fit, Design, Fit, FitOptions, NonlinearModel, Variance};

/// Names of the accelerometer parameters in the result (`acc.m_yz`, …).
pub(super) fn acc_names() -> Vec<String> {
    ACC_PARAMS.iter().map(|n| format!("acc.{n}")).collect()
}

/// The accelerometer's [`TriadParams`] of the parameter vector `x`
/// ([`ACC_PARAMS`] order; `m_xz = m_xy = m_yx = 0`).
pub(super) fn acc_params(x: &DVector<f64>) -> TriadParams {
    TriadParams {
        mis: [x[0], x[1], x[2], 0.0, 0.0, 0.0],
        scale: [x[3], x[4], x[5]],
        bias: [x[6], x[7], x[8]],
    }
}

/// Residuals `g − ‖T K (a − b)‖` of the samples `a`.
pub(super) fn acc_residuals(x: &DVector<f64>, samples: &[[f64; 3]], g: f64) -> DVector<f64> {
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

/// The residuals `g − ‖T K (a − b)‖` of a set of observations `a` as a
/// model of zero observations ([`crate::estimation::minimize`]).
pub(super) struct AccModel<'a> {
    /// Observations (samples or interval means, raw units).
    pub samples: &'a [[f64; 3]],
    /// Gravity magnitude (m/s²).
    pub g: f64,
}

impl NonlinearModel for AccModel<'_> {
    fn names(&self) -> Vec<String> {
        acc_names()
    }
    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        acc_residuals(x, self.samples, self.g)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        acc_jacobian(x, self.samples)
    }
}

/// Minimise the residuals of `samples` from `x0` with optional weights.
pub(super) fn minimize_acc(
    samples: &[[f64; 3]],
    g: f64,
    x0: DVector<f64>,
    weights: Option<&DVector<f64>>,
) -> Result<DVector<f64>> {
    minimize(&AccModel { samples, g }, samples.len(), x0, weights)
}

/// The accelerometer fit's starting point: the user's initial values
/// where given ([`Initial`]), the rest from an ellipsoid through the
/// intervals' means ([`ellipsoid_start`]), or `fallback` (bias 0, scale g
/// over the median mean magnitude) when the means do not define one.
pub(super) fn acc_start(
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

/// Accelerometer observations and their weights.
pub(super) type AccObservations = (Vec<[f64; 3]>, Option<DVector<f64>>);

/// The accelerometer observations: tedaldi, the used samples (no
/// weights); incal, the interval means with weights `n/σ²` where σ is the
/// scatter of the interval's residuals at `at` (equal weights before).
pub(super) fn acc_observations(
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
pub(super) fn check_separation(
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

/// The final accelerometer fit at the kept threshold: tedaldi, the
/// candidate's minimum; incal, refitted with the weights `n/σ²` from each
/// interval's residual scatter at the candidate. Returns `x̂` and the
/// linear fit at `x̂` with its covariance (tedaldi: `s²(JᵀJ)⁻¹`; incal: the
/// prior variance unless the residuals show lack of fit).
pub(super) fn final_fit(s: &Session, best: &Candidate) -> Result<(DVector<f64>, Fit)> {
    let (acc, opts, g) = (&s.acc[..], s.opts, s.g);
    let used = |iv: &Interval| s.used(iv);
    let (samples, mut weights) = acc_observations(acc, &best.intervals, &used, opts, None)?;
    let mut x = best.x.clone();
    if opts.method == Method::Incal {
        // Weights from each interval's residual scatter at the solution.
        let (s2, w) = acc_observations(acc, &best.intervals, &used, opts, Some(&x))?;
        weights = w;
        x = minimize_acc(&s2, g, x, weights.as_ref())
            .map_err(|e| best.separation.clone().unwrap_or(e))?;
    }
    let variance = match opts.method {
        Method::Tedaldi => Variance::FromResiduals,
        Method::Incal => Variance::AtLeast {
            dof: best
                .intervals
                .iter()
                .filter_map(used)
                .map(|u| (u.len() - 1) as f64)
                .sum(),
        },
    };
    let r = acc_residuals(&x, &samples, g);
    let j = acc_jacobian(&x, &samples);
    let design = Design::new(acc_names(), j)?;
    let f = fit(
        &design,
        &(-&r),
        &FitOptions {
            weights,
            variance,
            ..FitOptions::default()
        },
    )?;
    Ok((x, f))
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
}
