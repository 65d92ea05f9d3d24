//! The deviations and their bounds against published numbers: NIST SP 1065
//! NBS14 (10-point and 1000-point sets, Table 31 / §12.4) and Stable32 1.60's
//! output for PHASE.DAT (fixtures from allantools' tests/phasedat, with its
//! license beside them).

use incal::noise::{dev, edf, phase_from_rate, stability, Deviation, StabilityOptions, TauGrid};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// NBS14 10-point frequency data (SP 1065 §12.4).
const NBS14_F: [f64; 9] = [
    892.0, 809.0, 823.0, 798.0, 671.0, 644.0, 883.0, 903.0, 677.0,
];

/// SP 1065 §12.4 1000-point set: n_{i+1} = 16807 n_i mod 2147483647,
/// n_0 = 1234567890, normalised by 2147483647.
fn nbs14_1000() -> Vec<f64> {
    let mut n = vec![1_234_567_890u64];
    for i in 0..999 {
        n.push(16807 * n[i] % 2_147_483_647);
    }
    assert_eq!(&n[1..4], &[395_529_916, 1_209_410_747, 633_705_974]);
    n.iter().map(|&v| v as f64 / 2_147_483_647.0).collect()
}

/// The phase of frequency data without removing the mean (SP 1065 eq. 4).
fn raw_phase(y: &[f64]) -> Vec<f64> {
    let mut x = vec![0.0];
    for v in y {
        x.push(x.last().unwrap() + v);
    }
    x
}

fn devs_at(x: &[f64], m: usize) -> [f64; 5] {
    let oa = dev::oavar(x, m, 1.0, true).unwrap().var.sqrt();
    let md = dev::mvar(x, m, 1.0, true).unwrap().var;
    // The prefix-sum MDEV the command uses gives the same value.
    let many = dev::mvar_many(x, &[m], 1.0, true)[0].unwrap().var;
    assert!(((many - md) / md).abs() < 1e-12, "m {m}: {many} vs {md}");
    let oh = dev::ohvar(x, m, 1.0, true).unwrap().var.sqrt();
    let tot = dev::totvar(x, m, 1.0, true).unwrap().var.sqrt();
    [oa, md.sqrt(), oh, dev::tvar(md, m as f64).sqrt(), tot]
}

#[test]
fn nbs14_10_point() {
    // SP 1065 Table 31 (τ = 1, 2): OADEV, MDEV, OHDEV, TDEV, TOTDEV.
    let want = [
        [91.22945, 91.22945, 70.80607, 52.67135, 91.22945],
        [85.95287, 74.78849, 85.61487, 86.35831, 93.90379],
    ];
    for x in [raw_phase(&NBS14_F), phase_from_rate(&NBS14_F, 1.0)] {
        for (k, m) in [1usize, 2].iter().enumerate() {
            let got = devs_at(&x, *m);
            for j in 0..5 {
                assert!(
                    rel(got[j], want[k][j]) < 1e-6,
                    "m={m} dev {j}: {} vs {}",
                    got[j],
                    want[k][j]
                );
            }
        }
    }
}

#[test]
fn nbs14_1000_point() {
    // SP 1065 Table 32 (τ = 1, 10, 100).
    let want = [
        [
            2.922319e-01,
            2.922319e-01,
            2.943883e-01,
            1.687202e-01,
            2.922319e-01,
        ],
        [
            9.159953e-02,
            6.172376e-02,
            9.581083e-02,
            3.563623e-01,
            9.134743e-02,
        ],
        [
            3.241343e-02,
            2.170921e-02,
            3.237638e-02,
            1.253382e+00,
            3.406530e-02,
        ],
    ];
    let y = nbs14_1000();
    for x in [raw_phase(&y), phase_from_rate(&y, 1.0)] {
        for (k, m) in [1usize, 10, 100].iter().enumerate() {
            let got = devs_at(&x, *m);
            for j in 0..5 {
                assert!(
                    rel(got[j], want[k][j]) < 1e-6,
                    "m={m} dev {j}: {} vs {}",
                    got[j],
                    want[k][j]
                );
            }
        }
    }
}

const FIX: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/allantools-phasedat/"
);

/// The numeric rows of a Stable32 result file, including rows allantools
/// commented out with `#`.
fn read_rows_with_commented(name: &str) -> Vec<Vec<f64>> {
    std::fs::read_to_string(format!("{FIX}{name}"))
        .unwrap()
        .lines()
        .filter_map(|l| {
            let r: Option<Vec<f64>> = l
                .trim_start_matches('#')
                .split_whitespace()
                .map(|w| w.parse().ok())
                .collect();
            r.filter(|r| r.len() == 7)
        })
        .collect()
}

