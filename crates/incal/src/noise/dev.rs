//! The deviation kernels on phase data `x` (time-error or angle samples at
//! spacing τ0); σ(τ) for τ = m·τ0.
//!
//! Every kernel sums its squared terms in fixed blocks ([`COMB_BLOCK`],
//! [`BLOCK`] terms),
//! each block with eight lane accumulators (so the loop vectorizes), and
//! adds the block sums in block order. The blocks run on rayon; the fixed
//! partition and the ordered reduction make a parallel run bit-for-bit a
//! serial one.
//!
//! Formulas: NIST SP 1065 (Riley 2008) §5.2.4 eq. (14) OADEV, §5.2.5
//! eq. (15) MDEV, §5.2.6 eq. (17) TDEV, §5.2.9 eq. (22) OHDEV, §5.2.11
//! eq. (25) TOTDEV.

use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::ordered_map;

/// Terms per block of the blocked sums of MDEV.
pub const BLOCK: usize = 1 << 14;

/// Terms per block of the OADEV and OHDEV sums (a window of about fifty
/// of them stays in the caches in [`comb_many`]; the unit tests use short
/// blocks so that short records cross every band).
pub const COMB_BLOCK: usize = if cfg!(test) { 1 << 8 } else { 1 << 11 };

/// The comb term of `K` samples `c`: for `K = 3` the second difference
/// `c₀ − 2c₁ + c₂`, evaluated as `(c₀ + c₂) − 2c₁`; for `K = 4` the third
/// difference `c₀ − 3c₁ + 3c₂ − c₃`, as `(c₀ − c₃) + 3(c₂ − c₁)`.
/// Differences before products: fewer multiplies than the weighted sum
/// (the multiplies bounded the kernels), and the large phase values
/// cancel before they are scaled. Every kernel here evaluates it in this
/// order; the AVX2 kernels' fused `s − 2c₁` for `K = 3` is the same value
/// (`2c₁` is exact), so the portable and AVX2 kernels give the same bits.
#[inline(always)]
fn comb_term<const K: usize>(c: [f64; K]) -> f64 {
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
fn comb_sq<const K: usize>(s: [&[f64]; K]) -> f64 {
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
fn comb_sq_avx2<const K: usize>(s: [&[f64]; K]) -> f64 {
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

fn comb_block<const K: usize>(s: [&[f64]; K]) -> f64 {
    avx2_kernel!(comb_sq_avx2(s), comb_sq(s))
}

/// OADEV and OHDEV terms of one block at once from the four windows
/// `s = [x_{3m+j}, x_{2m+j}, x_{m+j}, x_j]`: `(Σ t₃(s₁, s₂, s₃)², Σ
/// t₄(s₀, …, s₃)²)` ([`comb_term`]), each with exactly the operations of
/// [`comb_sq`] (the same bits as two calls), the windows loaded once.
fn comb2_block(s: [&[f64]; 4]) -> (f64, f64) {
    avx2_kernel!(comb2_sq_avx2(s), (comb_sq([s[1], s[2], s[3]]), comb_sq(s)))
}

/// [`comb2_block`] in AVX2 registers (per lane the operations of
/// [`comb_sq`], squares by `vfmadd`: the same bits).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn comb2_sq_avx2(s: [&[f64]; 4]) -> (f64, f64) {
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
fn comb_sum<const K: usize>(s: [&[f64]; K], parallel: bool) -> f64 {
    let n = s[0].len();
    let nb = n.div_ceil(COMB_BLOCK);
    let block = |b: usize| {
        let (lo, hi) = (b * COMB_BLOCK, ((b + 1) * COMB_BLOCK).min(n));
        comb_block(s.map(|v| &v[lo..hi]))
    };
    ordered_map(nb, parallel, block).iter().sum()
}

/// Octaves of factor per band of [`comb_many`]'s sweep.
const BAND: usize = 16;
/// Blocks of the sweep's order per task (a task warms its window of
/// blocks once, so tasks are long).
const TASK: usize = 1024;

/// [`comb_sum`] for many averaging factors at once, OADEV's (`want[0]`,
/// `x_{j+2m} − 2x_{j+m} + x_j`) and OHDEV's (`want[1]`, the third
/// difference) sums, with the record read from memory a few times in
/// all, not a few times per factor and deviation.
///
/// Block b of factor m reads the windows of [`COMB_BLOCK`] samples at
/// `b + k·q` blocks (`q = m/COMB_BLOCK`, k = 0..3; both deviations from
/// the same loads, [`comb2_block`]), so a window is
/// read again by the same factor q blocks later and by the factors 2m,
/// 4m, … Factors go in bands of [`BAND`] octaves of q: band k (stride
/// `s = BAND^k` blocks, `s ≤ q < BAND·s`; band 0 also takes m below a
/// block) visits its blocks in residue order (`r, r + s, r + 2s, …` for
/// r = 0..s), so every window a block needs was read at most
/// `3·BAND` visits before, a window of about 50 blocks (800 kB) that
/// stays in the caches, and the band reads the record about once.
/// Each factor's blocks and their ordered sum are exactly those of
/// [`comb_sum`], so the numbers are the same bits; in parallel the visit
/// order is cut into tasks of [`TASK`] visits.
fn comb_many(x: &[f64], ms: &[usize], want: [bool; 2], mdev: &[bool], parallel: bool) -> Sweep {
    // Terms of each factor: Allan L − 2m, Hadamard L − 3m (0 if unwanted;
    // the Hadamard terms are also MDEV's slide steps).
    let md = |j: usize| mdev.get(j) == Some(&true);
    let terms: [Vec<usize>; 2] = [2, 3].map(|span| {
        (0..ms.len())
            .map(|j| {
                let m = ms[j];
                if m == 0 || !(want[span - 2] || (span == 3 && md(j))) {
                    0
                } else {
                    x.len().saturating_sub(span * m)
                }
            })
            .collect()
    });
    let blocks = |j: usize| terms[0][j].max(terms[1][j]).div_ceil(COMB_BLOCK);
    // Stride (blocks) of each factor's band.
    let stride = |m: usize| {
        let mut s = 1;
        while m / COMB_BLOCK >= BAND * s {
            s *= BAND;
        }
        s
    };
    let mut bands: Vec<(usize, Vec<usize>)> = Vec::new();
    for (j, &m) in ms.iter().enumerate().filter(|&(j, _)| blocks(j) > 0) {
        let s = stride(m);
        match bands.iter_mut().find(|(t, _)| *t == s) {
            Some((_, v)) => v.push(j),
            None => bands.push((s, vec![j])),
        }
    }
    // Blocks of each band (its largest count).
    let nbs: Vec<usize> = bands
        .iter()
        .map(|(_, js)| js.iter().map(|&j| blocks(j)).max().unwrap_or(0))
        .collect();
    // Tasks: (band, first visit, end visit) over each band's visit order.
    let mut tasks = Vec::new();
    for (bi, &nb) in nbs.iter().enumerate() {
        let mut v = 0;
        while v < nb {
            tasks.push((bi, v, (v + TASK).min(nb)));
            v += TASK;
        }
    }
    type Part = Vec<(usize, usize, Option<f64>, Option<f64>, Option<[f64; 3]>)>;
    let task = |&(bi, v0, v1): &(usize, usize, usize)| -> Part {
        let (s, js, nb) = (bands[bi].0, &bands[bi].1, nbs[bi]);
        let mut out = Vec::with_capacity((v1 - v0) * js.len());
        // Visits in residue order: residue r takes ceil((nb − r)/s)
        // visits, blocks r, r + s, r + 2s, …; residues below `extra` have
        // per + 1 visits, the rest per.
        let (per, extra) = (nb / s, nb % s);
        for v in v0..v1 {
            let big = extra * (per + 1);
            let (r, i) = if v < big {
                (v / (per + 1), v % (per + 1))
            } else {
                (extra + (v - big) / per.max(1), (v - big) % per.max(1))
            };
            let b = r + i * s;
            let lo = b * COMB_BLOCK;
            for &j in js {
                let m = ms[j];
                let [ha, hh] = [0, 1].map(|k| (lo + COMB_BLOCK).min(terms[k][j]));
                let w = |k: usize, hi: usize| &x[k * m + lo..k * m + hi];
                let (va, vh) = if want[1] && lo < ha && ha == hh {
                    let (va, vh) = comb2_block([w(3, hh), w(2, hh), w(1, hh), w(0, hh)]);
                    (Some(va), Some(vh))
                } else {
                    (
                        (lo < ha).then(|| comb_block([w(2, ha), w(1, ha), w(0, ha)])),
                        (want[1] && lo < hh)
                            .then(|| comb_block([w(3, hh), w(2, hh), w(1, hh), w(0, hh)])),
                    )
                };
                let md = (lo < hh && md(j))
                    .then(|| avx2_or_not!(mdev_stats([w(3, hh), w(2, hh), w(1, hh), w(0, hh)])));
                if va.is_some() || vh.is_some() || md.is_some() {
                    out.push((j, b, va, vh, md));
                }
            }
        }
        out
    };
    let parts: Vec<Part> = ordered_map(tasks.len(), parallel, |i| task(&tasks[i]));
    let mut table: [Vec<Vec<f64>>; 2] = [0, 1].map(|k| {
        terms[k]
            .iter()
            .map(|n| vec![0.0; n.div_ceil(COMB_BLOCK)])
            .collect()
    });
    let mut mtable: Vec<Vec<[f64; 3]>> = (0..ms.len())
        .map(|j| {
            let n = if md(j) { terms[1][j] } else { 0 };
            vec![[0.0; 3]; n.div_ceil(COMB_BLOCK)]
        })
        .collect();
    for (j, b, va, vh, md) in parts.into_iter().flatten() {
        if let Some(v) = va {
            table[0][j][b] = v;
        }
        if let Some(v) = vh {
            table[1][j][b] = v;
        }
        if let Some(v) = md {
            mtable[j][b] = v;
        }
    }
    let sums = [0, 1].map(|k| {
        table[k]
            .iter()
            .zip(&terms[k])
            .map(|(t, &n)| (n > 0 && want[k]).then(|| (t.iter().sum(), n)))
            .collect()
    });
    // MDEV: W_0 by its direct sum, then block by block in order
    // (`W_{j+1} = W_j + h_j`, the Hadamard terms h): the block adds
    // `n·W² + 2W·S1 + S2` and moves W on by its total.
    let modified = (0..ms.len())
        .map(|j| {
            let (m, nh) = (ms[j], terms[1][j]);
            // n = L + 1 − 3m terms (W_0 alone when L = 3m).
            (md(j) && m > 0 && x.len() >= 3 * m).then(|| {
                let mut w = lanes(0, m, |i| comb_term([x[i + 2 * m], x[i + m], x[i]]));
                let mut acc = w * w;
                for (b, &[t, s1, s2]) in mtable[j].iter().enumerate() {
                    let n = (nh - b * COMB_BLOCK).min(COMB_BLOCK) as f64;
                    acc += n * w * w + 2.0 * w * s1 + s2;
                    w += t;
                }
                (acc, nh + 1)
            })
        })
        .collect();
    Sweep { sums, modified }
}

/// What [`comb_many`] returns: the OADEV and OHDEV sums `(S, n)` per
/// factor, and the MDEV sums `(Σ W², n)` of the factors asked for.
struct Sweep {
    sums: [Vec<Option<(f64, usize)>>; 2],
    modified: Vec<Option<(f64, usize)>>,
}

/// One block's part of the MDEV sums from its Hadamard windows `s` (as
/// [`comb2_block`]): with `h_t` the block's terms (the MDEV slide's steps)
/// and `loc_t = Σ_{u≤t} h_u`, returns `[Σ h, Σ loc, Σ loc²]`, so that the
/// block adds `n·W² + 2W·Σloc + Σloc²` to `Σ W²` for W the inner sum
/// before it. The running sum goes as eight shorter ones in lanes (one
/// add chain would bound the loop); a block is short against m, so W hardly
/// moves along it and the expansion loses nothing to cancellation
/// (checked against the direct sums in the tests).
#[inline(always)]
fn mdev_stats(s: [&[f64]; 4]) -> [f64; 3] {
    const L: usize = LANES;
    let n = s[0].len();
    let h = |t: usize| comb_term(s.map(|v| v[t]));
    let r = n / L;
    let [loc, s1, s2] = lane_slides(r, h);
    let (mut o, mut a1, mut a2) = (0.0f64, 0.0f64, 0.0f64);
    for l in 0..L {
        a1 += r as f64 * o + s1[l];
        a2 += r as f64 * o * o + 2.0 * o * s1[l] + s2[l];
        o += loc[l];
    }
    for t in L * r..n {
        o += h(t);
        a1 += o;
        a2 += o * o;
    }
    [o, a1, a2]
}

/// [`oavar`] at every factor of `ms`: one block-major sweep (same bits as
/// [`oavar`]), or, for a dense grid (`taus all`) where the direct sums
/// would cost more than the transforms, the lagged products by FFT
/// ([`dense_sums`]).
pub fn oavar_many(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> Vec<Option<VarN>> {
    variances(&many_sums(x, ms, Kind::Allan, parallel), ms, tau0, 2.0)
}

/// [`ohvar`] at every factor of `ms`, as [`oavar_many`].
pub fn ohvar_many(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> Vec<Option<VarN>> {
    variances(&many_sums(x, ms, Kind::Hadamard, parallel), ms, tau0, 6.0)
}

/// `σ² = S / (c·m²τ0²·n)` from the sums `(S, n)` of each factor
/// (c = 2 Allan, 6 Hadamard).
fn variances(sums: &[Option<(f64, usize)>], ms: &[usize], tau0: f64, c: f64) -> Vec<Option<VarN>> {
    sums.iter()
        .zip(ms)
        .map(|(r, &m)| {
            r.map(|(s, n)| {
                let mt = m as f64 * tau0;
                VarN {
                    var: s / (c * mt * mt * n as f64),
                    n,
                }
            })
        })
        .collect()
}

/// The second (Allan) or third (Hadamard) difference at lag m.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Allan,
    Hadamard,
}

/// Largest estimated round-off of the FFT sums, relative to the sum,
/// that [`dense_sums`] accepts; past it the factor is summed directly.
pub const DENSE_TOL: f64 = 1e-9;

/// Direct sums cost over the transforms' cost at which [`many_sums`]
/// takes the FFT: about where they take the same time on this machine
/// (measured on 10⁵ samples).
const DENSE_RATIO: f64 = 60.0;

/// Per factor `(Σ_j (Σ_k w_k x_{j+km})², terms)` of the kind, by the
/// block-major direct sums or, when they would cost more than
/// [`DENSE_RATIO`]`·L·log₂L`, by [`dense_sums`].
fn many_sums(x: &[f64], ms: &[usize], kind: Kind, parallel: bool) -> Vec<Option<(f64, usize)>> {
    let span = match kind {
        Kind::Allan => 2,
        Kind::Hadamard => 3,
    };
    let l = x.len();
    if dense(l, ms, span) {
        let (mut out, refused) = dense_sums(x, ms, kind, DENSE_TOL, parallel);
        let redo: Vec<usize> = (0..ms.len()).filter(|&k| refused[k]).collect();
        let rm: Vec<usize> = redo.iter().map(|&k| ms[k]).collect();
        for (&k, v) in redo.iter().zip(direct_sums(x, &rm, kind, parallel)) {
            out[k] = v;
        }
        out
    } else {
        direct_sums(x, ms, kind, parallel)
    }
}

/// Whether the direct sums (`L − span·m` terms per factor) would cost
/// more than [`DENSE_RATIO`]`·L·log₂L`, where [`many_sums`] takes the FFT.
fn dense(l: usize, ms: &[usize], span: usize) -> bool {
    let direct: f64 = ms.iter().map(|&m| l.saturating_sub(span * m) as f64).sum();
    l > 1 && direct > DENSE_RATIO * l as f64 * (l as f64).log2()
}

fn direct_sums(x: &[f64], ms: &[usize], kind: Kind, parallel: bool) -> Vec<Option<(f64, usize)>> {
    let want = [kind == Kind::Allan, kind == Kind::Hadamard];
    let [a, h] = comb_many(x, ms, want, &[], parallel).sums;
    match kind {
        Kind::Allan => a,
        Kind::Hadamard => h,
    }
}

/// The sums of [`many_sums`] from lagged products of the whole record.
///
/// With `u` the record less its least-squares line (Allan) or parabola
/// (Hadamard), to which the differences are blind, and
/// `S(m) = Σ_{j<n} (Σ_k w_k u_{j+km})²`, `n = L − (K−1)m`, the square is
/// expanded: the squares are differences of the prefix sums of `u²`; each
/// cross term `Σ_{j<n} u_{j+km} u_{j+lm}` is the autocorrelation
/// `R((l−k)m)` less the products cut off at the ends of the record, which
/// are wedge sums (`super::corr::wedge`) of `u` and of `u` reversed:
///
/// * Allan (`w = 1, −2, 1`): `S = Σw²·squares − 4(R(m) − G₁'(m))
///   − 4(R(m) − G₁(m)) + 2R(2m)`;
/// * Hadamard (`w = −1, 3, −3, 1`): `S = Σw²·squares − 6(R(m) − G₂'(m))
///   − 18(R(m) − G₁'(m) − G₁(m)) − 6(R(m) − G₂(m))
///   + 6(R(2m) − G½'(2m)) + 6(R(2m) − G½(2m)) − 2R(3m)`,
///
/// `G_c(d) = Σ_{t<c·d} u_t u_{t+d}`, `'` on the reversed record. All of it
/// costs O(L log² L) for every m at once instead of O(L) per m.
///
/// Round-off: every FFT value carries about `4ε·log₂(n_FFT)·Σu²`, so S
/// carries `(Σ|w|)²` times that; a factor whose estimate exceeds `tol`
/// relative to S (short τ of a record with much random-walk FM) is summed
/// directly by the caller. Returns the sums (`None` where refused or
/// undefined) and which factors were refused. Same numbers serial or
/// parallel.
fn dense_sums(
    x: &[f64],
    ms: &[usize],
    kind: Kind,
    tol: f64,
    parallel: bool,
) -> (Vec<Option<(f64, usize)>>, Vec<bool>) {
    use super::corr::{autocorr, wedge};
    let l = x.len();
    let (span, deg) = match kind {
        Kind::Allan => (2, 1),
        Kind::Hadamard => (3, 2),
    };
    let terms = |m: usize| l.checked_sub(span * m).filter(|&n| n > 0 && m > 0);
    let mmax = ms
        .iter()
        .copied()
        .filter(|&m| terms(m).is_some())
        .max()
        .unwrap_or(0);
    let mut out: Vec<Option<(f64, usize)>> = vec![None; ms.len()];
    let mut slid = vec![false; ms.len()];
    if mmax == 0 {
        return (out, slid);
    }
    let u = detrend(x, deg);
    let ur: Vec<f64> = u.iter().rev().copied().collect();
    // The transforms, each independent (parallel = serial).
    type Job<'a> = Box<dyn Fn() -> Vec<f64> + Sync + Send + 'a>;
    let (u, ur) = (&u[..], &ur[..]);
    let mut jobs: Vec<Job> = vec![
        Box::new(move || autocorr(u, span * mmax)),
        Box::new(move || wedge(u, 1, 1, mmax)),
        Box::new(move || wedge(ur, 1, 1, mmax)),
    ];
    if kind == Kind::Hadamard {
        jobs.push(Box::new(move || wedge(u, 2, 1, mmax)));
        jobs.push(Box::new(move || wedge(ur, 2, 1, mmax)));
        jobs.push(Box::new(move || wedge(u, 1, 2, 2 * mmax)));
        jobs.push(Box::new(move || wedge(ur, 1, 2, 2 * mmax)));
    }
    let res: Vec<Vec<f64>> = ordered_map(jobs.len(), parallel, |i| jobs[i]());
    let r = &res[0];
    let (g1, g1r) = (&res[1], &res[2]);
    // Prefix sums of u².
    let mut q = Vec::with_capacity(l + 1);
    q.push(0.0);
    let mut acc = 0.0;
    for v in u {
        acc += v * v;
        q.push(acc);
    }
    let sq = |a: usize, n: usize| q[a + n] - q[a];
    let nfft = (l + span * mmax + 1).next_power_of_two() as f64;
    let wabs: f64 = match kind {
        Kind::Allan => 4.0,
        Kind::Hadamard => 8.0,
    };
    let err = 4.0 * f64::EPSILON * nfft.log2() * acc * wabs * wabs;
    let mut redo = Vec::new();
    for (k, &m) in ms.iter().enumerate() {
        let Some(n) = terms(m) else { continue };
        let s = match kind {
            Kind::Allan => {
                sq(0, n) + 4.0 * sq(m, n) + sq(2 * m, n)
                    - 4.0 * (r[m] - g1r[m])
                    - 4.0 * (r[m] - g1[m])
                    + 2.0 * r[2 * m]
            }
            Kind::Hadamard => {
                let (g2, g2r, gh, ghr) = (&res[3], &res[4], &res[5], &res[6]);
                sq(0, n) + 9.0 * sq(m, n) + 9.0 * sq(2 * m, n) + sq(3 * m, n)
                    - 6.0 * (r[m] - g2r[m])
                    - 18.0 * (r[m] - g1r[m] - g1[m])
                    - 6.0 * (r[m] - g2[m])
                    + 6.0 * (r[2 * m] - ghr[2 * m])
                    + 6.0 * (r[2 * m] - gh[2 * m])
                    - 2.0 * r[3 * m]
            }
        };
        if s > 0.0 && err <= tol * s {
            out[k] = Some((s, n));
        } else {
            redo.push(k);
        }
    }
    for k in redo {
        slid[k] = true;
    }
    (out, slid)
}

/// `x` less its least-squares polynomial of degree `deg` (1 or 2) in the
/// sample index (scaled to [−1, 1] for conditioning).
pub(crate) fn detrend(x: &[f64], deg: usize) -> Vec<f64> {
    use nalgebra::{Matrix3, Vector3};
    let n = x.len();
    if n <= deg + 1 {
        return x.to_vec();
    }
    let c = (n as f64 - 1.0) / 2.0;
    let basis = |i: usize| {
        let t = (i as f64 - c) / c;
        Vector3::new(1.0, t, if deg >= 2 { t * t } else { 0.0 })
    };
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for (i, &v) in x.iter().enumerate() {
        let p = basis(i);
        a += p * p.transpose();
        b += p * v;
    }
    if deg < 2 {
        a[(2, 2)] = 1.0;
    }
    let coef = a
        .try_inverse()
        .map(|ai| ai * b)
        .unwrap_or_else(Vector3::zeros);
    x.iter()
        .enumerate()
        .map(|(i, &v)| v - coef.dot(&basis(i)))
        .collect()
}

/// A variance and the number of terms behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VarN {
    /// The variance σ²(τ) (unit² of x/τ).
    pub var: f64,
    /// Number of terms summed.
    pub n: usize,
}

/// Overlapping Allan variance, SP 1065 eq. (14):
/// `σ²(τ) = Σ_{i=0}^{N−2m−1} (x_{i+2m} − 2x_{i+m} + x_i)² / (2 m² τ0² (N − 2m))`.
/// `None` when `N < 2m + 1`.
pub fn oavar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    let n = x.len().checked_sub(2 * m).filter(|&n| n > 0 && m > 0)?;
    let s = comb_sum([&x[2 * m..2 * m + n], &x[m..m + n], &x[..n]], parallel);
    let mt = m as f64 * tau0;
    Some(VarN {
        var: s / (2.0 * mt * mt * n as f64),
        n,
    })
}

/// Overlapping Hadamard variance, SP 1065 eq. (22):
/// `σ²(τ) = Σ_{i=0}^{N−3m−1} (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)² / (6 m² τ0² (N − 3m))`.
pub fn ohvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    let n = x.len().checked_sub(3 * m).filter(|&n| n > 0 && m > 0)?;
    let s = comb_sum(
        [
            &x[3 * m..3 * m + n],
            &x[2 * m..2 * m + n],
            &x[m..m + n],
            &x[..n],
        ],
        parallel,
    );
    let mt = m as f64 * tau0;
    Some(VarN {
        var: s / (6.0 * mt * mt * n as f64),
        n,
    })
}

/// Modified Allan variance, SP 1065 eq. (15):
/// `Mod σ²(τ) = Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))² / (2 m⁴ τ0² (N − 3m + 1))`.
///
/// The inner sums slide (`W_{j+1} = W_j + d_{j+1}`,
/// `d_j = x_{j+3m−1} − 3x_{j+2m−1} + 3x_{j+m−1} − x_{j−1}`) inside blocks
/// of at least 8m terms, eight slides in vector lanes per block
/// ([`mvar_block`]); every block starts from a direct sum, so round-off
/// cannot build up along the record and the blocks are independent.
pub fn mvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    let nt = (x.len() + 1)
        .checked_sub(3 * m)
        .filter(|&n| n > 0 && m > 0)?;
    let blen = BLOCK.max(8 * m);
    let nb = nt.div_ceil(blen);
    let block = |b: usize| -> f64 {
        let lo = b * blen;
        mvar_block(x, m, lo, (lo + blen).min(nt))
    };
    let sums = ordered_map(nb, parallel, block);
    Some(mvar_of(sums.iter().sum(), nt, m, tau0))
}

