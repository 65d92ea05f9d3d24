//! Power-law noise identification at every averaging time, as Stable32
//! does it:
//!
//! - **lag-1 autocorrelation** (W. J. Riley and C. A. Greenhall, "Power law
//!   noise identification using the lag 1 autocorrelation", 18th EFTF,
//!   2004) where the decimated record has at least [`MIN_POINTS`] points:
//!   the phase data decimated by m, differenced d times until
//!   `δ = r1/(1 + r1) < 0.25` (or d = dmax); then `α = 2 − 2d − round(2δ)`
//!   (S_y ∝ f^α: 2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2
//!   random-walk FM). Only the mean is removed: a quadratic fitted to a few
//!   tens of decimated points takes the low-frequency content with it and
//!   makes random-walk phase look white (on the Cs 5071A record of
//!   allantools' tests it turned Stable32's α = 0 at τ = 10⁴ s into 2;
//!   without it every α of that record's 1530 Stable32 rows with enough
//!   points is reproduced); the differences remove any trend.
//! - **B1 ratio and R(n)** ([`b1_rn`]) where it has fewer: J. A. Barnes'
//!   bias function B1 (the standard variance of the τ-averages over the
//!   Allan variance; D. A. Howe, R. L. Beard, C. A. Greenhall, J. Vernotte,
//!   W. J. Riley, "A total estimator of the Hadamard function used for GPS
//!   operations", 32nd PTTI, 2000, Table 3 for its expected values) picks
//!   μ, the τ exponent of the Allan variance; where μ = −2 (phase noise)
//!   the ratio R(n) = MVAR/AVAR (IEEE Std 1139-2008) separates white PM,
//!   flicker PM and white FM.

use serde::{Deserialize, Serialize};

/// Fewest decimated points the lag-1 method is used on (Riley & Greenhall
/// §3); below it the B1 ratio and R(n) ([`b1_rn`]), as in Stable32's
/// overlapping statistics.
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

/// One averaging factor: the record decimated by `m` has `n` points.
#[derive(Clone, Copy)]
struct Level {
    m: usize,
    n: usize,
}

