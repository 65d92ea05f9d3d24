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
    let c = (n as f64 - 1.0) / 2.0;
    let sc = 1.0 / c;
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for i in 0..n {
        let t = (i as f64 - c) * sc;
        let p = Vector3::new(1.0, t, t * t);
        a += p * p.transpose();
        b += p * x[i * m];
    }
    let coef = a
        .try_inverse()
        .map(|ai| ai * b)
        .unwrap_or_else(Vector3::zeros);
    let mut acf = [Acf::default(); 4];
    // The last value of each differenced series.
    let mut hist: [Option<f64>; 3] = [None; 3];
    for i in 0..n {
        let t = (i as f64 - c) * sc;
        let mut z = x[i * m] - (coef[0] + coef[1] * t + coef[2] * t * t);
        acf[0].push(z);
        for d in 0..3 {
            let prev = hist[d].replace(z);
            match prev {
                Some(p) => {
                    z -= p;
                    acf[d + 1].push(z);
                }
                None => break,
            }
        }
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
