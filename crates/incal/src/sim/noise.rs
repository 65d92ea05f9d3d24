//! Seeded rate-noise records with the IEEE Std 952 terms as truth.
//!
//! Rate samples `y_k` at spacing τ0 (rate unit u) as the sum of
//! * quantization Q (u·s): the first difference of a white phase error of
//!   standard deviation Q (uniform, like a quantizer) over τ0 —
//!   `σ² = 3Q²/τ²`;
//! * angle random walk N (u·√s): white rate of standard deviation N/√τ0 —
//!   `σ² = N²/τ`;
//! * bias instability B (u): flicker rate by Kasdin & Walter's power-law
//!   generator (N. J. Kasdin and T. Walter, "Discrete simulation of power
//!   law noise", 1992 IEEE FCS, eq. 7 ff.): white noise of standard
//!   deviation B filtered by `h_0 = 1`, `h_k = h_{k−1}(k − ½)/k`, so the
//!   one-sided PSD is `B²/(πf)` at low f and `σ² = (2 ln 2/π) B²`;
//! * rate random walk K (u/√s): `y_k = y_{k−1} + K√τ0 w_k` — `σ² ≈ K²τ/3`;
//! * rate ramp R (u/s): `R·t` — `σ² = R²τ²/2`.
//!
//! Each term draws from its own ChaCha8 stream, seeded from the channel's
//! seed, so adding a term does not change the others.

use rand::RngExt;

use super::{normal, rng, trial_seed};

/// IEEE terms of one simulated channel (rate unit base: Q in u·s, N in
/// u·√s, B in u, K in u/√s, R in u/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NoiseTruth {
    /// Quantization Q.
    pub q: f64,
    /// Angle (velocity) random walk N.
    pub n: f64,
    /// Bias instability B.
    pub b: f64,
    /// Rate random walk K.
    pub k: f64,
    /// Rate ramp R.
    pub r: f64,
}

/// In-place radix-2 FFT of `(re, im)` (length a power of two); `inverse`
/// without the 1/n scale.
fn fft(re: &mut [f64], im: &mut [f64], inverse: bool) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let sign = if inverse { 1.0 } else { -1.0 };
    // The twiddles e^{±2πik/n}, k < n/2, computed once: a sin_cos per
    // butterfly took minutes at 10⁸ samples. Stage `len` uses every
    // (n/len)-th one.
    let base = sign * 2.0 * std::f64::consts::PI / n as f64;
    let tw: Vec<(f64, f64)> = (0..n / 2).map(|k| (base * k as f64).sin_cos()).collect();
    let mut len = 2;
    while len <= n {
        let half = len / 2;
        let stride = n / len;
        for start in (0..n).step_by(len) {
            for k in 0..half {
                let (s, c) = tw[k * stride];
                let (a, b) = (start + k, start + k + half);
                let tr = re[b] * c - im[b] * s;
                let ti = re[b] * s + im[b] * c;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
}

/// Flicker (1/f) noise of `n` samples by Kasdin & Walter: white noise of
/// standard deviation `sigma` convolved with the α = 1 power-law filter
/// (linear convolution through zero-padded FFTs).
pub fn flicker(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    if n == 0 || sigma <= 0.0 {
        return vec![0.0; n];
    }
    let len = (2 * n).next_power_of_two();
    let mut r = rng(seed);
    let mut hr = vec![0.0; len];
    let mut hi = vec![0.0; len];
    let mut wr = vec![0.0; len];
    let mut wi = vec![0.0; len];
    hr[0] = 1.0;
    for k in 1..n {
        hr[k] = hr[k - 1] * (k as f64 - 0.5) / k as f64;
    }
    for w in wr.iter_mut().take(n) {
        *w = normal(&mut r, sigma);
    }
    fft(&mut hr, &mut hi, false);
    fft(&mut wr, &mut wi, false);
    for k in 0..len {
        let (a, b) = (hr[k] * wr[k] - hi[k] * wi[k], hr[k] * wi[k] + hi[k] * wr[k]);
        wr[k] = a;
        wi[k] = b;
    }
    fft(&mut wr, &mut wi, true);
    wr.truncate(n);
    for v in &mut wr {
        *v /= len as f64;
    }
    wr
}

/// `n` rate samples at spacing `tau0_s` with the terms of `truth` (module
/// docs), seeded with `seed`.
pub fn rate_record(truth: &NoiseTruth, tau0_s: f64, n: usize, seed: u64) -> Vec<f64> {
    let mut y = if truth.b > 0.0 {
        flicker(n, truth.b, trial_seed(seed, 2))
    } else {
        vec![0.0; n]
    };
    if truth.n > 0.0 {
        let mut r = rng(trial_seed(seed, 1));
        let s = truth.n / tau0_s.sqrt();
        for v in y.iter_mut() {
            *v += normal(&mut r, s);
        }
    }
    if truth.q > 0.0 {
        let mut r = rng(trial_seed(seed, 0));
        let half = truth.q * 3f64.sqrt();
        let mut prev = r.random_range(-half..half);
        for v in y.iter_mut() {
            let e = r.random_range(-half..half);
            *v += (e - prev) / tau0_s;
            prev = e;
        }
    }
    if truth.k > 0.0 {
        let mut r = rng(trial_seed(seed, 3));
        let s = truth.k * tau0_s.sqrt();
        let mut walk = 0.0;
        for v in y.iter_mut() {
            walk += normal(&mut r, s);
            *v += walk;
        }
    }
    if truth.r != 0.0 {
        for (i, v) in y.iter_mut().enumerate() {
            *v += truth.r * i as f64 * tau0_s;
        }
    }
    y
}
