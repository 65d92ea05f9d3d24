//! The ellipsoid fit of a magnetometer session and its alignment to the
//! accelerometer: damped Gauss–Newton on the normal equations, the
//! core's fit summary at the minimum (the core's
//! [`crate::estimation::gauss_newton::gauss_newton`]).
//!
//! # Model
//! A raw reading is `m = S⁻¹ b + h + e`: `b` the field in the
//! magnetometer's axes (`|b| = F` everywhere the unit is turned), `h` the
//! hard-iron offset, `S` the soft-iron correction (scale factors,
//! non-orthogonality and soft iron together) and `e` the noise. Only
//! `|S(m − h)|` is observed, so `S` is determined up to a rotation: it is
//! taken symmetric positive definite (the polar factor; any rotation of
//! the axes is the alignment's). The fit estimates `h` and
//! `C = S/F` (the map onto the unit sphere) from the magnitude residuals
//!
//! `r_i = |C (m_i − h)| − ρ`,
//!
//! with `ρ = 1 + s²`: the mean of `|y + ε|` exceeds `|y| = 1` by the
//! variance `s²` of the noise across the sphere (two tangential
//! components of variance `s²`, each adding `s²/2`), `s²` the variance of
//! the first fit's residuals. Without it the soft-iron scale would be
//! biased by `s²` (relative).
//!
//! With an accelerometer, the rows at rest add the dot residuals
//!
//! `d_i = f̂_iᵀ R ŷ_i + sin I`,
//!
//! `f̂` the unit specific force (up), `ŷ = y/|y|` the unit corrected
//! field, `R = exp([φ]×)` the rotation from the corrected magnetometer
//! axes to the accelerometer's and `I` the inclination (down positive):
//! the angle between gravity and the field does not change as the unit
//! turns (Kok & Schön, "Maximum likelihood calibration of a magnetometer
//! using inertial sensors", IFAC 2014; Vasconcelos et al., "Geometric
//! approach to strapdown magnetometer calibration in sensor frame", IEEE
//! TAES 2011). Both blocks are fitted together.
//!
//! # Uncertainty
//! Each block of residuals is weighted by `1/(s_b² κ_b)`: `s_b²` its
//! residual variance and `κ_b = 1 + 2 Σ ρ_k` the variance inflation of
//! its mean from the residuals' autocorrelation in time order (Geyer's
//! initial positive sequence, Statistical Science 1992). The covariance
//! is the delete-one-block jackknife's ([`JACKKNIFE_LAGS`]): the session
//! cut into `B` runs of consecutive rows, each at least three times the
//! lag over which the residuals stay correlated, refitted without each,
//! with `B − 1` degrees of freedom (Künsch, Annals of Statistics 1989).
//! Noise correlated over a dwell (flicker, a slow drift, the field's own
//! wander), and the share of it the fit absorbs, are in u: the first-order
//! `(JᵀWJ)⁻¹` with `N/κ` samples covered the truth in 82–94 % of 400
//! seeds with Gauss–Markov noise, the jackknife in 93–97 %.

use nalgebra::{DMatrix, DVector, Matrix3, SymmetricEigen, Vector3};

use crate::error::{Error, Result};
use crate::estimation::gauss_newton::{
    gauss_newton, GaussNewtonOptions, NonlinearModel, StepControl,
};
use crate::estimation::linear::{Design, Diagnostics, FitOptions, Variance, DEFAULT_COND_LIMIT};
use crate::estimation::Fit;

/// A vector of three.
pub type V3 = Vector3<f64>;
/// A 3 × 3 matrix.
pub type M3 = Matrix3<f64>;

