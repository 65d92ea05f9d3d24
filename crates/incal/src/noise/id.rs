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

/// Samples of `x` per segment: the fixed partition the segments' sums are
/// added over, in order, so a parallel run gives a serial run's bits.
const SEG: usize = if cfg!(test) { 1 << 13 } else { 1 << 22 };
/// Samples of `x` per chunk: every factor below it takes its points of a
/// chunk while the chunk is in cache, so the record is read from memory
/// once per pass, not once per factor.
const CHUNK: usize = if cfg!(test) { 1 << 9 } else { 1 << 15 };
/// Decimated points per block of the vectorised loops. (The unit tests
/// use small sizes so that short records cross every boundary.)
const BLK: usize = if cfg!(test) { 1 << 6 } else { 1 << 11 };

/// One averaging factor: the record decimated by `m` has `n` points at
/// scaled times `t_i = (i − c)/c` (on [−1, 1], which keeps the normal
/// equations well conditioned).
#[derive(Clone, Copy)]
struct Level {
    m: usize,
    n: usize,
    c: f64,
    sc: f64,
}

impl Level {
    fn new(len: usize, m: usize) -> Option<Level> {
        let m = m.max(1);
        let n = (len.checked_sub(1)?) / m + 1;
        let c = (n as f64 - 1.0) / 2.0;
        (n >= MIN_POINTS).then_some(Level {
            m,
            n,
            c,
            sc: 1.0 / c,
        })
    }
    /// Decimated indices whose samples lie in `x[a..b]`.
    fn range(&self, a: usize, b: usize) -> (usize, usize) {
        (
            a.div_ceil(self.m).min(self.n),
            b.div_ceil(self.m).min(self.n),
        )
    }
    /// The decimated points `i0..i1`: the record itself for m = 1,
    /// gathered into `buf` otherwise.
    fn points<'a>(&self, x: &'a [f64], i0: usize, i1: usize, buf: &'a mut Vec<f64>) -> &'a [f64] {
        if self.m == 1 {
            return &x[i0..i1];
        }
        buf.clear();
        buf.extend((i0..i1).map(|i| x[i * self.m]));
        buf
    }
    /// Residual of a point from the fitted quadratic `c0 + c1 t + c2 t²`.
    /// `fi` is the index as f64 (exact), so every caller gets the same bits.
    #[inline(always)]
    fn resid(&self, coef: &[f64; 3], fi: f64, v: f64) -> f64 {
        let t = (fi - self.c) * self.sc;
        v - (coef[0] + coef[1] * t + coef[2] * t * t)
    }
}

#[inline(always)]
/// `Σ v, Σ t v, Σ t² v` over decimated points starting at index `i0`,
/// four lanes (the loop vectorises), lanes added in a fixed order.
fn poly_sums(lv: &Level, v: &[f64], i0: usize) -> [f64; 3] {
    let mut a = [[0.0f64; 4]; 3];
    let mut base = i0 as f64;
    let quads = v.chunks_exact(4);
    let rest = quads.remainder();
    for q in quads {
        for l in 0..4 {
            let t = (base + l as f64 - lv.c) * lv.sc;
            a[0][l] += q[l];
            a[1][l] += t * q[l];
            a[2][l] += t * t * q[l];
        }
        base += 4.0;
    }
    for (l, &y) in rest.iter().enumerate() {
        let t = (base + l as f64 - lv.c) * lv.sc;
        a[0][l] += y;
        a[1][l] += t * y;
        a[2][l] += t * t * y;
    }
    a.map(|s| (s[0] + s[1]) + (s[2] + s[3]))
}

/// [`poly_sums`], in AVX2 registers when the CPU has them (the same bits).
fn normal_sums(lv: &Level, v: &[f64], i0: usize) -> [f64; 3] {
    avx2_kernel!(poly_sums_avx2(lv, v, i0), poly_sums(lv, v, i0))
}

