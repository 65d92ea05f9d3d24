//! The dense-grid sums by FFT ([`dense_sums`]): the squared second or
//! third differences at every lag at once from the autocorrelation and
//! wedge sums of the detrended record, with their round-off estimate,
//! and the least-squares detrending ([`detrend`]).

use super::overlapping::Kind;
use crate::noise::ordered_map;

/// Largest estimated round-off of the FFT sums, relative to the sum,
/// that `dense_sums` accepts; past it the factor is summed directly.
pub const DENSE_TOL: f64 = 1e-9;

/// The sums of [`many_sums`](super::overlapping::many_sums) from lagged
/// products of the whole record.
///
/// With `u` the record less its least-squares line (Allan) or parabola
/// (Hadamard), to which the differences are blind, and
/// `S(m) = Σ_{j<n} (Σ_k w_k u_{j+km})²`, `n = L − (K−1)m`, the square is
/// expanded: the squares are differences of the prefix sums of `u²`; each
/// cross term `Σ_{j<n} u_{j+km} u_{j+lm}` is the autocorrelation
/// `R((l−k)m)` less the products cut off at the ends of the record, which
/// are wedge sums (`crate::noise::corr::wedge`) of `u` and of `u` reversed:
///
/// * Allan (`w = 1, −2, 1`): `S = Σw²·squares − 4(R(m) − G₁'(m))
///   − 4(R(m) − G₁(m)) + 2R(2m)`;
/// * Hadamard (`w = −1, 3, −3, 1`): `S = Σw²·squares − 6(R(m) − G₂'(m))
///   − 18(R(m) − G₁'(m) − G₁(m)) − 6(R(m) − G₂(m))
///   + 6(R(2m) − G½'(2m)) + 6(R(2m) − G½(2m)) − 2R(3m)`,
///
/// `G_c(d) = Σ_{t<c·d} u_t u_{t+d}`, `'` on the reversed record. All of it
/// costs O(L log² L) for every m at once instead of O(L) per m.
///
/// Round-off: every FFT value carries about `4ε·log₂(n_FFT)·Σu²`, so S
/// carries `(Σ|w|)²` times that; a factor whose estimate exceeds `tol`
/// relative to S (short τ of a record with much random-walk FM) is summed
/// directly by the caller. Returns the sums (`None` where refused or
/// undefined) and which factors were refused. Same numbers serial or
/// parallel.
pub(super) fn dense_sums(
    x: &[f64],
    ms: &[usize],
    kind: Kind,
    tol: f64,
    parallel: bool,
) -> (Vec<Option<(f64, usize)>>, Vec<bool>) {
    use crate::noise::corr::{autocorr, wedge};
    let l = x.len();
    let (span, deg) = match kind {
        Kind::Allan => (2, 1),
        Kind::Hadamard => (3, 2),
    };
    let terms = |m: usize| l.checked_sub(span * m).filter(|&n| n > 0 && m > 0);
    let mmax = ms
        .iter()
        .copied()
        .filter(|&m| terms(m).is_some())
        .max()
        .unwrap_or(0);
    let mut out: Vec<Option<(f64, usize)>> = vec![None; ms.len()];
    let mut slid = vec![false; ms.len()];
    if mmax == 0 {
        return (out, slid);
    }
    let u = detrend(x, deg);
    let ur: Vec<f64> = u.iter().rev().copied().collect();
    // The transforms, each independent (parallel = serial).
    type Job<'a> = Box<dyn Fn() -> Vec<f64> + Sync + Send + 'a>;
    let (u, ur) = (&u[..], &ur[..]);
    let mut jobs: Vec<Job> = vec![
        Box::new(move || autocorr(u, span * mmax)),
        Box::new(move || wedge(u, 1, 1, mmax)),
        Box::new(move || wedge(ur, 1, 1, mmax)),
    ];
    if kind == Kind::Hadamard {
        jobs.push(Box::new(move || wedge(u, 2, 1, mmax)));
        jobs.push(Box::new(move || wedge(ur, 2, 1, mmax)));
        jobs.push(Box::new(move || wedge(u, 1, 2, 2 * mmax)));
        jobs.push(Box::new(move || wedge(ur, 1, 2, 2 * mmax)));
    }
    let res: Vec<Vec<f64>> = ordered_map(jobs.len(), parallel, |i| jobs[i]());
    let r = &res[0];
    let (g1, g1r) = (&res[1], &res[2]);
    // Prefix sums of u².
    let mut q = Vec::with_capacity(l + 1);
    q.push(0.0);
    let mut acc = 0.0;
    for v in u {
        acc += v * v;
        q.push(acc);
    }
    let sq = |a: usize, n: usize| q[a + n] - q[a];
    let nfft = (l + span * mmax + 1).next_power_of_two() as f64;
    let wabs: f64 = match kind {
        Kind::Allan => 4.0,
        Kind::Hadamard => 8.0,
    };
    let err = 4.0 * f64::EPSILON * nfft.log2() * acc * wabs * wabs;
    let mut redo = Vec::new();
    for (k, &m) in ms.iter().enumerate() {
        let Some(n) = terms(m) else { continue };
        let s = match kind {
            Kind::Allan => {
                sq(0, n) + 4.0 * sq(m, n) + sq(2 * m, n)
                    - 4.0 * (r[m] - g1r[m])
                    - 4.0 * (r[m] - g1[m])
                    + 2.0 * r[2 * m]
            }
            Kind::Hadamard => {
                let (g2, g2r, gh, ghr) = (&res[3], &res[4], &res[5], &res[6]);
                sq(0, n) + 9.0 * sq(m, n) + 9.0 * sq(2 * m, n) + sq(3 * m, n)
                    - 6.0 * (r[m] - g2r[m])
                    - 18.0 * (r[m] - g1r[m] - g1[m])
                    - 6.0 * (r[m] - g2[m])
                    + 6.0 * (r[2 * m] - ghr[2 * m])
                    + 6.0 * (r[2 * m] - gh[2 * m])
                    - 2.0 * r[3 * m]
            }
        };
        if s > 0.0 && err <= tol * s {
            out[k] = Some((s, n));
        } else {
            redo.push(k);
        }
    }
    for k in redo {
        slid[k] = true;
    }
    (out, slid)
}

/// `x` less its least-squares polynomial of degree `deg` (1 or 2) in the
/// sample index (scaled to [−1, 1] for conditioning).
pub(crate) fn detrend(x: &[f64], deg: usize) -> Vec<f64> {
    use nalgebra::{Matrix3, Vector3};
    let n = x.len();
    if n <= deg + 1 {
        return x.to_vec();
    }
    let c = (n as f64 - 1.0) / 2.0;
    let basis = |i: usize| {
        let t = (i as f64 - c) / c;
        Vector3::new(1.0, t, if deg >= 2 { t * t } else { 0.0 })
    };
    let mut a = Matrix3::<f64>::zeros();
    let mut b = Vector3::<f64>::zeros();
    for (i, &v) in x.iter().enumerate() {
        let p = basis(i);
        a += p * p.transpose();
        b += p * v;
    }
    if deg < 2 {
        a[(2, 2)] = 1.0;
    }
    let coef = a
        .try_inverse()
        .map(|ai| ai * b)
        .unwrap_or_else(Vector3::zeros);
    x.iter()
        .enumerate()
        .map(|(i, &v)| v - coef.dot(&basis(i)))
        .collect()
}
