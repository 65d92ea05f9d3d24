//! Compensation and angular-motion solution of a gyro-free unit
//! (docs/src/gfimu.md; the seed's paper stops after writing the six equations).
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
//! # Two ways to solve a sample
//! The centripetal term is `Ks_jᵀ(W r_j − tr(W) r_j)/g` with `W = ωωᵀ`, linear
//! in the six products `ω_a ω_b`. Only the products whose regressors are
//! non-zero enter (for accelerometers sensing across their lever arm,
//! `Ks ⟂ r`, the squares drop out).
//!
//! * **direct**: when the layout can separate f0, ω̇ *and* every product
//!   that enters (e.g. twelve accelerometers, two across each of six lever
//!   arms), each sample is one linear least-squares solve with no feedback;
//!   ω is then only integrated, and its error is a random walk.
//! * **feedback** (the six-accelerometer layout of the paper): the products
//!   are computed from the integrated ω. Per sample: predict
//!   `ω⁻ = ω_{k−1} + ω̇_{k−1} Δt`, solve the linear system for `(f0, ω̇_k)`,
//!   integrate `ω_k = ω_{k−1} + (ω̇_{k−1} + ω̇_k) Δt/2` (trapezoid), and solve
//!   once more with `ω_k` (a fixed-point step of the implicit trapezoid).
//!   An error δω feeds back through the centripetal term into ω̇, so it
//!   can grow exponentially: this is physics, and the solution reports it.
//!
//! Either way the weighted pseudo-inverse `P = (AᵀWA)⁻¹AᵀW` of the fixed
//! design is computed once (SVD, [`crate::estimation::fit`]'s engine), so a
//! sample costs one N×p product: 10⁶ samples take well under a second.
//!
//! # Uncertainty
//! Per sample, `C = C_noise + C_cal + C_ω`:
//! * `C_noise = (AᵀWA)⁻¹` with `W = diag(1/σ_j²)` when the calibration gives
//!   every accelerometer's sample noise σ_j (else from the residuals when
//!   N > p, else none);
//! * `C_cal = P diag(u²(K0_j) + Σ_a f_{j,a}² u²(Ks_{j,a})) Pᵀ`, the
//!   calibration's u carried through the specific force `f_j` at each
//!   accelerometer (JCGM 100 §5.1.2, components taken independent);
//! * `C_ω = P G Σ_ω Gᵀ Pᵀ` (feedback only), the integrated-ω error through
//!   the centripetal gradient `G_j = [Ks_j(ωᵀr_j) + r_j(Ks_jᵀω) − 2(Ks_jᵀr_j)ω]ᵀ/g`.
//!
//! The predicted ω error covariance is propagated with the solution,
//! `Σ_k = F Σ_{k−1} Fᵀ + Δt² C_ω̇` with `F = I − Q Δt` and `Q` the
//! ω̇ rows of `P G` (zero in direct mode): `u_omega_rad_s` is its diagonal,
//! and a warning (`model-range`) says when it first exceeds
//! [`SolveOptions::omega_u_limit_rad_s`]. A solution whose |ω| passes
//! 10⁴ rad/s has diverged and is refused at that sample.

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};
use crate::estimation::{Design, Diagnostics, DEFAULT_COND_LIMIT, WARN_COND};
use crate::models::gfimu::{Geometry, MOTION_TERMS};
use crate::warning::{Warning, WarningCode};

mod prepare;
mod uncertainty;

use prepare::{check_inputs, geometry_diagnostics, sample_design, weighted_pinv};

/// Calibrated coefficients of one accelerometer, geometry order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedAccelerometer {
    /// Equivalent bias K0 (output).
    pub k0: f64,
    /// Equivalent sensitive vector Ks (output/g).
    pub ks: Vector3<f64>,
    /// Standard deviation of one output sample (output), if known.
    pub noise_output: Option<f64>,
    /// Standard uncertainty of K0 (output); 0 when not known.
    pub u_k0: f64,
    /// Standard uncertainty of each Ks component (output/g); 0 when not known.
    pub u_ks: Vector3<f64>,
}

