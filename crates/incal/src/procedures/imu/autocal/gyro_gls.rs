//! incal's gyro fit: generalised least squares. The residual covariance
//! `V = D + B_a C_a B_aᵀ + B_b C_b B_bᵀ` holds the random part `D` (gyro
//! white noise integrated over each motion, noise of the two gravity
//! directions) and the systematic parts shared by every motion
//! (accelerometer parameters through the gravity directions, the gyro
//! bias from the start); the fit is whitened by `L⁻¹` (`V = L Lᵀ`), and
//! the gyro parameters' cross-covariances with the accelerometer and
//! the bias follow from `θ̂_g − θ_g = −(J'ᵀJ')⁻¹ J'ᵀ L⁻¹ (… + B δθ)`
//! (`J' = L⁻¹ J`).

use nalgebra::{DMatrix, DVector};

use super::super::detect::{self, Interval};
use super::super::{M3, V3};
use super::accel::acc_params;
use super::gyro::{
    central_jacobian, gyr_names, gyr_params, gyro_residuals, motions, quat_free_diff, GyroModel,
    StartBias,
};
use super::kinematics::{integrate, Motion};
use super::minimize;
use super::session::Session;
use crate::error::{Error, Result};
use crate::estimation::{fit, propagate, Design, Fit, FitOptions, NonlinearModel, Variance};

/// What the generalised fit needs of the session and the first fit.
pub(super) struct Context<'a> {
    /// The session.
    pub s: &'a Session<'a>,
    /// Raw gyro samples.
    pub gy: &'a [[f64; 3]],
    /// The kept still intervals.
    pub intervals: &'a [Interval],
    /// Accelerometer parameters.
    pub x_acc: &'a DVector<f64>,
    /// Accelerometer fit (its covariance `C_a`).
    pub acc_fit: &'a Fit,
    /// The gyro model (projected residuals).
    pub model: &'a GyroModel<'a>,
    /// The gyro bias from the start.
    pub start: &'a StartBias,
    /// Covariance of the gyro bias `C_b`.
    pub cb: &'a DMatrix<f64>,
}

/// A model whitened by `L⁻¹`: residuals `L⁻¹ r(x)`, Jacobian `L⁻¹ J(x)`.
struct Whitened<'a, M> {
    model: &'a M,
    l_inv: &'a DMatrix<f64>,
}

impl<M: NonlinearModel> NonlinearModel for Whitened<'_, M> {
    fn names(&self) -> Vec<String> {
        self.model.names()
    }
    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        self.l_inv * self.model.predict(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.l_inv * self.model.jacobian(x)
    }
}

/// The random part `D` of the residual covariance at the gyro parameters
/// `xg` (diagonal): per motion and projection direction `e`,
/// `(e × ĝ₁)ᵀ C_φ (e × ĝ₁) + eᵀ (Rᵀ C_ĝ₀ R + C_ĝ₁) e` with `C_φ` the gyro
/// white noise (still-start variance, calibrated) times `Σ Δt²`, and `C_ĝ`
/// the calibrated interval mean's covariance over g².
fn random_part(ctx: &Context, xg: &DVector<f64>) -> Result<DMatrix<f64>> {
    let s = ctx.s;
    let motions = ctx.model.motions;
    let acc_p = acc_params(ctx.x_acc);
    let acc_tk = acc_p.t() * acc_p.k();
    let spans: Vec<(V3, f64)> = ctx
        .intervals
        .iter()
        .map(|iv| {
            let u = s.used(iv).unwrap_or(*iv);
            (V3::from(detect::variance(&s.acc, u)), u.len() as f64)
        })
        .collect();
    let gdir_cov = |k: usize| -> M3 {
        let (v, n) = spans[k];
        acc_tk * M3::from_diagonal(&(v / n)) * acc_tk.transpose() / (s.g * s.g)
    };
    let p = gyr_params(xg, [0.0; 3]);
    let tk = p.t() * p.k();
    let cw = tk * M3::from_diagonal(&V3::from(ctx.start.var)) * tk.transpose();
    let nr = 2 * motions.len();
    let mut v = DMatrix::zeros(nr, nr);
    for (k, m) in motions.iter().enumerate() {
        let dt2: f64 = m.dt.iter().map(|d| d * d).sum();
        let c_phi = cw * dt2;
        let rot = integrate(m, &tk, &ctx.model.bias);
        let c0 = rot.transpose() * gdir_cov(m.from) * rot;
        let c1 = gdir_cov(m.from + 1);
        for a in 0..2 {
            let e = m.basis[a];
            let vv = e.cross(&m.g1);
            let var = (vv.transpose() * c_phi * vv)[0] + (e.transpose() * (c0 + c1) * e)[0];
            if !(var > 0.0 && var.is_finite()) {
                return Err(Error::Unsupported(
                    "the initial still interval has no gyro scatter: the weights of the gyro fit are undefined (a noise-free or clipped record?)".into(),
                ));
            }
            v[(2 * k + a, 2 * k + a)] = var;
        }
    }
    Ok(v)
}

