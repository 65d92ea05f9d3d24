//! Rate-transfer test plans and their predicted uncertainties: the
//! reduction ([`super::calibrate`]) run on noise-free means at a nominal
//! scale factor with a known noise, so the plan and the reduction cannot
//! disagree (IEEE Std 952-1997 §12.3.3 for the test; JCGM 100 for the
//! propagation).

use serde_json::json;

use super::{
    calibrate, coefficient_unit, input_rate_deg_s, GyroRateOptions, InputAxis, RateObservation,
    RateResult, RateTerm, MAX_RATE_DEG_S,
};
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::estimation::Noise;

/// Most samples a plan may average per rate.
pub const MAX_PLAN_SAMPLES: usize = 100_000_000;

/// Predicted standard uncertainty of every coefficient for a plan: the
/// reduction run on noise-free means at the nominal scale factor `k1`
/// with a known noise `noise` per sample and `samples` samples per rate.
/// The result's coefficients hold the predicted u (K1, B, K2, K3 as
/// chosen, and the asymmetry when the rates separate it).
pub fn plan(
    rates_deg_s: &[f64],
    samples: usize,
    noise: f64,
    k1: f64,
    opts: &GyroRateOptions,
) -> Result<RateResult> {
    crate::validity::require_plan_inputs(samples, noise, k1, "nominal K1")?;
    // Noise-free means: each rate gets `samples` identical samples.
    let obs: Vec<RateObservation> = rates_deg_s
        .iter()
        .flat_map(|&r| {
            let e = k1 * input_rate_deg_s(r, opts.latitude_rad(), opts.ia);
            std::iter::repeat_n(
                RateObservation {
                    rate_deg_s: r,
                    output: e,
                    run: None,
                },
                samples,
            )
        })
        .collect();
    let o = GyroRateOptions {
        noise: Noise::Known { sigma: noise },
        ..opts.clone()
    };
    calibrate(&obs, &o)
}

/// Options of a rate-transfer plan. In the plan document's `options`:
/// `ia`, `k1` (nominal, output/(deg/s)), `latitude_deg`, `noise` (σ of one
/// output sample, output units), `rate_uncertainty_ppm`, `rates_deg_s`,
/// `samples` (per rate), `terms` (sorted, K1 added).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RatePlanOptions {
    /// Table rates (deg/s), in test order.
    pub rates_deg_s: Vec<f64>,
    /// Samples averaged per rate (1…[`MAX_PLAN_SAMPLES`]).
    #[serde(default = "one")]
    pub samples: usize,
    /// σ of one output sample (output units, > 0).
    pub noise: f64,
    /// Nominal scale factor K1 (output/(deg/s)).
    pub k1: f64,
    /// Latitude of the rate table (deg, −90…90; default 0).
    #[serde(default)]
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[serde(default = "super::default_ia")]
    pub ia: InputAxis,
    /// Terms (K1 is added when missing; default B and K1).
    #[serde(
        default = "super::default_terms",
        serialize_with = "super::serialize_terms"
    )]
    pub terms: Vec<RateTerm>,
    /// Relative standard uncertainty of the table rate (ppm, ≥ 0).
    #[serde(default)]
    pub rate_uncertainty_ppm: f64,
}

pub(crate) fn one() -> usize {
    1
}

impl RatePlanOptions {
    /// Refuse options no prediction can use: a noise that is not a
    /// positive number, no samples or more than [`MAX_PLAN_SAMPLES`], a
    /// rate that is not finite or beyond 1e5 deg/s, a K1 that is not
    /// finite; then what the reduction refuses ([`GyroRateOptions::validate`]:
    /// a latitude outside ±90°, a rate uncertainty outside 0…1e5 ppm).
    pub fn validate(&self) -> Result<()> {
        check_plan_noise(self.noise, self.samples)?;
        if let Some(r) = self
            .rates_deg_s
            .iter()
            .find(|r| !(r.is_finite() && r.abs() <= MAX_RATE_DEG_S))
        {
            return crate::options::invalid(
                "rates_deg_s",
                format!("a table rate must be finite and within ±1e5 deg/s, got {r}"),
            );
        }
        if !self.k1.is_finite() {
            return crate::options::invalid(
                "k1",
                format!("must be a finite scale factor, got {}", self.k1),
            );
        }
        self.test_options().validate()
    }

