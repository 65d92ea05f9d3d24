//! Synthetic sessions of an environmental-sensitivity test for the Monte
//! Carlo propagation ([`crate::montecarlo`]).
//!
//! The reduction's uncertainty starts from the run means' joint
//! covariance `Σ` that its noise model (white, flicker and random walk
//! from the runs' pooled Allan variance) gives: a run's own noise at its
//! length, and the drift between runs far apart. Each trial keeps every
//! run (its times, stimulus, applied input and samples' scatter about
//! their mean) and moves each output column's run means onto the fitted
//! model plus one correlated draw,
//!
//! `s_rk* = s_rk − ȳ_r + ŷ_r + δ_r`, `δ ~ N(0, Σ*)`,
//!
//! `ŷ` the fitted run means of the terms the order rule chose and `Σ*`
//! the covariance of a noise model drawn once per trial: each of its
//! levels `θ_k` (white, flicker, walk) as `θ_k ν_k / χ²_{ν_k}` with `ν_k =
//! 2θ_k² / C_kk` from the Allan fit's covariance `C` (the information the
//! reduction's Welch–Satterthwaite degrees of freedom come from: each
//! coefficient's t then follows from the mix of levels its u holds,
//! where the document states the least over the coefficients). Where the
//! fit failed its lack-of-fit test, `Σ` is the reduction's scaled by its
//! `χ²/(n − p)`, drawn as `Σ ν / χ²_ν` with `ν = n − p`, as the GUM's u
//! is. The samples' scatter within each run, and so the noise
//! model each trial estimates again, is the recording's. Each trial runs
//! the reduction with the terms the order rule chose for the recording
//! (as the GUM's u is conditional on them; the fast path
//! [`crate::montecarlo::Synthesis::values`], checked against the
//! document of the same terms).

use nalgebra::DMatrix;
use rand::rngs::ChaCha8Rng;

use super::input::Record;
use super::noise::NoiseModel;
use super::{reduce, reduce_terms, SensitivityOptions};
use crate::error::Result;
use crate::estimation::linear::VarianceSource;
use crate::montecarlo::{correlated, factor, scaled_variance, Drawn, Synthesis};

/// One column's recipe: the shift of each run's mean onto the model and
/// how its covariance is drawn.
struct Column {
    shift: Vec<f64>,
    draw: Covariance,
}

/// How a column's run means' covariance is drawn (module docs).
enum Covariance {
    /// The noise model's levels, each with its degrees of freedom.
    Levels(NoiseModel, [f64; 3]),
    /// The lack-of-fit-scaled covariance's factor, with `n − p`.
    Scaled(DMatrix<f64>, f64),
}

/// Each noise level's degrees of freedom, `2θ²/Var θ` (infinite for a
/// level the fit left at 0 or whose variance is 0).
fn level_dof(nm: &NoiseModel) -> [f64; 3] {
    let c = nm.terms_covariance();
    let theta = [nm.white, nm.flicker, nm.walk];
    std::array::from_fn(|k| {
        if theta[k] > 0.0 && c[(k, k)] > 0.0 {
            2.0 * theta[k] * theta[k] / c[(k, k)]
        } else {
            f64::INFINITY
        }
    })
}

