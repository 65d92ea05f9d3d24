//! The radius quantities of the joint propagation (step 6 of the module
//! docs of [`super`]; formulas: `CentrifugeResult::joint`): their inputs
//! (K0, the at-rest mean E0, the static-speed means E_a± and speeds, each
//! polarity's regression parameters) pushed after K1 into the joint input
//! vector, and the map from that vector to `R±` (eq. 7), the static `R±`
//! (eq. 5–6 with the nonlinearity removed), `R_centre_m`, `ecm_offset_m`
//! and the tilt λ (eq. 4) (He & Yin 2017 §2.1–2.2).

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::estimation::{Noise, PositionStats};

use super::budget::{self, UncertaintyType};
use super::estimate::Inputs;
use super::options::CentrifugeOptions;
use super::radius::{self, radius_from_scale, RadiusFit};

/// What the IA-radial station gives the joint propagation for the radius
/// quantities (raw output statistics, regression fits).
pub(super) struct RadiusInputs<'a> {
    /// At-rest output (E0), both polarities.
    pub(super) e0: Option<PositionStats>,
    /// Per polarity (+, −): output at the static speed (E_a) and that speed.
    pub(super) static_point: [Option<(PositionStats, f64)>; 2],
    /// Per polarity: the regression–iteration fit.
    pub(super) regression: [Option<&'a RadiusFit>; 2],
}

/// Where one polarity's regression inputs sit in the joint input vector.
struct RegressionAt {
    /// Index of `scale`.
    scale: usize,
    /// Fitted scale ŝ and last iterate r (m).
    scale_hat: f64,
    r_m: f64,
    /// Indices of K2, K3 (when the order has them).
    k2: Option<usize>,
    k3: Option<usize>,
}

/// The radius quantities as functions of the joint input vector
/// (formulas: [`CentrifugeResult::joint`](super::CentrifugeResult::joint)).
pub(super) struct RadiusMap {
    k1: usize,
    k1_used: f64,
    /// Indices of K0 and E0 (with at-rest rows).
    k0_e0: Option<(usize, usize)>,
    g_local_m_s2: f64,
    /// Per polarity (+, −): regression inputs.
    regression: [Option<RegressionAt>; 2],
    /// Per polarity: indices of E_a and of the static speed ω (rad/s).
    static_point: [Option<(usize, usize)>; 2],
    /// Latitude (rad) and sense of the table, for the rate² of ω.
    latitude_rad: f64,
    opposite_sense: bool,
}

impl RadiusMap {
    /// Named outputs at `x`, in the order of [`CentrifugeResult::joint`](super::CentrifugeResult::joint).
    pub(super) fn eval(&self, x: &DVector<f64>) -> Vec<(&'static str, f64)> {
        let k1 = x[self.k1];
        let ratio = k1 / self.k1_used;
        let reg = [0, 1].map(|k| {
            self.regression[k]
                .as_ref()
                .map(|r| radius_from_scale(r.r_m, r.scale_hat, x[r.scale], self.k1_used, k1))
        });
        let mut out = Vec::with_capacity(7);
        if let Some(v) = reg[0] {
            out.push(("R_plus_m", v));
        }
        if let Some(v) = reg[1] {
            out.push(("R_minus_m", v));
        }
        for (k, name, sign) in [(0, "R_plus_static_m", 1.0), (1, "R_minus_static_m", -1.0)] {
            let (Some((k0, e0)), Some((ea, jw))) = (self.k0_e0, self.static_point[k]) else {
                continue;
            };
            let rate2 = crate::rigs::centrifuge::centripetal_rate_squared(
                x[jw],
                self.latitude_rad,
                self.opposite_sense,
            );
            let g = self.g_local_m_s2;
            let r6 = radius::eq6_radius(x[k0], k1, x[ea], x[e0], rate2, sign, g);
            let v = match &self.regression[k] {
                // The regression's K2, K3 are in units of E/K1_used: with
                // K1 they scale as K1/K1_used and (K1/K1_used)².
                Some(r) => {
                    let a_g = r6 * rate2 / g;
                    let k2 = r.k2.map_or(0.0, |j| x[j] * ratio);
                    let k3 = r.k3.map_or(0.0, |j| x[j] * ratio * ratio);
                    r6 / radius::static_nonlinearity_factor(k2, k3, a_g, sign)
                }
                None => r6,
            };
            out.push((name, v));
        }
        match reg {
            [Some(p), Some(m)] => {
                let (centre, offset) = budget::ecm_offset(p, m);
                out.push(("R_centre_m", centre));
                out.push(("ecm_offset_m", offset));
            }
            [Some(v), None] | [None, Some(v)] => out.push(("R_centre_m", v)),
            [None, None] => {}
        }
        if let Some((k0, e0)) = self.k0_e0 {
            out.push(("tilt_rad", radius::tilt_at(x[k0], k1, x[e0])));
        }
        out
    }
    pub(super) fn values(&self, x: &DVector<f64>) -> DVector<f64> {
        let v = self.eval(x);
        DVector::from_iterator(v.len(), v.into_iter().map(|(_, y)| y))
    }
}