impl CalibratedAccelerometer {
    /// K0, Ks and the sample noise, with no calibration uncertainty.
    pub fn new(k0: f64, ks: Vector3<f64>, noise_output: Option<f64>) -> Self {
        Self {
            k0,
            ks,
            noise_output,
            u_k0: 0.0,
            u_ks: Vector3::zeros(),
        }
    }
}

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveOptions {
    /// Angular rate at the first sample (rad/s, unit frame).
    pub omega0_rad_s: Vector3<f64>,
    /// Local gravity defining the g unit (m/s²).
    pub gravity_m_s2: f64,
    /// Predicted u(ω) (rad/s) beyond which the solution warns.
    pub omega_u_limit_rad_s: f64,
}

/// Largest local gravity accepted (m/s²): the g unit of a unit on Earth
/// (or a centrifuge's equivalent), not a typo of 1000.
pub const MAX_GRAVITY_M_S2: f64 = 100.0;

impl SolveOptions {
    /// Refuse a non-finite initial rate, a gravity that is not positive
    /// or above [`MAX_GRAVITY_M_S2`], and a u limit that is not positive,
    /// naming the option.
    pub fn validate(&self) -> Result<()> {
        if let Some(v) = self.omega0_rad_s.iter().find(|v| !v.is_finite()) {
            return Err(Error::Unsupported(format!(
                "`omega0_rad_s` must be three finite numbers, got {v}"
            )));
        }
        let g = self.gravity_m_s2;
        if !(g.is_finite() && g > 0.0 && g <= MAX_GRAVITY_M_S2) {
            return Err(Error::Unsupported(format!(
                "`gravity_m_s2` must be a positive number (at most {MAX_GRAVITY_M_S2}), got {}",
                super::input::shown(g)
            )));
        }
        let l = self.omega_u_limit_rad_s;
        if !(l.is_finite() && l > 0.0) {
            return Err(Error::Unsupported(format!(
                "`omega_u_limit_rad_s` must be a positive number, got {}",
                super::input::shown(l)
            )));
        }
        Ok(())
    }
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            omega0_rad_s: Vector3::zeros(),
            gravity_m_s2: crate::units::STANDARD_GRAVITY_M_S2,
            omega_u_limit_rad_s: 0.01,
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
    /// Predicted standard uncertainty of the integrated ω (rad/s).
    pub u_omega_rad_s: Option<Vector3<f64>>,
}

/// Result of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct MotionSolution {
    /// One solution per input sample.
    pub samples: Vec<MotionSample>,
    /// Rank and condition of the calibrated N×6 system.
    pub diagnostics: Diagnostics,
    /// Warnings (weak geometry, ω error growth).
    pub warnings: Vec<crate::Warning>,
    /// How the samples were solved.
    pub mode: SolveMode,
}

/// How a layout solves a sample (module docs).
#[derive(Debug, Clone, PartialEq)]
pub enum SolveMode {
    /// f0, ω̇ and the products that enter, linear, no feedback.
    Direct {
        /// Names of the products solved as unknowns (`ww_xy`, …).
        products: Vec<String>,
    },
    /// f0 and ω̇, the products from the integrated ω.
    Feedback {
        /// Why not direct: the combination the layout cannot separate.
        reason: String,
    },
}

impl SolveMode {
    /// `direct` or `feedback`.
    pub fn name(&self) -> &'static str {
        match self {
            SolveMode::Direct { .. } => "direct",
            SolveMode::Feedback { .. } => "feedback",
        }
    }
}

/// Products `ω_a ω_b` in the order of [`PRODUCT_NAMES`].
pub const PRODUCTS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
/// Names of the products.
pub const PRODUCT_NAMES: [&str; 6] = ["ww_xx", "ww_yy", "ww_zz", "ww_xy", "ww_xz", "ww_yz"];

/// Regressor of product `(a, b)` for sensitive vector `s` at lever arm `r`
/// (times g): `s_a r_a − sᵀr` for a square, `s_a r_b + s_b r_a` else.
fn product_regressor(s: &Vector3<f64>, r: &Vector3<f64>, (a, b): (usize, usize)) -> f64 {
    if a == b {
        s[a] * r[a] - s.dot(r)
    } else {
        s[a] * r[b] + s[b] * r[a]
    }
}

