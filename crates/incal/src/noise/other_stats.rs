//! The statistics a frequency-stability or inertial lab asks for beyond
//! the default five: non-overlapping Allan and Hadamard deviations,
//! modified total and Hadamard total deviations, Theo1, and the time
//! interval errors MTIE and TIE rms. All take a phase record `x` (N
//! points, sample interval τ0) and an averaging factor m; each returns the
//! variance (or the deviation, for the time-interval errors) with the
//! number of terms summed. Definitions: NIST SP 1065, "Handbook of
//! Frequency Stability Analysis", W. J. Riley, 2008 (equation numbers
//! below are its), and ITU-T G.810 for MTIE and TIE.
//!
//! MTOTDEV, HTOTDEV and Theo1 cost O(N·m) per averaging factor:
//! [`work`] estimates a run's operations, and a run stops at the last
//! averaging time within [`MAX_WORK`] (warning `statistic-truncated`:
//! average the record down for the longer ones).

use super::dev::VarN;

/// Non-overlapping Allan variance (SP 1065 eq. 7 on phase):
/// `σ²(τ) = Σ (x_{i+2m} − 2x_{i+m} + x_i)² / (2 n τ²)` over the n
/// indices i = 0, m, 2m, … with i + 2m ≤ N − 1; τ = mτ0.
pub fn avar(x: &[f64], m: usize, tau0: f64) -> Option<VarN> {
    strided(x, m, tau0, &[1.0, -2.0, 1.0], 2.0)
}

/// Non-overlapping Hadamard variance (SP 1065 eq. 17 on phase):
/// `σ²(τ) = Σ (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)² / (6 n τ²)` over
/// i = 0, m, 2m, … with i + 3m ≤ N − 1.
pub fn hvar(x: &[f64], m: usize, tau0: f64) -> Option<VarN> {
    strided(x, m, tau0, &[-1.0, 3.0, -3.0, 1.0], 6.0)
}

/// `Σ (Σ_k c_k x_{i+km})² / (norm · n · (mτ0)²)` over i = 0, m, 2m, ….
fn strided(x: &[f64], m: usize, tau0: f64, c: &[f64], norm: f64) -> Option<VarN> {
    let span = (c.len() - 1) * m;
    if m == 0 || x.len() <= span {
        return None;
    }
    let (mut s, mut n) = (0.0, 0usize);
    let mut i = 0;
    while i + span < x.len() {
        let d: f64 = c.iter().enumerate().map(|(k, ck)| ck * x[i + k * m]).sum();
        s += d * d;
        n += 1;
        i += m;
    }
    let tau = m as f64 * tau0;
    Some(VarN {
        var: s / (norm * n as f64 * tau * tau),
        n,
    })
}

/// Remove the line through the means of the first and last halves of `w`
/// (3m points; for an odd length the middle point is in neither half)
/// and reflect: the 9m-point sequence `w*` reversed, `w*`, reversed
/// (SP 1065 §5.2.12: "uninverted, even reflection").
fn reflected(w: &[f64], out: &mut Vec<f64>) {
    let l = w.len();
    let (h1, h2) = (l / 2, l.div_ceil(2));
    let m1 = w[..h1].iter().sum::<f64>() / h1 as f64;
    let m2 = w[h2..].iter().sum::<f64>() / (l - h2) as f64;
    // Distance between the halves' centres, in samples.
    let dist = (h2 + l - 1) as f64 / 2.0 - (h1 - 1) as f64 / 2.0;
    let slope = (m2 - m1) / dist;
    out.clear();
    out.extend((0..l).rev().map(|i| w[i] - slope * i as f64));
    out.extend((0..l).map(|i| w[i] - slope * i as f64));
    out.extend((0..l).rev().map(|i| w[i] - slope * i as f64));
}

/// Σ over the 6m positions j of the 9m-point `e` of
/// `((S₁ − 2S₂ + S₃)/m)²`, S_k the sum of the k-th m points from j.
fn second_diff_of_means(e: &[f64], m: usize) -> f64 {
    let mut s = [0.0; 3];
    for (k, sk) in s.iter_mut().enumerate() {
        *sk = e[k * m..(k + 1) * m].iter().sum();
    }
    let mf = m as f64;
    let mut acc = 0.0;
    for j in 0..6 * m {
        if j > 0 {
            for (k, sk) in s.iter_mut().enumerate() {
                *sk += e[j + (k + 1) * m - 1] - e[j + k * m - 1];
            }
        }
        let z = (s[0] - 2.0 * s[1] + s[2]) / mf;
        acc += z * z;
    }
    acc
}

