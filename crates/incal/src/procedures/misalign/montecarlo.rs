//! Synthetic recordings of the accelerometer misalignment test for the
//! Monte Carlo propagation ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's angles β and sample counts and draws
//! every output from the fitted model ([`super::accel`]):
//! `V_i = ĉ + kI (−Δθ̂y2 cos β_j + Δθ̂z2 sin β_j) + σ* z_i`, with `σ*` the
//! sample noise as the reduction used it ([`crate::montecarlo::sample_noise`]:
//! the known σ, else the pooled scatter of the angles with `Σ(n_j − 1)`
//! degrees of freedom, else the residual σ with `n − 3`), drawn per trial
//! as `σ*² = s² ν / χ²_ν`. The misalignment `γ = √(Δθy2² + Δθz2²)` and its
//! azimuth are nonlinear in the outputs: where `γ` is not large against
//! its u the GUM's first-order interval is not validated, and the Monte
//! Carlo interval is the one to use.

use super::accel::{calibrate, AccelObservation, AccelOptions, ACCEL_ANGLES};
use super::angle_key;
use crate::error::Result;
use crate::montecarlo::{sample_noise, scaled_variance, Synthesis};
use crate::rigs::rate_table::face_factors;
use crate::sim::normal;

/// The recipe of synthetic accelerometer misalignment recordings for `obs`
/// reduced with `o`.
pub(super) fn accel_synthesis(
    obs: &[AccelObservation],
    o: &AccelOptions,
) -> Result<Synthesis<Vec<AccelObservation>>> {
    let r = calibrate(obs, o)?;
    let c = r.offset.values()[0];
    let (dy, dz) = (
        r.angles.value(ACCEL_ANGLES[0]).unwrap_or(0.0),
        r.angles.value(ACCEL_ANGLES[1]).unwrap_or(0.0),
    );
    let stats: Vec<_> = r.positions.iter().map(|p| p.stats).collect();
    let (s2, dof, noise) = sample_noise(
        o.noise.sigma(),
        &stats,
        r.fit.sigma,
        r.fit.dof as f64,
        "angle",
    );
    let k = o.scale_factor;
    let expected = move |beta: f64| {
        let f = face_factors(beta);
        c + k * (f[0] * dy + f[1] * dz)
    };
    let keys: Vec<i64> = r.positions.iter().map(|p| angle_key(p.beta_rad)).collect();
    let template: Vec<(f64, f64)> = obs
        .iter()
        .map(|x| {
            let j = keys
                .iter()
                .position(|q| *q == angle_key(x.beta_rad))
                .unwrap_or(0);
            (x.beta_rad, expected(r.positions[j].beta_rad))
        })
        .collect();
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Vec<AccelObservation>> {
        let sigma = scaled_variance(rng, s2, dof).sqrt();
        Ok(template
            .iter()
            .map(|&(beta_rad, mean)| AccelObservation {
                beta_rad,
                output: mean + normal(rng, sigma),
            })
            .collect())
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn: vec![noise],
        values: None,
    })
}
