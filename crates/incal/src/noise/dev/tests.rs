//! The kernels against the direct sums of SP 1065, the AVX2 copies against
//! the portable loops, and parallel runs against serial ones.

use super::dense::{dense_sums, DENSE_TOL};
use super::kernels::comb_sq;
#[cfg(target_arch = "x86_64")]
use super::kernels::{comb2_sq_avx2, comb_sq_avx2};
use super::modified::{dense_blocks, mvar_of};
use super::overlapping::{direct_sums, Kind};
use super::prefix::{mvar_many_tol, MVAR_TOL};
use super::sweep::mdev_stats;
use super::*;

/// Deterministic uniform numbers in [−½, ½) (a 64-bit LCG).
/// White FM (x a random walk, with `trend` added per step) and
/// random-walk FM (x the double sum of white noise, plus white phase
/// noise of amplitude `jitter` when not zero) phases of n + 1 samples,
/// the draws of each step in that order.
fn fm_phases(seed: u64, n: usize, trend: f64, jitter: f64) -> (Vec<f64>, Vec<f64>) {
    let mut u = uniform(seed);
    let (mut y, mut xw, mut xr) = (0.0, vec![0.0], vec![0.0]);
    for i in 0..n {
        y += u();
        let j = if jitter != 0.0 { jitter * u() } else { 0.0 };
        xr.push(xr[i] + y + j);
        xw.push(xw[i] + u() + trend);
    }
    (xw, xr)
}

fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

fn data(n: usize) -> Vec<f64> {
    // A deterministic random walk with a trend.
    let mut u = uniform(12345);
    let mut x = vec![0.0];
    for i in 1..n {
        x.push(x[i - 1] + u() + 0.01);
    }
    x
}

fn naive(x: &[f64], m: usize) -> [f64; 4] {
    let n = x.len();
    let d2 = |i: usize| x[i + 2 * m] - 2.0 * x[i + m] + x[i];
    let oa: f64 = (0..n - 2 * m).map(|i| d2(i).powi(2)).sum::<f64>()
        / (2.0 * (m * m) as f64 * (n - 2 * m) as f64);
    let oh: f64 = (0..n - 3 * m)
        .map(|i| (x[i + 3 * m] - 3.0 * x[i + 2 * m] + 3.0 * x[i + m] - x[i]).powi(2))
        .sum::<f64>()
        / (6.0 * (m * m) as f64 * (n - 3 * m) as f64);
    let md: f64 = (0..=n - 3 * m)
        .map(|j| (j..j + m).map(d2).sum::<f64>().powi(2))
        .sum::<f64>()
        / (2.0 * (m as f64).powi(4) * (n - 3 * m + 1) as f64);
    let last = n - 1;
    let xs = |k: isize| {
        if k < 0 {
            2.0 * x[0] - x[(-k) as usize]
        } else if k as usize > last {
            2.0 * x[last] - x[2 * last - k as usize]
        } else {
            x[k as usize]
        }
    };
    let mi = m as isize;
    let tot: f64 = (1..=n as isize - 2)
        .map(|i| (xs(i - mi) - 2.0 * xs(i) + xs(i + mi)).powi(2))
        .sum::<f64>()
        / (2.0 * (m * m) as f64 * (n - 2) as f64);
    [oa, oh, md, tot]
}

/// The AVX2 kernel is the portable one in wider registers: same bits.
#[test]
#[cfg(target_arch = "x86_64")]
fn the_avx2_kernel_gives_the_portable_kernels_bits() {
    if !(std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma"))
    {
        return;
    }
    let mut u = uniform(7);
    let v: Vec<f64> = (0..1010).map(|_| u() * 1e3).collect();
    for n in [0, 1, 7, 8, 9, 15, 1000] {
        let s3 = [&v[2..2 + n], &v[1..1 + n], &v[..n]];
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        let wide = unsafe { comb_sq_avx2(s3) };
        assert_eq!(comb_sq(s3).to_bits(), wide.to_bits(), "n {n}");
        let s4 = [&v[9..9 + n], &v[6..6 + n], &v[3..3 + n], &v[..n]];
        // SAFETY: as above.
        let wide = unsafe { comb_sq_avx2(s4) };
        assert_eq!(comb_sq(s4).to_bits(), wide.to_bits(), "n {n}");
        // SAFETY: as above.
        let (a, h) = unsafe { comb2_sq_avx2(s4) };
        assert_eq!(a.to_bits(), comb_sq([s4[1], s4[2], s4[3]]).to_bits());
        assert_eq!(h.to_bits(), comb_sq(s4).to_bits());
    }
    // The MDEV block statistics through the AVX2 copy: the same bits,
    // block lengths across the eight lanes' split.
    let v: Vec<f64> = (0..COMB_BLOCK + 9).map(|_| u() * 1e3).collect();
    for n in [0, 1, 7, 8, 9, 17, 100, COMB_BLOCK - 1, COMB_BLOCK] {
        let s4 = [&v[9..9 + n], &v[6..6 + n], &v[3..3 + n], &v[..n]];
        let (a, b) = (mdev_stats(s4), avx2_or_not!(mdev_stats(s4)));
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "n {n}");
        assert!(a.iter().all(|s| s.is_finite()));
    }
}

