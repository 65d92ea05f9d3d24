//! Threshold and resolution: round trips from known dead bands over many
//! seeds (U95 coverage of the threshold, the resolution and K1, white and
//! Gauss–Markov noise, gyro and accelerometer, a quantized output), the
//! plan against the spread of reductions, and the refusals (steps that do
//! not bracket, one size, no revisit, no scale factor).

use incal::procedures::threshold::plan::{plan_document, ThresholdPlanOptions};
use incal::procedures::threshold::sim::{SimSensor, ThresholdSimOptions};
use incal::procedures::threshold::{calibrate, ThresholdOptions};
use incal::sim::monte_carlo;
use incal::sim::tier::{band, trials};

/// The coefficients' names and the truth's keys, gyro and accelerometer.
const GYRO: [&str; 3] = ["threshold_deg_s", "resolution_deg_s", "K1"];
const ACCEL: [&str; 3] = ["threshold_g", "resolution_g", "K1"];

fn covered(s: &ThresholdSimOptions, o: &ThresholdOptions, names: &[&str]) -> Vec<Option<bool>> {
    let truth = s.truth_json().unwrap();
    let r = calibrate(&s.record().unwrap(), o).expect("reduces");
    let e = r.coefficients().unwrap();
    let doc = r.document().unwrap();
    names
        .iter()
        .map(|name| {
            let t = truth[*name].as_f64()?;
            let c = doc.coefficients.get(name)?;
            Some((c.value - t).abs() <= c.u95)
        })
        .chain(std::iter::once(Some(e.len() == names.len())))
        .collect()
}

fn assert_band(label: &str, names: &[&str], runs: &[Vec<Option<bool>>]) {
    let (lo, hi) = band(runs.len(), 0.93, 0.97);
    let mut outside = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let hits: Vec<bool> = runs.iter().filter_map(|r| r[k]).collect();
        assert!(!hits.is_empty(), "{label}: {name} never reported");
        let rate = hits.iter().filter(|h| **h).count() as f64 / hits.len() as f64;
        eprintln!("{label}, {name}: {rate:.3} of {}", hits.len());
        if !(lo..=hi).contains(&rate) {
            outside.push(format!(
                "{name}: {rate:.3} of {} (band {lo:.3}..{hi:.3})",
                hits.len()
            ));
        }
    }
    assert!(
        runs.iter().all(|r| r[names.len()] == Some(true)),
        "{label}: a reduction reported another set of coefficients"
    );
    assert!(outside.is_empty(), "{label}: {}", outside.join("; "));
}

fn gyro(seed: u64) -> ThresholdSimOptions {
    ThresholdSimOptions {
        seed,
        ..ThresholdSimOptions::default()
    }
}

#[test]
fn threshold_white_noise_u95_covers_the_truth() {
    let runs = monte_carlo(601, trials(40, 1000), |s| {
        covered(&gyro(s), &ThresholdOptions::default(), &GYRO)
    });
    assert_band("threshold, gyro, white noise", &GYRO, &runs);
}

/// Gauss–Markov noise half the white's σ, correlated over 1 s (10
/// samples): plateau means scatter 6 times more (in variance) than the
/// white noise alone would make them; the revisits see it.
#[test]
fn threshold_correlated_noise_u95_covers_the_truth() {
    let runs = monte_carlo(602, trials(40, 1000), |s| {
        let o = ThresholdSimOptions {
            gm_sigma: 0.001,
            gm_tau_s: 1.0,
            ..gyro(s)
        };
        covered(&o, &ThresholdOptions::default(), &GYRO)
    });
    assert_band("threshold, gyro, Gauss-Markov noise", &GYRO, &runs);
}

/// An accelerometer tilted on a dividing head (inputs in g, the base at
/// 30°) with an output quantized at half the noise.
#[test]
fn threshold_accelerometer_quantized_u95_covers_the_truth() {
    let runs = monte_carlo(603, trials(40, 1000), |s| {
        let o = ThresholdSimOptions {
            sensor: SimSensor::Accel,
            quantum: 5e-6,
            ..gyro(s)
        };
        covered(&o, &ThresholdOptions::default(), &ACCEL)
    });
    assert_band("threshold, accelerometer, quantized", &ACCEL, &runs);
}

/// Steps at zero only, K1 given with its u (from a scale-factor test).
#[test]
fn threshold_at_zero_with_a_given_scale_factor_covers_the_truth() {
    let names = ["threshold_deg_s"];
    let runs = monte_carlo(604, trials(40, 1000), |s| {
        let o = ThresholdSimOptions {
            base_input: Some(0.0),
            scale_factor: 2.0,
            ..gyro(s)
        };
        let r = ThresholdOptions {
            scale_factor: Some(2.0),
            scale_factor_u: 0.002,
            ..ThresholdOptions::default()
        };
        covered(&o, &r, &names)
    });
    assert_band("threshold at zero, K1 given", &names, &runs);
}

