//! Centrifuge test plans and their predicted uncertainties.
//!
//! A plan (fixture positions × nominal centripetal levels × samples per
//! point, He & Yin 2017 §3) is judged by running the reduction itself on the
//! noise-free outputs of the expected instrument with a deterministic
//! scatter of exactly the output noise σ at every point
//! ([`super::sim::plan`]): every u it reports (coefficients and radius
//! quantities, one joint propagation) is the predicted standard
//! uncertainty of that plan, and shrinks as `1/sqrt(samples)`.

use serde_json::json;

use super::sim::{CentrifugeTruth, RigPlan};
use super::CentrifugeOptions;
use crate::document::plan::PlanDocument;
use crate::document::Procedure;
use crate::error::Result;
use crate::estimation::Noise;
use crate::models::Term;
use crate::options::invalid;

/// Options of a centrifuge plan's prediction: the instrument expected
/// (its K0 and K1 matter most), the rig and plan of [`RigPlan`], `u_k0`,
/// `u_k1` (standard uncertainties of K0 and K1 from the 1 g calibration),
/// `order` (2 or 3), `alignment_tolerance_deg` (fixture angle bound) and
/// `u_omega_ppm` (relative u of the table rate); every key has the
/// command line's default. In the plan document's `options`: all of them
/// but the expected instrument's terms other than `k0` and `k1`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct CentrifugePlanOptions {
    /// The instrument expected (its K0 and K1 matter most).
    #[serde(flatten)]
    pub truth: CentrifugeTruth,
    /// The rig and the plan.
    #[serde(flatten)]
    pub rig: RigPlan,
    /// Standard uncertainty of K0 from the 1 g calibration (g, ≥ 0).
    #[serde(default)]
    pub u_k0: f64,
    /// Standard uncertainty of K1 from the 1 g calibration (output/g, ≥ 0).
    #[serde(default)]
    pub u_k1: f64,
    /// Model order of the radius regression and the station fits (2 or 3).
    #[serde(default = "default_order")]
    pub order: usize,
    /// Bound of the fixture angle error (deg, 0…10), for the type-B Δc2.
    #[serde(default)]
    pub alignment_tolerance_deg: f64,
    /// Relative standard uncertainty of the table rate (ppm, 0…1e5).
    #[serde(default)]
    pub u_omega_ppm: f64,
}

fn default_order() -> usize {
    3
}

/// The expected instrument's terms a plan document does not record (the
/// prediction barely depends on them).
const UNRECORDED_TRUTH: [&str; 10] = [
    "k2",
    "k3",
    "delta_o_arcsec",
    "delta_p_arcsec",
    "k_ip",
    "k_io",
    "k_po",
    "k_pp",
    "k_oo",
    "k_oq",
];

impl CentrifugePlanOptions {
    /// Refuse options no prediction can use: fewer than 2 samples per
    /// point or no noise (the plan needs a scatter), a negative u or
    /// tolerance, `u_k1` not below |K1|, `u_k0` not below 1 g, a tolerance
    /// above 10°, `u_omega_ppm` outside 0…1e5, a model order other than 2
    /// or 3, and the rig checks of [`RigPlan::validate`]; each names its
    /// option.
    pub fn validate(&self) -> Result<()> {
        if self.rig.samples < 2 {
            return invalid(
                "samples",
                format!(
                    "at least 2 per point (the plan needs a scatter), got {}",
                    self.rig.samples
                ),
            );
        }
        crate::options::check_positive("noise", self.rig.noise)?;
        // Bounds on what a 1 g calibration and a fixture can give: a u as
        // large as K1 (or above 1 g for K0) means the quantity is not
        // known, and past 10 deg the small-angle fixture model fails.
        let k1 = self.truth.k1.abs();
        for (name, v, limit, what) in [
            ("u_k0", self.u_k0, 1.0, "below 1 g"),
            ("u_k1", self.u_k1, k1, "smaller than |K1|"),
            (
                "alignment_tolerance_deg",
                self.alignment_tolerance_deg,
                10.0,
                "at most 10 deg",
            ),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return invalid(name, format!("must be a non-negative number, got {v}"));
            }
            let ok = if name == "alignment_tolerance_deg" {
                v <= limit
            } else {
                v < limit
            };
            if !ok {
                return invalid(name, format!("must be {what}, got {v}"));
            }
        }
        super::check_u_omega_ppm(self.u_omega_ppm)?;
        super::check_order(self.order)?;
        self.rig.validate()
    }
}

impl crate::procedures::Plan for super::CentrifugeTest {
    type Options = CentrifugePlanOptions;