/// The unknowns of the ellipsoid: three hard-iron offsets and six
/// soft-iron elements.
pub const UNKNOWNS: usize = 9;
/// The hard-iron offsets (raw units).
pub const HARD: [&str; 3] = ["hard_iron_x", "hard_iron_y", "hard_iron_z"];
/// The soft-iron elements, in the order of [`PAIRS`].
pub const SOFT: [&str; 6] = [
    "soft_iron_xx",
    "soft_iron_yy",
    "soft_iron_zz",
    "soft_iron_xy",
    "soft_iron_xz",
    "soft_iron_yz",
];
/// The row and column of each soft-iron element.
pub const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
/// The alignment's rotation vector (rad inside the fit).
pub const ALIGN: [&str; 3] = ["alignment_x", "alignment_y", "alignment_z"];
/// The inclination (rad inside the fit).
pub const INCLINATION: &str = "inclination";

/// The symmetric matrix of six elements in [`PAIRS`] order.
pub fn sym(c: &[f64]) -> M3 {
    let mut m = M3::zeros();
    for (k, (i, j)) in PAIRS.iter().enumerate() {
        m[(*i, *j)] = c[k];
        m[(*j, *i)] = c[k];
    }
    m
}

/// The ellipsoid's parameters `[h; c_xx … c_yz]` of `h` and `C`.
pub fn pack(h: &V3, c: &M3) -> DVector<f64> {
    let mut x = DVector::zeros(UNKNOWNS);
    x.as_mut_slice()[..3].copy_from_slice(h.as_slice());
    for (k, (i, j)) in PAIRS.iter().enumerate() {
        x[3 + k] = c[(*i, *j)];
    }
    x
}

/// `h` and `C` of the parameters (the first [`UNKNOWNS`] of `x`).
pub fn unpack(x: &DVector<f64>) -> (V3, M3) {
    (V3::new(x[0], x[1], x[2]), sym(&x.as_slice()[3..UNKNOWNS]))
}

/// `[v]×`, the cross-product matrix.
pub fn skew(v: &V3) -> M3 {
    M3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// `exp([φ]×)` (Rodrigues).
pub fn rotation(phi: &V3) -> M3 {
    let t = phi.norm();
    let k = skew(phi);
    if t < 1e-8 {
        return M3::identity() + k + 0.5 * k * k;
    }
    M3::identity() + (t.sin() / t) * k + ((1.0 - t.cos()) / (t * t)) * k * k
}

/// The left Jacobian of SO(3): `exp([φ + δ]×) ≈ exp([J_l δ]×) exp([φ]×)`.
fn left_jacobian(phi: &V3) -> M3 {
    let t = phi.norm();
    let k = skew(phi);
    if t < 1e-6 {
        return M3::identity() + 0.5 * k + k * k / 6.0;
    }
    M3::identity() + ((1.0 - t.cos()) / (t * t)) * k + ((t - t.sin()) / (t * t * t)) * k * k
}

/// The symmetric positive-definite square root of a symmetric matrix, if
/// it is positive definite.
pub fn sqrt_pd(m: &M3) -> Option<M3> {
    let e = SymmetricEigen::new(*m);
    if e.eigenvalues
        .iter()
        .any(|v| v.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) || !v.is_finite())
    {
        return None;
    }
    let d = M3::from_diagonal(&e.eigenvalues.map(f64::sqrt));
    Some(e.eigenvectors * d * e.eigenvectors.transpose())
}

