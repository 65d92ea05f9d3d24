//! The comb kernels under every deviation: the squared second and third
//! differences of the phase summed over equal-length windows, in eight
//! lane accumulators (portable loops and AVX2 copies giving the same
//! bits), in fixed blocks of [`COMB_BLOCK`] terms added in order, and the
//! eight-lane sum [`lanes`] of the edge and start terms.

use super::COMB_BLOCK;
use crate::noise::ordered_map;

/// The comb term of `K` samples `c`: for `K = 3` the second difference
/// `c₀ − 2c₁ + c₂`, evaluated as `(c₀ + c₂) − 2c₁`; for `K = 4` the third
/// difference `c₀ − 3c₁ + 3c₂ − c₃`, as `(c₀ − c₃) + 3(c₂ − c₁)`.
/// Differences before products: fewer multiplies than the weighted sum
/// (the multiplies bounded the kernels), and the large phase values
/// cancel before they are scaled. Every kernel here evaluates it in this
/// order; the AVX2 kernels' fused `s − 2c₁` for `K = 3` is the same value
/// (`2c₁` is exact), so the portable and AVX2 kernels give the same bits.
#[inline(always)]
pub(super) fn comb_term<const K: usize>(c: [f64; K]) -> f64 {
    const { assert!(K == 3 || K == 4) };
    if K == 3 {
        (c[0] + c[K - 1]) - 2.0 * c[1]
    } else {
        (c[0] - c[K - 1]) + 3.0 * (c[K - 2] - c[1])
    }
}

/// `a + v²` rounded once (a fused multiply-add), as the comb kernels
/// accumulate their squares: the AVX2 kernels' `vfmadd` in one
/// instruction (it frees the add ports that bounded them: OADEV and OHDEV
/// at every octave of 10⁸ samples 17 % faster here), the portable ones
/// through `f64::mul_add` (correctly rounded everywhere, so the same bits).
#[inline(always)]
fn sq_acc(a: f64, v: f64) -> f64 {
    v.mul_add(v, a)
}

/// `Σ_i t(s₀[i], …, s_{K−1}[i])²`, `t` the comb term ([`comb_term`]),
/// over one block of equal-length slices, eight lane accumulators, each
/// square added by [`sq_acc`], lanes added in a fixed order. (The portable
/// copy; on x86-64 without FMA its `mul_add` is a library call: slower,
/// the same bits.)
#[inline(always)]
pub(super) fn comb_sq<const K: usize>(s: [&[f64]; K]) -> f64 {
    let n = s[0].len();
    let s = s.map(|v| &v[..n]);
    let full = n / 8 * 8;
    let mut acc = [0.0f64; 8];
    let mut i = 0;
    while i < full {
        let c: [&[f64]; K] = s.map(|v| &v[i..i + 8]);
        for (l, a) in acc.iter_mut().enumerate() {
            *a = sq_acc(*a, comb_term(c.map(|v| v[l])));
        }
        i += 8;
    }
    for (l, a) in acc.iter_mut().enumerate().take(n - full) {
        *a = sq_acc(*a, comb_term(s.map(|v| v[full + l])));
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}

/// [`comb_term`] on four lanes: the same operations in the same order
/// (`K = 3`: `s − 2c₁` as one fused `vfnmadd`, exact like the product).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn comb_term_avx2<const K: usize>(
    c: [std::arch::x86_64::__m256d; K],
) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    if K == 3 {
        _mm256_fnmadd_pd(_mm256_set1_pd(2.0), c[1], _mm256_add_pd(c[0], c[K - 1]))
    } else {
        _mm256_add_pd(
            _mm256_sub_pd(c[0], c[K - 1]),
            _mm256_mul_pd(_mm256_set1_pd(3.0), _mm256_sub_pd(c[K - 2], c[1])),
        )
    }
}

