//! The Monte Carlo on the tumble test: agreement with the GUM where the
//! model is linear, a constructed ratio where it is not, the same
//! document on one thread or many, and the refusals.

use super::*;
use crate::estimation::Noise;
use crate::models::{AccelerometerModel, Term};
use crate::procedures::tumble::sim::{simulate, TumbleSim};
use crate::procedures::tumble::{Observation, Tumble, TumbleOptions};
use crate::procedures::{Procedure, Silent};
use crate::rigs::Mount;

fn twelve() -> Vec<f64> {
    (0..12).map(|k| f64::from(k) * 30.0).collect()
}

/// A tumble recording: 12 positions, `samples` each, noise `noise`.
fn recording(k0_g: f64, noise: f64, samples: usize, seed: u64) -> Vec<Observation> {
    simulate(&TumbleSim {
        truth: AccelerometerModel {
            k0_g,
            k1_out_per_g: 1.0,
            k2: 0.0,
            k3: 0.0,
            delta_o_rad: 0.0,
            k_ip: 0.0,
            ..AccelerometerModel::default()
        },
        mount: Mount::Pendulum,
        angles_deg: twelve(),
        samples,
        noise,
        index_error_rad: 0.0,
        passes: 1,
        seed,
    })
}

fn options(noise: Noise) -> TumbleOptions {
    TumbleOptions {
        mount: Mount::Pendulum,
        terms: vec![Term::K0, Term::K1],
        noise,
    }
}

fn reduce(obs: &Vec<Observation>, o: &TumbleOptions) -> ResultDocument {
    Tumble::reduce(obs, o, &Silent).unwrap()
}

fn mc(trials: u64, seed: u64) -> MonteCarloOptions {
    MonteCarloOptions {
        trials: Trials::Fixed(trials),
        seed,
        digits: 1,
    }
}

/// Linear in the data and the noise known: the trials' standard deviation
/// is the GUM u within the Monte Carlo's own sampling error (the standard
/// deviation of a sample standard deviation is `u / √(2(M − 1))`).
#[test]
fn a_linear_result_agrees_with_the_gum() {
    let obs = recording(0.01, 1e-3, 10, 4);
    let o = options(Noise::Known { sigma: 1e-3 });
    let doc = reduce(&obs, &o);
    let m = 4000;
    let (section, warnings) = run::<Tumble>(&obs, &o, &doc, &mc(m, 9), &Silent).unwrap();
    assert_eq!(section.trials, m);
    for (name, c) in doc.coefficients.iter() {
        let s = &section.coefficients[name];
        let sampling = c.u / (2.0 * (m as f64 - 1.0)).sqrt();
        assert!(
            (s.std - c.u).abs() <= 4.0 * sampling,
            "{name}: {} vs {}",
            s.std,
            c.u
        );
        assert!(s.shortest[0] < c.value && c.value < s.shortest[1]);
    }
    assert!(!warnings.iter().any(|w| w.code == WarningCode::TrialsFailed));
    // The correlation of K0 and K1 is the fit's.
    let r = section.correlation.matrix[0][1];
    assert!((r - doc.correlation.matrix[0][1]).abs() < 0.1, "{r}");
}

/// K0 = p0/p1 with p1 known to 25 %: the distribution of K0 is skewed,
/// the GUM's symmetric interval is not validated and a warning says so.
#[test]
fn a_ratio_with_a_poor_denominator_is_not_validated() {
    let obs = recording(5.0, 1.5, 4, 3);
    let o = options(Noise::Auto);
    let doc = reduce(&obs, &o);
    let (section, warnings) = run::<Tumble>(&obs, &o, &doc, &mc(4000, 1), &Silent).unwrap();
    let k0 = &section.coefficients["K0"];
    assert!(!k0.validated, "{k0:?}");
    assert_eq!(k0.decision, "not validated: use the Monte Carlo interval");
    // Skewed to the right: the upper end lies further from y than the lower.
    let y = doc.coefficients.get("K0").unwrap().value;
    assert!(k0.symmetric[1] - y > y - k0.symmetric[0], "{k0:?}");
    assert!(warnings
        .iter()
        .any(|w| w.code == WarningCode::GumNotValidated && w.message.contains("K0")));
}