    /// The rate-transfer test the plan predicts: its latitude, input axis,
    /// terms and rate uncertainty, with the plan's σ as the known noise of
    /// one output sample.
    pub fn test_options(&self) -> GyroRateOptions {
        GyroRateOptions {
            latitude_deg: self.latitude_deg,
            ia: self.ia,
            terms: self.terms.clone(),
            noise: Noise::Known { sigma: self.noise },
            rate_uncertainty_ppm: self.rate_uncertainty_ppm,
            linearity_ppm: None,
            output_limit: None,
        }
    }
}

impl crate::procedures::Plan for super::GyroRate {
    type Options = RatePlanOptions;

    fn plan(o: &RatePlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The σ of one sample and the samples per position of a plan: a
/// positive number, and 1…[`MAX_PLAN_SAMPLES`].
pub(crate) fn check_plan_noise(noise: f64, samples: usize) -> Result<()> {
    crate::options::check_positive("noise", noise)?;
    if !(1..=MAX_PLAN_SAMPLES).contains(&samples) {
        return crate::options::invalid(
            "samples",
            format!("must be within 1..{MAX_PLAN_SAMPLES} per position, got {samples}"),
        );
    }
    Ok(())
}

/// The plan document of a rate-transfer plan: the rates, samples, noise
/// and K1 as planned (top-level keys `plan`, `rates_deg_s`, `samples`,
/// `noise`, `k1`, `latitude_deg`, `ia`, `rate_uncertainty_ppm`,
/// `warnings`) and the predicted u of K1, B, K2, K3 (those chosen) and of
/// the asymmetry (ppm) when the rates separate it.
pub fn plan_document(o: &RatePlanOptions) -> Result<PlanDocument> {
    o.validate()?;
    let p = plan(&o.rates_deg_s, o.samples, o.noise, o.k1, &o.test_options())?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::GyroRate,
        format!(
            "Gyro rate-transfer plan: {} rates, {} samples each, noise {:e} per sample, K1 = {}",
            o.rates_deg_s.len(),
            o.samples,
            o.noise,
            o.k1
        ),
    );
    d.with_options(o)?;
    d.set("plan", json!("gyro-rate"))?;
    d.set("rates_deg_s", json!(o.rates_deg_s))?;
    d.set("samples", json!(o.samples))?;
    d.set("noise", json!(o.noise))?;
    d.set("k1", json!(o.k1))?;
    d.set("latitude_deg", json!(o.latitude_deg))?;
    d.set("ia", json!(o.ia.name()))?;
    d.set("rate_uncertainty_ppm", json!(o.rate_uncertainty_ppm))?;
    let c = &p.coefficients;
    for (k, n) in c.names().iter().enumerate() {
        // K1_pos and K1_neg follow from K1 and the asymmetry.
        if !n.starts_with("K1_") {
            d.predict(n, c.u_at(k), coefficient_unit(n))?;
        }
    }
    let fitted = c.names().iter().filter(|n| !n.starts_with("K1_")).count();
    d.expect_dof(o.rates_deg_s.len(), o.samples, fitted);
    set_warnings(&mut d, &p.warnings)?;
    Ok(d)
}

/// The warnings of a plan's reduction: the `warnings` key (typed, as in
/// result documents) and one note each for people.
pub(crate) fn set_warnings(d: &mut PlanDocument, warnings: &[crate::Warning]) -> Result<()> {
    d.set("warnings", json!(warnings))?;
    for w in warnings {
        d.note(format!("warning [{}]: {}", w.code, w.message));
    }
    Ok(())
}

/// The run sheet of a rate-transfer plan: the table rates in order
/// (`rate_deg_s`).
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let rows = values(&d.plan, "rates_deg_s");
    (
        vec!["rate_deg_s"],
        rows.into_iter().map(|r| vec![num(r)]).collect(),
    )
}