/// The algebraic start: the quadric `xᵀQx + 2gᵀx = 1` by linear least
/// squares on centred, scaled data, turned into `h` and `C` (the map
/// onto the unit sphere). A sphere about the mean when the quadric is
/// not an ellipsoid (a session that does not cover enough directions).
pub fn algebraic(mag: &[V3]) -> (V3, M3) {
    let n = mag.len() as f64;
    let mu = mag.iter().fold(V3::zeros(), |a, m| a + m) / n;
    let s = (mag.iter().map(|m| (m - mu).norm_squared()).sum::<f64>() / n)
        .sqrt()
        .max(f64::MIN_POSITIVE);
    let sphere = (mu, M3::identity() / s);
    let mut ata = DMatrix::<f64>::zeros(9, 9);
    let mut atb = DVector::<f64>::zeros(9);
    for m in mag {
        let p = (m - mu) / s;
        let row = [
            p.x * p.x,
            p.y * p.y,
            p.z * p.z,
            2.0 * p.x * p.y,
            2.0 * p.x * p.z,
            2.0 * p.y * p.z,
            2.0 * p.x,
            2.0 * p.y,
            2.0 * p.z,
        ];
        for i in 0..9 {
            atb[i] += row[i];
            for j in 0..9 {
                ata[(i, j)] += row[i] * row[j];
            }
        }
    }
    let Some(v) = ata.cholesky().map(|c| c.solve(&atb)) else {
        return sphere;
    };
    let q = sym(&[v[0], v[1], v[2], v[3], v[4], v[5]]);
    let g = V3::new(v[6], v[7], v[8]);
    let Some(qi) = q.try_inverse() else {
        return sphere;
    };
    let c = -(qi * g);
    let k = 1.0 + (c.transpose() * q * c)[0];
    match sqrt_pd(&(q / k)) {
        Some(cp) if k > 0.0 => (mu + s * c, cp / s),
        _ => sphere,
    }
}

/// How the session's directions fill the sphere: `spread = √(3 λ_min)`
/// of the covariance of the unit corrected directions (1 for directions
/// spread evenly over the sphere, 0 for a session turned about one axis)
/// and that eigenvector (the axis the session was turned about, or the
/// direction it never saw).
pub fn coverage(mag: &[V3], h: &V3, c: &M3) -> (f64, V3) {
    let n = mag.len() as f64;
    let u: Vec<V3> = mag
        .iter()
        .map(|m| (c * (m - h)).try_normalize(0.0).unwrap_or_else(V3::zeros))
        .collect();
    let mean = u.iter().fold(V3::zeros(), |a, v| a + v) / n;
    let cov =
        u.iter().fold(M3::zeros(), |a, v| a + v * v.transpose()) / n - mean * mean.transpose();
    let e = SymmetricEigen::new(cov);
    let k = e.eigenvalues.imin();
    let axis = e.eigenvectors.column(k).into_owned();
    (
        (3.0 * e.eigenvalues[k].max(0.0)).sqrt().min(1.0),
        axis.try_normalize(0.0).unwrap_or_else(V3::z),
    )
}

/// Distinct orientations: greedy clusters of the unit corrected
/// directions more than `deg` apart, counted up to `cap`.
pub fn orientations(mag: &[V3], h: &V3, c: &M3, deg: f64, cap: usize) -> usize {
    let cos = deg.to_radians().cos();
    let mut seen: Vec<V3> = Vec::new();
    for m in mag {
        let Some(u) = (c * (m - h)).try_normalize(0.0) else {
            continue;
        };
        if seen.iter().all(|s| s.dot(&u) < cos) {
            seen.push(u);
            if seen.len() >= cap {
                break;
            }
        }
    }
    seen.len()
}

/// The rows at rest paired with their unit specific force (rows into the
/// magnitude block's rows).
pub type AtRest = [(usize, V3)];

/// The fit's model (module docs): the magnitude of every row of `mag`,
/// then the dot residual of every row of `rest` when `rest` is not empty.
pub struct Model<'a> {
    /// The raw readings.
    pub mag: &'a [V3],
    /// The rows at rest and their unit specific force.
    pub rest: &'a AtRest,
}

impl Model<'_> {
    fn aligned(&self) -> bool {
        !self.rest.is_empty()
    }
}

/// The fit's parameter names: [`HARD`], [`SOFT`], then [`ALIGN`] and
/// [`INCLINATION`] when aligned.
pub fn names(aligned: bool) -> Vec<String> {
    let mut v: Vec<String> = HARD
        .iter()
        .chain(SOFT.iter())
        .map(|s| s.to_string())
        .collect();
    if aligned {
        v.extend(ALIGN.iter().map(|s| s.to_string()));
        v.push(INCLINATION.into());
    }
    v
}

