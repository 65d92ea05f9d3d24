//! IMU triad calibration from simulated sessions with a known truth: the
//! stated U95 covers the truth 92–98 % of the time for every parameter.

use incal::procedures::imu::ferraris::{element_names, ferraris, FerrarisOptions, SECTIONS};
use incal::sim::imu::{simulate, ImuSim, ImuTruth, Sequence};
use incal::sim::tier::{band, trials};
use incal::sim::{monte_carlo, trial_seed};

/// Sessions per coverage check: 300 in the statistical tier.
fn seeds() -> usize {
    trials(40, 300)
}

fn ferraris_session(truth: ImuTruth, seed: u64) -> [Vec<[f64; 6]>; 9] {
    let s = simulate(&ImuSim {
        truth,
        sequence: Sequence::Ferraris {
            rotation_deg: -360.0,
            rotation_s: 4.0,
        },
        rate_hz: 100.0,
        static_s: 2.0,
        gravity: 9.81,
        noise_acc: 3.0,
        noise_gyr: 2.0,
        latitude_deg: None,
        seed,
    })
    .unwrap();
    let mut out: [Vec<[f64; 6]>; 9] = Default::default();
    for x in s {
        let k = SECTIONS.iter().position(|l| *l == x.part).unwrap();
        out[k].push([x.acc[0], x.acc[1], x.acc[2], x.gyr[0], x.gyr[1], x.gyr[2]]);
    }
    out
}

/// Coverage of `|x̂ − x| ≤ U95` per parameter over the trials.
fn check_coverage(label: &str, names: &[String], hits: &[Vec<bool>]) {
    let mut bad = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let n = hits.iter().filter(|h| h[k]).count();
        let rate = n as f64 / hits.len() as f64;
        eprintln!("{label} {name}: {:.1} %", 100.0 * rate);
        // The diagonal of a unit-norm row (R_a.xx, R_g.yy, …) is
        // sqrt(1 − Σ off-diagonal²): its error is second order where the
        // off-diagonals are near zero, so the first-order u can only
        // over-cover there; it must not under-cover.
        let unit_row_diagonal = name.starts_with("R_")
            && name.as_bytes()[name.len() - 1] == name.as_bytes()[name.len() - 2];
        let (lo, hi) = band(hits.len(), 0.92, 0.98);
        let ok = if unit_row_diagonal {
            rate >= lo
        } else {
            (lo..=hi).contains(&rate)
        };
        if !ok {
            bad.push(format!("{name} {:.1} %", 100.0 * rate));
        }
    }
    assert!(
        bad.is_empty(),
        "{label}: U95 coverage outside 92-98 % (widened by the binomial spread of a small count) over {} trials: {}",
        hits.len(),
        bad.join(", ")
    );
}

#[test]
fn ferraris_u95_covers_the_truth() {
    let names = element_names();
    let keep: Vec<usize> = (0..names.len())
        .filter(|&k| {
            let n = &names[k];
            // The off-diagonal zeros of K_a and K_g are structural.
            !((n.starts_with("K_a.") || n.starts_with("K_g."))
                && n.as_bytes()[n.len() - 1] != n.as_bytes()[n.len() - 2])
        })
        .collect();
    let hits = monte_carlo(11, seeds(), |seed| {
        let truth = ImuTruth::random_around_mems(trial_seed(seed, 1));
        let want = truth.ferraris().to_vec();
        let r = ferraris(
            &ferraris_session(truth, seed),
            &FerrarisOptions::imucal(100.0),
        )
        .unwrap();
        let k95 = r.estimates.coverage_factor(0.95);
        keep.iter()
            .map(|&k| (r.estimates.values()[k] - want[k]).abs() <= k95 * r.estimates.u_at(k))
            .collect::<Vec<bool>>()
    });
    let kept: Vec<String> = keep.iter().map(|&k| names[k].clone()).collect();
    check_coverage("ferraris", &kept, &hits);
}

mod autocal {
    use super::*;
    use incal::procedures::imu::autocal::{autocal, AutocalOptions, Method};
    use incal::procedures::imu::M3;

    /// A random-orientation session from a truth without g-sensitivity
    /// (outside the autocalibration model).
    /// Truth, time, raw accelerometer and gyro samples.
    pub type Session = (ImuTruth, Vec<f64>, Vec<[f64; 3]>, Vec<[f64; 3]>);