#[test]
fn kernels_equal_the_direct_sums_and_parallel_equals_serial() {
    for n in [9usize, 40, 5000, 70_001] {
        let x = data(n);
        for m in [1usize, 2, 3, 10, 64, n / 4, n / 3, n / 2 - 1] {
            if m == 0 || 3 * m >= n {
                continue;
            }
            let want = naive(&x, m);
            let got = [
                oavar(&x, m, 1.0, false).unwrap().var,
                ohvar(&x, m, 1.0, false).unwrap().var,
                mvar(&x, m, 1.0, false).unwrap().var,
                totvar(&x, m, 1.0, false).unwrap().var,
            ];
            for k in 0..4 {
                assert!(
                    ((got[k] - want[k]) / want[k]).abs() < 1e-9,
                    "n {n} m {m} k {k}: {} vs {}",
                    got[k],
                    want[k]
                );
            }
            let par = [
                oavar(&x, m, 1.0, true).unwrap().var,
                ohvar(&x, m, 1.0, true).unwrap().var,
                mvar(&x, m, 1.0, true).unwrap().var,
                totvar(&x, m, 1.0, true).unwrap().var,
            ];
            assert_eq!(got.map(f64::to_bits), par.map(f64::to_bits));
        }
        let ms: Vec<usize> = (1..n / 3).step_by(1 + n / 40).collect();
        // MDEV by prefix sums: the slides' values to round-off, the
        // same bits serial or parallel.
        let md = mvar_many(&x, &ms, 1.0, true);
        assert_eq!(
            md.iter()
                .map(|v| v.map(|v| v.var.to_bits()))
                .collect::<Vec<_>>(),
            mvar_many(&x, &ms, 1.0, false)
                .iter()
                .map(|v| v.map(|v| v.var.to_bits()))
                .collect::<Vec<_>>()
        );
        for (k, &m) in ms.iter().enumerate() {
            let (a, b) = (md[k].unwrap(), mvar(&x, m, 1.0, false).unwrap());
            assert_eq!(a.n, b.n);
            assert!(((a.var - b.var) / b.var).abs() < 1e-11, "n {n} m {m}");
        }
        let many = oavar_many(&x, &ms, 1.0, true);
        // TOTDEV from the OADEV sums: the same bits as alone.
        let (oa2, tot) = oavar_totvar_many(&x, &ms, 1.0, true);
        assert_eq!(oa2, many);
        for (k, &m) in ms.iter().enumerate() {
            assert_eq!(
                tot[k].map(|v| v.var.to_bits()),
                totvar(&x, m, 1.0, false).map(|v| v.var.to_bits()),
                "n {n} m {m}"
            );
        }
        let hmany = ohvar_many(&x, &ms, 1.0, true);
        // OADEV and OHDEV in one sweep: the same bits as apart, serial
        // or parallel.
        for par in [false, true] {
            let v = stability_vars(&x, &ms, 1.0, par);
            assert_eq!((&v.oa, &v.oh, &v.tot), (&many, &hmany, &tot));
            assert_eq!(v.md, md);
        }
        for (k, &m) in ms.iter().enumerate() {
            assert_eq!(
                many[k].map(|v| v.var.to_bits()),
                oavar(&x, m, 1.0, false).map(|v| v.var.to_bits())
            );
            assert_eq!(
                hmany[k].map(|v| v.var.to_bits()),
                ohvar(&x, m, 1.0, false).map(|v| v.var.to_bits())
            );
        }
        // TOTDEV beyond N/2 (all centres reflected).
        if n > 10 {
            assert!(totvar(&x, n - 3, 1.0, false).unwrap().var.is_finite());
        }
    }
}