impl NonlinearModel for Model<'_> {
    fn names(&self) -> Vec<String> {
        names(self.aligned())
    }

    fn predict(&self, x: &DVector<f64>) -> DVector<f64> {
        let (h, c) = unpack(x);
        let n = self.mag.len();
        let mut out = DVector::zeros(n + self.rest.len());
        for (k, m) in self.mag.iter().enumerate() {
            out[k] = (c * (m - h)).norm();
        }
        if self.aligned() {
            let r = rotation(&V3::new(x[9], x[10], x[11]));
            let s = x[12].sin();
            for (k, (row, f)) in self.rest.iter().enumerate() {
                let y = c * (self.mag[*row] - h);
                out[n + k] = f.dot(&(r * y)) / y.norm() + s;
            }
        }
        out
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let (h, c) = unpack(x);
        let n = self.mag.len();
        let p = x.len();
        let mut j = DMatrix::zeros(n + self.rest.len(), p);
        // d(C d)/d h = −C; d(C d)/d c_ab: e_a d_b + e_b d_a (a ≠ b).
        let fill = |j: &mut DMatrix<f64>, row: usize, d: &V3, gy: &V3| {
            let gh = -(c * gy);
            for a in 0..3 {
                j[(row, a)] = gh[a];
            }
            for (k, (a, b)) in PAIRS.iter().enumerate() {
                j[(row, 3 + k)] = if a == b {
                    gy[*a] * d[*a]
                } else {
                    gy[*a] * d[*b] + gy[*b] * d[*a]
                };
            }
        };
        for (k, m) in self.mag.iter().enumerate() {
            let d = m - h;
            let y = c * d;
            let ny = y.norm();
            fill(&mut j, k, &d, &(y / ny));
        }
        if self.aligned() {
            let phi = V3::new(x[9], x[10], x[11]);
            let r = rotation(&phi);
            let jl = left_jacobian(&phi);
            for (k, (row, f)) in self.rest.iter().enumerate() {
                let d = self.mag[*row] - h;
                let y = c * d;
                let ny = y.norm();
                let yh = y / ny;
                let rtf = r.transpose() * f;
                // d(f̂ᵀ R ŷ)/dy = (I − ŷŷᵀ) Rᵀ f̂ / |y|.
                let gy = (rtf - yh * yh.dot(&rtf)) / ny;
                fill(&mut j, n + k, &d, &gy);
                let v = r * yh;
                let g = jl.transpose() * v.cross(f);
                for a in 0..3 {
                    j[(n + k, 9 + a)] = g[a];
                }
                j[(n + k, 12)] = x[12].cos();
            }
        }
        j
    }
}

/// The variance inflation of the mean of `r` from its autocorrelation
/// (Geyer's initial positive sequence: pairs of lags summed while
/// positive and not rising): `κ = 1 + 2 Σ ρ_k` (at least 1) and the lag
/// where the sum stopped, `L`.
pub fn inflation(r: &[f64]) -> (f64, usize) {
    let n = r.len();
    if n < 4 {
        return (1.0, 1);
    }
    let mean = r.iter().sum::<f64>() / n as f64;
    let c: Vec<f64> = r.iter().map(|v| v - mean).collect();
    let acf = crate::noise::corr::autocorr(&c, n / 2);
    if acf[0].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return (1.0, 1);
    }
    let rho = |k: usize| acf.get(k).copied().unwrap_or(0.0) / acf[0];
    let mut sum = 0.0;
    let mut last = f64::INFINITY;
    let mut m = 0;
    while 2 * m + 1 < acf.len() {
        let g = (rho(2 * m) + rho(2 * m + 1)).min(last);
        if g <= 0.0 {
            break;
        }
        sum += g;
        last = g;
        m += 1;
    }
    ((2.0 * sum - 1.0).max(1.0), (2 * m).max(1))
}