    pub fn session(seed: u64) -> Session {
        simulated(
            seed,
            2,
            Sequence::Random {
                positions: 30,
                init_s: 10.0,
                move_s: 1.5,
            },
            2.5,
        )
    }

    /// A session of `sequence` (static positions of `static_s` s) from a
    /// truth drawn from trial stream `stream`, without g-sensitivity.
    pub fn simulated(seed: u64, stream: u64, sequence: Sequence, static_s: f64) -> Session {
        let mut truth = ImuTruth::random_around_mems(trial_seed(seed, stream));
        truth.gyr_k_ga = M3::zeros();
        let s = simulate(&ImuSim {
            truth: truth.clone(),
            sequence,
            rate_hz: 100.0,
            static_s,
            gravity: 9.81,
            noise_acc: 3.0,
            noise_gyr: 2.0,
            latitude_deg: None,
            seed,
        })
        .unwrap();
        let time = s.iter().map(|x| x.time_s).collect();
        let acc = s.iter().map(|x| [x.acc[0], x.acc[1], x.acc[2]]).collect();
        let gyr = s.iter().map(|x| [x.gyr[0], x.gyr[1], x.gyr[2]]).collect();
        (truth, time, acc, gyr)
    }

    /// Whether `|x̂ − x| ≤ U95` for each parameter of `e` against `want`.
    pub fn u95_hits(e: &incal::estimation::Estimates, want: &[f64]) -> Vec<bool> {
        let k95 = e.coverage_factor(0.95);
        (0..want.len())
            .map(|k| (e.values()[k] - want[k]).abs() <= k95 * e.u_at(k))
            .collect()
    }

    pub fn truth_vector(t: &ImuTruth) -> Vec<f64> {
        let (a, g) = t.imu_tk().unwrap();
        let mut v: Vec<f64> = a.mis[..3].to_vec();
        v.extend(a.scale);
        v.extend(a.bias);
        v.extend(g.mis);
        v.extend(g.scale);
        v.extend(g.bias);
        v
    }

    #[test]
    fn one_session_recovers_the_truth() {
        for method in [Method::Incal, Method::Tedaldi] {
            let (truth, time, acc, gyr) = session(5);
            let r = autocal(
                &time,
                &acc,
                Some(&gyr),
                &AutocalOptions::new(method, 9.81, 10.0),
            )
            .unwrap();
            let want = truth_vector(&truth);
            for (k, name) in r.estimates.names().iter().enumerate() {
                let (x, u) = (r.estimates.values()[k], r.estimates.u_at(k));
                eprintln!(
                    "{:?} {name}: {x:.6e} truth {:.6e} u {u:.2e} z {:.2}",
                    method,
                    want[k],
                    (x - want[k]) / u
                );
            }
            eprintln!(
                "k {} intervals {} orientations {}",
                r.k,
                r.intervals.len(),
                r.orientations
            );
            for (k, name) in r.estimates.names().iter().enumerate() {
                let (x, u) = (r.estimates.values()[k], r.estimates.u_at(k));
                assert!((x - want[k]).abs() < 6.0 * u, "{method:?} {name}");
            }
        }
    }
}

#[test]
fn autocal_incal_u95_covers_the_truth() {
    use incal::procedures::imu::autocal::{autocal as run, AutocalOptions, Method};
    let mut names = Vec::new();
    let hits = monte_carlo(23, trials(40, 400), |seed| {
        let (truth, time, acc, gyr) = autocal::session(seed);
        let r = run(
            &time,
            &acc,
            Some(&gyr),
            &AutocalOptions::new(Method::Incal, 9.81, 10.0),
        )
        .unwrap();
        let want = autocal::truth_vector(&truth);
        (
            r.estimates.names().to_vec(),
            autocal::u95_hits(&r.estimates, &want),
        )
    });
    names.extend(hits[0].0.iter().cloned());
    let h: Vec<Vec<bool>> = hits.into_iter().map(|x| x.1).collect();
    check_coverage("autocal incal", &names, &h);
}

