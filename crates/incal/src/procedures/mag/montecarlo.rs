//! Synthetic magnetometer sessions for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the session's rows (their number, order, the
//! accelerometer's magnitudes and the gyro) and the field's direction at
//! each row as the fit saw it, `ŷ_i = C (m_i − ĥ) / |C (m_i − ĥ)|` (`C`
//! the fitted map onto the unit sphere), and draws the readings from the
//! fitted ellipsoid:
//!
//! `m_i* = ĥ + C⁻¹ (ŷ_i + ε_i)`,
//!
//! * `ε_i` three components of sample noise on the unit sphere, standard
//!   deviation `s_m` (the magnitude residuals', variance drawn once per
//!   trial from its scaled inverse χ² with the jackknife's `B − 1` degrees
//!   of freedom), correlated in time as the residuals were: a first-order
//!   Gauss–Markov sequence with `ρ = (κ − 1)/(κ + 1)` between fitted rows
//!   (the AR(1) sequence whose variance inflation of the mean `1 + 2 Σ ρ_k`
//!   is `κ`). `κ` is the noise's, not the residuals' `κ_r`: a fit of `p`
//!   unknowns absorbs `p` of the `n/κ` effective samples of correlated
//!   noise, so the residuals keep `κ_r = κ (1 − p κ / n)` of its
//!   low-frequency power, solved for `κ` ([`noise_kappa`]; `n/(n − p)`
//!   for white noise, the usual degrees of freedom).
//!
//! With `--field-ut` and `--u-field-ut`, the reduction scales the
//! soft-iron matrix by the stated field `F`: `S = F C`. The trials' soft-iron
//! elements are multiplied by `F*/F`, `F* ~ N(F, u_F²)` once per trial
//! ([`crate::montecarlo::Factor`]); the raw radius (`field_raw`,
//! `field_ut`) does not depend on it.
//!
//! With the alignment, each row at rest gets the specific-force direction
//! the fitted model gives (`f̂ᵀ R ŷ = −sin Î`: the recorded direction
//! moved within the plane of `f̂` and `R ŷ`, its magnitude kept, so the
//! same rows are at rest) plus direction noise of standard deviation
//! `s_a` per component, correlated as the dot residuals were, with `s_a²
//! = s_d² / cos² Î − s_m²` (the dot residuals' variance `s_d²` less the
//! magnetometer's share, at least 0).

use nalgebra::Vector3;
use rand::rngs::ChaCha8Rng;

use super::fit::{self, V3};
use super::input::Record;
use super::{calibrate, MagOptions};
use crate::error::Result;
use crate::montecarlo::{scaled_variance, Drawn, Factor, Synthesis};
use crate::sim::normal;

/// A first-order Gauss–Markov sequence of 3-vectors, unit variance per
/// component, correlation `rho` between consecutive elements.
struct Ar1 {
    rho: f64,
    state: Option<V3>,
}

impl Ar1 {
    fn new(rho: f64) -> Self {
        Ar1 { rho, state: None }
    }

    fn next(&mut self, rng: &mut ChaCha8Rng) -> V3 {
        let z = Vector3::from_fn(|_, _| normal(rng, 1.0));
        let v = match self.state {
            None => z,
            Some(s) => s * self.rho + z * (1.0 - self.rho * self.rho).sqrt(),
        };
        self.state = Some(v);
        v
    }
}

/// The noise's variance inflation `κ` from the residuals' `κ_r` of a fit
/// of `p` unknowns to `n` rows (module docs): the root of `κ_r = κ (1 − p
/// κ / n)` nearer `κ_r`, at most `n/(2p)` (`2 κ_r`, where the roots
/// meet).
fn noise_kappa(kappa_r: f64, n: usize, p: usize) -> f64 {
    let (n, p) = (n as f64, p as f64);
    if !(kappa_r.is_finite() && kappa_r > 0.0) || n <= 2.0 * p {
        return kappa_r.max(1.0);
    }
    let disc = 1.0 - 4.0 * p * kappa_r / n;
    if disc <= 0.0 {
        return n / (2.0 * p);
    }
    (1.0 - disc.sqrt()) / (2.0 * p / n)
}