/// A solved session: the fit (its covariance from the weighted
/// residuals, module docs) and what weighted it.
#[derive(Debug, Clone)]
pub struct Solved {
    /// The last Gauss–Newton fit.
    pub fit: Fit,
    /// The magnitude target `ρ = 1 + s²`.
    pub target: f64,
    /// Residual standard deviation and inflation of the magnitude block
    /// (unit-sphere units).
    pub magnitude: (f64, f64),
    /// Residual standard deviation and inflation of the dot block, when
    /// aligned.
    pub dot: Option<(f64, f64)>,
    /// Degrees of freedom of the covariance (blocks − 1).
    pub dof: f64,
    /// Jackknife blocks.
    pub blocks: usize,
}

fn gn_options(weights: Option<DVector<f64>>, variance: Variance) -> GaussNewtonOptions {
    GaussNewtonOptions {
        fit: FitOptions {
            weights,
            variance,
            cond_limit: DEFAULT_COND_LIMIT,
        },
        max_iter: 200,
        tol: 1e-6,
        rel_tol: Some(1e-14),
        step: StepControl::Halving {
            halvings: 40,
            polish: 1e-3,
            polish_steps: 8,
        },
    }
}

fn observations(n: usize, na: usize, target: f64) -> DVector<f64> {
    DVector::from_iterator(
        n + na,
        (0..n + na).map(|k| if k < n { target } else { 0.0 }),
    )
}

fn mean_square(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64
}

/// The design's rank and conditioning at `x` (magnitude block only).
pub fn diagnose(mag: &[V3], x: &DVector<f64>) -> Result<Diagnostics> {
    let model = Model { mag, rest: &[] };
    let design = Design::new(model.names(), model.jacobian(x))?;
    Ok(design.diagnose(None, DEFAULT_COND_LIMIT))
}

/// Fit the session (module docs) from the start `h0`, `c0`; the
/// alignment too when `rest` has rows.
pub fn solve(mag: &[V3], rest: &AtRest, h0: &V3, c0: &M3) -> Result<Solved> {
    let n = mag.len();
    let x = pack(h0, c0);
    let ellipsoid = Model { mag, rest: &[] };
    let ones = DVector::from_element(n, 1.0);
    // Unit target, then the noise's bias removed (module docs).
    let (x1, r1) = converge(&ellipsoid, &ones, 1.0, x)?;
    let target = 1.0 + mean_square(r1.as_slice());
    let (x2, r2) = converge(&ellipsoid, &ones, target, x1)?;
    let s2m = mean_square(r2.as_slice()).max(f64::MIN_POSITIVE);
    if rest.is_empty() {
        let k = inflation(r2.as_slice()).0;
        return finish(&ellipsoid, x2, target, s2m, k, None);
    }
    // The alignment's start: no rotation, the mean inclination.
    let (h, c) = unpack(&x2);
    let dots: Vec<f64> = rest
        .iter()
        .map(|(row, f)| f.dot(&(c * (mag[*row] - h)).normalize()))
        .collect();
    let mean_dot = dots.iter().sum::<f64>() / dots.len() as f64;
    let s2d0 = dots.iter().map(|d| (d - mean_dot).powi(2)).sum::<f64>() / dots.len() as f64;
    let mut x = DVector::zeros(UNKNOWNS + 4);
    x.as_mut_slice()[..UNKNOWNS].copy_from_slice(x2.as_slice());
    x[12] = (-mean_dot).clamp(-1.0, 1.0).asin();
    let joint = Model { mag, rest };
    let weights = |s2m: f64, s2d: f64| {
        DVector::from_iterator(
            n + rest.len(),
            (0..n + rest.len()).map(|k| if k < n { 1.0 / s2m } else { 1.0 / s2d }),
        )
    };
    let (x3, r3) = converge(
        &joint,
        &weights(s2m, s2d0.max(f64::MIN_POSITIVE)),
        target,
        x,
    )?;
    let s2d = mean_square(&r3.as_slice()[n..]).max(f64::MIN_POSITIVE);
    let s2m = mean_square(&r3.as_slice()[..n]).max(f64::MIN_POSITIVE);
    let (x4, r4) = converge(&joint, &weights(s2m, s2d), target, x3)?;
    let km = inflation(&r4.as_slice()[..n]).0;
    let kd = inflation(&r4.as_slice()[n..]).0;
    let s2d = mean_square(&r4.as_slice()[n..]).max(f64::MIN_POSITIVE);
    let s2m = mean_square(&r4.as_slice()[..n]).max(f64::MIN_POSITIVE);
    finish(&joint, x4, target, s2m, km, Some((s2d, kd, rest.len())))
}

