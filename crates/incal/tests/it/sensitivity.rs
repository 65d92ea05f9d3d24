//! Environmental sensitivities: round trips from a known vibration
//! rectification, vibropendulous coefficient, magnetic sensitivity matrix
//! and shock shifts over many seeds (U95 coverage with white noise, with
//! flicker and with a random walk, runs in ascending order so that the
//! drift aliases into the slope), the refusals named in one line, and the
//! plan's prediction against the reductions' u.

use incal::procedures::sensitivity::input::Record;
use incal::procedures::sensitivity::plan::{plan_document, SensitivityPlanOptions};
use incal::procedures::sensitivity::sim::SensitivitySimOptions;
use incal::procedures::sensitivity::{reduce, Kind, SensitivityOptions, Sensor};
use incal::sim::monte_carlo;
use incal::sim::tier::{band, trials};

/// For each truth key: covered by U95?
fn covered(s: &SensitivitySimOptions) -> Vec<(String, bool)> {
    let truth = s.truth_json().unwrap();
    let r = reduce(&s.record().unwrap(), &s.reduction()).expect("reduces");
    let mut out = Vec::new();
    for (name, t) in truth.as_object().unwrap() {
        let t = t.as_f64().unwrap();
        let c = r
            .columns
            .iter()
            .find(|c| c.coefficients.get(name).is_some())
            .unwrap_or_else(|| panic!("{name} not reported"));
        let e = &c.coefficients;
        let (v, u) = e.get(name).unwrap();
        out.push((name.clone(), (v - t).abs() <= e.coverage_factor(0.95) * u));
    }
    out
}

fn assert_band(label: &str, runs: &[Vec<(String, bool)>]) {
    let (lo, hi) = band(runs.len(), 0.93, 0.97);
    let mut outside = Vec::new();
    for (k, (name, _)) in runs[0].iter().enumerate() {
        let rate = runs.iter().filter(|r| r[k].1).count() as f64 / runs.len() as f64;
        eprintln!("{label}, {name}: {rate:.3} of {}", runs.len());
        if !(lo..=hi).contains(&rate) {
            outside.push(format!("{name}: {rate:.3} (band {lo:.3}..{hi:.3})"));
        }
    }
    assert!(outside.is_empty(), "{label}: {}", outside.join("; "));
}

fn vibration(seed: u64) -> SensitivitySimOptions {
    SensitivitySimOptions {
        seed,
        angles_deg: "0,45,-45".into(),
        run_s: 20.0,
        rate_hz: 50.0,
        ..SensitivitySimOptions::default()
    }
}

#[test]
fn vibration_u95_covers_the_truth_under_flicker() {
    // Flicker at a bias instability of 3 µg against 50 µg white per
    // sample: the run means' u is mostly flicker.
    let runs = monte_carlo(11, trials(60, 1000), |seed| {
        covered(&SensitivitySimOptions {
            flicker: Some(3.0),
            ..vibration(seed)
        })
    });
    assert_band("vibration, flicker", &runs);
}

#[test]
fn vibration_u95_covers_the_truth_with_white_noise() {
    let runs = monte_carlo(12, trials(60, 1000), |seed| {
        covered(&SensitivitySimOptions {
            flicker: Some(0.0),
            run_s: 60.0,
            rate_hz: 20.0,
            ..vibration(seed)
        })
    });
    assert_band("vibration, white", &runs);
}

#[test]
fn magnetic_matrix_u95_covers_the_truth_with_flicker_and_random_walk() {
    let runs = monte_carlo(13, trials(40, 1000), |seed| {
        covered(&SensitivitySimOptions {
            seed,
            kind: Kind::Magnetic,
            sensor: Sensor::Gyro,
            run_s: 60.0,
            rate_hz: 20.0,
            flicker: Some(2.0),
            random_walk: 0.05,
            interleave: true,
            ..SensitivitySimOptions::default()
        })
    });
    assert_band("magnetic, flicker and random walk", &runs);
}

#[test]
fn shock_shifts_u95_covers_the_truth_with_the_scale_factor() {
    let runs = monte_carlo(14, trials(40, 1000), |seed| {
        covered(&SensitivitySimOptions {
            seed,
            kind: Kind::Shock,
            inputs: Some("-1,1".into()),
            sf_shifts_ppm: Some("150,-80".into()),
            repeats: 2,
            run_s: 20.0,
            rate_hz: 50.0,
            flicker: Some(10.0),
            ..SensitivitySimOptions::default()
        })
    });
    assert_band("shock with scale factor, flicker", &runs);
}

fn refused(rec: &Record, o: &SensitivityOptions, needles: &[&str]) {
    let e = reduce(rec, o).expect_err("refused").to_string();
    assert!(!e.contains('\n'), "{e}");
    for n in needles {
        assert!(e.contains(n), "{e} (wanted {n})");
    }
}

#[test]
fn a_single_level_is_refused_naming_the_stimulus() {
    let s = SensitivitySimOptions {
        levels: Some("4".into()),
        ..SensitivitySimOptions::default()
    };
    refused(
        &s.record().unwrap(),
        &s.reduction(),
        &["single stimulus level", "vib_g"],
    );
    let s = SensitivitySimOptions {
        kind: Kind::Magnetic,
        field_axes: "x".into(),
        levels: Some("0.5".into()),
        ..SensitivitySimOptions::default()
    };
    refused(
        &s.record().unwrap(),
        &s.reduction(),
        &["single stimulus level", "field"],
    );
}

#[test]
fn runs_at_plus_minus_45_alone_cannot_separate_the_rectification_terms() {
    let s = SensitivitySimOptions {
        angles_deg: "45,-45".into(),
        ..SensitivitySimOptions::default()
    };
    refused(
        &s.record().unwrap(),
        &s.reduction(),
        &["vrc", "vrc_pendulous"],
    );
}

#[test]
fn the_plan_predicts_the_reductions_u() {
    let p = SensitivityPlanOptions {
        angles_deg: "0,45,-45".into(),
        run_s: 20.0,
        rate_hz: 50.0,
        flicker: Some(3.0),
        ..SensitivityPlanOptions::default()
    };
    let doc = plan_document(&p).unwrap();
    let v = serde_json::to_value(&doc).unwrap();
    let predicted = v["predicted_u"]["vibropendulous"].as_f64().unwrap();
    let us: Vec<f64> = (0..20)
        .map(|k| {
            let s = SensitivitySimOptions {
                seed: 100 + k,
                flicker: Some(3.0),
                ..vibration(0)
            };
            let r = reduce(&s.record().unwrap(), &s.reduction()).unwrap();
            r.columns[0].coefficients.get("vibropendulous").unwrap().1
        })
        .collect();
    let rms = (us.iter().map(|u| u * u).sum::<f64>() / us.len() as f64).sqrt();
    assert!(
        (rms / predicted - 1.0).abs() < 0.35,
        "predicted {predicted}, reductions' rms u {rms}"
    );
}
