//! Centrifuge calibration of a pendulous accelerometer: test radius,
//! input-axis nonlinearity, cross-axis nonlinearity and cross-coupling
//! with ECM alignment errors and an uncertainty budget (He & Yin 2017;
//! IEEE Std 836; docs/src/centrifuge.md).
//!
//! # Pipeline
//! 1. Samples with the same plane, angle, polarity and rate form a point;
//!    points with the same plane and angle form a *station* (both
//!    polarities). Angles are taken modulo 180° (φ0 + 180° with polarity s
//!    is φ0 with polarity −s).
//! 2. At the IA-radial station (`ip,0`, else `io,0`): static tilt λ
//!    (eq. 4), static radius per polarity (eq. 5–6) and the
//!    regression–iteration radii R± (eq. 7) — see [`radius`]. A table of
//!    regression radii for model orders 1–3 over growing input ranges shows
//!    whether the model is adequate (He & Yin 2017 Table 2: order 1 drifts).
//! 3. The regression radii give the ECM offset `r = (R+ − R−)/2` and, at
//!    every position, the ECM radius and alignment error Δφ
//!    ([`crate::rigs::centrifuge`], He & Yin 2017 §2.2).
//! 4. Every station is fitted with the polarity model of eq. 9, against
//!    the centripetal input `x` (g) computed with those radii:
//!    `E/K1 = b± ± s± x + c2 x² ± q (w± x)² (+ ± c3 (w± x)³)` (`±` =
//!    polarity; `q` only with both polarities, `c3` with model order 3;
//!    `w± = cos(φ0 + Δφ±)/cos φ0` carries the ECM alignment error into the
//!    odd terms, 1 when IA is not in the radial plane or is perpendicular
//!    to the radial direction). Linear in the
//!    parameters, solved by [`crate::estimation::fit_means`]: position means
//!    weighted by the pooled sample scatter, never below the lack of fit.
//! 5. Physical coefficients (g units) by the algebra of [`budget`]: IA
//!    radial gives `K2 = c2`, `K3 = c3`, `K_oq = q`; PA radial (`ip,90` or
//!    `po,0`) gives `K_pp`; OA radial (`io,90` or `po,90`) gives `K_oo`;
//!    a cross station (`ip`, `io`, `po` at an angle off the axes, 45°
//!    preferred) gives `K_ip`, `K_io`, `K_po` by eq. 2–3. Uncertainties by
//!    GUM propagation ([`Estimates::map`]) with the budget printed line by
//!    line: the c2 of each station (type A), the alignment Δc2 of each
//!    station (eq. 8, type B, uniform with half-width
//!    `|dc2/dφ| (|Δφ_net| + tolerance)`, `Δφ_net` the ECM alignment error
//!    left after averaging both polarities, `tolerance` the fixture angle
//!    bound given by the user) and K1 (the scale of `E/K1`).
//! 6. One propagation for everything: the coefficients of step 5 and the
//!    radius quantities of steps 2–3 (`R±`, static `R±`, `R = (R+ + R−)/2`,
//!    `r`, λ) are one map of one input vector (K0, K1, the raw means E0 and
//!    E_a±, each regression fit's parameters, each station fit's c2, q, c3
//!    and the type-B Δc2) through [`Estimates::map`], so the covariance is
//!    complete: K1, shared by every `E/K1`, enters R+ and R− fully
//!    correlated and does not average down in `R`
//!    (`CentrifugeResult::joint`). The coefficient budgets are the rows of
//!    that Jacobian for the coefficients.
//!
//! Because the ECM alignment error has opposite signs in the two
//! polarities (module docs of [`crate::rigs::centrifuge`]), its first-order
//! effect on the common c2 cancels; the paper's 1° deliberate errors (Tables
//! 3–4) are what the `tolerance` covers.

pub mod budget;
pub mod document;
pub mod input;
pub mod plan;
pub mod radius;
pub mod sim;

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

use crate::document::ResultDocument;
use crate::error::{Error, Result};
use crate::estimation::{
    fit_means, numeric_jacobian, Design, Estimates, Fit, Noise, PositionStats,
};
use crate::models::Term;
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};
use crate::warning::{Warning, WarningCode};
use budget::{delta_c2, Budget, BudgetLine, UncertaintyType};
use radius::{
    radius_from_scale, regression_radius, static_radius, static_tilt, RadiusContext, RadiusFit,
    SpeedPoint, ValueU,
};

/// One recorded sample (one row of the input CSV).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Fixture position.
    pub position: Position,
    /// Table rate ω (rad/s); 0 = at rest.
    pub omega_rad_s: f64,
    /// Instrument output E (output units).
    pub output: f64,
}

/// Coefficients a centrifuge run can give, in report order.
pub const CENTRIFUGE_TERMS: [Term; 8] = [
    Term::K2,
    Term::K3,
    Term::Koq,
    Term::Kpp,
    Term::Koo,
    Term::Kip,
    Term::Kio,
    Term::Kpo,
];

/// Options of [`calibrate`].
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeOptions {
    /// Bias K0 (g) from the 1 g calibration, with u.
    pub k0_g: ValueU,
    /// Scale factor K1 (output/g), with u.
    pub k1: ValueU,
    /// Covariance of K0 and K1 (g·output/g), e.g. from the tumble result
    /// they came from; 0 when they were estimated independently.
    pub cov_k0_k1: f64,
    /// Nominal radius R0 (m): start of the iteration, speed choice.
    pub radius0_m: f64,
    /// Latitude Φ (rad).
    pub latitude_rad: f64,
    /// Local gravity g_L (m/s²).
    pub g_local_m_s2: f64,
    /// Table spins opposite to Earth's sense.
    pub opposite_sense: bool,
    /// Model order of the radius regression and of the stations (2 or 3).
    pub order: usize,
    /// Bound of the fixture angle error (rad), for the type-B Δc2.
    pub alignment_tolerance_rad: f64,
    /// Output noise policy (σ in output units).
    pub noise: Noise,
    /// Coefficients required (`None`: every one the data supports).
    pub terms: Option<Vec<Term>>,
    /// Relative standard uncertainty of the table rate (ppm): a type-B
    /// input of the static (eq. 6) radius, `u(R)/R = 2 u(ω)/ω`.
    pub u_omega_ppm: f64,
}

/// A result document K0 and K1 are taken from (the 1 g calibration the
/// centrifuge run chains to): its name as the user gave it, the SHA-256 of
/// its bytes, and the document.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainedResult {
    /// The file as named by the user (`<stdin>` for standard input).
    pub name: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// The result document (it must be a tumble result).
    pub document: ResultDocument,
}

