//! Power-law noise identification by the lag-1 autocorrelation
//! (W. J. Riley and C. A. Greenhall, "Power law noise identification using
//! the lag 1 autocorrelation", 18th EFTF, 2004): the phase data decimated
//! by m, the quadratic trend removed, differenced d times until
//! `δ = r1/(1 + r1) < 0.25` (or d = dmax); then `α = 2 − 2d − round(2δ)`
//! (S_y ∝ f^α: 2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2
//! random-walk FM).

use nalgebra::{Matrix3, Vector3};

/// Fewest decimated points the method is used on (Riley & Greenhall §3).
pub const MIN_POINTS: usize = 30;

/// Noise exponents identified at one averaging factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NoiseId {
    /// α with at most two differences (Allan family).
    pub alpha_allan: i32,
    /// α with at most three differences (Hadamard).
    pub alpha_hadamard: i32,
}

/// Running sums of one differenced series for its lag-1 autocorrelation.
#[derive(Clone, Copy, Default)]
struct Acf {
    n: f64,
    sum: f64,
    sum2: f64,
    lag: f64,
    first: f64,
    last: f64,
    prev: Option<f64>,
}

impl Acf {
    fn push(&mut self, z: f64) {
        match self.prev {
            None => self.first = z,
            Some(p) => self.lag += p * z,
        }
        self.n += 1.0;
        self.sum += z;
        self.sum2 += z * z;
        self.last = z;
        self.prev = Some(z);
    }
    /// `Σ (z_i − μ)(z_{i+1} − μ) / Σ (z_i − μ)²` (Riley & Greenhall eq. 2)
    /// from the sums.
    fn r1(&self) -> f64 {
        let mu = self.sum / self.n;
        let num = self.lag - mu * (self.sum - self.last) - mu * (self.sum - self.first)
            + (self.n - 1.0) * mu * mu;
        let den = self.sum2 - self.n * mu * mu;
        if den > 0.0 {
            num / den
        } else {
            0.0
        }
    }
}

/// The sums of [`Acf`] over a run of a series that continues one whose
/// last value is known (no first-value bookkeeping per sample).
#[derive(Clone, Copy, Default)]
struct Run {
    n: f64,
    sum: f64,
    sum2: f64,
    lag: f64,
    last: Option<f64>,
    first: f64,
}

impl Run {
    #[inline(always)]
    fn push(&mut self, z: f64) {
        if let Some(p) = self.last {
            self.lag += p * z;
        } else {
            self.first = z;
        }
        self.n += 1.0;
        self.sum += z;
        self.sum2 += z * z;
        self.last = Some(z);
    }
}

impl Acf {
    /// Append a run that follows this series.
    fn merge(&mut self, r: Run) {
        let Some(last) = r.last else { return };
        match self.prev {
            None => self.first = r.first,
            Some(p) => self.lag += p * r.first,
        }
        self.n += r.n;
        self.sum += r.sum;
        self.sum2 += r.sum2;
        self.lag += r.lag;
        self.last = last;
        self.prev = Some(last);
    }
}

/// Identify the noise at averaging factor `m` of phase data `x`; `None`
/// when the decimated record has fewer than [`MIN_POINTS`] points.
///
/// Two passes over the decimated samples and no copy: the first fits the
/// quadratic, the second forms the residuals and their first three
/// differences on the fly with the sums of each series' lag-1
/// autocorrelation.
pub fn identify(x: &[f64], m: usize) -> Option<NoiseId> {
    let m = m.max(1);
    if x.is_empty() {
        return None;
    }
    let n = (x.len() - 1) / m + 1;
    if n < MIN_POINTS {
        return None;
    }
    // t scaled to [−1, 1] keeps the normal equations well conditioned.
    // On the symmetric grid t_i = (i − c)/c the odd power sums vanish and
    // the even ones have closed forms: Σt² = n(n²−1)/(12c²),
    // Σt⁴ = n(n²−1)(3n²−7)/(240c⁴).
    let c = (n as f64 - 1.0) / 2.0;
    let sc = 1.0 / c;
    let nf = n as f64;
    let s2 = nf * (nf * nf - 1.0) / 12.0 * sc * sc;
    let s4 = nf * (nf * nf - 1.0) * (3.0 * nf * nf - 7.0) / 240.0 * sc.powi(4);
    let a = Matrix3::new(nf, 0.0, s2, 0.0, s2, 0.0, s2, 0.0, s4);
    // Σ p_k(t) x: four lanes of the three sums (the loads stride by m).
    let mut b4 = [[0.0f64; 3]; 4];
    for i in 0..n {
        let t = (i as f64 - c) * sc;
        let v = x[i * m];
        let l = &mut b4[i % 4];
        l[0] += v;
        l[1] += t * v;
        l[2] += t * t * v;
    }
    let b = Vector3::from_fn(|k, _| (b4[0][k] + b4[1][k]) + (b4[2][k] + b4[3][k]));
    let coef = a
        .try_inverse()
        .map(|ai| ai * b)
        .unwrap_or_else(Vector3::zeros);
    let resid = |i: usize| {
        let t = (i as f64 - c) * sc;
        x[i * m] - (coef[0] + coef[1] * t + coef[2] * t * t)
    };
    let mut acf = [Acf::default(); 4];
    // The first three residuals start the differenced series; after them
    // every residual extends all four (no branch per sample).
    let mut hist = [0.0f64; 3];
    for i in 0..3 {
        let mut z = resid(i);
        acf[0].push(z);
        for d in 0..i {
            let p = std::mem::replace(&mut hist[d], z);
            z -= p;
            acf[d + 1].push(z);
        }
        hist[i] = z;
    }
    let mut run = [Run::default(); 4];
    for i in 3..n {
        let z0 = resid(i);
        let z1 = z0 - hist[0];
        let z2 = z1 - hist[1];
        let z3 = z2 - hist[2];
        hist = [z0, z1, z2];
        for (r, z) in run.iter_mut().zip([z0, z1, z2, z3]) {
            r.push(z);
        }
    }
    for (a, r) in acf.iter_mut().zip(run) {
        a.merge(r);
    }
    let mut allan = None;
    for (d, s) in acf.iter().enumerate() {
        let r1 = s.r1();
        let delta = r1 / (1.0 + r1);
        let alpha = 2 - 2 * d as i32 - (2.0 * delta).round_ties_even() as i32;
        if allan.is_none() && (delta < 0.25 || d >= 2) {
            allan = Some(alpha);
        }
        if delta < 0.25 || d >= 3 {
            return Some(NoiseId {
                alpha_allan: allan.unwrap_or(alpha),
                alpha_hadamard: alpha,
            });
        }
    }
    None
}