/// Centripetal specific force along `s` at `r`: `sᵀ(ω×(ω×r))` (g·m/s² units / g outside).
fn centripetal(s: &Vector3<f64>, r: &Vector3<f64>, w: &Vector3<f64>) -> f64 {
    s.dot(&w.cross(&w.cross(r)))
}

/// Which unknowns a layout can solve (module docs): the direct set when
/// f0, ω̇ and every entering product separate, else feedback, with the
/// inseparable combination named.
pub fn solve_mode(geometry: &Geometry, ks: &[Vector3<f64>], g: f64) -> Result<SolveMode> {
    let accs = geometry.accelerometers();
    let scale = accs
        .iter()
        .map(|a| a.position_m.norm())
        .fold(0.0, f64::max)
        .max(1e-12);
    let entering: Vec<usize> = (0..6)
        .filter(|&k| {
            accs.iter().zip(ks).any(|(a, s)| {
                product_regressor(s, &a.position_m, PRODUCTS[k]).abs() > 1e-9 * scale * s.norm()
            })
        })
        .collect();
    let mut names: Vec<String> = MOTION_TERMS.iter().map(|s| s.to_string()).collect();
    names.extend(entering.iter().map(|&k| PRODUCT_NAMES[k].to_string()));
    let rows: Vec<Vec<f64>> = accs
        .iter()
        .zip(ks)
        .map(|(a, s)| {
            let r = a.position_m;
            let m = r.cross(s) / g;
            let mut row = vec![s.x, s.y, s.z, m.x, m.y, m.z];
            row.extend(
                entering
                    .iter()
                    .map(|&k| product_regressor(s, &r, PRODUCTS[k]) / g),
            );
            row
        })
        .collect();
    let d = Design::from_rows(names, &rows)?.diagnose(None, DEFAULT_COND_LIMIT);
    if entering.is_empty() || d.is_separable() && d.condition < WARN_COND {
        return Ok(SolveMode::Direct {
            products: entering
                .iter()
                .map(|&k| PRODUCT_NAMES[k].to_string())
                .collect(),
        });
    }
    let reason = match d.aliases.first() {
        Some(a) => format!(
            "{} accelerometers cannot separate f0, omega_dot and the products {}: {}",
            accs.len(),
            entering
                .iter()
                .map(|&k| PRODUCT_NAMES[k])
                .collect::<Vec<_>>()
                .join(", "),
            a
        ),
        None => format!(
            "f0, omega_dot and the products are weakly separated (condition number {:.2e})",
            d.condition
        ),
    };
    Ok(SolveMode::Feedback { reason })
}

/// Largest number of unknowns per sample: f0, ω̇ and the six products.
const MAX_P: usize = 12;

/// A streaming motion solver: one call of [`Solver::step`] per sample, in
/// time order, constant memory (module docs). A step allocates nothing:
/// the pseudo-inverse and the constant covariance blocks are computed once
/// in [`Solver::new`], the per-sample work is a few N×p products.
#[derive(Debug, Clone)]
pub struct Solver {
    r: Vec<Vector3<f64>>,
    cal: Vec<CalibratedAccelerometer>,
    g: f64,
    mode: SolveMode,
    /// Indices (into PRODUCTS) of the products solved directly.
    direct_products: Vec<usize>,
    /// Unknowns per sample.
    p: usize,
    /// Weighted pseudo-inverse, row-major p × N.
    pinv: Vec<f64>,
    /// Design, row-major N × p, for the residual variance when σ is unknown.
    design: Vec<f64>,
    /// Diagonal of the per-sample noise covariance: `(AᵀWA)⁻¹` with
    /// W = 1/σ², or `P Pᵀ` to be scaled by the residual variance.
    noise_diag: [f64; MAX_P],
    /// The ω̇ block of the same matrix.
    noise_wd: Matrix3<f64>,
    /// How the noise covariance is known (module docs).
    noise: NoiseSource,
    omega_u_limit: f64,
    warned_at: Option<f64>,
    prev: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    sigma_omega: Matrix3<f64>,
    /// Sensitivity of the integrated ω to every calibration parameter
    /// (K0_j, Ks_j: 4N columns): calibration errors are systematic, so
    /// their effect on ω grows linearly, not as a random walk.
    j_cal: Vec<Vector3<f64>>,
    /// Direct mode (F = I): column c of accelerometer j in `j_cal` is
    /// `P_ω̇,j · s_jc` with `s_j0 = −Σ Δt`, `s_ja = −Σ f_ja Δt`, so only these
    /// four integrals per accelerometer are kept.
    cal_integrals: Vec<[f64; 4]>,
    /// `Q` of the last sample (ω̇ rows of `P G`; zero in direct mode).
    q_last: Matrix3<f64>,
    /// Variances of the calibration parameters (4N).
    u2_cal: Vec<f64>,
    has_cal: bool,
    omega0: Vector3<f64>,
    diagnostics: Diagnostics,
    warnings: Vec<Warning>,
    count: u64,
    /// Reduced outputs of the current sample (N).
    y: Vec<f64>,
    /// Centripetal gradient of the current sample (N), feedback only.
    grad: Vec<Vector3<f64>>,
}