/// `B_a = ∂r/∂θ_a` at the gyro parameters `xg`: the gravity directions
/// rebuilt from perturbed accelerometer parameters, the projection basis
/// kept.
fn acc_sensitivity(ctx: &Context, xg: &DVector<f64>) -> DMatrix<f64> {
    let motions = ctx.model.motions;
    let nr = 2 * motions.len();
    let ra = |xa: &DVector<f64>| {
        let m = motions_at(ctx, xa);
        let mut out = DVector::zeros(nr);
        for (k, (mm, m0)) in m.iter().zip(motions).enumerate() {
            let d = quat_free_diff(xg, &ctx.model.bias, mm);
            out[2 * k] = m0.basis[0].dot(&d);
            out[2 * k + 1] = m0.basis[1].dot(&d);
        }
        out
    };
    let ascale: Vec<f64> = (0..9)
        .map(|k| ctx.acc_fit.estimates.u_at(k).max(1e-12))
        .collect();
    central_jacobian(&ra, ctx.x_acc, &ascale)
}

/// The motions under accelerometer parameters `xa`.
fn motions_at(ctx: &Context, xa: &DVector<f64>) -> Vec<Motion> {
    motions(ctx.s, ctx.gy, ctx.intervals, xa)
}

/// `B_b = ∂r/∂b` at the gyro parameters `xg`.
fn bias_sensitivity(ctx: &Context, xg: &DVector<f64>) -> DMatrix<f64> {
    let motions = ctx.model.motions;
    let rb = |b: &DVector<f64>| gyro_residuals(xg, &V3::new(b[0], b[1], b[2]), motions, true);
    let bvec = DVector::from_vec(ctx.start.mean.to_vec());
    let bscale: Vec<f64> = (0..3).map(|k| ctx.cb[(k, k)].sqrt().max(1e-12)).collect();
    central_jacobian(&rb, &bvec, &bscale)
}

/// `L⁻¹` of the Cholesky factor `V = L Lᵀ`.
fn whitening(v: DMatrix<f64>) -> Result<DMatrix<f64>> {
    let nr = v.nrows();
    let Some(chol) = v.cholesky() else {
        return Err(Error::Unsupported(
            "gyro fit: the residual covariance is not positive definite".into(),
        ));
    };
    chol.l()
        .solve_lower_triangular(&DMatrix::identity(nr, nr))
        .ok_or_else(|| Error::Unsupported("gyro fit: singular whitening".into()))
}

/// The generalised fit from the first fit's `xg` (module docs): `x̂_g` and
/// its fit (the prior variance, dof of the still start, unless the
/// residuals show lack of fit); the cross-covariances with the
/// accelerometer (rows 9–17, columns 0–8) and the gyro bias (columns
/// 18–20) written into the joint covariance `c`.
pub(super) fn gls_fit(
    ctx: &Context,
    xg: DVector<f64>,
    c: &mut DMatrix<f64>,
) -> Result<(DVector<f64>, Fit)> {
    let acc_cov = ctx.acc_fit.estimates.covariance();
    let cb = ctx.cb;
    let mut v = random_part(ctx, &xg)?;
    let ja = acc_sensitivity(ctx, &xg);
    let jb = bias_sensitivity(ctx, &xg);
    v += propagate(acc_cov, &ja) + propagate(cb, &jb);
    let l_inv = whitening(v)?;
    let white = Whitened {
        model: ctx.model,
        l_inv: &l_inv,
    };
    let xg = minimize(&white, ctx.model.len(), xg, None)?;
    let jw = white.jacobian(&xg);
    let gf = fit(
        &Design::new(gyr_names(), jw.clone())?,
        &(-white.predict(&xg)),
        &FitOptions {
            variance: Variance::AtLeast {
                dof: (ctx.s.init.len() - 1) as f64,
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
    let cga = -(&pinv * &ja) * acc_cov;
    let cgb = -(&pinv * &jb) * cb;
    let n_a = 9;
    c.view_mut((n_a, 0), (9, 9)).copy_from(&cga);
    c.view_mut((0, n_a), (9, 9)).copy_from(&cga.transpose());
    c.view_mut((n_a, 18), (9, 3)).copy_from(&cgb);
    c.view_mut((18, n_a), (3, 9)).copy_from(&cgb.transpose());
    Ok((xg, gf))
}