/// Options of the centrifuge procedure as a front end gives them; the
/// reduction's [`CentrifugeOptions`] follow from them
/// ([`CentrifugeRun::resolve`]).
///
/// K0 and K1 with their u come from `k0_g`/`u_k0_g` and `k1`/`u_k1`, or
/// from the tumble result `from` (`coefficients.K0`, `coefficients.K1` and
/// their covariance). An explicit value wins over `from`; an explicit
/// value without its u is taken as exact with a warning (never a silent
/// 0); a u without its value is refused when the value comes from `from`.
/// The covariance of K0 and K1 is used only when both come from `from`.
///
/// In the document's `options`: `k0`, `u_k0`, `k1`, `u_k1`, `cov_k0_k1`
/// (as used), `radius_m`, `latitude_deg`, `gravity_m_s2`,
/// `opposite_sense`, `order`, `alignment_tolerance_deg`, `noise` (σ of one
/// output sample, output units, or null for "from the data"),
/// `u_omega_ppm`.
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeRun {
    /// The tumble result K0 and K1 come from, if any.
    pub from: Option<ChainedResult>,
    /// Bias K0 (g); overrides `from`.
    pub k0_g: Option<f64>,
    /// Standard uncertainty of K0 (g); with `k0_g`.
    pub u_k0_g: Option<f64>,
    /// Scale factor K1 (output/g); overrides `from`.
    pub k1: Option<f64>,
    /// Standard uncertainty of K1 (output/g); with `k1`.
    pub u_k1: Option<f64>,
    /// Nominal test radius R0 (m): start of the regression iteration.
    pub radius_m: f64,
    /// Latitude Φ (deg, north positive).
    pub latitude_deg: f64,
    /// Local gravity g_L (m/s²): the g unit of every coefficient.
    pub gravity_m_s2: f64,
    /// The table spins opposite to Earth's sense.
    pub opposite_sense: bool,
    /// Model order of the radius regression and the station fits (2 or 3).
    pub order: usize,
    /// Bound of the fixture angle error (deg), for the type-B Δc2.
    pub alignment_tolerance_deg: f64,
    /// Output noise policy (σ of one sample, output units).
    pub noise: Noise,
    /// Coefficients required (`None`: every one the data supports).
    pub terms: Option<Vec<Term>>,
    /// Relative standard uncertainty of the table rate (ppm).
    pub u_omega_ppm: f64,
}

/// The reduction's options and the warnings of how K0 and K1 were chosen.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// Options of [`calibrate`].
    pub options: CentrifugeOptions,
    /// Warnings about K0 and K1 (an explicit value without its u).
    pub warnings: Vec<Warning>,
}

impl CentrifugeRun {
    /// K0 or K1 (`name`) from its explicit value and u or from the result
    /// `from`; `key`/`ukey` name the options in messages.
    fn pick(
        &self,
        key: &str,
        ukey: &str,
        name: &str,
        v: Option<f64>,
        u: Option<f64>,
        warnings: &mut Vec<Warning>,
    ) -> Result<ValueU> {
        match (v, &self.from) {
            (Some(value), _) => {
                if let Some(u) = u {
                    // An input's u as large as the value (K1) or a whole g
                    // (K0) leaves nothing to calibrate.
                    let (limit, bound) = if name == "K1" {
                        (value.abs(), "|k1|")
                    } else {
                        (1.0, "1 g")
                    };
                    if !(u.is_finite() && u >= 0.0 && u < limit) {
                        return Err(Error::InvalidValue {
                            what: format!("{ukey} (>= 0 and below {bound})"),
                            value: u.to_string(),
                        });
                    }
                } else {
                    warnings.push(Warning::new(
                        WarningCode::MissingUncertainty,
                        format!("{key} given without {ukey}: {name} is taken as exact, and every u derived from it is too small by its share"),
                    ));
                }
                Ok(ValueU {
                    value,
                    u: u.unwrap_or(0.0),
                })
            }
            (None, Some(f)) => {
                if u.is_some() {
                    return Err(Error::Unsupported(format!(
                        "{ukey} goes with {key} (the u of a chained result comes from that result)"
                    )));
                }
                let c = f.document.coefficients.get(name).ok_or_else(|| {
                    Error::Unsupported(format!("$.coefficients.{name}: missing")).in_file(&f.name)
                })?;
                Ok(ValueU {
                    value: c.value,
                    u: c.u,
                })
            }
            (None, None) => Err(Error::Unsupported(format!(
                "give {key} (with {ukey}) or a tumble result to chain to (from)"
            ))),
        }
    }

    /// The reduction's options: K0 and K1 chosen as the type docs say,
    /// every other option converted (deg to rad).
    pub fn resolve(&self) -> Result<Resolved> {
        if let Some(f) = &self.from {
            if f.document.procedure != crate::document::Procedure::Tumble {
                return Err(Error::Unsupported(format!(
                    "from (the result K0 and K1 come from) needs a tumble result, this is a {} result",
                    f.document.procedure
                ))
                .in_file(&f.name));
            }
        }
        let mut warnings = Vec::new();
        let k0_g = self.pick("k0", "u_k0", "K0", self.k0_g, self.u_k0_g, &mut warnings)?;
        let k1 = self.pick("k1", "u_k1", "K1", self.k1, self.u_k1, &mut warnings)?;
        // The covariance holds only when both come from the same result.
        let cov_k0_k1 = match (&self.from, self.k0_g, self.k1) {
            (Some(f), None, None) => f.document.covariance("K0", "K1").ok_or_else(|| {
                Error::Unsupported("$.correlation: no entry for K0 and K1".into()).in_file(&f.name)
            })?,
            _ => 0.0,
        };
        Ok(Resolved {
            options: CentrifugeOptions {
                k0_g,
                k1,
                cov_k0_k1,
                radius0_m: self.radius_m,
                latitude_rad: self.latitude_deg.to_radians(),
                g_local_m_s2: self.gravity_m_s2,
                opposite_sense: self.opposite_sense,
                order: self.order,
                alignment_tolerance_rad: self.alignment_tolerance_deg.to_radians(),
                noise: self.noise,
                terms: self.terms.clone(),
                u_omega_ppm: self.u_omega_ppm,
            },
            warnings,
        })
    }
}

impl serde::Serialize for CentrifugeRun {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::{Error as _, SerializeMap};
        let o = self.resolve().map_err(S::Error::custom)?.options;
        let mut m = s.serialize_map(Some(13))?;
        m.serialize_entry("alignment_tolerance_deg", &self.alignment_tolerance_deg)?;
        m.serialize_entry("cov_k0_k1", &o.cov_k0_k1)?;
        m.serialize_entry("gravity_m_s2", &self.gravity_m_s2)?;
        m.serialize_entry("k0", &o.k0_g.value)?;
        m.serialize_entry("k1", &o.k1.value)?;
        m.serialize_entry("latitude_deg", &self.latitude_deg)?;
        m.serialize_entry("noise", &self.noise.sigma())?;
        m.serialize_entry("opposite_sense", &self.opposite_sense)?;
        m.serialize_entry("order", &self.order)?;
        m.serialize_entry("radius_m", &self.radius_m)?;
        m.serialize_entry("u_k0", &o.k0_g.u)?;
        m.serialize_entry("u_k1", &o.k1.u)?;
        m.serialize_entry("u_omega_ppm", &self.u_omega_ppm)?;
        m.end()
    }
}

/// The centrifuge test as one [`super::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct CentrifugeTest;

impl super::Procedure for CentrifugeTest {
    const ID: crate::document::Procedure = crate::document::Procedure::Centrifuge;
    type Options = CentrifugeRun;
    type Input = Vec<Observation>;

    fn validate(o: &CentrifugeRun) -> Result<()> {
        o.noise.validate()?;
        check_u_omega_ppm(o.u_omega_ppm)?;
        check_options(&o.resolve()?.options)
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &CentrifugeRun,
    ) -> Result<Vec<Observation>> {
        input::read(rows)
    }