/// `ρ` of the AR(1) whose variance inflation of the mean is `kappa`.
fn ar1_rho(kappa: f64) -> f64 {
    if kappa.is_finite() && kappa > 1.0 {
        ((kappa - 1.0) / (kappa + 1.0)).min(0.999)
    } else {
        0.0
    }
}

/// The recipe of synthetic sessions for `rec` calibrated with `o` (module
/// docs).
pub(super) fn synthesis(rec: &Record, o: &MagOptions) -> Result<Synthesis<Record>> {
    let r = calibrate(rec, o)?;
    let x = r.solved.fit.estimates.values().clone();
    let (h, c) = fit::unpack(&x);
    let c_inv = c.try_inverse().unwrap_or_else(fit::M3::identity);
    let (_, _, stride) = r.rows;
    let dirs: Vec<V3> = rec
        .mag
        .iter()
        .map(|m| (c * (V3::from(*m) - h)).normalize())
        .collect();
    let (s_m, k_m) = r.solved.magnitude;
    let dof = r.solved.dof;
    // The rows at rest as the reduction found them (record rows).
    let mut warnings = Vec::new();
    let fitted: Vec<usize> = (0..rec.mag.len()).step_by(stride).collect();
    let rest: Vec<usize> = super::at_rest(rec, &fitted, o, &mut warnings)
        .iter()
        .map(|(i, _)| fitted[*i])
        .collect();
    let aligned = x.len() > fit::UNKNOWNS && !rest.is_empty();
    let (rot, sin_i, s_a, k_d) = match (aligned, r.solved.dot) {
        (true, Some((s_d, k_d))) => {
            let phi = V3::new(x[9], x[10], x[11]);
            let (sin_i, cos_i) = x[12].sin_cos();
            let s_a2 = (s_d / cos_i.abs().max(1e-3)).powi(2) - s_m * s_m;
            (fit::rotation(&phi), sin_i, s_a2.max(0.0).sqrt(), k_d)
        }
        _ => (fit::M3::identity(), 0.0, 0.0, 1.0),
    };
    let (n_fit, n_rest) = (fitted.len(), rest.len());
    let k_m = noise_kappa(k_m, n_fit, fit::UNKNOWNS);
    let k_d = noise_kappa(k_d, n_rest, 4);
    let rho_m = ar1_rho(k_m).powf(1.0 / stride as f64);
    let rho_d = ar1_rho(k_d);
    let u_rel = match o.field_ut {
        Some(f) if o.u_field_ut > 0.0 => o.u_field_ut / f,
        _ => 0.0,
    };
    let drawn = drawn_rows(s_m, dof, rho_m, u_rel, aligned.then_some((s_a, rho_d)));
    let template = rec.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Record> {
        let s = scaled_variance(rng, s_m * s_m, dof).sqrt();
        let mut out = template.clone();
        let mut noise = Ar1::new(rho_m);
        for (m, y) in out.mag.iter_mut().zip(&dirs) {
            *m = (h + c_inv * (y + noise.next(rng) * s)).into();
        }
        if let Some(acc) = out.acc.as_mut().filter(|_| aligned) {
            let s_a = s_a * (s / s_m.max(f64::MIN_POSITIVE));
            let mut noise = Ar1::new(rho_d);
            for &k in &rest {
                let f = V3::from(acc[k]);
                let z = rot * dirs[k];
                let along = f.normalize().dot(&z);
                let t = f.normalize() - z * along;
                let t = if t.norm() > 1e-12 {
                    t.normalize()
                } else {
                    z.cross(&V3::x()).normalize()
                };
                let model = z * (-sin_i) + t * (1.0 - sin_i * sin_i).max(0.0).sqrt();
                let dir = (model + noise.next(rng) * s_a).normalize();
                acc[k] = (dir * f.norm()).into();
            }
        }
        Ok(out)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: None,
        method: Vec::new(),
        factors: if u_rel > 0.0 {
            vec![Factor {
                coefficients: fit::SOFT.iter().map(|n| n.to_string()).collect(),
                u_rel,
            }]
        } else {
            Vec::new()
        },
    })
}

