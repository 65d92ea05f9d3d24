//! OADEV and OHDEV: the overlapping Allan and Hadamard variances at one
//! averaging factor (blocked direct sums) or at many (one block-major
//! sweep, or on a dense grid the lagged products by FFT).

use super::dense::{dense_sums, DENSE_TOL};
use super::kernels::comb_sum;
use super::sweep::comb_many;
use super::VarN;

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

/// [`oavar`] at every factor of `ms`: one block-major sweep (same bits as
/// [`oavar`]), or, for a dense grid (`taus all`) where the direct sums
/// would cost more than the transforms, the lagged products by FFT
/// (`dense_sums`).
pub fn oavar_many(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> Vec<Option<VarN>> {
    variances(&many_sums(x, ms, Kind::Allan, parallel), ms, tau0, 2.0)
}

/// [`ohvar`] at every factor of `ms`, as [`oavar_many`].
pub fn ohvar_many(x: &[f64], ms: &[usize], tau0: f64, parallel: bool) -> Vec<Option<VarN>> {
    variances(&many_sums(x, ms, Kind::Hadamard, parallel), ms, tau0, 6.0)
}

/// `σ² = S / (c·m²τ0²·n)` from the sums `(S, n)` of each factor
/// (c = 2 Allan, 6 Hadamard).
pub(super) fn variances(
    sums: &[Option<(f64, usize)>],
    ms: &[usize],
    tau0: f64,
    c: f64,
) -> Vec<Option<VarN>> {
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
pub(super) enum Kind {
    Allan,
    Hadamard,
}

/// Direct sums cost over the transforms' cost at which [`many_sums`]
/// takes the FFT: about where they take the same time on this machine
/// (measured on 10⁵ samples).
const DENSE_RATIO: f64 = 60.0;

/// Per factor `(Σ_j (Σ_k w_k x_{j+km})², terms)` of the kind, by the
/// block-major direct sums or, when they would cost more than
/// [`DENSE_RATIO`]`·L·log₂L`, by [`dense_sums`].
pub(super) fn many_sums(
    x: &[f64],
    ms: &[usize],
    kind: Kind,
    parallel: bool,
) -> Vec<Option<(f64, usize)>> {
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
pub(super) fn dense(l: usize, ms: &[usize], span: usize) -> bool {
    let direct: f64 = ms.iter().map(|&m| l.saturating_sub(span * m) as f64).sum();
    l > 1 && direct > DENSE_RATIO * l as f64 * (l as f64).log2()
}

/// The sums of [`many_sums`] of the kind, all by the block-major sweep
/// ([`comb_many`]).
pub(super) fn direct_sums(
    x: &[f64],
    ms: &[usize],
    kind: Kind,
    parallel: bool,
) -> Vec<Option<(f64, usize)>> {
    let want = [kind == Kind::Allan, kind == Kind::Hadamard];
    let [a, h] = comb_many(x, ms, want, &[], parallel).sums;
    match kind {
        Kind::Allan => a,
        Kind::Hadamard => h,
    }
}