    fn reduce(
        obs: &Vec<Observation>,
        o: &CentrifugeRun,
        _: &dyn super::Progress,
    ) -> Result<ResultDocument> {
        let Resolved { options, warnings } = o.resolve()?;
        let r = calibrate(obs, &options)?;
        let mut doc = r.document(&options)?;
        if let Some(f) = &o.from {
            // The path as given: `-` for standard input.
            let path = if f.name == incal_io::source::STDIN_NAME {
                "-"
            } else {
                f.name.as_str()
            };
            doc.inputs.push(crate::document::InputFile {
                role: "from".into(),
                path: path.into(),
                sha256: f.sha256.clone(),
                rows: None,
            });
            // The instrument is the tumble result's: a chained result keeps
            // its serial, model and --meta pairs.
            doc.instrument = f.document.instrument.clone();
            doc.decisions.push(crate::document::Decision {
                code: crate::document::DecisionCode::ChainedInput,
                message: format!(
                    "K0 and K1 from the tumble result {}{} (covariance of K0 and K1 included)",
                    f.name,
                    f.document
                        .instrument
                        .serial
                        .as_ref()
                        .map_or(String::new(), |s| format!(" of serial {s}"))
                ),
            });
        }
        doc.warnings.splice(0..0, warnings);
        Ok(doc)
    }
}

/// ECM radius and alignment error of one polarity at a station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// ±1.
    pub polarity: i8,
    /// Distance of the ECM from the spin axis (m).
    pub radius_m: f64,
    /// True minus nominal radial angle Δφ (rad).
    pub delta_phi_rad: f64,
    /// c2 change this Δφ alone would cause (eq. 8), g/g².
    pub delta_c2: f64,
}

/// One point of a station fit (one polarity and rate): the abscissa and
/// the mean that eq. 9 fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationPoint {
    /// ±1.
    pub polarity: i8,
    /// Table rate ω (rad/s).
    pub omega_rad_s: f64,
    /// Centripetal input `x = R±(φ0)·(ω² + 2ωΩe sinΦ)/g_L` (g).
    pub input_g: f64,
    /// Samples, mean and scatter of `E/K1` (g).
    pub stats: PositionStats,
}

/// Fit of one station (plane, φ0), eq. 9.
#[derive(Debug, Clone, PartialEq)]
pub struct Station {
    /// Plane.
    pub plane: Plane,
    /// Nominal angle φ0 in [0, π) (rad).
    pub phi_rad: f64,
    /// Polarities present.
    pub polarities: Vec<i8>,
    /// Number of points (plane, angle, polarity, rate).
    pub points: usize,
    /// Quadratic coefficient (g/g²).
    pub c2: ValueU,
    /// Odd quadratic (g/g²), with both polarities.
    pub q: Option<ValueU>,
    /// Cubic coefficient (g/g³), with order 3.
    pub c3: Option<ValueU>,
    /// ECM alignment per polarity.
    pub alignment: Vec<Alignment>,
    /// Half-width of the uniform type-B Δc2 (g/g²).
    pub delta_c2_half_width: f64,
    /// The linear fit.
    pub fit: Fit,
    /// The points fitted, in the order of `fit.residuals`.
    pub point_data: Vec<StationPoint>,
}

impl Station {
    /// `plane,phi_deg` label.
    pub fn label(&self) -> String {
        station_label(self.plane, self.phi_rad)
    }
}

fn station_label(plane: Plane, phi_rad: f64) -> String {
    let d = (phi_rad.to_degrees() * 1e6).round() / 1e6;
    format!("{},{}", plane.name(), d)
}

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
/// exact. GUM first order. [`calibrate`] applies the same correction inside
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

/// Everything a centrifuge calibration produces.
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeResult {
    /// Label of the IA-radial station used for the radius.
    pub ia_station: Option<String>,
    /// Static tilt λ (rad), eq. 4 (`tilt_rad` of [`CentrifugeResult::joint`]).
    pub tilt_rad: Option<ValueU>,
    /// Static back-calculated radius (m) for polarity + and −, eq. 5–6,
    /// with the nonlinearity at the 1 g speed removed as
    /// [`correct_static_radius`] does when the regression gives K2 (K3):
    /// `R_plus_static_m` / `R_minus_static_m` of [`CentrifugeResult::joint`].
    pub static_radius: [Option<ValueU>; 2],
    /// The same radius exactly as eq. 5–6 compute it (nonlinearity ignored).
    pub static_radius_uncorrected: [Option<ValueU>; 2],
    /// Rate used for each static radius (rad/s).
    pub static_rate_rad_s: [Option<f64>; 2],
    /// Regression–iteration radius fits, polarity + and −, eq. 7; the u of
    /// each `radius_m` is that of `R_plus_m` / `R_minus_m` in
    /// [`CentrifugeResult::joint`].
    pub regression: [Option<RadiusFit>; 2],
    /// Radius for model orders 1–3 over growing ranges (Table 2).
    pub radius_table: Vec<RadiusRangeRow>,
    /// Fixture-centre radius R = (R+ + R−)/2 (m), `R_centre_m` of
    /// [`CentrifugeResult::joint`] (shared K1 included); the nominal radius
    /// with u = NaN when no regression radius was measured.
    pub centre_radius_m: ValueU,
    /// Signed ECM offset r = (R+ − R−)/2 (m), `ecm_offset_m` of
    /// [`CentrifugeResult::joint`]; 0 with u = NaN unless both polarities
    /// were measured.
    pub ecm_offset_m: ValueU,
    /// Station fits.
    pub stations: Vec<Station>,
    /// Stations that could not be fitted, with the reason.
    pub station_errors: Vec<(String, String)>,
    /// Physical coefficients (g units), in the order of
    /// [`CENTRIFUGE_TERMS`], those available and requested: the leading
    /// block of [`CentrifugeResult::joint`] (same values and covariance),
    /// with `dof` the minimum over the inputs of the coefficients only
    /// (K1, the station fits, the type-B Δc2). The coefficient map depends
    /// on the same inputs as before the joint propagation, K1 once, so
    /// values and u are those of the coefficient map alone; K1 shows only
    /// in the cross-covariance with the radii.
    pub coefficients: Estimates,
    /// Coefficients and radius quantities from one GUM propagation
    /// ([`Estimates::map`]) of one input vector, with the full covariance.
    ///
    /// Names, in order, those available: the coefficients (as in
    /// [`CentrifugeResult::coefficients`]: `K2`, `K3`, `K_oq`, `K_pp`,
    /// `K_oo`, `K_ip`, `K_io`, `K_po`; g units), then
    /// * `R_plus_m`, `R_minus_m`: regression–iteration radii (m, eq. 7,
    ///   [`radius::radius_from_scale`]);
    /// * `R_plus_static_m`, `R_minus_static_m`: static radii (m, eq. 5–6,
    ///   [`radius::eq6_radius`], divided by the nonlinearity factor
    ///   `1 ± K2 a_g + K3 a_g²` of [`correct_static_radius`] with that
    ///   polarity's regression K2, K3 when there is a regression);
    /// * `R_centre_m = (R+ + R−)/2` (m, He & Yin 2017 §2.2; the one regression
    ///   radius when only one polarity was measured);
    /// * `ecm_offset_m = (R+ − R−)/2` (m, signed; both polarities only);
    /// * `tilt_rad`: λ = E0/K1 − K0 (rad, eq. 4).
    ///
    /// Inputs: K1 and K0 (u from the options), the at-rest mean E0 and the
    /// static-speed means E_a± (raw output, u = s/√n), each polarity's
    /// regression parameters (`b`, `scale`, `K2`, `K3`, covariance block of
    /// that fit), each station's c2 (with `q`, `c3` at the IA-radial
    /// station; covariance block of the station fit) and the type-B Δc2.
    /// K1 is one input: the scale of every `E/K1`, it is fully correlated
    /// between R+ and R− (`u²(R±) ⊃ (R± u(K1)/K1)²`, which does not average
    /// down in `R_centre_m`), between the radii and the tilt, and
    /// anti-correlated between the radii and the coefficients (a larger K1
    /// shrinks the radius and grows c2 ∝ K1). Blocks from different fits are
    /// independent: the regression fits and the IA-radial station fit share
    /// data, and that cross-covariance is not modelled. `dof`: the minimum
    /// over the inputs used (the raw means count as ∞, as for the static
    /// radius of [`radius::static_radius`]).
    pub joint: Estimates,
    /// Uncertainty budget of every coefficient.
    pub budgets: Vec<Budget>,
    /// Coefficients the data cannot give, with the reason.
    pub unsupported: Vec<(Term, String)>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

struct Point {
    position: Position,
    omega: f64,
    samples: Vec<f64>,
}

/// Normalise (φ, polarity) to φ in [0°, 180°) and give a µ° key.
fn normalise(pos: &Position) -> (i64, Position) {
    let mut key = (pos.phi_rad.to_degrees() * 1e6).round() as i64;
    key = key.rem_euclid(360_000_000);
    let mut pol = pos.polarity;
    if key >= 180_000_000 {
        key -= 180_000_000;
        pol = -pol;
    }
    (
        key,
        Position {
            plane: pos.plane,
            phi_rad: (key as f64 / 1e6).to_radians(),
            polarity: pol,
        },
    )
}

/// Group into stations (plane, angle key) → points, in order of appearance.
fn group(obs: &[Observation]) -> Vec<((Plane, i64), Vec<Point>)> {
    let mut stations: Vec<((Plane, i64), Vec<Point>)> = Vec::new();
    let mut index: BTreeMap<(Plane, i64), usize> = BTreeMap::new();
    let mut pindex: BTreeMap<(Plane, i64, i8, i64), (usize, usize)> = BTreeMap::new();
    for o in obs {
        let (key, pos) = normalise(&o.position);
        let s = *index.entry((pos.plane, key)).or_insert_with(|| {
            stations.push(((pos.plane, key), Vec::new()));
            stations.len() - 1
        });
        let wkey = (o.omega_rad_s * 1e9).round() as i64;
        let (si, pi) = *pindex
            .entry((pos.plane, key, pos.polarity, wkey))
            .or_insert_with(|| {
                stations[s].1.push(Point {
                    position: pos,
                    omega: o.omega_rad_s,
                    samples: Vec::new(),
                });
                (s, stations[s].1.len() - 1)
            });
        stations[si].1[pi].samples.push(o.output);
    }
    stations
}

fn check_options(o: &CentrifugeOptions) -> Result<()> {
    let pos = |what: &str, v: f64| -> Result<()> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(Error::InvalidValue {
                what: what.into(),
                value: v.to_string(),
            })
        }
    };
    let nonneg = |what: &str, v: f64| -> Result<()> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(Error::InvalidValue {
                what: what.into(),
                value: v.to_string(),
            })
        }
    };
    crate::error::finite("K0", o.k0_g.value)?;
    crate::error::finite("K1", o.k1.value)?;
    if o.k1.value == 0.0 {
        return Err(Error::InvalidValue {
            what: "K1".into(),
            value: "0".into(),
        });
    }
    nonneg("u(K0)", o.k0_g.u)?;
    nonneg("u(K1)", o.k1.u)?;
    crate::error::finite("covariance of K0 and K1", o.cov_k0_k1)?;
    if o.cov_k0_k1.abs() > o.k0_g.u * o.k1.u * (1.0 + 1e-9) {
        return Err(Error::InvalidValue {
            what: "covariance of K0 and K1 (larger than u(K0)·u(K1))".into(),
            value: o.cov_k0_k1.to_string(),
        });
    }
    pos("nominal radius", o.radius0_m)?;
    pos("local gravity", o.g_local_m_s2)?;
    crate::error::finite("latitude", o.latitude_rad)?;
    nonneg("alignment tolerance", o.alignment_tolerance_rad)?;
    check_u_omega_ppm(o.u_omega_ppm)?;
    check_order(o.order)
}

