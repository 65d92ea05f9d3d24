//! Tumble test plans and their predicted uncertainties (docs/src/tumble.md;
//! Wu et al. 2015 §2.2 and Table 3).
//!
//! * GJB 1037A 12-point plan: θ = 0°, 30°, …, 330°.
//! * Small-angle 12-point plan with step a (Wu et al. 2015 §2.2):
//!   0, a, 2a, 3a, 4a, 5a, 180°, 360°−5a, …, 360°−a. Largest input `sin 5a`
//!   for a ≤ 18°.
//! * N-point plan: N equally spaced angles.
//!
//! The step for an instrument of range r (g) is the largest whole multiple
//! of the head's step resolution (default 1°) with `sin 5a ≤ r`; an
//! instrument whose range reaches 1 g uses the GJB plan.

use nalgebra::DVector;

use super::{design, to_physical};
use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::models::Term;
use crate::rigs::Mount;

/// Largest small-angle step: `5a` must not pass 90°.
pub const MAX_SMALL_STEP_DEG: f64 = 18.0;

/// Which kind of plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanKind {
    /// GJB 1037A 12-point plan (30° steps).
    Gjb12,
    /// Small-angle 12-point plan with this step (deg).
    SmallAngle {
        /// Step a (deg).
        step_deg: f64,
    },
    /// N equally spaced angles.
    NPoint {
        /// Number of angles.
        n: usize,
    },
}

/// A test plan: its kind and angles.
#[derive(Debug, Clone, PartialEq)]
pub struct TumblePlan {
    /// Kind of plan.
    pub kind: PlanKind,
    /// Step between neighbouring angles (deg).
    pub step_deg: f64,
    /// Head angles (deg), in test order.
    pub angles_deg: Vec<f64>,
}

impl TumblePlan {
    /// The GJB 1037A 12-point plan.
    pub fn gjb12() -> Self {
        Self {
            kind: PlanKind::Gjb12,
            step_deg: 30.0,
            angles_deg: (0..12).map(|k| 30.0 * k as f64).collect(),
        }
    }

    /// Small-angle 12-point plan with step `step_deg` (0 < a ≤ 18°).
    pub fn small_angle(step_deg: f64) -> Result<Self> {
        if !(step_deg > 0.0 && step_deg <= MAX_SMALL_STEP_DEG) {
            return Err(Error::InvalidValue {
                what: format!("small-angle step (deg; 0 < a <= {MAX_SMALL_STEP_DEG})"),
                value: step_deg.to_string(),
            });
        }
        let mut angles: Vec<f64> = (0..6).map(|k| k as f64 * step_deg).collect();
        angles.push(180.0);
        angles.extend((1..6).rev().map(|k| 360.0 - k as f64 * step_deg));
        Ok(Self {
            kind: PlanKind::SmallAngle { step_deg },
            step_deg,
            angles_deg: angles,
        })
    }

    /// `n` equally spaced angles from 0°.
    pub fn n_point(n: usize) -> Result<Self> {
        // Four is the least that separates K0, K1 and a misalignment (the
        // GJB 4-point test, 0/90/180/270); two (0/180) leave K1 unobservable.
        if n < 4 {
            return Err(Error::TooFew {
                what: "angles in an N-point plan (0/180 alone cannot observe K1)".into(),
                needed: 4,
                got: n,
            });
        }
        if n > 3600 {
            return Err(Error::Unsupported(format!(
                "an N-point plan has at most 3600 angles (0.1 deg steps), got {n}"
            )));
        }
        let step = 360.0 / n as f64;
        Ok(Self {
            kind: PlanKind::NPoint { n },
            step_deg: step,
            angles_deg: (0..n).map(|k| k as f64 * step).collect(),
        })
    }