/// The residuals `y − h(x)` of the model (the magnitude target, then 0
/// for the angles).
fn residuals(model: &Model<'_>, target: f64, x: &DVector<f64>) -> DVector<f64> {
    let n = model.mag.len();
    let mut r = model.predict(x);
    for (k, v) in r.iter_mut().enumerate() {
        *v = if k < n { target - *v } else { -*v };
    }
    r
}

/// Damped Gauss–Newton on the normal equations (step halving, as the
/// estimation core's [`StepControl::Halving`]) until every step is below
/// 1e-6 of its parameter's standard uncertainty: the minimum and its
/// residuals. The
/// covariance is not taken from here (module docs).
fn converge(
    model: &Model<'_>,
    w: &DVector<f64>,
    target: f64,
    mut x: DVector<f64>,
) -> Result<(DVector<f64>, DVector<f64>)> {
    let cost = |r: &DVector<f64>| r.iter().zip(w.iter()).map(|(a, b)| a * a * b).sum::<f64>();
    let mut r = residuals(model, target, &x);
    let mut c = cost(&r);
    if !c.is_finite() {
        return Err(Error::Unsupported(
            "the starting point gives a non-finite residual".into(),
        ));
    }
    for _ in 0..MAX_ITERATIONS {
        let (a, g) = normal_equations(&model.jacobian(&x), w, &r);
        let Some(ch) = a.cholesky() else {
            return Err(Error::Unsupported(
                "the normal equations are singular: the orientations do not determine every term"
                    .into(),
            ));
        };
        let step = ch.solve(&g);
        // Every step within 1e-6 of its parameter's standard uncertainty
        // (as the core's Gauss–Newton stops), or the cost no longer falls.
        let s2 = c / (r.len().saturating_sub(x.len())).max(1) as f64;
        let inv = ch.inverse();
        let small = (0..x.len()).all(|k| step[k].abs() <= 1e-6 * (s2 * inv[(k, k)]).sqrt());
        let before = c;
        let mut alpha = 1.0;
        let mut moved = false;
        for _ in 0..40 {
            let xn = &x + &step * alpha;
            let rn = residuals(model, target, &xn);
            let cn = cost(&rn);
            if cn.is_finite() && cn <= c {
                (x, r, c) = (xn, rn, cn);
                moved = true;
                break;
            }
            alpha *= 0.5;
        }
        let flat = before - c <= 1e-15 * before;
        if small || !moved || flat {
            return Ok((x, r));
        }
    }
    Err(Error::Unsupported(format!(
        "Gauss–Newton did not converge in {MAX_ITERATIONS} iterations"
    )))
}

/// `JᵀWJ` and `JᵀWr`, row by row.
fn normal_equations(
    j: &DMatrix<f64>,
    w: &DVector<f64>,
    r: &DVector<f64>,
) -> (DMatrix<f64>, DVector<f64>) {
    let p = j.ncols();
    let mut a = DMatrix::zeros(p, p);
    let mut g = DVector::zeros(p);
    for i in 0..j.nrows() {
        add_row(&mut a, &mut g, j, i, w[i], r[i]);
    }
    a.fill_lower_triangle_with_upper_triangle();
    (a, g)
}

