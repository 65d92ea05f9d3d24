//! What the IA-radial station (`ip,0`, else `io,0`) measures (step 2 of
//! the module docs of [`super`]; He & Yin 2017 §2.1–2.2): the static tilt
//! λ (eq. 4), the static radius of each polarity (eq. 5–6) with the
//! nonlinearity at the static speed removed ([`correct_static_radius`]),
//! the regression–iteration radii R± (eq. 7) and the table of regression
//! radii by model order and range (He & Yin 2017 Table 2).

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::{Estimates, Noise, PositionStats};
use crate::rigs::centrifuge::Centrifuge;
use crate::warning::{Warning, WarningCode};

use super::options::CentrifugeOptions;
use super::radius::{
    self, regression_radius, static_radius, static_tilt, RadiusContext, RadiusFit, SpeedPoint,
    ValueU,
};
use super::stations::{e_over_k1, Point};

/// One cell of the radius-versus-range table (He & Yin 2017 Table 2).
#[derive(Debug, Clone, PartialEq)]
pub struct RadiusRangeRow {
    /// Model order.
    pub order: usize,
    /// +1 or −1.
    pub polarity: i8,
    /// Largest input of the range (g).
    pub max_input_g: f64,
    /// Radius (m) and u, or why it could not be fitted.
    pub radius: std::result::Result<ValueU, String>,
    /// Lack-of-fit p-value (when the noise is known from the samples).
    pub chi2_p_value: Option<f64>,
}

/// Remove the input-axis nonlinearity from an eq. 5–6 static radius.
///
/// At the static speed the centripetal input is `a_g` (g) and IA sees
/// `a_i = p·a_g` (polarity p); the indicated input
/// `a_i + K2 a_i² + K3 a_i³` makes eq. 6 read `R·(1 + p·K2·a_g + K3·a_g²)`
/// ([`radius::static_nonlinearity_factor`]). Returns
/// `R_eq6 / (1 + p·K2·a_g + K3·a_g²)` (m), with `u` propagated by
/// [`Estimates::map`] from `u(R_eq6)` and the covariance of (K2, K3) in
/// `regression` (the regression–iteration fit of the same polarity; a
/// missing term counts as 0 ± 0), `R_eq6` independent of (K2, K3), `a_g`
/// exact. GUM first order. [`calibrate`](super::calibrate) applies the same correction inside
/// its joint propagation (`CentrifugeResult::joint`), where K1 is shared.
pub fn correct_static_radius(
    r_eq6: ValueU,
    a_g: f64,
    polarity: f64,
    regression: &Estimates,
) -> Result<ValueU> {
    let names: Vec<&str> = ["K2", "K3"]
        .into_iter()
        .filter(|n| regression.index(n).is_some())
        .collect();
    let k = regression.select(&names)?;
    let n = names.len();
    let mut cov = DMatrix::zeros(n + 1, n + 1);
    cov[(0, 0)] = r_eq6.u * r_eq6.u;
    cov.view_mut((1, 1), (n, n)).copy_from(k.covariance());
    let mut values = vec![r_eq6.value];
    values.extend(k.values().iter());
    let mut in_names = vec!["R_eq6".to_string()];
    in_names.extend(names.iter().map(|s| s.to_string()));
    let inputs = Estimates::new(in_names, DVector::from_vec(values), cov, k.dof())?;
    let k2_at = names.iter().position(|n| *n == "K2").map(|j| j + 1);
    let k3_at = names.iter().position(|n| *n == "K3").map(|j| j + 1);
    let factor = move |x: &DVector<f64>| {
        let c = |at: Option<usize>| at.map_or(0.0, |j| x[j]);
        radius::static_nonlinearity_factor(c(k2_at), c(k3_at), a_g, polarity)
    };
    let out = inputs.map(
        vec!["R".into()],
        |x| DVector::from_element(1, x[0] / factor(x)),
        |x| {
            // ∂r/∂R_eq6 = 1/factor, ∂r/∂K2 = −r·p·a_g/factor,
            // ∂r/∂K3 = −r·a_g²/factor.
            let f = factor(x);
            let r = x[0] / f;
            let mut j = DMatrix::zeros(1, n + 1);
            j[(0, 0)] = 1.0 / f;
            if let Some(k) = k2_at {
                j[(0, k)] = -r * polarity * a_g / f;
            }
            if let Some(k) = k3_at {
                j[(0, k)] = -r * a_g * a_g / f;
            }
            j
        },
    )?;
    Ok(ValueU {
        value: out.values()[0],
        u: out.u_at(0),
    })
}