/// The four lanes of each of three AVX2 accumulators.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn lanes3(v: [std::arch::x86_64::__m256d; 3]) -> [[f64; 4]; 3] {
    let mut a = [[0.0f64; 4]; 3];
    for (row, r) in a.iter_mut().zip(v) {
        // SAFETY: each row holds four f64.
        unsafe { std::arch::x86_64::_mm256_storeu_pd(row.as_mut_ptr(), r) };
    }
    a
}

/// [`poly_sums`] in AVX2 registers: lane l takes the points k ≡ l
/// (mod 4), with `t = (i − c)·sc` and the products `t·v`, `(t·t)·v`, as
/// there (no FMA: the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn poly_sums_avx2(lv: &Level, v: &[f64], i0: usize) -> [f64; 3] {
    use std::arch::x86_64::*;
    let n = v.len();
    let full = n / 4 * 4;
    let (c, sc) = (_mm256_set1_pd(lv.c), _mm256_set1_pd(lv.sc));
    let step = _mm256_set1_pd(4.0);
    let b = i0 as f64;
    let mut fi = _mm256_setr_pd(b, b + 1.0, b + 2.0, b + 3.0);
    let zero = _mm256_setzero_pd();
    let (mut a0, mut a1, mut a2) = (zero, zero, zero);
    let mut k = 0;
    while k < full {
        // SAFETY: k + 4 <= full <= v.len().
        let y = unsafe { _mm256_loadu_pd(v.as_ptr().add(k)) };
        let t = _mm256_mul_pd(_mm256_sub_pd(fi, c), sc);
        a0 = _mm256_add_pd(a0, y);
        a1 = _mm256_add_pd(a1, _mm256_mul_pd(t, y));
        a2 = _mm256_add_pd(a2, _mm256_mul_pd(_mm256_mul_pd(t, t), y));
        fi = _mm256_add_pd(fi, step);
        k += 4;
    }
    let mut a = lanes3([a0, a1, a2]);
    let base = (i0 + full) as f64;
    for (l, &y) in v[full..].iter().enumerate() {
        let t = (base + l as f64 - lv.c) * lv.sc;
        a[0][l] += y;
        a[1][l] += t * y;
        a[2][l] += t * t * y;
    }
    a.map(|s| (s[0] + s[1]) + (s[2] + s[3]))
}

#[inline(always)]
/// `Σ z, Σ z², Σ z_{j−1} z_j` of a run of one series (`prev` the value
/// before the run, if any), four lanes, lanes added in a fixed order.
fn acf_sums(z: &[f64], prev: Option<f64>) -> [f64; 3] {
    let Some((&last, head)) = z.split_last() else {
        return [0.0; 3];
    };
    let (mut s, mut s2, mut lag) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
    let (a, b) = (head.chunks_exact(4), z[1..].chunks_exact(4));
    let (ra, rb) = (a.remainder(), b.remainder());
    for (p, q) in a.zip(b) {
        for l in 0..4 {
            s[l] += p[l];
            s2[l] += p[l] * p[l];
            lag[l] += p[l] * q[l];
        }
    }
    for (l, (&p, &q)) in ra.iter().zip(rb).enumerate() {
        s[l] += p;
        s2[l] += p * p;
        lag[l] += p * q;
    }
    let sum = |v: [f64; 4]| (v[0] + v[1]) + (v[2] + v[3]);
    [
        sum(s) + last,
        sum(s2) + last * last,
        sum(lag) + prev.map_or(0.0, |p| p * z[0]),
    ]
}

/// `out[k]` = the residual ([`Level::resid`]) of decimated point `i0 + k`,
/// value `v[k]`: four lanes at a time, in AVX2 registers when the CPU has
/// them (the same operations in the same order: the same bits).
#[inline(always)]
fn residuals(lv: &Level, coef: &[f64; 3], v: &[f64], i0: usize, out: &mut [f64]) {
    avx2_kernel!(
        residuals_avx2(lv, coef, v, i0, out),
        residuals_portable(lv, coef, v, i0, out)
    )
}

