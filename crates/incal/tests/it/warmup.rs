//! Warm-up: round trips from a known warm-up curve over many seeds (U95
//! coverage of B∞, A, τ, the settling time and the warm-up drift, with
//! white and with Gauss–Markov noise), the curve rule's false-inclusion
//! and miss rates on two noise generators, the plan against the spread of
//! reductions, and the refusals.

use incal::procedures::warmup::fit::Shape;
use incal::procedures::warmup::plan::{plan_document, WarmupPlanOptions};
use incal::procedures::warmup::sim::WarmupSimOptions;
use incal::procedures::warmup::{calibrate, CurveChoice, WarmupOptions};
use incal::sim::monte_carlo;
use incal::sim::tier::{band, trials};

const NAMES: [(&str, &str); 6] = [
    ("bias_settled", "bias_settled"),
    ("amplitude", "amplitude"),
    ("tau_s", "tau_s"),
    ("settling_time_s", "settling_time_s"),
    ("warmup_drift", "warmup_drift"),
    ("tau_2_s", "tau_2_s"),
];

/// A 30-minute warm-up at 2 Hz, τ = 300 s.
fn sim(seed: u64) -> WarmupSimOptions {
    WarmupSimOptions {
        seed,
        rate_hz: 2.0,
        duration_s: 1800.0,
        ..WarmupSimOptions::default()
    }
}

/// Gauss–Markov noise as large as the white, correlated over 2 s (four
/// samples; its long-run variance 9 times the white's). Batch means hold
/// a fraction `1 − (τ_c/M)(1 − e^{−M/τ_c})` of it: 98 % for the 90-s
/// batches here. Measured over 200 seeds, longer correlation is partly
/// missed: at τ_c = 5 s (94 %) coverage 91.5–94.5 %, at 10 s (89 %)
/// 92–93.5 % (docs/src/warmup.md).
fn correlated(seed: u64) -> WarmupSimOptions {
    WarmupSimOptions {
        gm_sigma: 0.01,
        gm_tau_s: 2.0,
        ..sim(seed)
    }
}

fn covered(s: &WarmupSimOptions, o: &WarmupOptions) -> Vec<Option<bool>> {
    let truth = s.truth_json().unwrap();
    let r = calibrate(&s.record().unwrap().0, o).expect("reduces");
    let e = &r.coefficients;
    let k95 = e.coverage_factor(0.95);
    NAMES
        .iter()
        .map(|(name, key)| {
            let t = truth[*key].as_f64()?;
            let (v, u) = e.get(name)?;
            Some((v - t).abs() <= k95 * u)
        })
        .collect()
}

/// Assert every name's coverage in `[lo, hi]` (widened in the fast tier).
/// The band is 92–97.5 % at 200 seeds, where a rate spreads ±1.5 %; over
/// 1000 seeds (release build, 2026-11-29) every rate lies in 93–97 %:
/// white 95.1–97.0 %, Gauss–Markov 95.2–96.0 %, two exponentials
/// 95.6–96.5 %. The Gauss–Markov case, whose 200 seeds gave 92.5 %, runs
/// 1000 seeds in the statistical tier.
fn assert_band(label: &str, runs: &[Vec<Option<bool>>]) {
    let (lo, hi) = band(runs.len(), 0.92, 0.975);
    let mut outside = Vec::new();
    for (k, (name, _)) in NAMES.iter().enumerate() {
        let hits: Vec<bool> = runs.iter().filter_map(|r| r[k]).collect();
        if hits.is_empty() {
            continue;
        }
        let rate = hits.iter().filter(|h| **h).count() as f64 / hits.len() as f64;
        eprintln!("{label}, {name}: {rate:.3} of {}", hits.len());
        if !(lo..=hi).contains(&rate) {
            outside.push(format!(
                "{name}: {rate:.3} of {} (band {lo:.3}..{hi:.3})",
                hits.len()
            ));
        }
    }
    assert!(outside.is_empty(), "{label}: {}", outside.join("; "));
}

