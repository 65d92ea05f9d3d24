//! Synthetic chamber ramps for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's blocks (their times, sensor and
//! chamber temperatures, sample counts: the branches, the `dT/dt` and
//! the hysteresis regressor are the recording's) and draws every
//! channel's block statistics from its fitted polynomial (with the
//! hysteresis and `dT/dt` terms fitted): the block mean `ŷ_i + σ* z /
//! √n_i` and the block's sum of squared deviations `σ_w² χ²_{n_i − 1}`,
//! how the mean and scatter of `n_i` white samples are distributed.
//! `σ_w²` is the within-block variance pooled over the blocks (its
//! `Σ(n_i − 1)` degrees of freedom), `σ*²` the same drawn once per trial
//! from its scaled inverse χ², and where the fit failed its lack-of-fit
//! test (block means scattering more than their white-noise u: bias
//! instability) the means' variance is scaled by the fit's `χ²/(n − p)`
//! with `n − p` degrees of freedom ([`crate::montecarlo::with_lack_of_fit`]),
//! as the GUM's u is, while the within-block scatter keeps `σ_w²`.
//!
//! Each trial is fitted with the degree the reduction chose for the
//! channel (the coefficients `NAME.ck` are then the same set): the
//! fast path ([`crate::montecarlo::Synthesis::values`]) fits the
//! polynomials alone, without the document's tables, and a test checks
//! it reports the reduction's values. The lag `τ` is not a coefficient
//! and is not drawn.

use rand::rngs::ChaCha8Rng;

use super::input::RampInput;
use super::ramp::{block_design, both_branches, ChannelBlocks, RampOptions};
use super::Degree;
use crate::error::Result;
use crate::montecarlo::{
    sample_variance, scaled_variance, with_lack_of_fit, Drawn, Synthesis, ValuesFn,
};
use crate::sim::normal;

/// Named regressor columns (the fit's extra terms).
type Columns = Vec<(String, Vec<f64>)>;

/// The blocks' temperatures and the recording's extra regressors
/// (hysteresis, `dT/dt`) as the reduction builds them.
fn extras(input: &RampInput, o: &RampOptions) -> Result<(Vec<f64>, Columns)> {
    let d = block_design(input, o.block_s)?;
    let mut extra = Vec::new();
    if both_branches(&d.temp_c, &d.branch) {
        extra.push((
            "hysteresis".to_string(),
            d.branch.iter().map(|&s| 0.5 * f64::from(s)).collect(),
        ));
    }
    if o.rate_term {
        extra.push(("rate_term".to_string(), d.rate_c_s.clone()));
    }
    Ok((d.temp_c, extra))
}

/// One channel's recipe: the blocks kept, their predictions, the noise.
struct Channel {
    keep: Vec<usize>,
    predicted: Vec<f64>,
    within: f64,
    means: (f64, f64),
}