/// `Σ_{j=lo}^{hi−1} W_j²`, `W_j = Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i)`
/// (the MDEV inner sums, [`mvar`]).
///
/// One direct sum starts the block; then the steps `d_j` of a chunk of
/// [`MVAR_CHUNK`] positions go to a buffer (four streams, vectorised) and
/// the chunk's slide runs as eight shorter slides in lanes (one slide's
/// add chain would bound the loop): lane l slides `loc` from zero,
/// `W = off_l + loc`, keeping `Σ loc` and `Σ loc²`, so its
/// `Σ W² = n·off_l² + 2·off_l·Σ loc + Σ loc²` once `off_l` (the previous
/// lane's last W plus one step) is known. A lane is short against m, so
/// W hardly moves along it and the expansion loses nothing to
/// cancellation (checked against the direct sums in the tests).
fn mvar_block(x: &[f64], m: usize, lo: usize, hi: usize) -> f64 {
    const L: usize = LANES;
    const R: usize = MVAR_CHUNK / L;
    // The direct start, in eight lanes (it streams, it does not chain).
    let mut w = lanes(lo, lo + m, |i| comb_term([x[i + 2 * m], x[i + m], x[i]]));
    let mut acc = w * w;
    // Positions lo+1.. step from the previous W by d_j.
    let mut j0 = lo + 1;
    while j0 < hi {
        let n = (hi - j0).min(MVAR_CHUNK);
        let st = |k: usize| &x[j0 + k * m - 1..j0 + k * m - 1 + n];
        let (a, b, c, e) = (st(0), st(1), st(2), st(3));
        let step = |k: usize| comb_term([e[k], c[k], b[k], a[k]]);
        if n == MVAR_CHUNK {
            // Lane l takes positions l·R.. of the chunk.
            let [loc, s1, s2] = lane_slides(R, step);
            // Lane l's first W is the last W plus its first step, which
            // its own loc already holds: off_l is the W before the lane.
            for l in 0..L {
                acc += R as f64 * w * w + 2.0 * w * s1[l] + s2[l];
                w += loc[l];
            }
        } else {
            for k in 0..n {
                w += step(k);
                acc += w * w;
            }
        }
        j0 += n;
    }
    acc
}

