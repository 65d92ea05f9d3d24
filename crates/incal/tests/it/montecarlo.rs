//! The Monte Carlo propagation (JCGM 101) over many seeds: a linear
//! procedure's GUM interval validated at the default tolerance, and a
//! constructed nonlinear case (a ratio with a poor denominator) whose
//! Monte Carlo interval covers the truth at 95 % while the GUM's does not.
//! The statistical tier runs the counts of docs/src/monte-carlo.md's
//! figures at a smaller scale; `scripts/monte-carlo-study.sh` runs them
//! whole.

use incal::estimation::Noise;
use incal::models::{AccelerometerModel, Term};
use incal::montecarlo::{run, MonteCarloOptions, Trials};
use incal::procedures::gyro::rate::{GyroRate, GyroRateOptions, InputAxis, RateTerm};
use incal::procedures::tumble::sim::{simulate, TumbleSim};
use incal::procedures::tumble::{Tumble, TumbleOptions};
use incal::procedures::{Procedure, Silent};
use incal::rigs::Mount;
use incal::sim::gyro::{simulate_rate, GyroRateSim};
use incal::sim::tier;

fn tumble_sim(k0_g: f64, noise: f64, samples: usize, seed: u64) -> TumbleSim {
    TumbleSim {
        truth: AccelerometerModel {
            k0_g,
            k1_out_per_g: 1.0,
            ..AccelerometerModel::default()
        },
        mount: Mount::Pendulum,
        angles_deg: (0..12).map(|k| f64::from(k) * 30.0).collect(),
        samples,
        noise,
        index_error_rad: 0.0,
        passes: 1,
        seed,
    }
}

/// K0 = p0/p1 with K1 known to about 30 %: over the seeds whose
/// recording the reduction accepts (K1 observable), the Monte Carlo's
/// probabilistically symmetric interval covers the true K0 at 93–97 %,
/// the GUM interval measurably less (about 89 % in the chapter's run).
#[test]
fn a_ratio_is_covered_by_the_monte_carlo_interval_not_the_gum_one() {
    let seeds = tier::trials(30, 200) as u64;
    let o = TumbleOptions {
        mount: Mount::Pendulum,
        terms: vec![Term::K0, Term::K1],
        noise: Noise::Auto,
    };
    let (mut n, mut mc_hit, mut gum_hit, mut not_validated) = (0usize, 0usize, 0usize, 0usize);
    for seed in 1..=seeds {
        let obs = simulate(&tumble_sim(5.0, 1.5, 4, seed));
        let Ok(doc) = Tumble::reduce(&obs, &o, &Silent) else {
            continue; // K1 not observable: no result to judge
        };
        let mc = MonteCarloOptions {
            trials: Trials::Fixed(1000),
            seed,
            digits: 1,
        };
        let (section, _) = run::<Tumble>(&obs, &o, &doc, &mc, &Silent).unwrap();
        let s = &section.coefficients["K0"];
        let c = doc.coefficients.get("K0").unwrap();
        n += 1;
        mc_hit += usize::from(s.symmetric[0] <= 5.0 && 5.0 <= s.symmetric[1]);
        gum_hit += usize::from((c.value - 5.0).abs() <= c.u95);
        not_validated += usize::from(!s.validated);
    }
    assert!(n as f64 >= 0.8 * seeds as f64, "{n} of {seeds} reduced");
    let (mc_rate, gum_rate) = (mc_hit as f64 / n as f64, gum_hit as f64 / n as f64);
    let (lo, hi) = tier::band(n, 0.93, 0.97);
    assert!(
        lo <= mc_rate && mc_rate <= hi,
        "MC coverage {mc_rate} over {n}"
    );
    assert!(gum_rate < mc_rate, "GUM {gum_rate} vs MC {mc_rate}");
    if tier::full() {
        assert!(gum_rate < 0.93, "GUM coverage {gum_rate} over {n}");
    }
    assert!(
        not_validated as f64 >= 0.9 * n as f64,
        "{not_validated} of {n}"
    );
}

/// The linear procedures: with adaptive trials the GUM interval of every
/// coefficient is validated (JCGM 101 §8, δ from u to one significant
/// digit) at a rate of 95 % for the rate-transfer test (a 20 ppm table),
/// and of 85 % for the tumble test (default terms,
/// noise from the positions' scatter): where its test for an index-angle
/// error fires by chance (5 % of seeds) the tumble gives every coefficient
/// that estimate's n − p degrees of freedom, a conservative interval the
/// Monte Carlo does not validate (docs/src/monte-carlo.md: 92 of 100).
#[test]
fn linear_procedures_are_validated() {
    let seeds = tier::trials(3, 10) as u64;
    let auto = |seed| MonteCarloOptions {
        trials: Trials::Auto,
        seed,
        digits: 1,
    };
    let mut tumble_ok = 0;
    let mut rate_ok = 0;
    let o = TumbleOptions::new(Mount::Pendulum);
    let ro = GyroRateOptions {
        latitude_deg: 45.0,
        ia: InputAxis::Up,
        terms: vec![RateTerm::B, RateTerm::K1],
        noise: Noise::Auto,
        rate_uncertainty_ppm: 20.0,
        linearity_ppm: None,
        output_limit: None,
    };
    for seed in 1..=seeds {
        let mut sim = tumble_sim(0.01, 1e-4, 10, seed);
        sim.truth.k1_out_per_g = 10.0;
        let obs = simulate(&sim);
        let doc = Tumble::reduce(&obs, &o, &Silent).unwrap();
        let (s, _) = run::<Tumble>(&obs, &o, &doc, &auto(seed), &Silent).unwrap();
        tumble_ok += usize::from(s.coefficients.values().all(|c| c.validated));
        let robs = simulate_rate(&GyroRateSim {
            k1_pos: 0.02,
            k1_neg: 0.02,
            b_deg_h: 5.0,
            k2: 0.0,
            k3: 0.0,
            latitude_rad: 45f64.to_radians(),
            ia: InputAxis::Up,
            rates_deg_s: vec![-100.0, -50.0, -10.0, 0.0, 10.0, 50.0, 100.0],
            samples: 10,
            noise: 2e-5,
            runs: 1,
            run_scatter_ppm: 0.0,
            clip: 0.0,
            seed,
        });
        let rdoc = GyroRate::reduce(&robs, &ro, &Silent).unwrap();
        let (s, _) = run::<GyroRate>(&robs, &ro, &rdoc, &auto(seed), &Silent).unwrap();
        rate_ok += usize::from(s.coefficients.values().all(|c| c.validated));
    }
    // Three binomial standard deviations below the rate (10 seeds cannot
    // tell 95 % from 90 %; the chapter's figures are over 100 seeds, by
    // scripts/monte-carlo-study.sh).
    let n = seeds as f64;
    let at_least = |p: f64| ((p - 3.0 * (p * (1.0 - p) / n).sqrt()) * n + 1e-9).floor();
    assert!(
        tumble_ok as f64 >= at_least(0.85),
        "tumble {tumble_ok} of {seeds}"
    );
    assert!(
        rate_ok as f64 >= at_least(0.95),
        "gyro rate {rate_ok} of {seeds}"
    );
}
