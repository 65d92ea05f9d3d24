//! Synthetic noise records for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the record's channels, length, sample rate, gaps and
//! missing samples (and its temperature column) and draws every
//! channel from the IEEE Std 952 terms its reduction identified:
//! quantization, white, flicker (Kasdin & Walter), random walk and ramp
//! noise of those amplitudes ([`super::sim::rate_record`]), each channel
//! from its own seed, around the channel's mean (rate data) or summed
//! into angle (angle data). A term not identified is absent. The record
//! drawn is the preprocessed one (`outliers`, `fill`, `detrend` applied
//! once, to the recording), and a trial is reduced without them.
//!
//! The terms are the measurands: the trials' truth is the fitted terms,
//! and each trial is fitted with the same set of terms (the choice among
//! sets, [`crate::noise::terms::fit_terms`], is a model selection the
//! trials do not repeat: a trial reports what the recording's document
//! reports, through [`crate::noise::terms::fit_terms_fixed`]). Trials
//! compute OADEV only, beside the spectrum, the Gauss–Markov fit and the
//! temperature bins when the options ask for them; with the set fixed the
//! values are the reduction's (a test checks it on the recording).

use rand::rngs::ChaCha8Rng;
use rand::RngExt;

use super::input::Channels;
use super::sim::{rate_record, NoiseTruth};
use super::{analyse, document, preprocess, temperature, DataKind, NoiseOptions};
use crate::error::Result;
use crate::montecarlo::{Drawn, Synthesis, ValuesFn};
use crate::noise::terms::{fit_terms_fixed, TermFit, TERMS};

/// One channel's model: the terms (internal unit), their set, the mean
/// (input unit).
struct Model {
    truth: NoiseTruth,
    set: Vec<usize>,
    mean: f64,
}