/// The recipe of synthetic sessions for `rec` reduced with `o` (module
/// docs).
pub(super) fn synthesis(rec: &Record, o: &SensitivityOptions) -> Result<Synthesis<Record>> {
    let r = reduce(rec, o)?;
    let mut columns = Vec::new();
    let mut drawn = Vec::new();
    for c in &r.columns {
        let scaled = c.fit.fit.variance_source == VarianceSource::Residuals
            && c.fit.fit.variance_factor > 1.0
            && c.fit.fit.variance_factor.is_finite()
            && c.fit.fit.dof > 0;
        let (k, dof) = if scaled {
            (c.fit.fit.variance_factor, c.fit.fit.dof as f64)
        } else {
            (1.0, c.noise.dof)
        };
        drawn.push(Drawn::new(
            &format!("run means of {} (jointly)", c.column),
            &if scaled {
                format!("multivariate normal, covariance scaled inverse χ² (ν = {dof})")
            } else {
                let d = level_dof(&c.noise).map(|v| format!("{v:.1}"));
                format!("multivariate normal, covariance of the noise levels each scaled inverse χ² (ν = {}, {}, {})", d[0], d[1], d[2])
            },
            format!(
                "white {:.3e}, flicker {:.3e}, walk {:.3e}{}",
                c.noise.white,
                c.noise.flicker,
                c.noise.walk,
                if scaled {
                    format!(", scaled by the fit's lack of fit {k:.3}")
                } else {
                    String::new()
                }
            ),
            "the noise model of the runs' pooled Allan variance",
        ));
        columns.push(Column {
            shift: c
                .fit
                .fitted
                .iter()
                .zip(&c.fit.y)
                .map(|(m, y)| m - y)
                .collect(),
            draw: if scaled {
                Covariance::Scaled(factor(&(&c.covariance * k)), dof)
            } else {
                Covariance::Levels(c.noise.clone(), level_dof(&c.noise))
            },
        });
    }
    let terms: Vec<Vec<String>> = r
        .columns
        .iter()
        .map(|c| c.fit.terms.iter().map(|t| t.name.clone()).collect())
        .collect();
    let fixed = o.clone();
    let values = move |x: &Record| -> Result<Vec<(String, f64)>> {
        let r = reduce_terms(x, &fixed, Some(&terms))?;
        Ok(r.columns
            .iter()
            .flat_map(|c| {
                let e = &c.coefficients;
                e.names()
                    .to_vec()
                    .into_iter()
                    .zip(e.values().iter().copied())
            })
            .collect())
    };
    let spans = super::spans(rec);
    let template = rec.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Record> {
        let mut x = template.clone();
        for (j, c) in columns.iter().enumerate() {
            let d = match &c.draw {
                Covariance::Scaled(l, dof) => {
                    correlated(rng, l) * scaled_variance(rng, 1.0, *dof).sqrt()
                }
                Covariance::Levels(nm, dof) => {
                    let mut m = nm.clone();
                    m.white = scaled_variance(rng, m.white, dof[0]);
                    m.flicker = scaled_variance(rng, m.flicker, dof[1]);
                    m.walk = scaled_variance(rng, m.walk, dof[2]);
                    correlated(rng, &factor(&m.run_covariance(&spans)?))
                }
            };
            for ((run, shift), dr) in x.runs.iter_mut().zip(&c.shift).zip(d.iter()) {
                let by = shift + dr;
                run.samples[j].iter_mut().for_each(|s| *s += by);
            }
        }
        Ok(x)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: Some(Box::new(values)),
        method: Vec::new(),
        factors: Vec::new(),
    })
}

#[cfg(test)]
mod tests {
    use super::super::sim::SensitivitySimOptions;
    use super::super::Sensitivity;
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    /// A vibration session under flicker (the run means correlated): the
    /// coefficients are linear in the run means given the noise model, so
    /// each Monte Carlo 95 % interval is near the GUM's `y ± k95 u`, the t
    /// of the least Welch–Satterthwaite dof over the terms (9.1 here):
    /// measured 0.96–1.16 of U95 at M = 1000, the widest the
    /// vibropendulous term, whose u is mostly the poorly known flicker
    /// (its trials re-choose the noise model); a covariance not drawn
    /// gives 0, levels not drawn with their dof 0.79–0.96.
    #[test]
    fn run_means_drawn_with_their_covariance_give_the_u() {
        let s = SensitivitySimOptions {
            seed: 3,
            angles_deg: "0,45,-45".into(),
            run_s: 20.0,
            rate_hz: 50.0,
            flicker: Some(3.0),
            ..SensitivitySimOptions::default()
        };
        let rec = s.record().unwrap();
        let o = s.reduction();
        let doc = Sensitivity::reduce(&rec, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(1000, 8);
        let (section, _) = run::<Sensitivity>(&rec, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0, "{:?}", section.failed);
        for (name, c) in doc.coefficients.iter() {
            let [lo, hi] = section.coefficients[name].symmetric;
            let r = 0.5 * (hi - lo) / c.u95;
            assert!((0.85..1.25).contains(&r), "{name}: half-width/U95 = {r}");
        }
        // The fast path: the document's values of the same terms (the
        // recording's, whose order rule chose them).
        let syn = Sensitivity::synthesis(&rec, &o, &doc).unwrap().unwrap();
        for (name, v) in (syn.values.as_ref().unwrap())(&rec).unwrap() {
            assert_eq!(doc.coefficients.get(&name).unwrap().value, v, "{name}");
        }
    }
}
