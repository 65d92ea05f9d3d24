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
        rate_hz: Some(prof.rate_hz),
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

/// The options of a thermal plan (`incal plan thermal`): a soak plan
/// (`plateaus_c` with `u`) or a ramp plan (`ramp_c_per_min` with
/// `noise`); temperatures in °C, times in s, rates in Hz. Every key is
/// in the plan document's `options` (those not given left out).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ThermalPlanOptions {
    /// Plateau temperatures, °C (a soak plan).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plateaus_c: Option<Vec<f64>>,
    /// Standard uncertainty of the coefficient at one plateau, its unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub u: Option<f64>,
    /// The chamber's ramp rate, °C/min (a ramp plan).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ramp_c_per_min: Option<f64>,
    /// Ramp plan: low temperature, °C.
    #[serde(default = "default_t_low_c")]
    pub t_low_c: f64,
    /// Ramp plan: high temperature, °C.
    #[serde(default = "default_t_high_c")]
    pub t_high_c: f64,
    /// Ramp plan: hold at each end, s.
    #[serde(default = "default_hold_s")]
    pub hold_s: f64,
    /// Ramp plan: the sensor's lag behind the chamber, s.
    #[serde(default = "default_lag_s")]
    pub lag_s: f64,
    /// Ramp plan: sample rate, Hz.
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    /// Ramp plan: white noise of one sample, the channel's unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// Ramp plan: block length, s.
    #[serde(default = "default_block_s")]
    pub block_s: f64,
    /// Degree of the polynomial (0 to 3).
    pub degree: usize,
    /// Reference temperature T_ref, °C.
    #[serde(default = "super::ramp::default_t_ref_c")]
    pub t_ref_c: f64,
}

fn default_t_low_c() -> f64 {
    -20.0
}

fn default_t_high_c() -> f64 {
    60.0
}

fn default_hold_s() -> f64 {
    1800.0
}

fn default_lag_s() -> f64 {
    120.0
}

fn default_rate_hz() -> f64 {
    10.0
}

fn default_block_s() -> f64 {
    10.0
}

impl ThermalPlanOptions {
    /// Refuse options no plan can use, naming the key: a degree above
    /// [`MAX_DEGREE`], a `u` or `noise` that is not positive, a
    /// temperature below absolute zero, `t_low_c` not below `t_high_c`,
    /// a ramp rate beyond 100 °C/min, a hold, lag or block beyond a week. The ramp's profile is checked by the simulator
    /// and the reduction it predicts.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, invalid};
        if self.degree > MAX_DEGREE {
            return invalid(
                "degree",
                format!("must be within 0..{MAX_DEGREE}, got {}", self.degree),
            );
        }
        if let Some(u) = self.u {
            check_positive("u", u)?;
        }
        if let Some(noise) = self.noise {
            check_positive("noise", noise)?;
        }
        super::sim::check_profile(&super::sim::Profile {
            plateaus_c: self.plateaus_c.as_deref(),
            t_low_c: self.t_low_c,
            t_high_c: self.t_high_c,
            ramp_c_per_min: self.ramp_c_per_min,
            hold_s: self.hold_s,
            lag_s: self.lag_s,
        })?;
        crate::options::check_range("block_s", self.block_s, 1e-3, 7.0 * 86400.0, "s")?;
        super::ramp::check_t_ref_c(self.t_ref_c)
    }
}

impl crate::procedures::Plan for super::Thermal {
    type Options = ThermalPlanOptions;

    fn plan(o: &ThermalPlanOptions) -> Result<crate::document::plan::PlanDocument> {
        plan_document(o)
    }
}

/// The unit of `c_k`: the channel's unit per °C^k (`unit`, `unit/degC`,
/// `unit/degC^2`, …), the channel being any.
fn coefficient_unit(k: usize) -> String {
    match k {
        0 => "unit".to_string(),
        1 => "unit/degC".to_string(),
        k => format!("unit/degC^{k}"),
    }
}

