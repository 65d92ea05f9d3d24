//! The Ferraris calibration's synthetic sessions (the module docs of
//! [`super`]).

use nalgebra::DMatrix;
use rand::rngs::ChaCha8Rng;

use super::super::ferraris::{ferraris, pooled_static_gyro, FerrarisOptions};
use super::super::input::FerrarisSections;
use super::super::{M3, V3};
use crate::error::Result;
use crate::montecarlo::{correlated, factor, Drawn, Synthesis};
use crate::sim::normal;
use crate::timebase::TimeBase;

/// A section's shifts: the factor of the covariance of its shift and,
/// for a rotation, the rate part of each sample's gyro output (the output
/// above the static bias and g-sensitivity) the angle error scales.
struct Section {
    l: DMatrix<f64>,
    /// A rotation's per-sample gyro bias `b_g + K_ga a_cal`: the output
    /// the angle does not scale.
    bias: Option<V3>,
}

/// The recipe of synthetic Ferraris sessions for `input` reduced with `o`
/// (module docs of [`super`]).
pub(in crate::procedures::imu) fn ferraris_synthesis(
    input: &(FerrarisSections, Option<TimeBase>),
    o: &FerrarisOptions,
) -> Result<Synthesis<(FerrarisSections, Option<TimeBase>)>> {
    let opts = o.at_stamps_rate(input.1.as_ref());
    let r = ferraris(&input.0, &opts)?;
    let m = &r.matrices;
    let acc_cal = (m.k_a * m.r_a).try_inverse().unwrap_or_else(M3::zeros);
    let pooled = pooled_static_gyro(&r.sections);
    let sections: Vec<Section> = r
        .sections
        .iter()
        .enumerate()
        .map(|(s, st)| {
            let n = st.n as f64;
            let mut c = DMatrix::<f64>::zeros(6, 6);
            if s < 6 {
                for j in 0..6 {
                    for k in 0..6 {
                        c[(j, k)] = st.cov[j][k] / n;
                    }
                }
                Section {
                    l: factor(&c),
                    bias: None,
                }
            } else {
                for j in 0..3 {
                    for k in 0..3 {
                        c[(j, k)] = st.cov[j][k] / n;
                        // The integral's n S_g, per sample: S_g / n.
                        c[(3 + j, 3 + k)] = pooled[j][k] / n;
                    }
                }
                let a_cal = acc_cal * (st.acc() - m.b_a);
                Section {
                    l: factor(&c),
                    bias: Some(m.b_g + m.k_ga * a_cal),
                }
            }
        })
        .collect();
    let u_rel = (opts.u_rotation_deg / opts.rotation_deg).abs();
    let mut drawn = vec![
        Drawn::new(
            "mean of each static section (six channels jointly)",
            "normal",
            "covariance S/n, the section's own scatter".into(),
            "the recording",
        ),
        Drawn::new(
            "accelerometer mean and gyro integral of each rotation",
            "normal",
            "S_a/n and n·S_g, S_g pooled within the static sections".into(),
            "the recording",
        ),
    ];
    if u_rel > 0.0 {
        drawn.push(Drawn::new(
            "true angle of the rotations (one per trial, as the budget's one A; each rotation's rate part scaled by 1 + ε)",
            "normal",
            format!("u = {} deg", opts.u_rotation_deg),
            "u_rotation_deg",
        ));
    }
    let template = input.clone();
    let draw = move |rng: &mut ChaCha8Rng| -> Result<(FerrarisSections, Option<TimeBase>)> {
        let mut x = template.clone();
        let eps = if u_rel > 0.0 { normal(rng, u_rel) } else { 0.0 };
        for (samples, sec) in x.0.iter_mut().zip(&sections) {
            let d = correlated(rng, &sec.l);
            for v in samples.iter_mut() {
                if let Some(b) = sec.bias {
                    for j in 0..3 {
                        v[3 + j] += eps * (v[3 + j] - b[j]);
                    }
                }
                for (c, dc) in v.iter_mut().zip(d.iter()) {
                    *c += dc;
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