/// Modified total variance (SP 1065 eq. 27): for each of the N − 3m + 1
/// subsequences of 3m phase points, the half-average line removed and the
/// sequence extended by even reflection to 9m points (`reflected`);
/// `Mod σ²_total(τ) = Σ_n [ (1/6m) Σ_j z_j² ] / (2 (mτ0)² (N − 3m + 1))`,
/// z_j the second difference of m-point phase averages. n = N − 3m + 1.
pub fn mtotvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    let l = 3 * m;
    if m == 0 || x.len() < l {
        return None;
    }
    let count = x.len() - l + 1;
    let sum = windows_sum(x, l, parallel, |e| {
        second_diff_of_means(e, m) / (6 * m) as f64
    });
    let tau = m as f64 * tau0;
    Some(VarN {
        var: sum / (2.0 * tau * tau * count as f64),
        n: count,
    })
}

/// Windows per block of [`windows_sum`]: the fixed partition that gives a
/// parallel run a serial run's bits.
const BLOCK: usize = 1024;

/// Σ over every window of `l` points of `x` of `f` applied to the window
/// reflected ([`reflected`]), summed block by block in order (blocks on
/// rayon's threads when `parallel`).
fn windows_sum(x: &[f64], l: usize, parallel: bool, f: impl Fn(&[f64]) -> f64 + Sync) -> f64 {
    let count = x.len() + 1 - l;
    let blocks = count.div_ceil(BLOCK);
    super::ordered_map(blocks, parallel, |b| {
        let mut e = Vec::with_capacity(3 * l);
        let mut s = 0.0;
        for i in b * BLOCK..((b + 1) * BLOCK).min(count) {
            reflected(&x[i..i + l], &mut e);
            s += f(&e);
        }
        s
    })
    .into_iter()
    .sum()
}

/// Hadamard total variance (SP 1065 eq. 29), on the frequency record
/// `y_i = (x_{i+1} − x_i)/τ0` (N − 1 values): for each of the
/// N − 1 − 3m + 1 subsequences of 3m frequency values, the half-average
/// line removed and reflected to 9m (`reflected`);
/// `Tot σ²_H(τ) = Σ_n [ (1/6m) Σ_j H_j² ] / (6 (N − 3m))`, H_j the second
/// difference of m-point frequency averages. At m = 1 it is the Hadamard
/// variance ([`hvar`]), as SP 1065 defines it. n the subsequences.
pub fn htotvar(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    if m == 1 {
        return hvar(x, 1, tau0);
    }
    if m == 0 || x.len() < 2 {
        return None;
    }
    let y: Vec<f64> = x.windows(2).map(|w| (w[1] - w[0]) / tau0).collect();
    let l = 3 * m;
    if y.len() < l {
        return None;
    }
    let count = y.len() - l + 1;
    let sum = windows_sum(&y, l, parallel, |e| {
        second_diff_of_means(e, m) / (6 * m) as f64
    });
    Some(VarN {
        var: sum / (6.0 * count as f64),
        n: count,
    })
}

/// Theo1 variance (SP 1065 eq. 30), m even, at τ = 0.75·m·τ0:
/// `Theo1(m) = Σ_{i=0}^{N−m−1} Σ_{δ=0}^{m/2−1} [(x_i − x_{i−δ+m/2}) +
/// (x_{i+m} − x_{i+δ+m/2})]² / (m/2 − δ) / (0.75 (N − m) (mτ0)²)`, without
/// bias correction. n = (N − m)·m/2 terms.
pub fn theo1var(x: &[f64], m: usize, tau0: f64, parallel: bool) -> Option<VarN> {
    if m < 2 || m % 2 != 0 || x.len() <= m {
        return None;
    }
    let n = x.len();
    let h = m / 2;
    let w: Vec<f64> = (0..h).map(|d| 1.0 / (h - d) as f64).collect();
    let outer = n - m;
    let sum: f64 = super::ordered_map(outer.div_ceil(BLOCK), parallel, |b| {
        let mut acc = 0.0;
        for i in b * BLOCK..((b + 1) * BLOCK).min(outer) {
            let mut s = 0.0;
            for (d, wd) in w.iter().enumerate() {
                let v = x[i] - x[i + h - d] + x[i + m] - x[i + h + d];
                s += v * v * wd;
            }
            acc += s;
        }
        acc
    })
    .into_iter()
    .sum();
    let tau = m as f64 * tau0;
    Some(VarN {
        var: sum / (0.75 * outer as f64 * tau * tau),
        n: outer * h,
    })
}

