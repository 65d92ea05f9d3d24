//! The covariance of K0 and K1 (e.g. from the tumble result they came
//! from, `centrifuge --from`) enters every quantity that depends on both.
//! Checked on the static tilt λ = E0/K1 − K0 (He & Yin 2017 eq. 4), whose
//! variance changes by exactly `2·(∂λ/∂K0)(∂λ/∂K1)·C(K0, K1)`
//! = `2·(λ + K0)/K1·C` (GUM, JCGM 100 eq. 13).

use incal::estimation::Noise;
use incal::procedures::centrifuge::{calibrate, CentrifugeOptions};
use incal::sim::centrifuge::{rates_for_levels, simulate, standard_positions, CentrifugeSim};
use incal::sim::demo::{centrifuge_rig, centrifuge_truth};
use incal::units::STANDARD_GRAVITY_M_S2;

#[test]
fn k0_k1_covariance_enters_the_tilt_exactly() {
    let truth = centrifuge_truth();
    let obs = simulate(&CentrifugeSim {
        truth,
        rig: centrifuge_rig(),
        positions: standard_positions(),
        rates_rad_s: rates_for_levels(&[0.0, 1.0, 4.0, 10.0, 25.0], 0.71, STANDARD_GRAVITY_M_S2),
        samples: 5,
        noise: 2e-6,
        seed: 5,
    });
    let (u0, u1) = (1e-5, 1e-3);
    let run = |cov: f64| {
        calibrate(
            &obs,
            &CentrifugeOptions {
                from: None,
                k0: Some(truth.k0_g),
                u_k0: Some(u0),
                k1: Some(truth.k1_out_per_g),
                u_k1: Some(u1),
                cov_k0_k1: Some(cov),
                radius_m: 0.71,
                latitude_deg: 39.9,
                gravity_m_s2: STANDARD_GRAVITY_M_S2,
                opposite_sense: false,
                order: 3,
                alignment_tolerance_deg: 0.0,
                noise: Noise::Auto,
                terms: None,
                u_omega_ppm: 0.0,
            },
        )
        .unwrap()
    };
    let c = 0.9 * u0 * u1;
    let (a, b) = (run(0.0), run(c));
    let (lambda, u_a) = a.joint.get("tilt_rad").unwrap();
    let (_, u_b) = b.joint.get("tilt_rad").unwrap();
    let expect = 2.0 * (lambda + truth.k0_g) / truth.k1_out_per_g * c;
    let got = u_b * u_b - u_a * u_a;
    assert!(
        (got - expect).abs() <= 1e-3 * expect.abs(),
        "Δvar {got:e}, expected {expect:e}"
    );
    // The values do not move; the coefficients that do not depend on K0
    // keep their u.
    assert_eq!(a.joint.values(), b.joint.values());
    let (k2a, k2b) = (a.joint.u("K2").unwrap(), b.joint.u("K2").unwrap());
    assert!((k2a - k2b).abs() <= 1e-9 * k2a);
}
