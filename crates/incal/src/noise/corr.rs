//! Lagged products of one record at every lag at once, by FFT: the full
//! autocorrelation `R(d) = Σ_t u_t u_{t+d}` and the partial ("wedge") sums
//! `G(d) = Σ_{t < c·d} u_t u_{t+d}` the deviations at dense τ grids need
//! for the ends of their ranges (see [`super::dev::oavar_many`]).
//!
//! A wedge sum is the sum along each diagonal `s − t = d` of the products
//! `u_t u_s` inside the half-plane `den·t < num·(s − t)`. The plane is cut
//! into aligned squares (a quadtree): a square wholly inside adds the
//! cross-correlation of its two segments to the lags it spans, by FFT; a
//! square on the boundary splits in four down to [`HMIN`], then is summed
//! product by product. The squares of one size whose lags start at the
//! same multiple of the size share one inverse transform (their spectra
//! add), and each segment is transformed once per size, so a wedge of
//! lags up to D costs O(D log² D) instead of the O(D²) of direct sums.
//! The same quadtree construction is used for the semi-relaxed products
//! of online convolution (van der Hoeven, "Relax, but don't be too lazy",
//! J. Symb. Comput. 34, 2002).
//!
//! Round-off: an FFT correlation carries an absolute error of a few
//! `ε·log₂(n)·Σu²` at every lag; the callers compare that with what they
//! need and fall back to direct sums where it is too large.

use std::collections::BTreeMap;

use realfft::num_complex::Complex64;
use std::sync::Arc;

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

/// Side of the boundary squares summed product by product.
pub const HMIN: usize = 32;

thread_local! {
    /// One planner per thread: it keeps its plans (twiddles and all), so
    /// a size is planned once, not per call.
    static PLANNER: std::cell::RefCell<RealFftPlanner<f64>> =
        std::cell::RefCell::new(RealFftPlanner::new());
}

/// The forward and inverse real transforms of size `n`, from the
/// thread's planner.
fn plans(n: usize) -> (Arc<dyn RealToComplex<f64>>, Arc<dyn ComplexToReal<f64>>) {
    PLANNER.with(|p| {
        let mut p = p.borrow_mut();
        (p.plan_fft_forward(n), p.plan_fft_inverse(n))
    })
}

/// `R(d) = Σ_{t=0}^{L−1−d} u_t u_{t+d}` for `d = 0..=dmax` (`dmax < L`).
pub fn autocorr(u: &[f64], dmax: usize) -> Vec<f64> {
    let l = u.len();
    if l == 0 {
        return Vec::new();
    }
    let dmax = dmax.min(l - 1);
    // No wrap-around for lags up to dmax.
    let n = (l + dmax + 1).next_power_of_two();
    let (fwd, inv) = plans(n);
    let mut a = vec![0.0; n];
    a[..l].copy_from_slice(u);
    let mut z = fwd.make_output_vec();
    fwd.process(&mut a, &mut z).expect("sizes from the plan");
    for v in &mut z {
        *v = Complex64::new(v.norm_sqr(), 0.0);
    }
    inv.process(&mut z, &mut a).expect("real spectrum");
    let s = 1.0 / n as f64;
    a[..=dmax].iter().map(|v| v * s).collect()
}

/// `G(d) = Σ { u_t u_{t+d} : t ≥ 0, t + d < L, den·t < num·d }` for
/// `d = 0..=dmax`: the sum over the first `c·d` products of lag d,
/// `c = num/den` (e.g. `num = den = 1`: `Σ_{t<d} u_t u_{t+d}`).
pub fn wedge(u: &[f64], num: u64, den: u64, dmax: usize) -> Vec<f64> {
    let mut g = vec![0.0; dmax + 1];
    let l = u.len();
    if l < 2 || dmax == 0 || num == 0 {
        return g;
    }
    let (a, b) = ((den + num) as i128, num as i128);
    // Inside: a·t < b·s (same as den·t < num·(s − t)).
    let inside = |t: usize, s: usize| a * (t as i128) < b * (s as i128);
    // t < c·dmax and s < t + dmax + 1, s < L.
    let tmax = ((num as u128 * dmax as u128).div_ceil(den as u128) as usize).min(l);
    let smax = (tmax + dmax + 1).min(l);
    let mut h = smax.max(tmax).next_power_of_two().max(HMIN);
    let mut level: Vec<(usize, usize)> = vec![(0, 0)];
    let mut brute: Vec<(usize, usize)> = Vec::new();
    while !level.is_empty() {
        let mut inner: Vec<(usize, usize)> = Vec::new();
        let mut next: Vec<(usize, usize)> = Vec::new();
        for &(t0, s0) in &level {
            if t0 >= tmax || s0 >= smax || s0 + h <= t0 + 1 || s0 > t0 + h - 1 + dmax {
                continue; // no t < tmax, no s < L, no lag ≥ 1, or every lag > dmax
            }
            if inside(t0 + h - 1, s0) {
                inner.push((t0, s0));
            } else if !inside(t0, s0 + h - 1) {
                continue; // wholly outside
            } else if h <= HMIN {
                brute.push((t0, s0));
            } else {
                let q = h / 2;
                for (dt, ds) in [(0, 0), (0, q), (q, 0), (q, q)] {
                    next.push((t0 + dt, s0 + ds));
                }
            }
        }
        if !inner.is_empty() {
            squares(u, h, &inner, &mut g);
        }
        level = next;
        h /= 2;
    }
    for (t0, s0) in brute {
        for t in t0..(t0 + HMIN).min(l) {
            // First s inside: a·t < b·s.
            let smin = ((a * t as i128) / b + 1) as usize;
            let lo = s0.max(smin);
            let hi = (s0 + HMIN).min(l).min(t + dmax + 1);
            let ut = u[t];
            for s in lo..hi {
                g[s - t] += ut * u[s];
            }
        }
    }
    g
}

