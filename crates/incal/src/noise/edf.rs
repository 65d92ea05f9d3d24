//! Equivalent degrees of freedom and χ² confidence bounds.
//!
//! EDF of the Allan-family variances by Greenhall & Riley's algorithm
//! ("Uncertainty of stability variances based on finite differences",
//! C. A. Greenhall and W. J. Riley, 35th PTTI, 2003; the algorithm Stable32
//! uses): eqs. (7)–(10) for the exact sums, Tables 1–3 for the large-record
//! asymptotes. TOTDEV: NIST SP 1065 §5.2.11 Table 7.

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Greenhall's `sw(t)` (eq. 7) for power-law exponent `alpha` of S_y.
fn sw(t: f64, alpha: i32) -> f64 {
    let lg = |p: i32| {
        if t == 0.0 {
            0.0
        } else {
            t.powi(p) * t.abs().ln()
        }
    };
    match alpha {
        2 => -t.abs(),
        1 => lg(2),
        0 => t.abs().powi(3),
        -1 => lg(4),
        -2 => t.abs().powi(5),
        -3 => lg(6),
        _ => t.abs().powi(7),
    }
}

/// `sx(t)` (eq. 8): the filter factor F (`None` = F → ∞).
fn sx(t: f64, f: Option<f64>, alpha: i32) -> f64 {
    match f {
        None => sw(t, alpha + 2),
        Some(f) => f * f * (2.0 * sw(t, alpha) - sw(t - 1.0 / f, alpha) - sw(t + 1.0 / f, alpha)),
    }
}

/// `sz(t)` (eq. 9): the d-th difference (binomial weights).
fn sz(t: f64, f: Option<f64>, alpha: i32, d: u32) -> f64 {
    let w: &[f64] = match d {
        1 => &[2.0, -1.0],
        2 => &[6.0, -4.0, 1.0],
        _ => &[20.0, -15.0, 6.0, -1.0],
    };
    let mut s = w[0] * sx(t, f, alpha);
    for (k, wk) in w.iter().enumerate().skip(1) {
        let k = k as f64;
        s += wk * (sx(t - k, f, alpha) + sx(t + k, f, alpha));
    }
    s
}

/// BasicSum (eq. 10).
fn basic_sum(j: f64, m: f64, s: f64, f: Option<f64>, alpha: i32, d: u32) -> f64 {
    let mut sum = sz(0.0, f, alpha, d).powi(2) + (1.0 - j / m) * sz(j / s, f, alpha, d).powi(2);
    let mut k = 1.0;
    while k < j {
        sum += 2.0 * (1.0 - k / m) * sz(k / s, f, alpha, d).powi(2);
        k += 1.0;
    }
    sum
}

/// Table 1 `(a0, a1)`: modified variances (F = 1).
fn table1(alpha: i32, d: u32) -> (f64, f64) {
    const T: [[(f64, f64); 3]; 7] = [
        [
            (2.0 / 3.0, 1.0 / 3.0),
            (7.0 / 9.0, 0.5),
            (22.0 / 25.0, 2.0 / 3.0),
        ],
        [(0.840, 0.345), (0.997, 0.616), (1.141, 0.843)],
        [(1.079, 0.368), (1.033, 0.607), (1.184, 0.848)],
        [(f64::NAN, f64::NAN), (1.048, 0.534), (1.180, 0.816)],
        [(f64::NAN, f64::NAN), (1.302, 0.535), (1.175, 0.777)],
        [(f64::NAN, f64::NAN), (f64::NAN, f64::NAN), (1.194, 0.703)],
        [(f64::NAN, f64::NAN), (f64::NAN, f64::NAN), (1.489, 0.702)],
    ];
    T[(2 - alpha) as usize][(d - 1) as usize]
}

