//! The statistics of a Monte Carlo run (JCGM 101:2008 §7.6–§7.9, §8):
//! estimate and standard uncertainty from the trials, the probabilistically
//! symmetric and the shortest coverage intervals, the numerical tolerance
//! of a standard uncertainty stated to `n` significant digits, and the
//! validation of a GUM interval against the Monte Carlo one.

/// Mean and sample standard deviation of `x` (summed in order: the same
/// trials give the same bits whatever ran them).
///
/// `ȳ = Σ y_r / M`, `u² = Σ (y_r − ȳ)² / (M − 1)` (JCGM 101 §7.6, eq. 14–15).
pub fn mean_std(x: &[f64]) -> (f64, f64) {
    let m = x.len() as f64;
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = x.iter().sum::<f64>() / m;
    if x.len() < 2 {
        return (mean, f64::NAN);
    }
    let ss: f64 = x.iter().map(|v| (v - mean).powi(2)).sum();
    (mean, (ss / (m - 1.0)).sqrt())
}

/// The number of sorted values an interval of coverage `p` spans among
/// `m`: `q = pM` when an integer, else `⌊pM + ½⌋` (JCGM 101 §7.7.1).
fn span(m: usize, p: f64) -> usize {
    let pm = p * m as f64;
    let q = if (pm - pm.round()).abs() < 1e-9 {
        pm.round()
    } else {
        (pm + 0.5).floor()
    };
    (q as usize).clamp(1, m.saturating_sub(1).max(1))
}

/// The probabilistically symmetric coverage interval of `sorted` (ascending)
/// for coverage `p`: `[y_(r), y_(r+q)]` with `r = (M − q)/2` when an
/// integer, else `(M − q + 1)/2` (JCGM 101 §7.7.2; 1-based ranks).
pub fn symmetric(sorted: &[f64], p: f64) -> (f64, f64) {
    let m = sorted.len();
    if m < 2 {
        return (f64::NAN, f64::NAN);
    }
    let q = span(m, p);
    // (M − q)/2 when an integer, else (M − q + 1)/2: the ceiling.
    let r = (m - q).div_ceil(2);
    let r = r.max(1);
    (sorted[r - 1], sorted[(r + q - 1).min(m - 1)])
}

/// The shortest coverage interval of `sorted` for coverage `p`: the
/// `[y_(r), y_(r+q)]` of least length over `r = 1 … M − q` (JCGM 101
/// §7.7.3); the first of equal lengths.
pub fn shortest(sorted: &[f64], p: f64) -> (f64, f64) {
    let m = sorted.len();
    if m < 2 {
        return (f64::NAN, f64::NAN);
    }
    let q = span(m, p);
    let mut best = (sorted[0], sorted[q.min(m - 1)]);
    for r in 0..m.saturating_sub(q) {
        let (lo, hi) = (sorted[r], sorted[r + q]);
        if hi - lo < best.1 - best.0 {
            best = (lo, hi);
        }
    }
    best
}

/// The numerical tolerance of a standard uncertainty `u` stated to
/// `digits` significant digits: write `u = c × 10^l` with `c` an integer of
/// `digits` digits, then `δ = ½ × 10^l` (JCGM 101 §7.9.2). `NaN` for a
/// `u` that is zero or not finite.
pub fn tolerance(u: f64, digits: u32) -> f64 {
    if !(u.is_finite() && u > 0.0) {
        return f64::NAN;
    }
    let l = u.log10().floor() - (digits as f64 - 1.0);
    0.5 * 10f64.powf(l)
}

/// The validation of a GUM interval `y ± U` against the Monte Carlo
/// probabilistically symmetric interval `[low, high]` (JCGM 101 §8.2):
/// `d_low = |y − U − low|`, `d_high = |y + U − high|`; validated when both
/// are at most `delta`.
pub fn validate(y: f64, u95: f64, low: f64, high: f64, delta: f64) -> (f64, f64, bool) {
    let d_low = (y - u95 - low).abs();
    let d_high = (y + u95 - high).abs();
    (d_low, d_high, d_low <= delta && d_high <= delta)
}

/// The correlation matrix of the columns of `trials` (`trials[r][j]`:
/// coefficient `j` of trial `r`): `r_jk = s_jk / (s_j s_k)` (JCGM 101
/// §7.6 for the covariance); a column without spread correlates 0 with
/// the others (1 with itself).
pub fn correlation(trials: &[Vec<f64>], n: usize) -> Vec<Vec<f64>> {
    let m = trials.len() as f64;
    let means: Vec<f64> = (0..n)
        .map(|j| trials.iter().map(|t| t[j]).sum::<f64>() / m)
        .collect();
    let mut cov = vec![vec![0.0; n]; n];
    for t in trials {
        for j in 0..n {
            let dj = t[j] - means[j];
            for k in j..n {
                cov[j][k] += dj * (t[k] - means[k]);
            }
        }
    }
    let mut out = vec![vec![0.0; n]; n];
    for j in 0..n {
        for k in j..n {
            let den = (cov[j][j] * cov[k][k]).sqrt();
            let r = if j == k {
                1.0
            } else if den > 0.0 && den.is_finite() {
                (cov[j][k] / den).clamp(-1.0, 1.0)
            } else {
                0.0
            };
            out[j][k] = r;
            out[k][j] = r;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_follow_the_ranks_of_jcgm_101() {
        let x: Vec<f64> = (1..=100).map(f64::from).collect();
        // q = 95, r = (100 − 95 + 1)/2 = 3: [y_3, y_98].
        assert_eq!(symmetric(&x, 0.95), (3.0, 98.0));
        // Equal spacing: every window is as long, the first is kept.
        assert_eq!(shortest(&x, 0.95), (1.0, 96.0));
        // A skewed sample: the shortest interval sits where values crowd.
        let skew: Vec<f64> = (0..1000).map(|i| (i as f64 / 1000.0).powi(3)).collect();
        let (lo, hi) = shortest(&skew, 0.95);
        assert_eq!(lo, 0.0);
        assert!(hi < symmetric(&skew, 0.95).1);
    }

    #[test]
    fn tolerance_is_half_a_unit_of_the_last_stated_digit() {
        // u = 0.0036 to two digits: 36 × 10⁻⁴, δ = 0.5 × 10⁻⁴.
        assert!((tolerance(0.0036, 2) - 0.5e-4).abs() < 1e-18);
        assert!((tolerance(0.0036, 1) - 0.5e-3).abs() < 1e-18);
        assert!((tolerance(12.0, 2) - 0.5).abs() < 1e-15);
        assert!(tolerance(0.0, 2).is_nan());
    }

    #[test]
    fn validation_compares_both_ends() {
        assert!(validate(1.0, 0.2, 0.8, 1.2, 0.01).2);
        assert!(!validate(1.0, 0.2, 0.75, 1.2, 0.01).2);
        assert!(!validate(1.0, 0.2, 0.8, 1.3, 0.01).2);
    }

    #[test]
    fn correlation_of_dependent_columns() {
        let t: Vec<Vec<f64>> = (0..50)
            .map(|i| {
                let x = f64::from(i);
                vec![x, -2.0 * x, 3.0]
            })
            .collect();
        let r = correlation(&t, 3);
        assert!((r[0][1] + 1.0).abs() < 1e-12);
        assert_eq!(r[0][2], 0.0);
        assert_eq!(r[2][2], 1.0);
        let (m, s) = mean_std(&[1.0, 2.0, 3.0]);
        assert_eq!((m, s), (2.0, 1.0));
    }
}