fn read_numbers(name: &str) -> Vec<Vec<f64>> {
    std::fs::read_to_string(format!("{FIX}{name}"))
        .unwrap()
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap()).collect())
        .collect()
}

#[test]
fn phase_dat_against_stable32() {
    let x: Vec<f64> = read_numbers("PHASE.DAT")
        .into_iter()
        .map(|r| r[0])
        .collect();
    assert_eq!(x.len(), 1001);
    for parallel in [false, true] {
        let st = stability(
            &x,
            &StabilityOptions {
                tau0_s: 1.0,
                grid: TauGrid::Octave,
                confidence: 0.683,
                parallel,
            },
        )
        .unwrap();
        assert_eq!(st.m, [1, 2, 4, 8, 16, 32, 64, 128]);
        for (d, file) in [
            (Deviation::Oadev, "phase_dat_oadev_octave.txt"),
            (Deviation::Mdev, "phase_dat_mdev_octave.txt"),
            (Deviation::Ohdev, "phase_dat_ohdev_octave.txt"),
            (Deviation::Tdev, "phase_dat_tdev_octave.txt"),
            (Deviation::Totdev, "phase_dat_totdev_octave.txt"),
        ] {
            let s = st.series(d);
            let rows = read_numbers(file);
            let mut checked = 0;
            for r in rows {
                // AF, tau, #, alpha, min, sigma, max
                let Some(k) = st.m.iter().position(|&m| m as f64 == r[0]) else {
                    continue;
                };
                checked += 1;
                let tag = format!("{} m={}", d.as_str(), r[0]);
                if d != Deviation::Totdev {
                    assert_eq!(s.n[k] as f64, r[2], "{tag} n");
                }
                assert_eq!(st.alpha[k], Some(r[3] as i32), "{tag} alpha");
                assert!(
                    rel(s.value[k].unwrap(), r[5]) < 1e-4,
                    "{tag} value {:?} vs {}",
                    s.value[k],
                    r[5]
                );
                assert!(
                    rel(s.lo[k].unwrap(), r[4]) < 1e-2,
                    "{tag} lo {:?} vs {}",
                    s.lo[k],
                    r[4]
                );
                assert!(
                    rel(s.hi[k].unwrap(), r[6]) < 1e-2,
                    "{tag} hi {:?} vs {}",
                    s.hi[k],
                    r[6]
                );
                // Tighter than the contract where the algorithm is Stable32's.
                assert!(
                    rel(s.lo[k].unwrap(), r[4]) < 2e-3,
                    "{tag} lo tight {:?} vs {}",
                    s.lo[k],
                    r[4]
                );
                assert!(
                    rel(s.hi[k].unwrap(), r[6]) < 2e-3,
                    "{tag} hi tight {:?} vs {}",
                    s.hi[k],
                    r[6]
                );
            }
            assert_eq!(checked, 8, "{}", d.as_str());
        }
    }
}

#[test]
fn greenhall_exact_sums_meet_the_paper_asymptotes() {
    // Below J = 100 the algorithm sums exactly (BasicSum, eq. 10); above,
    // it takes the paper's Tables 1–3. Both sides of the switch must agree
    // (edf·m is smooth in m) for every noise type and variance.
    let n = 100_001usize;
    for d in [2u32, 3] {
        let (lo, hi) = (100 / (d as usize + 1), 100 / (d as usize + 1) + 1);
        for modified in [false, true] {
            if modified && d == 3 {
                continue;
            }
            for alpha in [1, 0, -1, -2] {
                if modified && alpha == 1 {
                    continue;
                }
                let e =
                    |m: usize| edf::greenhall(alpha, d, m, n, true, modified).unwrap() * m as f64;
                let (a, b) = (e(lo), e(hi));
                // White FM converges slowest in m (finite-F terms, a few per cent).
                assert!(
                    rel(a, b) < 5e-2,
                    "alpha {alpha} d {d} mod {modified}: {a} vs {b}"
                );
            }
        }
    }
    // White PM, unmodified: the closed form of the paper's case 4.
    let got = edf::greenhall(2, 2, 4, 1001, true, false).unwrap();
    // L = m/F + m·d = 9, M = 1 + floor(S(N − L)/m) = 993, r = M/S.
    let big_m = 993.0;
    let want = big_m / (70.0 / 36.0 - 1.0 / (big_m / 4.0));
    assert!(rel(got, want) < 1e-12, "{got} vs {want}");
}