/// Positions per chunk of [`mvar_block`]'s slides.
const MVAR_CHUNK: usize = 2048;

/// Lanes of [`lane_slides`].
const LANES: usize = 8;

/// Eight running sums in lanes over the steps `step(0..8r)`: lane l
/// slides `loc` from zero over steps `l·r .. (l+1)·r` and returns its
/// `[loc, Σ loc, Σ loc²]` per lane ([`mvar_block`] and [`mdev_stats`]
/// join the lanes). The steps go to a transposed buffer first (row t holds
/// every lane's step t), so the slides run as one vector of eight lanes
/// (one slide's add chain would bound the loop). `r ≤ MVAR_CHUNK / 8`.
#[inline(always)]
fn lane_slides(r: usize, step: impl Fn(usize) -> f64) -> [[f64; LANES]; 3] {
    const L: usize = LANES;
    const _: () = assert!(COMB_BLOCK <= MVAR_CHUNK);
    debug_assert!(r <= MVAR_CHUNK / L);
    // Not zeroed first (16 kB per call, about 5 % of MDEV's time at
    // 10⁷): rows below r are written whole before they are read.
    let mut buf = [[MaybeUninit::<f64>::uninit(); L]; MVAR_CHUNK / L];
    for l in 0..L {
        for (t, row) in buf[..r].iter_mut().enumerate() {
            row[l].write(step(l * r + t));
        }
    }
    let (mut loc, mut s1, mut s2) = ([0.0f64; L], [0.0f64; L], [0.0f64; L]);
    for row in &buf[..r] {
        for l in 0..L {
            // SAFETY: every lane of the rows below r was written above.
            loc[l] += unsafe { row[l].assume_init() };
            s1[l] += loc[l];
            s2[l] += loc[l] * loc[l];
        }
    }
    [loc, s1, s2]
}