fn residuals_portable(lv: &Level, coef: &[f64; 3], v: &[f64], i0: usize, out: &mut [f64]) {
    for (k, (o, &y)) in out.iter_mut().zip(v).enumerate() {
        *o = lv.resid(coef, (i0 + k) as f64, y);
    }
}

/// [`residuals_portable`] in AVX2 registers: per lane `t = (i − c)·sc`,
/// `y − ((c₀ + c₁t) + (c₂t)t)`, as [`Level::resid`] (no FMA).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn residuals_avx2(lv: &Level, coef: &[f64; 3], v: &[f64], i0: usize, out: &mut [f64]) {
    use std::arch::x86_64::*;
    let n = v.len().min(out.len());
    let full = n / 4 * 4;
    let (c, sc) = (_mm256_set1_pd(lv.c), _mm256_set1_pd(lv.sc));
    let [c0, c1, c2] = coef.map(|a| _mm256_set1_pd(a));
    let step = _mm256_set1_pd(4.0);
    // Indices below 2^53: exact in f64, and so is every `+ 4`.
    let b = i0 as f64;
    let mut fi = _mm256_setr_pd(b, b + 1.0, b + 2.0, b + 3.0);
    let mut k = 0;
    while k < full {
        // SAFETY: k + 4 <= full <= n <= both lengths.
        unsafe {
            let y = _mm256_loadu_pd(v.as_ptr().add(k));
            let t = _mm256_mul_pd(_mm256_sub_pd(fi, c), sc);
            let p = _mm256_add_pd(
                _mm256_add_pd(c0, _mm256_mul_pd(c1, t)),
                _mm256_mul_pd(_mm256_mul_pd(c2, t), t),
            );
            _mm256_storeu_pd(out.as_mut_ptr().add(k), _mm256_sub_pd(y, p));
        }
        fi = _mm256_add_pd(fi, step);
        k += 4;
    }
    residuals_portable(lv, coef, &v[full..n], i0 + full, &mut out[full..n]);
}

/// `Σ z, Σ z², Σ z_{j−1} z_j` of a run of one series (`prev` the value
/// before the run, if any), four lanes, lanes added in a fixed order; in
/// AVX2 registers when the CPU has them (the same bits).
#[inline(always)]
fn lag1_sums(z: &[f64], prev: Option<f64>) -> [f64; 3] {
    avx2_kernel!(acf_sums_avx2(z, prev), acf_sums(z, prev))
}

/// [`acf_sums`] in AVX2 registers: lane l takes the pairs `(z_k, z_{k+1})`
/// with k ≡ l (mod 4), as there (no FMA: the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn acf_sums_avx2(z: &[f64], prev: Option<f64>) -> [f64; 3] {
    use std::arch::x86_64::*;
    let Some((&last, head)) = z.split_last() else {
        return [0.0; 3];
    };
    let n = head.len();
    let full = n / 4 * 4;
    let zero = _mm256_setzero_pd();
    let (mut s, mut s2, mut lag) = (zero, zero, zero);
    let mut k = 0;
    while k < full {
        // SAFETY: k + 4 <= n = z.len() − 1, so z[k + 1..k + 5] is in z.
        unsafe {
            let p = _mm256_loadu_pd(z.as_ptr().add(k));
            let q = _mm256_loadu_pd(z.as_ptr().add(k + 1));
            s = _mm256_add_pd(s, p);
            s2 = _mm256_add_pd(s2, _mm256_mul_pd(p, p));
            lag = _mm256_add_pd(lag, _mm256_mul_pd(p, q));
        }
        k += 4;
    }
    let mut a = lanes3([s, s2, lag]);
    for l in 0..n - full {
        let (p, q) = (z[full + l], z[full + l + 1]);
        a[0][l] += p;
        a[1][l] += p * p;
        a[2][l] += p * q;
    }
    let sum = |v: [f64; 4]| (v[0] + v[1]) + (v[2] + v[3]);
    [
        sum(a[0]) + last,
        sum(a[1]) + last * last,
        sum(a[2]) + prev.map_or(0.0, |p| p * z[0]),
    ]
}

