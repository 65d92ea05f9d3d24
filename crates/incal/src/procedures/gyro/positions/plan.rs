//! Multi-position test plans and their predicted uncertainties: the
//! reduction ([`super::calibrate`]) run on noise-free means (zero drift,
//! output `K1·Ω·IA/3600`) with a known noise, so the plan and the
//! reduction cannot disagree (IEEE Std 1431-2004 §10.3.6 for the test;
//! JCGM 100 for the propagation).

use serde_json::json;

use super::{
    calibrate, check_angles_deg, earth_rate_ia_deg_h, Axial, DriftTerm, GyroPositionsOptions,
    PositionObservation, PositionsResult,
};
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::estimation::Noise;
use crate::procedures::gyro::rate::plan::{check_plan_noise, set_warnings};

/// Predicted uncertainties for a plan: the reduction run on noise-free
/// means (zero drift, output `K1·Ω·IA/3600`) with a known noise per sample.
/// `angles_rad × azimuths_rad` are the positions, `samples` per position.
pub fn plan(
    angles_rad: &[f64],
    azimuths_rad: &[f64],
    samples: usize,
    noise: f64,
    k1_nominal: f64,
    opts: &GyroPositionsOptions,
) -> Result<PositionsResult> {
    crate::validity::require_plan_inputs(samples, noise, k1_nominal, "nominal K1")?;
    let mut obs = Vec::new();
    for &z in azimuths_rad {
        for &a in angles_rad {
            let e = k1_nominal * earth_rate_ia_deg_h(a, z, opts.latitude_rad()) / 3600.0;
            for _ in 0..samples {
                obs.push(PositionObservation {
                    angle_rad: a,
                    azimuth_rad: z,
                    output: e,
                });
            }
        }
    }
    let o = GyroPositionsOptions {
        noise: Noise::Known { sigma: noise },
        ..opts.clone()
    };
    calibrate(&obs, &o)
}

/// Options of a multi-position plan. In the plan document's `options`:
/// `angles_deg`, `axial`, `azimuths_deg`, `fit_k1`, `k1` (nominal,
/// output/(deg/s)), `latitude_deg`, `noise` (σ of one output sample,
/// output units), `samples` (per position), `terms` (sorted), `u_k1`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct PositionsPlanOptions {
    /// Head angles (deg); every angle at each azimuth (default 0, 30, …, 330).
    #[serde(default = "super::default_angles_deg")]
    pub angles_deg: Vec<f64>,
    /// Azimuths of the head axis (deg from north towards east; default 0).
    #[serde(default = "north")]
    pub azimuths_deg: Vec<f64>,
    /// Latitude (deg, −90…90).
    pub latitude_deg: f64,
    /// Which gyro axis is along the head axis (default `sa`).
    #[serde(default = "spin_axis")]
    pub axial: Axial,
    /// Drift terms (default: the axial axis' default terms).
    #[serde(default, serialize_with = "super::serialize_terms")]
    #[schemars(with = "Option<Vec<DriftTerm>>")]
    pub terms: Vec<DriftTerm>,
    /// Nominal scale factor K1 (output/(deg/s)).
    pub k1: f64,
    /// Standard uncertainty of K1 (output/(deg/s), ≥ 0; unused with `fit_k1`).
    #[serde(default)]
    pub u_k1: f64,
    /// Predict with K1 fitted from the Earth-rate projection.
    #[serde(default)]
    pub fit_k1: bool,
    /// σ of one output sample (output units, > 0).
    pub noise: f64,
    /// Samples averaged per position.
    #[serde(default = "crate::procedures::gyro::rate::plan::one")]
    pub samples: usize,
}

fn north() -> Vec<f64> {
    vec![0.0]
}

fn spin_axis() -> Axial {
    Axial::Sa
}

