//! `--method tedaldi` against a straightforward reimplementation of imu_tk's
//! steps (written here independently: naive windows, Levenberg–Marquardt on
//! the normal equations with its own Jacobians and its own RK4): every
//! parameter agrees to 1e-9 relative on simulated sessions.

use incal::procedures::imu::autocal::{autocal, AutocalOptions, Method};
use incal::procedures::imu::M3;
use incal::sim::imu::{simulate, ImuSim, ImuTruth, Sequence};
use nalgebra::{DMatrix, DVector};

type V = [f64; 3];

fn var_of(x: &[V], a: usize, b: usize) -> V {
    let n = (b - a + 1) as f64;
    let mut m = [0.0; 3];
    for s in &x[a..=b] {
        for k in 0..3 {
            m[k] += s[k];
        }
    }
    for v in m.iter_mut() {
        *v /= n;
    }
    let mut v = [0.0; 3];
    for s in &x[a..=b] {
        for k in 0..3 {
            v[k] += (s[k] - m[k]) * (s[k] - m[k]);
        }
    }
    v.map(|q| q / (n - 1.0))
}

fn mean_of(x: &[V], a: usize, b: usize) -> V {
    let n = (b - a + 1) as f64;
    let mut m = [0.0; 3];
    for s in &x[a..=b] {
        for k in 0..3 {
            m[k] += s[k] / 1.0;
        }
    }
    m.map(|q| q / n)
}

fn nrm(v: V) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// imu_tk's staticIntervalsDetector (window 101).
fn detect(x: &[V], th: f64) -> Vec<(usize, usize)> {
    let h = 50;
    let mut out = Vec::new();
    let mut start = None;
    for i in h..x.len() - h {
        let v = nrm(var_of(x, i - h, i + h));
        match start {
            None => {
                if v < th {
                    start = Some(i)
                }
            }
            Some(s) => {
                if v >= th {
                    out.push((s, i - 1));
                    start = None;
                }
            }
        }
    }
    if let Some(s) = start {
        out.push((s, x.len() - h - 1));
    }
    out
}

/// Calibrate with p = [m_yz, m_zy, m_zx, m_xz, m_xy, m_yx, sx, sy, sz, bx, by, bz].
fn cal(p: &[f64; 12], r: V) -> V {
    let v = [
        (r[0] - p[9]) * p[6],
        (r[1] - p[10]) * p[7],
        (r[2] - p[11]) * p[8],
    ];
    [
        v[0] - p[0] * v[1] + p[1] * v[2],
        p[3] * v[0] + v[1] - p[2] * v[2],
        -p[4] * v[0] + p[5] * v[1] + v[2],
    ]
}

