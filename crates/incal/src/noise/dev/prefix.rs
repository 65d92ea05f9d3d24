//! MDEV at many factors by prefix sums ([`mvar_many_tol`]): the inner
//! sums as third differences of the prefix sums, built per superblock of
//! the record (the line through its ends removed), with the round-off
//! estimate that sends a factor back to the slides of [`mvar`].

use rayon::prelude::*;

use super::kernels::comb_block;
use super::modified::{mvar, mvar_of};
use super::{VarN, BLOCK};
use crate::noise::ordered_map;

/// Superblock sizes (terms) of [`mvar_many`](super::mvar_many), smallest first;
/// factor m goes to the first with `3m ≤ R`. Small m take short superblocks,
/// whose prefix sums stay small (their round-off is what limits small m). All
/// run in one pass over the record (the short superblocks of a long one while
/// its samples are in cache).
pub(super) const MVAR_GROUPS: [usize; 3] = [1 << 11, BLOCK, 1 << 17];

/// Largest estimated round-off, relative to the variance, that
/// [`mvar_many`](super::mvar_many) accepts from its prefix sums; past it the
/// factor is summed by [`mvar`]'s slides.
pub const MVAR_TOL: f64 = 1e-9;

/// Whether factor m is too large for [`mvar_many_tol`]'s prefix
/// superblocks (`3m` past the largest), so that its inner sum would slide.
pub(super) fn past_superblocks(m: usize) -> bool {
    3 * m > MVAR_GROUPS[MVAR_GROUPS.len() - 1]
}

/// [`mvar_many`](super::mvar_many) with the round-off tolerance given; also
/// says which factors were summed again by [`mvar`] (the tests check the
/// estimate against the slides with `tol = ∞`).
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

/// The levels of one pass of [`mvar_many`](super::mvar_many): `(R, factors)`,
/// the first R a multiple of the others. The record goes in superblocks of the
/// first R, in parallel (with the factors dealt round-robin into chunks when
/// the superblocks are too few for the cores, each chunk a task that builds its
/// own prefix); inside one, every level's superblocks in order, each with its
/// own prefix sums, every factor of the level over it in sub-blocks of
/// [`BLOCK`] terms. Returns per level and factor the sum of `W_j²` (sub-block
/// sums added in order) and the largest rms of P.
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
pub(super) fn local_prefix(v: &[f64], buf: &mut Vec<f64>) -> f64 {
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