/// What the IA-radial station gives: the tilt and the radii as measured
/// (their u replaced by the joint propagation's in
/// [`super::calibrate`]), and the raw means behind them for that
/// propagation.
#[derive(Debug, Default)]
pub(super) struct RadiusMeasurement {
    /// Static tilt λ (rad), eq. 4; `None` without at-rest rows.
    pub(super) tilt: Option<ValueU>,
    /// Static radius per polarity (+, −), eq. 5–6 (m).
    pub(super) static_radius: [Option<ValueU>; 2],
    /// The same, kept as eq. 5–6 give it, when the polarity has a
    /// regression radius (the joint propagation corrects the other).
    pub(super) static_uncorrected: [Option<ValueU>; 2],
    /// Rate of each static radius (rad/s).
    pub(super) static_rate: [Option<f64>; 2],
    /// Regression–iteration fit per polarity, eq. 7.
    pub(super) regression: [Option<RadiusFit>; 2],
    /// Radius by model order and range (Table 2).
    pub(super) radius_table: Vec<RadiusRangeRow>,
    /// At-rest output E0 (both polarities), for the joint propagation.
    pub(super) e0: Option<PositionStats>,
    /// Output E_a at the static speed, per polarity.
    pub(super) e_a: [Option<PositionStats>; 2],
}

/// Measure tilt and radii at the IA-radial station from its `points`
/// (module docs); `nominal` (the nominal radius, no tilt) picks the static
/// speed nearest 1 g. A regression that fails, or no at-rest rows, earn a
/// warning.
pub(super) fn measure_radius(
    points: &[Point],
    nominal: &Centrifuge,
    opts: &CentrifugeOptions,
    ctx: &RadiusContext,
    noise: Noise,
    warnings: &mut Vec<Warning>,
) -> Result<RadiusMeasurement> {
    let mut m = RadiusMeasurement::default();
    let at_rest: Vec<f64> = points
        .iter()
        .filter(|p| p.omega == 0.0)
        .flat_map(|p| p.samples.iter().copied())
        .collect();
    if at_rest.is_empty() {
        warnings.push(Warning::new(
            WarningCode::RadiusIncomplete,
            "no at-rest rows at the IA-radial station: tilt taken as 0 and no static radius",
        ));
    } else {
        m.tilt = Some(static_tilt(&at_rest, ctx)?);
        m.e0 = Some(PositionStats::of(&at_rest)?);
    }
    let lambda = m.tilt.map_or(0.0, |t| t.value);
    for (slot, pol) in [(0usize, 1i8), (1, -1)] {
        let mine: Vec<&Point> = points
            .iter()
            .filter(|p| p.position.polarity == pol)
            .collect();
        if mine.iter().all(|p| p.omega == 0.0) {
            continue;
        }
        if !at_rest.is_empty() {
            m.measure_static(slot, pol, &mine, &at_rest, nominal, ctx)?;
        }
        let speed_points: Vec<SpeedPoint> = mine
            .iter()
            .map(|p| {
                Ok(SpeedPoint {
                    omega_rad_s: p.omega,
                    stats: e_over_k1(&p.samples, opts.k1_u().value)?,
                })
            })
            .collect::<Result<_>>()?;
        match regression_radius(
            &speed_points,
            f64::from(pol),
            opts.order,
            opts.radius_m,
            lambda,
            ctx,
            noise,
        ) {
            Ok(f) => {
                // Eq. 5–6 ignore the nonlinearity at a_g (~1 g): the
                // joint propagation below divides the eq. 6 radius by
                // 1 ± K2 a_g + K3 a_g² with this polarity's K2, K3
                // (correct_static_radius); the paper's uncorrected
                // value is kept.
                m.static_uncorrected[slot] = m.static_radius[slot];
                for w in f.fit.quality_warnings(
                    "a model order too low for the speed range, a radius that changes with speed, or drift",
                ) {
                    warnings.push(w.prefixed(&format!("radius regression, polarity {pol:+}")));
                }
                m.regression[slot] = Some(f);
            }
            Err(e) => warnings.push(Warning::new(
                WarningCode::PartFailed,
                format!("regression radius, polarity {pol:+}: {e}"),
            )),
        }
        m.radius_table
            .extend(range_table(&speed_points, pol, lambda, opts, ctx, noise));
    }
    Ok(m)
}