/// Add row `i` of `J` with weight `w` and residual `r` to `JᵀWJ` (its
/// upper triangle) and `JᵀWr`.
fn add_row(a: &mut DMatrix<f64>, g: &mut DVector<f64>, j: &DMatrix<f64>, i: usize, w: f64, r: f64) {
    for k in 0..j.ncols() {
        let wk = w * j[(i, k)];
        g[k] += wk * r;
        for l in k..j.ncols() {
            a[(k, l)] += wk * j[(i, l)];
        }
    }
}

/// Gauss–Newton iterations of a fit at most.
pub const MAX_ITERATIONS: usize = 200;

/// A jackknife block is at least this many times the lag where the
/// residuals' autocorrelation sum stopped ([`inflation`]): measured over
/// 400 seeds, blocks of 1 and 1.5 lags left Gauss–Markov noise partly
/// out of u (coverage down to 86 and 89 %), 3 lags holds 93–97 %.
pub const JACKKNIFE_LAGS: f64 = 3.0;
/// At least this many blocks (the covariance's degrees of freedom are
/// blocks − 1).
pub const JACKKNIFE_MIN: usize = 12;
/// At most this many blocks.
pub const JACKKNIFE_MAX: usize = 120;

/// The fit at `x`, weighted by each block's variance and inflation, and
/// its covariance by the delete-one-block jackknife (module docs).
fn finish(
    model: &Model<'_>,
    x: DVector<f64>,
    target: f64,
    s2m: f64,
    km: f64,
    dot: Option<(f64, f64, usize)>,
) -> Result<Solved> {
    let n = model.mag.len();
    let na = dot.map_or(0, |d| d.2);
    let lr_d = dot.map_or(1.0, |(s2d, kd, _)| s2d * kd);
    let w = DVector::from_iterator(
        n + na,
        (0..n + na).map(|k| if k < n { 1.0 / (s2m * km) } else { 1.0 / lr_d }),
    );
    let (x, _) = converge(model, &w, target, x)?;
    // The core's fit at the minimum: its residuals, conditioning and
    // lack-of-fit summary (one linearisation).
    let (fit, _) = gauss_newton(
        model,
        &observations(n, na, target),
        x,
        &gn_options(Some(w.clone()), Variance::FromResiduals),
    )?;
    let lag = inflation(&fit.residuals.as_slice()[..n]).1;
    let blocks = ((n as f64 / (JACKKNIFE_LAGS * lag as f64)).floor() as usize)
        .clamp(JACKKNIFE_MIN, JACKKNIFE_MAX)
        .min(n / 2);
    let cov = jackknife(model, &fit, &w, target, blocks)?;
    let dof = (blocks - 1) as f64;
    let estimates = crate::estimation::Estimates::new(
        fit.estimates.names().to_vec(),
        fit.estimates.values().clone(),
        cov,
        dof,
    )?;
    Ok(Solved {
        fit: Fit { estimates, ..fit },
        target,
        magnitude: (s2m.sqrt(), km),
        dot: dot.map(|(s2d, kd, _)| (s2d.sqrt(), kd)),
        dof,
        blocks,
    })
}