/// A hand-held session on a cube fixture, as the RealSense T265 recording
/// published with imu_tk (41 still intervals on 6 faces, each 2.5–4.5°
/// off the sensor axes): a still start, then 40 quarter turns
/// ([`Sequence::Faces`], tilts of 3° standard deviation), no
/// g-sensitivity.
fn faces_session(seed: u64) -> autocal::Session {
    autocal::simulated(
        seed,
        5,
        Sequence::Faces {
            positions: 40,
            init_s: 10.0,
            move_s: 1.5,
        },
        3.0,
    )
}

/// On cube-face sessions (the T265 recording's kind) incal's U95 covers
/// the truth at its stated rate, pooled per group of parameters; imu_tk's
/// estimator (`--method tedaldi`) does not: its gyro misalignments miss
/// the truth by several of its own U95 (printed; measured 2026-11-26 over
/// 13 CLI sessions: 58 of 273 parameters beyond U95, the gyro
/// misalignments m_xz, m_xy, m_yx up to 8.8 U95). This is why the two
/// disagree on the T265 recording ([`imu_tk_recordings`] test file).
#[test]
fn autocal_on_cube_faces_incal_covers_and_tedaldi_misses() {
    use incal::procedures::imu::autocal::{autocal as run, AutocalOptions, Method};
    let n_trials = trials(24, 60);
    // Groups: acc misalignment, scale, bias (0..9); gyro misalignment
    // (9..15), scale (15..18), bias (18..21).
    let groups = [(0, 3), (3, 6), (6, 9), (9, 15), (15, 18), (18, 21)];
    let mut pooled = Vec::new();
    for method in [Method::Incal, Method::Tedaldi] {
        let hits = monte_carlo(29, n_trials, |seed| {
            let (truth, time, acc, gyr) = faces_session(seed);
            let r = run(
                &time,
                &acc,
                Some(&gyr),
                &AutocalOptions::new(method, 9.81, 10.0),
            )
            .unwrap();
            autocal::u95_hits(&r.estimates, &autocal::truth_vector(&truth))
        });
        let rates: Vec<f64> = groups
            .iter()
            .map(|&(a, b)| {
                let n: usize = hits
                    .iter()
                    .map(|h| h[a..b].iter().filter(|x| **x).count())
                    .sum();
                n as f64 / (n_trials * (b - a)) as f64
            })
            .collect();
        eprintln!("{method:?} coverage by group (acc m, s, b; gyr m, s, b): {rates:.3?}");
        pooled.push(rates);
    }
    for ((g, r), (a, b)) in pooled[0].iter().enumerate().zip(groups) {
        let (lo, hi) = band(n_trials * (b - a), 0.90, 0.99);
        assert!((lo..=hi).contains(r), "incal group {g}: {r:.3}");
    }
    // The miss is asserted at 0.85, plus three binomial spreads of a
    // small count in the fast tier.
    let (_, miss) = band(n_trials * 6, 0.71, 0.85);
    assert!(
        pooled[1][3] < miss,
        "tedaldi's gyro misalignments cover at {:.3}: imu_tk's estimator no longer misses on faces, revisit the T265 note",
        pooled[1][3]
    );
}

mod multipos {
    use super::*;
    use incal::procedures::imu::multipos::{
        multipos, MatrixForm, MultiposOptions, RotationSection, StaticPosition,
    };
    use incal::procedures::imu::{SectionStats, M3, V3};