impl RadiusMeasurement {
    /// The static radius (eq. 5–6) of polarity `pol` (slot 0 for +, 1 for
    /// −) at the speed of `mine` nearest 1 g with the nominal radius.
    fn measure_static(
        &mut self,
        slot: usize,
        pol: i8,
        mine: &[&Point],
        at_rest: &[f64],
        nominal: &Centrifuge,
        ctx: &RadiusContext,
    ) -> Result<()> {
        // Speed nearest 1 g with the nominal radius.
        let best = mine.iter().filter(|p| p.omega != 0.0).min_by(|a, b| {
            let fa = (nominal.centripetal_g(&a.position, a.omega) - 1.0).abs();
            let fb = (nominal.centripetal_g(&b.position, b.omega) - 1.0).abs();
            fa.total_cmp(&fb)
        });
        if let Some(b) = best {
            self.static_radius[slot] = Some(static_radius(
                &b.samples,
                at_rest,
                b.omega,
                f64::from(pol),
                ctx,
            )?);
            self.static_rate[slot] = Some(b.omega);
            self.e_a[slot] = Some(PositionStats::of(&b.samples)?);
        }
        Ok(())
    }
}

/// Regression radius for orders 1–3 on the data up to ⅓, ⅔ and all of the
/// largest input (He & Yin 2017 Table 2 uses 7, 14 and 25 g).
fn range_table(
    points: &[SpeedPoint],
    pol: i8,
    lambda: f64,
    opts: &CentrifugeOptions,
    ctx: &RadiusContext,
    noise: Noise,
) -> Vec<RadiusRangeRow> {
    let rate = |p: &SpeedPoint| {
        opts.radius_m
            * crate::rigs::centrifuge::centripetal_rate_squared(
                p.omega_rad_s,
                opts.latitude_rad(),
                opts.opposite_sense,
            )
            / opts.gravity_m_s2
    };
    let max = points.iter().map(rate).fold(0.0, f64::max);
    let mut out = Vec::new();
    let mut done: Vec<usize> = Vec::new();
    for frac in [1.0 / 3.0, 2.0 / 3.0, 1.0] {
        let sub: Vec<SpeedPoint> = points
            .iter()
            .filter(|p| rate(p) <= frac * max * (1.0 + 1e-9))
            .cloned()
            .collect();
        if done.contains(&sub.len()) {
            continue;
        }
        done.push(sub.len());
        let top = sub.iter().map(rate).fold(0.0, f64::max);
        for order in 1..=3 {
            let r = regression_radius(
                &sub,
                f64::from(pol),
                order,
                opts.radius_m,
                lambda,
                ctx,
                noise,
            );
            out.push(RadiusRangeRow {
                order,
                polarity: pol,
                max_input_g: top,
                chi2_p_value: r.as_ref().ok().and_then(|f| f.fit.chi2_p_value),
                radius: r.map(|f| f.radius_m).map_err(|e| e.to_string()),
            });
        }
    }
    out
}
