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

/// Flicker (1/f) noise of `n` samples by Kasdin & Walter: white noise of
/// standard deviation `sigma` convolved with the α = 1 power-law filter
/// (linear convolution through zero-padded real FFTs, `realfft`).
pub fn flicker(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    use realfft::num_complex::Complex64;
    use realfft::RealFftPlanner;
    if n == 0 || sigma <= 0.0 {
        return vec![0.0; n];
    }
    let len = (2 * n).next_power_of_two();
    // The forward plan (its twiddles are gigabytes at 10⁸ samples) is
    // dropped before the inverse is planned.
    let fwd = RealFftPlanner::<f64>::new().plan_fft_forward(len);
    // One real buffer and one scratch serve every transform (at 10⁸
    // samples each buffer is 2 GB): the filter's spectrum first, then the
    // same buffer holds the noise.
    let mut scratch = vec![Complex64::new(0.0, 0.0); fwd.get_scratch_len()];
    let mut w = vec![0.0; len];
    w[0] = 1.0;
    for k in 1..n {
        w[k] = w[k - 1] * (k as f64 - 0.5) / k as f64;
    }
    let mut hs = fwd.make_output_vec();
    fwd.process_with_scratch(&mut w, &mut hs, &mut scratch)
        .expect("sizes from the plan");
    let mut r = rng(seed);
    w.fill(0.0);
    for v in w.iter_mut().take(n) {
        *v = normal(&mut r, sigma);
    }
    let mut ws = fwd.make_output_vec();
    fwd.process_with_scratch(&mut w, &mut ws, &mut scratch)
        .expect("sizes from the plan");
    let scale = 1.0 / len as f64;
    for (a, b) in ws.iter_mut().zip(&hs) {
        *a *= b * scale;
    }
    drop((hs, fwd));
    let inv = RealFftPlanner::<f64>::new().plan_fft_inverse(len);
    scratch.resize(inv.get_scratch_len(), Complex64::new(0.0, 0.0));
    // Real signals: the spectrum is real at 0 and len/2 but for round-off.
    ws[0].im = 0.0;
    if let Some(last) = ws.last_mut() {
        last.im = 0.0;
    }
    inv.process_with_scratch(&mut ws, &mut w, &mut scratch)
        .expect("real spectrum");
    drop((ws, scratch));
    w.truncate(n);
    w.shrink_to_fit();
    w
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