/// Where the per-sample noise covariance comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NoiseSource {
    /// Every accelerometer's σ is known: `(AᵀWA)⁻¹`.
    Known,
    /// From the residuals of each sample (N > p): `s² P Pᵀ`.
    Residuals,
    /// Neither: no u is reported.
    None,
}

impl Solver {
    /// Check the calibration and geometry and prepare the solve.
    pub fn new(
        geometry: &Geometry,
        cal: &[CalibratedAccelerometer],
        opts: &SolveOptions,
    ) -> Result<Self> {
        let n = geometry.len();
        let g = check_inputs(n, cal, opts)?;
        let ks: Vec<Vector3<f64>> = cal.iter().map(|c| c.ks).collect();
        let (diagnostics, warnings) = geometry_diagnostics(geometry, &ks, g)?;
        let mode = solve_mode(geometry, &ks, g)?;
        let direct_products: Vec<usize> = match &mode {
            SolveMode::Direct { products } => products
                .iter()
                .filter_map(|p| PRODUCT_NAMES.iter().position(|n| n == p))
                .collect(),
            SolveMode::Feedback { .. } => Vec::new(),
        };
        let r: Vec<Vector3<f64>> = geometry
            .accelerometers()
            .iter()
            .map(|a| a.position_m)
            .collect();
        let p = 6 + direct_products.len();
        let design = sample_design(&ks, &r, g, &direct_products);
        let (pinv, base_cov, noise) = weighted_pinv(&design, cal, &diagnostics)?;
        let mut noise_diag = [0.0; MAX_P];
        for (a, d) in noise_diag.iter_mut().enumerate().take(p) {
            *d = base_cov[(a, a)];
        }
        let u2_cal: Vec<f64> = cal
            .iter()
            .flat_map(|c| [c.u_k0, c.u_ks.x, c.u_ks.y, c.u_ks.z].map(|u| u * u))
            .collect();
        Ok(Self {
            r,
            cal: cal.to_vec(),
            g,
            mode,
            direct_products,
            p,
            pinv: (0..p)
                .flat_map(|a| (0..n).map(move |j| (a, j)))
                .map(|(a, j)| pinv[(a, j)])
                .collect(),
            design: (0..n)
                .flat_map(|j| (0..p).map(move |a| (j, a)))
                .map(|(j, a)| design[(j, a)])
                .collect(),
            noise_diag,
            noise_wd: Matrix3::from_fn(|i, j| base_cov[(3 + i, 3 + j)]),
            noise,
            omega_u_limit: opts.omega_u_limit_rad_s,
            warned_at: None,
            prev: None,
            sigma_omega: Matrix3::zeros(),
            j_cal: vec![Vector3::zeros(); 4 * n],
            cal_integrals: vec![[0.0; 4]; n],
            q_last: Matrix3::zeros(),
            has_cal: u2_cal.iter().any(|v| *v > 0.0),
            u2_cal,
            omega0: opts.omega0_rad_s,
            diagnostics,
            warnings,
            count: 0,
            y: vec![0.0; n],
            grad: vec![Vector3::zeros(); n],
        })
    }