/// The table of what is drawn.
fn drawn_rows(s_m: f64, dof: f64, rho_m: f64, u_rel: f64, acc: Option<(f64, f64)>) -> Vec<Drawn> {
    let mut drawn = vec![Drawn::new(
        "magnetometer noise of each row (three components, on the unit sphere)",
        &format!(
            "Gauss–Markov, ρ = {rho_m:.3} between rows; variance scaled inverse χ² (ν = {dof})"
        ),
        format!("σ = {s_m:.3e} of the field"),
        "the magnitude residuals and their autocorrelation",
    )];
    if u_rel > 0.0 {
        drawn.push(Drawn::new(
            "the local field's true magnitude (one per trial, multiplying the soft-iron elements)",
            "normal",
            format!("u = {:.3e} relative", u_rel),
            "u_field_ut",
        ));
    }
    if let Some((s_a, rho)) = acc {
        drawn.push(Drawn::new(
            "direction of the specific force at each row at rest",
            &format!("Gauss–Markov, ρ = {rho:.3} between rows at rest"),
            format!("σ = {s_a:.3e} rad"),
            "the dot residuals less the magnetometer's share",
        ));
    }
    drawn
}

#[cfg(test)]
mod tests {
    use super::super::sim::MagSimOptions;
    use super::super::{Mag, MagOptions};
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    /// `std / u` of every coefficient over `m` trials of one session.
    fn ratios(s: &MagSimOptions, o: &MagOptions, m: u64) -> Vec<(String, f64)> {
        let rec = s.record().unwrap();
        let doc = Mag::reduce(&rec, o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(m, 3);
        let (section, _) = run::<Mag>(&rec, o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0, "{:?}", section.failed);
        doc.coefficients
            .iter()
            .map(|(n, c)| (n.to_string(), section.coefficients[n].std / c.u))
            .collect()
    }

    /// The Monte Carlo standard deviations against the jackknife's u, with
    /// white noise and with Gauss–Markov noise as large as the white (0.5
    /// s): a u has the sampling error of its `B − 1` degrees of freedom
    /// (about 12 %), and with correlated noise the trials' hard iron
    /// scatters 12–23 % less than the recordings' (docs/src/monte-carlo.md),
    /// so each ratio is held to 0.55–1.6 and their median to 0.8–1.2.
    #[test]
    fn standard_deviations_follow_the_jackknife_u_with_white_and_correlated_noise() {
        for (label, gm) in [("white", 0.0), ("Gauss-Markov", 0.3)] {
            let s = MagSimOptions {
                seed: 11,
                orientations: 24,
                dwell_s: 1.0,
                move_s: 0.5,
                rate_hz: 20.0,
                gm_ut: gm,
                gm_tau_s: 0.5,
                ..MagSimOptions::default()
            };
            let o = MagOptions {
                field_ut: Some(s.field_ut),
                u_field_ut: 0.05,
                ..MagOptions::default()
            };
            let r = ratios(&s, &o, 600);
            assert!(r.iter().any(|(n, _)| n == "alignment_z_deg"), "{r:?}");
            let mut v: Vec<f64> = r.iter().map(|x| x.1).collect();
            v.sort_by(f64::total_cmp);
            let median = v[v.len() / 2];
            assert!(
                (0.8..1.2).contains(&median),
                "{label}: median {median}, {r:?}"
            );
            for (n, x) in &r {
                assert!((0.55..1.6).contains(x), "{label}: {n} std/u = {x}");
            }
        }
    }
}