/// Superblock sizes (terms) of [`mvar_many`], smallest first; factor m
/// goes to the first with `3m ≤ R`. Small m take short superblocks, whose
/// prefix sums stay small (their round-off is what limits small m). All
/// run in one pass over the record (the short superblocks of a long one
/// while its samples are in cache).
const MVAR_GROUPS: [usize; 3] = [1 << 11, BLOCK, 1 << 17];

/// Largest estimated round-off, relative to the variance, that
/// [`mvar_many`] accepts from its prefix sums; past it the factor is
/// summed by [`mvar`]'s slides.
pub const MVAR_TOL: f64 = 1e-9;

/// [`mvar`] at every factor of `ms`, by prefix sums shared across factors.
///
/// With `P_k = Σ_{i<k} x_i` the inner sum is a third difference,
/// `W_j = P_{j+3m} − 3P_{j+2m} + 3P_{j+m} − P_j`, so once `P` is built
/// every m costs four loads per term, vectorized and block-major over the
/// factors as [`oavar_many`] (the slides of [`mvar`] run a dependent add
/// per term, one m at a time). `P` is built per superblock of R terms
/// (`R` from [`MVAR_GROUPS`], `3m ≤ R`) over `R + 3m` samples, of
/// `x_k − x_r − b(k − r)` (the line through the superblock's ends removed:
/// W is blind to a line in x), so it stays small and the buffer is at most
/// 2R values per thread, never a second copy of the record.
///
/// Round-off: the differences of P cancel. Each W carries about
/// `δ = ε·P_rms·(√(2m) + 4)` (the rounding of the m adds between two of
/// its points, growing as √m, Higham & Mary 2019, and of the four values);
/// the relative error of the variance is then about
/// `20·(δ/W_rms)·√(3m/n) + (δ/W_rms)²` (the cross term averages over the
/// `n/3m` independent windows; factor 20 for safety, checked against the
/// slides in the tests). A factor whose estimate exceeds [`MVAR_TOL`]
/// (random-walk FM dominating the short τ of a long record) is summed
/// again by [`mvar`]. Same numbers serial or parallel.
pub fn mvar_many(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> Vec<Option<VarN>> {
    // The Hadamard kernel runs on P, one value longer than x.
    let l = x.len() + 1;
    if l < 3 || !dense(l, ms, 3) {
        // A sparse grid: the factors past the prefix superblocks from the
        // Hadamard sweep ([`comb_many`]: its terms are their slide steps),
        // the others by the superblocks.
        let big: Vec<bool> = ms.iter().map(|&m| past_superblocks(m)).collect();
        if !big.contains(&true) {
            return mvar_many_tol(x, ms, tau0, parallel, MVAR_TOL).0;
        }
        let sw = comb_many(x, ms, [false, false], &big, parallel);
        return mvar_merge(x, ms, tau0, parallel, &big, &sw.modified);
    }
    // A dense grid: the Hadamard sums of P by FFT ([`dense_sums`]; the
    // whole P is one more copy of the record, which a grid this dense
    // only meets on short records), the refused factors as above.
    let mut p = Vec::with_capacity(l);
    p.push(0.0);
    let mut acc = 0.0;
    for v in x {
        acc += v;
        p.push(acc);
    }
    let (sums, refused) = dense_sums(&p, ms, Kind::Hadamard, DENSE_TOL, parallel);
    drop(p);
    // The refused factors (short τ) again by blocks of the record, each
    // with its own prefix, far smaller than the whole record's; what they
    // refuse too is summed directly.
    let rm: Vec<usize> = (0..ms.len())
        .filter(|&k| refused[k])
        .map(|k| ms[k])
        .collect();
    let mut got: Vec<Option<VarN>> = vec![None; rm.len()];
    // One round: a second, with blocks sized for the factors still
    // refused, cost more in transforms than it saved (measured).
    let (bsums, brefused) = dense_blocks(x, &rm, parallel);
    let mut left = Vec::new();
    for (k, (v, r)) in bsums.into_iter().zip(brefused).enumerate() {
        if r {
            left.push(k);
        } else {
            got[k] = v.map(|(s, n)| mvar_of(s, n, rm[k], tau0));
        }
    }
    let fs: Vec<usize> = left.iter().map(|&k| rm[k]).collect();
    for (&k, v) in left
        .iter()
        .zip(mvar_many_tol(x, &fs, tau0, parallel, MVAR_TOL).0)
    {
        got[k] = v;
    }
    let mut redone = got.into_iter();
    sums.into_iter()
        .zip(ms)
        .zip(refused)
        .map(|((v, &m), r)| {
            if r {
                return redone.next().flatten();
            }
            v.map(|(s, n)| mvar_of(s, n, m, tau0))
        })
        .collect()
}

/// `Σ W²` (and the number of terms) of MDEV at the factors `ms` by
/// [`dense_sums`] over blocks of the record: block k's terms
/// `[lo, lo + B)` are the dense sums over the P slice `[lo, lo + B + 3M)`
/// (M the largest factor) less those over `[lo + B, lo + B + 3M)` (its
/// terms past the block), each slice with its own prefix of x less the
/// slice's end-to-end line (W is blind to it), so the prefix and with it
/// the transforms' round-off stay small: the round-off scales as the
/// slice's `Σ u²`, about `L³` against the whole record's `N³`. A factor
/// is refused (second value) when any block's estimate exceeds a quarter
/// of [`DENSE_TOL`] (the two sums of a block are within a factor of
/// about two of their difference for `B ≥ 3M`). Same numbers serial or
/// parallel (fixed blocks, sums added in block order).
fn dense_blocks(x: &[f64], ms: &[usize], parallel: bool) -> (Vec<Option<(f64, usize)>>, Vec<bool>) {
    let l = x.len() + 1;
    let Some(&mmax) = ms.iter().max() else {
        return (Vec::new(), Vec::new());
    };
    let span = 3 * mmax;
    let b = (4 * span).max(1 << 13);
    type Part = (Vec<Option<(f64, usize)>>, Vec<bool>);
    let sums = |lo: usize, hi: usize| -> Part {
        let mut buf = Vec::new();
        local_prefix(&x[lo..hi - 1], &mut buf);
        dense_sums(&buf[..hi - lo], ms, Kind::Hadamard, DENSE_TOL / 4.0, false)
    };
    let part = |k: usize| -> [Part; 2] {
        let lo = k * b;
        let hi = (lo + b + span).min(l);
        let rest = if lo + b < hi {
            sums(lo + b, hi)
        } else {
            (vec![None; ms.len()], vec![false; ms.len()])
        };
        [sums(lo, hi), rest]
    };
    let parts = ordered_map(l.div_ceil(b), parallel, part);
    let mut out = vec![Some((0.0, 0usize)); ms.len()];
    let mut refused = vec![false; ms.len()];
    for [(s1, r1), (s2, r2)] in parts {
        for j in 0..ms.len() {
            refused[j] |= r1[j] || r2[j];
            if refused[j] {
                // A refused sum is not returned: nothing to add.
                continue;
            }
            let (a, na) = s1[j].unwrap_or((0.0, 0));
            let (c, nc) = s2[j].unwrap_or((0.0, 0));
            if let Some((s, n)) = &mut out[j] {
                *s += a - c;
                *n += na - nc;
            }
        }
    }
    // Every term counted once, or the factor goes to the direct sums.
    for ((o, r), &m) in out.iter_mut().zip(&mut refused).zip(ms) {
        match *o {
            Some((_, 0)) => *o = None,
            Some((_, n)) if n != l.saturating_sub(3 * m) => *r = true,
            _ => {}
        }
    }
    (out, refused)
}

/// The MDEV variance from the sum `s = Σ W²` of `n` inner sums at factor
/// m (SP 1065 eq. 14): `s / (2 m⁴ τ0² n)`.
fn mvar_of(s: f64, n: usize, m: usize, tau0: f64) -> VarN {
    let mf = m as f64;
    VarN {
        var: s / (2.0 * mf.powi(4) * tau0 * tau0 * n as f64),
        n,
    }
}

/// Whether factor m is too large for [`mvar_many_tol`]'s prefix
/// superblocks (`3m` past the largest), so that its inner sum would slide.
fn past_superblocks(m: usize) -> bool {
    3 * m > MVAR_GROUPS[MVAR_GROUPS.len() - 1]
}

/// MDEV at every factor of `ms`: those marked `big` from the sums
/// `modified` of a [`comb_many`] sweep, the others by
/// [`mvar_many_tol`].
fn mvar_merge(
    x: &[f64],
    ms: &[usize],
    tau0: f64,
    parallel: bool,
    big: &[bool],
    modified: &[Option<(f64, usize)>],
) -> Vec<Option<VarN>> {
    let small: Vec<usize> = (0..ms.len()).filter(|&j| !big[j]).map(|j| ms[j]).collect();
    let mut rest = mvar_many_tol(x, &small, tau0, parallel, MVAR_TOL)
        .0
        .into_iter();
    (0..ms.len())
        .map(|j| {
            if big[j] {
                modified[j].map(|(s, n)| mvar_of(s, n, ms[j], tau0))
            } else {
                rest.next().flatten()
            }
        })
        .collect()
}

/// [`mvar_many`] with the round-off tolerance given; also says which
/// factors were summed again by [`mvar`] (the tests check the estimate
/// against the slides with `tol = ∞`).
pub(crate) fn mvar_many_tol(
    x: &[f64],
    ms: &[usize],
    tau0: f64,
    parallel: bool,
    tol: f64,
) -> (Vec<Option<VarN>>, Vec<bool>) {
    let nx = x.len();
    let terms = |m: usize| (nx + 1).checked_sub(3 * m).filter(|&n| n > 0 && m > 0);
    let mut out: Vec<Option<VarN>> = vec![None; ms.len()];
    let mut slid = vec![false; ms.len()];
    // Indices of ms per group; the rest (3m > the largest R) slide.
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); MVAR_GROUPS.len()];
    let mut rest = Vec::new();
    for k in (0..ms.len()).filter(|&k| terms(ms[k]).is_some()) {
        match MVAR_GROUPS.iter().position(|&r| 3 * ms[k] <= r) {
            Some(g) => groups[g].push(k),
            None => rest.push(k),
        }
    }
    // Every group in one pass, the largest superblocks outermost.
    let order = [2, 1, 0];
    let levels: Vec<(usize, Vec<usize>)> = order
        .iter()
        .map(|&g| (MVAR_GROUPS[g], groups[g].iter().map(|&k| ms[k]).collect()))
        .collect();
    for (res, g) in mvar_levels(x, &levels, parallel).into_iter().zip(order) {
        for (&k, (s, prms)) in groups[g].iter().zip(res) {
            let m = ms[k];
            let n = terms(m).unwrap_or(0);
            let (mf, nf) = (m as f64, n as f64);
            let rms = (s / nf).sqrt();
            let d = f64::EPSILON * prms * ((2.0 * mf).sqrt() + 4.0) / rms;
            let rel = 20.0 * d * (3.0 * mf / nf).min(1.0).sqrt() + d * d;
            out[k] = if rel.is_finite() && rel <= tol {
                Some(mvar_of(s, n, m, tau0))
            } else {
                slid[k] = true;
                mvar(x, m, tau0, parallel)
            };
        }
    }
    // The largest factors have few blocks each: in parallel over factors
    // too (each factor's numbers are the same either way).
    let slides = ordered_map(rest.len(), parallel, |i| {
        mvar(x, ms[rest[i]], tau0, parallel)
    });
    for (k, v) in rest.into_iter().zip(slides) {
        slid[k] = true;
        out[k] = v;
    }
    (out, slid)
}

