//! Synthetic tumble recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's angles, pass labels and sample
//! counts and draws the outputs from the fitted model:
//! `E_i = Σ_t p_t φ_t(a(θ_j + ε_j)) + σ* z_i`, where
//! * `p` are the fitted linear parameters ([`super::design`]);
//! * `ε_j ~ N(0, τ*²)` is the head's index-angle error at position `j`,
//!   `τ*² = τ̂² ν / χ²_ν` with `τ̂` the Paule–Mandel estimate and `ν` the
//!   fit's degrees of freedom (`n − p`), when the residuals showed one;
//! * `σ*` is the sample noise: the known σ (`noise`), else the pooled
//!   scatter `s` of the positions with its `Σ(n_j − 1)` degrees of freedom,
//!   else (one sample per position) the residual σ with `n − p`, each
//!   drawn as `σ*² = s² ν / χ²_ν`.

use crate::error::Result;
use crate::estimation::PositionStats;
use crate::montecarlo::{sample_noise, scaled_variance, Drawn, Synthesis};
use crate::sim::normal;

use super::{angle_key, calibrate, coefficients, Observation, TumbleOptions};

/// The recipe of synthetic tumble recordings for `obs` reduced with `o`.
pub(super) fn synthesis(
    obs: &[Observation],
    o: &TumbleOptions,
) -> Result<Synthesis<Vec<Observation>>> {
    let o = o.settled();
    let r = calibrate(obs, &o)?;
    let p = r.fit.estimates.values().clone();
    // Each sample's position (the reduction's grouping by pass and angle).
    let keys: Vec<(Option<String>, i64)> = r
        .positions
        .iter()
        .map(|q| (q.pass.clone(), angle_key(q.angle_rad).0))
        .collect();
    let slot: Vec<usize> = obs
        .iter()
        .map(|x| {
            let k = (x.pass.clone(), angle_key(x.angle_rad).0);
            keys.iter().position(|q| *q == k).unwrap_or(0)
        })
        .collect();
    let angles: Vec<f64> = r.positions.iter().map(|q| q.angle_rad).collect();
    let stats: Vec<PositionStats> = r.positions.iter().map(|q| q.stats).collect();
    let fit_dof = r.fit.dof as f64;
    let (noise_s2, noise_dof, noise) =
        sample_noise(o.noise.sigma(), &stats, r.fit.sigma, fit_dof, "position");
    let index = r.index_error_rad.filter(|t| *t > 0.0 && fit_dof > 0.0);
    let mut drawn = vec![noise];
    if let Some(t) = index {
        drawn.push(Drawn::new(
            "index-angle error of the head at each position",
            &format!("normal, variance scaled inverse χ² (ν = {fit_dof})"),
            format!("τ = {:.3e} rad", t),
            "the residuals beyond the noise (Paule–Mandel)",
        ));
    }
    let mount = o.mount;
    let terms = o.terms.clone();
    let template: Vec<Observation> = obs.to_vec();
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Vec<Observation>> {
        let sigma = scaled_variance(rng, noise_s2, noise_dof).sqrt();
        let tau = index.map_or(0.0, |t| scaled_variance(rng, t * t, fit_dof).sqrt());
        let expected: Vec<f64> = angles
            .iter()
            .map(|&a| {
                let f = mount.specific_force(a + normal(rng, tau));
                terms
                    .iter()
                    .zip(p.iter())
                    .map(|(t, pk)| pk * t.regressor(&f))
                    .sum()
            })
            .collect();
        Ok(template
            .iter()
            .zip(&slot)
            .map(|(x, &j)| Observation {
                angle_rad: x.angle_rad,
                output: expected[j] + normal(rng, sigma),
                pass: x.pass.clone(),
            })
            .collect())
    };
    let values = move |x: &Vec<Observation>| -> Result<Vec<(String, f64)>> {
        let c = coefficients(x, &o)?;
        Ok(c.names()
            .iter()
            .cloned()
            .zip(c.values().iter().copied())
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