/// The recipe of synthetic ramps for `input` reduced with `o` (module
/// docs).
pub(super) fn synthesis(input: &RampInput, o: &RampOptions) -> Result<Synthesis<RampInput>> {
    let (temp, extra) = extras(input, o)?;
    let mut channels = Vec::new();
    let mut degrees = Vec::new();
    let mut drawn = Vec::new();
    for (c, name) in input.names.iter().enumerate() {
        let d = ChannelBlocks::of(&input.blocks, c, name, &temp, &extra)?;
        let (f, _) = d.fit(name, o.t_ref_c, o.degree)?;
        let within = d.variance;
        let row = Drawn::new(
            &format!("{name}: noise of each sample"),
            &format!("normal, variance scaled inverse χ² (ν = {})", d.pooled_dof),
            format!("σ = {:.3e}", within.sqrt()),
            "the within-block scatter pooled over the blocks",
        );
        let (s2, dof, row) = with_lack_of_fit((within, d.pooled_dof as f64, row), &f.fit);
        drawn.push(row);
        channels.push(Channel {
            predicted: d
                .y
                .iter()
                .zip(f.fit.residuals.iter())
                .map(|(y, e)| y - e)
                .collect(),
            keep: d.keep,
            within,
            means: (s2, dof),
        });
        degrees.push(f.degree);
    }
    let template = input.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<RampInput> {
        let mut x = template.clone();
        for (c, ch) in channels.iter().enumerate() {
            let s2 = scaled_variance(rng, ch.means.0, ch.means.1);
            let ratio = s2 / ch.means.0.max(f64::MIN_POSITIVE);
            for (&i, &mean) in ch.keep.iter().zip(&ch.predicted) {
                let a = &mut x.blocks[i].channels[c];
                let n = a.n as f64;
                a.mean = mean + normal(rng, (s2 / n).sqrt());
                // The sum of squared deviations: ν times a sample variance.
                let nu = (a.n - 1) as f64;
                a.m2 = nu * sample_variance(rng, ch.within * ratio, nu);
            }
        }
        Ok(x)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: Some(values(o, temp, extra, degrees)),
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// The fast path: every channel's polynomial of the degree the reduction
/// chose, `NAME.ck` as the document names them.
fn values(
    o: &RampOptions,
    temp: Vec<f64>,
    extra: Columns,
    degrees: Vec<usize>,
) -> ValuesFn<RampInput> {
    let t_ref_c = o.t_ref_c;
    Box::new(move |x: &RampInput| {
        let mut out = Vec::new();
        for (c, name) in x.names.iter().enumerate() {
            let d = ChannelBlocks::of(&x.blocks, c, name, &temp, &extra)?;
            let (f, _) = d.fit(name, t_ref_c, Degree::Fixed(degrees[c]))?;
            out.extend((0..=f.degree).map(|k| (format!("{name}.c{k}"), f.values[k])));
        }
        Ok(out)
    })
}

#[cfg(test)]
mod tests {
    use super::super::ramp::{Ramp, RampOptions};
    use super::super::sim::{ChannelTruth, RampSim};
    use super::super::Degree;
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::noise::QuantityKind;
    use crate::procedures::{Procedure, Silent};

    /// A gyro channel on a −10…50…−10 °C ramp with hysteresis and lag.
    fn ramp(seed: u64) -> (super::RampInput, RampOptions) {
        let sim = RampSim {
            channels: vec![ChannelTruth {
                name: "gx".into(),
                c: vec![0.05, 2e-3, -3e-5],
                hysteresis: 0.01,
                noise: 0.02,
            }],
            unit: "deg/s".into(),
            t_ref_c: 25.0,
            waypoints_c: vec![-10.0, 50.0, -10.0],
            ramp_c_per_min: 2.0,
            hold_s: 600.0,
            lag_s: 90.0,
            rate_hz: 1.0,
            temperature_noise_c: 0.01,
            seed,
        };
        let mut csv = Vec::new();
        sim.write(&mut csv).unwrap();
        let o = RampOptions {
            rate_hz: Some(1.0),
            quantity: QuantityKind::Gyro,
            ..RampOptions::default()
        };
        let read = incal_io::ReadOptions::default();
        let mut rows = incal_io::Reader::new("ramp.csv", &csv[..], &read).unwrap();
        (Ramp::read(&mut rows, &o).unwrap(), o)
    }

    /// The polynomial is linear in the block means: each coefficient's
    /// Monte Carlo standard deviation is its u within the sampling error
    /// (`u/√(2M)`: 2.5 % at M = 800, four spreads), and the fast path
    /// reports what the reduction of the same synthetic ramp reports.
    #[test]
    fn polynomial_coefficients_propagate_linearly_and_the_fast_path_agrees() {
        let (input, o) = ramp(3);
        let doc = Ramp::reduce(&input, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(800, 2);
        let (section, _) = run::<Ramp>(&input, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0);
        assert!(doc.coefficients.names().len() >= 2);
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            assert!((0.88..1.12).contains(&r), "{name}: std/u = {r}");
        }
        let degree = doc.coefficients.names().len() - 1;
        let fixed = RampOptions {
            degree: Degree::Fixed(degree),
            ..o.clone()
        };
        let s = Ramp::synthesis(&input, &o, &doc).unwrap().unwrap();
        let fast = s.values.as_ref().unwrap();
        for k in 0..3 {
            let x = (s.draw)(&mut crate::sim::rng(k)).unwrap();
            let full = Ramp::reduce(&x, &fixed, &Silent).unwrap();
            for (name, v) in fast(&x).unwrap() {
                assert_eq!(full.coefficients.get(&name).unwrap().value, v, "{name}");
            }
        }
    }
}