    fn plan(o: &CentrifugePlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// Unit of a planned quantity: the tilt in rad, radii in m, coefficients
/// in their term's unit.
fn unit_of(name: &str) -> String {
    match name {
        "tilt_rad" => "rad".into(),
        n if n.ends_with("_m") => "m".into(),
        n => Term::parse(n).map_or("g/g^2".to_string(), |t| t.unit().as_str().to_string()),
    }
}

/// The plan document of a centrifuge plan: the positions, levels and
/// samples, and the predicted u of every coefficient and radius quantity
/// (with the reduction's warnings about the plan).
pub fn plan_document(o: &CentrifugePlanOptions) -> Result<PlanDocument> {
    let truth = o.truth.model()?;
    o.validate()?;
    let cfg = o.rig.simulation(truth, 0)?;
    let t = &cfg.truth;
    let opts = CentrifugeOptions {
        from: None,
        k0: Some(t.k0_g),
        u_k0: Some(o.u_k0),
        k1: Some(t.k1_out_per_g),
        u_k1: Some(o.u_k1),
        cov_k0_k1: Some(0.0),
        radius_m: o.rig.radius_m,
        latitude_deg: o.rig.latitude_deg,
        gravity_m_s2: o.rig.gravity_m_s2,
        opposite_sense: o.rig.opposite_sense,
        order: o.order,
        alignment_tolerance_deg: o.alignment_tolerance_deg,
        noise: Noise::Known { sigma: o.rig.noise },
        terms: None,
        u_omega_ppm: o.u_omega_ppm,
    };
    let r = super::sim::plan(&cfg, &opts)?;
    let mut d = PlanDocument::new(
        Procedure::Centrifuge,
        format!(
            "Centrifuge plan: {} positions x {} levels, {} samples per point, noise {:e} per sample, K1 = {}",
            cfg.positions.len(),
            o.rig.levels_g.len(),
            o.rig.samples,
            o.rig.noise,
            t.k1_out_per_g
        ),
    );
    d.with_options(o)?;
    for k in UNRECORDED_TRUTH {
        d.options.remove(k);
    }
    for (key, value) in [
        ("plan", json!("centrifuge")),
        ("positions", json!(o.rig.positions)),
        ("single_polarity", json!(o.rig.single_polarity)),
        ("levels_g", json!(o.rig.levels_g)),
        ("radius_m", json!(o.rig.radius_m)),
        ("samples", json!(o.rig.samples)),
        ("noise", json!(o.rig.noise)),
        ("k0", json!(t.k0_g)),
        ("k1", json!(t.k1_out_per_g)),
        ("u_k0", json!(o.u_k0)),
        ("u_k1", json!(o.u_k1)),
        ("order", json!(o.order)),
        ("u_omega_ppm", json!(o.u_omega_ppm)),
        ("latitude_deg", json!(o.rig.latitude_deg)),
        ("warnings", json!(r.warnings)),
    ] {
        d.set(key, value)?;
    }
    let mut seen: Vec<&str> = Vec::new();
    for e in [&r.coefficients, &r.joint] {
        for (k, n) in e.names().iter().enumerate() {
            if seen.contains(&n.as_str()) {
                continue;
            }
            seen.push(n);
            d.predict(n, e.u_at(k), &unit_of(n))?;
        }
    }
    Ok(d)
}

/// The run sheet of a centrifuge plan: each position, polarity and level
/// in turn, with the table speed `ω = √(a/R)` for the nominal level
/// (`position`, `polarity`, `level_g`, `speed_rpm`).
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, texts, values};
    use serde_json::Value;
    let radius = d.plan.get("radius_m").and_then(Value::as_f64);
    let g = d
        .options
        .get("gravity_m_s2")
        .and_then(Value::as_f64)
        .unwrap_or(crate::units::STANDARD_GRAVITY_M_S2);
    let levels = values(&d.plan, "levels_g");
    let polarities: &[&str] = if d.plan.get("single_polarity") == Some(&Value::Bool(true)) {
        &["+"]
    } else {
        &["+", "-"]
    };
    let mut rows = Vec::new();
    for p in texts(&d.plan, "positions") {
        for pol in polarities {
            for &l in &levels {
                let rpm = radius.filter(|r| *r > 0.0).map_or(String::new(), |r| {
                    let w = (l * g / r).sqrt();
                    format!("{:.3}", w * 60.0 / (2.0 * std::f64::consts::PI))
                });
                rows.push(vec![p.clone(), pol.to_string(), num(l), rpm]);
            }
        }
    }
    (vec!["position", "polarity", "level_g", "speed_rpm"], rows)
}
