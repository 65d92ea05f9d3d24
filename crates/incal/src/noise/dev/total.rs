//! TOTDEV: the total variance on the record extended by reflection, at
//! one averaging factor or at many from the OADEV sums (its interior
//! terms) plus the reflected edge terms.

use super::kernels::{comb_sum, comb_term, lanes};
use super::overlapping::{many_sums, variances, Kind};
use super::VarN;
use crate::noise::ordered_map;

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

/// [`oavar_many`](super::oavar_many) and [`totvar`] at every factor of `ms`.
/// The centres of TOTDEV with both neighbours inside the record (`m ≤ i ≤
/// N−1−m`) are the N − 2m terms of the OADEV sum, the same terms in the same
/// blocks, so TOTDEV only adds its 2(m − 1) reflected edge terms to the OADEV
/// sum (O(m) per factor instead of O(N)).
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

/// TOTDEV at every factor from the OADEV sums `(S, n)` (its interior
/// terms), adding the reflected edge terms.
pub(super) fn totvar_from(
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
