//! The GFIMU note (six-accelerometer gyro-free unit), docs/src/gfimu.md.
//!
//! The paper publishes no numerical tables (its mathematics was lost in text
//! extraction and docs/src/gfimu.md reconstructs it), so "the paper's numbers"
//! here are its closed-form six-position formulas: the least-squares
//! calibration must reproduce them exactly (to rounding, 1e-12 relative)
//! on the same data.

use incal::models::gfimu::{ArrayAccelerometer, Geometry};
use incal::procedures::gfimu::{calibrate, six_position, CalibrateOptions, StaticSample};
use incal::sim::gfimu::{simulate_static, six_positions, GfimuTruth};
use incal::Error;
use nalgebra::Vector3;

const TOL: f64 = 1e-12;

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= TOL * (1.0 + a.abs().max(b.abs())),
        "{what}: {a} vs {b}"
    );
}

/// Position means E1..E6 (+x, −x, +y, −y, +z, −z) of accelerometer j.
fn means(samples: &[StaticSample], j: usize) -> [f64; 6] {
    let pos = six_positions();
    pos.iter()
        .map(|p| {
            let v: Vec<f64> = samples
                .iter()
                .filter(|s| s.specific_force_g == *p)
                .map(|s| s.outputs[j])
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        })
        .collect::<Vec<_>>()
        .try_into()
        .unwrap()
}

/// Sensing axis of each paper accelerometer: a, b → z; c, d → x; e, f → y.
const SENSING: [usize; 6] = [2, 2, 0, 0, 1, 1];

/// With noisy data (5 samples per position) least squares equals the
/// paper's `K0 = mean of (E1+E2)/2, (E3+E4)/2, (E5+E6)/2`,
/// `Ks = [(E1−E2), (E3−E4), (E5−E6)]/2g`, the paper's k1 = Ks along the
/// sensing axis, and its cross terms k2, k3 averaged over the position and
/// the opposite position (GFIMU note, formulas for accelerometers a–f).
#[test]
fn closed_forms_agree_with_least_squares_on_noisy_data() {
    let g = Geometry::paper(0.1).unwrap();
    let truth = GfimuTruth::typical(&g, 2.5);
    let data = simulate_static(&g, &truth, &six_positions(), 5, 1e-3, 4).unwrap();
    let cal = calibrate(&g, &data, &CalibrateOptions::default()).unwrap();
    for (j, acc) in cal.accelerometers.iter().enumerate() {
        let cf = six_position(means(&data, j), SENSING[j]).unwrap();
        close(acc.k0(), cf.k0, "K0");
        for k in 0..3 {
            close(acc.ks()[k], cf.ks[k], "Ks");
        }
        let d = &acc.derived;
        close(d.value("k1").unwrap(), cf.paper[1], "k1");
        close(
            d.value("k2").unwrap(),
            0.5 * (cf.paper[2] + cf.paper_cross_opposite[0]),
            "k2",
        );
        close(
            d.value("k3").unwrap(),
            0.5 * (cf.paper[3] + cf.paper_cross_opposite[1]),
            "k3",
        );
        let c = acc.k0_consistency.unwrap();
        for k in 0..3 {
            close(c.values[k], cf.k0_by_axis[k], "K0 by axis");
        }
    }
}

/// Noise-free data: every one of the paper's single-position formulas
/// (k0 from its own axis pair, k2 = (2E1−E5−E6)/2g for a, …) equals the
/// least-squares value and the truth.
#[test]
fn each_paper_formula_is_exact_without_noise() {
    let g = Geometry::paper(0.05).unwrap();
    let truth = GfimuTruth::typical(&g, 1.0);
    let data = simulate_static(&g, &truth, &six_positions(), 1, 0.0, 0).unwrap();
    // One sample per position, no noise: residual variance is zero, which
    // the fit accepts (dof 2).
    let cal = calibrate(&g, &data, &CalibrateOptions::default()).unwrap();
    for (j, acc) in cal.accelerometers.iter().enumerate() {
        let cf = six_position(means(&data, j), SENSING[j]).unwrap();
        for k in 0..3 {
            close(cf.k0_by_axis[k], truth.k0[j], "K0 by axis");
            close(cf.ks[k], truth.ks[j][k], "Ks");
        }
        close(cf.paper[0], acc.k0(), "paper k0");
        close(cf.paper[2], acc.derived.value("k2").unwrap(), "paper k2");
        close(cf.paper[3], acc.derived.value("k3").unwrap(), "paper k3");
        close(cf.paper_cross_opposite[0], cf.paper[2], "k2 opposite");
        close(cf.paper_cross_opposite[1], cf.paper[3], "k3 opposite");
    }
}