/// Refuse a model order other than 2 or 3.
fn check_order(order: usize) -> Result<()> {
    if (2..=3).contains(&order) {
        Ok(())
    } else {
        Err(Error::Unsupported(format!(
            "model order {order} (use 2 or 3)"
        )))
    }
}

/// Largest relative standard uncertainty of the table rate (ppm, 10 %).
const MAX_U_OMEGA_PPM: f64 = 1e5;

/// Refuse a relative u of the table rate outside 0…1e5 ppm.
fn check_u_omega_ppm(u_omega_ppm: f64) -> Result<()> {
    if u_omega_ppm.is_finite() && (0.0..=MAX_U_OMEGA_PPM).contains(&u_omega_ppm) {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: "u_omega_ppm (within 0..1e5)".into(),
            value: u_omega_ppm.to_string(),
        })
    }
}

fn e_over_k1(samples: &[f64], k1: f64) -> Result<PositionStats> {
    let y: Vec<f64> = samples.iter().map(|e| e / k1).collect();
    PositionStats::of(&y)
}

fn noise_in_g(noise: Noise, k1: f64) -> Noise {
    match noise {
        Noise::Known { sigma } => Noise::Known {
            sigma: sigma / k1.abs(),
        },
        Noise::Auto => Noise::Auto,
    }
}