/// The TheoBR bias factor (Howe & Tasset, "TheoH: a hybrid,
/// high-confidence statistic that improves on the Allan deviation",
/// Metrologia 43, 2006; NIST SP 1065 §5.2.15): the mean ratio of OAVAR to
/// Theo1 at the same τ,
/// `k = (1/(n+1)) Σ_{i=0}^{n} OAVAR(m = 9+3i) / Theo1(m = 12+4i)`,
/// n = ⌊0.1·N/3 − 3⌋, N phase points; TheoBR = k·Theo1. `None` below 120
/// points (n < 0) or where a Theo1 term vanishes. O(N³/900) operations
/// ([`theobr_work`]): a longer record is first averaged in blocks of `ba`
/// points (Taylor & Howe, "Fast TheoBR: a method for long data set
/// stability analysis", IEEE Trans. UFFC 57(9), 2010), with their
/// correction `+ 0.00055·(ba − 1)`.
pub fn theobr_bias(x: &[f64], ba: usize, parallel: bool) -> Option<f64> {
    let ba = ba.max(1);
    let avg: Vec<f64>;
    let x = if ba > 1 {
        avg = x
            .chunks_exact(ba)
            .map(|c| c.iter().sum::<f64>() / ba as f64)
            .collect();
        &avg[..]
    } else {
        x
    };
    let n = x.len();
    let nb = (0.1 * n as f64 / 3.0 - 3.0).floor();
    if nb < 0.0 {
        return None;
    }
    let nb = nb as usize;
    let ratios = super::ordered_map(nb + 1, parallel, |i| {
        let a = super::dev::oavar(x, 9 + 3 * i, 1.0, false)?.var;
        let t = theo1var(x, 12 + 4 * i, 1.0, false)?.var;
        (t > 0.0).then(|| a / t)
    });
    let mut sum = 0.0;
    for r in ratios {
        sum += r?;
    }
    let k = sum / (nb + 1) as f64 + 0.00055 * (ba - 1) as f64;
    k.is_finite().then_some(k)
}

/// Operations of [`theobr_bias`] on N points: Σ_{i=0}^{n} (N − 12 − 4i)·(6 + 2i),
/// the Theo1 terms (the OAVAR terms are O(N) each).
pub fn theobr_work(n: usize) -> f64 {
    let nb = (0.1 * n as f64 / 3.0 - 3.0).floor();
    if nb < 0.0 {
        return 0.0;
    }
    (0..=nb as usize)
        .map(|i| (n as f64 - 12.0 - 4.0 * i as f64).max(0.0) * (6.0 + 2.0 * i as f64) + n as f64)
        .sum()
}

/// The block length [`theobr_bias`] averages N points in so that its work
/// stays within `budget` operations: 1 (exact) where it fits.
pub fn theobr_block(n: usize, budget: f64) -> usize {
    let mut ba = 1;
    while ba < n && theobr_work(n / ba) > budget {
        ba += 1;
    }
    ba
}

/// Maximum time interval error (ITU-T G.810; SP 1065 §5.2.14): the
/// largest peak-to-peak phase over every window of m + 1 points (τ = mτ0),
/// by monotonic queues in O(N). Returns (MTIE, windows = N − m).
pub fn mtie(x: &[f64], m: usize) -> Option<(f64, usize)> {
    if m == 0 || x.len() <= m {
        return None;
    }
    let w = m + 1;
    let mut hi: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut lo: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut best = 0.0f64;
    for (i, &v) in x.iter().enumerate() {
        while hi.back().is_some_and(|&j| x[j] <= v) {
            hi.pop_back();
        }
        hi.push_back(i);
        while lo.back().is_some_and(|&j| x[j] >= v) {
            lo.pop_back();
        }
        lo.push_back(i);
        if i + 1 >= w {
            let start = i + 1 - w;
            while hi.front().is_some_and(|&j| j < start) {
                hi.pop_front();
            }
            while lo.front().is_some_and(|&j| j < start) {
                lo.pop_front();
            }
            if let (Some(&a), Some(&b)) = (hi.front(), lo.front()) {
                best = best.max(x[a] - x[b]);
            }
        }
    }
    Some((best, x.len() - m))
}