/// The trials' seeds do not depend on who runs them: one thread and many
/// give the same section, bit for bit; another seed another one.
#[test]
fn one_thread_and_many_give_the_same_bits() {
    let obs = recording(0.01, 1e-3, 5, 2);
    let o = options(Noise::Auto);
    let doc = reduce(&obs, &o);
    let go = |seed| run::<Tumble>(&obs, &o, &doc, &mc(500, seed), &Silent).unwrap();
    let many = go(5);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| go(5));
    assert_eq!(many, one);
    assert_ne!(
        many.0.coefficients["K1"].mean,
        go(6).0.coefficients["K1"].mean
    );
}

/// The tumble's fast path gives exactly the values of its reduction.
#[test]
fn the_fast_path_reports_what_the_reduction_reports() {
    let obs = recording(0.01, 1e-3, 5, 7);
    let o = TumbleOptions::new(Mount::Pendulum);
    let doc = reduce(&obs, &o);
    let s = Tumble::synthesis(&obs, &o, &doc).unwrap().unwrap();
    let fast = s.values.as_ref().unwrap();
    for k in 0..5 {
        let x = (s.draw)(&mut crate::sim::rng(k)).unwrap();
        assert_eq!(x.len(), obs.len());
        let full = reduce(&x, &o);
        for (name, v) in fast(&x).unwrap() {
            assert_eq!(full.coefficients.get(&name).unwrap().value, v, "{name}");
        }
    }
}

/// Adaptive trials stop once every result is stable to its tolerance;
/// then a linear result's GUM interval is validated (JCGM 101 §8 asks for
/// the Monte Carlo to be stable at δ before it judges).
#[test]
fn auto_stops_when_stable_and_validates_a_linear_result() {
    let obs = recording(0.01, 1e-3, 5, 2);
    let o = options(Noise::Known { sigma: 1e-3 });
    let doc = reduce(&obs, &o);
    let a = MonteCarloOptions::new(Trials::Auto);
    let (section, _) = run::<Tumble>(&obs, &o, &doc, &a, &Silent).unwrap();
    assert_eq!(section.stabilised, Some(true));
    assert!(section.trials >= 2 * BATCH && section.trials % BATCH == 0);
    assert!(section.tolerance_ratio.unwrap() <= 1.0);
    for (name, c) in &section.coefficients {
        assert!(c.validated, "{name}: {c:?}");
    }
}

#[test]
fn refusals_name_the_option() {
    let obs = recording(0.01, 1e-3, 5, 2);
    let o = options(Noise::Auto);
    let doc = reduce(&obs, &o);
    for (bad, key) in [
        (mc(10, 1), "monte_carlo"),
        (mc(MAX_TRIALS + 1, 1), "monte_carlo"),
    ] {
        match run::<Tumble>(&obs, &o, &doc, &bad, &Silent) {
            Err(crate::Error::InvalidOption { key: k, .. }) => assert_eq!(k, key),
            other => panic!("{other:?}"),
        }
    }
    let mut digits = mc(200, 1);
    digits.digits = 0;
    assert!(
        matches!(digits.validate(), Err(crate::Error::InvalidOption { key, .. }) if key == "mc_digits")
    );
    assert_eq!("auto".parse::<Trials>(), Ok(Trials::Auto));
    assert!("many".parse::<Trials>().unwrap_err().contains("'many'"));
    let t: MonteCarloOptions = serde_json::from_str(r#"{"trials": "auto"}"#).unwrap();
    assert_eq!((t.trials, t.seed, t.digits), (Trials::Auto, 1, 1));
    assert!(serde_json::from_str::<MonteCarloOptions>(r#"{"trials": "lots"}"#).is_err());
}

#[test]
fn failed_trials_are_grouped_by_reason() {
    assert_eq!(
        reason_key("K1 = 1.5e-3 at line 12, U95 -2"),
        "K1 = # at line #, U95 -#"
    );
    let t: Vec<Trial> = vec![
        Err("x = 1".into()),
        Err("x = 2".into()),
        Ok(vec![1.0]),
        Err("y".into()),
    ];
    assert_eq!(
        failures(&t),
        vec![("x = #".to_string(), 2), ("y".to_string(), 1)]
    );
}
