//! Synthetic multi-position recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's head angles, azimuths and sample
//! counts and draws every output from the fitted model (module
//! [`super`]): `E_i = K1* (Ω·IA + Σ_t D̂_t x_t(θ)) / 3600 + σ* z_i`, with
//! * `D̂` the fitted drift terms (deg/h, deg/h/g, deg/h/g²);
//! * `K1*` the gyro's true scale factor in this trial: with K1 given (or
//!   from a gyro-rate result) `K1* = K1 + u(K1) t`, `t` normal, or Student
//!   t with the result's degrees of freedom (drawn as a normal with a
//!   scaled inverse χ² variance), while the reduction divides by the stated
//!   K1 — the type-B input of the reduction; with K1 fitted, the fitted
//!   K1 (it is estimated from these outputs);
//! * `σ*` the sample noise as the reduction used it
//!   ([`crate::montecarlo::sample_noise`], scaled by the lack of fit where
//!   the fit failed its test, [`crate::montecarlo::with_lack_of_fit`]),
//!   drawn per trial.

use super::{
    calibrate, earth_rate_ia_deg_h, specific_force, GyroPositionsOptions, PositionObservation,
    ScaleFactor,
};
use crate::error::Result;
use crate::montecarlo::{sample_noise, scaled_variance, with_lack_of_fit, Drawn, Synthesis};
use crate::sim::normal;

/// The recipe of synthetic multi-position recordings for `obs` reduced
/// with `o`.
pub(super) fn synthesis(
    obs: &[PositionObservation],
    o: &GyroPositionsOptions,
) -> Result<Synthesis<Vec<PositionObservation>>> {
    let r = calibrate(obs, o)?;
    let sf = o.k1_source()?.scale_factor();
    let (k1, k1_draw) = match sf {
        ScaleFactor::Known { k1, u, dof } => (k1, (u > 0.0).then_some((u, dof))),
        ScaleFactor::Fit => (r.coefficients.value("K1").unwrap_or(f64::NAN), None),
    };
    // The drift in deg/h at each sample's position (Earth rate included).
    let lat = o.latitude_rad();
    let terms = r.terms.clone();
    let d: Vec<f64> = terms
        .iter()
        .map(|t| r.coefficients.value(t.name()).unwrap_or(0.0))
        .collect();
    let rate_deg_h: Vec<(f64, f64, f64)> = obs
        .iter()
        .map(|x| {
            let a = specific_force(x.angle_rad, o.axial);
            let drift: f64 = terms.iter().zip(&d).map(|(t, v)| v * t.regressor(a)).sum();
            (
                x.angle_rad,
                x.azimuth_rad,
                earth_rate_ia_deg_h(x.angle_rad, x.azimuth_rad, lat) + drift,
            )
        })
        .collect();
    // The fit's residual σ is in deg/h when K1 is given (the outputs were
    // scaled by 3600/K1), in output units when K1 is fitted.
    let fit_sigma = match sf {
        ScaleFactor::Known { k1, .. } => r.fit.sigma * k1.abs() / 3600.0,
        ScaleFactor::Fit => r.fit.sigma,
    };
    let stats: Vec<_> = r.positions.iter().map(|p| p.stats).collect();
    let (s2, nu, noise) = with_lack_of_fit(
        sample_noise(
            o.noise.sigma(),
            &stats,
            fit_sigma,
            r.fit.dof as f64,
            "position",
        ),
        &r.fit,
    );
    let mut drawn = vec![noise];
    if let Some((u, dof)) = k1_draw {
        drawn.push(Drawn::new(
            "scale factor K1 of the gyro (one per trial, systematic)",
            &if dof.is_finite() {
                format!("normal, variance scaled inverse χ² (ν = {dof})")
            } else {
                "normal".to_string()
            },
            format!("K1 = {k1:.6e}, u = {u:.3e} output/(deg/s)"),
            "k1 and u_k1, or the gyro-rate result",
        ));
    }
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Vec<PositionObservation>> {
        let sigma = scaled_variance(rng, s2, nu).sqrt();
        let k = match k1_draw {
            Some((u, dof)) => {
                let u_star = scaled_variance(rng, u * u, dof).sqrt();
                k1 + normal(rng, u_star)
            }
            None => k1,
        };
        Ok(rate_deg_h
            .iter()
            .map(|&(angle_rad, azimuth_rad, w)| PositionObservation {
                angle_rad,
                azimuth_rad,
                output: k * w / 3600.0 + normal(rng, sigma),
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