/// The levels of one pass of [`mvar_many`]: `(R, factors)`, the first R
/// a multiple of the others. The record goes in superblocks of the first
/// R, in parallel (with the factors dealt round-robin into chunks when
/// the superblocks are too few for the cores, each chunk a task that
/// builds its own prefix); inside one, every level's superblocks in order, each
/// with its own prefix sums, every factor of the level over it in
/// sub-blocks of [`BLOCK`] terms. Returns per level and factor the sum of
/// `W_j²` (sub-block sums added in order) and the largest rms of P.
fn mvar_levels(x: &[f64], levels: &[(usize, Vec<usize>)], parallel: bool) -> Vec<Vec<(f64, f64)>> {
    let nx = x.len();
    let outer = levels[0].0;
    let nt = |m: usize| nx + 1 - 3 * m;
    let span = levels
        .iter()
        .flat_map(|(_, ms)| ms.iter().map(|&m| nt(m)))
        .max()
        .unwrap_or(0);
    // Per level, per factor: the sub-block sums and the largest P rms.
    type Part = Vec<Vec<(Vec<f64>, f64)>>;
    let nsb = span.div_ceil(outer);
    // Chunks of factors: enough tasks for the cores when the record is
    // short (a fixed number, so the split is the same serial or parallel).
    let nfac = levels.iter().map(|(_, ms)| ms.len()).sum::<usize>();
    let nch = if nsb >= 8 {
        1
    } else {
        (16 / nsb.max(1)).min(nfac.div_ceil(4)).max(1)
    };
    let task = |t: usize, buf: &mut Vec<f64>| -> Part {
        let (s, c) = (t / nch, t % nch);
        levels
            .iter()
            .map(|(r, ms)| {
                let mut acc: Vec<(Vec<f64>, f64)> = vec![(Vec::new(), 0.0); ms.len()];
                let mine: Vec<usize> = (c..ms.len()).step_by(nch).map(|k| ms[k]).collect();
                let mut got: Vec<(Vec<f64>, f64)> = vec![(Vec::new(), 0.0); mine.len()];
                let mmax = mine.iter().copied().max().unwrap_or(0);
                let lim = mine.iter().map(|&m| nt(m)).max().unwrap_or(0);
                let mut lo = s * outer;
                while lo < ((s + 1) * outer).min(lim) {
                    superblock(x, lo, *r, mmax, &mine, buf, &mut got);
                    lo += r;
                }
                for (k, g) in (c..ms.len()).step_by(nch).zip(got) {
                    acc[k] = g;
                }
                acc
            })
            .collect()
    };
    let parts: Vec<Part> = if parallel && nsb * nch > 1 {
        (0..nsb * nch)
            .into_par_iter()
            .map_init(Vec::new, |buf, t| task(t, buf))
            .collect()
    } else {
        let mut buf = Vec::new();
        (0..nsb * nch).map(|t| task(t, &mut buf)).collect()
    };
    levels
        .iter()
        .enumerate()
        .map(|(l, (_, ms))| {
            (0..ms.len())
                .map(|k| {
                    let (mut s, mut prms) = (0.0, 0.0f64);
                    for p in &parts {
                        let (v, pr) = &p[l][k];
                        if !v.is_empty() {
                            s += v.iter().sum::<f64>();
                            prms = prms.max(*pr);
                        }
                    }
                    (s, prms)
                })
                .collect()
        })
        .collect()
}

/// One superblock `[lo, lo + r)` of terms of [`mvar_levels`]: its prefix
/// sums over the samples it needs, then, sub-block-major (the factors'
/// windows near a sub-block share the cache), each factor's sub-block
/// sums of `W_j²` pushed onto `acc` with the P rms.
fn superblock(
    x: &[f64],
    lo: usize,
    r: usize,
    mmax: usize,
    ms: &[usize],
    buf: &mut Vec<f64>,
    acc: &mut [(Vec<f64>, f64)],
) {
    let nx = x.len();
    // Terms j < lo + r need P up to j + 3m, i.e. samples below lo + r + 3m.
    let end = (lo + r + 3 * mmax).min(nx);
    let prms = local_prefix(&x[lo..end], buf);
    let mut a = lo;
    while a < lo + r {
        let b = (a + BLOCK).min(lo + r);
        for (&m, (v, pr)) in ms.iter().zip(acc.iter_mut()) {
            let hi = b.min(nx + 1 - 3 * m);
            if a < hi {
                let (ja, jb) = (a - lo, hi - lo);
                v.push(comb_block(
                    [3, 2, 1, 0].map(|k| &buf[ja + k * m..jb + k * m]),
                ));
                *pr = pr.max(prms);
            }
        }
        a = b;
    }
}