/// MDEV of the factors past the prefix superblocks, from the OHDEV
/// sweep's terms (with OADEV and OHDEV, or alone in [`mvar_many`]):
/// the slides' values to round-off (white FM and random-walk FM), the
/// same bits serial or parallel.
#[test]
fn mdev_from_the_sweep_equals_the_slides() {
    let n = (1usize << 18) + 12_345;
    let mut u = uniform(5);
    let mut white = vec![0.0];
    let mut rw = vec![0.0];
    let (mut y, mut z) = (0.0, 0.0);
    for _ in 1..n {
        y += u();
        z += y + u();
        white.push(y);
        rw.push(z);
    }
    let mut ms: Vec<usize> = (0..17).map(|k| 1usize << k).collect();
    ms.extend([50_000, 60_001, 87_000, n / 3]);
    for x in [&white, &rw] {
        let v = stability_vars(x, &ms, 1.0, true);
        assert_eq!(v, stability_vars(x, &ms, 1.0, false));
        // MDEV alone takes the same sums from a sweep of its own.
        for par in [false, true] {
            assert_eq!(mvar_many(x, &ms, 1.0, par), v.md);
        }
        for (k, &m) in ms.iter().enumerate() {
            let (a, b) = (v.md[k].unwrap(), mvar(x, m, 1.0, false).unwrap());
            assert_eq!(a.n, b.n, "m {m}");
            assert!(
                ((a.var - b.var) / b.var).abs() < 1e-10,
                "m {m}: {} vs {}",
                a.var,
                b.var
            );
        }
    }
}

/// Random-walk FM (x the double sum of white noise) and white FM, as
/// the short τ of a long gyro record see them: MDEV by prefix sums
/// matches the slides where its round-off estimate accepts it, the
/// estimate is never below the error it estimates, and where it is
/// too large the factor is slid (so the numbers agree everywhere).
#[test]
fn mvar_prefix_round_off_is_estimated_and_refused_past_the_tolerance() {
    let (xw, xr) = fm_phases(99, 1 << 18, 0.0, 0.0);
    let ms: Vec<usize> = (0..15).map(|k| 1usize << k).collect();
    let mut slid_any = false;
    for (x, name) in [(&xw, "white FM"), (&xr, "random-walk FM")] {
        let slides: Vec<f64> = ms
            .iter()
            .map(|&m| mvar(x, m, 1.0, true).unwrap().var)
            .collect();
        let (raw, _) = mvar_many_tol(x, &ms, 1.0, true, f64::INFINITY);
        let (_, slid) = mvar_many_tol(x, &ms, 1.0, true, 0.0);
        assert!(slid.iter().all(|&s| s), "tol 0 slides every factor");
        let (got, slid) = mvar_many_tol(x, &ms, 1.0, true, MVAR_TOL);
        for k in 0..ms.len() {
            let err = ((raw[k].unwrap().var - slides[k]) / slides[k]).abs();
            let e = ((got[k].unwrap().var - slides[k]) / slides[k]).abs();
            assert!(e <= 10.0 * MVAR_TOL, "{name} m {}: {e:e}", ms[k]);
            if !slid[k] {
                assert!(err <= MVAR_TOL, "{name} m {}: accepted with {err:e}", ms[k]);
            }
            slid_any |= slid[k];
        }
        if name == "white FM" {
            assert!(slid.iter().all(|&s| !s), "white FM needs no slides");
        }
    }
    assert!(slid_any, "random-walk FM at short τ is slid");
}

/// The blocked dense MDEV sums take most of what the whole-record
/// transforms refuse (short τ of a long record), within the
/// tolerance of the slides, every term counted once, parallel =
/// serial; what they refuse is flagged, not returned.
#[test]
fn dense_blocks_take_the_short_factors_within_tolerance() {
    let (xw, xr) = fm_phases(11, 60_000, 0.3, 0.2);
    for (x, name) in [(&xw, "white FM"), (&xr, "random-walk FM")] {
        let mut p = vec![0.0];
        for v in x.iter() {
            p.push(p.last().unwrap() + v);
        }
        let all: Vec<usize> = (1..=x.len() / 3).collect();
        let (_, refused) = dense_sums(&p, &all, Kind::Hadamard, DENSE_TOL, false);
        let ms: Vec<usize> = (0..all.len())
            .filter(|&k| refused[k])
            .map(|k| all[k])
            .collect();
        assert!(ms.len() > 10, "{name}: the whole record refuses short τ");
        let (got, slid) = dense_blocks(x, &ms, true);
        assert_eq!((got.clone(), slid.clone()), dense_blocks(x, &ms, false));
        let taken = slid.iter().filter(|&&r| !r).count();
        // White FM: about three in five here; random-walk FM about a third.
        assert!(
            4 * taken > ms.len(),
            "{name}: blocks took {taken} of {}",
            ms.len()
        );
        for (k, &m) in ms.iter().enumerate() {
            if slid[k] {
                continue;
            }
            let (s, nt) = got[k].unwrap();
            let w = mvar(x, m, 1.0, false).unwrap();
            assert_eq!(nt, w.n, "{name} m {m}");
            let v = mvar_of(s, nt, m, 1.0).var;
            let e = ((v - w.var) / w.var).abs();
            assert!(e <= 2.0 * DENSE_TOL, "{name} m {m}: {e:e}");
        }
    }
}

