//! The gyro-free motion solution at real lengths: a twelve-accelerometer
//! layout solved directly (no centripetal feedback) keeps the ω error
//! within its predicted u; the paper's six-accelerometer layout (feedback)
//! warns before its error grows, and refuses a diverged solution by
//! sample; the calibration's u is carried into f0, ω̇ and ω; gravity
//! turning through a unit rotating off the vertical, and a rate that
//! oscillates, are solved within u.

use incal::models::gfimu::Geometry;
use incal::procedures::gfimu::solve::{solve_mode, SolveMode, Solver};
use incal::procedures::gfimu::{calibrate, solve, CalibrateOptions, SolveOptions};
use incal::sim::gfimu::{
    motion_truth, simulate_motion, simulate_static, six_positions, F0Frame, GfimuTruth,
    MotionProfile,
};
use incal::sim::monte_carlo;
use incal::units::STANDARD_GRAVITY_M_S2;
use nalgebra::Vector3;

/// Twelve accelerometers: at ±L on each axis, each sensing the two
/// directions across its lever arm.
fn twelve(l: f64) -> Geometry {
    Geometry::twelve(l).unwrap()
}

fn motion(duration_s: f64, rate_hz: f64) -> MotionProfile {
    MotionProfile {
        axis: Vector3::new(0.3, -0.2, 1.0),
        angular_accel_rad_s2: 1.0,
        spin_up_s: 1.0025,
        omega0_rad_s: Vector3::zeros(),
        f0_g: Vector3::new(0.05, -0.02, 1.0),
        duration_s,
        rate_hz,
        gravity_m_s2: STANDARD_GRAVITY_M_S2,
        ..MotionProfile::rate_table()
    }
}

#[test]
fn layouts_say_which_unknowns_they_solve() {
    let g6 = Geometry::paper(0.1).unwrap();
    let nominal = |g: &Geometry| {
        g.accelerometers()
            .iter()
            .map(|a| a.direction)
            .collect::<Vec<_>>()
    };
    match solve_mode(&g6, &nominal(&g6), STANDARD_GRAVITY_M_S2).unwrap() {
        SolveMode::Feedback { reason } => assert!(reason.contains("ww_"), "{reason}"),
        m => panic!("six accelerometers cannot solve directly: {m:?}"),
    }
    let g12 = twelve(0.1);
    match solve_mode(&g12, &nominal(&g12), STANDARD_GRAVITY_M_S2).unwrap() {
        // Sensing across the lever arm: only the cross products enter.
        SolveMode::Direct { products } => assert_eq!(products, ["ww_xy", "ww_xz", "ww_yz"]),
        m => panic!("twelve accelerometers solve directly: {m:?}"),
    }
}

/// Over 200 seeds of a 20 s motion at 200 Hz, the twelve-accelerometer
/// solution's final ω error lies within k·u(ω) at the normal rate, and the
/// error does not grow exponentially (the u at 20 s is within 3× of the
/// random-walk extrapolation of the u at 5 s).
#[test]
fn twelve_accelerometers_keep_omega_within_its_u() {
    let g = twelve(0.1);
    let t = GfimuTruth::typical(&g, 1.0);
    let m = motion(20.0, 200.0);
    let noise = 2e-4;
    let cal = t.calibration(Some(noise));
    let runs = monte_carlo(31, 200, |seed| {
        let series = simulate_motion(&g, &t, &m, noise, seed).unwrap();
        let sol = solve(&g, &cal, &series, &SolveOptions::default()).unwrap();
        assert_eq!(sol.mode.name(), "direct");
        let last = sol.samples.last().unwrap();
        let at5 = &sol.samples[1000];
        let (_, _, w) = motion_truth(&m, last.time_s);
        let u = last.u_omega_rad_s.unwrap();
        let z: Vec<f64> = (0..3)
            .map(|k| (last.omega_rad_s[k] - w[k]) / u[k])
            .collect();
        (z, at5.u_omega_rad_s.unwrap().amax(), u.amax())
    });
    let zs: Vec<f64> = runs.iter().flat_map(|r| r.0.clone()).collect();
    let inside = zs.iter().filter(|z| z.abs() <= 1.96).count() as f64 / zs.len() as f64;
    assert!((0.92..=0.98).contains(&inside), "ω within 1.96u: {inside}");
    let (u5, u20) = (runs[0].1, runs[0].2);
    assert!(
        u20 < 3.0 * u5 * 2.0,
        "u(ω) 5 s {u5}, 20 s {u20}: not a random walk"
    );
}

/// The paper's layout feeds ω back: with a calibrated (slightly wrong)
/// unit standing still, the solution warns when the predicted u(ω) passes
/// the limit, well before it refuses a diverged rate, naming the sample.
#[test]
fn six_accelerometers_warn_before_they_diverge() {
    let g = Geometry::paper(0.1).unwrap();
    let t = GfimuTruth::typical(&g, 1.0);
    let noise = 2e-4;
    let data = simulate_static(&g, &t, &six_positions(), 50, noise, 11).unwrap();
    let cal = calibrate(&g, &data, &CalibrateOptions::default())
        .unwrap()
        .calibrated();
    let mut m = motion(200.0, 100.0);
    m.angular_accel_rad_s2 = 0.0;
    let series = simulate_motion(&g, &t, &m, noise, 12).unwrap();
    let mut solver = Solver::new(&g, &cal, &SolveOptions::default()).unwrap();
    let mut warned_at = None;
    let mut failed_at = None;
    for (k, (time, e)) in series.iter().enumerate() {
        match solver.step(*time, e) {
            Ok(s) => {
                assert!(s.omega_rad_s.iter().all(|v| v.is_finite()));
                if warned_at.is_none() && !solver.warnings().is_empty() {
                    warned_at = Some(k);
                }
            }
            Err(err) => {
                let msg = err.to_string();
                assert!(msg.contains("diverged") && msg.contains("sample"), "{msg}");
                failed_at = Some(k);
                break;
            }
        }
    }
    let w = warned_at.expect("a warning before any divergence");
    if let Some(f) = failed_at {
        assert!(w + 100 < f, "warned at {w}, diverged at {f}");
    }
}