/// Explicit check of accelerometer a's printed formulas on hand numbers.
#[test]
fn accelerometer_a_formulas_by_hand() {
    let e = [0.013, 0.009, 0.002, 0.020, 1.011, -0.989];
    let cf = six_position(e, 2).unwrap();
    close(cf.paper[0], 0.011, "k_a0 = (E5+E6)/2");
    close(cf.paper[1], 1.0, "k_a1 = (E5-E6)/2g");
    close(cf.paper[2], (2.0 * 0.013 - 0.022) / 2.0, "k_a2");
    close(cf.paper[3], (2.0 * 0.002 - 0.022) / 2.0, "k_a3");
}

/// An even-order term (a K2-like offset on the ±z positions only) makes
/// the three K0 estimates disagree: the consistency check flags it.
#[test]
fn inconsistent_k0_is_flagged() {
    let g = Geometry::paper(0.1).unwrap();
    let truth = GfimuTruth::typical(&g, 1.0);
    let mut data = simulate_static(&g, &truth, &six_positions(), 10, 1e-5, 9).unwrap();
    for s in &mut data {
        if s.specific_force_g.z.abs() > 0.5 {
            s.outputs[0] += 1e-3;
        }
    }
    let cal = calibrate(&g, &data, &CalibrateOptions::default()).unwrap();
    let c = cal.accelerometers[0].k0_consistency.unwrap();
    assert!(c.max_normalized_difference > 10.0, "{c:?}");
    assert!(
        cal.warnings
            .iter()
            .any(|w| w.code == incal::WarningCode::InconsistentBias && w.message.contains("'a'")),
        "{:?}",
        cal.warnings
    );
    let c = cal.accelerometers[1].k0_consistency.unwrap();
    assert!(c.max_normalized_difference < 5.0, "{c:?}");
}

/// A geometry that cannot separate f0 and ω̇ is refused, naming the terms:
/// c and d both at +L on y (sensing x) give identical rows.
#[test]
fn degenerate_geometry_is_refused() {
    let p = Geometry::paper(0.1).unwrap();
    let mut accs: Vec<ArrayAccelerometer> = p.accelerometers().to_vec();
    accs[3].position_m = accs[2].position_m;
    let g = Geometry::new(accs).unwrap();
    let err = g.require_solvable().unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, Error::Unseparable { .. }), "{msg}");
    assert!(msg.contains("f0_x") && msg.contains("omega_dot_z"), "{msg}");

    // All six sensing along z: f0_x, f0_y and ω̇_z are unobservable.
    let mut accs: Vec<ArrayAccelerometer> = p.accelerometers().to_vec();
    for a in &mut accs {
        a.direction = Vector3::z();
    }
    let msg = Geometry::new(accs)
        .unwrap()
        .require_solvable()
        .unwrap_err()
        .to_string();
    assert!(msg.contains("f0_x") && msg.contains("omega_dot_z"), "{msg}");
}

/// Positions all horizontal in x–y cannot separate Ks_z: refused naming it;
/// fewer than six distinct positions are refused as too few.
#[test]
fn unseparable_plan_is_refused() {
    let g = Geometry::paper(0.1).unwrap();
    let truth = GfimuTruth::typical(&g, 1.0);
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let plan = vec![
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(-1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, -1.0, 0.0),
        Vector3::new(h, h, 0.0),
        Vector3::new(-h, h, 0.0),
    ];
    let data = simulate_static(&g, &truth, &plan, 3, 1e-4, 1).unwrap();
    let err = calibrate(&g, &data, &CalibrateOptions::default()).unwrap_err();
    assert!(matches!(err, Error::Unseparable { .. }), "{err}");
    assert!(err.to_string().contains("Ks_z"), "{err}");
    assert!(!err.to_string().contains("Ks_x"), "{err}");

    let data = simulate_static(&g, &truth, &six_positions()[..5], 3, 1e-4, 1).unwrap();
    let err = calibrate(&g, &data, &CalibrateOptions::default()).unwrap_err();
    assert!(
        matches!(
            err,
            Error::TooFew {
                needed: 6,
                got: 5,
                ..
            }
        ),
        "{err}"
    );
}