impl Level {
    fn new(len: usize, m: usize) -> Option<Level> {
        let m = m.max(1);
        let n = (len.checked_sub(1)?) / m + 1;
        (n >= MIN_POINTS).then_some(Level { m, n })
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
}

/// `Σ v` in four lanes (the loop vectorises), lanes added in a fixed
/// order, so every caller gets the same bits.
#[inline(always)]
fn lane_sum(v: &[f64]) -> f64 {
    let mut a = [0.0f64; 4];
    let quads = v.chunks_exact(4);
    let rest = quads.remainder();
    for q in quads {
        for l in 0..4 {
            a[l] += q[l];
        }
    }
    for (l, &y) in rest.iter().enumerate() {
        a[l] += y;
    }
    (a[0] + a[1]) + (a[2] + a[3])
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
/// centred values before the next block, the sums of the four series.
struct Acf4<'a> {
    lv: &'a Level,
    /// The decimated record's mean, removed from every point.
    mean: f64,
    tail: Vec<f64>,
    sums: [[f64; 3]; 4],
}

impl Acf4<'_> {
    /// Start at decimated index `i0`: the centred values of up to four
    /// points before it, recomputed from the record (the same bits the
    /// previous segment computed).
    fn start(&mut self, x: &[f64], i0: usize) {
        self.tail.clear();
        let lv = self.lv;
        for i in i0.saturating_sub(4)..i0 {
            self.tail.push(x[i * lv.m] - self.mean);
        }
    }
    /// Add the points `i0..i1` (following the tail) to the four series.
    fn block(&mut self, v: &[f64], bufs: &mut [Vec<f64>; 4]) {
        let s = avx2_or_not!(block_sums(self.mean, &self.tail, v, bufs));
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
/// block's centred values, `bufs[d]` their d-th differences (element k of
/// series d is decimated index `i0 − h + d + k`, `i0` the block's first
/// point and h the tail's length; the block's
/// points start at k = h − d, or at 0 near the record's start, where
/// series d begins at index d).
#[inline(always)]
fn block_sums(mean: f64, tail: &[f64], v: &[f64], bufs: &mut [Vec<f64>; 4]) -> [[f64; 3]; 4] {
    let h = tail.len();
    let e = &mut bufs[0];
    e.clear();
    e.extend_from_slice(tail);
    e.resize(h + v.len(), 0.0);
    for (o, &y) in e[h..].iter_mut().zip(v) {
        *o = y - mean;
    }
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

/// Lag-1 autocorrelations `r1` of the decimated record (mean removed)
/// and of its first three differences (Riley & Greenhall eq. 2,
/// `Σ (z_i − μ)(z_{i+1} − μ) / Σ (z_i − μ)²`), at every factor of `ms`;
/// `None` where the decimated record has fewer than [`MIN_POINTS`] points.
///
/// Two sweeps over the record for all factors together: the first sums
/// each decimated record for its mean, the second forms the centred values
/// and their differences block by block with the sums of each series.
fn lag1_many(x: &[f64], ms: &[usize], parallel: bool) -> Vec<Option<[f64; 4]>> {
    let all: Vec<Option<Level>> = ms.iter().map(|&m| Level::new(x.len(), m)).collect();
    let levels: Vec<Level> = all.iter().flatten().copied().collect();
    if levels.is_empty() {
        return vec![None; ms.len()];
    }
    let parts = per_segment(x.len(), parallel, |lo, hi| {
        let mut out = vec![0.0f64; levels.len()];
        let mut buf = Vec::with_capacity(BLK);
        sweep(&levels, lo, hi, |k, i0, i1| {
            let lv = &levels[k];
            let v = lv.points(x, i0, i1, &mut buf);
            out[k] += lane_sum(v);
        });
        out
    });
    // On the symmetric grid the odd power sums vanish and the even ones
    // have closed forms: Σt² = n(n²−1)/(12c²), Σt⁴ = n(n²−1)(3n²−7)/(240c⁴).
    // Only the mean is removed (module docs): `c0 = Σv/n`, the series
    // centred so that the sums below do not cancel; the autocorrelation
    // removes the (then tiny) remaining mean exactly.
    let means: Vec<f64> = levels
        .iter()
        .enumerate()
        .map(|(k, lv)| parts.iter().map(|p| p[k]).sum::<f64>() / lv.n as f64)
        .collect();
    let parts = per_segment(x.len(), parallel, |lo, hi| {
        let mut st: Vec<Acf4> = levels
            .iter()
            .zip(&means)
            .map(|(lv, &mean)| Acf4 {
                lv,
                mean,
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
            st[k].block(v, &mut bufs);
        });
        st.into_iter().map(|s| s.sums).collect::<Vec<_>>()
    });
    let mut r1s = levels.iter().enumerate().map(|(k, lv)| {
        let r = |i: usize| x[i * lv.m] - means[k];
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

/// How the noise was identified at one averaging time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum IdMethod {
    /// Lag-1 autocorrelation (at least [`MIN_POINTS`] decimated points).
    Lag1,
    /// The B1 ratio.
    B1,
    /// The B1 ratio said phase noise; R(n) chose which.
    Rn,
}

impl IdMethod {
    /// Key in the JSON (`lag1`, `b1`, `rn`).
    pub fn as_str(self) -> &'static str {
        match self {
            IdMethod::Lag1 => "lag1",
            IdMethod::B1 => "b1",
            IdMethod::Rn => "rn",
        }
    }
}

/// Expected B1 ratio for `n` τ-averages of a noise whose Allan variance
/// goes as τ^μ (Barnes' bias function; Howe et al. 2000, Table 3):
/// `B1(N, μ) = N(1 − N^μ) / (2(N − 1)(1 − 2^μ))`, and
/// `N ln N / (2(N − 1) ln 2)` at μ = 0 (flicker FM). μ = 1, 0, −1, −2
/// are random-walk FM, flicker FM, white FM and phase noise.
pub fn b1_expected(n: f64, mu: i32) -> f64 {
    if mu == 0 {
        n * n.ln() / (2.0 * (n - 1.0) * std::f64::consts::LN_2)
    } else {
        let m = f64::from(mu);
        n * (1.0 - n.powf(m)) / (2.0 * (n - 1.0) * (1.0 - 2f64.powf(m)))
    }
}

/// Expected R(n) = MVAR/AVAR of flicker PM at factor m, with the
/// measurement bandwidth at the Nyquist frequency, `2π f_h τ = π m`
/// (IEEE Std 1139-2008 Table: AVAR `(1.038 + 3 ln(2π f_h τ))/(4π²)`,
/// MVAR `3 ln(256/27)/(8π²)`, both times `h₁/τ²`).
pub fn rn_flicker_pm(m: f64) -> f64 {
    use std::f64::consts::PI;
    let mvar = 3.0 * (256.0f64 / 27.0).ln() / (8.0 * PI * PI);
    let avar = (1.038 + 3.0 * (PI * m).ln()) / (4.0 * PI * PI);
    mvar / avar
}

/// Noise exponent α at one factor `m` from the observed B1 ratio `b1`
/// (standard variance of the τ-averages over the Allan variance) with
/// `n_avg` non-overlapping τ-averages in the record, and the observed
/// `rn` = MVAR/AVAR at the factor:
///
/// 1. μ is the first of 1, 0, −1 whose boundary with the next, the
///    geometric mean `√(B1(N, μ)·B1(N, μ − 1))`, `b1` exceeds:
///    `α = −μ − 1` ([`IdMethod::B1`]);
/// 2. otherwise the noise is in the phase (μ = −2) and R(n) chooses,
///    by the geometric means of neighbouring expected values, between
///    white PM (`1/m`, α = 2), flicker PM ([`rn_flicker_pm`], α = 1) and
///    white FM (1/2, α = 0: where B1 and R(n) disagree, R(n) decides)
///    ([`IdMethod::Rn`]); where `1/m` is not below the flicker PM value
///    (m ≤ 2, R(n) cannot tell them apart) or R(n) is missing, white PM
///    ([`IdMethod::B1`]).
///
/// `None` for fewer than two averages or a ratio that is not finite.
pub fn b1_rn(b1: f64, n_avg: usize, rn: Option<f64>, m: usize) -> Option<(i32, IdMethod)> {
    if n_avg < 2 || !b1.is_finite() || b1 < 0.0 {
        return None;
    }
    let n = n_avg as f64;
    for mu in [1, 0, -1] {
        if b1 > (b1_expected(n, mu) * b1_expected(n, mu - 1)).sqrt() {
            return Some((-mu - 1, IdMethod::B1));
        }
    }
    let (white, flicker) = (1.0 / m as f64, rn_flicker_pm(m as f64));
    match rn.filter(|r| r.is_finite()) {
        Some(r) if white < flicker && flicker < 0.5 => Some(if r > (flicker * 0.5).sqrt() {
            (0, IdMethod::Rn)
        } else if r > (white * flicker).sqrt() {
            (1, IdMethod::Rn)
        } else {
            (2, IdMethod::Rn)
        }),
        _ => Some((2, IdMethod::B1)),
    }
}

/// Where [`b1_overlapping_many`] sums directly: when the direct sums
/// (`L − m` terms per factor) cost less than this many times `L·log₂L`.
const B1_DIRECT_RATIO: f64 = 60.0;

/// Largest estimated round-off of an FFT-based variance, relative to it,
/// that [`b1_overlapping_many`] accepts before summing directly.
const B1_TOL: f64 = 1e-9;

/// The sample variance (divisor M − 1) of the M = L − m overlapping
/// first differences `x_{i+m} − x_i` of phase record `x` (L points), at
/// every factor of `ms` (`None` for fewer than two differences): the
/// numerator of the overlapping B1 ratio (divide by `(mτ0)²` for the
/// variance of the τ-averages of the rate). Stable32's overlapping
/// statistics agree with this form of B1 (module docs).
///
/// Direct two-pass sums on a sparse grid; on a dense one, from the
/// record less its least-squares line `u` (the centred differences are
/// blind to a line): `Σ (u_{i+m} − u_i)² = Q(L) − Q(m) + Q(M) − 2R(m)`
/// with `Q` the prefix sums of `u²` and `R` the autocorrelation by FFT
/// ([`super::corr::autocorr`]), a factor whose round-off estimate
/// exceeds `B1_TOL` summed directly. Same numbers serial or parallel.
pub fn b1_overlapping_many(x: &[f64], ms: &[usize], parallel: bool) -> Vec<Option<f64>> {
    let l = x.len();
    let direct = |m: usize| -> Option<f64> {
        let mm = l.checked_sub(m).filter(|&mm| mm >= 2 && m >= 1)?;
        let mean = (x[mm..].iter().sum::<f64>() - x[..m].iter().sum::<f64>()) / mm as f64;
        let ss: f64 = x[m..]
            .iter()
            .zip(x)
            .map(|(b, a)| {
                let d = (b - a) - mean;
                d * d
            })
            .sum();
        Some(ss / (mm - 1) as f64)
    };
    let cost: f64 = ms.iter().map(|&m| l.saturating_sub(m) as f64).sum();
    let lf = l as f64;
    if l < 4 || cost <= B1_DIRECT_RATIO * lf * lf.log2() {
        return super::ordered_map(ms.len(), parallel, |k| direct(ms[k]));
    }
    let u = super::dev::detrend(x, 1);
    let mut q = vec![0.0; l + 1];
    let mut p = vec![0.0; l + 1];
    for (t, &v) in u.iter().enumerate() {
        q[t + 1] = q[t] + v * v;
        p[t + 1] = p[t] + v;
    }
    let dmax = ms.iter().copied().max().unwrap_or(0).min(l - 1);
    let r = super::corr::autocorr(&u, dmax);
    let noise = 16.0 * f64::EPSILON * ((l + dmax + 1).next_power_of_two() as f64).log2() * q[l];
    super::ordered_map(ms.len(), parallel, |k| {
        let m = ms[k];
        let mm = l.checked_sub(m).filter(|&mm| mm >= 2 && m >= 1)?;
        let d = q[l] - q[m] + q[mm] - 2.0 * r[m];
        let mean = (p[l] - p[mm] - p[m]) / mm as f64;
        let ss = d - mm as f64 * mean * mean;
        if ss > 0.0 && noise <= B1_TOL * ss {
            Some(ss / (mm - 1) as f64)
        } else {
            direct(m)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{noise::flicker, normal, rng};

    /// Riley & Greenhall's method written out: decimate, difference,
    /// mean-centred r1.
    fn reference(x: &[f64], m: usize) -> Option<[f64; 4]> {
        let mut z: Vec<f64> = x.iter().step_by(m).copied().collect();
        if z.len() < MIN_POINTS {
            return None;
        }
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
        let bits = |a: &[f64]| a.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for n in [0, 1, 3, 4, 5, 8, 9, 31, 1000] {
            for i0 in [0, 7, 1001] {
                let v = &x[i0..i0 + n];
                for prev in [None, Some(0.25)] {
                    // SAFETY: the CPU supports AVX2 (checked above).
                    let wide = unsafe { acf_sums_avx2(v, prev) };
                    assert_eq!(bits(&acf_sums(v, prev)), bits(&wide), "n {n}");
                }
            }
        }
    }

    /// The variance of the overlapping first differences, written out.
    fn diff_var(x: &[f64], m: usize) -> f64 {
        let d: Vec<f64> = x[m..].iter().zip(x).map(|(b, a)| b - a).collect();
        let mu = d.iter().sum::<f64>() / d.len() as f64;
        d.iter().map(|v| (v - mu) * (v - mu)).sum::<f64>() / (d.len() - 1) as f64
    }

    #[test]
    fn the_b1_variances_match_the_sums_written_out_on_sparse_and_dense_grids() {
        // Random-walk phase with a large offset and a slope, plus white.
        let w = white(5000, 21);
        let x: Vec<f64> = cumsum(white(5000, 22))
            .iter()
            .zip(&w)
            .enumerate()
            .map(|(i, (r, e))| 1e6 + 3.0 * i as f64 + r + 0.1 * e)
            .collect();
        // Sparse: summed directly. Dense (every factor): by FFT.
        let sparse = [1usize, 7, 160, 1249];
        let all: Vec<usize> = (1..=1249).collect();
        for ms in [&sparse[..], &all[..]] {
            let got = b1_overlapping_many(&x, ms, true);
            assert_eq!(got, b1_overlapping_many(&x, ms, false));
            for (&m, g) in ms.iter().zip(&got) {
                let want = diff_var(&x, m);
                let g = g.unwrap();
                assert!(((g - want) / want).abs() < 1e-9, "m {m}: {g} vs {want}");
            }
        }
        assert_eq!(b1_overlapping_many(&x[..3], &[2], false), vec![None]);
    }

    #[test]
    fn b1_and_rn_name_the_noise_by_their_expected_values() {
        // The expected B1 of each μ is classified as that μ.
        for n_avg in [4usize, 10, 29] {
            for (mu, alpha) in [(1, -2), (0, -1), (-1, 0)] {
                let b1 = b1_expected(n_avg as f64, mu);
                assert_eq!(b1_rn(b1, n_avg, None, 1000), Some((alpha, IdMethod::B1)));
            }
            // Phase noise: R(n) decides.
            let b1 = b1_expected(n_avg as f64, -2);
            let m = 1000;
            assert_eq!(
                b1_rn(b1, n_avg, Some(1.0 / m as f64), m),
                Some((2, IdMethod::Rn))
            );
            assert_eq!(
                b1_rn(b1, n_avg, Some(rn_flicker_pm(m as f64)), m),
                Some((1, IdMethod::Rn))
            );
            assert_eq!(b1_rn(b1, n_avg, Some(0.5), m), Some((0, IdMethod::Rn)));
        }
        // The closed forms at μ = 1, −1, −2 (Howe et al. Table 3).
        let n = 12.0;
        assert!((b1_expected(n, 1) - n / 2.0).abs() < 1e-12);
        assert!((b1_expected(n, -1) - 1.0).abs() < 1e-12);
        assert!((b1_expected(n, -2) - (n * n - 1.0) / (1.5 * n * (n - 1.0))).abs() < 1e-12);
        assert_eq!(b1_rn(f64::NAN, 10, None, 10), None);
        assert_eq!(b1_rn(1.0, 1, None, 10), None);
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
