//! Gyro tests on the rate table and the dividing head (IEEE Std 952 /
//! 1431 / 517): the rate-transfer test ([`rate`]) and the multi-position
//! test ([`positions`]).
//!
//! Each is one procedure folder with the files of every procedure
//! (`{mod,input,plan,sim,document}.rs`: model and map, columns and checks
//! of a recording, plan, simulator, result document) and implements
//! [`super::Procedure`]: [`rate::GyroRate`] and [`positions::GyroPositions`].
//!
//! Both are reduced from the means of repeated samples (per rate, per head
//! angle and azimuth) on the one least-squares engine, with the variance of
//! the means from the pooled sample scatter (or a known noise σ of one
//! sample), and both are planned by running the same reduction on
//! noise-free means with a known noise (so the plan and the reduction
//! cannot disagree).
//!
//! # Units
//! Rates in deg/s at the input (`rate_deg_s`), the scale factor K1 in
//! output/(deg/s), drift terms in deg/h, deg/h/g and deg/h/g² as IEEE
//! Std 1431 quotes them. The Earth rate is
//! [`crate::units::EARTH_RATE_RAD_S`] (7.292115e-5 rad/s = 15.041 deg/h).

pub mod positions;
pub mod rate;

use crate::document::{DocumentBuilder, FitSummary, Procedure};
use crate::estimation::{Estimates, Fit, Noise, PositionStats};
use crate::units::{Unit, EARTH_RATE_RAD_S};

/// Earth rate in deg/h (15.0411 deg/h).
pub fn earth_rate_deg_h() -> f64 {
    EARTH_RATE_RAD_S.to_degrees() * 3600.0
}

/// Earth rate in deg/s.
pub fn earth_rate_deg_s() -> f64 {
    EARTH_RATE_RAD_S.to_degrees()
}

/// Group values by a key, keeping the order of first appearance.
pub(crate) fn group<K: PartialEq + Clone>(
    items: impl Iterator<Item = (K, f64)>,
) -> Vec<(K, Vec<f64>)> {
    let mut out: Vec<(K, Vec<f64>)> = Vec::new();
    for (k, v) in items {
        match out.iter_mut().find(|(kk, _)| *kk == k) {
            Some((_, vs)) => vs.push(v),
            None => out.push((k, vec![v])),
        }
    }
    out
}

/// Position statistics scaled by `s` (mean and scatter in new units).
pub(crate) fn scale_stats(p: &PositionStats, s: f64) -> PositionStats {
    PositionStats {
        n: p.n,
        mean: p.mean * s,
        std: p.std * s.abs(),
    }
}

/// A noise option scaled by `s` (|s|).
pub(crate) fn scale_noise(n: Noise, s: f64) -> Noise {
    match n {
        Noise::Auto => Noise::Auto,
        Noise::Known { sigma } => Noise::Known {
            sigma: sigma * s.abs(),
        },
    }
}

/// Effective degrees of freedom of coefficient `name` (infinite when not listed).
pub(crate) fn dof_lookup(dof: &[(String, f64)], name: &str) -> f64 {
    dof.iter()
        .find(|d| d.0 == name)
        .map_or(f64::INFINITY, |d| d.1)
}

/// What both gyro result documents open with.
pub(crate) struct DocumentHead<'a> {
    /// The procedure of the document.
    pub procedure: Procedure,
    /// The title before the counts (`Gyro rate-transfer test`).
    pub title: String,
    /// What the fit's observations are, plural (`rates`, `positions`).
    pub observations: &'a str,
    /// The terms fitted, in model order.
    pub terms: Vec<&'static str>,
    /// The coefficients.
    pub coefficients: &'a Estimates,
    /// Effective degrees of freedom of each coefficient ([`dof_lookup`]).
    pub dof: &'a [(String, f64)],
    /// The unit of a coefficient by its name.
    pub unit_of: fn(&str) -> crate::error::Result<Unit>,
    /// The fit.
    pub fit: &'a Fit,
    /// The unit of the fit's residuals.
    pub residual_unit: Unit,
}

impl DocumentHead<'_> {
    /// The builder holding the title `TITLE (N OBSERVATIONS, terms A, B)`,
    /// the coefficients with their own degrees of freedom, the fit summary
    /// `main` and the option `terms`.
    pub(crate) fn builder(self) -> crate::error::Result<DocumentBuilder> {
        let fit = self.fit;
        let mut b = DocumentBuilder::new(
            self.procedure,
            format!(
                "{} ({} {}, terms {})",
                self.title,
                fit.diagnostics.n_obs,
                self.observations,
                self.terms.join(", ")
            ),
        );
        b.estimates_dof(self.coefficients, "", self.unit_of, |n| {
            dof_lookup(self.dof, n)
        })?;
        b.fit(FitSummary::of("main", fit, self.residual_unit));
        b.option("terms", serde_json::json!(self.terms));
        Ok(b)
    }
}

/// Welch–Satterthwaite effective degrees of freedom (JCGM 100 eq. G.2b) of
/// `u_c² = Σ u_i²` from components `(u_i, ν_i)`.
pub fn welch_satterthwaite(components: &[(f64, f64)]) -> f64 {
    // One contributing component: its own dof, exactly (no rounding).
    let mut live = components.iter().filter(|(u, _)| *u > 0.0);
    if let (Some(only), None) = (live.next(), live.next()) {
        return only.1;
    }
    let uc2: f64 = components.iter().map(|(u, _)| u * u).sum();
    let den: f64 = components
        .iter()
        .filter(|(u, nu)| *u > 0.0 && nu.is_finite())
        .map(|(u, nu)| u.powi(4) / nu)
        .sum();
    if den > 0.0 {
        uc2 * uc2 / den
    } else {
        f64::INFINITY
    }
}
