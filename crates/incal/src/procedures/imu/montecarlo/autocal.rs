//! Synthetic autocalibration records for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the record's stamps and motion and draws fresh sensor
//! noise into it, so the still intervals, their gravity directions and the
//! rotations between them are the recording's:
//! * in every still interval the reduction used (and in its initial
//!   interval) each channel is its interval mean plus white noise, so the
//!   interval's scatter, and with it the detector's variance test, is what
//!   it was;
//! * between them the recorded gyro signal is kept and white noise of the
//!   gyro's own level is added (the accelerometer in motion enters no
//!   fit and is kept).
//!
//! The noise σ of each accelerometer axis is the intervals' pooled scatter
//! (`Σ(n − 1)` degrees of freedom), each gyro axis's the initial
//! interval's; each is drawn once per trial as `s² ν / χ²_ν`. For the
//! means and the motion this is the parametric bootstrap of a linear
//! estimator (the spread of `θ̂*` around `θ̂` is that of `θ̂` around the
//! truth); the recording's own noise in motion stays in the trials' truth.

use rand::rngs::ChaCha8Rng;

use super::super::autocal::{autocal, AutocalSessionOptions, Method};
use super::super::input::AutocalInput;
use crate::error::Result;
use crate::estimation::{pooled_variance, PositionStats};
use crate::montecarlo::{scaled_variance, Drawn, Synthesis};
use crate::sim::normal;

/// Pooled variance of each of three channels over sample ranges of
/// `data` ([`crate::estimation::pooled_variance`]): `(s² per axis (0
/// without a degree of freedom), Σ(n − 1))`.
fn pooled(data: &[[f64; 3]], ranges: &[(usize, usize)]) -> Result<([f64; 3], f64)> {
    let (mut s2, mut dof) = ([0.0; 3], 0.0);
    for (k, v) in s2.iter_mut().enumerate() {
        let stats = ranges
            .iter()
            .map(|&(a, b)| {
                let axis: Vec<f64> = data[a..=b].iter().map(|x| x[k]).collect();
                PositionStats::of(&axis)
            })
            .collect::<Result<Vec<_>>>()?;
        let (s, d) = pooled_variance(&stats);
        *v = s.max(0.0);
        dof = d as f64;
    }
    Ok((s2, dof))
}

/// Each channel of `data` over `a..=b` replaced by its mean plus noise
/// `sd` per axis.
fn redraw(data: &mut [[f64; 3]], (a, b): (usize, usize), sd: &[f64; 3], rng: &mut ChaCha8Rng) {
    let n = (b + 1 - a) as f64;
    let mut m = [0.0; 3];
    for x in &data[a..=b] {
        for k in 0..3 {
            m[k] += x[k] / n;
        }
    }
    for x in &mut data[a..=b] {
        for k in 0..3 {
            x[k] = m[k] + normal(rng, sd[k]);
        }
    }
}