    /// The plan for an instrument of range `range_g` (see module docs).
    pub fn for_range(range_g: f64, resolution_deg: f64) -> Result<Self> {
        if !(range_g.is_finite() && range_g > 0.0) {
            return Err(Error::InvalidValue {
                what: "range (g)".into(),
                value: range_g.to_string(),
            });
        }
        if !(resolution_deg.is_finite()
            && resolution_deg > 0.0
            && resolution_deg <= MAX_SMALL_STEP_DEG)
        {
            return Err(Error::InvalidValue {
                what: format!("step resolution (deg, above 0 and at most {MAX_SMALL_STEP_DEG})"),
                value: resolution_deg.to_string(),
            });
        }
        if range_g >= 1.0 {
            return Ok(Self::gjb12());
        }
        let max_k = (MAX_SMALL_STEP_DEG / resolution_deg + 1e-9).floor() as usize;
        let best = (1..=max_k)
            .rev()
            .map(|k| k as f64 * resolution_deg)
            .find(|a| (5.0 * a).to_radians().sin() <= range_g + 1e-12);
        match best {
            Some(a) => Self::small_angle(a),
            None => Err(Error::Unsupported(format!(
                "range {range_g} g is below sin(5 x {resolution_deg} deg) = {:.4} g: use a finer step resolution",
                (5.0 * resolution_deg).to_radians().sin()
            ))),
        }
    }

    /// Largest input on IA over the plan, `max |sin θ|` (g).
    pub fn max_input_g(&self) -> f64 {
        self.angles_deg
            .iter()
            .map(|a| a.to_radians().sin().abs())
            .fold(0.0, f64::max)
    }

    /// Angles in radians.
    pub fn angles_rad(&self) -> Vec<f64> {
        self.angles_deg.iter().map(|a| a.to_radians()).collect()
    }
}

/// Predicted standard uncertainty of every coefficient before the test
/// (docs/src/plans.md): a nominal instrument (scale factor `k1`, every
/// other coefficient 0) on `mount`, with `noise` the standard deviation of
/// one position's averaged output and `index_error_rad` the standard
/// deviation of the head's angle error, which acts as extra output noise
/// `∂E/∂θ · ε ≈ K1 cos θ · ε` (docs/src/tumble.md).
pub fn predict(
    mount: Mount,
    terms: &[Term],
    angles_rad: &[f64],
    k1: f64,
    noise: f64,
    index_error_rad: f64,
) -> Result<Estimates> {
    if !(k1.is_finite() && k1 != 0.0) {
        return Err(Error::InvalidValue {
            what: "scale factor K1".into(),
            value: k1.to_string(),
        });
    }
    if !(noise.is_finite() && noise > 0.0) {
        return Err(Error::InvalidValue {
            what: "noise (output units)".into(),
            value: noise.to_string(),
        });
    }
    if !(index_error_rad.is_finite() && index_error_rad >= 0.0) {
        return Err(Error::InvalidValue {
            what: "index-angle error".into(),
            value: index_error_rad.to_string(),
        });
    }
    let d = design(mount, terms, angles_rad)?;
    let sigma = DVector::from_iterator(
        angles_rad.len(),
        angles_rad.iter().map(|t| {
            let e = k1 * t.cos() * index_error_rad;
            (noise * noise + e * e).sqrt()
        }),
    );
    let cov = d.predict(&sigma)?;
    let nominal = DVector::from_iterator(
        terms.len(),
        terms.iter().map(|t| if *t == Term::K1 { k1 } else { 0.0 }),
    );
    let linear = Estimates::new(
        cov.names().to_vec(),
        nominal,
        cov.covariance().clone(),
        f64::INFINITY,
    )?;
    to_physical(&linear, terms)
}

impl TumblePlan {
    /// An explicit list of head angles (deg), in test order; each finite.
    pub fn explicit(angles_deg: &[f64]) -> Result<Self> {
        if let Some(x) = angles_deg
            .iter()
            .find(|x| !(x.is_finite() && x.abs() <= 1e4))
        {
            return Err(Error::InvalidValue {
                what: "angles_deg (a finite angle within 1e4 deg)".into(),
                value: x.to_string(),
            });
        }
        Ok(Self {
            kind: PlanKind::NPoint {
                n: angles_deg.len(),
            },
            step_deg: f64::NAN,
            angles_deg: angles_deg.to_vec(),
        })
    }
}

