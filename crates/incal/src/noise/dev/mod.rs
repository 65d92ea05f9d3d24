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
//!
//! The kernels by family: `kernels` (the comb sums), `sweep` (many
//! factors in one pass), `overlapping` (OADEV, OHDEV), `dense` (dense
//! grids by FFT), `modified` and `prefix` (MDEV, TDEV), `total`
//! (TOTDEV).

mod dense;
mod kernels;
mod modified;
mod overlapping;
mod prefix;
mod sweep;
mod total;

#[cfg(test)]
mod tests;

pub(crate) use dense::detrend;
pub use dense::DENSE_TOL;
pub use modified::{mvar, mvar_many, tvar};
pub use overlapping::{oavar, oavar_many, ohvar, ohvar_many};
pub use prefix::MVAR_TOL;
pub use total::{oavar_totvar_many, totvar};

use modified::mvar_merge;
use overlapping::{dense, many_sums, variances, Kind};
use prefix::past_superblocks;
use sweep::comb_many;
use total::totvar_from;

/// Terms per block of the blocked sums of MDEV.
pub const BLOCK: usize = 1 << 14;

/// Terms per block of the OADEV and OHDEV sums (a window of about fifty
/// of them stays in the caches in `comb_many`; the unit tests use short
/// blocks so that short records cross every band).
pub const COMB_BLOCK: usize = if cfg!(test) { 1 << 8 } else { 1 << 11 };

/// A variance and the number of terms behind it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VarN {
    /// The variance σ²(τ) (unit² of x/τ).
    pub var: f64,
    /// Number of terms summed.
    pub n: usize,
}

/// OADEV, OHDEV, TOTDEV and MDEV variances at every factor of `ms`, as
/// [`oavar_many`], [`ohvar_many`], [`oavar_totvar_many`] and [`mvar_many`]
/// give them, sharing the work: on a sparse grid one sweep
/// (`comb_many`) gives OADEV's and OHDEV's sums (the same bits as apart)
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