/// `Δ^d` of four consecutive values for d = 0..3, in place as the blocks
/// difference them: after d differences element k follows the k-th value
/// by d places.
fn differences(r: [f64; 4]) -> [[f64; 4]; 4] {
    let mut out = [r; 4];
    for d in 1..4 {
        for k in 0..4 - d {
            out[d][k] = out[d - 1][k + 1] - out[d - 1][k];
        }
    }
    out
}

/// Pass-2 state of one factor inside a segment: the last (up to four)
/// residuals before the next block, the sums of the four series.
struct Acf4<'a> {
    lv: &'a Level,
    coef: [f64; 3],
    tail: Vec<f64>,
    sums: [[f64; 3]; 4],
}

impl Acf4<'_> {
    /// Start at decimated index `i0`: the residuals of up to four
    /// points before it, recomputed from the record (the same bits the
    /// previous segment computed).
    fn start(&mut self, x: &[f64], i0: usize) {
        self.tail.clear();
        let lv = self.lv;
        for i in i0.saturating_sub(4)..i0 {
            self.tail.push(lv.resid(&self.coef, i as f64, x[i * lv.m]));
        }
    }
    /// Add the points `i0..i1` (following the tail) to the four series.
    fn block(&mut self, v: &[f64], i0: usize, bufs: &mut [Vec<f64>; 4]) {
        let s = avx2_or_not!(block_sums(self.lv, &self.coef, &self.tail, v, i0, bufs));
        for (acc, s) in self.sums.iter_mut().zip(s) {
            for (a, b) in acc.iter_mut().zip(s) {
                *a += b;
            }
        }
        let e = &bufs[0];
        let keep = e.len().min(4);
        self.tail.clear();
        self.tail.extend_from_slice(&e[e.len() - keep..]);
    }
}

/// The four series' sums of one block: `bufs[0]` gets the tail and the
/// block's residuals, `bufs[d]` their d-th differences (element k of
/// series d is index `i0 − h + d + k`, h the tail's length; the block's
/// points start at k = h − d, or at 0 near the record's start, where
/// series d begins at index d).
#[inline(always)]
fn block_sums(
    lv: &Level,
    coef: &[f64; 3],
    tail: &[f64],
    v: &[f64],
    i0: usize,
    bufs: &mut [Vec<f64>; 4],
) -> [[f64; 3]; 4] {
    let h = tail.len();
    let e = &mut bufs[0];
    e.clear();
    e.extend_from_slice(tail);
    e.resize(h + v.len(), 0.0);
    residuals(lv, coef, v, i0, &mut e[h..]);
    for d in 1..4 {
        let (lo, hi) = bufs.split_at_mut(d);
        let (src, dst) = (&lo[d - 1], &mut hi[0]);
        dst.clear();
        dst.extend(src.iter().skip(1).zip(src.iter()).map(|(b, a)| b - a));
    }
    // A plain loop, not `array::from_fn`, so it stays inside the AVX2 copy.
    let mut out = [[0.0; 3]; 4];
    for (d, o) in out.iter_mut().enumerate() {
        let z = &bufs[d];
        let ks = h.saturating_sub(d);
        if ks < z.len() {
            *o = lag1_sums(&z[ks..], ks.checked_sub(1).map(|k| z[k]));
        }
    }
    out
}

/// Run `f(level index, i0, i1)` over the decimated points of every level
/// in `x[lo..hi]`, in blocks of at most [`BLK`] points: factors below
/// [`CHUNK`] chunk by chunk (all of them while a chunk is in cache),
/// larger ones (at most one point per chunk) straight through.
fn sweep(levels: &[Level], lo: usize, hi: usize, mut f: impl FnMut(usize, usize, usize)) {
    let mut blocks = |k: usize, a: usize, b: usize| {
        let (mut i, i1) = levels[k].range(a, b);
        while i < i1 {
            let j = (i + BLK).min(i1);
            f(k, i, j);
            i = j;
        }
    };
    let mut a = lo;
    while a < hi {
        let b = (a + CHUNK).min(hi);
        for (k, lv) in levels.iter().enumerate() {
            if lv.m < CHUNK {
                blocks(k, a, b);
            }
        }
        a = b;
    }
    for (k, lv) in levels.iter().enumerate() {
        if lv.m >= CHUNK {
            blocks(k, lo, hi);
        }
    }
}