fn exp1() -> WarmupOptions {
    WarmupOptions {
        curve: CurveChoice::Exp1,
        ..WarmupOptions::default()
    }
}

#[test]
fn warmup_white_noise_u95_covers_the_truth() {
    let runs = monte_carlo(501, trials(40, 200), |s| covered(&sim(s), &exp1()));
    assert_band("warm-up, white noise", &runs);
}

#[test]
fn warmup_correlated_noise_u95_covers_the_truth() {
    let runs = monte_carlo(502, trials(40, 1000), |s| covered(&correlated(s), &exp1()));
    assert_band("warm-up, Gauss-Markov noise", &runs);
}

#[test]
fn warmup_two_exponentials_u95_covers_the_truth() {
    let two = |s| WarmupSimOptions {
        amplitude_2: 0.1,
        tau_2_s: 30.0,
        ..correlated(s)
    };
    let o = WarmupOptions {
        curve: CurveChoice::Exp2,
        ..WarmupOptions::default()
    };
    let runs = monte_carlo(503, trials(40, 200), |s| covered(&two(s), &o));
    assert_band("warm-up, two exponentials", &runs);
}

/// The shape the rule picks for each seed.
fn picks(make: impl Fn(u64) -> WarmupSimOptions + Sync, seed: u64, n: usize) -> Vec<Shape> {
    monte_carlo(seed, n, |s| {
        calibrate(&make(s).record().unwrap().0, &WarmupOptions::default())
            .expect("reduces")
            .shape
    })
}

fn rate(v: &[Shape], f: impl Fn(Shape) -> bool) -> f64 {
    v.iter().filter(|s| f(**s)).count() as f64 / v.len() as f64
}

/// A noise generator: its name, the simulator and a second exponential's
/// amplitude.
type Generator = (&'static str, fn(u64) -> WarmupSimOptions, f64);

#[test]
fn warmup_curve_rule_false_inclusion_and_miss_rates_on_two_generators() {
    let n = trials(40, 200);
    // The second exponential's amplitude and the miss rate allowed per
    // generator: the Gauss-Markov noise's long-run variance is 40 times
    // the white's (a second exponential of 0.1 is missed there in about
    // 15 % of records).
    let generators: [Generator; 2] = [("white", sim, 0.1), ("Gauss-Markov", correlated, 0.2)];
    for (label, gen, a2) in generators {
        // One exponential: anything more is a false inclusion (the rule's
        // level is 5 %; tested below 10 %).
        let one = picks(gen, 601, n);
        let fi = rate(&one, |s| s != Shape::Exp1);
        eprintln!("{label}: false inclusion {fi:.3} of {n}");
        let (_, hi) = band(n, 0.0, 0.10);
        assert!(fi <= hi, "{label}: false inclusion {fi:.3} of {n}");
        // A second exponential (tau_2 = 30 s), and a drift of 1e-4
        // output/s (a third of the settled value over the record): missed
        // in at most 10 % of records.
        let two = picks(
            |s| WarmupSimOptions {
                amplitude_2: a2,
                tau_2_s: 30.0,
                ..gen(s)
            },
            602,
            n,
        );
        let miss = rate(&two, |s| !s.two());
        eprintln!("{label}: second exponential missed {miss:.3} of {n}");
        assert!(
            miss <= hi,
            "{label}: second exponential missed {miss:.3} of {n}"
        );
        let drift = picks(
            |s| WarmupSimOptions {
                drift_per_s: 1e-4,
                ..gen(s)
            },
            603,
            n,
        );
        let miss = rate(&drift, |s| !s.drift());
        eprintln!("{label}: drift missed {miss:.3} of {n}");
        assert!(miss <= hi, "{label}: drift missed {miss:.3} of {n}");
    }
}

#[test]
fn warmup_plan_predicts_the_spread_and_refuses_a_short_record() {
    let o = WarmupPlanOptions {
        rate_hz: 2.0,
        duration_s: 1800.0,
        turn_on_s: 2.0,
        bias_settled: 0.5,
        amplitude: 0.2,
        tau_s: 300.0,
        noise: 0.01,
        gm_sigma: 0.0,
        gm_tau_s: 5.0,
        seed: 1,
    };
    let d = plan_document(&o).unwrap();
    let j = serde_json::to_value(&d).unwrap();
    let predicted = j["predicted_u"]["tau_s"].as_f64().expect("tau_s predicted");
    let runs = monte_carlo(701, trials(30, 200), |s| {
        calibrate(&sim(s).record().unwrap().0, &exp1())
            .unwrap()
            .coefficients
            .value("tau_s")
            .unwrap()
    });
    let mean = runs.iter().sum::<f64>() / runs.len() as f64;
    let sd =
        (runs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs.len() - 1) as f64).sqrt();
    assert!(
        (sd / predicted - 1.0).abs() < 0.4,
        "plan u(tau) {predicted:.3} s against the spread {sd:.3} s"
    );
    let short = WarmupPlanOptions {
        duration_s: 600.0,
        ..o
    };
    let e = plan_document(&short).unwrap_err().to_string();
    assert!(e.contains("duration_s") && e.contains("3 tau"), "{e}");
}