/// The delete-one-block jackknife covariance (Künsch, "The jackknife and
/// the bootstrap for general stationary observations", Annals of
/// Statistics, 1989): the session cut into `blocks` runs of consecutive
/// rows; each refit without one run (its rows at rest too) is one
/// Gauss–Newton step from the whole solution `θ̂`, `θ₋b = θ̂ − (A −
/// A_b)⁻¹ g_b` with `A = Σ w jjᵀ` and `A_b`, `g_b = Σ_b w j r` the run's
/// share (the whole gradient is 0 at `θ̂`); `C = (B − 1)/B Σ (θ₋b −
/// θ̄)(θ₋b − θ̄)ᵀ`. Noise correlated within a run, and the share of it
/// the fit absorbs, are in `C`.
fn jackknife(
    model: &Model<'_>,
    fit: &Fit,
    w: &DVector<f64>,
    target: f64,
    blocks: usize,
) -> Result<DMatrix<f64>> {
    let n = model.mag.len();
    let x = fit.estimates.values();
    let p = x.len();
    let j = model.jacobian(x);
    let r = residuals(model, target, x);
    let block = |i: usize| {
        let row = if i < n { i } else { model.rest[i - n].0 };
        (row * blocks / n).min(blocks - 1)
    };
    let mut a = vec![DMatrix::<f64>::zeros(p, p); blocks];
    let mut g = vec![DVector::<f64>::zeros(p); blocks];
    for i in 0..j.nrows() {
        let b = block(i);
        add_row(&mut a[b], &mut g[b], &j, i, w[i], r[i]);
    }
    for m in &mut a {
        m.fill_lower_triangle_with_upper_triangle();
    }
    let total = a.iter().fold(DMatrix::zeros(p, p), |s, m| s + m);
    let mut thetas: Vec<DVector<f64>> = Vec::with_capacity(blocks);
    for b in 0..blocks {
        let step = (&total - &a[b]).cholesky().map(|c| c.solve(&g[b])).ok_or_else(|| {
            Error::Unsupported(format!(
                "the jackknife without rows {}..{} is singular: the session depends on those rows alone",
                b * n / blocks + 1,
                (b + 1) * n / blocks
            ))
        })?;
        thetas.push(x - step);
    }
    let mean = thetas.iter().fold(DVector::zeros(p), |s, t| s + t) / blocks as f64;
    let mut cov = DMatrix::zeros(p, p);
    for t in &thetas {
        let d = t - &mean;
        cov += &d * d.transpose();
    }
    Ok(cov * ((blocks - 1) as f64 / blocks as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimation::numeric_jacobian;

    #[test]
    fn the_jacobian_is_the_derivative_of_the_prediction() {
        let mag = [
            V3::new(30.0, 5.0, -20.0),
            V3::new(-10.0, 40.0, 3.0),
            V3::new(2.0, -35.0, 25.0),
        ];
        let rest = [(0, V3::new(0.0, 0.6, 0.8)), (2, V3::new(1.0, 0.0, 0.0))];
        let model = Model {
            mag: &mag,
            rest: &rest,
        };
        let x = DVector::from_vec(vec![
            1.0, -2.0, 3.0, 0.021, 0.019, 0.02, 0.001, -0.002, 0.0005, 0.05, -0.1, 0.2, 1.0,
        ]);
        let steps = vec![1e-6; x.len()];
        let num = numeric_jacobian(&|z: &DVector<f64>| model.predict(z), &x, &steps);
        let ana = model.jacobian(&x);
        assert!((num - ana).amax() < 1e-6);
    }

    #[test]
    fn inflation_is_one_for_white_noise_and_large_for_a_random_walk() {
        let mut r = crate::sim::rng(3);
        let w: Vec<f64> = (0..20000)
            .map(|_| crate::sim::normal(&mut r, 1.0))
            .collect();
        let k = inflation(&w).0;
        assert!((0.9..1.2).contains(&k), "{k}");
        let mut g = 0.0;
        let ar: Vec<f64> = (0..20000)
            .map(|_| {
                g = 0.9 * g + crate::sim::normal(&mut r, 1.0);
                g
            })
            .collect();
        // AR(1) with φ = 0.9: κ = (1 + φ)/(1 − φ) = 19.
        let k = inflation(&ar).0;
        assert!((14.0..25.0).contains(&k), "{k}");
    }
}