impl PlanKind {
    /// The plan's name in documents: `gjb12`, `small-angle`, `n-point`.
    pub fn name(self) -> &'static str {
        match self {
            PlanKind::Gjb12 => "gjb12",
            PlanKind::SmallAngle { .. } => "small-angle",
            PlanKind::NPoint { .. } => "n-point",
        }
    }
}

/// Which angles a tumble plan visits: the instrument's range, a
/// small-angle step, N equal steps or explicit angles (at most one; the
/// GJB 12-point plan when none is given). Not recorded in the plan
/// document's `options`: the document records the angles themselves.
#[derive(
    Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct TumblePlanChoice {
    /// Instrument range (g): the small-angle plan with the largest step
    /// whose inputs stay within it (GJB plan at 1 g and above).
    #[serde(default, skip_serializing)]
    pub range_g: Option<f64>,
    /// Small-angle 12-point plan with this step (deg, at most 18).
    #[serde(default, skip_serializing)]
    pub step_deg: Option<f64>,
    /// N equally spaced angles (GJB 12-point: 12).
    #[serde(default, skip_serializing)]
    pub points: Option<usize>,
    /// Explicit angles (deg).
    #[serde(default, skip_serializing)]
    pub angles_deg: Option<Vec<f64>>,
    /// Dividing-head step resolution used with `range_g` (deg; default 1).
    #[serde(default, skip_serializing)]
    pub step_resolution_deg: Option<f64>,
}

impl TumblePlanChoice {
    /// The chosen plan (GJB 12-point when nothing is chosen); two choices
    /// at once are refused naming the second.
    pub fn plan(&self) -> Result<TumblePlan> {
        let given: Vec<&str> = [
            ("range_g", self.range_g.is_some()),
            ("step_deg", self.step_deg.is_some()),
            ("points", self.points.is_some()),
            ("angles_deg", self.angles_deg.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(k, _)| *k)
        .collect();
        if given.len() > 1 {
            return crate::options::invalid(
                given[1],
                format!(
                    "cannot be given with {} (one plan choice at a time)",
                    given[0]
                ),
            );
        }
        if let Some(r) = self.range_g {
            TumblePlan::for_range(r, self.step_resolution_deg.unwrap_or(1.0))
        } else if let Some(a) = self.step_deg {
            TumblePlan::small_angle(a)
        } else if let Some(n) = self.points {
            TumblePlan::n_point(n)
        } else if let Some(angles) = &self.angles_deg {
            TumblePlan::explicit(angles)
        } else {
            Ok(TumblePlan::gjb12())
        }
    }
}

/// Options of a tumble plan's prediction. In the plan document's
/// `options`: `mount`, `terms`, `k1` (output/g), `noise` (σ of one output
/// sample, output units), `samples` (per position), `index_error_arcsec`
/// (σ of the head's index error).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct TumblePlanOptions {
    /// Which angles (not recorded: the document lists them).
    #[serde(flatten)]
    pub choice: TumblePlanChoice,
    /// Mount on the head.
    pub mount: Mount,
    /// Terms to predict (default: the mount's default terms).
    #[serde(default, deserialize_with = "super::terms_or_default")]
    #[schemars(with = "Option<Vec<Term>>")]
    pub terms: Vec<Term>,
    /// Nominal scale factor K1 (output/g); with `noise`, needed for a prediction.
    #[serde(default)]
    pub k1: Option<f64>,
    /// σ of one output sample (output units); with `k1`, needed for a prediction.
    #[serde(default)]
    pub noise: Option<f64>,
    /// Samples averaged per position (≥ 1).
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// σ of the head's index-angle error (arcsec, 0…3600).
    #[serde(default)]
    pub index_error_arcsec: f64,
}

fn default_samples() -> usize {
    1
}

