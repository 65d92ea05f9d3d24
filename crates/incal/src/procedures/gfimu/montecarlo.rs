//! Synthetic static recordings of a gyro-free unit for the Monte Carlo
//! propagation ([`crate::montecarlo`]).
//!
//! Each trial keeps every sample's specific force (the positions and
//! their sample counts) and draws every accelerometer's output from its
//! fitted model, `E_j = K̂0_j + K̂s_jᵀ f + σ*_j z`, with `σ*_j` the sample
//! noise as the reduction used it ([`crate::montecarlo::fit_noise`]: the
//! known σ, else the positions' pooled scatter with `Σ(n − 1)` degrees of
//! freedom, else the residuals' with `n − 4`; scaled by the lack of fit
//! where the fit failed its test), drawn once per trial and accelerometer
//! as `s² ν / χ²_ν`. The derived scale factor, cross-couplings and
//! misalignment angles (atan2 of small ratios) come through the
//! reduction's nonlinear map.

use std::collections::BTreeMap;

use rand::rngs::ChaCha8Rng;

use super::calibrate::{calibrate, key, CalibrateOptions, StaticSample};
use super::GfimuCalibrateOptions;
use crate::error::Result;
use crate::estimation::PositionStats;
use crate::montecarlo::{fit_noise, scaled_variance, Synthesis};
use crate::sim::normal;

/// The recipe of synthetic static recordings for `samples` reduced with
/// `o` (module docs).
pub(super) fn synthesis(
    samples: &[StaticSample],
    o: &GfimuCalibrateOptions,
) -> Result<Synthesis<Vec<StaticSample>>> {
    let array = o.array.load()?;
    let r = calibrate(
        &array.geometry,
        samples,
        &CalibrateOptions { noise: o.noise },
    )?;
    // Each accelerometer's outputs grouped by position, for its scatter.
    let mut slots: BTreeMap<[i64; 3], usize> = BTreeMap::new();
    for s in samples {
        let next = slots.len();
        slots.entry(key(&s.specific_force_g)).or_insert(next);
    }
    let mut models = Vec::new();
    let mut drawn = Vec::new();
    for (j, acc) in r.accelerometers.iter().enumerate() {
        let mut groups = vec![Vec::new(); slots.len()];
        for s in samples {
            groups[slots[&key(&s.specific_force_g)]].push(s.outputs[j]);
        }
        let stats: Vec<PositionStats> = groups
            .iter()
            .map(|g| PositionStats::of(g))
            .collect::<Result<_>>()?;
        let (s2, dof, mut row) = fit_noise(o.noise.sigma(), &stats, &acc.fit, "position");
        row.input = format!("accelerometer '{}': {}", acc.name, row.input);
        drawn.push(row);
        let v = acc.linear.values();
        models.push(([v[0], v[1], v[2], v[3]], s2, dof));
    }
    let template = samples.to_vec();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Vec<StaticSample>> {
        let sigma: Vec<f64> = models
            .iter()
            .map(|m| scaled_variance(rng, m.1, m.2).sqrt())
            .collect();
        Ok(template
            .iter()
            .map(|s| {
                let f = s.specific_force_g;
                StaticSample {
                    specific_force_g: f,
                    outputs: models
                        .iter()
                        .zip(&sigma)
                        .map(|((c, _, _), sd)| {
                            c[0] + c[1] * f.x + c[2] * f.y + c[3] * f.z + normal(rng, *sd)
                        })
                        .collect(),
                }
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

#[cfg(test)]
mod tests {
    use super::super::GfimuCalibrate;
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::gfimu::sim::{simulate_static, six_positions, GfimuTruth};
    use crate::procedures::{Procedure, Silent};

    /// The six-position test of the built-in array: K0 and Ks are linear
    /// in the outputs, the derived terms nearly so: every Monte Carlo
    /// standard deviation is its u within the sampling error (`u/√(2M)`,
    /// 2.5 % at M = 800; the t of `Σ(n − 1)` = 54 dof adds 1 %).
    #[test]
    fn every_accelerometer_propagates_as_the_gum_says() {
        let o = GfimuCalibrate::example();
        let g = o.array.load().unwrap().geometry;
        let t = GfimuTruth::typical(&g, 1.5);
        let data = simulate_static(&g, &t, &six_positions(), 10, 2e-4, 5).unwrap();
        let doc = GfimuCalibrate::reduce(&data, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(800, 4);
        let (section, _) = run::<GfimuCalibrate>(&data, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0);
        assert_eq!(section.drawn.len(), g.len());
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            assert!((0.88..1.14).contains(&r), "{name}: std/u = {r}");
        }
    }
}
