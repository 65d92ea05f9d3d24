//! Synthetic threshold recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's rows, commands and plateaus and
//! moves every plateau's mean onto a draw, `ȳ*_k = m_k + σ* z_k/√n_k`,
//! keeping each sample's deviation from its plateau mean (so the
//! within-plateau scatter is the recording's). The model `m_k` is what
//! the reduction assumes: the plateaus at one level (zero, the base
//! input) share one output, the level's mean weighted by samples; a step
//! plateau's output is its own mean (the response curve the reduction
//! measures, with no model across sizes). `σ*² = s² ν / χ²_ν` is the
//! noise of a plateau mean as the reduction measured it on the level
//! revisits (`s²` at the plateau's length, its `ν` degrees of freedom).
//! A given scale factor with a u (`scale_factor_u`) is a type-B input of
//! the measurement model, drawn as JCGM 101 draws an input: each trial
//! reduces with `K1* = K1 + N(0, u²)` and no u of its own (the reduction's
//! Fieller interval widens and moves its middle by the stated u, which in
//! a trial would count K1's uncertainty twice). The recording itself keeps
//! the stated K1: every plateau's distance from the first is scaled by
//! `K1/K1*` and the trial reduces with the stated K1, the same ratios
//! `S/K1*`. The threshold is the middle of a Fieller interval (module
//! docs of the reduction), so the trials' spread is that middle's,
//! compared with `u = U95/k95`.

use rand::rngs::ChaCha8Rng;

use super::input::Record;
use super::levels::Group;
use super::{calibrate, ThresholdOptions};
use crate::error::Result;
use crate::montecarlo::{scaled_variance, Drawn, Synthesis, ValuesFn};
use crate::sim::normal;

/// The recipe of synthetic threshold recordings for `rec` reduced with
/// `o` (module docs).
pub(super) fn synthesis(rec: &Record, o: &ThresholdOptions) -> Result<Synthesis<Record>> {
    let r = calibrate(rec, o)?;
    let level_mean = |g: Group| -> Option<f64> {
        let (s, n) = r
            .plateaus
            .iter()
            .filter(|q| q.level == Some(g))
            .fold((0.0, 0usize), |a, q| (a.0 + q.mean * q.n as f64, a.1 + q.n));
        (n > 0).then(|| s / n as f64)
    };
    let (zero, base) = (level_mean(Group::Zero), level_mean(Group::Base));
    // Each plateau: its rows, sample count, observed mean and model.
    let plateaus: Vec<((usize, usize), f64, f64, f64)> = r
        .plateaus
        .iter()
        .map(|q| {
            let m = match q.level {
                Some(Group::Zero) => zero.unwrap_or(q.mean),
                Some(Group::Base) => base.unwrap_or(q.mean),
                None => q.mean,
            };
            (q.rows, q.n as f64, q.mean, m)
        })
        .collect();
    let (s2, dof) = (r.noise.var_long, r.noise.dof);
    let mut drawn = vec![Drawn::new(
        "noise of each plateau mean (σ/√n)",
        &format!("normal, variance scaled inverse χ² (ν = {dof:.1})"),
        format!("σ = {:.3e} output, over √n of each plateau", s2.sqrt()),
        "the levels' revisits (two-sample variance at the plateaus' length)",
    )];
    let k_rel = match o.scale_factor {
        Some(k) if o.scale_factor_u > 0.0 => o.scale_factor_u / k.abs(),
        _ => 0.0,
    };
    if k_rel > 0.0 {
        drawn.push(Drawn::new(
            "the scale factor K1 each trial reduces with",
            "normal",
            format!("u(K1)/K1 = {k_rel:.3e}"),
            "--scale-factor-u",
        ));
    }
    let template = rec.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Record> {
        let s = scaled_variance(rng, s2, dof).sqrt();
        let gain = 1.0 / (1.0 + normal(rng, k_rel));
        let origin = plateaus.first().map_or(0.0, |p| p.3);
        let mut out = template.clone();
        for &((a, b), n, mean, m) in &plateaus {
            let target = origin + (m - origin) * gain + normal(rng, s / n.sqrt());
            for y in &mut out.output[a..=b] {
                *y += target - mean;
            }
        }
        Ok(out)
    };
    // With K1 drawn, each trial reduces without the stated u.
    let plain = ThresholdOptions {
        scale_factor_u: 0.0,
        ..o.clone()
    };
    let values: Option<ValuesFn<Record>> = (k_rel > 0.0).then(|| {
        Box::new(move |x: &Record| {
            let e = calibrate(x, &plain)?.coefficients()?;
            Ok(e.names()
                .iter()
                .cloned()
                .zip(e.values().iter().copied())
                .collect())
        }) as ValuesFn<Record>
    });
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values,
        method: Vec::new(),
        factors: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::super::sim::ThresholdSimOptions;
    use super::super::{Threshold, ThresholdOptions};
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    /// The simulator's gyro record: the threshold, the resolution and K1
    /// spread over the trials as their u says (K1 is linear in the plateau
    /// means: its std is its u times the t's `√(ν/(ν − 2))` = 1.07 at the
    /// revisits' 16 dof, within the sampling error; the crossings' are
    /// Fieller middles, within 25 %).
    #[test]
    fn the_plateau_draws_spread_as_the_reduction_says() {
        let rec = ThresholdSimOptions {
            seed: 11,
            ..ThresholdSimOptions::default()
        }
        .record()
        .unwrap();
        let o = ThresholdOptions::default();
        let doc = Threshold::reduce(&rec, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(600, 3);
        let (section, _) = run::<Threshold>(&rec, &o, &doc, &mc, &Silent).unwrap();
        assert!(section.failed.count <= 6, "{:?}", section.failed);
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            eprintln!("{name}: std/u = {r:.3}");
            let band = if name == "K1" { 0.97..1.17 } else { 0.85..1.3 };
            assert!(band.contains(&r), "{name}: std/u = {r}");
        }
    }

    /// A given K1 with a u: the trials' outputs answer another K1, so the
    /// threshold widens; without the u it does not.
    #[test]
    fn a_stated_scale_factor_u_widens_the_threshold() {
        let sim = ThresholdSimOptions {
            seed: 12,
            ..ThresholdSimOptions::default()
        };
        let rec = sim.record().unwrap();
        let k = sim.scale_factor;
        let std = |u: f64| {
            let o = ThresholdOptions {
                scale_factor: Some(k),
                scale_factor_u: u,
                ..ThresholdOptions::default()
            };
            let doc = Threshold::reduce(&rec, &o, &Silent).unwrap();
            let mc = MonteCarloOptions::fixed(400, 5);
            let (s, _) = run::<Threshold>(&rec, &o, &doc, &mc, &Silent).unwrap();
            (s.coefficients["threshold_deg_s"].std, doc)
        };
        let (plain, _) = std(0.0);
        let (wide, doc) = std(0.1 * k.abs());
        let u = doc.coefficients.get("threshold_deg_s").unwrap().u;
        eprintln!("plain {plain:.3e}, wide {wide:.3e}, u {u:.3e}");
        assert!(wide > 1.2 * plain, "plain {plain}, wide {wide}");
        assert!((0.75..1.3).contains(&(wide / u)), "std/u = {}", wide / u);
    }
}
