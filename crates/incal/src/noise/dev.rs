//! The deviation kernels on phase data `x` (time-error or angle samples at
//! spacing τ0); σ(τ) for τ = m·τ0.
//!
//! Every kernel sums its squared terms in fixed blocks of [`BLOCK`] terms,
//! each block with eight lane accumulators (so the loop vectorizes), and
//! adds the block sums in block order. The blocks run on rayon; the fixed
//! partition and the ordered reduction make a parallel run bit-for-bit a
//! serial one.
//!
//! Formulas: NIST SP 1065 (Riley 2008) §5.2.4 eq. (14) OADEV, §5.2.5
//! eq. (15) MDEV, §5.2.6 eq. (17) TDEV, §5.2.9 eq. (22) OHDEV, §5.2.11
//! eq. (25) TOTDEV.

use rayon::prelude::*;

/// Terms per block of the blocked sums.
pub const BLOCK: usize = 1 << 14;

/// `Σ_{i<n} f(i)²` in fixed blocks (eight lanes each), block sums added in
/// order; parallel over blocks when `parallel`.
fn sum_sq(n: usize, parallel: bool, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let nb = n.div_ceil(BLOCK);
    let block = |b: usize| -> f64 {
        let lo = b * BLOCK;
        let hi = (lo + BLOCK).min(n);
        let mut acc = [0.0f64; 8];
        let mut i = lo;
        while i + 8 <= hi {
            for (l, a) in acc.iter_mut().enumerate() {
                let v = f(i + l);
                *a += v * v;
            }
            i += 8;
        }
        for (l, a) in acc.iter_mut().enumerate().take(hi - i) {
            let v = f(i + l);
            *a += v * v;
        }
        ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7]))
    };
    let sums: Vec<f64> = if parallel && nb > 1 {
        (0..nb).into_par_iter().map(block).collect()
    } else {
        (0..nb).map(block).collect()
    };
    sums.iter().sum()
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
    let (a, b, c) = (&x[..n], &x[m..m + n], &x[2 * m..2 * m + n]);
    let s = sum_sq(n, parallel, |i| c[i] - 2.0 * b[i] + a[i]);
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
    let (a, b, c, d) = (
        &x[..n],
        &x[m..m + n],
        &x[2 * m..2 * m + n],
        &x[3 * m..3 * m + n],
    );
    let s = sum_sq(n, parallel, |i| d[i] - 3.0 * c[i] + 3.0 * b[i] - a[i]);
    let mt = m as f64 * tau0;
    Some(VarN {
        var: s / (6.0 * mt * mt * n as f64),
        n,
    })
}

/// Modified Allan variance, SP 1065 eq. (15):
/// `Mod σ²(τ) = Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))² / (2 m⁴ τ0² (N − 3m + 1))`.
///
/// The inner sums slide (`W_{j+1} = W_j + s_{j+m} − s_j`) inside blocks of
/// at least 4m terms; each block starts from a direct sum, so round-off
/// cannot build up along the record and the blocks are independent.
pub fn mvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    let nt = (x.len() + 1)
        .checked_sub(3 * m)
        .filter(|&n| n > 0 && m > 0)?;
    let s = |i: usize| x[i + 2 * m] - 2.0 * x[i + m] + x[i];
    let blen = BLOCK.max(4 * m);
    let nb = nt.div_ceil(blen);
    let block = |b: usize| -> f64 {
        let lo = b * blen;
        let hi = (lo + blen).min(nt);
        let mut w = 0.0;
        for i in lo..lo + m {
            w += s(i);
        }
        let mut acc = w * w;
        for j in lo + 1..hi {
            w += s(j + m - 1) - s(j - 1);
            acc += w * w;
        }
        acc
    };
    let sums: Vec<f64> = if parallel && nb > 1 {
        (0..nb).into_par_iter().map(block).collect()
    } else {
        (0..nb).map(block).collect()
    };
    let total: f64 = sums.iter().sum();
    let mf = m as f64;
    Some(VarN {
        var: total / (2.0 * mf.powi(4) * tau0 * tau0 * nt as f64),
        n: nt,
    })
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
    let s = sum_sq(nt, parallel, |j| {
        let i = j as isize + 1;
        xs(i - mi) - 2.0 * xs(i) + xs(i + mi)
    });
    let mt = m as f64 * tau0;
    Some(VarN {
        var: s / (2.0 * mt * mt * nt as f64),
        n: nt,
    })
}