/// Table 2 `(a0, a1)`: unmodified variances (F = m).
fn table2(alpha: i32, d: u32) -> (f64, f64) {
    const T: [[(f64, f64); 3]; 7] = [
        [(1.5, 0.5), (35.0 / 18.0, 1.0), (231.0 / 100.0, 1.5)],
        [(78.6, 25.2), (790.0, 410.0), (9950.0, 6520.0)],
        [
            (2.0 / 3.0, 1.0 / 6.0),
            (2.0 / 3.0, 1.0 / 3.0),
            (7.0 / 9.0, 0.5),
        ],
        [(f64::NAN, f64::NAN), (0.852, 0.375), (0.997, 0.617)],
        [(f64::NAN, f64::NAN), (1.079, 0.368), (1.033, 0.607)],
        [(f64::NAN, f64::NAN), (f64::NAN, f64::NAN), (1.053, 0.553)],
        [(f64::NAN, f64::NAN), (f64::NAN, f64::NAN), (1.302, 0.535)],
    ];
    T[(2 - alpha) as usize][(d - 1) as usize]
}

/// Table 3 `(b0, b1)`: flicker PM (α = 1), unmodified.
fn table3(d: u32) -> (f64, f64) {
    [(6.0, 4.0), (15.23, 12.0), (47.8, 40.0)][(d - 1) as usize]
}