/// The FFT sums of the dense grids against the direct sums, on white
/// FM (x a random walk, with a trend), random-walk FM and a short
/// record: accepted factors within the tolerance, the estimate never
/// below the error, refused factors summed directly.
#[test]
fn dense_sums_equal_the_direct_sums_within_their_estimate() {
    let (xw, xr) = fm_phases(7, 20_000, 0.3, 0.0);
    let short = data(700);
    let mut refused = 0;
    for (x, name) in [
        (&xw, "white FM"),
        (&xr, "random-walk FM"),
        (&short, "short"),
    ] {
        let ms: Vec<usize> = (1..=x.len() / 3).collect();
        for kind in [Kind::Allan, Kind::Hadamard] {
            let want = direct_sums(x, &ms, kind, false);
            let (raw, _) = dense_sums(x, &ms, kind, f64::INFINITY, false);
            let (got, slid) = dense_sums(x, &ms, kind, DENSE_TOL, true);
            assert_eq!(
                got,
                dense_sums(x, &ms, kind, DENSE_TOL, false).0,
                "parallel = serial"
            );
            let got: Vec<Option<(f64, usize)>> = (0..ms.len())
                .map(|k| if slid[k] { want[k] } else { got[k] })
                .collect();
            for k in 0..ms.len() {
                let Some((w, nw)) = want[k] else {
                    assert!(got[k].is_none());
                    continue;
                };
                let (g, ng) = got[k].unwrap();
                assert_eq!(nw, ng);
                let e = ((g - w) / w).abs();
                assert!(e <= 2.0 * DENSE_TOL, "{name} {kind:?} m {}: {e:e}", ms[k]);
                if slid[k] {
                    refused += 1;
                } else {
                    // What was accepted was as good as the estimate.
                    let er = ((raw[k].unwrap().0 - w) / w).abs();
                    assert!(er <= 2.0 * DENSE_TOL, "{name} {kind:?} m {}", ms[k]);
                }
            }
        }
    }
    assert!(
        refused > 0,
        "random-walk FM at short τ goes to the direct sums"
    );
    // TOTDEV on a dense grid (its interior the OADEV sums by FFT).
    for x in [&xw, &xr] {
        let ms: Vec<usize> = (1..=x.len() / 4).collect();
        let (_, tot) = oavar_totvar_many(x, &ms, 1.0, true);
        for (k, &m) in ms.iter().enumerate() {
            let (g, w) = (tot[k].unwrap().var, totvar(x, m, 1.0, false).unwrap().var);
            assert!(((g - w) / w).abs() <= 2.0 * DENSE_TOL, "TOTDEV m {m}");
        }
    }
    // MDEV on a dense grid (Hadamard sums of the prefix sums by FFT,
    // the refused factors by the superblocks) against the slides.
    for (x, name) in [
        (&xw, "white FM"),
        (&xr, "random-walk FM"),
        (&short, "short"),
    ] {
        let ms: Vec<usize> = (1..=x.len() / 3 + 1).collect();
        let got = mvar_many(x, &ms, 1.0, true);
        assert_eq!(got, mvar_many(x, &ms, 1.0, false), "parallel = serial");
        for (k, &m) in ms.iter().enumerate() {
            let want = mvar(x, m, 1.0, false);
            let Some(w) = want else {
                assert!(got[k].is_none(), "{name} m {m}");
                continue;
            };
            let g = got[k].unwrap();
            assert_eq!(g.n, w.n);
            let e = ((g.var - w.var) / w.var).abs();
            assert!(e <= 2.0 * DENSE_TOL, "{name} MDEV m {m}: {e:e}");
        }
    }
}
