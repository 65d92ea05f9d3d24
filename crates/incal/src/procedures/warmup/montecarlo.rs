//! Synthetic warm-up records for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the record's rows, each row's validity (carried as a
//! status column, the trials reduced without the output limits, so the
//! turn-on row is the same) and draws every valid row after turn-on from
//! the fitted curve (module [`super`]):
//! `y_k = B(t_k + δ − t_on) + σ* z_k`, where
//! * `B` is the fitted curve, of the shape the reduction chose; each
//!   trial is reduced with that shape (the measurement model the GUM's u
//!   belongs to: a trial choosing again would mix other models' terms into
//!   the distributions);
//! * `δ ~ U(−s/2, s/2)` shifts the record's clock against power-on, `s`
//!   the interval the turn-on is known within: the turn-on time's
//!   rectangular type-B uncertainty, `u = s/√12`;
//! * `σ*² = σ²_LR ν/χ²_ν` is the long-run variance of one sample the
//!   reduction estimated (batch means, `ν = 20 − p`; scaled by the lack of
//!   fit where no shape passed, [`crate::montecarlo::with_lack_of_fit`]),
//!   drawn per trial; the
//!   trials' noise is white with that variance, which gives block means
//!   the variance the reduction assigned them (a sensor's correlated noise
//!   at the batch scale is in `σ²_LR`, not in its shape).

use rand::RngExt;

use super::fit::curve;
use super::input::Record;
use super::{calibrate, valid, CurveChoice, WarmupOptions};
use crate::error::Result;
use crate::montecarlo::{scaled_variance, with_lack_of_fit, Drawn, Synthesis};
use crate::sim::normal;