/// The recipe of synthetic noise records for `input` reduced with `o`
/// (module docs).
pub(super) fn synthesis(
    input: &Channels,
    o: &NoiseOptions,
    doc: &crate::document::ResultDocument,
) -> Result<Synthesis<Channels>> {
    let (quantity, unit, factor) = o.units()?;
    let pre = match preprocess::apply(input, &o.preprocess)? {
        Some((c, _, _)) => c,
        None => input.clone(),
    };
    let build = o.build(factor, pre.rate_hz);
    let results = analyse(
        &super::Samples::Columns(&pre.samples),
        &pre.names,
        pre.rows,
        None,
        &pre.gaps,
        build,
        o,
        &crate::procedures::Silent,
    )?;
    let internal = match quantity {
        document::Quantity::Gyro => "deg/s".to_string(),
        document::Quantity::Accel => "g".to_string(),
        document::Quantity::Generic(_) => unit.clone(),
    };
    let mut drawn = Vec::new();
    let mut models = Vec::new();
    for (r, col) in results.iter().zip(&pre.samples) {
        let t = |j: usize| r.fit.terms[j].map_or(0.0, |t| t.value);
        let set: Vec<usize> = (0..5).filter(|&j| r.fit.terms[j].is_some()).collect();
        let kept: Vec<f64> = col.iter().copied().filter(|v| !v.is_nan()).collect();
        let mean = kept.iter().sum::<f64>() / kept.len().max(1) as f64;
        let listed: Vec<String> = set
            .iter()
            .map(|&j| format!("{} = {:.3e}", TERMS[j], t(j)))
            .collect();
        drawn.push(Drawn::new(
            &format!("noise of channel {}", r.name),
            "quantization, white, flicker, random walk and ramp of the fitted amplitudes",
            if listed.is_empty() {
                "no term identified: constant".into()
            } else {
                format!("{} ({internal}-based)", listed.join(", "))
            },
            "the IEEE 952 term fit",
        ));
        models.push(Model {
            truth: NoiseTruth {
                q: t(0),
                n: t(1),
                b: t(2),
                k: t(3),
                r: t(4),
            },
            set,
            mean,
        });
    }
    let tau0 = build.tau0;
    let angle = o.data == DataKind::Angle;
    let template = Channels {
        timebase: None,
        ..pre
    };
    let sets: Vec<Vec<usize>> = models.iter().map(|m| m.set.clone()).collect();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<Channels> {
        let mut x = template.clone();
        for (col, m) in x.samples.iter_mut().zip(&models) {
            let seed: u64 = rng.random();
            let y = rate_record(&m.truth, tau0, col.len(), seed);
            let mut sum = 0.0;
            for (v, r) in col.iter_mut().zip(y) {
                let s = if angle {
                    let a = sum;
                    sum += r * tau0;
                    a / factor
                } else {
                    m.mean + r / factor
                };
                if !v.is_nan() {
                    *v = s;
                }
            }
        }
        Ok(x)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: Some(values(o, sets, doc)?),
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// A trial's coefficients: the reduction without preprocessing, OADEV
/// only, each channel's terms fitted as the set `sets` (module docs).
fn values(
    o: &NoiseOptions,
    sets: Vec<Vec<usize>>,
    doc: &crate::document::ResultDocument,
) -> Result<ValuesFn<Channels>> {
    let (quantity, unit, factor) = o.units()?;
    let to_stability = quantity.units().stability.1;
    let names: Vec<String> = doc.coefficients.names();
    let shown = o.selection()?.shown;
    let o = NoiseOptions {
        deviations: "oadev".into(),
        preprocess: preprocess::PreprocessOptions::default(),
        three_cornered_hat: false,
        ..o.clone()
    };
    Ok(Box::new(move |x: &Channels| {
        let build = o.build(factor, x.rate_hz);
        let mut results = analyse(
            &super::Samples::Columns(&x.samples),
            &x.names,
            x.rows,
            None,
            &x.gaps,
            build,
            &o,
            &crate::procedures::Silent,
        )?;
        let temps = temperature::compute(x, &o, build)?;
        for ((r, t), set) in results.iter_mut().zip(temps).zip(&sets) {
            r.temperature = t;
            let st = &r.stability;
            r.fit = if set.is_empty() {
                TermFit {
                    terms: [None; 5],
                    squares: None,
                    warnings: Vec::new(),
                    chi2: None,
                }
            } else {
                let n_phase = x.rows + usize::from(o.data == DataKind::Rate);
                fit_terms_fixed(&st.taus_s, &st.oadev, &st.alpha, build.tau0, n_phase, set)?
            };
        }
        let doc = document::document(&shown, &results, &quantity, &unit, o.confidence, false)?;
        let mut got: Vec<(String, f64)> = doc
            .coefficients
            .iter()
            .map(|(n, c)| (n.to_string(), c.value))
            .collect();
        // The curve's minimum where the recording's had one inside the
        // grid: a trial whose minimum falls at an end reports that end.
        for r in &results {
            let name = format!("{}.adev_min", r.name);
            if names.contains(&name) && !got.iter().any(|g| g.0 == name) {
                let low = r
                    .stability
                    .oadev
                    .value
                    .iter()
                    .flatten()
                    .copied()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .reduce(f64::min);
                if let Some(v) = low {
                    got.push((name, v * to_stability));
                }
            }
        }
        Ok(got)
    }))
}

#[cfg(test)]
mod tests {
    use super::super::sim::NoiseSim;
    use super::super::{Noise, NoiseOptions, QuantityKind};
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    fn record(seed: u64) -> (super::Channels, NoiseOptions) {
        let sim: NoiseSim = crate::options::from_json(&serde_json::json!({
            "arw_deg_rth": 0.2,
            "bias_instability_deg_h": 4.0,
            "rate_hz": 100.0,
            "duration_s": 2000.0,
            "seed": seed,
        }))
        .unwrap();
        let samples = sim.simulate();
        let x = super::Channels {
            names: vec!["ch1".into()],
            rows: samples[0].len(),
            samples,
            rate_hz: 100.0,
            timebase: None,
            gaps: Vec::new(),
            duplicates: 0,
            sorted: 0,
            temperature_c: None,
        };
        let o = NoiseOptions {
            quantity: QuantityKind::Gyro,
            rate_hz: Some(100.0),
            ..NoiseOptions::default()
        };
        (x, o)
    }

    /// The trials' fast path reports the recording's own coefficients
    /// when given the recording.
    #[test]
    fn the_values_are_the_reduction_s_on_the_recording() {
        let (x, o) = record(4);
        let doc = Noise::reduce(&x, &o, &Silent).unwrap();
        let s = super::synthesis(&x, &o, &doc).unwrap();
        let got = (s.values.unwrap())(&x).unwrap();
        assert_eq!(got.len(), doc.coefficients.len());
        for (n, v) in got {
            assert_eq!(v, doc.coefficients.get(&n).unwrap().value, "{n}");
        }
    }

    /// White and flicker noise: N, B and the bias stabilities spread over
    /// the trials as their u says (the u of an Allan-variance fit with
    /// modelled correlations between τ; within 30 %).
    #[test]
    fn the_term_draws_spread_as_the_fit_says() {
        let (x, o) = record(5);
        let doc = Noise::reduce(&x, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(200, 9);
        let (section, _) = run::<Noise>(&x, &o, &doc, &mc, &Silent).unwrap();
        assert_eq!(section.failed.count, 0, "{:?}", section.failed);
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            eprintln!("{name}: {} ± {}, std/u = {r:.3}", c.value, c.u);
        }
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            assert!((0.7..1.3).contains(&r), "{name}: std/u = {r}");
        }
    }
}