/// `buf[t] = Σ_{i<t} (v_i − v_0 − b·i)` for `t = 0..=v.len()`, `b` the
/// slope of the line through `v`'s ends; returns the rms of `buf`. Four
/// independent running sums over the four quarters (one add chain per
/// value would bound the loop), the quarters' offsets added after.
fn local_prefix(v: &[f64], buf: &mut Vec<f64>) -> f64 {
    let n = v.len();
    // Every value below n + 1 is written here: grow the buffer only when
    // needed (zeroing it per superblock was 8% of MDEV's time).
    if buf.len() < n + 1 {
        buf.resize(n + 1, 0.0);
    }
    buf[0] = 0.0;
    if n == 0 {
        return 0.0;
    }
    let b = if n > 1 {
        (v[n - 1] - v[0]) / (n - 1) as f64
    } else {
        0.0
    };
    let q = n / 4;
    // Quarter l sums v_i − (v_0 + b·l·q) − b·t, t = i − l·q.
    let c: [f64; 4] = std::array::from_fn(|l| v[0] + b * (l * q) as f64);
    let mut acc = [0.0f64; 4];
    {
        let (out, v) = (&mut buf[1..], v);
        let (o0, r) = out.split_at_mut(q);
        let (o1, r) = r.split_at_mut(q);
        let (o2, o3) = r.split_at_mut(q);
        let (v0, r) = v.split_at(q);
        let (v1, r) = r.split_at(q);
        let (v2, v3) = r.split_at(q);
        let mut tf = 0.0;
        for t in 0..q {
            let bt = b * tf;
            tf += 1.0;
            acc[0] += v0[t] - c[0] - bt;
            acc[1] += v1[t] - c[1] - bt;
            acc[2] += v2[t] - c[2] - bt;
            acc[3] += v3[t] - c[3] - bt;
            o0[t] = acc[0];
            o1[t] = acc[1];
            o2[t] = acc[2];
            o3[t] = acc[3];
        }
        // The tail after the fourth quarter continues the fourth chain.
        for t in q..v3.len() {
            acc[3] += v3[t] - c[3] - b * t as f64;
            o3[t] = acc[3];
        }
    }
    // Quarter l's values are relative to its start, buf[l·q]: add the
    // offsets, and take Σ P² on the way (eight lanes).
    let mut ss = [0.0f64; 8];
    let mut off = 0.0;
    for l in 0..4 {
        let stop = if l == 3 { n } else { (l + 1) * q };
        let seg = &mut buf[l * q + 1..=stop];
        let mut it = seg.chunks_exact_mut(8);
        for ch in &mut it {
            for k in 0..8 {
                ch[k] += off;
                ss[k] += ch[k] * ch[k];
            }
        }
        for (k, y) in it.into_remainder().iter_mut().enumerate() {
            *y += off;
            ss[k] += *y * *y;
        }
        off = buf[stop];
    }
    (ss.iter().sum::<f64>() / (n + 1) as f64).sqrt()
}

/// Time variance from the modified Allan variance, SP 1065 eq. (17):
/// `σ_x²(τ) = (τ²/3) Mod σ²(τ)` (unit² of x).
pub fn tvar(mvar: f64, tau: f64) -> f64 {
    tau * tau / 3.0 * mvar
}

/// Total variance, SP 1065 eq. (25), with the record extended by
/// reflection about both end points (`x*_{−j} = 2x_0 − x_j`,
/// `x*_{N−1+j} = 2x_{N−1} − x_{N−1−j}`):
/// `Tot σ²(τ) = Σ_{i=1}^{N−2} (x*_{i−m} − 2x*_i + x*_{i+m})² / (2 m² τ0² (N − 2))`.
/// Defined for `m ≤ N − 2`.
pub fn totvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    totvar_with(x, m, tau0, |lo, len| {
        comb_sum(
            [
                &x[lo + m..lo + m + len],
                &x[lo..lo + len],
                &x[lo - m..lo - m + len],
            ],
            parallel,
        )
    })
}

/// [`oavar_many`] and [`totvar`] at every factor of `ms`. The centres of
/// TOTDEV with both neighbours inside the record (`m ≤ i ≤ N−1−m`) are the
/// N − 2m terms of the OADEV sum, the same terms in the same blocks, so
/// TOTDEV only adds its 2(m − 1) reflected edge terms to the OADEV sum
/// (O(m) per factor instead of O(N)).
pub fn oavar_totvar_many(
    x: &[f64],
    ms: &[usize],
    tau0: f64,
    parallel: bool,
) -> (Vec<Option<VarN>>, Vec<Option<VarN>>) {
    let sums = many_sums(x, ms, Kind::Allan, parallel);
    let tot = totvar_from(x, ms, tau0, parallel, &sums);
    (variances(&sums, ms, tau0, 2.0), tot)
}