/// Per segment of the fixed partition, in segment order (in parallel
/// when asked; the same values either way).
fn per_segment<T: Send>(
    len: usize,
    parallel: bool,
    f: impl Fn(usize, usize) -> T + Sync,
) -> Vec<T> {
    let nseg = len.div_ceil(SEG).max(1);
    super::ordered_map(nseg, parallel, |s| f(s * SEG, ((s + 1) * SEG).min(len)))
}

/// Lag-1 autocorrelations `r1` of the quadratic-detrended decimated record
/// and of its first three differences (Riley & Greenhall eq. 2,
/// `Σ (z_i − μ)(z_{i+1} − μ) / Σ (z_i − μ)²`), at every factor of `ms`;
/// `None` where the decimated record has fewer than [`MIN_POINTS`] points.
///
/// Two sweeps over the record for all factors together: the first sums
/// the quadratic's normal equations, the second forms the residuals and
/// their differences block by block with the sums of each series.
fn lag1_many(x: &[f64], ms: &[usize], parallel: bool) -> Vec<Option<[f64; 4]>> {
    let all: Vec<Option<Level>> = ms.iter().map(|&m| Level::new(x.len(), m)).collect();
    let levels: Vec<Level> = all.iter().flatten().copied().collect();
    if levels.is_empty() {
        return vec![None; ms.len()];
    }
    let parts = per_segment(x.len(), parallel, |lo, hi| {
        let mut out = vec![[0.0f64; 3]; levels.len()];
        let mut buf = Vec::with_capacity(BLK);
        sweep(&levels, lo, hi, |k, i0, i1| {
            let lv = &levels[k];
            let v = lv.points(x, i0, i1, &mut buf);
            let p = normal_sums(lv, v, i0);
            for (a, b) in out[k].iter_mut().zip(p) {
                *a += b;
            }
        });
        out
    });
    // On the symmetric grid the odd power sums vanish and the even ones
    // have closed forms: Σt² = n(n²−1)/(12c²), Σt⁴ = n(n²−1)(3n²−7)/(240c⁴).
    let coefs: Vec<[f64; 3]> = levels
        .iter()
        .enumerate()
        .map(|(k, lv)| {
            let nf = lv.n as f64;
            let s2 = nf * (nf * nf - 1.0) / 12.0 * lv.sc * lv.sc;
            let s4 = nf * (nf * nf - 1.0) * (3.0 * nf * nf - 7.0) / 240.0 * lv.sc.powi(4);
            let a = Matrix3::new(nf, 0.0, s2, 0.0, s2, 0.0, s2, 0.0, s4);
            let mut b = [0.0f64; 3];
            for p in &parts {
                for (s, v) in b.iter_mut().zip(p[k]) {
                    *s += v;
                }
            }
            a.try_inverse()
                .map(|ai| ai * Vector3::from(b))
                .map_or([0.0; 3], |c| [c[0], c[1], c[2]])
        })
        .collect();
    let parts = per_segment(x.len(), parallel, |lo, hi| {
        let mut st: Vec<Acf4> = levels
            .iter()
            .zip(&coefs)
            .map(|(lv, &coef)| Acf4 {
                lv,
                coef,
                tail: Vec::with_capacity(4),
                sums: [[0.0; 3]; 4],
            })
            .collect();
        for (s, lv) in st.iter_mut().zip(&levels) {
            s.start(x, lv.range(lo, hi).0);
        }
        let mut buf = Vec::new();
        let mut bufs: [Vec<f64>; 4] = Default::default();
        sweep(&levels, lo, hi, |k, i0, i1| {
            let v = levels[k].points(x, i0, i1, &mut buf);
            st[k].block(v, i0, &mut bufs);
        });
        st.into_iter().map(|s| s.sums).collect::<Vec<_>>()
    });
    let mut r1s = levels.iter().enumerate().map(|(k, lv)| {
        let coef = &coefs[k];
        let r = |i: usize| lv.resid(coef, i as f64, x[i * lv.m]);
        let first = differences([r(0), r(1), r(2), r(3)]);
        let n = lv.n;
        let last = differences([r(n - 4), r(n - 3), r(n - 2), r(n - 1)]);
        std::array::from_fn(|d| {
            let mut s = [0.0f64; 3];
            for p in &parts {
                for (a, b) in s.iter_mut().zip(p[k][d]) {
                    *a += b;
                }
            }
            let [sum, sum2, lag] = s;
            let (first, last) = (first[d][0], last[d][3 - d]);
            let nd = (n - d) as f64;
            let mu = sum / nd;
            let num = lag - mu * (sum - last) - mu * (sum - first) + (nd - 1.0) * mu * mu;
            let den = sum2 - nd * mu * mu;
            if den > 0.0 {
                num / den
            } else {
                0.0
            }
        })
    });
    all.iter().map(|l| l.and_then(|_| r1s.next())).collect()
}