/// Calibrate from centrifuge observations (module docs).
pub fn calibrate(obs: &[Observation], opts: &CentrifugeOptions) -> Result<CentrifugeResult> {
    check_options(opts)?;
    if obs.is_empty() {
        return Err(Error::TooFew {
            what: "observations".into(),
            needed: 1,
            got: 0,
        });
    }
    for o in obs {
        Position::new(o.position.plane, o.position.phi_rad, o.position.polarity)?;
        crate::error::finite("rate omega", o.omega_rad_s)?;
        crate::error::finite("output", o.output)?;
    }
    let k1 = opts.k1.value;
    let noise = noise_in_g(opts.noise, k1);
    let ctx = RadiusContext {
        k0_g: opts.k0_g,
        k1: opts.k1,
        latitude_rad: opts.latitude_rad,
        g_local_m_s2: opts.g_local_m_s2,
        opposite_sense: opts.opposite_sense,
        u_omega_rel: opts.u_omega_ppm * 1e-6,
        known_sigma: match opts.noise {
            Noise::Known { sigma } => Some(sigma),
            Noise::Auto => None,
        },
    };
    let nominal = Centrifuge {
        r_plus_m: opts.radius0_m,
        r_minus_m: opts.radius0_m,
        latitude_rad: opts.latitude_rad,
        g_local_m_s2: opts.g_local_m_s2,
        opposite_sense: opts.opposite_sense,
        tilt_rad: 0.0,
    };
    let groups = group(obs);
    let mut warnings = Vec::new();

    // --- IA-radial station: tilt and radius -------------------------------
    let ia = [(Plane::Ip, 0i64), (Plane::Io, 0i64)]
        .iter()
        .find_map(|k| groups.iter().find(|g| g.0 == *k));
    let mut tilt = None;
    let mut static_r = [None, None];
    let mut static_uncorrected = [None, None];
    let mut static_w = [None, None];
    let mut regression: [Option<RadiusFit>; 2] = [None, None];
    let mut radius_table = Vec::new();
    // Raw means behind the tilt and the static radii, for the joint
    // propagation: E0 (at rest, both polarities) and E_a per polarity.
    let mut e0_stats = None;
    let mut e_a_stats: [Option<PositionStats>; 2] = [None, None];
    if let Some((_, points)) = ia {
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
            tilt = Some(static_tilt(&at_rest, &ctx)?);
            e0_stats = Some(PositionStats::of(&at_rest)?);
        }
        let lambda = tilt.map_or(0.0, |t| t.value);
        for (slot, pol) in [(0usize, 1i8), (1, -1)] {
            let mine: Vec<&Point> = points
                .iter()
                .filter(|p| p.position.polarity == pol)
                .collect();
            if mine.iter().all(|p| p.omega == 0.0) {
                continue;
            }
            if !at_rest.is_empty() {
                // Speed nearest 1 g with the nominal radius.
                let best = mine.iter().filter(|p| p.omega != 0.0).min_by(|a, b| {
                    let fa = (nominal.centripetal_g(&a.position, a.omega) - 1.0).abs();
                    let fb = (nominal.centripetal_g(&b.position, b.omega) - 1.0).abs();
                    fa.total_cmp(&fb)
                });
                if let Some(b) = best {
                    static_r[slot] = Some(static_radius(
                        &b.samples,
                        &at_rest,
                        b.omega,
                        f64::from(pol),
                        &ctx,
                    )?);
                    static_w[slot] = Some(b.omega);
                    e_a_stats[slot] = Some(PositionStats::of(&b.samples)?);
                }
            }
            let speed_points: Vec<SpeedPoint> = mine
                .iter()
                .map(|p| {
                    Ok(SpeedPoint {
                        omega_rad_s: p.omega,
                        stats: e_over_k1(&p.samples, k1)?,
                    })
                })
                .collect::<Result<_>>()?;
            match regression_radius(
                &speed_points,
                f64::from(pol),
                opts.order,
                opts.radius0_m,
                lambda,
                &ctx,
                noise,
            ) {
                Ok(f) => {
                    // Eq. 5–6 ignore the nonlinearity at a_g (~1 g): the
                    // joint propagation below divides the eq. 6 radius by
                    // 1 ± K2 a_g + K3 a_g² with this polarity's K2, K3
                    // (correct_static_radius); the paper's uncorrected
                    // value is kept.
                    static_uncorrected[slot] = static_r[slot];
                    for w in f.fit.quality_warnings(
                        "a model order too low for the speed range, a radius that changes with speed, or drift",
                    ) {
                        warnings.push(w.prefixed(&format!("radius regression, polarity {pol:+}")));
                    }
                    regression[slot] = Some(f);
                }
                Err(e) => warnings.push(Warning::new(
                    WarningCode::PartFailed,
                    format!("regression radius, polarity {pol:+}: {e}"),
                )),
            }
            radius_table.extend(range_table(&speed_points, pol, lambda, opts, &ctx, noise));
        }
    } else {
        warnings.push(Warning::new(
            WarningCode::RadiusIncomplete,
            "no IA-radial station (ip,0 or io,0): radius not measured, nominal radius used",
        ));
    }

    // --- ECM offset (values; u from the joint propagation below) ------------
    let (r_plus, r_minus) = match (&regression[0], &regression[1]) {
        (Some(p), Some(m)) => (p.radius_m.value, m.radius_m.value),
        (Some(p), None) => {
            warnings.push(Warning::new(
                WarningCode::RadiusIncomplete,
                "only polarity + measured: ECM offset taken as 0",
            ));
            (p.radius_m.value, p.radius_m.value)
        }
        (None, Some(m)) => {
            warnings.push(Warning::new(
                WarningCode::RadiusIncomplete,
                "only polarity - measured: ECM offset taken as 0",
            ));
            (m.radius_m.value, m.radius_m.value)
        }
        (None, None) => (opts.radius0_m, opts.radius0_m),
    };
    let (centre, offset) = budget::ecm_offset(r_plus, r_minus);
    let rig = Centrifuge {
        r_plus_m: r_plus,
        r_minus_m: r_minus,
        tilt_rad: 0.0,
        ..nominal
    };

    // --- stations ----------------------------------------------------------
    let mut stations = Vec::new();
    let mut station_errors = Vec::new();
    for ((plane, key), points) in &groups {
        let phi = (*key as f64 / 1e6).to_radians();
        match fit_station(*plane, phi, points, &rig, opts.order, k1, noise) {
            Ok(s) => stations.push(s),
            Err(e) => station_errors.push((station_label(*plane, phi), e.to_string())),
        }
    }

    // --- coefficients and radii, one propagation ---------------------------
    let radius_inputs = RadiusInputs {
        e0: e0_stats,
        static_point: [0, 1].map(|k| e_a_stats[k].zip(static_w[k])),
        regression: [regression[0].as_ref(), regression[1].as_ref()],
    };
    let Estimated {
        coefficients,
        joint,
        budgets,
        unsupported,
    } = estimate(&mut stations, &station_errors, &radius_inputs, opts)?;
    if let Some(req) = &opts.terms {
        for t in req {
            if let Some((_, why)) = unsupported.iter().find(|(u, _)| u == t) {
                return Err(Error::Unsupported(format!(
                    "this position set cannot give {t}: {why}"
                )));
            }
        }
    }
    if coefficients.is_empty() {
        // One reason per distinct cause (terms sharing it listed together),
        // so the line stays readable; `incal plan centrifuge` says the rest.
        let mut why: Vec<(Vec<String>, &str)> = Vec::new();
        for (t, w) in &unsupported {
            match why.iter_mut().find(|(_, r)| *r == w.as_str()) {
                Some((terms, _)) => terms.push(t.to_string()),
                None => why.push((vec![t.to_string()], w.as_str())),
            }
        }
        let shown: Vec<String> = why
            .iter()
            .take(2)
            .map(|(t, w)| format!("{}: {w}", t.join(", ")))
            .collect();
        let more = why.len().saturating_sub(2);
        return Err(Error::Unsupported(format!(
            "this position set gives no coefficient ({}{})",
            shown.join("; "),
            if more > 0 {
                format!("; and {more} more: see incal plan centrifuge")
            } else {
                String::new()
            }
        )));
    }
    for s in &stations {
        let c = s.phi_rad.cos();
        if let ([pol], true) = (&s.polarities[..], s.plane.ia_horizontal() && c.abs() > 1e-6) {
            let sign = if *pol > 0 { "+" } else { "-" };
            warnings.push(Warning::new(
                WarningCode::OnePolarity,
                format!(
                    "one polarity only at {}: the odd quadratic cannot be separated there, its c2 includes {sign}{:.3}*K_oq",
                    s.label(),
                    c * c
                ),
            ));
        }
    }
    for s in &stations {
        for w in s
            .fit
            .quality_warnings("a model order too low for the speed range, drift, or rig vibration")
        {
            warnings.push(w.prefixed(&format!("station {}", s.label())));
        }
    }
    // Every radius field carries the u of the joint propagation.
    let ju = |name: &str| joint.get(name).map(|(value, u)| ValueU { value, u });
    for (k, name) in [(0usize, "R_plus_m"), (1, "R_minus_m")] {
        if let (Some(f), Some(v)) = (regression[k].as_mut(), ju(name)) {
            f.radius_m.u = v.u;
        }
    }
    for (k, name) in [(0usize, "R_plus_static_m"), (1, "R_minus_static_m")] {
        if let Some(v) = ju(name) {
            static_r[k] = Some(v);
        }
    }
    let centre_radius_m = ju("R_centre_m").unwrap_or(ValueU {
        value: centre,
        u: f64::NAN,
    });
    // A radius is a length: a negative one means the scale factor's sign
    // (or K0) does not match the output, and every coefficient would be
    // sign-flipped nonsense.
    for (name, v) in [
        ("R_centre_m", Some(centre_radius_m)),
        ("R_plus_m", ju("R_plus_m")),
        ("R_minus_m", ju("R_minus_m")),
        ("R_plus_static_m", static_r[0]),
        ("R_minus_static_m", static_r[1]),
    ] {
        if let Some(v) = v {
            if !(v.value.is_finite() && v.value > 0.0) {
                return Err(Error::Unsupported(format!(
                    "the fitted radius {name} = {:.6} m is not positive: the sign of K1 ({}) does not match the output's response to the rate (check --k1 and the polarity)",
                    v.value, opts.k1.value
                )));
            }
        }
    }
    let ecm_offset_m = ju("ecm_offset_m").unwrap_or(ValueU {
        value: offset,
        u: f64::NAN,
    });
    if let Some(v) = ju("tilt_rad") {
        tilt = Some(v);
    }
    Ok(CentrifugeResult {
        ia_station: ia.map(|g| station_label(g.0 .0, (g.0 .1 as f64 / 1e6).to_radians())),
        tilt_rad: tilt,
        static_radius: static_r,
        static_radius_uncorrected: static_uncorrected,
        static_rate_rad_s: static_w,
        regression,
        radius_table,
        centre_radius_m,
        ecm_offset_m,
        stations,
        station_errors,
        coefficients,
        joint,
        budgets,
        unsupported,
        warnings,
    })
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
        opts.radius0_m
            * crate::rigs::centrifuge::centripetal_rate_squared(
                p.omega_rad_s,
                opts.latitude_rad,
                opts.opposite_sense,
            )
            / opts.g_local_m_s2
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
                opts.radius0_m,
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

