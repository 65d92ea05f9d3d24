//! Repeated samples at one test position, and the fit of their means.
//!
//! Every rig here records several samples per steady position. The fit uses
//! the position means `ȳ_i` (n_i samples each) with weights `n_i / s²`,
//! where `s²` is the pooled within-position variance
//! `s² = Σ_i Σ_k (y_ik − ȳ_i)² / Σ_i (n_i − 1)` (ν = Σ(n_i − 1) degrees of
//! freedom). Because position-level errors (index angle, drift, re-mounting)
//! do not average down with more samples, the variance factor is
//! `max(1, χ²/(n−p))` ([`Variance::AtLeast`]): the residuals between
//! positions can only raise the uncertainty, never hide behind the sample
//! scatter. With a single sample per position the residual scatter alone is
//! used (ν = n − p).

use nalgebra::DVector;

use super::linear::{fit, Design, Fit, FitOptions, Variance};
use crate::error::{Error, Result};

/// Summary of the samples taken at one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionStats {
    /// Number of samples.
    pub n: usize,
    /// Sample mean.
    pub mean: f64,
    /// Sample standard deviation (NaN when `n = 1`).
    pub std: f64,
}

impl PositionStats {
    /// Mean and standard deviation of `samples` (must be non-empty).
    pub fn of(samples: &[f64]) -> Result<PositionStats> {
        let n = samples.len();
        if n == 0 {
            return Err(Error::TooFew {
                what: "samples at a position".into(),
                needed: 1,
                got: 0,
            });
        }
        let mean = samples.iter().sum::<f64>() / n as f64;
        let std = if n > 1 {
            (samples.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt()
        } else {
            f64::NAN
        };
        Ok(PositionStats { n, mean, std })
    }
}

/// How the noise of one sample is known.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Noise {
    /// From the pooled scatter of repeated samples when there is any, else
    /// from the residuals; never below what the residuals show.
    #[default]
    Auto,
    /// Standard deviation of one sample, known beforehand (output units);
    /// still never below what the residuals show.
    Known {
        /// σ of one sample.
        sigma: f64,
    },
}

/// Pooled within-position variance and its degrees of freedom.
pub fn pooled_variance(positions: &[PositionStats]) -> (f64, usize) {
    let dof: usize = positions.iter().map(|p| p.n.saturating_sub(1)).sum();
    if dof == 0 {
        return (f64::NAN, 0);
    }
    let ss: f64 = positions
        .iter()
        .filter(|p| p.n > 1)
        .map(|p| p.std * p.std * (p.n - 1) as f64)
        .sum();
    (ss / dof as f64, dof)
}

/// Fit the position means with the noise policy of the module docs.
/// Returns the fit and the weights used (for standardized residuals).
pub fn fit_means(
    design: &Design,
    positions: &[PositionStats],
    noise: Noise,
) -> Result<(Fit, DVector<f64>)> {
    let y = DVector::from_iterator(positions.len(), positions.iter().map(|p| p.mean));
    let counts = DVector::from_iterator(positions.len(), positions.iter().map(|p| p.n as f64));
    let (weights, variance) = match noise {
        Noise::Known { sigma } => {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(Error::InvalidValue {
                    what: "noise sigma".into(),
                    value: sigma.to_string(),
                });
            }
            (
                counts / (sigma * sigma),
                Variance::AtLeast { dof: f64::INFINITY },
            )
        }
        Noise::Auto => {
            let (s2, dof) = pooled_variance(positions);
            if dof > 0 && s2 > 0.0 {
                (counts / s2, Variance::AtLeast { dof: dof as f64 })
            } else {
                (counts, Variance::FromResiduals)
            }
        }
    };
    let opts = FitOptions {
        weights: Some(weights.clone()),
        variance,
        ..FitOptions::default()
    };
    Ok((fit(design, &y, &opts)?, weights))
}