    /// Faces and edges of a cube: 18 up directions.
    pub fn cube18() -> Vec<V3> {
        let mut v = Vec::new();
        for k in 0..3 {
            for s in [1.0, -1.0] {
                let mut e = V3::zeros();
                e[k] = s;
                v.push(e);
            }
        }
        for (a, b) in [(0, 1), (0, 2), (1, 2)] {
            for (sa, sb) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                let mut e = V3::zeros();
                e[a] = sa;
                e[b] = sb;
                v.push(e.normalize());
            }
        }
        v
    }

    pub fn run(
        truth: &ImuTruth,
        up: Vec<V3>,
        rotations: bool,
        matrix: MatrixForm,
        seed: u64,
    ) -> incal::Result<incal::procedures::imu::multipos::MultiposResult> {
        let s = simulate(&ImuSim {
            truth: truth.clone(),
            sequence: Sequence::Positions {
                up: up.clone(),
                rotations: rotations.then_some((-360.0, 4.0)),
            },
            rate_hz: 100.0,
            static_s: 2.0,
            gravity: 9.81,
            noise_acc: 3.0,
            noise_gyr: 2.0,
            latitude_deg: None,
            seed,
        })
        .unwrap();
        let mut statics = Vec::new();
        let mut rots = Vec::new();
        let mut k = 0;
        while k < s.len() {
            let label = s[k].part.clone();
            let mut block = Vec::new();
            let first = k;
            while k < s.len() && s[k].part == label {
                let x = &s[k];
                block.push([x.acc[0], x.acc[1], x.acc[2], x.gyr[0], x.gyr[1], x.gyr[2]]);
                k += 1;
            }
            let stats = SectionStats::of(&block).unwrap();
            if let Some(axis) = ["x_rot", "y_rot", "z_rot"].iter().position(|l| *l == label) {
                rots.push(RotationSection { label, axis, stats });
            } else {
                statics.push(StaticPosition {
                    label,
                    up: s[first].up.unwrap() / 9.81f64.signum(),
                    north: None,
                    stats,
                });
            }
        }
        multipos(
            &statics,
            &rots,
            &MultiposOptions {
                gravity: 9.81,
                matrix,
                rate_hz: 100.0,
                latitude_deg: None,
                rotation_deg: -360.0,
                gyro: true,
            },
        )
    }

    /// The truth of every multipos parameter, by name.
    pub fn truth_of(t: &ImuTruth, name: &str) -> f64 {
        let ax = |c: u8| (c - b'x') as usize;
        let b = name.as_bytes();
        let (tri, rest) = name.split_once('.').unwrap();
        let a_g = t.gyr_a * std::f64::consts::PI / 180.0; // output/(deg/s)
        let m = |tri: &str| if tri == "acc" { t.acc_a } else { a_g };
        match &rest[..2] {
            "b_" => {
                let v = if tri == "acc" { t.acc_b } else { t.gyr_b };
                v[ax(b[b.len() - 1])]
            }
            "A_" => m(tri)[(ax(b[b.len() - 2]), ax(b[b.len() - 1]))],
            "G_" => t.gyr_k_ga[(ax(b[b.len() - 2]), ax(b[b.len() - 1]))],
            "S_" => {
                let j = ax(b[b.len() - 1]);
                m(tri)[(j, j)]
            }
            "M_" => {
                let (j, k) = (ax(b[b.len() - 2]), ax(b[b.len() - 1]));
                m(tri)[(j, k)] / m(tri)[(j, j)]
            }
            _ => panic!("{name}"),
        }
    }

    #[test]
    fn poor_position_set_is_refused_by_name() {
        // Every position about the z axis (up always in the x-y plane):
        // the z terms cannot be separated from the biases.
        let up: Vec<V3> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::PI / 4.0;
                V3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let e = run(&ImuTruth::mems_counts(), up, false, MatrixForm::Full, 1).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("acc.A_xz") || msg.contains("acc.b_x"), "{msg}");
        let _ = M3::zeros();
    }
}

#[test]
fn multipos_u95_covers_the_truth() {
    use incal::procedures::imu::multipos::MatrixForm;
    for (matrix, rotations) in [(MatrixForm::Full, true), (MatrixForm::Upper, false)] {
        let mut names: Vec<String> = Vec::new();
        let trials = monte_carlo(31, seeds(), |seed| {
            let mut truth = ImuTruth::random_around_mems(trial_seed(seed, 3));
            if matrix == MatrixForm::Upper {
                // An upper-triangular accelerometer matrix.
                for (j, k) in [(1, 0), (2, 0), (2, 1)] {
                    truth.acc_a[(j, k)] = 0.0;
                }
            }
            let r = multipos::run(&truth, multipos::cube18(), rotations, matrix, seed).unwrap();
            let k95 = r.estimates.coverage_factor(0.95);
            let names = r.estimates.names().to_vec();
            let hits: Vec<bool> = names
                .iter()
                .enumerate()
                .map(|(k, n)| {
                    (r.estimates.values()[k] - multipos::truth_of(&truth, n)).abs()
                        <= k95 * r.estimates.u_at(k)
                })
                .collect();
            (names, hits)
        });
        names.extend(trials[0].0.iter().cloned());
        let h: Vec<Vec<bool>> = trials.into_iter().map(|x| x.1).collect();
        check_coverage(&format!("multipos {}", matrix.name()), &names, &h);
    }
}
