//! Dynamic response from a broadband record: round trips from a known
//! transfer function over many seeds (U95 coverage of the model's
//! coefficients, bandwidth, delay and latency for both orders), the plan
//! against the Monte Carlo scatter, and the refusals.

use incal::procedures::response::broadband::plan::{plan_document, BroadbandPlanOptions};
use incal::procedures::response::broadband::sim::BroadbandSimOptions;
use incal::procedures::response::broadband::{calibrate, BroadbandOptions};
use incal::procedures::response::model::Order;
use incal::procedures::response::plan::ModelGuess;
use incal::procedures::response::OrderChoice;
use incal::sim::monte_carlo;
use incal::sim::tier::{band, trials};

fn sim(order: Order, seed: u64) -> BroadbandSimOptions {
    let mut o = BroadbandSimOptions {
        duration_s: 40.0,
        seed,
        ..BroadbandSimOptions::default()
    };
    if order == Order::First {
        o.model = ModelGuess {
            order: Order::First,
            corner_hz: 40.0,
            ..ModelGuess::default()
        };
    }
    o
}

fn options(order: Order) -> BroadbandOptions {
    let mut o = BroadbandOptions::default();
    o.model.order = match order {
        Order::First => OrderChoice::First,
        Order::Second => OrderChoice::Second,
    };
    o
}

const NAMES: [(&str, &str); 7] = [
    ("k_dc", "k_dc"),
    ("corner", "corner_hz"),
    ("zeta", "zeta"),
    ("delay_s", "delay_s"),
    ("bandwidth_hz", "bandwidth_hz"),
    ("phase_freq_hz", "phase_freq_hz"),
    ("latency_s", "latency_s"),
];

/// Whether each of `names` (`(coefficient, truth key)`; `corner` is
/// `fc_hz` or `fn_hz` by the order) covers the truth within its U95;
/// `None` where the truth or the result lacks it. Shared with the step's
/// round trips.
pub(crate) fn covered(
    e: &incal::estimation::Estimates,
    truth: &serde_json::Value,
    order: Order,
    names: &[(&str, &str)],
) -> Vec<Option<bool>> {
    let k95 = e.coverage_factor(0.95);
    let corner = if order == Order::First {
        "fc_hz"
    } else {
        "fn_hz"
    };
    names
        .iter()
        .map(|(name, key)| {
            let name = if *name == "corner" { corner } else { name };
            let t = truth[*key].as_f64()?;
            let (v, u) = e.get(name)?;
            Some((v - t).abs() <= k95 * u)
        })
        .collect()
}

/// Assert the coverage rate of every name over `runs` (rows of
/// [`covered`]) within the tier's band around 93–97 %; for the names in
/// `whole`, only its lower end (their u holds a rectangular part that U95
/// covers wholly).
pub(crate) fn assert_coverage(
    label: &str,
    names: &[(&str, &str)],
    runs: &[Vec<Option<bool>>],
    whole: &[&str],
) {
    let (lo, hi) = band(runs.len(), 0.93, 0.97);
    let mut outside = Vec::new();
    for (k, (name, _)) in names.iter().enumerate() {
        let hits: Vec<bool> = runs.iter().filter_map(|r| r[k]).collect();
        if hits.is_empty() {
            continue;
        }
        let rate = hits.iter().filter(|h| **h).count() as f64 / hits.len() as f64;
        eprintln!("{label}, {name}: {rate:.3} of {}", hits.len());
        let hi = if whole.contains(name) { 1.0 } else { hi };
        if !(lo..=hi).contains(&rate) {
            outside.push(format!(
                "{name}: U95 covers the truth in {rate:.3} of {} (band {lo:.3}..{hi:.3})",
                hits.len()
            ));
        }
    }
    assert!(outside.is_empty(), "{label}: {}", outside.join("; "));
}

fn coverage_run(order: Order, seed: u64) -> Vec<Option<bool>> {
    let s = sim(order, seed);
    let truth = s.truth_json().unwrap();
    let r = calibrate(&s.record().unwrap(), &options(order)).expect("reduces");
    covered(&r.part.coefficients, &truth, order, &NAMES)
}

fn check_coverage(order: Order, seed: u64) {
    let runs = monte_carlo(seed, trials(40, 200), |s| coverage_run(order, s));
    assert_coverage(&format!("broadband {order:?} order"), &NAMES, &runs, &[]);
}

#[test]
fn broadband_second_order_u95_covers_the_truth() {
    check_coverage(Order::Second, 301);
}

#[test]
fn broadband_first_order_u95_covers_the_truth() {
    check_coverage(Order::First, 302);
}

/// The plan's u are the reduction's own on four simulated records: they
/// predict the u the reduction reports (whose honesty the coverage tests
/// check), each within the spread of an RMS over four jackknife variances
/// of 19 degrees of freedom (about 8 %, three of them allowed).
#[test]
fn the_broadband_plan_predicts_the_u_the_reduction_reports() {
    let n = trials(20, 100);
    let s = sim(Order::Second, 0);
    let plan = BroadbandPlanOptions {
        model: s.model.clone(),
        duration_s: s.duration_s,
        rate_hz: s.rate_hz,
        amplitude: s.amplitude,
        noise: s.noise,
        segment_samples: 1024,
        min_coherence: 0.9,
        f_max_hz: None,
        seed: 1000,
    };
    let predicted = plan_document(&plan).unwrap().predicted_u.unwrap();
    let names = ["fn_hz", "zeta", "delay_s", "bandwidth_hz"];
    let runs = monte_carlo(19, n, |seed| {
        let mut o = s.clone();
        o.seed = seed;
        let r = calibrate(&o.record().unwrap(), &options(Order::Second)).unwrap();
        names.map(|n| r.part.coefficients.u(n).unwrap().powi(2))
    });
    for (k, name) in names.iter().enumerate() {
        let rms = (runs.iter().map(|r| r[k]).sum::<f64>() / n as f64).sqrt();
        let ratio = rms / predicted[*name];
        eprintln!("broadband plan, {name}: reported u / predicted u = {ratio:.3}");
        assert!(
            (ratio - 1.0).abs() <= 0.25,
            "{name}: the reductions report u {rms:.3e} (RMS), the plan {:.3e} (ratio {ratio:.3})",
            predicted[*name]
        );
    }
}

#[test]
fn a_broadband_plan_whose_coherent_bins_stop_below_the_corner_is_refused() {
    let plan = BroadbandPlanOptions {
        model: ModelGuess::default(),
        duration_s: 60.0,
        rate_hz: 1000.0,
        amplitude: 10.0,
        noise: 0.02,
        segment_samples: 1024,
        min_coherence: 0.9,
        f_max_hz: Some(50.0),
        seed: 1,
    };
    let e = plan_document(&plan).unwrap_err().to_string();
    assert!(e.contains("bandwidth_hz is not determined"), "{e}");
}

#[test]
fn a_reference_that_does_not_move_is_refused() {
    let mut rec = sim(Order::Second, 1).record().unwrap();
    rec.reference.iter_mut().for_each(|v| *v = 3.0);
    let e = calibrate(&rec, &BroadbandOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("reference does not move"), "{e}");
}

#[test]
fn too_few_coherent_bins_are_refused_naming_the_coherence() {
    let mut s = sim(Order::Second, 2);
    s.noise = 1e3;
    let e = calibrate(&s.record().unwrap(), &BroadbandOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("min_coherence"), "{e}");
}
