//! `plan gfimu`: the predicted u of every K0 and Ks matches the Monte
//! Carlo scatter of the calibration it plans (within 20 %), and a plan that
//! cannot separate K0 and Ks is refused like the reduction refuses it.

use incal::models::gfimu::Geometry;
use incal::procedures::gfimu::calibrate::plan;
use incal::procedures::gfimu::{calibrate, CalibrateOptions};
use incal::sim::gfimu::{simulate_static, six_positions, GfimuTruth};
use incal::sim::monte_carlo;
use nalgebra::Vector3;

#[test]
fn plan_predicts_the_calibration_scatter() {
    let g = Geometry::paper(0.1).unwrap();
    let t = GfimuTruth::typical(&g, 1.0);
    let (samples, noise) = (20, 2e-4);
    let p = plan(&g, &six_positions(), samples, noise, 1.0).unwrap();
    let trials = 400;
    let runs = monte_carlo(51, trials, |seed| {
        let data = simulate_static(&g, &t, &six_positions(), samples, noise, seed).unwrap();
        let c = calibrate(&g, &data, &CalibrateOptions::default()).unwrap();
        c.accelerometers
            .iter()
            .flat_map(|a| a.linear.values().iter().copied().collect::<Vec<f64>>())
            .collect::<Vec<f64>>()
    });
    let n = runs[0].len();
    for k in 0..n {
        let m = runs.iter().map(|r| r[k]).sum::<f64>() / trials as f64;
        let sd =
            (runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (trials as f64 - 1.0)).sqrt();
        let u = p.accelerometers[k / 4].linear.u_at(k % 4);
        let ratio = u / sd;
        assert!(
            (0.8..=1.2).contains(&ratio),
            "parameter {k}: plan u {u:e} / MC sd {sd:e} = {ratio}"
        );
    }
}

#[test]
fn plan_refuses_positions_that_cannot_separate() {
    let g = Geometry::paper(0.1).unwrap();
    let four = [Vector3::x(), -Vector3::x(), Vector3::y(), -Vector3::y()];
    let e = plan(&g, &four, 10, 1e-4, 1.0).unwrap_err().to_string();
    assert!(e.contains("positions"), "{e}");
}
