//! Plans by simulation (`incal::procedures::sim_plan`): the IMU sessions
//! and the noise analysis predicted by simulating the planned session and
//! reducing it. Checked: every term predicted with a positive u, the same
//! options give the same plan, bad options refused naming the key, and
//! the predicted u against the scatter of the estimates over the seeds
//! (the plan's `scatter_over_u`, pooled over the terms).

use incal::procedures::registry::find;
use serde_json::{json, Value};

fn plan(id: &str, options: Value) -> incal::Result<incal::document::plan::PlanDocument> {
    let e = find(id).expect("registry entry");
    let t = e.planner.expect("a typed plan");
    (t.run)(&options)
}

fn ferraris(seeds: usize) -> Value {
    json!({
        "session": {"sequence": "ferraris", "static_s": 1.0, "rotation_s": 2.0, "seed": 5},
        "reduce": {"rate_hz": 100.0, "gravity_m_s2": 9.80665, "convention": "standard",
                   "rotation_deg": -360.0, "u_rotation_deg": 0.0},
        "seeds": seeds
    })
}

#[test]
fn an_imu_plan_predicts_every_term_and_repeats() {
    let a = plan("imu-ferraris", ferraris(3)).unwrap();
    let u = a.predicted_u.clone().unwrap();
    assert!(u.len() >= 30, "{} terms", u.len());
    assert!(u.values().all(|x| x.is_finite() && *x > 0.0));
    assert!(a.predicted_u95.is_some() && a.predicted_dof.is_some());
    let b = plan("imu-ferraris", ferraris(3)).unwrap();
    assert_eq!(a, b, "the same options give the same plan");
}

#[test]
fn bad_plan_options_are_refused_naming_the_key() {
    for (options, key) in [
        (
            {
                let mut o = ferraris(3);
                o["seeds"] = json!(0);
                o
            },
            "seeds",
        ),
        (
            {
                let mut o = ferraris(3);
                o["sesion"] = json!({});
                o
            },
            "sesion",
        ),
    ] {
        match plan("imu-ferraris", options) {
            Err(incal::Error::InvalidOption { key: k, .. }) => assert_eq!(k, key),
            other => panic!("{key}: {other:?}"),
        }
    }
}

/// The reported u against the scatter of the estimates: pooled over the
/// terms of a multi-position session (about 40 terms × `n` seeds), the
/// mean of (scatter / u)² is 1 for an honest u; a u half its size gives 4.
#[test]
fn the_predicted_u_matches_the_scatter_of_the_estimates() {
    let n = incal::sim::tier::trials(20, 50);
    let options = json!({
        "session": {"sequence": "positions", "static_s": 0.5, "rotations": true, "seed": 9},
        "reduce": {"rate_hz": 100.0, "gravity_m_s2": 9.80665, "matrix": "full",
                   "latitude_deg": null, "rotation_deg": -360.0},
        "seeds": n
    });
    let p = plan("imu-multipos", options).unwrap();
    let ratios = p.plan["scatter_over_u"].as_object().unwrap();
    let r2: Vec<f64> = ratios
        .values()
        .filter_map(Value::as_f64)
        .map(|r| r * r)
        .collect();
    let mean = r2.iter().sum::<f64>() / r2.len() as f64;
    assert!(r2.len() >= 20, "{} terms", r2.len());
    eprintln!(
        "multipos plan: mean (scatter/u)^2 = {mean:.3} over {} terms, {n} seeds",
        r2.len()
    );
    assert!(
        (0.6..1.6).contains(&mean),
        "mean (scatter/u)^2 = {mean} over {} terms, {n} seeds",
        r2.len()
    );
}

#[test]
fn a_noise_plan_predicts_the_identified_terms() {
    let options = json!({
        "session": {"quantity": "gyro", "arw_deg_rth": 0.1, "bias_instability_deg_h": 5.0,
                    "rate_hz": 10.0, "duration_s": 1800.0, "seed": 4},
        "reduce": {"rate_hz": 10.0, "quantity": "gyro"},
        "seeds": 3
    });
    let p = plan("noise", options).unwrap();
    let u = p.predicted_u.unwrap();
    assert!(u.contains_key("ch1.ARW"), "{u:?}");
    assert!(u.values().all(|x| x.is_finite() && *x > 0.0));
}