impl PositionsPlanOptions {
    /// Refuse options no prediction can use: a noise that is not a
    /// positive number, no samples or too many, no angles or azimuths or
    /// one beyond 1e4 deg, a K1 that is not finite, zero or beyond 1e15, a
    /// u(K1) that is not a non-negative number below |K1| (when K1 is
    /// given), a latitude outside ±90°.
    pub fn validate(&self) -> Result<()> {
        use crate::options::invalid;
        check_plan_noise(self.noise, self.samples)?;
        check_angles_deg("angles_deg", &self.angles_deg)?;
        check_angles_deg("azimuths_deg", &self.azimuths_deg)?;
        if !(self.k1.is_finite() && self.k1 != 0.0 && self.k1.abs() <= incal_io::MAX_ABS_VALUE) {
            return invalid(
                "k1",
                format!(
                    "must be a finite, non-zero scale factor up to 1e15, got {}",
                    crate::error::short_f64(self.k1)
                ),
            );
        }
        if !(self.u_k1.is_finite() && self.u_k1 >= 0.0) {
            return invalid(
                "u_k1",
                format!("must be a non-negative number, got {}", self.u_k1),
            );
        }
        if !self.fit_k1 && self.u_k1 >= self.k1.abs() {
            return invalid(
                "u_k1",
                format!(
                    "{} is not below |k1| = {}: K1 would not be known at all",
                    crate::error::short_f64(self.u_k1),
                    crate::error::short_f64(self.k1.abs())
                ),
            );
        }
        crate::options::check_latitude_deg(self.latitude_deg)
    }

    /// The test the plan predicts: its latitude, axial axis and terms,
    /// with K1 known (its u, infinite dof) or fitted.
    pub fn test_options(&self) -> GyroPositionsOptions {
        GyroPositionsOptions {
            latitude_deg: self.latitude_deg,
            azimuth_deg: None,
            axial: self.axial,
            terms: self.terms.clone(),
            noise: Noise::Auto,
            k1: (!self.fit_k1).then_some(self.k1),
            u_k1: (!self.fit_k1).then_some(self.u_k1),
            fit_k1: self.fit_k1,
            k1_from: None,
        }
    }
}

impl crate::procedures::Plan for super::GyroPositions {
    type Options = PositionsPlanOptions;

    fn plan(o: &PositionsPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// The plan document of a multi-position plan: the angles, azimuths,
/// samples, noise and K1 as planned (top-level keys `plan`, `angles_deg`,
/// `azimuths_deg`, `samples`, `noise`, `k1`, `u_k1`, `fit_k1`,
/// `latitude_deg`, `axial`, `warnings`) and the predicted u of every drift
/// term (and of K1 when fitted).
pub fn plan_document(o: &PositionsPlanOptions) -> Result<PlanDocument> {
    o.validate()?;
    let rad = |v: &[f64]| v.iter().map(|x| x.to_radians()).collect::<Vec<f64>>();
    let p = plan(
        &rad(&o.angles_deg),
        &rad(&o.azimuths_deg),
        o.samples,
        o.noise,
        o.k1,
        &o.test_options(),
    )?;
    let mut d = PlanDocument::new(
        crate::document::Procedure::GyroPositions,
        format!(
            "Gyro multi-position plan: {} angles x {} azimuths, {} samples each, noise {:e} per sample, K1 = {}",
            o.angles_deg.len(),
            o.azimuths_deg.len(),
            o.samples,
            o.noise,
            o.k1
        ),
    );
    d.with_options(&PositionsPlanOptions {
        terms: o.test_options().terms(),
        ..o.clone()
    })?;
    d.set("plan", json!("gyro-positions"))?;
    d.set("angles_deg", json!(o.angles_deg))?;
    d.set("azimuths_deg", json!(o.azimuths_deg))?;
    d.set("samples", json!(o.samples))?;
    d.set("noise", json!(o.noise))?;
    d.set("k1", json!(o.k1))?;
    d.set("u_k1", json!(o.u_k1))?;
    d.set("fit_k1", json!(o.fit_k1))?;
    d.set("latitude_deg", json!(o.latitude_deg))?;
    d.set("axial", json!(o.axial.name()))?;
    let c = &p.coefficients;
    for (k, n) in c.names().iter().enumerate() {
        let unit = if n == "K1" {
            "output/(deg/s)"
        } else {
            DriftTerm::parse(n).map_or("", |t| t.unit())
        };
        d.predict(n, c.u_at(k), unit)?;
    }
    d.expect_dof(
        o.angles_deg.len() * o.azimuths_deg.len(),
        o.samples,
        c.len(),
    );
    set_warnings(&mut d, &p.warnings)?;
    Ok(d)
}

/// The run sheet of a multi-position plan: every head angle at each
/// azimuth in turn (`azimuth_deg`, `angle_deg`).
pub fn run_sheet(d: &crate::document::plan::PlanDocument) -> crate::procedures::registry::RunSheet {
    use crate::document::plan::{sheet_number as num, values};
    let angles = values(&d.plan, "angles_deg");
    let rows = values(&d.plan, "azimuths_deg")
        .into_iter()
        .flat_map(|az| angles.iter().map(move |&a| vec![num(az), num(a)]))
        .collect();
    (vec!["azimuth_deg", "angle_deg"], rows)
}