/// Axes (first, second) of a plane as model terms of their squares and
/// product: (K_aa, K_bb, K_ab).
fn plane_terms(plane: Plane) -> (Term, Term, Term) {
    match plane {
        Plane::Ip => (Term::K2, Term::Kpp, Term::Kip),
        Plane::Io => (Term::K2, Term::Koo, Term::Kio),
        Plane::Po => (Term::Kpp, Term::Koo, Term::Kpo),
    }
}

/// Fit one station with the polarity model of eq. 9 (module docs).
fn fit_station(
    plane: Plane,
    phi_rad: f64,
    points: &[Point],
    rig: &Centrifuge,
    order: usize,
    k1: f64,
    noise: Noise,
) -> Result<Station> {
    let mut pols: Vec<i8> = points.iter().map(|p| p.position.polarity).collect();
    pols.sort_unstable_by(|a, b| b.cmp(a));
    pols.dedup();
    let both = pols.len() == 2;
    let mut names: Vec<String> = Vec::new();
    for p in &pols {
        let s = if *p > 0 { "+" } else { "-" };
        names.push(format!("b{s}"));
        names.push(format!("s{s}"));
    }
    names.push("c2".into());
    if both {
        names.push("q".into());
    }
    if order >= 3 {
        names.push("c3".into());
    }
    let mut rows = Vec::new();
    let mut stats = Vec::new();
    let mut point_data = Vec::with_capacity(points.len());
    for p in points {
        let x = rig.centripetal_g(&p.position, p.omega);
        let s = p.position.sign();
        // Odd terms follow the input axis, whose angle to the radial
        // direction is off by the ECM alignment error Δφ±, opposite in the
        // two polarities: scale them by w = cos(φ0 + Δφ±)/cos φ0 so that
        // the polarity-dependent part of K_oq·a_i|a_i| and K3·a_i³ does not
        // leak into the common c2.
        let w = if plane.ia_horizontal() && phi_rad.cos().abs() > 1e-6 {
            let d = rig.geometry(&p.position).delta_phi_rad;
            (phi_rad + d).cos() / phi_rad.cos()
        } else {
            1.0
        };
        let mut row = Vec::with_capacity(names.len());
        for q in &pols {
            let on = if *q == p.position.polarity { 1.0 } else { 0.0 };
            row.push(on);
            row.push(on * s * x);
        }
        row.push(x * x);
        if both {
            row.push(s * (w * x).powi(2));
        }
        if order >= 3 {
            row.push(s * (w * x).powi(3));
        }
        rows.push(row);
        let st = e_over_k1(&p.samples, k1)?;
        point_data.push(StationPoint {
            polarity: p.position.polarity,
            omega_rad_s: p.omega,
            input_g: x,
            stats: st,
        });
        stats.push(st);
    }
    let design = Design::from_rows(names, &rows)?;
    let (fit, _) = fit_means(&design, &stats, noise)?;
    let get = |n: &str| fit.estimates.get(n).map(|(value, u)| ValueU { value, u });
    let c2 = get("c2").ok_or_else(|| Error::Unsupported("station fit lost c2".into()))?;
    let alignment = pols
        .iter()
        .map(|&pol| {
            let g = rig.geometry(&Position {
                plane,
                phi_rad,
                polarity: pol,
            });
            Alignment {
                polarity: pol,
                radius_m: g.radius_m,
                delta_phi_rad: g.delta_phi_rad,
                delta_c2: 0.0,
            }
        })
        .collect();
    Ok(Station {
        plane,
        phi_rad,
        polarities: pols,
        points: points.len(),
        c2,
        q: if both { get("q") } else { None },
        c3: if order >= 3 { get("c3") } else { None },
        alignment,
        delta_c2_half_width: 0.0,
        fit,
        point_data,
    })
}

fn is_key(s: &Station, plane: Plane, deg: f64) -> bool {
    s.plane == plane && ((s.phi_rad.to_degrees() - deg).abs() < 1e-6)
}

fn is_axis(s: &Station) -> bool {
    let d = s.phi_rad.to_degrees();
    d.abs() < 1e-6 || (d - 90.0).abs() < 1e-6
}

/// A physical coefficient as a linear combination of inputs.
type Combo = Vec<(usize, f64)>;

fn add(a: &mut Combo, b: &Combo, f: f64) {
    for (k, c) in b {
        if let Some(e) = a.iter_mut().find(|(j, _)| j == k) {
            e.1 += f * c;
        } else {
            a.push((*k, f * c));
        }
    }
}

