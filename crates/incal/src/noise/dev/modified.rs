//! MDEV and TDEV: the modified Allan variance at one averaging factor
//! (the inner sums sliding in eight lanes per block) or at many (prefix
//! sums over superblocks, the sweep's OHDEV terms for the largest factors,
//! or on a dense grid the prefix sums' Hadamard sums by FFT), and the time
//! variance from it.

use std::mem::MaybeUninit;

use super::dense::{dense_sums, DENSE_TOL};
use super::kernels::{comb_term, lanes};
use super::overlapping::{dense, Kind};
use super::prefix::{local_prefix, mvar_many_tol, past_superblocks, MVAR_TOL};
use super::sweep::comb_many;
use super::{VarN, BLOCK, COMB_BLOCK};
use crate::noise::ordered_map;

/// Modified Allan variance, SP 1065 eq. (15):
/// `Mod σ²(τ) = Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))² / (2 m⁴ τ0² (N − 3m + 1))`.
///
/// The inner sums slide (`W_{j+1} = W_j + d_{j+1}`,
/// `d_j = x_{j+3m−1} − 3x_{j+2m−1} + 3x_{j+m−1} − x_{j−1}`) inside blocks
/// of at least 8m terms, eight slides in vector lanes per block
/// (`mvar_block`); every block starts from a direct sum, so round-off
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
pub(super) const LANES: usize = 8;

/// Eight running sums in lanes over the steps `step(0..8r)`: lane l slides
/// `loc` from zero over steps `l·r .. (l+1)·r` and returns its `[loc, Σ loc, Σ
/// loc²]` per lane ([`mvar_block`] and [`mdev_stats`](super::sweep::mdev_stats)
/// join the lanes). The steps go to a transposed buffer first (row t holds
/// every lane's step t), so the slides run as one vector of eight lanes (one
/// slide's add chain would bound the loop). `r ≤ MVAR_CHUNK / 8`.
#[inline(always)]
pub(super) fn lane_slides(r: usize, step: impl Fn(usize) -> f64) -> [[f64; LANES]; 3] {
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

/// [`mvar`] at every factor of `ms`, by prefix sums shared across factors.
///
/// With `P_k = Σ_{i<k} x_i` the inner sum is a third difference, `W_j =
/// P_{j+3m} − 3P_{j+2m} + 3P_{j+m} − P_j`, so once `P` is built every m costs
/// four loads per term, vectorized and block-major over the factors as
/// [`oavar_many`](super::oavar_many) (the slides of [`mvar`] run a dependent
/// add per term, one m at a time). `P` is built per superblock of R terms (`R`
/// from `MVAR_GROUPS`, `3m ≤ R`) over `R + 3m`
/// samples, of `x_k − x_r − b(k − r)` (the line through the superblock's ends
/// removed: W is blind to a line in x), so it stays small and the buffer is at
/// most 2R values per thread, never a second copy of the record.
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
pub(super) fn dense_blocks(
    x: &[f64],
    ms: &[usize],
    parallel: bool,
) -> (Vec<Option<(f64, usize)>>, Vec<bool>) {
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
pub(super) fn mvar_of(s: f64, n: usize, m: usize, tau0: f64) -> VarN {
    let mf = m as f64;
    VarN {
        var: s / (2.0 * mf.powi(4) * tau0 * tau0 * n as f64),
        n,
    }
}

/// MDEV at every factor of `ms`: those marked `big` from the sums
/// `modified` of a [`comb_many`] sweep, the others by
/// [`mvar_many_tol`].
pub(super) fn mvar_merge(
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

/// Time variance from the modified Allan variance, SP 1065 eq. (17):
/// `σ_x²(τ) = (τ²/3) Mod σ²(τ)` (unit² of x).
pub fn tvar(mvar: f64, tau: f64) -> f64 {
    tau * tau / 3.0 * mvar
}
