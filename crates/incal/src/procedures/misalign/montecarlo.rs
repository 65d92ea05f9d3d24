//! Synthetic recordings of the misalignment tests for the Monte Carlo
//! propagation ([`crate::montecarlo`]): the gyro on a rate table
//! ([`gyro_synthesis`]) and the accelerometer on a vertical face
//! ([`accel_synthesis`]).
//!
//! The gyro's trials keep every whole-revolution mean's configuration,
//! rate and count and draw it from the fitted linearised model
//! ([`super::gyro::model_output`]) with the fitted bias (one, or the
//! configuration's own), plus the sample noise as the reduction used it.
//! The raw records' summaries, which the document lists, are kept as
//! they are.
//!
//! Each trial keeps the recording's angles β and sample counts and draws
//! every output from the fitted model ([`super::accel`]):
//! `V_i = ĉ + kI (−Δθ̂y2 cos β_j + Δθ̂z2 sin β_j) + σ* z_i`, with `σ*` the
//! sample noise as the reduction used it ([`crate::montecarlo::sample_noise`]:
//! the known σ, else the pooled scatter of the angles with `Σ(n_j − 1)`
//! degrees of freedom, else the residual σ with `n − 3`; scaled by the
//! lack of fit where the fit failed its test,
//! [`crate::montecarlo::with_lack_of_fit`]), drawn per trial as
//! `σ*² = s² ν / χ²_ν`. The misalignment `γ = √(Δθy2² + Δθz2²)` and its
//! azimuth are nonlinear in the outputs: where `γ` is not large against
//! its u the GUM's first-order interval is not validated, and the Monte
//! Carlo interval is the one to use.

use super::accel::{calibrate, AccelObservation, AccelOptions, ACCEL_ANGLES};
use super::gyro::{self, GyroConfig, GyroObservation, GyroOptions, GYRO_ANGLES};
use super::input::GyroInput;
use super::{angle_key, key_angle};
use crate::error::Result;
use crate::montecarlo::{fit_noise, scaled_variance, Synthesis};
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
    let (s2, dof, noise) = fit_noise(o.noise.sigma(), &stats, &r.fit, "angle");
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
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// The recipe of synthetic gyro misalignment recordings for `i` reduced
/// with `o` (module docs).
pub(super) fn gyro_synthesis(i: &GyroInput, o: &GyroOptions) -> Result<Synthesis<GyroInput>> {
    let r = gyro::calibrate(&i.observations, o)?;
    let angles: [f64; 5] = GYRO_ANGLES.map(|n| r.angles.value(n).unwrap_or(0.0));
    let config = |x: &GyroObservation| GyroConfig {
        alpha_rad: key_angle(angle_key(x.alpha_rad)),
        beta_rad: key_angle(angle_key(x.beta_rad)),
    };
    let bias = |c: &GyroConfig| {
        let name = if o.per_config_bias {
            c.bias_name()
        } else {
            "bias".to_string()
        };
        r.biases.value(&name).unwrap_or(0.0)
    };
    let template: Vec<(GyroObservation, f64)> = i
        .observations
        .iter()
        .map(|x| {
            let c = config(x);
            let mean = gyro::model_output(c, x.rate_deg_s, o.scale_factor, bias(&c), &angles);
            (*x, mean)
        })
        .collect();
    let stats: Vec<_> = r.positions.iter().map(|p| p.stats).collect();
    let (s2, dof, noise) = fit_noise(o.noise.sigma(), &stats, &r.fit, "position");
    let records = i.records.clone();
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<GyroInput> {
        let sigma = scaled_variance(rng, s2, dof).sqrt();
        Ok(GyroInput {
            observations: template
                .iter()
                .map(|(x, mean)| GyroObservation {
                    output: mean + normal(rng, sigma),
                    ..*x
                })
                .collect(),
            records: records.clone(),
        })
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn: vec![noise],
        values: None,
        method: Vec::new(),
        factors: Vec::new(),
    })
}