/// The statistics beyond the default five against Stable32 1.60 on
/// PHASE.DAT: ADEV and HDEV values, n and bounds (Greenhall's EDF for the
/// non-overlapping estimators, as Stable32 uses); MTOTDEV and HTOTDEV
/// values and n, and incal's bounds no narrower than Stable32's (incal uses
/// the parent estimator's EDF, a lower bound); Theo1 values and n at every
/// published factor (10 to 998); MTIE at every published factor.
#[test]
fn phase_dat_more_statistics_against_stable32() {
    use incal::noise::{more, statistic, Statistic};
    let x: Vec<f64> = read_numbers("PHASE.DAT")
        .into_iter()
        .map(|r| r[0])
        .collect();
    let opts = StabilityOptions {
        tau0_s: 1.0,
        grid: TauGrid::Octave,
        confidence: 0.683,
        parallel: false,
    };
    let st = stability(&x, &opts).unwrap();
    for (s, file) in [
        (Statistic::Adev, "phase_dat_adev_octave.txt"),
        (Statistic::Hdev, "phase_dat_hdev_octave.txt"),
    ] {
        let got = statistic(&x, s, &st, &opts).unwrap();
        let mut checked = 0;
        for r in read_numbers(file) {
            let Some(k) = got.taus_s.iter().position(|&t| t == r[1]) else {
                continue;
            };
            checked += 1;
            let tag = format!("{} m={}", s.as_str(), r[0]);
            assert_eq!(got.dev.n[k] as f64, r[2], "{tag} n");
            let v = got.dev.value[k].unwrap();
            assert!(rel(v, r[5]) < 1e-4, "{tag} value {v} vs {}", r[5]);
            let (lo, hi) = (got.dev.lo[k].unwrap(), got.dev.hi[k].unwrap());
            assert!(rel(lo, r[4]) < 3e-3, "{tag} lo {lo} vs {}", r[4]);
            assert!(rel(hi, r[6]) < 3e-3, "{tag} hi {hi} vs {}", r[6]);
        }
        assert_eq!(checked, 8, "{}", s.as_str());
    }
    // MTOTDEV, and HTOTDEV without Stable32's bias correction (the
    // "nobias" run): values and n at every factor incal runs (allantools
    // comments out the rows from m = 32, where its own code disagreed;
    // incal agrees with them, so they are read too). Bounds: incal's
    // relative width at least Stable32's (from the bias-corrected runs).
    for (s, values, bounds) in [
        (
            Statistic::Mtotdev,
            "phase_dat_mtotdev_octave.txt",
            "phase_dat_mtotdev_octave.txt",
        ),
        (
            Statistic::Htotdev,
            "phase_dat_htotdev_octave_nobias.txt",
            "phase_dat_htotdev_octave.txt",
        ),
    ] {
        let got = statistic(&x, s, &st, &opts).unwrap();
        let widths = read_rows_with_commented(bounds);
        let mut checked = 0;
        for r in read_rows_with_commented(values) {
            let Some(k) = got.taus_s.iter().position(|&t| t == r[1]) else {
                continue;
            };
            checked += 1;
            let tag = format!("{} m={}", s.as_str(), r[0]);
            assert_eq!(got.dev.n[k] as f64, r[2], "{tag} n");
            let v = got.dev.value[k].unwrap();
            assert!(rel(v, r[5]) < 1e-4, "{tag} value {v} vs {}", r[5]);
            let w = widths.iter().find(|w| w[0] == r[0]).unwrap();
            let (lo, hi) = (got.dev.lo[k].unwrap(), got.dev.hi[k].unwrap());
            assert!(
                (hi - lo) / v >= 0.99 * (w[6] - w[4]) / w[5],
                "{tag}: [{lo}, {hi}] narrower than Stable32's [{}, {}]",
                w[4],
                w[6]
            );
        }
        assert_eq!(checked, 8, "{}", s.as_str());
    }
    let mut checked = 0;
    for r in read_numbers("phase_dat_theo1_alpha0.txt") {
        let m = r[0] as usize;
        let v = more::theo1var(&x, m, 1.0, false).unwrap();
        assert!(
            rel(v.var.sqrt(), r[5]) < 1e-4,
            "theo1 m={m}: {} vs {}",
            v.var.sqrt(),
            r[5]
        );
        assert_eq!(0.75 * m as f64, r[1]);
        checked += 1;
    }
    assert_eq!(checked, 181);
    // (Stable32 with "Alpha = 0": no bias correction, as incal.)
    // On the octave grid Theo1 runs at even factors to N − 1, τ = 0.75 m.
    let th = statistic(&x, Statistic::Theo1, &st, &opts).unwrap();
    assert_eq!(th.taus_s.first(), Some(&1.5));
    assert_eq!(th.taus_s.last(), Some(&(0.75 * 512.0)));
    for r in read_numbers("phase_dat_mtie.txt") {
        let (v, n) = more::mtie(&x, r[0] as usize).unwrap();
        assert_eq!(n as f64, r[2], "mtie m={} n", r[0]);
        assert!(rel(v, r[3]) < 1e-4, "mtie m={}: {v} vs {}", r[0], r[3]);
    }
}