    /// [`Solver::new`] for the calibration file `file`: every problem is
    /// refused naming the file, and a calibrated array that cannot separate
    /// f0 and ω̇ says so.
    pub fn for_calibration(
        file: &str,
        geometry: &Geometry,
        cal: &[CalibratedAccelerometer],
        opts: &SolveOptions,
    ) -> Result<Self> {
        Self::new(geometry, cal, opts).map_err(|e| match e {
            Error::Unseparable { .. } | Error::IllConditioned { .. } => {
                Error::Unsupported(format!("calibrated geometry cannot solve the motion: {e}"))
                    .in_file(file)
            }
            e => e.in_file(file),
        })
    }

    /// How the samples are solved.
    pub fn mode(&self) -> &SolveMode {
        &self.mode
    }

    /// Rank and condition of the calibrated N×6 system.
    pub fn diagnostics(&self) -> &Diagnostics {
        &self.diagnostics
    }

    /// Warnings so far (geometry, ω error growth).
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// `self.y` ← the outputs minus bias and, in feedback mode, the
    /// centripetal term at ω.
    fn reduce(&mut self, e: &[f64], w: &Vector3<f64>) {
        let feedback = self.direct_products.is_empty();
        for (j, (yj, c)) in self.y.iter_mut().zip(&self.cal).enumerate() {
            let cent = if feedback {
                centripetal(&c.ks, &self.r[j], w) / self.g
            } else {
                0.0
            };
            *yj = e[j] - c.k0 - cent;
        }
    }

    /// `x = P y` for the reduced outputs at ω.
    fn solve_at(&mut self, e: &[f64], w: &Vector3<f64>) -> [f64; MAX_P] {
        self.reduce(e, w);
        let n = self.y.len();
        let mut x = [0.0; MAX_P];
        for (a, xa) in x.iter_mut().enumerate().take(self.p) {
            let row = &self.pinv[a * n..(a + 1) * n];
            *xa = row.iter().zip(&self.y).map(|(p, y)| p * y).sum();
        }
        x
    }

    /// Add warnings about the series (its time stamps) to the solution's.
    pub fn add_warnings(&mut self, w: impl IntoIterator<Item = Warning>) {
        self.warnings.extend(w);
    }

    /// Count the sample and refuse one with another number of outputs
    /// than accelerometers, or a time or output that is not finite.
    /// Returns the sample's number (from 1).
    fn check_sample(&mut self, t: f64, e: &[f64]) -> Result<u64> {
        let n = self.cal.len();
        self.count += 1;
        let k = self.count;
        if e.len() != n {
            return Err(Error::Unsupported(format!(
                "sample {k}: {} outputs for {n} accelerometers",
                e.len()
            )));
        }
        if let Some(v) = std::iter::once(&t).chain(e.iter()).find(|v| !v.is_finite()) {
            return Err(Error::InvalidValue {
                what: format!("sample {k}"),
                value: v.to_string(),
            });
        }
        Ok(k)
    }

    /// Solve sample `k` and integrate ω (module docs): the first at the
    /// initial rate; then predict `ω⁻ = ω_{k−1} + ω̇_{k−1} Δt`, solve,
    /// integrate by the trapezoid (feedback: solved once more at the
    /// integrated ω). Returns the unknowns, ω and Δt.
    fn advance(&mut self, t: f64, e: &[f64], k: u64) -> Result<([f64; MAX_P], Vector3<f64>, f64)> {
        let feedback = matches!(self.mode, SolveMode::Feedback { .. });
        let Some((tp, wp, wdp)) = self.prev else {
            let w = self.omega0;
            return Ok((self.solve_at(e, &w), w, 0.0));
        };
        if t < tp {
            return Err(Error::InvalidValue {
                what: format!("time of sample {k} (times must not decrease)"),
                value: t.to_string(),
            });
        }
        let dt = t - tp;
        let mut w = wp + wdp * dt;
        let mut x = self.solve_at(e, &w);
        let passes = if feedback { 2 } else { 1 };
        for _ in 0..passes {
            let wd = Vector3::new(x[3], x[4], x[5]);
            w = wp + (wdp + wd) * (0.5 * dt);
            if feedback {
                x = self.solve_at(e, &w);
            }
        }
        let wd = Vector3::new(x[3], x[4], x[5]);
        w = wp + (wdp + wd) * (0.5 * dt);
        Ok((x, w, dt))
    }