/// Push the radius inputs after K1 (at `k1_idx`): K0 and E0 (with at-rest
/// rows), then per polarity E_a and the static speed ω (type B,
/// `u_omega_ppm`) and the regression parameters with their covariance
/// block. Returns the radius quantities as functions of the inputs.
pub(super) fn push_radius_inputs(
    inp: &mut Inputs,
    k1_idx: usize,
    radii: &RadiusInputs,
    opts: &CentrifugeOptions,
) -> Result<RadiusMap> {
    let known_sigma = match opts.noise {
        Noise::Known { sigma } => Some(sigma),
        Noise::Auto => None,
    };
    let k0_e0 = radii.e0.map(|e0| {
        let k0 = inp.push_block(
            None,
            UncertaintyType::B,
            vec![("K0".into(), opts.k0_u().value)],
            DMatrix::from_element(1, 1, opts.k0_u().u.powi(2)),
            f64::INFINITY,
        );
        // K0 and K1 from one tumble fit are correlated.
        if opts.cov_k0_k1() != 0.0 {
            inp.cross.push((k0, k1_idx, opts.cov_k0_k1()));
        }
        let e = inp.push_block(
            None,
            UncertaintyType::A,
            vec![("E0".into(), e0.mean)],
            DMatrix::from_element(1, 1, radius::sem(&e0, known_sigma).powi(2)),
            f64::INFINITY,
        );
        (k0, e)
    });
    let mut reg_at: [Option<RegressionAt>; 2] = [None, None];
    let mut static_at: [Option<(usize, usize)>; 2] = [None, None];
    for (k, sign) in [(0usize, "+"), (1, "-")] {
        if let (Some(_), Some((ea, w))) = (k0_e0, radii.static_point[k]) {
            let j = inp.push_block(
                None,
                UncertaintyType::A,
                vec![(format!("E_a({sign})"), ea.mean)],
                DMatrix::from_element(1, 1, radius::sem(&ea, known_sigma).powi(2)),
                f64::INFINITY,
            );
            // The static speed, a type-B input (--u-omega-ppm): the eq. 6
            // radius goes as 1/ω².
            let jw = inp.push_block(
                None,
                UncertaintyType::B,
                vec![(format!("omega_static({sign})"), w)],
                DMatrix::from_element(1, 1, (opts.u_omega_ppm * 1e-6 * w).powi(2)),
                f64::INFINITY,
            );
            static_at[k] = Some((j, jw));
        }
        if let Some(f) = radii.regression[k] {
            reg_at[k] = Some(push_regression(inp, sign, f)?);
        }
    }
    Ok(RadiusMap {
        k1: k1_idx,
        k1_used: opts.k1_u().value,
        k0_e0,
        g_local_m_s2: opts.gravity_m_s2,
        regression: reg_at,
        static_point: static_at,
        latitude_rad: opts.latitude_rad(),
        opposite_sense: opts.opposite_sense,
    })
}

/// Push the parameters of one polarity's (`sign`) regression fit with
/// their covariance block; where they sit.
fn push_regression(inp: &mut Inputs, sign: &str, f: &RadiusFit) -> Result<RegressionAt> {
    let e = &f.fit.estimates;
    let first = inp.push_block(
        None,
        UncertaintyType::A,
        e.names()
            .iter()
            .zip(e.values().iter())
            .map(|(n, v)| (format!("{n}({sign})"), *v))
            .collect(),
        e.covariance().clone(),
        e.dof(),
    );
    let at = |n: &str| e.index(n).map(|j| first + j);
    let scale = at("scale")
        .ok_or_else(|| Error::Unsupported("regression radius fit has no scale term".into()))?;
    Ok(RegressionAt {
        scale,
        scale_hat: inp.values[scale],
        r_m: f.radius_m.value,
        k2: at("K2"),
        k3: at("K3"),
    })
}