/// Binomial coefficient (small arguments).
fn binom(n: u32, k: u32) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Greenhall & Riley EDF of a variance with `d`-th differences (2 Allan,
/// 3 Hadamard) at averaging factor `m` over `n` phase points, for noise
/// exponent `alpha` (S_y ∝ f^α, clamped to `α + 2d > 1`), overlapping or
/// not, modified (MVAR/TVAR, F = 1) or not (F = m). `None` where the
/// algorithm has no case (white PM with fewer than d+1 strides).
pub fn greenhall(
    alpha: i32,
    d: u32,
    m: usize,
    n: usize,
    overlapping: bool,
    modified: bool,
) -> Option<f64> {
    let alpha = alpha.clamp(2 - 2 * d as i32, 2);
    let mf = m as f64;
    let nf = n as f64;
    let df = d as f64;
    let f = if modified { 1.0 } else { mf };
    let s = if overlapping { mf } else { 1.0 };
    let l = mf / f + mf * df;
    if nf < l {
        return None;
    }
    let big_m = 1.0 + (s * (nf - l) / mf).floor();
    let j = big_m.min((df + 1.0) * s);
    const JMAX: f64 = 100.0;
    let r = big_m / s;
    let inv = if modified {
        if j <= JMAX {
            basic_sum(j, big_m, s, Some(1.0), alpha, d)
                / (sz(0.0, Some(1.0), alpha, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table1(alpha, d);
            (a0 - a1 / r) / r
        } else {
            let mp = JMAX / r;
            basic_sum(JMAX, JMAX, mp, Some(1.0), alpha, d)
                / (sz(0.0, Some(1.0), alpha, d).powi(2) * JMAX)
        }
    } else if alpha <= 0 {
        if j <= JMAX {
            let fp = if mf * (df + 1.0) <= JMAX {
                Some(mf)
            } else {
                None
            };
            basic_sum(j, big_m, s, fp, alpha, d) / (sz(0.0, fp, alpha, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table2(alpha, d);
            (a0 - a1 / r) / r
        } else {
            let mp = JMAX / r;
            basic_sum(JMAX, JMAX, mp, None, alpha, d) / (sz(0.0, None, alpha, d).powi(2) * JMAX)
        }
    } else if alpha == 1 {
        if j <= JMAX {
            basic_sum(j, big_m, s, Some(mf), 1, d) / (sz(0.0, Some(mf), 1, d).powi(2) * big_m)
        } else if r > df + 1.0 {
            let (a0, a1) = table2(1, d);
            let (b0, b1) = table3(d);
            (a0 - a1 / r) / ((b0 + b1 * mf.ln()).powi(2) * r)
        } else {
            let mp = JMAX / r;
            let (b0, b1) = table3(d);
            basic_sum(JMAX, JMAX, mp, Some(mp), 1, d) / ((b0 + b1 * mf.ln()).powi(2) * JMAX)
        }
    } else {
        if r.ceil() <= df {
            return None;
        }
        let a0 = binom(4 * d, 2 * d) / binom(2 * d, d).powi(2);
        (a0 - df / 2.0 / r) / big_m
    };
    let edf = 1.0 / inv;
    (edf.is_finite() && edf > 0.0).then_some(edf)
}

/// EDF of the total variance, NIST SP 1065 Table 7: `b·(N/m) − c` for
/// white FM (b = 1.50, c = 0), flicker FM (1.17, 0.22) and random-walk FM
/// (0.93, 0.36), N phase points; for α ≥ 1 (not in the table) the
/// overlapping Allan EDF, which TOTDEV at least matches.
pub fn totdev(alpha: i32, m: usize, n: usize) -> Option<f64> {
    let (b, c) = match alpha {
        0 => (1.50, 0.0),
        -1 => (1.17, 0.22),
        a if a <= -2 => (0.93, 0.36),
        a => return greenhall(a, 2, m, n, true, false),
    };
    let edf = b * n as f64 / m as f64 - c;
    (edf > 0.0).then_some(edf)
}

/// EDF of Theo1 at factor m (τ = 0.75·m·τ0) on N phase points, NIST SP
/// 1065 Table 11 (Howe & Peppler, "Estimation of very long-term frequency
/// stability using a special-purpose statistic", Proc. 2003 IEEE IFCS /
/// EFTF), with r = 0.75·m:
/// - white PM: `0.86(N+1)(N − 4r/3)/(N − r) · r/(r + 1.14)`;
/// - flicker PM: `(4.798N² − 6.374Nr + 12.387r)/(√(r + 36.6)(N − r)) · r/(r + 0.3)`;
/// - white FM: `((4.1N + 0.8)/r − (3.1N + 6.5)/N) · r^1.5/(r^1.5 + 5.2)`;
/// - flicker FM: `(2N² − 1.3Nr − 3.5r)/(Nr) · r³/(r³ + 2.3)`;
/// - random-walk FM: `(4.4N − 2)/(2.9r) · ((4.4N − 1)² − 8.6r(4.4N − 1) + 11.4r²)/(4.4N − 3)²`.
///
/// `None` where the approximation is not positive (random-walk FM beyond
/// r ≈ 0.63N): no bounds are stated there.
pub fn theo1(alpha: i32, m: usize, n: usize) -> Option<f64> {
    let (nn, r) = (n as f64, 0.75 * m as f64);
    let edf = match alpha {
        a if a >= 2 => 0.86 * (nn + 1.0) * (nn - 4.0 * r / 3.0) / (nn - r) * (r / (r + 1.14)),
        1 => {
            (4.798 * nn * nn - 6.374 * nn * r + 12.387 * r) / ((r + 36.6).sqrt() * (nn - r))
                * (r / (r + 0.3))
        }
        0 => ((4.1 * nn + 0.8) / r - (3.1 * nn + 6.5) / nn) * (r.powf(1.5) / (r.powf(1.5) + 5.2)),
        -1 => (2.0 * nn * nn - 1.3 * nn * r - 3.5 * r) / (nn * r) * (r.powi(3) / (r.powi(3) + 2.3)),
        _ => {
            let a = 4.4 * nn - 1.0;
            (4.4 * nn - 2.0) / (2.9 * r) * (a * a - 8.6 * r * a + 11.4 * r * r)
                / (4.4 * nn - 3.0).powi(2)
        }
    };
    (edf.is_finite() && edf > 0.0).then_some(edf)
}

/// χ² bounds of a deviation: `(σ·√(ν/χ²_{ν,(1+p)/2}), σ·√(ν/χ²_{ν,(1−p)/2}))`
/// for confidence `p` and EDF ν (SP 1065 §5.3.2 eq. 45).
pub fn chi2_bounds(dev: f64, edf: f64, p: f64) -> Option<(f64, f64)> {
    let dist = ChiSquared::new(edf).ok()?;
    let ql = (1.0 - p) / 2.0;
    let (chi_lo, chi_hi) = (dist.inverse_cdf(ql), dist.inverse_cdf(1.0 - ql));
    let lo = dev * (edf / chi_hi).sqrt();
    let hi = dev * (edf / chi_lo).sqrt();
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}
