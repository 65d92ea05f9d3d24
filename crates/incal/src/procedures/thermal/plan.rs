//! Plateau plan: the predicted u of every polynomial coefficient for a
//! set of plateau temperatures, before the chamber is booked
//! (`incal plan thermal`).
//!
//! With each plateau's coefficient known to `u_p` (from the reduction's
//! own plan, e.g. `incal plan tumble`), the polynomial (1) of degree `d`
//! has `C = (AᵀWA)⁻¹`, `A_ik = (T_i − T_ref)^k`, `W = diag(1/u_p²)`: the
//! same design the fit uses ([`super::fit_poly`]), so the prediction is
//! the fit's own covariance when the plateaus deliver their u. A degree
//! the plateaus cannot separate (`d + 1` above the distinct
//! temperatures) is refused naming the term.

use super::{distinct_temperatures, fit_poly, MAX_DEGREE};
use crate::error::{Error, Result};

/// The predicted standard uncertainty of `c_0…c_d` (unit per °C^k) and
/// the residual degrees of freedom `n − d − 1`.
pub fn predict(
    plateaus_c: &[f64],
    u_plateau: f64,
    degree: usize,
    t_ref_c: f64,
) -> Result<(Vec<f64>, usize)> {
    if !(u_plateau.is_finite() && u_plateau > 0.0) {
        return Err(Error::InvalidValue {
            what: "u of a plateau (above 0)".into(),
            value: u_plateau.to_string(),
        });
    }
    if degree > MAX_DEGREE {
        return Err(Error::InvalidValue {
            what: format!("degree (0 to {MAX_DEGREE})"),
            value: degree.to_string(),
        });
    }
    let m = distinct_temperatures(plateaus_c);
    if degree + 1 > m {
        return Err(Error::Unsupported(format!(
            "{m} distinct plateau temperature(s) cannot separate c{degree} (the degree-{degree} term): add plateaus, at least {}",
            degree + 1
        )));
    }
    // The fit of zeros has the design's covariance.
    let n = plateaus_c.len();
    let f = fit_poly(
        plateaus_c,
        &vec![0.0; n],
        &vec![u_plateau; n],
        &[],
        t_ref_c,
        degree,
        f64::INFINITY,
    )?;
    let u = (0..=degree)
        .map(|k| f.covariance[(k, k)].max(0.0).sqrt())
        .collect();
    Ok((u, n - degree - 1))
}

/// A ramp plan: the chamber profile of [`super::sim::RampSim`] (set
/// points, ramp rate, holds, the sensor's lag, sample rate), the white
/// noise σ of one sample and the block length.
#[derive(Debug, Clone)]
pub struct RampPlan {
    /// The profile (its channels and seed are not used).
    pub profile: super::sim::RampSim,
    /// White noise of one sample, in the channel's unit.
    pub noise: f64,
    /// Block length, s.
    pub block_s: f64,
    /// Degree of the polynomial.
    pub degree: usize,
}

/// The predicted u of `c_0…c_d` and of the hysteresis (when both branches
/// are covered) for a ramp, with the residual degrees of freedom: the
/// blocks the reduction ([`super::ramp`]) will form from the noiseless
/// profile, each with `u = σ/√n`, in the design the fit uses.
pub fn predict_ramp(p: &RampPlan) -> Result<(Vec<f64>, Option<f64>, usize)> {
    let mut prof = p.profile.clone();
    prof.temperature_noise_c = 0.0;
    if prof.channels.is_empty() {
        prof.channels = vec![super::sim::ChannelTruth {
            name: "x".into(),
            c: vec![0.0],
            hysteresis: 0.0,
            noise: 1.0,
        }];
    }
    if !(p.noise.is_finite() && p.noise > 0.0) {
        return Err(Error::InvalidValue {
            what: "noise (above 0)".into(),
            value: p.noise.to_string(),
        });
    }
    prof.validate()?;
    let o = super::ramp::RampOptions {
        rate_hz: prof.rate_hz,
        block_s: p.block_s,
        degree: super::Degree::Fixed(p.degree),
        ..Default::default()
    };
    <super::ramp::Ramp as crate::procedures::Procedure>::validate(&o)?;
    let mut csv = Vec::new();
    prof.write(&mut csv)?;
    let mut rows =
        incal_io::Reader::new("plan", csv.as_slice(), &incal_io::ReadOptions::default())?;
    let input = super::ramp::read(&mut rows, &o)?;
    let super::ramp::BlockDesign {
        temp_c: t,
        rows: n,
        branch,
        ..
    } = super::ramp::block_design(&input, p.block_s)?;
    let u: Vec<f64> = n.iter().map(|&n| p.noise / (n as f64).sqrt()).collect();
    let mut extra = Vec::new();
    let both = super::ramp::both_branches(&t, &branch);
    if both {
        extra.push((
            "hysteresis".to_string(),
            branch.iter().map(|&b| 0.5 * b as f64).collect::<Vec<f64>>(),
        ));
    }
    let m = distinct_temperatures(&t);
    if p.degree + 1 > m {
        return Err(Error::Unsupported(format!(
            "the ramp covers {m} distinct block temperature(s): it cannot separate c{}",
            p.degree
        )));
    }
    let f = fit_poly(
        &t,
        &vec![0.0; t.len()],
        &u,
        &extra,
        prof.t_ref_c,
        p.degree,
        f64::INFINITY,
    )?;
    let uc = (0..=p.degree)
        .map(|k| f.covariance[(k, k)].max(0.0).sqrt())
        .collect();
    let uh = both.then(|| {
        let j = p.degree + 1;
        f.covariance[(j, j)].max(0.0).sqrt()
    });
    Ok((uc, uh, f.fit.dof))
}