/// The calibration's u enters f0 and ω̇: solving a noise-free motion with a
/// calibration from noisy static data (sample noise set negligible), the
/// f0 errors are covered by their u at about the normal rate.
#[test]
fn calibration_uncertainty_reaches_f0() {
    let g = twelve(0.1);
    let t = GfimuTruth::typical(&g, 1.0);
    let noise = 2e-4;
    let runs = monte_carlo(41, 100, |seed| {
        let data = simulate_static(&g, &t, &six_positions(), 20, noise, seed).unwrap();
        let mut cal = calibrate(&g, &data, &CalibrateOptions::default())
            .unwrap()
            .calibrated();
        // The motion is noise-free: leave only the calibration's part of u.
        for c in &mut cal {
            c.noise_output = Some(1e-9);
        }
        let m = motion(2.0, 100.0);
        let series = simulate_motion(&g, &t, &m, 0.0, seed).unwrap();
        let sol = solve(&g, &cal, &series, &SolveOptions::default()).unwrap();
        let s = &sol.samples[150];
        let (f0, _, _) = motion_truth(&m, s.time_s);
        let u = s.u_f0_g.unwrap();
        (0..3)
            .map(|k| ((s.f0_g[k] - f0[k]) / u[k]).abs())
            .collect::<Vec<f64>>()
    });
    let zs: Vec<f64> = runs.into_iter().flatten().collect();
    let inside = zs.iter().filter(|z| **z <= 1.96).count() as f64 / zs.len() as f64;
    assert!((0.90..=0.99).contains(&inside), "f0 within 1.96u: {inside}");
}

/// A unit turning about a tilted axis with gravity fixed in the table
/// frame (so f0 turns through the unit) and a rate that oscillates
/// (0.5 rad/s at 1 Hz on top of the spin-up): over 100 seeds, f0 and ω̇ at
/// every tenth sample of the first 4 s, and ω at the end, lie within
/// 1.96 u at the normal rate.
#[test]
fn turning_gravity_and_oscillating_rate_solved_within_u() {
    let g = twelve(0.1);
    let t = GfimuTruth::typical(&g, 1.0);
    let m = MotionProfile {
        f0_frame: F0Frame::Table,
        f0_g: Vector3::new(0.0, 0.0, 1.0),
        oscillation_amplitude_rad_s: 0.5,
        oscillation_hz: 1.0,
        ..motion(4.0, 200.0)
    };
    // f0 really turns: its unit-frame z changes by more than 0.1 g.
    let (f_end, _, _) = motion_truth(&m, 4.0);
    assert!(
        (f_end.z - 1.0).abs() > 0.1 || (f_end.xy().norm() > 0.1),
        "{f_end:?}"
    );
    let noise = 2e-4;
    let cal = t.calibration(Some(noise));
    let runs = monte_carlo(53, 100, |seed| {
        let series = simulate_motion(&g, &t, &m, noise, seed).unwrap();
        let sol = solve(&g, &cal, &series, &SolveOptions::default()).unwrap();
        let mut f = Vec::new();
        let mut wd = Vec::new();
        for s in sol.samples.iter().step_by(10) {
            let (f0, wd0, _) = motion_truth(&m, s.time_s);
            let (uf, uw) = (s.u_f0_g.unwrap(), s.u_omega_dot_rad_s2.unwrap());
            for k in 0..3 {
                f.push((s.f0_g[k] - f0[k]) / uf[k]);
                wd.push((s.omega_dot_rad_s2[k] - wd0[k]) / uw[k]);
            }
        }
        let last = sol.samples.last().unwrap();
        let (_, _, w) = motion_truth(&m, last.time_s);
        let uw = last.u_omega_rad_s.unwrap();
        let w: Vec<f64> = (0..3)
            .map(|k| (last.omega_rad_s[k] - w[k]) / uw[k])
            .collect();
        (f, wd, w)
    });
    let rate =
        |zs: Vec<f64>| zs.iter().filter(|z| z.abs() <= 1.96).count() as f64 / zs.len() as f64;
    let f = rate(runs.iter().flat_map(|r| r.0.clone()).collect());
    let wd = rate(runs.iter().flat_map(|r| r.1.clone()).collect());
    let w = rate(runs.iter().flat_map(|r| r.2.clone()).collect());
    assert!((0.93..=0.97).contains(&f), "f0 within 1.96u: {f}");
    assert!((0.93..=0.97).contains(&wd), "omega_dot within 1.96u: {wd}");
    assert!((0.90..=0.99).contains(&w), "omega within 1.96u: {w}");
}
