//! Synthetic runs for the Monte Carlo propagation of a repeatability
//! analysis ([`crate::montecarlo`]).
//!
//! Each trial keeps the runs' days, sources and stated u and draws their
//! values from the fitted nested model, `x*_dt = μ̂ + a_d + b_dt + e_dt`
//! with `a_d ~ N(0, σ̂²_day)`, `b_dt ~ N(0, σ̂²_on)` (each component as
//! the analysis reported it, 0 where it was estimated at or below zero)
//! and `e_dt ~ N(0, u²_dt)`; a run whose u carries degrees of freedom
//! reports `u·√(χ²_ν/ν)` (the scatter of an estimated u), an exact u
//! itself. The components are the measurands: they are the truth of the
//! trials, not drawn from a posterior (the spread of the trials'
//! estimates around them is the estimates' sampling distribution, which
//! `u(s) = s/√(2ν)` approximates).

use rand::rngs::ChaCha8Rng;

use super::{analyse, RepeatabilityOptions, Run};
use crate::error::Result;
use crate::montecarlo::{sample_variance, Drawn, Synthesis};
use crate::sim::normal;

/// The recipe of synthetic runs for `runs` analysed with `o` (module
/// docs).
pub(super) fn synthesis(runs: &[Run], o: &RepeatabilityOptions) -> Result<Synthesis<Vec<Run>>> {
    let r = analyse(runs, o)?;
    let mu = r.mean.0;
    let on = r.turn_on.map_or(0.0, |c| c.sd);
    let day = r.day.map_or(0.0, |c| c.sd);
    // Each run's day index.
    let mut day_of = vec![0usize; runs.len()];
    for (d, (_, ix)) in r.days.iter().enumerate() {
        for &k in ix {
            day_of[k] = d;
        }
    }
    let n_days = r.days.len();
    let unit = &o.unit;
    let mut drawn = vec![Drawn::new(
        "each run's own error",
        "normal",
        format!("σ = the run's u ({:.3e} {unit} mean square)", r.within.sd),
        "each run's u",
    )];
    if runs.iter().any(|x| x.dof.is_finite()) {
        drawn.push(Drawn::new(
            "each run's stated u",
            "u·√(χ²_ν/ν), ν the run's dof",
            "the run's u and dof".into(),
            "each run's dof",
        ));
    }
    if r.turn_on.is_some() {
        drawn.push(Drawn::new(
            "turn-on effect of each run",
            "normal",
            format!("σ = {on:.3e} {unit}"),
            "turn_on_repeatability",
        ));
    }
    if r.day.is_some() {
        drawn.push(Drawn::new(
            "day effect of each day",
            "normal",
            format!("σ = {day:.3e} {unit}"),
            "day_repeatability",
        ));
    }
    let template = runs.to_vec();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Vec<Run>> {
        let a: Vec<f64> = (0..n_days).map(|_| normal(rng, day)).collect();
        Ok(template
            .iter()
            .zip(&day_of)
            .map(|(x, &d)| {
                let value = mu + a[d] + normal(rng, on) + normal(rng, x.u);
                let u = if x.dof.is_finite() {
                    sample_variance(rng, x.u * x.u, x.dof).sqrt()
                } else {
                    x.u
                };
                Run {
                    value,
                    u,
                    ..x.clone()
                }
            })
            .collect())
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: None,
        method: Vec::new(),
        factors: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::super::sim::RepeatSimOptions;
    use super::super::{Repeatability, RepeatabilityOptions};
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    /// Five days of three turn-ons with every component well above the
    /// runs' u: the mean and the simple formula spread as their u, the
    /// components as `s/√(2ν)` within the sampling error of the trials and
    /// the roughness of Satterthwaite's ν at these few runs.
    #[test]
    fn the_nested_draws_spread_as_the_analysis_says() {
        let runs = RepeatSimOptions {
            days: 8,
            turn_ons_per_day: 4,
            seed: 3,
            ..RepeatSimOptions::default()
        }
        .runs()
        .unwrap();
        let o = RepeatabilityOptions::default();
        let doc = Repeatability::reduce(&runs, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(2000, 7);
        let (section, _) = run::<Repeatability>(&runs, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0);
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            eprintln!("{name}: std/u = {r:.3}");
            assert!((0.8..1.25).contains(&r), "{name}: std/u = {r}");
        }
    }

    /// Runs whose u carry few degrees of freedom: the stated u are drawn,
    /// so the trials' within-run part scatters; the trials still run
    /// (weighted when the drawn u spread past 3).
    #[test]
    fn estimated_run_u_are_drawn_with_their_dof() {
        let runs = RepeatSimOptions {
            within_dof: Some(4.0),
            seed: 5,
            ..RepeatSimOptions::default()
        }
        .runs()
        .unwrap();
        let o = RepeatabilityOptions::default();
        let doc = Repeatability::reduce(&runs, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(300, 2);
        let (section, _) = run::<Repeatability>(&runs, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0);
        assert_eq!(section.drawn.len(), 4);
        assert!(section.coefficients["mean"].std > 0.0);
    }
}
