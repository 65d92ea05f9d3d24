//! The block-major sweep ([`comb_many`]): OADEV's and OHDEV's sums at many
//! averaging factors at once, and the MDEV sums of the factors past the
//! prefix superblocks from the same loads (their slide steps are OHDEV's
//! terms), with the record read a few times in all.

use super::kernels::{comb2_block, comb_block, comb_term, lanes};
use super::modified::lane_slides;
use super::COMB_BLOCK;
use crate::noise::ordered_map;

/// Octaves of factor per band of [`comb_many`]'s sweep.
const BAND: usize = 16;
/// Blocks of the sweep's order per task (a task warms its window of
/// blocks once, so tasks are long).
const TASK: usize = 1024;

/// [`comb_sum`](super::kernels::comb_sum) for many averaging factors at once,
/// OADEV's (`want[0]`, `x_{j+2m} − 2x_{j+m} + x_j`) and OHDEV's (`want[1]`, the
/// third difference) sums, with the record read from memory a few times in all,
/// not a few times per factor and deviation.
///
/// Block b of factor m reads the windows of [`COMB_BLOCK`] samples at `b + k·q`
/// blocks (`q = m/COMB_BLOCK`, k = 0..3; both deviations from the same loads,
/// [`comb2_block`]), so a window is read again by the same factor q blocks
/// later and by the factors 2m, 4m, … Factors go in bands of [`BAND`] octaves
/// of q: band k (stride `s = BAND^k` blocks, `s ≤ q < BAND·s`; band 0 also
/// takes m below a block) visits its blocks in residue order (`r, r + s, r +
/// 2s, …` for r = 0..s), so every window a block needs was read at most
/// `3·BAND` visits before, a window of about 50 blocks (800 kB) that stays in
/// the caches, and the band reads the record about once. Each factor's blocks
/// and their ordered sum are exactly those of
/// [`comb_sum`](super::kernels::comb_sum), so the numbers are the same bits; in
/// parallel the visit order is cut into tasks of [`TASK`] visits.
pub(super) fn comb_many(
    x: &[f64],
    ms: &[usize],
    want: [bool; 2],
    mdev: &[bool],
    parallel: bool,
) -> Sweep {
    let plan = Plan::new(x, ms, want, mdev);
    let tasks = plan.tasks();
    let parts: Vec<Vec<BlockSums>> = ordered_map(tasks.len(), parallel, |i| plan.task(tasks[i]));
    let terms = &plan.terms;
    let mut table: [Vec<Vec<f64>>; 2] = [0, 1].map(|k| {
        terms[k]
            .iter()
            .map(|n| vec![0.0; n.div_ceil(COMB_BLOCK)])
            .collect()
    });
    let mut mtable: Vec<Vec<[f64; 3]>> = (0..ms.len())
        .map(|j| {
            let n = if plan.md(j) { terms[1][j] } else { 0 };
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
    let modified = (0..ms.len())
        .map(|j| plan.modified(j, &mtable[j]))
        .collect();
    Sweep { sums, modified }
}

/// What [`comb_many`] returns: the OADEV and OHDEV sums `(S, n)` per
/// factor, and the MDEV sums `(Σ W², n)` of the factors asked for.
pub(super) struct Sweep {
    pub(super) sums: [Vec<Option<(f64, usize)>>; 2],
    pub(super) modified: Vec<Option<(f64, usize)>>,
}

/// One block of one factor in [`comb_many`]'s sweep: `(factor index j,
/// block b, OADEV sum, OHDEV sum, MDEV block statistics)`.
type BlockSums = (usize, usize, Option<f64>, Option<f64>, Option<[f64; 3]>);

/// The work of [`comb_many`]: the factors' terms and their bands.
struct Plan<'a> {
    x: &'a [f64],
    ms: &'a [usize],
    want: [bool; 2],
    mdev: &'a [bool],
    /// Terms of each factor: Allan L − 2m, Hadamard L − 3m (0 if
    /// unwanted; the Hadamard terms are also MDEV's slide steps).
    terms: [Vec<usize>; 2],
    /// Per band its stride (blocks) and the indices of its factors.
    bands: Vec<(usize, Vec<usize>)>,
    /// Blocks of each band (its largest count).
    nbs: Vec<usize>,
}

impl<'a> Plan<'a> {
    /// The terms of every factor and the bands of [`BAND`] octaves.
    fn new(x: &'a [f64], ms: &'a [usize], want: [bool; 2], mdev: &'a [bool]) -> Self {
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
        let nbs: Vec<usize> = bands
            .iter()
            .map(|(_, js)| js.iter().map(|&j| blocks(j)).max().unwrap_or(0))
            .collect();
        Plan {
            x,
            ms,
            want,
            mdev,
            terms,
            bands,
            nbs,
        }
    }

    /// Whether factor j's MDEV sums are asked for.
    fn md(&self, j: usize) -> bool {
        self.mdev.get(j) == Some(&true)
    }

    /// The tasks: `(band, first visit, end visit)` over each band's visit
    /// order, [`TASK`] visits each.
    fn tasks(&self) -> Vec<(usize, usize, usize)> {
        let mut tasks = Vec::new();
        for (bi, &nb) in self.nbs.iter().enumerate() {
            let mut v = 0;
            while v < nb {
                tasks.push((bi, v, (v + TASK).min(nb)));
                v += TASK;
            }
        }
        tasks
    }

    /// The block sums of visits `v0..v1` of band `bi`, every factor of the
    /// band at each visited block.
    fn task(&self, (bi, v0, v1): (usize, usize, usize)) -> Vec<BlockSums> {
        let (s, js, nb) = (self.bands[bi].0, &self.bands[bi].1, self.nbs[bi]);
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
            out.extend(js.iter().filter_map(|&j| self.block(j, b)));
        }
        out
    }

    /// Factor j's sums over block b: OADEV's and OHDEV's from one load of
    /// the windows when both are wanted over the same terms, and the MDEV
    /// block statistics ([`mdev_stats`]) when asked for. `None` when the
    /// block holds none of the factor's terms.
    fn block(&self, j: usize, b: usize) -> Option<BlockSums> {
        let (x, m, want) = (self.x, self.ms[j], self.want);
        let lo = b * COMB_BLOCK;
        let [ha, hh] = [0, 1].map(|k| (lo + COMB_BLOCK).min(self.terms[k][j]));
        let w = |k: usize, hi: usize| &x[k * m + lo..k * m + hi];
        let (va, vh) = if want[1] && lo < ha && ha == hh {
            let (va, vh) = comb2_block([w(3, hh), w(2, hh), w(1, hh), w(0, hh)]);
            (Some(va), Some(vh))
        } else {
            (
                (lo < ha).then(|| comb_block([w(2, ha), w(1, ha), w(0, ha)])),
                (want[1] && lo < hh).then(|| comb_block([w(3, hh), w(2, hh), w(1, hh), w(0, hh)])),
            )
        };
        let md = (lo < hh && self.md(j))
            .then(|| avx2_or_not!(mdev_stats([w(3, hh), w(2, hh), w(1, hh), w(0, hh)])));
        (va.is_some() || vh.is_some() || md.is_some()).then_some((j, b, va, vh, md))
    }

    /// Factor j's MDEV sum `(Σ W², n)` from its blocks' statistics `mtable`
    /// ([`mdev_stats`]): W_0 by its direct sum, then block by block in
    /// order (`W_{j+1} = W_j + h_j`, the Hadamard terms h): the block adds
    /// `n·W² + 2W·S1 + S2` and moves W on by its total. `None` when not
    /// asked for or undefined.
    fn modified(&self, j: usize, mtable: &[[f64; 3]]) -> Option<(f64, usize)> {
        let x = self.x;
        let (m, nh) = (self.ms[j], self.terms[1][j]);
        // n = L + 1 − 3m terms (W_0 alone when L = 3m).
        (self.md(j) && m > 0 && x.len() >= 3 * m).then(|| {
            let mut w = lanes(0, m, |i| comb_term([x[i + 2 * m], x[i + m], x[i]]));
            let mut acc = w * w;
            for (b, &[t, s1, s2]) in mtable.iter().enumerate() {
                let n = (nh - b * COMB_BLOCK).min(COMB_BLOCK) as f64;
                acc += n * w * w + 2.0 * w * s1 + s2;
                w += t;
            }
            (acc, nh + 1)
        })
    }
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
pub(super) fn mdev_stats(s: [&[f64]; 4]) -> [f64; 3] {
    const L: usize = super::modified::LANES;
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