/// α from the four lag-1 autocorrelations: the first series (difference
/// order d) with `δ = r1/(1 + r1) < 0.25`, or the last allowed, gives
/// `α = 2 − 2d − round(2δ)`.
fn classify(r1: [f64; 4]) -> NoiseId {
    let mut allan = None;
    for (d, &r) in r1.iter().enumerate() {
        let delta = r / (1.0 + r);
        let alpha = 2 - 2 * d as i32 - (2.0 * delta).round_ties_even() as i32;
        if allan.is_none() && (delta < 0.25 || d >= 2) {
            allan = Some(alpha);
        }
        if delta < 0.25 || d >= 3 {
            return NoiseId {
                alpha_allan: allan.unwrap_or(alpha),
                alpha_hadamard: alpha,
            };
        }
    }
    unreachable!("d = 3 always returns")
}

/// Identify the noise at every averaging factor of `ms` in phase data `x`
/// (`None` where the decimated record has fewer than [`MIN_POINTS`]
/// points): the lag-1 autocorrelation method of Riley & Greenhall with
/// at most two differences for the Allan family and three for Hadamard.
/// Two sweeps over the record for all factors; the same values serial or
/// parallel.
pub fn identify_many(x: &[f64], ms: &[usize], parallel: bool) -> Vec<Option<NoiseId>> {
    lag1_many(x, ms, parallel)
        .into_iter()
        .map(|r| r.map(classify))
        .collect()
}