/// The recipe of synthetic autocalibration records for `input` reduced
/// with `o` (module docs).
pub(in crate::procedures::imu) fn autocal_synthesis(
    input: &AutocalInput,
    o: &AutocalSessionOptions,
) -> Result<Synthesis<AutocalInput>> {
    let time = match (o.method, &input.stamps) {
        (Method::Tedaldi, Some(stamps)) => stamps,
        _ => &input.time,
    };
    let r = autocal(time, &input.acc, input.gyr.as_deref(), &o.model())?;
    let mut still: Vec<(usize, usize)> = r
        .intervals
        .iter()
        .map(|i| (i.interval.start, i.interval.end))
        .collect();
    let init = (r.init.start, r.init.end);
    // The initial interval may overlap the first still one: one range
    // each, so no sample is redrawn twice.
    still.push(init);
    still.sort_unstable();
    let mut merged: Vec<(usize, usize)> = Vec::with_capacity(still.len());
    for (a, b) in still {
        match merged.last_mut() {
            Some(last) if a <= last.1 + 1 => last.1 = last.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    let still = merged;
    let (acc_s2, acc_dof) = pooled(&input.acc, &still)?;
    let gyr = match &input.gyr {
        Some(g) => Some(pooled(g, &[init])?),
        None => None,
    };
    let mut drawn = vec![Drawn::new(
        "accelerometer noise of each sample in a still interval (around its mean)",
        &format!("normal, variance scaled inverse χ² (ν = {acc_dof})"),
        format!(
            "σ = {:.3e}, {:.3e}, {:.3e} output",
            acc_s2[0].sqrt(),
            acc_s2[1].sqrt(),
            acc_s2[2].sqrt()
        ),
        "the still intervals' pooled scatter",
    )];
    if let Some((s2, dof)) = gyr {
        drawn.push(Drawn::new(
            "gyro noise of each sample (around the interval means; added to the motion)",
            &format!("normal, variance scaled inverse χ² (ν = {dof})"),
            format!(
                "σ = {:.3e}, {:.3e}, {:.3e} output",
                s2[0].sqrt(),
                s2[1].sqrt(),
                s2[2].sqrt()
            ),
            "the initial still interval's scatter",
        ));
    }
    let mut moving = vec![true; input.acc.len()];
    for &(a, b) in &still {
        moving[a..=b].iter_mut().for_each(|m| *m = false);
    }
    let template = input.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<AutocalInput> {
        let mut x = template.clone();
        let sd = acc_s2.map(|s2| scaled_variance(rng, s2, acc_dof).sqrt());
        for &range in &still {
            redraw(&mut x.acc, range, &sd, rng);
        }
        if let (Some(g), Some((s2, dof))) = (x.gyr.as_mut(), gyr) {
            let sd = s2.map(|s2| scaled_variance(rng, s2, dof).sqrt());
            // The stills: their means plus one draw of the noise; the
            // motion: the recording plus one draw.
            for &range in &still {
                redraw(g, range, &sd, rng);
            }
            for (v, _) in g.iter_mut().zip(&moving).filter(|(_, m)| **m) {
                for k in 0..3 {
                    v[k] += normal(rng, sd[k]);
                }
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

#[cfg(test)]
mod tests {
    use super::super::super::autocal::{Autocal, AutocalSessionOptions, Method};
    use super::super::super::input::AutocalInput;
    use super::super::super::sim::{simulate, ImuSim, ImuTruth, Sequence};
    use super::super::super::M3;
    use crate::montecarlo::{run, MonteCarloOptions};
    use crate::procedures::{Procedure, Silent};

    /// A random-orientation session without g-sensitivity (outside the
    /// autocalibration model), and the options it is reduced with.
    fn session(seed: u64) -> (AutocalInput, AutocalSessionOptions) {
        let mut truth = ImuTruth::random_around_mems(seed);
        truth.gyr_k_ga = M3::zeros();
        let s = simulate(&ImuSim {
            truth,
            sequence: Sequence::Random {
                positions: 24,
                init_s: 10.0,
                move_s: 1.5,
            },
            rate_hz: 100.0,
            static_s: 2.5,
            gravity: 9.81,
            noise_acc: 3.0,
            noise_gyr: 2.0,
            latitude_deg: None,
            seed,
        })
        .unwrap();
        let x = AutocalInput {
            time: s.iter().map(|x| x.time_s).collect(),
            stamps: None,
            timebase: None,
            acc: s.iter().map(|x| [x.acc[0], x.acc[1], x.acc[2]]).collect(),
            gyr: Some(s.iter().map(|x| [x.gyr[0], x.gyr[1], x.gyr[2]]).collect()),
            sorted: 0,
            rate_hz: 100.0,
        };
        let o = AutocalSessionOptions {
            rate_hz: Some(100.0),
            method: Method::Incal,
            init_static_s: 10.0,
            ..Autocal::example()
        };
        (x, o)
    }

    /// One synthetic record keeps the still intervals and reduces to
    /// coefficients within a few u of the recording's.
    #[test]
    fn a_synthetic_record_keeps_the_stills_and_the_coefficients() {
        let (x, o) = session(3);
        let doc = Autocal::reduce(&x, &o, &Silent).unwrap();
        let s = super::autocal_synthesis(&x, &o).unwrap();
        let y = (s.draw)(&mut crate::sim::rng(1)).unwrap();
        assert_eq!(y.acc.len(), x.acc.len());
        let again = Autocal::reduce(&y, &o, &Silent).unwrap();
        for (name, c) in doc.coefficients.iter() {
            let d = (again.coefficients.get(name).unwrap().value - c.value) / c.u;
            assert!(d.abs() < 6.0, "{name}: moved {d} u");
        }
    }

    /// Statistical tier: 200 trials spread as the fit's u says (the
    /// recording's noise in motion kept in the truth; within 30 %).
    #[test]
    fn the_trials_spread_as_the_fit_says() {
        if !crate::sim::tier::full() {
            return;
        }
        let (x, o) = session(4);
        let doc = Autocal::reduce(&x, &o, &Silent).unwrap();
        let mc = MonteCarloOptions::fixed(200, 2);
        let (section, _) = run::<Autocal>(&x, &o, &doc, &mc, &Silent).unwrap();
        assert!(section.failed.count <= 2, "{:?}", section.failed);
        let mut bad = Vec::new();
        for (name, c) in doc.coefficients.iter() {
            let r = section.coefficients[name].std / c.u;
            eprintln!("{name}: std/u = {r:.3}");
            if !(0.7..1.3).contains(&r) {
                bad.push(format!("{name}: {r:.3}"));
            }
        }
        assert!(bad.is_empty(), "{}", bad.join("; "));
    }
}