/// Levenberg–Marquardt on the normal equations, forward-difference
/// Jacobian, until the cost stops decreasing.
fn lm(f: &dyn Fn(&[f64]) -> Vec<f64>, x0: Vec<f64>, step: &dyn Fn(usize, f64) -> f64) -> Vec<f64> {
    let mut x = x0;
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let mut r = f(&x);
    let mut c = cost(&r);
    let mut lambda = 1e-6;
    for _ in 0..500 {
        let n = x.len();
        let mut j = DMatrix::zeros(r.len(), n);
        for k in 0..n {
            let h = step(k, x[k]);
            let mut xp = x.clone();
            xp[k] += h;
            let mut xm = x.clone();
            xm[k] -= h;
            let (rp, rm) = (f(&xp), f(&xm));
            for i in 0..r.len() {
                j[(i, k)] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let rv = DVector::from_vec(r.clone());
        let jtj = j.transpose() * &j;
        let g = j.transpose() * rv;
        let mut improved = false;
        for _ in 0..30 {
            let mut a = jtj.clone();
            for k in 0..n {
                a[(k, k)] *= 1.0 + lambda;
            }
            let d = a.cholesky().unwrap().solve(&(-&g));
            let xn: Vec<f64> = x.iter().zip(d.iter()).map(|(a, b)| a + b).collect();
            let rn = f(&xn);
            let cn = cost(&rn);
            if cn <= c {
                // Go on while the step still moves a parameter by more
                // than 1e-14 of its size.
                improved = d
                    .iter()
                    .zip(&x)
                    .any(|(dk, xk)| dk.abs() > 1e-14 * xk.abs().max(1e-6));
                x = xn;
                r = rn;
                c = cn;
                lambda = (lambda / 10.0).max(1e-12);
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    // Then plain Gauss–Newton steps on the normal equations: they solve
    // Jᵀr = 0, which pins the minimum far below the cost's rounding.
    for _ in 0..6 {
        let n = x.len();
        let mut j = DMatrix::zeros(r.len(), n);
        for k in 0..n {
            let h = step(k, x[k]);
            let mut xp = x.clone();
            xp[k] += h;
            let mut xm = x.clone();
            xm[k] -= h;
            let (rp, rm) = (f(&xp), f(&xm));
            for i in 0..r.len() {
                j[(i, k)] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let g = j.transpose() * DVector::from_vec(r.clone());
        let d = (j.transpose() * &j).cholesky().unwrap().solve(&(-g));
        for k in 0..n {
            x[k] += d[k];
        }
        r = f(&x);
    }
    let _ = c;
    x
}

struct Reference {
    acc: [f64; 12],
    gyr: [f64; 12],
}

fn reference(time: &[f64], acc: &[V], gyr: &[V], g: f64, init_s: f64) -> Reference {
    // Initial interval: up to the sample nearest time[0] + init_s.
    let target = time[0] + init_s;
    let mut end = 0;
    for i in 0..time.len() {
        if (time[i] - target).abs() < (time[end] - target).abs()
            || ((time[i] - target).abs() == (time[end] - target).abs() && i > end)
        {
            end = i;
        }
    }
    let th0 = nrm(var_of(acc, 0, end));
    // The automatic start the library uses (imu_tk takes it from the caller).
    let mut mags: Vec<f64> = detect(acc, 2.0 * th0)
        .iter()
        .filter(|(a, b)| b - a + 1 >= 3)
        .map(|(a, b)| nrm(mean_of(acc, *a, *b)))
        .collect();
    mags.sort_by(f64::total_cmp);
    let s0 = g / mags[mags.len() / 2];
    // (cost, parameters, intervals) of the best threshold so far.
    type Best = (f64, Vec<f64>, Vec<(usize, usize)>);
    let mut best: Option<Best> = None;
    for k in 2..=10 {
        let ivs: Vec<(usize, usize)> = detect(acc, k as f64 * th0)
            .into_iter()
            .filter(|(a, b)| b - a + 1 >= 100)
            .collect();
        if ivs.len() < 12 {
            continue;
        }
        let samples: Vec<V> = ivs
            .iter()
            .flat_map(|(a, _)| acc[*a..*a + 100].to_vec())
            .collect();
        let f = |p: &[f64]| -> Vec<f64> {
            let q = [
                p[0], p[1], p[2], 0.0, 0.0, 0.0, p[3], p[4], p[5], p[6], p[7], p[8],
            ];
            samples.iter().map(|s| g - nrm(cal(&q, *s))).collect()
        };
        // Steps: misalignments 1e-6, scales 1e-6 of the scale, biases 1e-3
        // of the bias (at least 1e-3).
        let step = |k: usize, v: f64| match k {
            0..=2 => 1e-6,
            3..=5 => 1e-6 * v.abs(),
            _ => 1e-3 * v.abs().max(1.0),
        };
        let x = lm(&f, vec![0.0, 0.0, 0.0, s0, s0, s0, 0.0, 0.0, 0.0], &step);
        let cost = 0.5 * f(&x).iter().map(|v| v * v).sum::<f64>();
        if best.as_ref().is_none_or(|b| cost < b.0) {
            best = Some((cost, x, ivs));
        }
    }
    let (_, xa, ivs) = best.unwrap();
    let pa = [
        xa[0], xa[1], xa[2], 0.0, 0.0, 0.0, xa[3], xa[4], xa[5], xa[6], xa[7], xa[8],
    ];
    let bias = mean_of(gyr, 0, end);
    let dirs: Vec<V> = ivs
        .iter()
        .map(|(a, b)| {
            let cal_m: Vec<V> = acc[*a..=*b].iter().map(|s| cal(&pa, *s)).collect();
            let m = mean_of(&cal_m, 0, cal_m.len() - 1);
            let n = nrm(m);
            m.map(|v| v / n)
        })
        .collect();
    let integrate = |p: &[f64; 12], i0: usize, i1: usize| -> [[f64; 3]; 3] {
        let mut q = [1.0, 0.0, 0.0, 0.0];
        let om = |w: V, q: [f64; 4]| -> [f64; 4] {
            // ½ Ω(ω) q
            [
                0.5 * (-w[0] * q[1] - w[1] * q[2] - w[2] * q[3]),
                0.5 * (w[0] * q[0] + w[2] * q[2] - w[1] * q[3]),
                0.5 * (w[1] * q[0] - w[2] * q[1] + w[0] * q[3]),
                0.5 * (w[2] * q[0] + w[1] * q[1] - w[0] * q[2]),
            ]
        };
        let add = |a: [f64; 4], b: [f64; 4], s: f64| {
            [
                a[0] + s * b[0],
                a[1] + s * b[1],
                a[2] + s * b[2],
                a[3] + s * b[3],
            ]
        };
        for i in i0..i1 {
            let dt = time[i + 1] - time[i];
            let w0 = cal(
                p,
                [
                    gyr[i][0] - bias[0],
                    gyr[i][1] - bias[1],
                    gyr[i][2] - bias[2],
                ],
            );
            let w1 = cal(
                p,
                [
                    gyr[i + 1][0] - bias[0],
                    gyr[i + 1][1] - bias[1],
                    gyr[i + 1][2] - bias[2],
                ],
            );
            let wm = [
                (w0[0] + w1[0]) / 2.0,
                (w0[1] + w1[1]) / 2.0,
                (w0[2] + w1[2]) / 2.0,
            ];
            let k1 = om(w0, q);
            let k2 = om(wm, add(q, k1, 0.5 * dt));
            let k3 = om(wm, add(q, k2, 0.5 * dt));
            let k4 = om(w1, add(q, k3, dt));
            let mut qn = q;
            for j in 0..4 {
                qn[j] += dt * (k1[j] / 6.0 + k2[j] / 3.0 + k3[j] / 3.0 + k4[j] / 6.0);
            }
            let n = (qn.iter().map(|v| v * v).sum::<f64>()).sqrt();
            q = qn.map(|v| v / n);
        }
        let [a, b, c, d] = q;
        [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (a * c + b * d),
            ],
            [
                2.0 * (a * d + b * c),
                a * a - b * b + c * c - d * d,
                2.0 * (c * d - a * b),
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (a * b + c * d),
                a * a - b * b - c * c + d * d,
            ],
        ]
    };
    let fg = |p: &[f64]| -> Vec<f64> {
        let q = [
            p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], 0.0, 0.0, 0.0,
        ];
        let mut out = Vec::new();
        for w in 0..ivs.len() - 1 {
            let r = integrate(&q, ivs[w].1, ivs[w + 1].0 - 1);
            let g0 = dirs[w];
            for i in 0..3 {
                // (Rᵀ g0)_i − g1_i
                let v = r[0][i] * g0[0] + r[1][i] * g0[1] + r[2][i] * g0[2];
                out.push(v - dirs[w + 1][i]);
            }
        }
        out
    };
    // The library's start for the gyro scale: median gravity turn over
    // the raw integral (trapezoid), as documented.
    let mut ratios: Vec<f64> = (0..ivs.len() - 1)
        .filter_map(|w| {
            let (i0, i1) = (ivs[w].1, ivs[w + 1].0 - 1);
            let mut s = [0.0; 3];
            for i in i0..i1 {
                for k in 0..3 {
                    s[k] +=
                        (gyr[i][k] + gyr[i + 1][k] - 2.0 * bias[k]) * 0.5 * (time[i + 1] - time[i]);
                }
            }
            let (a, b) = (dirs[w], dirs[w + 1]);
            let ang = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
                .clamp(-1.0, 1.0)
                .acos();
            (nrm(s) > 0.0 && ang > 0.05).then(|| ang / nrm(s))
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    let sg = ratios[ratios.len() / 2];
    let gstep = |k: usize, v: f64| if k < 6 { 1e-6 } else { 1e-6 * v.abs() };
    let xg = lm(&fg, vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, sg, sg, sg], &gstep);
    Reference {
        acc: pa,
        gyr: [
            xg[0], xg[1], xg[2], xg[3], xg[4], xg[5], xg[6], xg[7], xg[8], bias[0], bias[1],
            bias[2],
        ],
    }
}

#[test]
fn tedaldi_mode_matches_a_reimplementation_of_imu_tk() {
    for seed in [1u64, 2, 3] {
        let mut truth = ImuTruth::random_around_mems(100 + seed);
        truth.gyr_k_ga = M3::zeros();
        let s = simulate(&ImuSim {
            truth,
            sequence: Sequence::Random {
                positions: 20,
                init_s: 8.0,
                move_s: 1.5,
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
        let time: Vec<f64> = s.iter().map(|x| x.time_s).collect();
        let acc: Vec<V> = s.iter().map(|x| [x.acc[0], x.acc[1], x.acc[2]]).collect();
        let gyr: Vec<V> = s.iter().map(|x| [x.gyr[0], x.gyr[1], x.gyr[2]]).collect();
        let r = autocal(
            &time,
            &acc,
            Some(&gyr),
            &AutocalOptions::new(Method::Tedaldi, 9.81, 8.0),
        )
        .unwrap();
        let want = reference(&time, &acc, &gyr, 9.81, 8.0);
        let g = r.gyr.unwrap();
        let got_acc = [
            r.acc.mis[0],
            r.acc.mis[1],
            r.acc.mis[2],
            0.0,
            0.0,
            0.0,
            r.acc.scale[0],
            r.acc.scale[1],
            r.acc.scale[2],
            r.acc.bias[0],
            r.acc.bias[1],
            r.acc.bias[2],
        ];
        let got_gyr = [
            g.mis[0], g.mis[1], g.mis[2], g.mis[3], g.mis[4], g.mis[5], g.scale[0], g.scale[1],
            g.scale[2], g.bias[0], g.bias[1], g.bias[2],
        ];
        let mut worst: f64 = 0.0;
        for (label, a, b) in [("acc", got_acc, want.acc), ("gyr", got_gyr, want.gyr)] {
            for k in 0..12 {
                let rel = (a[k] - b[k]).abs() / b[k].abs().max(1e-300);
                if b[k] != 0.0 {
                    worst = worst.max(rel);
                }
                assert!(
                    a[k] == b[k] || rel < 1e-9,
                    "seed {seed} {label}[{k}]: incal {} reference {} (relative {rel:e})",
                    a[k],
                    b[k]
                );
            }
        }
        eprintln!(
            "seed {seed}: k {} intervals {} worst relative {worst:e}",
            r.k,
            r.intervals.len()
        );
    }
}