/// [`identify_many`] at one factor.
pub fn identify(x: &[f64], m: usize) -> Option<NoiseId> {
    identify_many(x, &[m], false).pop().flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{noise::flicker, normal, rng};

    /// Riley & Greenhall's method written out: decimate, fit the quadratic
    /// by its full normal equations, difference, mean-centred r1.
    fn reference(x: &[f64], m: usize) -> Option<[f64; 4]> {
        let v: Vec<f64> = x.iter().step_by(m).copied().collect();
        let n = v.len();
        if n < MIN_POINTS {
            return None;
        }
        let t: Vec<f64> = (0..n)
            .map(|i| i as f64 / (n - 1) as f64 * 2.0 - 1.0)
            .collect();
        let mut a = Matrix3::zeros();
        let mut b = Vector3::zeros();
        for (&ti, &vi) in t.iter().zip(&v) {
            let p = Vector3::new(1.0, ti, ti * ti);
            a += p * p.transpose();
            b += p * vi;
        }
        let c = a.try_inverse().unwrap() * b;
        let mut z: Vec<f64> = t
            .iter()
            .zip(&v)
            .map(|(&ti, &vi)| vi - (c[0] + c[1] * ti + c[2] * ti * ti))
            .collect();
        Some(std::array::from_fn(|d| {
            if d > 0 {
                z = z.windows(2).map(|w| w[1] - w[0]).collect();
            }
            let mu = z.iter().sum::<f64>() / z.len() as f64;
            let num: f64 = z.windows(2).map(|w| (w[0] - mu) * (w[1] - mu)).sum();
            let den: f64 = z.iter().map(|v| (v - mu) * (v - mu)).sum();
            num / den
        }))
    }

    fn cumsum(v: Vec<f64>) -> Vec<f64> {
        let mut s = 0.0;
        v.into_iter()
            .map(|y| {
                s += y;
                s
            })
            .collect()
    }

    fn white(n: usize, seed: u64) -> Vec<f64> {
        let mut r = rng(seed);
        (0..n).map(|_| normal(&mut r, 1.0)).collect()
    }

    #[test]
    fn every_factor_matches_the_method_written_out_and_parallel_equals_serial() {
        let n = 40_000;
        // (phase data, α expected at the shortest τ)
        let cases = [
            (white(n, 1), 2),
            (flicker(n, 1.0, 2), 1),
            (cumsum(white(n, 3)), 0),
            (cumsum(flicker(n, 1.0, 4)), -1),
            (cumsum(cumsum(white(n, 5))), -2),
        ];
        // Octaves, a dense run of small factors and factors past a chunk.
        let mut ms: Vec<usize> = (0..12).map(|k| 1 << k).collect();
        ms.extend([3, 5, 7, 600, 700, 1333, 2000]);
        for (x, alpha) in &cases {
            let got = lag1_many(x, &ms, false);
            assert_eq!(got, lag1_many(x, &ms, true));
            for (&m, g) in ms.iter().zip(&got) {
                let want = reference(x, m);
                assert_eq!(g.is_some(), want.is_some(), "m = {m}");
                if let (Some(g), Some(w)) = (g, want) {
                    for d in 0..4 {
                        assert!(
                            (g[d] - w[d]).abs() < 1e-9,
                            "m = {m}, d = {d}: {} vs {}",
                            g[d],
                            w[d]
                        );
                    }
                    assert_eq!(classify(*g), classify(w));
                }
            }
            let id = identify(x, 1).unwrap();
            assert_eq!(id.alpha_hadamard, *alpha);
            assert_eq!(id.alpha_allan, *alpha);
        }
    }

    /// The AVX2 kernels are the portable ones in wider registers: the same
    /// bits, at every length around the four lanes.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_kernels_give_the_portable_kernels_bits() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let x = cumsum(white(5000, 11));
        let lv = Level::new(x.len(), 3).unwrap();
        let coef = [0.3, -1.7, 2.9];
        let bits = |a: &[f64]| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for n in [0, 1, 3, 4, 5, 8, 9, 31, 1000] {
            for i0 in [0, 7, 1001] {
                let v = &x[i0..i0 + n];
                let (mut p, mut w) = (vec![0.0; n], vec![0.0; n]);
                residuals_portable(&lv, &coef, v, i0, &mut p);
                // SAFETY: the CPU supports AVX2 (checked above).
                unsafe { residuals_avx2(&lv, &coef, v, i0, &mut w) };
                assert_eq!(bits(&p), bits(&w), "n {n}, i0 {i0}");
                // SAFETY: as above.
                let wide = unsafe { poly_sums_avx2(&lv, v, i0) };
                assert_eq!(bits(&poly_sums(&lv, v, i0)), bits(&wide), "n {n}");
                for prev in [None, Some(0.25)] {
                    // SAFETY: as above.
                    let wide = unsafe { acf_sums_avx2(v, prev) };
                    assert_eq!(bits(&acf_sums(v, prev)), bits(&wide), "n {n}");
                }
            }
        }
    }

    #[test]
    fn a_record_too_short_for_a_factor_is_not_identified() {
        let x = cumsum(white(100, 9));
        let got = identify_many(&x, &[1, 3, 4, 50], false);
        assert!(got[0].is_some() && got[1].is_some());
        assert!(got[2].is_none() && got[3].is_none());
        assert!(identify_many(&[], &[1], false)[0].is_none());
    }
}