/// The squares of side `h` wholly inside a wedge: per square the
/// cross-correlation of `u[t0..t0+h]` and `u[s0..s0+h]`, added to
/// `g[s0 − t0 + e]`, `|e| < h`. Squares with the same `(s0 − t0)/h` add
/// their spectra and share one inverse transform of size 2h.
fn squares(u: &[f64], h: usize, boxes: &[(usize, usize)], g: &mut [f64]) {
    let n = 2 * h;
    let (fwd, inv) = plans(n);
    let mut scratch = vec![0.0; n];
    let mut spectra: BTreeMap<usize, Vec<Complex64>> = BTreeMap::new();
    for &(t0, s0) in boxes {
        for q in [t0 / h, s0 / h] {
            spectra.entry(q).or_insert_with(|| {
                let lo = (q * h).min(u.len());
                let hi = (q * h + h).min(u.len());
                scratch.fill(0.0);
                scratch[..hi - lo].copy_from_slice(&u[lo..hi]);
                let mut z = fwd.make_output_vec();
                fwd.process(&mut scratch, &mut z)
                    .expect("sizes from the plan");
                z
            });
        }
    }
    let mut groups: BTreeMap<usize, Vec<Complex64>> = BTreeMap::new();
    for &(t0, s0) in boxes {
        let (ft, fs) = (&spectra[&(t0 / h)], &spectra[&(s0 / h)]);
        let acc = groups
            .entry((s0 - t0) / h)
            .or_insert_with(|| vec![Complex64::new(0.0, 0.0); h + 1]);
        for ((a, x), y) in acc.iter_mut().zip(ft).zip(fs) {
            *a += x.conj() * y;
        }
    }
    let scale = 1.0 / n as f64;
    for (k, mut z) in groups {
        // A real signal's spectrum is real at 0 and n/2; drop the
        // round-off there, which the inverse refuses.
        z[0].im = 0.0;
        z[h].im = 0.0;
        inv.process(&mut z, &mut scratch).expect("real spectrum");
        let base = k * h;
        // Index e holds lag e (e < h) or e − n (e > h); e = h is empty.
        for (e, v) in scratch.iter().enumerate() {
            let lag = if e < h {
                base + e
            } else if e > h {
                base + e - n
            } else {
                continue;
            };
            if lag < g.len() {
                g[lag] += v * scale;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        let mut x = 0.0;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                x += (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                x
            })
            .collect()
    }

    #[test]
    fn autocorrelation_and_wedges_equal_the_direct_sums() {
        for (n, dmax) in [(5usize, 2usize), (100, 40), (3000, 1000), (5000, 4999)] {
            let u = data(n, n as u64);
            let scale: f64 = u.iter().map(|v| v * v).sum();
            let r = autocorr(&u, dmax);
            for d in 0..=dmax.min(n - 1) {
                let want: f64 = (0..n - d).map(|t| u[t] * u[t + d]).sum();
                assert!((r[d] - want).abs() < 1e-12 * scale, "R n {n} d {d}");
            }
            for (num, den) in [(1u64, 1u64), (2, 1), (1, 2), (3, 5)] {
                let g = wedge(&u, num, den, dmax);
                for d in 0..=dmax {
                    let want: f64 = (0..n)
                        .filter(|&t| t + d < n && den as usize * t < num as usize * d)
                        .map(|t| u[t] * u[t + d])
                        .sum();
                    assert!(
                        (g[d] - want).abs() < 1e-12 * scale,
                        "G n {n} c {num}/{den} d {d}: {} vs {want}",
                        g[d]
                    );
                }
            }
        }
    }
}