/// Time interval error, rms (ITU-T G.810): `√(Σ (x_{i+m} − x_i)² / (N − m))`.
/// Returns (TIE rms, terms = N − m).
pub fn tierms(x: &[f64], m: usize) -> Option<(f64, usize)> {
    if m == 0 || x.len() <= m {
        return None;
    }
    let n = x.len() - m;
    let s: f64 = (0..n).map(|i| (x[i + m] - x[i]).powi(2)).sum();
    Some(((s / n as f64).sqrt(), n))
}

/// Operations a run of an O(N·m) statistic takes over the factors `ms`
/// on N points: Σ (N − k·m)·c·m with k and c the statistic's (MTOTDEV,
/// HTOTDEV: 3 and 15; Theo1: 1 and ½).
pub fn work(stat: &str, n: usize, ms: &[usize]) -> f64 {
    let (k, c) = match stat {
        "mtotdev" | "htotdev" => (3.0, 15.0),
        "theo1" | "theoh" => (1.0, 0.5),
        _ => return ms.len() as f64 * n as f64,
    };
    ms.iter()
        .map(|&m| (n as f64 - k * m as f64).max(0.0) * c * m as f64)
        .sum()
}

/// The most operations ([`work`]) one O(N·m) statistic may take in one
/// run (measured: 2–4 s here on 2 cores): the longer τ are left out, not
/// left to hang.
pub const MAX_WORK: f64 = 1e9;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mtie_is_the_largest_window_range_written_out() {
        let x = [0.0, 3.0, -1.0, 2.0, 5.0, 4.0, -2.0, 1.0];
        for m in 1..x.len() {
            let want = x
                .windows(m + 1)
                .map(|w| {
                    w.iter().cloned().fold(f64::MIN, f64::max)
                        - w.iter().cloned().fold(f64::MAX, f64::min)
                })
                .fold(0.0, f64::max);
            assert_eq!(mtie(&x, m), Some((want, x.len() - m)), "m={m}");
        }
        assert_eq!(mtie(&x, x.len()), None);
    }

    #[test]
    fn a_line_has_no_modified_total_or_hadamard_total_variance() {
        // The half-average line is removed from every subsequence.
        let x: Vec<f64> = (0..60).map(|i| 0.5 + 0.25 * i as f64).collect();
        for m in [2, 3, 5] {
            assert!(mtotvar(&x, m, 1.0, false).unwrap().var < 1e-24, "m={m}");
            let q: Vec<f64> = (0..60).map(|i| (i * i) as f64 * 1e-3).collect();
            assert!(htotvar(&q, m, 1.0, false).unwrap().var < 1e-20, "m={m}");
        }
    }

    #[test]
    fn parallel_runs_give_the_serial_bits() {
        let x: Vec<f64> = (0..5000)
            .map(|i| ((i * 7919) % 1013) as f64 * 1e-3)
            .collect();
        for m in [1, 4, 30] {
            assert_eq!(mtotvar(&x, m, 1.0, true), mtotvar(&x, m, 1.0, false));
            assert_eq!(htotvar(&x, m, 1.0, true), htotvar(&x, m, 1.0, false));
            assert_eq!(
                theo1var(&x, 2 * m, 1.0, true),
                theo1var(&x, 2 * m, 1.0, false)
            );
        }
    }

    #[test]
    fn the_non_overlapping_sums_take_every_mth_term() {
        let x: Vec<f64> = (0..11).map(|i| ((i * 7) % 5) as f64).collect();
        let v = avar(&x, 3, 2.0).unwrap();
        // i = 0, 3 (i + 6 ≤ 10); i = 6 would need x[12].
        let d = |i: usize| x[i + 6] - 2.0 * x[i + 3] + x[i];
        let want = (d(0).powi(2) + d(3).powi(2)) / (2.0 * 2.0 * 36.0);
        assert_eq!(v.n, 2);
        assert!((v.var - want).abs() < 1e-15);
    }
}
