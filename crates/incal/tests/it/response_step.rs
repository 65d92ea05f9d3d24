//! Step response: round trips from a known transfer function over many
//! seeds (U95 coverage of the model's coefficients, the delay and the step
//! metrics for both orders, with the step anywhere within a sample), and
//! the refusals.

use incal::procedures::response::model::Order;
use incal::procedures::response::plan::ModelGuess;
use incal::procedures::response::step::plan::{plan_document, StepPlanOptions};
use incal::procedures::response::step::sim::StepSimOptions;
use incal::procedures::response::step::{calibrate, StepOptions};
use incal::procedures::response::OrderChoice;
use incal::sim::monte_carlo;
use incal::sim::tier::trials;

use crate::response_broadband::{assert_coverage, covered};

fn sim(order: Order, seed: u64) -> StepSimOptions {
    let mut o = StepSimOptions {
        seed,
        ..StepSimOptions::default()
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

fn options(order: Order) -> StepOptions {
    StepOptions {
        order: match order {
            Order::First => OrderChoice::First,
            Order::Second => OrderChoice::Second,
        },
        ..StepOptions::default()
    }
}

const NAMES: [(&str, &str); 9] = [
    ("k_dc", "k_dc"),
    ("corner", "corner_hz"),
    ("zeta", "zeta"),
    ("delay_s", "delay_s"),
    ("bandwidth_hz", "bandwidth_hz"),
    ("latency_s", "latency_s"),
    ("rise_time_s", "rise_time_s"),
    ("settling_time_s", "settling_time_s"),
    ("overshoot_pct", "overshoot_pct"),
];

fn coverage_run(order: Order, seed: u64) -> Vec<Option<bool>> {
    let s = sim(order, seed);
    let truth = s.truth_json().unwrap();
    let r = calibrate(&s.record().unwrap().0, &options(order)).expect("reduces");
    covered(&r.coefficients, &truth, order, &NAMES)
}

fn check_coverage(order: Order, seed: u64) {
    let runs = monte_carlo(seed, trials(40, 300), |s| coverage_run(order, s));
    // The delay (and what holds it) is dominated by the step's time,
    // rectangular within one sample: U95 = 1.96 u of a rectangular covers
    // it wholly (GUM's normal k is conservative there).
    assert_coverage(
        &format!("step {order:?} order"),
        &NAMES,
        &runs,
        &["delay_s", "latency_s", "settling_time_s"],
    );
}

#[test]
fn step_second_order_u95_covers_the_truth() {
    check_coverage(Order::Second, 401);
}

#[test]
fn step_first_order_u95_covers_the_truth() {
    check_coverage(Order::First, 402);
}

#[test]
fn the_order_rule_finds_the_second_order_of_a_step() {
    let r = calibrate(
        &sim(Order::Second, 5).record().unwrap().0,
        &StepOptions::default(),
    )
    .unwrap();
    assert_eq!(r.order, Order::Second, "{}", r.order_reason);
}

#[test]
fn a_reference_that_does_not_step_is_refused() {
    let (mut rec, _) = sim(Order::Second, 1).record().unwrap();
    rec.reference.iter_mut().for_each(|v| *v = 2.0);
    let e = calibrate(&rec, &StepOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("does not step"), "{e}");
}

#[test]
fn a_step_plan_whose_record_ends_before_the_response_settles_is_refused() {
    let o = StepPlanOptions {
        model: ModelGuess {
            order: Order::First,
            corner_hz: 1.0,
            ..ModelGuess::default()
        },
        duration_s: 1.0,
        rate_hz: 1000.0,
        step_s: 0.3,
        amplitude: 10.0,
        noise: 0.02,
        reference_noise: 0.005,
        seed: 1,
    };
    let e = plan_document(&o).unwrap_err().to_string();
    assert!(e.contains("settling_time_s is not determined"), "{e}");
}
