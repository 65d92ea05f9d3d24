//! The IMU syntheses: a linear multi-position fit whose Monte Carlo
//! standard deviations are its u, and the Ferraris map whose draws
//! reproduce its propagated u and take the rotation angle's.

use serde_json::json;

use crate::montecarlo::{run, MonteCarloOptions};
use crate::procedures::imu::ferraris::Ferraris;
use crate::procedures::imu::multipos::Multipos;
use crate::procedures::imu::sim::ImuSimulator;
use crate::procedures::{Procedure, Silent, Simulate};

/// A simulated session (`incal simulate imu` with `options`) read by `P`.
fn session<P: Procedure>(sim: serde_json::Value, o: &P::Options) -> P::Input {
    let so = crate::options::from_json(&sim).unwrap();
    let mut csv = Vec::new();
    ImuSimulator::simulate(&so, &mut csv).unwrap();
    let read = incal_io::ReadOptions::default();
    let mut rows = incal_io::Reader::new("s.csv", &csv[..], &read).unwrap();
    P::read(&mut rows, o).unwrap()
}

/// `std / u` of every coefficient named.
fn ratios<P: Procedure>(
    input: &P::Input,
    o: &P::Options,
    m: u64,
    names: &[&str],
) -> Vec<(String, f64)> {
    let doc = P::reduce(input, o, &Silent).unwrap();
    let (section, _) = run::<P>(input, o, &doc, &MonteCarloOptions::fixed(m, 5), &Silent).unwrap();
    assert_eq!(section.failed.count, 0, "{:?}", section.failed);
    names
        .iter()
        .map(|n| {
            let u = doc.coefficients.get(n).unwrap().u;
            (n.to_string(), section.coefficients[*n].std / u)
        })
        .collect()
}

/// The multi-position fit is linear in the section means (the scale
/// factors and misalignments nearly so): each Monte Carlo standard
/// deviation is its u within the sampling error (`u/√(2M)`, 2 % at
/// M = 1500, five spreads) and the t factor of a large dof.
#[test]
fn multipos_standard_deviations_are_the_u() {
    let sim = json!({"sequence": "positions", "rotations": true, "static_s": 1.0, "seed": 4});
    let o = Multipos::example();
    let input = session::<Multipos>(sim, &o);
    let names = [
        "acc.b_x", "acc.A_xy", "acc.S_z", "acc.M_yx", "gyr.b_y", "gyr.G_zx", "gyr.S_x", "gyr.M_xz",
    ];
    for (name, r) in ratios::<Multipos>(&input, &o, 1500, &names) {
        assert!((0.9..1.1).contains(&r), "{name}: std/u = {r}");
    }
}

/// The Ferraris map through its draws: the propagated u of a bias, a
/// scale and a misalignment; a stated u of the rotation angle widens the
/// gyro scale as the GUM budget says (`u(K_g)/K_g ≈ u_A/A` once it
/// dominates), and not the accelerometer's.
#[test]
fn ferraris_draws_reproduce_the_propagated_u_and_the_angle() {
    let sim = json!({"sequence": "ferraris", "static_s": 1.0, "rotation_s": 2.0, "seed": 2});
    let mut o = Ferraris::example();
    let input = session::<Ferraris>(sim, &o);
    let names = [
        "b_a.x", "K_a.yy", "R_a.xy", "b_g.z", "K_g.xx", "R_g.zy", "K_ga.yx",
    ];
    for (name, r) in ratios::<Ferraris>(&input, &o, 1500, &names) {
        assert!((0.9..1.1).contains(&r), "{name}: std/u = {r}");
    }
    o.u_rotation_deg = 2.0;
    let doc = Ferraris::reduce(&input, &o, &Silent).unwrap();
    let k = doc.coefficients.get("K_g.xx").unwrap();
    assert!(k.u > 0.5 * 2.0 / 360.0 * k.value.abs(), "{k:?}");
    for (name, r) in ratios::<Ferraris>(&input, &o, 1500, &["K_g.xx", "K_g.zz", "K_a.xx"]) {
        assert!((0.9..1.1).contains(&r), "{name} with u(A): std/u = {r}");
    }
}