/// The recipe of synthetic warm-up records for `rec` reduced with `o`.
pub(super) fn synthesis(rec: &Record, o: &WarmupOptions) -> Result<Synthesis<Record>> {
    let r = calibrate(rec, o)?;
    let shape = r.shape;
    let p: Vec<f64> = r.fit.estimates.values().iter().copied().collect();
    let (s2, nu, noise) = with_lack_of_fit(
        (
            r.var_lr.0,
            r.var_lr.1,
            Drawn::new(
                "output noise of each valid sample",
                &format!("normal, variance scaled inverse χ² (ν = {})", r.var_lr.1),
                format!("σ_LR = {:.3e} output", r.var_lr.0.sqrt()),
                "the long-run variance of the fit's residuals (batch means)",
            ),
        ),
        &r.fit,
    );
    let step = r.turn_on.u_s * 12f64.sqrt();
    let from = r.turn_on.row;
    // Each row's validity is the recording's, carried as a status column
    // (the trials are reduced without the output limits): a drawn value
    // near a limit changes no row's validity nor the turn-on row.
    let status: Vec<f64> = (0..rec.output.len())
        .map(|k| f64::from(u8::from(valid(rec, o, k))))
        .collect();
    let fitted: Vec<bool> = status
        .iter()
        .enumerate()
        .map(|(k, v)| k >= from && *v != 0.0)
        .collect();
    let mut template = rec.clone();
    template.status = Some(status);
    let power_on = o.power_on_s;
    let half_step = step / 2.0;
    let drawn = vec![
        noise,
        Drawn::new(
            "the record's clock against power-on (the turn-on time)",
            "rectangular",
            format!("half-width {:.3e} s", step / 2.0),
            "the interval the first valid row leaves the turn-on in",
        ),
    ];
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Record> {
        let sigma = scaled_variance(rng, s2, nu).sqrt();
        let half = step / 2.0;
        let delta = if half > 0.0 {
            rng.random_range(-half..half)
        } else {
            0.0
        };
        let mut x = template.clone();
        for ((t, y), fit) in x.time_s.iter_mut().zip(x.output.iter_mut()).zip(&fitted) {
            *t += delta;
            if *fit {
                *y = Some(curve(shape, &p, *t - power_on) + normal(rng, sigma));
            }
        }
        Ok(x)
    };
    let fixed = WarmupOptions {
        curve: choice_of(shape),
        valid_min: None,
        valid_max: None,
        ..o.clone()
    };
    // The turn-on time of a trial is its first valid row's time less half
    // the recording's interval: the trial's own interval would be the
    // shifted first row's time where the output is valid from the first
    // row after power-on, half the spread.
    let values = move |x: &Record| -> Result<Vec<(String, f64)>> {
        let r = calibrate(x, &fixed)?;
        let c = &r.coefficients;
        let mut out: Vec<(String, f64)> = c
            .names()
            .iter()
            .cloned()
            .zip(c.values().iter().copied())
            .collect();
        out.push(("turn_on_time_s".into(), r.turn_on.first_valid_s - half_step));
        Ok(out)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: Some(Box::new(values)),
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// The option that asks for `shape`.
fn choice_of(shape: super::fit::Shape) -> CurveChoice {
    use super::fit::Shape;
    match shape {
        Shape::Exp1 => CurveChoice::Exp1,
        Shape::Exp1Drift => CurveChoice::Exp1Drift,
        Shape::Exp2 => CurveChoice::Exp2,
        Shape::Exp2Drift => CurveChoice::Exp2Drift,
    }
}

#[cfg(test)]
mod tests {
    use super::super::sim::WarmupSimOptions;
    use super::super::Warmup;
    use super::*;
    use crate::montecarlo::{MonteCarloOptions, Trials};
    use crate::procedures::{Procedure, Silent};

    fn record() -> Record {
        let s = WarmupSimOptions {
            rate_hz: 1.0,
            duration_s: 1200.0,
            tau_s: 120.0,
            ..WarmupSimOptions::default()
        };
        s.record().unwrap().0
    }

    /// The fast path gives exactly the document's coefficients.
    #[test]
    fn values_are_the_reductions() {
        let (rec, o) = (record(), WarmupOptions::default());
        let s = synthesis(&rec, &o).unwrap();
        let doc = Warmup::reduce(&rec, &o, &Silent).unwrap();
        let got = (s.values.unwrap())(&rec).unwrap();
        assert_eq!(got.len(), doc.coefficients.len());
        for (name, v) in got {
            assert_eq!(doc.coefficients.get(&name).unwrap().value, v, "{name}");
        }
    }

    /// The turn-on time is rectangular: its Monte Carlo std is the GUM's
    /// u (`s/√12`, here 0.29 s), its 95 % interval ±0.95 half-widths,
    /// narrower than the GUM's ±1.96 u by 0.09 s, beyond δ = 0.05 s: not
    /// validated, as for any rectangular input. The settled value's std is
    /// its u with the t of its dof (ν = 14: ×1.08).
    #[test]
    fn the_turn_on_is_rectangular() {
        let (rec, o) = (record(), WarmupOptions::default());
        let doc = Warmup::reduce(&rec, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::new(Trials::Fixed(200));
        let (m, _) = crate::montecarlo::run::<Warmup>(&rec, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(m.failed.count, 0);
        let on = &m.coefficients["turn_on_time_s"];
        let u = doc.coefficients.get("turn_on_time_s").unwrap().u;
        // M = 200: a uniform's std is known to 3.2 %.
        assert!((on.std / u - 1.0).abs() < 0.12, "{} {u}", on.std);
        assert!(!on.validated, "{on:?}");
        let b = &m.coefficients["bias_settled"];
        let ub = doc.coefficients.get("bias_settled").unwrap().u;
        assert!((0.9..1.3).contains(&(b.std / ub)), "{} {ub}", b.std);
    }

    /// Valid from the first row after power-on (power-on 0.5 s before
    /// it): the turn-on lies anywhere in [0, 0.5] s, u = 0.5/√12, and the
    /// trials spread over that whole interval, not half of it.
    #[test]
    fn a_record_valid_from_power_on_spreads_over_the_interval() {
        let rec = record();
        let o = WarmupOptions {
            power_on_s: 9.5,
            ..WarmupOptions::default()
        };
        let doc = Warmup::reduce(&rec, &o, &Silent).unwrap();
        let u = doc.coefficients.get("turn_on_time_s").unwrap().u;
        assert!((u - 0.5 / 12f64.sqrt()).abs() < 1e-9, "{u}");
        let mc = MonteCarloOptions::new(Trials::Fixed(200));
        let (m, _) = crate::montecarlo::run::<Warmup>(&rec, &o, &doc, &mc, &Silent).unwrap();
        let on = &m.coefficients["turn_on_time_s"];
        assert!((on.std / u - 1.0).abs() < 0.12, "{} {u}", on.std);
    }
}