/// The plan document (`incal.plan/1`) of a soak or a ramp plan: the
/// predicted u of `c0…cd` (and of the hysteresis for a ramp that covers
/// both branches), the residual degrees of freedom and U95. A plan that
/// is neither (no plateaus with their u, no ramp with its noise) is
/// refused saying what to give.
pub fn plan_document(o: &ThermalPlanOptions) -> Result<crate::document::plan::PlanDocument> {
    use serde_json::json;
    o.validate()?;
    let (u, hysteresis, dof, title, kind) = match (o.ramp_c_per_min, &o.plateaus_c, o.u) {
        (Some(rate), _, _) => {
            let noise = o.noise.ok_or_else(|| Error::InvalidOption {
                key: "noise".into(),
                message: "the white noise of one sample is needed for a ramp plan".into(),
            })?;
            let plan = RampPlan {
                profile: super::sim::RampSim {
                    channels: Vec::new(),
                    unit: String::new(),
                    t_ref_c: o.t_ref_c,
                    waypoints_c: vec![o.t_low_c, o.t_high_c, o.t_low_c],
                    ramp_c_per_min: rate,
                    hold_s: o.hold_s,
                    lag_s: o.lag_s,
                    rate_hz: o.rate_hz,
                    temperature_noise_c: 0.0,
                    seed: 0,
                },
                noise,
                block_s: o.block_s,
                degree: o.degree,
            };
            let (u, h, dof) = predict_ramp(&plan)?;
            let title = format!(
                "Thermal ramp plan: {} to {} degC at {} degC/min, holds {} s, lag {} s, {} Hz, noise {noise:e} per sample, blocks of {} s; degree {}, T_ref {} degC",
                o.t_low_c, o.t_high_c, rate, o.hold_s, o.lag_s, o.rate_hz, o.block_s, o.degree, o.t_ref_c
            );
            (u, h, dof, title, "thermal-ramp")
        }
        (None, Some(p), Some(up)) => {
            let (u, dof) = predict(p, up, o.degree, o.t_ref_c)?;
            let title = format!(
                "Thermal plateau plan: {} plateaus, degree {}, T_ref {} degC, u per plateau {up:e}",
                p.len(),
                o.degree,
                o.t_ref_c
            );
            (u, None, dof, title, "thermal-plateaus")
        }
        _ => {
            return Err(Error::InvalidOption {
                key: "plateaus_c".into(),
                message: "give the plateaus with their u, or a ramp (its rate and noise)".into(),
            })
        }
    };
    let mut d =
        crate::document::plan::PlanDocument::new(crate::document::Procedure::Thermal, title);
    d.with_options(o)?;
    d.set("plan", json!(kind))?;
    if let Some(p) = &o.plateaus_c {
        d.set("plateaus_c", json!(p))?;
    }
    d.set("degree", json!(o.degree))?;
    d.set("t_ref_c", json!(o.t_ref_c))?;
    d.set("residual_dof", json!(dof))?;
    for (k, v) in u.iter().enumerate() {
        d.predict(&format!("c{k}"), *v, &coefficient_unit(k))?;
    }
    if let Some(h) = hysteresis {
        d.predict("hysteresis", h, "unit")?;
    }
    d.set_dof(dof as f64);
    Ok(d)
}

/// The run sheet of a thermal plan: the plateau temperatures in order
/// (`plateau_c`), or the ramp's set points (low, high, low) with the
/// rate and holds of a ramp plan.
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let plateaus = values(&d.plan, "plateaus_c");
    if !plateaus.is_empty() {
        return (
            vec!["plateau_c"],
            plateaus.into_iter().map(|t| vec![num(t)]).collect(),
        );
    }
    let opt = |k: &str| d.options.get(k).and_then(serde_json::Value::as_f64);
    match (
        opt("t_low_c"),
        opt("t_high_c"),
        opt("ramp_c_per_min"),
        opt("hold_s"),
    ) {
        (Some(lo), Some(hi), Some(rate), Some(hold)) => (
            vec!["set_point_c", "ramp_c_per_min", "hold_s"],
            [lo, hi, lo]
                .iter()
                .map(|&t| vec![num(t), num(rate), num(hold)])
                .collect(),
        ),
        _ => (vec![], vec![]),
    }
}