#[test]
fn warmup_refuses_a_record_too_short_to_see_tau() {
    let s = WarmupSimOptions {
        duration_s: 500.0,
        ..sim(1)
    };
    let e = calibrate(&s.record().unwrap().0, &WarmupOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("too short to see tau") && e.contains("3 tau"),
        "{e}"
    );
}

#[test]
fn warmup_turn_on_follows_status_and_validity_band() {
    let (rec, t_on) = sim(4).record().unwrap();
    let r = calibrate(&rec, &WarmupOptions::default()).unwrap();
    assert!(
        (r.turn_on.time_s - t_on).abs() <= 0.5 / 2.0 + 1e-12,
        "{:?} vs {t_on}",
        r.turn_on
    );
    assert!(!r.turn_on.valid_at_start);
    // A band the first samples miss moves the turn-on later.
    let o = WarmupOptions {
        valid_max: Some(0.69),
        ..WarmupOptions::default()
    };
    let later = calibrate(&rec, &o).unwrap();
    assert!(
        later.turn_on.time_s > r.turn_on.time_s + 1.0,
        "{:?}",
        later.turn_on
    );
    let never = WarmupOptions {
        valid_min: Some(10.0),
        ..WarmupOptions::default()
    };
    let e = calibrate(&rec, &never).unwrap_err().to_string();
    assert!(
        e.contains("never valid") && e.contains("at least 10"),
        "{e}"
    );
}

#[test]
fn warmup_valid_from_the_first_row_widens_the_turn_on_and_says_so() {
    let (rec, _) = sim(4).record().unwrap();
    // Power-on 5 s before the record: the first row is valid and late.
    let mut rec = rec;
    let on = rec.output.iter().position(|y| y.is_some()).unwrap();
    rec.time_s.drain(..on);
    rec.output.drain(..on);
    rec.lines.drain(..on);
    for v in [rec.status.as_mut(), rec.temperature_c.as_mut()]
        .into_iter()
        .flatten()
    {
        v.drain(..on);
    }
    let t0 = rec.time_s[0];
    let o = WarmupOptions {
        power_on_s: t0 - 5.0,
        ..WarmupOptions::default()
    };
    let r = calibrate(&rec, &o).unwrap();
    assert!(r.turn_on.valid_at_start);
    assert!((r.turn_on.time_s - 2.5).abs() < 1e-9, "{:?}", r.turn_on);
    assert!((r.turn_on.u_s - 5.0 / 12f64.sqrt()).abs() < 1e-9);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.message.contains("within [0, 5")),
        "{:?}",
        r.warnings
    );
}
