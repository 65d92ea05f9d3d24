//! Synthetic rate-transfer recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's rates, run labels and sample counts
//! (the rates the reduction fitted: clipped ones and those beyond the
//! input range are left out) and draws the outputs from the fitted model
//! `E = a0 + a1 ω + c |ω| + a2 ω² + a3 ω³` (those fitted) at the true
//! input rate `ω = s ((1 + ε) ω_k + Ω_e sin φ)`, plus noise:
//! * `ε ~ N(0, u_r²)`, one draw per trial (the table's rate error is
//!   systematic), `u_r` = `rate_uncertainty_ppm` · 10⁻⁶;
//! * the sample noise as in the tumble's synthesis: the known σ, else the
//!   pooled scatter with `Σ(n_k − 1)` degrees of freedom, else the
//!   residual σ with `n − p`, each drawn as `σ*² = s² ν / χ²_ν`.

use crate::error::Result;
use crate::montecarlo::{sample_noise, scaled_variance, Drawn, Synthesis};
use crate::sim::normal;

use super::{
    calibrate, design, earth_rate_deg_s, normalized_terms, GyroRateOptions, RateObservation,
};

/// The recipe of synthetic rate-transfer recordings for `obs` reduced with
/// `o`.
pub(super) fn synthesis(
    obs: &[RateObservation],
    o: &GyroRateOptions,
) -> Result<Synthesis<Vec<RateObservation>>> {
    let r = calibrate(obs, o)?;
    let a = r.fit.estimates.values().clone();
    let terms = normalized_terms(&o.terms);
    let asym = r.asymmetric;
    let kept = |x: &RateObservation| {
        r.positions
            .iter()
            .any(|p| p.rate_deg_s.to_bits() == x.rate_deg_s.to_bits() && p.run == x.run)
    };
    let template: Vec<RateObservation> = obs.iter().filter(|x| kept(x)).cloned().collect();
    let stats: Vec<_> = r.positions.iter().map(|p| p.stats).collect();
    let fit_dof = r.fit.dof as f64;
    let (s2, dof, noise) = sample_noise(o.noise.sigma(), &stats, r.fit.sigma, fit_dof, "rate");
    let u_rate = o.rate_uncertainty_ppm * 1e-6;
    let mut drawn = vec![noise];
    if u_rate > 0.0 {
        drawn.push(Drawn::new(
            "relative error of the table's rate (one per trial)",
            "normal",
            format!("u = {} ppm", o.rate_uncertainty_ppm),
            "rate_uncertainty_ppm",
        ));
    }
    let (sign, earth) = (o.ia.sign(), earth_rate_deg_s() * o.latitude_rad().sin());
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Vec<RateObservation>> {
        let sigma = scaled_variance(rng, s2, dof).sqrt();
        let eps = normal(rng, u_rate);
        let inputs: Vec<f64> = template
            .iter()
            .map(|x| sign * ((1.0 + eps) * x.rate_deg_s + earth))
            .collect();
        let expected = design(&inputs, &terms, asym)?.matrix() * &a;
        Ok(template
            .iter()
            .zip(expected.iter())
            .map(|(x, e)| RateObservation {
                rate_deg_s: x.rate_deg_s,
                output: e + normal(rng, sigma),
                run: x.run.clone(),
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
