//! Synthetic step records for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the record's reference (so the step is located at the
//! same `t₀` with the same levels) and its rate, and draws the output
//! from the fitted model at every sample,
//!
//! `y_k* = ŷ₀ + K̂ A s(t_k − t₀ − δ − τ̂) + σ* z_k`,
//!
//! * `σ*²` the output's scatter before the step (`n_pre − 1` degrees of
//!   freedom), scaled by the fit's lack of fit where it failed its test
//!   ([`crate::montecarlo::with_lack_of_fit`]), drawn once per trial as
//!   `s² ν / χ²_ν`; every sample, before the step too, so the trial's
//!   weight is estimated as the record's was;
//! * `δ ~ U(−Δt/2, Δt/2)` once per trial where the reference jumps within
//!   one sample (the reduction's `u(t₀) = Δt/√12`): when in the sample
//!   interval the step truly happened, which the reduction cannot see.
//!
//! Each trial is fitted with the order the reduction chose (the fast path
//! [`crate::montecarlo::Synthesis::values`] is the reduction with that
//! order fixed): its coefficients are then the same set, except an
//! overshoot, which only an underdamped trial reports (the others count
//! as failed trials, by reason).

use rand::rngs::ChaCha8Rng;
use rand::RngExt;

use super::{calibrate, unit_step, StepOptions};
use crate::error::Result;
use crate::montecarlo::{scaled_variance, with_lack_of_fit, Drawn, Synthesis};
use crate::procedures::response::broadband::input::Record;
use crate::sim::normal;

/// The recipe of synthetic step records for `rec` reduced with `o`
/// (module docs).
pub(super) fn synthesis(rec: &Record, o: &StepOptions) -> Result<Synthesis<Record>> {
    let r = calibrate(rec, o)?;
    let p: Vec<f64> = r.fit.estimates.values().iter().copied().collect();
    let (order, at) = (r.order, r.located);
    let dof = (at.pre - 1) as f64;
    let row = Drawn::new(
        "output noise of each sample",
        &format!("normal, variance scaled inverse χ² (ν = {dof})"),
        format!("σ = {:.3e} output", r.sigma),
        "the output's scatter before the step",
    );
    let (s2, dof, row) = with_lack_of_fit((r.sigma * r.sigma, dof, row), &r.fit);
    let dt = 1.0 / rec.rate_hz;
    let half = if at.u_t0_s > 0.0 { 0.5 * dt } else { 0.0 };
    let mut drawn = vec![row];
    if half > 0.0 {
        drawn.push(Drawn::new(
            "the step's true time within the sample it jumps in (one per trial)",
            "rectangular",
            format!("half-width {half:.3e} s"),
            "the reference's sample interval",
        ));
    }
    let template = rec.clone();
    let a = at.r1 - at.r0;
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Record> {
        let sigma = scaled_variance(rng, s2, dof).sqrt();
        let delta = if half > 0.0 {
            rng.random_range(-half..half)
        } else {
            0.0
        };
        let x = &p[1..];
        let tau = x[x.len() - 1];
        let mut out = template.clone();
        for (k, y) in out.output.iter_mut().enumerate() {
            let t = k as f64 * dt - at.t0_s - delta - tau;
            *y = p[0] + x[0] * a * unit_step(order, x, t) + normal(rng, sigma);
        }
        Ok(out)
    };
    let fixed = StepOptions {
        order: order.into(),
        ..o.clone()
    };
    let values = move |x: &Record| -> Result<Vec<(String, f64)>> {
        let e = calibrate(x, &fixed)?.coefficients;
        Ok(e.names()
            .iter()
            .cloned()
            .zip(e.values().iter().copied())
            .collect())
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: Some(Box::new(values)),
        method: Vec::new(),
        factors: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::super::sim::StepSimOptions;
    use super::super::{ResponseStep, StepOptions};
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::response::OrderChoice;
    use crate::procedures::{Procedure, Silent};

    /// The simulator's second-order step: every coefficient's Monte Carlo
    /// standard deviation against its GUM u. The model is nonlinear in
    /// the corner, damping and delay, but at this noise the first order
    /// holds: each within 0.85–1.2 (the rectangular step time and the
    /// scaled inverse χ² of σ included); and the fast path is the
    /// reduction with the order fixed.
    #[test]
    fn step_coefficients_follow_their_u() {
        let s = StepSimOptions {
            seed: 4,
            ..StepSimOptions::default()
        };
        let rec = s.record().unwrap().0;
        let o = StepOptions::default();
        let doc = ResponseStep::reduce(&rec, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(400, 7);
        let (section, _) = run::<ResponseStep>(&rec, &o, &doc, &mc, &Silent).unwrap();
        assert!(section.failed.count <= 4, "{:?}", section.failed);
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            assert!((0.85..1.2).contains(&r), "{name}: std/u = {r}");
        }
        let syn = ResponseStep::synthesis(&rec, &o, &doc).unwrap().unwrap();
        let x = (syn.draw)(&mut crate::sim::rng(1)).unwrap();
        let second = StepOptions {
            order: OrderChoice::Second,
            ..o
        };
        let full = ResponseStep::reduce(&x, &second, &Silent).unwrap();
        for (name, v) in (syn.values.as_ref().unwrap())(&x).unwrap() {
            assert_eq!(full.coefficients.get(&name).unwrap().value, v, "{name}");
        }
    }
}