/// OADEV, OHDEV, TOTDEV and MDEV variances at every factor of `ms`, as
/// [`oavar_many`], [`ohvar_many`], [`oavar_totvar_many`] and [`mvar_many`]
/// give them, sharing the work: on a sparse grid one sweep
/// ([`comb_many`]) gives OADEV's and OHDEV's sums (the same bits as apart)
/// and the MDEV sums of the factors too large for [`mvar_many`]'s prefix
/// superblocks, whose slide steps are exactly OHDEV's terms (instead of
/// [`mvar`]'s slides, four more streams over the record per factor);
/// TOTDEV from the OADEV sums. Same numbers serial or parallel.
pub fn stability_vars(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> StabilityVars {
    let (a, h, mdev) = if dense(x.len(), ms, 2) || dense(x.len(), ms, 3) {
        let [a, h] = [Kind::Allan, Kind::Hadamard].map(|k| many_sums(x, ms, k, parallel));
        (a, h, mvar_many(x, ms, tau0, parallel))
    } else {
        let big: Vec<bool> = ms.iter().map(|&m| past_superblocks(m)).collect();
        let sw = comb_many(x, ms, [true, true], &big, parallel);
        let mdev = mvar_merge(x, ms, tau0, parallel, &big, &sw.modified);
        let [a, h] = sw.sums;
        (a, h, mdev)
    };
    StabilityVars {
        tot: totvar_from(x, ms, tau0, parallel, &a),
        oa: variances(&a, ms, tau0, 2.0),
        oh: variances(&h, ms, tau0, 6.0),
        md: mdev,
    }
}

/// The variances of [`stability_vars`], per factor.
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityVars {
    /// Overlapping Allan.
    pub oa: Vec<Option<VarN>>,
    /// Overlapping Hadamard.
    pub oh: Vec<Option<VarN>>,
    /// Total.
    pub tot: Vec<Option<VarN>>,
    /// Modified Allan.
    pub md: Vec<Option<VarN>>,
}

/// TOTDEV at every factor from the OADEV sums `(S, n)` (its interior
/// terms), adding the reflected edge terms.
fn totvar_from(
    x: &[f64],
    ms: &[usize],
    tau0: f64,
    parallel: bool,
    sums: &[Option<(f64, usize)>],
) -> Vec<Option<VarN>> {
    let one = |(r, &m): (&Option<(f64, usize)>, &usize)| match r {
        Some((s, n)) => totvar_with(x, m, tau0, |lo, len| {
            debug_assert!(lo == m && len == *n);
            *s
        }),
        None => totvar(x, m, tau0, parallel),
    };
    // Factors independent: in parallel on dense grids (same numbers).
    ordered_map(ms.len(), parallel, |k| one((&sums[k], &ms[k])))
}

/// `Σ_{i=a}^{b−1} f(i)` in eight lane accumulators, lanes added in a
/// fixed order.
#[inline]
fn lanes(a: usize, b: usize, f: impl Fn(usize) -> f64) -> f64 {
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

/// [`totvar`] with the sum over the interior centres `lo..lo+len` (both
/// neighbours inside the record) given by `interior(lo, len)`.
fn totvar_with(
    x: &[f64],
    m: usize,
    tau0: f64,
    interior: impl FnOnce(usize, usize) -> f64,
) -> Option<VarN> {
    let nx = x.len();
    if m == 0 || nx < 3 || m > nx - 2 {
        return None;
    }
    let last = nx - 1;
    let xs = |k: isize| -> f64 {
        if k < 0 {
            2.0 * x[0] - x[(-k) as usize]
        } else if k as usize > last {
            2.0 * x[last] - x[2 * last - k as usize]
        } else {
            x[k as usize]
        }
    };
    let nt = nx - 2;
    let mi = m as isize;
    let term = |i: usize| {
        let i = i as isize;
        let v = xs(i - mi) - 2.0 * xs(i) + xs(i + mi);
        v * v
    };
    // Centres i = 1..=N−2; those with both neighbours inside the record
    // (m ≤ i ≤ N−1−m) run on the vectorized kernel, the reflected edges
    // one by one.
    let (lo, hi) = (m.max(1), (nx - 1 - m).min(nx - 2));
    let mut s = 0.0;
    if lo <= hi {
        // Left edge, i < m: x*_{i−m} = 2x_0 − x_{m−i}; right edge,
        // i > N−1−m: x*_{i+m} = 2x_{N−1} − x_{2(N−1)−i−m}. Straight
        // loops (no reflection test per term), eight lanes.
        // The comb term in the interior's order ([`comb_term`]).
        let left = |i: usize| {
            let v = comb_term([x[i + m], x[i], 2.0 * x[0] - x[m - i]]);
            v * v
        };
        let right = |i: usize| {
            let v = comb_term([2.0 * x[last] - x[2 * last - i - m], x[i], x[i - m]]);
            v * v
        };
        s += lanes(1, lo, left);
        s += interior(lo, hi - lo + 1);
        s += lanes(hi + 1, nx - 1, right);
    } else {
        for i in 1..=nx - 2 {
            s += term(i);
        }
    }
    let mt = m as f64 * tau0;
    Some(VarN {
        var: s / (2.0 * mt * mt * nt as f64),
        n: nt,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic uniform numbers in [−½, ½) (a 64-bit LCG).
    /// White FM (x a random walk, with `trend` added per step) and
    /// random-walk FM (x the double sum of white noise, plus white phase
    /// noise of amplitude `jitter` when not zero) phases of n + 1 samples,
    /// the draws of each step in that order.
    fn fm_phases(seed: u64, n: usize, trend: f64, jitter: f64) -> (Vec<f64>, Vec<f64>) {
        let mut u = uniform(seed);
        let (mut y, mut xw, mut xr) = (0.0, vec![0.0], vec![0.0]);
        for i in 0..n {
            y += u();
            let j = if jitter != 0.0 { jitter * u() } else { 0.0 };
            xr.push(xr[i] + y + j);
            xw.push(xw[i] + u() + trend);
        }
        (xw, xr)
    }

    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    fn data(n: usize) -> Vec<f64> {
        // A deterministic random walk with a trend.
        let mut u = uniform(12345);
        let mut x = vec![0.0];
        for i in 1..n {
            x.push(x[i - 1] + u() + 0.01);
        }
        x
    }

    fn naive(x: &[f64], m: usize) -> [f64; 4] {
        let n = x.len();
        let d2 = |i: usize| x[i + 2 * m] - 2.0 * x[i + m] + x[i];
        let oa: f64 = (0..n - 2 * m).map(|i| d2(i).powi(2)).sum::<f64>()
            / (2.0 * (m * m) as f64 * (n - 2 * m) as f64);
        let oh: f64 = (0..n - 3 * m)
            .map(|i| (x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i]).powi(2))
            .sum::<f64>()
            / (6.0 * (m * m) as f64 * (n - 3 * m) as f64);
        let md: f64 = (0..=n - 3 * m)
            .map(|j| (j..j + m).map(d2).sum::<f64>().powi(2))
            .sum::<f64>()
            / (2.0 * (m as f64).powi(4) * (n - 3 * m + 1) as f64);
        let last = n - 1;
        let xs = |k: isize| {
            if k < 0 {
                2.0 * x[0] - x[(-k) as usize]
            } else if k as usize > last {
                2.0 * x[last] - x[2 * last - k as usize]
            } else {
                x[k as usize]
            }
        };
        let mi = m as isize;
        let tot: f64 = (1..=n as isize - 2)
            .map(|i| (xs(i - mi) - 2.0 * xs(i) + xs(i + mi)).powi(2))
            .sum::<f64>()
            / (2.0 * (m * m) as f64 * (n - 2) as f64);
        [oa, oh, md, tot]
    }

    /// The AVX2 kernel is the portable one in wider registers: same bits.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_kernel_gives_the_portable_kernels_bits() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma"))
        {
            return;
        }
        let mut u = uniform(7);
        let v: Vec<f64> = (0..1010).map(|_| u() * 1e3).collect();
        for n in [0, 1, 7, 8, 9, 15, 1000] {
            let s3 = [&v[2..2 + n], &v[1..1 + n], &v[..n]];
            // SAFETY: the CPU supports AVX2 and FMA (checked above).
            let wide = unsafe { comb_sq_avx2(s3) };
            assert_eq!(comb_sq(s3).to_bits(), wide.to_bits(), "n {n}");
            let s4 = [&v[9..9 + n], &v[6..6 + n], &v[3..3 + n], &v[..n]];
            // SAFETY: as above.
            let wide = unsafe { comb_sq_avx2(s4) };
            assert_eq!(comb_sq(s4).to_bits(), wide.to_bits(), "n {n}");
            // SAFETY: as above.
            let (a, h) = unsafe { comb2_sq_avx2(s4) };
            assert_eq!(a.to_bits(), comb_sq([s4[1], s4[2], s4[3]]).to_bits());
            assert_eq!(h.to_bits(), comb_sq(s4).to_bits());
        }
        // The MDEV block statistics through the AVX2 copy: the same bits,
        // block lengths across the eight lanes' split.
        let v: Vec<f64> = (0..COMB_BLOCK + 9).map(|_| u() * 1e3).collect();
        for n in [0, 1, 7, 8, 9, 17, 100, COMB_BLOCK - 1, COMB_BLOCK] {
            let s4 = [&v[9..9 + n], &v[6..6 + n], &v[3..3 + n], &v[..n]];
            let (a, b) = (mdev_stats(s4), avx2_or_not!(mdev_stats(s4)));
            assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "n {n}");
            assert!(a.iter().all(|s| s.is_finite()));
        }
    }

    #[test]
    fn kernels_equal_the_direct_sums_and_parallel_equals_serial() {
        for n in [9usize, 40, 5000, 70_001] {
            let x = data(n);
            for m in [1usize, 2, 3, 10, 64, n / 4, n / 3, n / 2 - 1] {
                if m == 0 || 3 * m >= n {
                    continue;
                }
                let want = naive(&x, m);
                let got = [
                    oavar(&x, m, 1.0, false).unwrap().var,
                    ohvar(&x, m, 1.0, false).unwrap().var,
                    mvar(&x, m, 1.0, false).unwrap().var,
                    totvar(&x, m, 1.0, false).unwrap().var,
                ];
                for k in 0..4 {
                    assert!(
                        ((got[k] - want[k]) / want[k]).abs() < 1e-9,
                        "n {n} m {m} k {k}: {} vs {}",
                        got[k],
                        want[k]
                    );
                }
                let par = [
                    oavar(&x, m, 1.0, true).unwrap().var,
                    ohvar(&x, m, 1.0, true).unwrap().var,
                    mvar(&x, m, 1.0, true).unwrap().var,
                    totvar(&x, m, 1.0, true).unwrap().var,
                ];
                assert_eq!(got.map(f64::to_bits), par.map(f64::to_bits));
            }
            let ms: Vec<usize> = (1..n / 3).step_by(1 + n / 40).collect();
            // MDEV by prefix sums: the slides' values to round-off, the
            // same bits serial or parallel.
            let md = mvar_many(&x, &ms, 1.0, true);
            assert_eq!(
                md.iter()
                    .map(|v| v.map(|v| v.var.to_bits()))
                    .collect::<Vec<_>>(),
                mvar_many(&x, &ms, 1.0, false)
                    .iter()
                    .map(|v| v.map(|v| v.var.to_bits()))
                    .collect::<Vec<_>>()
            );
            for (k, &m) in ms.iter().enumerate() {
                let (a, b) = (md[k].unwrap(), mvar(&x, m, 1.0, false).unwrap());
                assert_eq!(a.n, b.n);
                assert!(((a.var - b.var) / b.var).abs() < 1e-11, "n {n} m {m}");
            }
            let many = oavar_many(&x, &ms, 1.0, true);
            // TOTDEV from the OADEV sums: the same bits as alone.
            let (oa2, tot) = oavar_totvar_many(&x, &ms, 1.0, true);
            assert_eq!(oa2, many);
            for (k, &m) in ms.iter().enumerate() {
                assert_eq!(
                    tot[k].map(|v| v.var.to_bits()),
                    totvar(&x, m, 1.0, false).map(|v| v.var.to_bits()),
                    "n {n} m {m}"
                );
            }
            let hmany = ohvar_many(&x, &ms, 1.0, true);
            // OADEV and OHDEV in one sweep: the same bits as apart, serial
            // or parallel.
            for par in [false, true] {
                let v = stability_vars(&x, &ms, 1.0, par);
                assert_eq!((&v.oa, &v.oh, &v.tot), (&many, &hmany, &tot));
                assert_eq!(v.md, md);
            }
            for (k, &m) in ms.iter().enumerate() {
                assert_eq!(
                    many[k].map(|v| v.var.to_bits()),
                    oavar(&x, m, 1.0, false).map(|v| v.var.to_bits())
                );
                assert_eq!(
                    hmany[k].map(|v| v.var.to_bits()),
                    ohvar(&x, m, 1.0, false).map(|v| v.var.to_bits())
                );
            }
            // TOTDEV beyond N/2 (all centres reflected).
            if n > 10 {
                assert!(totvar(&x, n - 3, 1.0, false).unwrap().var.is_finite());
            }
        }
    }

    /// MDEV of the factors past the prefix superblocks, from the OHDEV
    /// sweep's terms (with OADEV and OHDEV, or alone in [`mvar_many`]):
    /// the slides' values to round-off (white FM and random-walk FM), the
    /// same bits serial or parallel.
    #[test]
    fn mdev_from_the_sweep_equals_the_slides() {
        let n = (1usize << 18) + 12_345;
        let mut u = uniform(5);
        let mut white = vec![0.0];
        let mut rw = vec![0.0];
        let (mut y, mut z) = (0.0, 0.0);
        for _ in 1..n {
            y += u();
            z += y + u();
            white.push(y);
            rw.push(z);
        }
        let mut ms: Vec<usize> = (0..17).map(|k| 1usize << k).collect();
        ms.extend([50_000, 60_001, 87_000, n / 3]);
        for x in [&white, &rw] {
            let v = stability_vars(x, &ms, 1.0, true);
            assert_eq!(v, stability_vars(x, &ms, 1.0, false));
            // MDEV alone takes the same sums from a sweep of its own.
            for par in [false, true] {
                assert_eq!(mvar_many(x, &ms, 1.0, par), v.md);
            }
            for (k, &m) in ms.iter().enumerate() {
                let (a, b) = (v.md[k].unwrap(), mvar(x, m, 1.0, false).unwrap());
                assert_eq!(a.n, b.n, "m {m}");
                assert!(
                    ((a.var - b.var) / b.var).abs() < 1e-10,
                    "m {m}: {} vs {}",
                    a.var,
                    b.var
                );
            }
        }
    }

    /// Random-walk FM (x the double sum of white noise) and white FM, as
    /// the short τ of a long gyro record see them: MDEV by prefix sums
    /// matches the slides where its round-off estimate accepts it, the
    /// estimate is never below the error it estimates, and where it is
    /// too large the factor is slid (so the numbers agree everywhere).
    #[test]
    fn mvar_prefix_round_off_is_estimated_and_refused_past_the_tolerance() {
        let (xw, xr) = fm_phases(99, 1 << 18, 0.0, 0.0);
        let ms: Vec<usize> = (0..15).map(|k| 1usize << k).collect();
        let mut slid_any = false;
        for (x, name) in [(&xw, "white FM"), (&xr, "random-walk FM")] {
            let slides: Vec<f64> = ms
                .iter()
                .map(|&m| mvar(x, m, 1.0, true).unwrap().var)
                .collect();
            let (raw, _) = mvar_many_tol(x, &ms, 1.0, true, f64::INFINITY);
            let (_, slid) = mvar_many_tol(x, &ms, 1.0, true, 0.0);
            assert!(slid.iter().all(|&s| s), "tol 0 slides every factor");
            let (got, slid) = mvar_many_tol(x, &ms, 1.0, true, MVAR_TOL);
            for k in 0..ms.len() {
                let err = ((raw[k].unwrap().var - slides[k]) / slides[k]).abs();
                let e = ((got[k].unwrap().var - slides[k]) / slides[k]).abs();
                assert!(e <= 10.0 * MVAR_TOL, "{name} m {}: {e:e}", ms[k]);
                if !slid[k] {
                    assert!(err <= MVAR_TOL, "{name} m {}: accepted with {err:e}", ms[k]);
                }
                slid_any |= slid[k];
            }
            if name == "white FM" {
                assert!(slid.iter().all(|&s| !s), "white FM needs no slides");
            }
        }
        assert!(slid_any, "random-walk FM at short τ is slid");
    }

    /// The blocked dense MDEV sums take most of what the whole-record
    /// transforms refuse (short τ of a long record), within the
    /// tolerance of the slides, every term counted once, parallel =
    /// serial; what they refuse is flagged, not returned.
    #[test]
    fn dense_blocks_take_the_short_factors_within_tolerance() {
        let (xw, xr) = fm_phases(11, 60_000, 0.3, 0.2);
        for (x, name) in [(&xw, "white FM"), (&xr, "random-walk FM")] {
            let mut p = vec![0.0];
            for v in x.iter() {
                p.push(p.last().unwrap() + v);
            }
            let all: Vec<usize> = (1..=x.len() / 3).collect();
            let (_, refused) = dense_sums(&p, &all, Kind::Hadamard, DENSE_TOL, false);
            let ms: Vec<usize> = (0..all.len())
                .filter(|&k| refused[k])
                .map(|k| all[k])
                .collect();
            assert!(ms.len() > 10, "{name}: the whole record refuses short τ");
            let (got, slid) = dense_blocks(x, &ms, true);
            assert_eq!((got.clone(), slid.clone()), dense_blocks(x, &ms, false));
            let taken = slid.iter().filter(|&&r| !r).count();
            // White FM: about three in five here; random-walk FM about a third.
            assert!(
                4 * taken > ms.len(),
                "{name}: blocks took {taken} of {}",
                ms.len()
            );
            for (k, &m) in ms.iter().enumerate() {
                if slid[k] {
                    continue;
                }
                let (s, nt) = got[k].unwrap();
                let w = mvar(x, m, 1.0, false).unwrap();
                assert_eq!(nt, w.n, "{name} m {m}");
                let v = mvar_of(s, nt, m, 1.0).var;
                let e = ((v - w.var) / w.var).abs();
                assert!(e <= 2.0 * DENSE_TOL, "{name} m {m}: {e:e}");
            }
        }
    }

    /// The FFT sums of the dense grids against the direct sums, on white
    /// FM (x a random walk, with a trend), random-walk FM and a short
    /// record: accepted factors within the tolerance, the estimate never
    /// below the error, refused factors summed directly.
    #[test]
    fn dense_sums_equal_the_direct_sums_within_their_estimate() {
        let (xw, xr) = fm_phases(7, 20_000, 0.3, 0.0);
        let short = data(700);
        let mut refused = 0;
        for (x, name) in [
            (&xw, "white FM"),
            (&xr, "random-walk FM"),
            (&short, "short"),
        ] {
            let ms: Vec<usize> = (1..=x.len() / 3).collect();
            for kind in [Kind::Allan, Kind::Hadamard] {
                let want = direct_sums(x, &ms, kind, false);
                let (raw, _) = dense_sums(x, &ms, kind, f64::INFINITY, false);
                let (got, slid) = dense_sums(x, &ms, kind, DENSE_TOL, true);
                assert_eq!(
                    got,
                    dense_sums(x, &ms, kind, DENSE_TOL, false).0,
                    "parallel = serial"
                );
                let got: Vec<Option<(f64, usize)>> = (0..ms.len())
                    .map(|k| if slid[k] { want[k] } else { got[k] })
                    .collect();
                for k in 0..ms.len() {
                    let Some((w, nw)) = want[k] else {
                        assert!(got[k].is_none());
                        continue;
                    };
                    let (g, ng) = got[k].unwrap();
                    assert_eq!(nw, ng);
                    let e = ((g - w) / w).abs();
                    assert!(e <= 2.0 * DENSE_TOL, "{name} {kind:?} m {}: {e:e}", ms[k]);
                    if slid[k] {
                        refused += 1;
                    } else {
                        // What was accepted was as good as the estimate.
                        let er = ((raw[k].unwrap().0 - w) / w).abs();
                        assert!(er <= 2.0 * DENSE_TOL, "{name} {kind:?} m {}", ms[k]);
                    }
                }
            }
        }
        assert!(
            refused > 0,
            "random-walk FM at short τ goes to the direct sums"
        );
        // TOTDEV on a dense grid (its interior the OADEV sums by FFT).
        for x in [&xw, &xr] {
            let ms: Vec<usize> = (1..=x.len() / 4).collect();
            let (_, tot) = oavar_totvar_many(x, &ms, 1.0, true);
            for (k, &m) in ms.iter().enumerate() {
                let (g, w) = (tot[k].unwrap().var, totvar(x, m, 1.0, false).unwrap().var);
                assert!(((g - w) / w).abs() <= 2.0 * DENSE_TOL, "TOTDEV m {m}");
            }
        }
        // MDEV on a dense grid (Hadamard sums of the prefix sums by FFT,
        // the refused factors by the superblocks) against the slides.
        for (x, name) in [
            (&xw, "white FM"),
            (&xr, "random-walk FM"),
            (&short, "short"),
        ] {
            let ms: Vec<usize> = (1..=x.len() / 3 + 1).collect();
            let got = mvar_many(x, &ms, 1.0, true);
            assert_eq!(got, mvar_many(x, &ms, 1.0, false), "parallel = serial");
            for (k, &m) in ms.iter().enumerate() {
                let want = mvar(x, m, 1.0, false);
                let Some(w) = want else {
                    assert!(got[k].is_none(), "{name} m {m}");
                    continue;
                };
                let g = got[k].unwrap();
                assert_eq!(g.n, w.n);
                let e = ((g.var - w.var) / w.var).abs();
                assert!(e <= 2.0 * DENSE_TOL, "{name} MDEV m {m}: {e:e}");
            }
        }
    }
}