impl TumblePlanOptions {
    /// Refuse options no prediction can use.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_positive, check_range, invalid};
        if self.samples == 0 {
            return invalid("samples", "at least 1 per position, got 0");
        }
        check_range(
            "index_error_arcsec",
            self.index_error_arcsec,
            0.0,
            3600.0,
            "arcsec",
        )?;
        match (self.k1, self.noise) {
            (Some(k1), Some(noise)) => {
                if !(k1.is_finite() && k1 != 0.0 && k1.abs() <= 1e12) {
                    return invalid(
                        "k1",
                        format!("must be a finite, non-zero scale factor, got {k1}"),
                    );
                }
                check_positive("noise", noise)
            }
            (None, None) => Ok(()),
            (Some(_), None) => invalid(
                "noise",
                "k1 and noise go together (both are needed for a prediction)",
            ),
            (None, Some(_)) => invalid(
                "k1",
                "k1 and noise go together (both are needed for a prediction)",
            ),
        }
    }

    /// The terms to predict: as given, or the mount's default terms.
    pub fn terms(&self) -> Vec<Term> {
        if self.terms.is_empty() {
            super::default_terms(self.mount)
        } else {
            self.terms.clone()
        }
    }
}

impl crate::procedures::Plan for super::Tumble {
    type Options = TumblePlanOptions;

    fn plan(o: &TumblePlanOptions) -> Result<crate::document::plan::PlanDocument> {
        plan_document(&o.choice.plan()?, o)
    }
}

/// The plan document of a tumble plan: the angles, the largest input, and
/// with `k1` and `noise` the predicted u of every term.
pub fn plan_document(
    plan: &TumblePlan,
    o: &TumblePlanOptions,
) -> Result<crate::document::plan::PlanDocument> {
    use serde_json::json;
    o.validate()?;
    let mut d = crate::document::plan::PlanDocument::new(
        crate::document::Procedure::Tumble,
        format!(
            "Tumble plan: {} ({} positions, largest input {:.3} g), {} mount",
            plan.kind.name(),
            plan.angles_deg.len(),
            plan.max_input_g(),
            o.mount.name()
        ),
    );
    let terms = o.terms();
    d.with_options(&TumblePlanOptions {
        terms: terms.clone(),
        ..o.clone()
    })?;
    d.set("plan", json!(plan.kind.name()))?;
    d.set(
        "step_deg",
        json!(plan.step_deg.is_finite().then_some(plan.step_deg)),
    )?;
    d.set("angles_deg", json!(plan.angles_deg))?;
    d.set("max_input_g", json!(plan.max_input_g()))?;
    d.set("mount", json!(o.mount.name()))?;
    match (o.k1, o.noise) {
        (Some(k1), Some(noise)) => {
            let p = predict(
                o.mount,
                &terms,
                &plan.angles_rad(),
                k1,
                noise / (o.samples as f64).sqrt(),
                crate::units::arcsec_to_rad(o.index_error_arcsec),
            )?;
            for (k, n) in p.names().iter().enumerate() {
                d.predict(n, p.u_at(k), Term::parse(n)?.unit().as_str())?;
            }
            // An index error shows as scatter beyond the samples': the
            // reduction then takes u and dof from the residuals.
            let samples = if o.index_error_arcsec > 0.0 {
                1
            } else {
                o.samples
            };
            d.expect_dof(plan.angles_deg.len(), samples, p.len());
            d.set("k1", json!(k1))?;
            d.set("noise", json!(noise))?;
            d.set("samples", json!(o.samples))?;
            d.set("index_error_arcsec", json!(o.index_error_arcsec))?;
        }
        _ => {
            // No prediction without them, but a plan that cannot separate a
            // term is refused all the same (its design does not depend on
            // the scale of K1 or of the noise).
            predict(o.mount, &terms, &plan.angles_rad(), 1.0, 1.0, 0.0)?;
            d.note("give k1 and noise for the predicted uncertainty of every coefficient");
        }
    }
    Ok(d)
}

/// The run sheet of a tumble plan: the head angles in order (`angle_deg`).
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let rows = values(&d.plan, "angles_deg");
    (
        vec!["angle_deg"],
        rows.into_iter().map(|a| vec![num(a)]).collect(),
    )
}