/// [`comb_sq`] in AVX2 registers: each lane does the same operations in
/// the same order (the squares added by `vfmadd`, as [`sq_acc`]), so the
/// same bits; two registers hold the eight accumulators.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(super) fn comb_sq_avx2<const K: usize>(s: [&[f64]; K]) -> f64 {
    use std::arch::x86_64::*;
    let n = s[0].len();
    let s = s.map(|v| &v[..n]);
    let full = n / 8 * 8;
    let (mut a0, mut a1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
    let mut i = 0;
    while i < full {
        // SAFETY: i + 8 <= full <= n = every slice's length.
        unsafe {
            let v0 = comb_term_avx2(s.map(|v| _mm256_loadu_pd(v.as_ptr().add(i))));
            let v1 = comb_term_avx2(s.map(|v| _mm256_loadu_pd(v.as_ptr().add(i + 4))));
            a0 = _mm256_fmadd_pd(v0, v0, a0);
            a1 = _mm256_fmadd_pd(v1, v1, a1);
        }
        i += 8;
    }
    let mut acc = [0.0f64; 8];
    // SAFETY: acc holds eight f64.
    unsafe {
        _mm256_storeu_pd(acc.as_mut_ptr(), a0);
        _mm256_storeu_pd(acc.as_mut_ptr().add(4), a1);
    }
    for (l, a) in acc.iter_mut().enumerate().take(n - full) {
        *a = sq_acc(*a, comb_term(s.map(|v| v[full + l])));
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}

/// [`comb_sq`] of one block, through its AVX2 copy when the CPU has AVX2
/// and FMA (the same bits).
pub(super) fn comb_block<const K: usize>(s: [&[f64]; K]) -> f64 {
    avx2_kernel!(comb_sq_avx2(s), comb_sq(s))
}

/// OADEV and OHDEV terms of one block at once from the four windows
/// `s = [x_{3m+j}, x_{2m+j}, x_{m+j}, x_j]`: `(Σ t₃(s₁, s₂, s₃)², Σ
/// t₄(s₀, …, s₃)²)` ([`comb_term`]), each with exactly the operations of
/// [`comb_sq`] (the same bits as two calls), the windows loaded once.
pub(super) fn comb2_block(s: [&[f64]; 4]) -> (f64, f64) {
    avx2_kernel!(comb2_sq_avx2(s), (comb_sq([s[1], s[2], s[3]]), comb_sq(s)))
}

/// [`comb2_block`] in AVX2 registers (per lane the operations of
/// [`comb_sq`], squares by `vfmadd`: the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
pub(super) fn comb2_sq_avx2(s: [&[f64]; 4]) -> (f64, f64) {
    use std::arch::x86_64::*;
    let n = s[0].len();
    let s = s.map(|v| &v[..n]);
    let full = n / 8 * 8;
    let z = _mm256_setzero_pd();
    let (mut a0, mut a1, mut h0, mut h1) = (z, z, z, z);
    let mut i = 0;
    while i < full {
        // SAFETY: i + 8 <= full <= n = every slice's length.
        unsafe {
            for (half, (acc_a, acc_h)) in [(0, (&mut a0, &mut h0)), (4, (&mut a1, &mut h1))] {
                let c = s.map(|v| _mm256_loadu_pd(v.as_ptr().add(i + half)));
                let va = comb_term_avx2([c[1], c[2], c[3]]);
                let vh = comb_term_avx2(c);
                *acc_a = _mm256_fmadd_pd(va, va, *acc_a);
                *acc_h = _mm256_fmadd_pd(vh, vh, *acc_h);
            }
        }
        i += 8;
    }
    let (mut ea, mut eh) = ([0.0f64; 8], [0.0f64; 8]);
    // SAFETY: ea and eh hold eight f64 each.
    unsafe {
        _mm256_storeu_pd(ea.as_mut_ptr(), a0);
        _mm256_storeu_pd(ea.as_mut_ptr().add(4), a1);
        _mm256_storeu_pd(eh.as_mut_ptr(), h0);
        _mm256_storeu_pd(eh.as_mut_ptr().add(4), h1);
    }
    for l in 0..n - full {
        let c = s.map(|v| v[full + l]);
        let va = comb_term([c[1], c[2], c[3]]);
        let vh = comb_term(c);
        ea[l] = sq_acc(ea[l], va);
        eh[l] = sq_acc(eh[l], vh);
    }
    let add = |e: [f64; 8]| ((e[0] + e[4]) + (e[1] + e[5])) + ((e[2] + e[6]) + (e[3] + e[7]));
    (add(ea), add(eh))
}

/// `Σ_i t(s₀[i], …)²` ([`comb_term`]) over slices of equal length in fixed blocks
/// of [`COMB_BLOCK`] terms, block sums added in order; parallel over blocks
/// when `parallel` (same bits either way).
pub(super) fn comb_sum<const K: usize>(s: [&[f64]; K], parallel: bool) -> f64 {
    let n = s[0].len();
    let nb = n.div_ceil(COMB_BLOCK);
    let block = |b: usize| {
        let (lo, hi) = (b * COMB_BLOCK, ((b + 1) * COMB_BLOCK).min(n));
        comb_block(s.map(|v| &v[lo..hi]))
    };
    ordered_map(nb, parallel, block).iter().sum()
}

/// `Σ_{i=a}^{b−1} f(i)` in eight lane accumulators, lanes added in a
/// fixed order.
#[inline]
pub(super) fn lanes(a: usize, b: usize, f: impl Fn(usize) -> f64) -> f64 {
    let mut acc = [0.0f64; 8];
    let mut i = a;
    while i + 8 <= b {
        for (l, al) in acc.iter_mut().enumerate() {
            *al += f(i + l);
        }
        i += 8;
    }
    for (l, al) in acc.iter_mut().enumerate().take(b.saturating_sub(i)) {
        *al += f(i + l);
    }
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
}