/// What the IA-radial station gives the joint propagation for the radius
/// quantities (raw output statistics, regression fits).
struct RadiusInputs<'a> {
    /// At-rest output (E0), both polarities.
    e0: Option<PositionStats>,
    /// Per polarity (+, −): output at the static speed (E_a) and that speed.
    static_point: [Option<(PositionStats, f64)>; 2],
    /// Per polarity: the regression–iteration fit.
    regression: [Option<&'a RadiusFit>; 2],
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
/// (formulas: [`CentrifugeResult::joint`]).
struct RadiusMap {
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
    /// Named outputs at `x`, in the order of [`CentrifugeResult::joint`].
    fn eval(&self, x: &DVector<f64>) -> Vec<(&'static str, f64)> {
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
    fn values(&self, x: &DVector<f64>) -> DVector<f64> {
        let v = self.eval(x);
        DVector::from_iterator(v.len(), v.into_iter().map(|(_, y)| y))
    }
}

/// What [`estimate`] gives [`calibrate`].
struct Estimated {
    coefficients: Estimates,
    joint: Estimates,
    budgets: Vec<Budget>,
    unsupported: Vec<(Term, String)>,
}

struct Inputs {
    names: Vec<String>,
    values: Vec<f64>,
    /// Covariance blocks: (first index, block).
    blocks: Vec<(usize, DMatrix<f64>)>,
    /// Covariances between blocks: (j, k, C_jk).
    cross: Vec<(usize, usize, f64)>,
    kind: Vec<UncertaintyType>,
    dof: Vec<f64>,
    /// Station index of each input (None for K1).
    station: Vec<Option<usize>>,
}

impl Inputs {
    fn push_block(
        &mut self,
        station: Option<usize>,
        kind: UncertaintyType,
        items: Vec<(String, f64)>,
        cov: DMatrix<f64>,
        dof: f64,
    ) -> usize {
        let first = self.names.len();
        for (n, v) in items {
            self.names.push(n);
            self.values.push(v);
            self.kind.push(kind);
            self.dof.push(dof);
            self.station.push(station);
        }
        self.blocks.push((first, cov));
        first
    }
    fn covariance(&self) -> DMatrix<f64> {
        let n = self.names.len();
        let mut c = DMatrix::zeros(n, n);
        for (first, b) in &self.blocks {
            c.view_mut((*first, *first), b.shape()).copy_from(b);
        }
        for &(j, k, v) in &self.cross {
            c[(j, k)] = v;
            c[(k, j)] = v;
        }
        c
    }
}

/// Coefficients, radius quantities and budgets from one propagation of one
/// input vector (module docs, [`CentrifugeResult::joint`]).
fn estimate(
    stations: &mut [Station],
    station_errors: &[(String, String)],
    radii: &RadiusInputs,
    opts: &CentrifugeOptions,
) -> Result<Estimated> {
    let find = |keys: &[(Plane, f64)]| -> Option<usize> {
        keys.iter()
            .find_map(|(p, d)| stations.iter().position(|s| is_key(s, *p, *d)))
    };
    let failed = |keys: &[(Plane, f64)]| -> Option<String> {
        keys.iter().find_map(|(p, d)| {
            let l = station_label(*p, d.to_radians());
            station_errors
                .iter()
                .find(|(s, _)| *s == l)
                .map(|(s, e)| format!("station {s} could not be fitted: {e}"))
        })
    };
    let ia_keys = [(Plane::Ip, 0.0), (Plane::Io, 0.0)];
    let pa_keys = [(Plane::Ip, 90.0), (Plane::Po, 0.0)];
    let oa_keys = [(Plane::Io, 90.0), (Plane::Po, 90.0)];
    let ia = find(&ia_keys);
    let pa = find(&pa_keys);
    let oa = find(&oa_keys);
    let cross = |plane: Plane| -> Option<usize> {
        stations
            .iter()
            .enumerate()
            .filter(|(_, s)| s.plane == plane && !is_axis(s))
            .min_by(|a, b| {
                let da = (a.1.phi_rad.to_degrees() - 45.0).abs();
                let db = (b.1.phi_rad.to_degrees() - 45.0).abs();
                da.total_cmp(&db)
            })
            .map(|(k, _)| k)
    };
    let mut unsupported: Vec<(Term, String)> = Vec::new();
    let need = |idx: Option<usize>,
                keys: &[(Plane, f64)],
                what: &str|
     -> std::result::Result<usize, String> {
        idx.ok_or_else(|| {
            failed(keys).unwrap_or_else(|| {
                format!(
                    "needs a {what} station ({})",
                    keys.iter()
                        .map(|(p, d)| format!("{},{}", p.name(), d))
                        .collect::<Vec<_>>()
                        .join(" or ")
                )
            })
        })
    };

    let known_sigma = match opts.noise {
        Noise::Known { sigma } => Some(sigma),
        Noise::Auto => None,
    };
    // Inputs: K1, then per station c2 (with q, c3 at the IA station), dc2.
    let mut inp = Inputs {
        names: Vec::new(),
        values: Vec::new(),
        blocks: Vec::new(),
        cross: Vec::new(),
        kind: Vec::new(),
        dof: Vec::new(),
        station: Vec::new(),
    };
    let k1_idx = inp.push_block(
        None,
        UncertaintyType::B,
        vec![("K1".into(), opts.k1.value)],
        DMatrix::from_element(1, 1, opts.k1.u.powi(2)),
        f64::INFINITY,
    );
    // Radius inputs: K0 and E0 (tilt, static radii), then per polarity E_a
    // and the regression parameters. They follow K1 so that a coefficient
    // budget (lines in input order, zero sensitivities left out) is as
    // before.
    let k0_e0 = match radii.e0 {
        Some(e0) => {
            let k0 = inp.push_block(
                None,
                UncertaintyType::B,
                vec![("K0".into(), opts.k0_g.value)],
                DMatrix::from_element(1, 1, opts.k0_g.u.powi(2)),
                f64::INFINITY,
            );
            // K0 and K1 from one tumble fit are correlated.
            if opts.cov_k0_k1 != 0.0 {
                inp.cross.push((k0, k1_idx, opts.cov_k0_k1));
            }
            let e = inp.push_block(
                None,
                UncertaintyType::A,
                vec![("E0".into(), e0.mean)],
                DMatrix::from_element(1, 1, radius::sem(&e0, known_sigma).powi(2)),
                f64::INFINITY,
            );
            Some((k0, e))
        }
        None => None,
    };
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
            let scale = at("scale").ok_or_else(|| {
                Error::Unsupported("regression radius fit has no scale term".into())
            })?;
            reg_at[k] = Some(RegressionAt {
                scale,
                scale_hat: inp.values[scale],
                r_m: f.radius_m.value,
                k2: at("K2"),
                k3: at("K3"),
            });
        }
    }
    let radius_map = RadiusMap {
        k1: k1_idx,
        k1_used: opts.k1.value,
        k0_e0,
        g_local_m_s2: opts.g_local_m_s2,
        regression: reg_at,
        static_point: static_at,
        latitude_rad: opts.latitude_rad,
        opposite_sense: opts.opposite_sense,
    };
    let radius_first = k1_idx + 1;
    let radius_end = inp.names.len();

    let mut c2_idx: BTreeMap<usize, usize> = BTreeMap::new();
    let mut dc2_idx: BTreeMap<usize, usize> = BTreeMap::new();
    let mut extra: BTreeMap<(usize, &'static str), usize> = BTreeMap::new();
    for (k, s) in stations.iter().enumerate() {
        let mut items = vec![(format!("c2({})", s.label()), s.c2.value)];
        let mut which = vec!["c2"];
        if Some(k) == ia {
            if s.q.is_some() {
                items.push((format!("q({})", s.label()), s.q.map_or(0.0, |v| v.value)));
                which.push("q");
            }
            if s.c3.is_some() {
                items.push((format!("c3({})", s.label()), s.c3.map_or(0.0, |v| v.value)));
                which.push("c3");
            }
        }
        let sel: Vec<&str> = which.clone();
        let block = s.fit.estimates.select(&sel)?;
        let first = inp.push_block(
            Some(k),
            UncertaintyType::A,
            items,
            block.covariance().clone(),
            s.fit.estimates.dof(),
        );
        for (j, w) in which.iter().enumerate() {
            if *w == "c2" {
                c2_idx.insert(k, first + j);
            } else {
                extra.insert((k, w), first + j);
            }
        }
        let d = inp.push_block(
            Some(k),
            UncertaintyType::B,
            vec![(format!("alignment dc2({})", s.label()), 0.0)],
            DMatrix::zeros(1, 1),
            f64::INFINITY,
        );
        dc2_idx.insert(k, d);
    }
    let direct = |k: usize| -> Combo { vec![(c2_idx[&k], 1.0), (dc2_idx[&k], 1.0)] };

    let mut combos: BTreeMap<Term, (Combo, Option<usize>)> = BTreeMap::new();
    match need(ia, &ia_keys, "IA-radial") {
        Ok(k) => {
            combos.insert(Term::K2, (direct(k), None));
            match extra.get(&(k, "c3")) {
                Some(&j) => {
                    combos.insert(Term::K3, (vec![(j, 1.0)], None));
                }
                None => unsupported.push((Term::K3, "needs model order 3".into())),
            }
            match extra.get(&(k, "q")) {
                Some(&j) => {
                    combos.insert(Term::Koq, (vec![(j, 1.0)], None));
                }
                None => unsupported.push((
                    Term::Koq,
                    "needs both polarities at the IA-radial station (the odd quadratic is separated from K2 only by the polarity reversal)".into(),
                )),
            }
        }
        Err(why) => {
            for t in [Term::K2, Term::K3, Term::Koq] {
                unsupported.push((t, why.clone()));
            }
        }
    }
    match need(pa, &pa_keys, "PA-radial") {
        Ok(k) => {
            combos.insert(Term::Kpp, (direct(k), None));
        }
        Err(why) => unsupported.push((Term::Kpp, why)),
    }
    match need(oa, &oa_keys, "OA-radial") {
        Ok(k) => {
            combos.insert(Term::Koo, (direct(k), None));
        }
        Err(why) => unsupported.push((Term::Koo, why)),
    }
    for plane in [Plane::Ip, Plane::Io, Plane::Po] {
        let (ta, tb, tab) = plane_terms(plane);
        let Some(k) = cross(plane) else {
            unsupported.push((
                tab,
                format!(
                    "needs a cross station in plane {} at an angle off the axes (e.g. {},45)",
                    plane.name(),
                    plane.name()
                ),
            ));
            continue;
        };
        let (Some((ca, _)), Some((cb, _))) = (combos.get(&ta).cloned(), combos.get(&tb).cloned())
        else {
            unsupported.push((
                tab,
                format!("needs {ta} and {tb} from their radial stations"),
            ));
            continue;
        };
        let (s, c) = stations[k].phi_rad.sin_cos();
        let mut combo = Vec::new();
        add(&mut combo, &direct(k), 1.0 / (s * c));
        add(&mut combo, &ca, -c * c / (s * c));
        add(&mut combo, &cb, -s * s / (s * c));
        combos.insert(tab, (combo, Some(k)));
    }

    // Point values (dc2 inputs are 0), then the type-B half-widths.
    let value_of = |combo: &Combo| combo.iter().map(|(j, c)| c * inp.values[*j]).sum::<f64>();
    let point: BTreeMap<Term, f64> = combos.iter().map(|(t, (c, _))| (*t, value_of(c))).collect();
    let mut dc2_var: Vec<(usize, f64)> = Vec::new();
    for (k, s) in stations.iter_mut().enumerate() {
        let (ta, tb, tab) = plane_terms(s.plane);
        let g = |t: Term| point.get(&t).copied().unwrap_or(0.0);
        let (kaa, kbb, kab) = (g(ta), g(tb), g(tab));
        for a in &mut s.alignment {
            a.delta_c2 = delta_c2(kaa, kbb, kab, s.phi_rad, a.delta_phi_rad);
        }
        let net = s.alignment.iter().map(|a| a.delta_phi_rad).sum::<f64>()
            / s.alignment.len().max(1) as f64;
        let hw = delta_c2(
            kaa,
            kbb,
            kab,
            s.phi_rad,
            net.abs() + opts.alignment_tolerance_rad,
        )
        .abs();
        s.delta_c2_half_width = hw;
        dc2_var.push((dc2_idx[&k], hw * hw / 3.0));
    }
    for (j, v) in dc2_var {
        if let Some(b) = inp.blocks.iter_mut().find(|(f, _)| *f == j) {
            b.1[(0, 0)] = v;
        }
    }

    // Requested subset, report order.
    let order: Vec<Term> = CENTRIFUGE_TERMS
        .iter()
        .copied()
        .filter(|t| combos.contains_key(t))
        .filter(|t| opts.terms.as_ref().is_none_or(|r| r.contains(t)))
        .collect();
    let n_in = inp.names.len();
    let rows: Vec<Combo> = order.iter().map(|t| combos[t].0.clone()).collect();
    let k1_0 = opts.k1.value;
    let f = |x: &DVector<f64>| {
        DVector::from_iterator(
            rows.len(),
            rows.iter()
                .map(|c| x[k1_idx] / k1_0 * c.iter().map(|(j, a)| a * x[*j]).sum::<f64>()),
        )
    };
    let jac = |x: &DVector<f64>| {
        let mut m = DMatrix::zeros(rows.len(), n_in);
        for (r, c) in rows.iter().enumerate() {
            let sum: f64 = c.iter().map(|(j, a)| a * x[*j]).sum();
            for (j, a) in c {
                m[(r, *j)] += x[k1_idx] / k1_0 * a;
            }
            m[(r, k1_idx)] += sum / k1_0;
        }
        m
    };
    let used_dof = order
        .iter()
        .flat_map(|t| combos[t].0.iter().map(|(j, _)| inp.dof[*j]))
        .fold(f64::INFINITY, f64::min);
    // Every radius input is used by some radius quantity.
    let joint_dof = inp.dof[radius_first..radius_end]
        .iter()
        .copied()
        .fold(used_dof, f64::min);
    let inputs = Estimates::new(
        inp.names.clone(),
        DVector::from_vec(inp.values.clone()),
        inp.covariance(),
        joint_dof,
    )?;
    let x = inputs.values().clone();
    let j = jac(&x);
    // Coefficient rows: analytic (a linear combination times K1/K1_used);
    // radius rows: central differences with the steps of
    // `Estimates::map_numeric`.
    let steps: Vec<f64> = (0..n_in)
        .map(|k| 1e-6 * x[k].abs().max(inputs.u_at(k)).max(1e-12))
        .collect();
    let radius_f = |x: &DVector<f64>| radius_map.values(x);
    let mut names: Vec<String> = order.iter().map(|t| t.name().to_string()).collect();
    names.extend(radius_map.eval(&x).into_iter().map(|(n, _)| n.to_string()));
    let joint = inputs.map(
        names,
        |x| {
            let c = f(x);
            let r = radius_f(x);
            DVector::from_iterator(c.len() + r.len(), c.iter().chain(r.iter()).copied())
        },
        |x| {
            let jc = jac(x);
            let jr = numeric_jacobian(&radius_f, x, &steps);
            let mut m = DMatrix::zeros(jc.nrows() + jr.nrows(), n_in);
            m.rows_mut(0, jc.nrows()).copy_from(&jc);
            m.rows_mut(jc.nrows(), jr.nrows()).copy_from(&jr);
            m
        },
    )?;
    let coef_names: Vec<&str> = order.iter().map(|t| t.name()).collect();
    let head = joint.select(&coef_names)?;
    let coefficients = Estimates::new(
        head.names().to_vec(),
        head.values().clone(),
        head.covariance().clone(),
        used_dof,
    )?;
    let budgets = order
        .iter()
        .enumerate()
        .map(|(r, t)| {
            let cross_station = combos[t].1;
            let mut lines = Vec::new();
            let mut own = Vec::new();
            let mut dofs = Vec::new();
            for k in 0..n_in {
                let sens = j[(r, k)];
                if sens == 0.0 {
                    continue;
                }
                let u = inputs.u_at(k);
                lines.push(BudgetLine {
                    component: inp.names[k].clone(),
                    kind: inp.kind[k],
                    u,
                    sensitivity: sens,
                    contribution: sens.abs() * u,
                });
                own.push(cross_station.is_some() && inp.station[k] == cross_station);
                dofs.push(inp.dof[k]);
            }
            let paper = cross_station
                .is_some_and(|k| (stations[k].phi_rad.to_degrees() - 45.0).abs() < 1e-6);
            Budget::from_lines(t.name().to_string(), lines, &own, &dofs, paper)
        })
        .collect();
    Ok(Estimated {
        coefficients,
        joint,
        budgets,
        unsupported,
    })
}
