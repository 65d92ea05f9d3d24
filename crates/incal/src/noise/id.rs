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

/// `x` minus its least-squares quadratic in the index.
fn detrend2(x: &[f64]) -> Vec<f64> {
    let n = x.len() as f64;
    // t scaled to [−1, 1] keeps the normal equations well conditioned.
    let c = (n - 1.0) / 2.0;
    let sc = if c > 0.0 { 1.0 / c } else { 1.0 };
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for (i, &v) in x.iter().enumerate() {
        let t = (i as f64 - c) * sc;
        let p = Vector3::new(1.0, t, t * t);
        a += p * p.transpose();
        b += p * v;
    }
    let coef = a
        .try_inverse()
        .map(|ai| ai * b)
        .unwrap_or_else(Vector3::zeros);
    x.iter()
        .enumerate()
        .map(|(i, &v)| {
            let t = (i as f64 - c) * sc;
            v - (coef[0] + coef[1] * t + coef[2] * t * t)
        })
        .collect()
}

/// Lag-1 autocorrelation about the mean (Riley & Greenhall eq. 2).
fn lag1(z: &[f64]) -> f64 {
    let mu = z.iter().sum::<f64>() / z.len() as f64;
    let mut num = 0.0;
    let mut den = 0.0;
    for w in z.windows(2) {
        num += (w[0] - mu) * (w[1] - mu);
    }
    for &v in z {
        den += (v - mu) * (v - mu);
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// Identify the noise at averaging factor `m` of phase data `x`; `None`
/// when the decimated record has fewer than [`MIN_POINTS`] points.
pub fn identify(x: &[f64], m: usize) -> Option<NoiseId> {
    let dec: Vec<f64> = x.iter().step_by(m.max(1)).copied().collect();
    if dec.len() < MIN_POINTS {
        return None;
    }
    let mut z = detrend2(&dec);
    let mut d = 0;
    let mut allan = None;
    loop {
        let r1 = lag1(&z);
        let delta = r1 / (1.0 + r1);
        let alpha = 2 - 2 * d - (2.0 * delta).round_ties_even() as i32;
        if allan.is_none() && (delta < 0.25 || d >= 2) {
            allan = Some(alpha);
        }
        if delta < 0.25 || d >= 3 {
            return Some(NoiseId {
                alpha_allan: allan.unwrap_or(alpha),
                alpha_hadamard: alpha,
            });
        }
        z = z.windows(2).map(|w| w[1] - w[0]).collect();
        d += 1;
    }
}
