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

/// How often the order rule adds `vib_linear` (a term in g) to the
/// vibration model.
fn linear_added(s: &SensitivitySimOptions) -> bool {
    let r = reduce(&s.record().unwrap(), &s.reduction()).expect("reduces");
    r.columns[0]
        .fit
        .terms
        .iter()
        .any(|t| t.name.starts_with("vib_linear"))
}

fn rate(v: &[bool]) -> f64 {
    v.iter().filter(|x| **x).count() as f64 / v.len() as f64
}

#[test]
fn the_order_rule_false_inclusion_and_miss_rates() {
    // Two generators: white noise with the runs in ascending order (0..8
    // g), and white with flicker with a run at zero between levels (in
    // ascending order a drift the runs hardly show is confounded with a
    // term in g: the chapter gives those rates); 20-s runs at 50 Hz.
    let n = trials(60, 400);
    // Measured over 400 seeds: white 5.2 % false inclusion, 93.8 % found;
    // flicker 4.8 % and 78.5 % (the flicker's u is larger).
    for (label, flicker, interleave, power) in
        [("white", 0.0, false, 0.9), ("flicker", 3.0, true, 0.72)]
    {
        let base = |seed| SensitivitySimOptions {
            seed,
            flicker: Some(flicker),
            interleave,
            run_s: 20.0,
            rate_hz: 50.0,
            ..SensitivitySimOptions::default()
        };
        let false_in = rate(&monte_carlo(21, n, |seed| linear_added(&base(seed))));
        // A linear term of 5 µg/g: what g² cannot absorb of it over 0..8 g
        // is about 9 µg, against runs' u of about 1.6 µg.
        let found = rate(&monte_carlo(22, n, |seed| {
            linear_added(&SensitivitySimOptions {
                vib_linear: 5.0,
                ..base(seed)
            })
        }));
        eprintln!("order rule, {label}: false inclusion {false_in:.3}, found {found:.3} of {n}");
        assert!(
            false_in <= incal::sim::tier::at_most(n, 0.08),
            "{label}: false inclusion {false_in}"
        );
        assert!(
            found >= incal::sim::tier::at_least(n, power),
            "{label}: found {found}"
        );
    }
}

#[test]
fn the_noise_model_flicker_false_inclusion_and_miss_rates() {
    let n = trials(40, 400);
    let flicker_kept = |seed, b: f64| {
        let s = SensitivitySimOptions {
            seed,
            flicker: Some(b),
            run_s: 20.0,
            rate_hz: 50.0,
            ..SensitivitySimOptions::default()
        };
        let r = reduce(&s.record().unwrap(), &s.reduction()).expect("reduces");
        r.columns[0].noise.flicker > 0.0
    };
    let false_in = rate(&monte_carlo(23, n, |seed| flicker_kept(seed, 0.0)));
    let marginal = rate(&monte_carlo(24, n, |seed| flicker_kept(seed, 3.0)));
    let strong = rate(&monte_carlo(25, n, |seed| flicker_kept(seed, 10.0)));
    eprintln!(
        "flicker kept: white {false_in:.3}, bias instability 3 µg {marginal:.3}, 10 µg {strong:.3} of {n}"
    );
    assert!(
        false_in <= incal::sim::tier::at_most(n, 0.3),
        "white: {false_in}"
    );
    assert!(
        strong >= incal::sim::tier::at_least(n, 0.95),
        "strong: {strong}"
    );
}

#[test]
fn an_empty_session_and_a_scale_factor_of_zero_are_refused_not_panicking() {
    let s = SensitivitySimOptions::default();
    let mut rec = s.record().unwrap();
    rec.runs.clear();
    assert!(reduce(&rec, &s.reduction()).is_err());
    // An input column that does not drive the output: the scale factor is
    // zero within its u and the ppm terms are refused.
    let s = SensitivitySimOptions {
        kind: Kind::Shock,
        inputs: Some("-1,1".into()),
        run_s: 5.0,
        rate_hz: 20.0,
        ..SensitivitySimOptions::default()
    };
    let mut rec = s.record().unwrap();
    for r in &mut rec.runs {
        let k0 = 1e6 * r.input.unwrap();
        for v in &mut r.samples[0] {
            *v -= k0;
        }
    }
    refused(
        &rec,
        &s.reduction(),
        &["scale factor", "not distinguishable from zero"],
    );
}
