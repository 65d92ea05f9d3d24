//! The centrifuge's saturation: points whose output sits at the
//! converter's rail are named and never fitted (the coefficients equal
//! those of the record without them), and a record with no rail is left
//! whole.

use incal::procedures::centrifuge::{calibrate, CentrifugeTest};
use incal::procedures::Procedure;
use incal::sim::centrifuge::simulate;
use incal::sim::centrifuge::CentrifugeSimOptions;

#[test]
fn clipped_points_are_named_and_never_fitted() {
    let o = CentrifugeSimOptions::default();
    let obs = simulate(&o.rig.simulation(o.truth.model().unwrap(), 3).unwrap());
    let options = CentrifugeTest::example();
    let whole = calibrate(&obs, &options).unwrap();
    assert!(!whole.warnings.iter().any(|w| w.message.contains("clips")));
    // A converter whose full scale is a little below the largest output.
    let top = obs.iter().map(|x| x.output).fold(f64::MIN, f64::max);
    let rail = 0.999 * top;
    let clipped: Vec<_> = obs
        .iter()
        .map(|x| {
            let mut x = *x;
            x.output = x.output.min(rail);
            x
        })
        .collect();
    let r = calibrate(&clipped, &options).unwrap();
    let w = r
        .warnings
        .iter()
        .find(|w| w.message.contains("clips"))
        .expect("a saturated warning");
    assert!(w.message.contains("rad/s"), "{}", w.message);
    // The same as the record without the points that reach the rail.
    let kept: Vec<_> = {
        let at = |x: &incal::procedures::centrifuge::Observation| {
            let same = |y: &&incal::procedures::centrifuge::Observation| {
                y.position == x.position && y.omega_rad_s == x.omega_rad_s
            };
            let n = obs.iter().filter(same).count();
            let over = obs.iter().filter(same).filter(|y| y.output >= rail).count();
            over >= 2 && 2 * over >= n
        };
        obs.iter().filter(|x| !at(x)).copied().collect()
    };
    assert!(kept.len() < obs.len());
    let r2 = calibrate(&kept, &options).unwrap();
    for (name, v) in r
        .coefficients
        .names()
        .iter()
        .zip(r.coefficients.values().iter())
    {
        let v2 = r2.coefficients.value(name).unwrap();
        assert!(
            (v - v2).abs() <= 1e-12 * v.abs().max(1e-12),
            "{name}: {v} against {v2}"
        );
    }
}