    /// Refuse a rate that is not finite or beyond 1e4 rad/s at sample `k`.
    fn check_divergence(&self, w: &Vector3<f64>, k: u64, t: f64) -> Result<()> {
        if w.iter().all(|v| v.is_finite()) && w.amax() <= 1e4 {
            return Ok(());
        }
        // The mode's full reason is in the output's head (diagnostics);
        // the refusal stays one readable line.
        let why = match &self.mode {
            SolveMode::Direct { .. } => "the integrated omega_dot error grew without bound",
            SolveMode::Feedback { .. } => "the centripetal products come from the integrated omega, so its error feeds back; a layout that solves them directly (e.g. --layout twelve) avoids this",
        };
        Err(Error::Unsupported(format!(
            "the angular rate diverged at sample {k} (t = {t} s): |omega| beyond 1e4 rad/s ({why})"
        )))
    }

    /// Warn (once) when the predicted u(ω) first passes the limit.
    fn warn_omega_u(&mut self, t: f64, k: u64, u_omega: &Vector3<f64>) {
        if self.warned_at.is_none() && u_omega.amax() > self.omega_u_limit {
            self.warned_at = Some(t);
            self.warnings.push(Warning::new(
                WarningCode::ModelRange,
                format!(
                    "the predicted error of the integrated omega passes {} rad/s at t = {t} s (sample {k}); {}",
                    self.omega_u_limit,
                    self.mode_reason()
                ),
            ));
        }
    }

    /// Solve one sample (time not before the previous one; a repeated
    /// stamp is a step of zero: ω does not move, [`crate::timebase`]).
    pub fn step(&mut self, t: f64, e: &[f64]) -> Result<MotionSample> {
        let k = self.check_sample(t, e)?;
        let (x, w, dt) = self.advance(t, e, k)?;
        let f0 = Vector3::new(x[0], x[1], x[2]);
        let wd = Vector3::new(x[3], x[4], x[5]);
        self.check_divergence(&w, k, t)?;
        let (diag, u_omega) = self.uncertainty(e, &x, &f0, &wd, &w, dt);
        let report_u = self.noise != NoiseSource::None;
        if report_u {
            self.warn_omega_u(t, k, &u_omega);
        }
        let u = |k0: usize| Vector3::from_fn(|i, _| diag[k0 + i].max(0.0).sqrt());
        self.prev = Some((t, w, wd));
        Ok(MotionSample {
            time_s: t,
            f0_g: f0,
            omega_dot_rad_s2: wd,
            omega_rad_s: w,
            u_f0_g: report_u.then(|| u(0)),
            u_omega_dot_rad_s2: report_u.then(|| u(3)),
            u_omega_rad_s: report_u.then_some(u_omega),
        })
    }

    fn mode_reason(&self) -> String {
        match &self.mode {
            SolveMode::Direct { .. } => "direct solution (no centripetal feedback): the error is the integrated omega_dot error, sample noise (a random walk) and calibration error (growing linearly)".into(),
            SolveMode::Feedback { reason } => format!(
                "the centripetal products come from the integrated omega, so its error feeds back ({reason})"
            ),
        }
    }
}

/// Solve every sample `(t_k, E_k)` of a time series for f0, ω̇ and ω
/// (module docs). Times must not decrease.
pub fn solve(
    geometry: &Geometry,
    cal: &[CalibratedAccelerometer],
    series: &[(f64, Vec<f64>)],
    opts: &SolveOptions,
) -> Result<MotionSolution> {
    let mut solver = Solver::new(geometry, cal, opts)?;
    let mut samples = Vec::with_capacity(series.len());
    for (t, e) in series {
        samples.push(solver.step(*t, e)?);
    }
    Ok(MotionSolution {
        samples,
        diagnostics: solver.diagnostics.clone(),
        warnings: solver.warnings.clone(),
        mode: solver.mode.clone(),
    })
}