#[test]
fn the_plan_predicts_the_spread_of_reductions() {
    let p = plan_document(&ThresholdPlanOptions {
        sensor: SimSensor::Gyro,
        rate_hz: 10.0,
        dwell_s: 30.0,
        steps: None,
        base_input: None,
        scale_factor: 1.0,
        expected_threshold: None,
        expected_resolution: None,
        noise: None,
        gm_sigma: 0.0,
        gm_tau_s: 2.0,
        seed: 1,
    })
    .unwrap();
    let j = serde_json::to_value(&p).unwrap();
    let predicted = j["predicted_u"]["threshold_deg_s"]
        .as_f64()
        .expect("predicted");
    let values: Vec<f64> = monte_carlo(605, 40, |s| {
        let r = calibrate(&gyro(s).record().unwrap(), &ThresholdOptions::default()).unwrap();
        r.crossings[0].value.0
    });
    let m = values.iter().sum::<f64>() / values.len() as f64;
    let sd =
        (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt();
    eprintln!("threshold: predicted u {predicted:.3e}, spread of 40 reductions {sd:.3e}");
    assert!(
        (0.6..1.6).contains(&(predicted / sd)),
        "predicted u {predicted:.3e} against a spread of {sd:.3e}"
    );
}

fn refusal(s: ThresholdSimOptions, o: ThresholdOptions) -> String {
    calibrate(&s.record().unwrap(), &o).unwrap_err().to_string()
}

#[test]
fn steps_that_do_not_bracket_are_refused_naming_the_level_and_size() {
    // Every step passes at zero: the dead band is far below the steps.
    let e = refusal(
        ThresholdSimOptions {
            dead_band: Some(1e-5),
            ..gyro(1)
        },
        ThresholdOptions::default(),
    );
    assert!(
        e.contains("every step at zero passes") && e.contains("1.0000e-3"),
        "{e}"
    );
    // No step passes about the base: the dead band is above the steps.
    let e = refusal(
        ThresholdSimOptions {
            resolution_band: Some(0.2),
            steps: Some(vec![0.001, 0.01, 0.1]),
            ..gyro(1)
        },
        ThresholdOptions::default(),
    );
    assert!(
        e.contains("no step at the base input passes") && e.contains("1.0000e-1"),
        "{e}"
    );
    // One size only.
    let e = refusal(
        ThresholdSimOptions {
            steps: Some(vec![0.01]),
            ..gyro(1)
        },
        ThresholdOptions::default(),
    );
    assert!(e.contains("one size"), "{e}");
}

#[test]
fn a_record_with_no_base_and_no_scale_factor_is_refused_naming_the_option() {
    let e = refusal(
        ThresholdSimOptions {
            base_input: Some(0.0),
            ..gyro(1)
        },
        ThresholdOptions::default(),
    );
    assert!(e.contains("scale_factor"), "{e}");
}

#[test]
fn a_plan_whose_steps_do_not_bracket_is_refused_naming_steps() {
    let e = plan_document(&ThresholdPlanOptions {
        sensor: SimSensor::Gyro,
        rate_hz: 10.0,
        dwell_s: 30.0,
        steps: Some(vec![0.01, 0.02, 0.05]),
        base_input: None,
        scale_factor: 1.0,
        expected_threshold: None,
        expected_resolution: None,
        noise: None,
        gm_sigma: 0.0,
        gm_tau_s: 2.0,
        seed: 1,
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("steps") && e.contains("bracket"), "{e}");
}

/// A record of many plateaus (10,001 here) reduces without a dense
/// plateau-by-plateau matrix or a quadratic count of the inputs: before,
/// the covariance of each step size built a 10⁴ × 10⁴ diagonal (800 MB).
#[test]
fn many_plateaus_reduce_in_bounded_memory() {
    use incal::procedures::threshold::input::{Record, Sensor};
    let mut rec = Record {
        sensor: Sensor::Gyro,
        command: Vec::new(),
        output: Vec::new(),
        time_s: None,
        lines: Vec::new(),
    };
    let mut r = incal::sim::rng(5);
    for i in 0..10_001usize {
        // 0, Δ_1, 0, Δ_2, … with Δ growing from 1e-3 to 5e-2.
        let u = if i % 2 == 0 {
            0.0
        } else {
            1e-3 * 50f64.powf(i as f64 / 10_001.0)
        };
        let y = 0.01 + incal::procedures::threshold::sim::dead_band(u, 0.004);
        for _ in 0..2 {
            rec.command.push(u);
            rec.output.push(y + incal::sim::normal(&mut r, 1e-5));
            rec.lines.push(rec.lines.len() + 2);
        }
    }
    let o = ThresholdOptions {
        scale_factor: Some(1.0),
        ..ThresholdOptions::default()
    };
    let res = calibrate(&rec, &o).expect("reduces");
    let t = res.crossings[0].value.0;
    assert!((0.007..0.009).contains(&t), "threshold {t}");
}
