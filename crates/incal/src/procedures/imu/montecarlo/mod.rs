//! Synthetic IMU sessions for the Monte Carlo propagation
//! ([`crate::montecarlo`]): the multi-position calibration
//! ([`multipos_synthesis`]) and the Ferraris calibration
//! ([`ferraris_synthesis`]).
//!
//! # Multi-position
//! Each trial keeps the session's positions (labels, up and north
//! directions, sample counts) and rotations, and draws every section's
//! statistics from the fitted model: per channel `c` (the six axis fits
//! are separate, as the reduction's), the mean of a section with `n`
//! samples is `ŷ + σ*_c z / √n` (`ŷ` the axis fit's prediction, `z ~
//! N(0, 1)`) and its sample variance `σ*_c² χ²_{n−1} / (n − 1)`, which is
//! how the mean and variance of `n` white normal samples are distributed;
//! `σ*_c²` is the channel's pooled within-position variance (`Σ(n − 1)`
//! degrees of freedom), else the fit's residual variance (`n − p`), scaled
//! by the fit's lack of fit where it failed its test
//! ([`crate::montecarlo::with_lack_of_fit`]), and drawn once per trial as
//! `s² ν / χ²_ν`. A rotation section's gyro mean is drawn the same way
//! around its prediction (the reduction fits the rotation's mean rate).
//!
//! # Ferraris
//! The Ferraris map has no redundancy: its "fitted model" is the sections'
//! means themselves. Each trial shifts every sample of a static section by
//! one draw `δ ~ N(0, S/n)` (`S` the section's sample covariance, all six
//! channels jointly) and every sample of a rotation by `δ_a ~ N(0,
//! S_a/n)` on the accelerometers and `δ_g/n`, `δ_g ~ N(0, n S_g)`, on the
//! gyros (`S_g` the gyro covariance pooled within the static sections:
//! white noise integrated over the rotation): the inputs' distribution the
//! GUM budget propagates, now through the map itself. With
//! `--u-rotation-deg`, the rotations' true angle is drawn as `A (1 + ε)`,
//! `ε ~ N(0, (u_A/A)²)`, once per trial (the budget has one angle for the
//! three rotations): each rotation's rate part (the gyro output above the
//! static bias and g-sensitivity the reduction estimated) is scaled by
//! `1 + ε` while the reduction still takes `A`.

use rand::rngs::ChaCha8Rng;

use super::input::MultiposInput;
use super::multipos::{multipos, pooled, MultiposSessionOptions};
use super::SectionStats;
use crate::error::Result;
use crate::montecarlo::{sample_variance, scaled_variance, with_lack_of_fit, Drawn, Synthesis};
use crate::sim::normal;

/// One channel's noise as the multi-position reduction used it: `(s², ν)`
/// and the row of the table.
fn channel_noise(
    input: &MultiposInput,
    fit: &crate::estimation::Fit,
    ch: usize,
    name: &str,
) -> (f64, f64, Drawn) {
    let (pooled, d) = pooled(&input.statics, ch);
    let (s2, dof, source) = if pooled > 0.0 && d > 0.0 {
        (pooled, d, "the positions' pooled scatter".to_string())
    } else {
        (
            fit.sigma.powi(2),
            fit.dof as f64,
            "the residuals (one mean per position)".to_string(),
        )
    };
    let row = Drawn::new(
        &format!("{name} noise of each sample"),
        &format!("normal, variance scaled inverse χ² (ν = {dof})"),
        format!("σ = {:.3e} output", s2.sqrt()),
        &source,
    );
    with_lack_of_fit((s2, dof, row), fit)
}

/// The recipe of synthetic multi-position sessions for `input` reduced
/// with `o` (module docs).
pub(super) fn multipos_synthesis(
    input: &MultiposInput,
    o: &MultiposSessionOptions,
) -> Result<Synthesis<MultiposInput>> {
    let r = multipos(
        &input.statics,
        &input.rotations,
        &o.model(input.gyro, input.rate_hz),
    )?;
    // Per channel: the predictions of the statics then the rotations, and
    // the noise.
    let mut predicted: Vec<Vec<f64>> = Vec::new();
    let mut noise: Vec<(f64, f64)> = Vec::new();
    let mut drawn = Vec::new();
    for (ch, (name, fit)) in r.fits.iter().enumerate() {
        let y: Vec<f64> = input
            .statics
            .iter()
            .map(|p| p.stats.mean[ch])
            .chain(input.rotations.iter().map(|s| s.stats.mean[ch]))
            .collect();
        predicted.push(
            y.iter()
                .zip(fit.residuals.iter())
                .map(|(y, e)| y - e)
                .collect(),
        );
        let (s2, dof, row) = channel_noise(input, fit, ch, name);
        noise.push((s2, dof));
        drawn.push(row);
    }
    let template = input.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<MultiposInput> {
        let mut x = template.clone();
        for (ch, (&(s2, dof), pred)) in noise.iter().zip(&predicted).enumerate() {
            let s2 = scaled_variance(rng, s2, dof);
            let sections = x
                .statics
                .iter_mut()
                .map(|p| (&mut p.stats, true))
                .chain(x.rotations.iter_mut().map(|s| (&mut s.stats, false)));
            for ((st, is_static), mean) in sections.zip(pred) {
                redraw_channel(rng, st, ch, *mean, s2, is_static);
            }
        }
        Ok(x)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: None,
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// Channel `ch` of `st` drawn anew (module docs): its mean around `mean`
/// with variance `s2 / n`; a static section's sample variance too (its
/// cross-covariances with the other channels set to 0: the axis fits are
/// separate); the sum follows the mean.
fn redraw_channel(
    rng: &mut ChaCha8Rng,
    st: &mut SectionStats,
    ch: usize,
    mean: f64,
    s2: f64,
    is_static: bool,
) {
    let n = st.n as f64;
    st.mean[ch] = mean + normal(rng, (s2 / n).sqrt());
    st.sum[ch] = st.mean[ch] * n;
    if is_static {
        for k in 0..6 {
            st.cov[ch][k] = 0.0;
            st.cov[k][ch] = 0.0;
        }
        st.cov[ch][ch] = sample_variance(rng, s2, n - 1.0);
    }
}

mod autocal;
mod ferraris;
pub(super) use autocal::autocal_synthesis;
pub(super) use ferraris::ferraris_synthesis;

#[cfg(test)]
mod tests;
