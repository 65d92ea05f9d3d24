//! Multi-position test of a gyro on a dividing head with a horizontal axis
//! (IEEE Std 1431-2004 §10.3.6, IEEE Std 517-1974 drift model): bias and
//! g-sensitive drift, with the Earth rate as a known input.
//!
//! # Frame and kinematics
//! Local frame x north, y east, z up. The head axis is horizontal at
//! azimuth A (from north towards east): `d = (cos A, sin A, 0)`;
//! `h = z × d = (−sin A, cos A, 0)`. At head angle θ the input axis is
//! `IA = cos θ h + sin θ z` (θ = 0: IA horizontal; θ = 90°: IA up), the
//! second axis in the plane is `P = −sin θ h + cos θ z`, and the third gyro
//! axis lies along `d`. With `axial = sa` the spin axis SA is along `d` and
//! P is the output axis OA; with `axial = oa`, OA is along `d` and P is SA.
//!
//! The specific force is `f = (0, 0, 1)` g (the reaction to gravity), so
//! `a_I = sin θ`, `a_P = cos θ` and 0 along `d`. The Earth rate is
//! `Ω = Ω_e (cos φ, 0, sin φ)`, whose IA component is
//! `Ω·IA = Ω_e (sin φ sin θ − cos φ sin A cos θ)`.
//!
//! # Model (deg/h)
//! ```text
//! 3600 E/K1 = Ω·IA + B + D_I a_I + D_O a_O + D_S a_S
//!           + D_II a_I² + D_IO a_I a_O + D_IS a_I a_S + D_OO a_O² + D_SS a_S²
//! ```
//! (IEEE Std 517 / 1431 eq. for the acceleration-sensitive drift), K1 in
//! output/(deg/s) from the rate test. With K1 known the model is linear in
//! the drift terms: `y = 3600 Ē/K1 − Ω·IA` is fitted by
//! [`crate::estimation::fit_means`], and the uncertainty of K1 is
//! propagated by the derivative of the estimates with respect to K1
//! (JCGM 100 §5.1.2), with Welch–Satterthwaite degrees of freedom.
//!
//! With `fit_k1` the scale factor is fitted too, from the Earth-rate
//! projection: `E = K1 Ω·IA/3600 + Σ c_t x_t` with `c_t = K1 D_t/3600`,
//! linear in `(K1, c)`, then mapped to `D_t = 3600 c_t/K1`. At a single
//! azimuth the Earth-rate projection is a combination of `sin θ` and
//! `cos θ`, so K1 cannot be separated from D_I and the in-plane D_O/D_S;
//! the refusal names that combination.
//!
//! Since `a_I² + a_P² = 1` at every position, B cannot be separated from
//! `D_II + D_PP` (P = O or S by the mount); the refusal names it.

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

pub use plan::plan;

use nalgebra::{DMatrix, DVector};

use super::{earth_rate_deg_h, group, scale_noise, scale_stats, welch_satterthwaite};
use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::rigs::rate_table::sin_cos_exact;
use crate::warning::{Warning, WarningCode};

/// One sample of the multi-position test.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionObservation {
    /// Head angle θ (rad).
    pub angle_rad: f64,
    /// Azimuth A of the head axis (rad).
    pub azimuth_rad: f64,
    /// Gyro output (output units).
    pub output: f64,
}

/// Which gyro axis lies along the head axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axial {
    /// Spin axis along the head axis: P is the output axis.
    Sa,
    /// Output axis along the head axis: P is the spin axis.
    Oa,
}

impl Axial {
    /// `sa` or `oa`.
    pub fn name(self) -> &'static str {
        match self {
            Axial::Sa => "sa",
            Axial::Oa => "oa",
        }
    }
    /// Parse `sa` or `oa` (case-insensitive).
    pub fn parse(s: &str) -> Result<Axial> {
        match s.trim().to_ascii_lowercase().as_str() {
            "sa" => Ok(Axial::Sa),
            "oa" => Ok(Axial::Oa),
            other => Err(Error::Unsupported(format!(
                "unknown axial axis '{other}' (use sa or oa)"
            ))),
        }
    }
}

crate::named_enum!(Axial, [Axial::Sa, Axial::Oa]);
crate::named_enum!(DriftTerm, ALL_TERMS);

/// A term of the drift model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum DriftTerm {
    /// Bias (deg/h).
    B,
    /// Sensitivity to acceleration along IA (deg/h/g).
    DI,
    /// Along OA (deg/h/g).
    DO,
    /// Along SA (deg/h/g).
    DS,
    /// Second order, IA² (deg/h/g²).
    DII,
    /// IA·OA (deg/h/g²).
    DIO,
    /// IA·SA (deg/h/g²).
    DIS,
    /// OA² (deg/h/g²).
    DOO,
    /// SA² (deg/h/g²).
    DSS,
}

/// Every drift term, in model order.
pub const ALL_TERMS: [DriftTerm; 9] = [
    DriftTerm::B,
    DriftTerm::DI,
    DriftTerm::DO,
    DriftTerm::DS,
    DriftTerm::DII,
    DriftTerm::DIO,
    DriftTerm::DIS,
    DriftTerm::DOO,
    DriftTerm::DSS,
];

impl DriftTerm {
    /// Coefficient name (`B`, `D_I`, …).
    pub fn name(self) -> &'static str {
        match self {
            DriftTerm::B => "B",
            DriftTerm::DI => "D_I",
            DriftTerm::DO => "D_O",
            DriftTerm::DS => "D_S",
            DriftTerm::DII => "D_II",
            DriftTerm::DIO => "D_IO",
            DriftTerm::DIS => "D_IS",
            DriftTerm::DOO => "D_OO",
            DriftTerm::DSS => "D_SS",
        }
    }
    /// Parse a name (case-insensitive, `D_I` or `DI`).
    pub fn parse(s: &str) -> Result<DriftTerm> {
        let k = s.trim().to_ascii_uppercase().replace('_', "");
        ALL_TERMS
            .iter()
            .copied()
            .find(|t| t.name().replace('_', "") == k)
            .ok_or_else(|| {
                Error::Unsupported(format!(
                    "unknown drift term '{}' (terms: B, D_I, D_O, D_S, D_II, D_IO, D_IS, D_OO, D_SS)",
                    s.trim()
                ))
            })
    }
    /// Unit string.
    pub fn unit(self) -> &'static str {
        match self {
            DriftTerm::B => "deg/h",
            DriftTerm::DI | DriftTerm::DO | DriftTerm::DS => "deg/h/g",
            _ => "deg/h/g^2",
        }
    }
    /// Regressor at specific-force components `(a_I, a_O, a_S)` (g).
    pub fn regressor(self, a: [f64; 3]) -> f64 {
        let [i, o, s] = a;
        match self {
            DriftTerm::B => 1.0,
            DriftTerm::DI => i,
            DriftTerm::DO => o,
            DriftTerm::DS => s,
            DriftTerm::DII => i * i,
            DriftTerm::DIO => i * o,
            DriftTerm::DIS => i * s,
            DriftTerm::DOO => o * o,
            DriftTerm::DSS => s * s,
        }
    }
}

/// Default terms: B, D_I and the in-plane one of D_O / D_S.
pub fn default_terms(axial: Axial) -> Vec<DriftTerm> {
    match axial {
        Axial::Sa => vec![DriftTerm::B, DriftTerm::DI, DriftTerm::DO],
        Axial::Oa => vec![DriftTerm::B, DriftTerm::DI, DriftTerm::DS],
    }
}

/// Specific-force components `(a_I, a_O, a_S)` (g) at head angle θ.
pub fn specific_force(theta_rad: f64, axial: Axial) -> [f64; 3] {
    let (s, c) = sin_cos_exact(theta_rad);
    match axial {
        Axial::Sa => [s, c, 0.0],
        Axial::Oa => [s, 0.0, c],
    }
}

/// Earth-rate component along IA (deg/h): `Ω_e (sin φ sin θ − cos φ sin A cos θ)`.
pub fn earth_rate_ia_deg_h(theta_rad: f64, azimuth_rad: f64, latitude_rad: f64) -> f64 {
    let (st, ct) = sin_cos_exact(theta_rad);
    let (sa, _) = sin_cos_exact(azimuth_rad);
    let (sl, cl) = sin_cos_exact(latitude_rad);
    earth_rate_deg_h() * (sl * st - cl * sa * ct)
}

/// Scale factor of the gyro for the multi-position test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScaleFactor {
    /// Known from a rate test: value (output/(deg/s)), standard
    /// uncertainty and its degrees of freedom.
    Known {
        /// K1 (output/(deg/s)).
        k1: f64,
        /// u(K1).
        u: f64,
        /// Degrees of freedom of u(K1).
        dof: f64,
    },
    /// Fitted from the Earth-rate projection.
    Fit,
}

/// Largest head angle or azimuth (deg, in magnitude) a recording, a plan
/// or a simulation may hold.
pub const MAX_ANGLE_DEG: f64 = 1e4;

/// Head angles of the default plan: 0°, 30°, …, 330° (deg).
pub fn default_angles_deg() -> Vec<f64> {
    (0..12).map(|k| 30.0 * k as f64).collect()
}

/// A list of angles (deg) named `what`: at least one, each finite and
/// within ±[`MAX_ANGLE_DEG`].
pub(crate) fn check_angles_deg(what: &str, v: &[f64]) -> Result<()> {
    if v.is_empty() {
        return crate::options::invalid(what, "need at least 1 angle, got 0");
    }
    match v
        .iter()
        .find(|x| !(x.is_finite() && x.abs() <= MAX_ANGLE_DEG))
    {
        Some(x) => crate::options::invalid(
            what,
            format!("an angle must be finite and within ±1e4 deg, got {x}"),
        ),
        None => Ok(()),
    }
}

impl TryFrom<crate::document::file::DocumentFile> for K1Source {
    type Error = String;

    /// K1 of the gyro-rate result of a file option (`k1_from`), recorded
    /// among the inputs as role `from`.
    fn try_from(f: crate::document::file::DocumentFile) -> std::result::Result<Self, String> {
        let (sha256, doc) = f.parse()?;
        let input = crate::document::InputFile {
            role: "from".into(),
            path: f.name.clone(),
            sha256,
            rows: None,
        };
        K1Source::from_rate_result(&doc, input)
            .map_err(|e| format!("{}: {e}", incal_io::clip(&f.name)))
    }
}

/// Where the scale factor K1 of a multi-position test comes from, as a
/// front end is given it.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(try_from = "crate::document::file::DocumentFile")]
pub enum K1Source {
    /// A value (output/(deg/s)) with its standard uncertainty; without
    /// one, K1 is taken as exact and the document warns that every u
    /// derived from it is too small by its share.
    Given {
        /// K1 (output/(deg/s)), finite and non-zero.
        k1: f64,
        /// u(K1), at least 0 and smaller than |K1|.
        u: Option<f64>,
    },
    /// The K1 of a gyro-rate result document, with its u and degrees of
    /// freedom; the document is recorded among the inputs (role `from`).
    Result {
        /// K1 (output/(deg/s)).
        k1: f64,
        /// u(K1).
        u: f64,
        /// Degrees of freedom of u(K1) (infinite when the result gives none).
        dof: f64,
        /// The result document as an input of the reduction.
        input: crate::document::InputFile,
    },
    /// Fitted from the Earth-rate projection (needs several azimuths).
    Fit,
}

impl K1Source {
    /// K1 from a gyro-rate result document (`input` records that document
    /// with role `from`). Refuses a result of another procedure, one
    /// without K1, or a K1 that is not a usable scale factor.
    pub fn from_rate_result(
        doc: &crate::document::ResultDocument,
        input: crate::document::InputFile,
    ) -> Result<K1Source> {
        if doc.procedure != crate::document::Procedure::GyroRate {
            return Err(Error::Unsupported(format!(
                "K1 needs a gyro-rate result, this is a {} result",
                doc.procedure
            )));
        }
        let c = doc
            .coefficients
            .get("K1")
            .ok_or_else(|| Error::Unsupported("$.coefficients.K1: missing".into()))?;
        if !(c.value.is_finite() && c.value != 0.0 && c.u.is_finite() && c.u >= 0.0) {
            return Err(Error::Unsupported(format!(
                "$.coefficients.K1: value {} with u {} is not a usable scale factor",
                c.value, c.u
            )));
        }
        // The positions reduction divides by K1 in output/(deg/s): another
        // unit, a u as large as K1 or a dof that is not positive would
        // give confident wrong rates.
        if c.unit != crate::units::Unit::OutputPerDegS {
            return Err(Error::Unsupported(format!(
                "$.coefficients.K1.unit: '{}', not '{}' (a gyro-rate scale factor)",
                c.unit.as_str(),
                crate::units::Unit::OutputPerDegS.as_str()
            )));
        }
        if c.u >= c.value.abs() {
            return Err(Error::Unsupported(format!(
                "$.coefficients.K1.u: {} is not smaller than |K1| = {}: the scale factor is not known",
                crate::error::short_f64(c.u),
                crate::error::short_f64(c.value.abs())
            )));
        }
        if let Some(d) = c.dof {
            if d.is_nan() || d <= 0.0 {
                return Err(Error::Unsupported(format!(
                    "$.coefficients.K1.dof: {}: degrees of freedom must be positive",
                    crate::error::short_f64(d)
                )));
            }
        }
        Ok(K1Source::Result {
            k1: c.value,
            u: c.u,
            dof: c.dof.unwrap_or(f64::INFINITY),
            input,
        })
    }

    /// Refuse a K1 that is not finite or is zero, and a u(K1) that is
    /// negative or not smaller than |K1|.
    pub fn validate(&self) -> Result<()> {
        let (k1, u) = match self {
            K1Source::Given { k1, u } => (*k1, *u),
            K1Source::Result { k1, u, .. } => (*k1, Some(*u)),
            K1Source::Fit => return Ok(()),
        };
        // A recording's numbers are within 1e15 (the CSV reader's bound):
        // a scale factor beyond that either way is nothing a gyro has.
        let max = incal_io::MAX_ABS_VALUE;
        if !(k1.is_finite() && (1.0 / max..=max).contains(&k1.abs())) {
            return Err(Error::InvalidValue {
                what: "k1 (a finite scale factor, 1e-15 to 1e15 in magnitude, output/(deg/s))"
                    .into(),
                value: k1.to_string(),
            });
        }
        match u {
            Some(u) if !(u.is_finite() && u >= 0.0 && u < k1.abs()) => Err(Error::InvalidValue {
                what: "u_k1 (>= 0 and smaller than |k1|)".into(),
                value: u.to_string(),
            }),
            _ => Ok(()),
        }
    }

    /// The scale factor of the reduction.
    pub fn scale_factor(&self) -> ScaleFactor {
        match self {
            K1Source::Given { k1, u } => ScaleFactor::Known {
                k1: *k1,
                u: u.unwrap_or(0.0),
                dof: f64::INFINITY,
            },
            K1Source::Result { k1, u, dof, .. } => ScaleFactor::Known {
                k1: *k1,
                u: *u,
                dof: *dof,
            },
            K1Source::Fit => ScaleFactor::Fit,
        }
    }

    /// What the document warns about the source (a K1 without its u).
    pub fn warnings(&self) -> Vec<Warning> {
        match self {
            K1Source::Given { u: None, .. } => vec![Warning::new(
                WarningCode::MissingUncertainty,
                "k1 given without u_k1: K1 is taken as exact, and every u derived from it is too small by its share",
            )],
            _ => Vec::new(),
        }
    }
}

/// Options of the multi-position test, validated once by
/// [`GyroPositionsOptions::validate`]. In the document's `options`:
/// `{"axial": "sa", "azimuth_deg": 90.0, "latitude_deg": 45.0, "noise":
/// null, "terms": ["B", "D_I", "D_O"]}` (angles as given; `azimuth_deg`
/// null when the recording has an `azimuth_deg` column; `noise` the known
/// σ of one output sample or null; `terms` as fitted, sorted). Where K1
/// came from (`k1` and `u_k1`, `fit_k1`, or a gyro-rate result) is in the
/// document's `scale_factor` and `inputs`, not in `options`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GyroPositionsOptions {
    /// Latitude φ (deg, −90…90).
    pub latitude_deg: f64,
    /// Azimuth of the head axis (deg from north towards east) of every row
    /// of a recording without an `azimuth_deg` column.
    #[serde(default)]
    pub azimuth_deg: Option<f64>,
    /// Which gyro axis is along the head axis.
    pub axial: Axial,
    /// Drift terms (default: [`default_terms`] of the axial axis).
    #[serde(default, serialize_with = "serialize_terms")]
    #[schemars(with = "Option<Vec<DriftTerm>>")]
    pub terms: Vec<DriftTerm>,
    /// Noise of one output sample (output units).
    #[serde(default)]
    pub noise: Noise,
    /// Scale factor K1 (output/(deg/s)) from a rate test.
    #[serde(default, skip_serializing)]
    pub k1: Option<f64>,
    /// Standard uncertainty of `k1` (output/(deg/s)); without it K1 is
    /// taken as exact and the document warns.
    #[serde(default, skip_serializing)]
    pub u_k1: Option<f64>,
    /// Fit K1 from the Earth-rate projection (needs several azimuths).
    #[serde(default, skip_serializing)]
    pub fit_k1: bool,
    /// K1 of a gyro-rate result document: the file as a front end read
    /// it (name, SHA-256, text; the CLI's `--from`), taken by
    /// [`K1Source::from_rate_result`].
    #[serde(default, skip_serializing)]
    #[schemars(with = "Option<crate::document::file::DocumentFile>")]
    pub k1_from: Option<K1Source>,
}

/// The terms as fitted (sorted, without repeats; the axial axis' default
/// when none are given), as documents record them.
fn serialize_terms<S: serde::Serializer>(
    terms: &[DriftTerm],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&term_names(terms), s)
}

impl GyroPositionsOptions {
    /// The options of an axial axis with its default terms, automatic
    /// noise and K1 `k1` (output/(deg/s)) given with its u `u_k1`.
    pub fn new(latitude_deg: f64, axial: Axial, k1: f64, u_k1: Option<f64>) -> Self {
        Self {
            latitude_deg,
            azimuth_deg: None,
            axial,
            terms: default_terms(axial),
            noise: Noise::Auto,
            k1: Some(k1),
            u_k1,
            fit_k1: false,
            k1_from: None,
        }
    }

    /// Refuse options no reduction can use: a latitude outside ±90°, an
    /// azimuth that is not an angle within 1e4 deg, a known noise that is
    /// not a positive number, no source of K1 or two, a K1 or u(K1)
    /// [`K1Source::validate`] refuses.
    pub fn validate(&self) -> Result<()> {
        crate::options::check_latitude_deg(self.latitude_deg)?;
        if let Some(z) = self.azimuth_deg {
            crate::options::check_range("azimuth_deg", z, -MAX_ANGLE_DEG, MAX_ANGLE_DEG, "deg")?;
        }
        self.noise.validate()?;
        self.k1_source()?.validate()
    }

    /// Where K1 comes from: `k1` (with `u_k1`), `fit_k1`, or a gyro-rate
    /// result (`k1_from`); exactly one of them.
    pub fn k1_source(&self) -> Result<K1Source> {
        use crate::options::invalid;
        let given = [self.k1.is_some(), self.fit_k1, self.k1_from.is_some()];
        if given.iter().filter(|g| **g).count() > 1 {
            return invalid(
                if self.fit_k1 { "fit_k1" } else { "k1" },
                "give one source of K1: `k1` (with `u_k1`), `k1_from` (a gyro-rate result) or `fit_k1`",
            );
        }
        if self.u_k1.is_some() && self.k1.is_none() {
            return invalid(
                "u_k1",
                "goes with `k1` (the u of a gyro-rate result comes from the result)",
            );
        }
        match (&self.k1_from, self.k1) {
            (Some(from), _) => Ok(from.clone()),
            (None, Some(k1)) => Ok(K1Source::Given { k1, u: self.u_k1 }),
            (None, None) if self.fit_k1 => Ok(K1Source::Fit),
            (None, None) => invalid(
                "k1",
                "give `k1` (with `u_k1`), `k1_from` (a gyro-rate result) or `fit_k1`",
            ),
        }
    }

    /// Latitude φ (rad): the one conversion of the option.
    pub fn latitude_rad(&self) -> f64 {
        self.latitude_deg.to_radians()
    }

    /// The drift terms: as given, or the axial axis' default terms.
    pub fn terms(&self) -> Vec<DriftTerm> {
        if self.terms.is_empty() {
            default_terms(self.axial)
        } else {
            self.terms.clone()
        }
    }

    /// The options as recorded: the terms filled in ([`Self::terms`]).
    pub fn settled(&self) -> GyroPositionsOptions {
        GyroPositionsOptions {
            terms: self.terms(),
            ..self.clone()
        }
    }
}

/// The names of the terms as fitted (sorted, without repeats).
pub(crate) fn term_names(terms: &[DriftTerm]) -> Vec<&'static str> {
    normalized(terms).iter().map(|t| t.name()).collect()
}

/// The multi-position test as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct GyroPositions;

impl crate::procedures::Procedure for GyroPositions {
    const ID: crate::document::Procedure = crate::document::Procedure::GyroPositions;
    type Options = GyroPositionsOptions;
    type Input = Vec<PositionObservation>;

    fn example() -> GyroPositionsOptions {
        GyroPositionsOptions {
            azimuth_deg: Some(90.0),
            ..GyroPositionsOptions::new(45.0, Axial::Sa, 0.02, None)
        }
    }

    /// The example with its K1, which the document's `options` leave out
    /// (it is in the document's `scale_factor`).
    fn example_json() -> serde_json::Value {
        let o = Self::example();
        let mut v = serde_json::to_value(&o).unwrap_or_default();
        if let Some(m) = v.as_object_mut() {
            m.insert("k1".into(), o.k1.into());
        }
        v
    }

    fn validate(o: &GyroPositionsOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &GyroPositionsOptions,
    ) -> Result<Vec<PositionObservation>> {
        input::read(rows, o.azimuth_deg)
    }

    fn reduce(
        obs: &Vec<PositionObservation>,
        o: &GyroPositionsOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let k1 = o.k1_source()?;
        let r = calibrate(obs, o)?;
        let mut doc = r.document(o.noise.sigma().is_some(), k1.scale_factor(), o.axial.name())?;
        doc.warnings.extend(k1.warnings());
        if let K1Source::Result { input, .. } = &k1 {
            doc.inputs.push(input.clone());
        }
        Ok(doc)
    }

    fn recorded(
        _: &Vec<PositionObservation>,
        o: &GyroPositionsOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        crate::procedures::options_map(&o.settled())
    }

    fn synthesis(
        obs: &Vec<PositionObservation>,
        o: &GyroPositionsOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<PositionObservation>>>> {
        montecarlo::synthesis(obs, o).map(Some)
    }
}

/// One position (head angle and azimuth) of the test.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroPosition {
    /// Head angle (rad).
    pub angle_rad: f64,
    /// Azimuth (rad).
    pub azimuth_rad: f64,
    /// Earth-rate component along IA (deg/h).
    pub earth_rate_deg_h: f64,
    /// Output statistics (output units).
    pub stats: PositionStats,
    /// Residual (deg/h).
    pub residual: f64,
    /// Standardized residual.
    pub standardized_residual: f64,
}

/// Result of the multi-position test.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionsResult {
    /// Drift terms (deg/h, deg/h/g, deg/h/g²), and `K1` first when fitted.
    pub coefficients: Estimates,
    /// Effective degrees of freedom of each coefficient.
    pub dof: Vec<(String, f64)>,
    /// The fit (in deg/h with K1 known, output units with K1 fitted).
    pub fit: Fit,
    /// Positions.
    pub positions: Vec<GyroPosition>,
    /// Terms, in model order.
    pub terms: Vec<DriftTerm>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

fn normalized(terms: &[DriftTerm]) -> Vec<DriftTerm> {
    let mut t = terms.to_vec();
    t.sort();
    t.dedup();
    t
}

/// Group samples into positions (angle, azimuth), order of first appearance.
pub fn positions_of(obs: &[PositionObservation]) -> Result<Vec<(f64, f64, PositionStats)>> {
    for o in obs {
        if !(o.angle_rad.is_finite() && o.azimuth_rad.is_finite() && o.output.is_finite()) {
            return Err(Error::InvalidValue {
                what: "angle, azimuth or output".into(),
                value: format!("{} / {} / {}", o.angle_rad, o.azimuth_rad, o.output),
            });
        }
    }
    group(
        obs.iter()
            .map(|o| ((o.angle_rad.to_bits(), o.azimuth_rad.to_bits()), o.output)),
    )
    .into_iter()
    .map(|((a, z), v)| Ok((f64::from_bits(a), f64::from_bits(z), PositionStats::of(&v)?)))
    .collect()
}

/// Reduce a multi-position test (module docs).
pub fn calibrate(
    obs: &[PositionObservation],
    opts: &GyroPositionsOptions,
) -> Result<PositionsResult> {
    opts.validate()?;
    let latitude_rad = opts.latitude_rad();
    let scale_factor = opts.k1_source()?.scale_factor();
    let terms = normalized(&opts.terms());
    if terms.is_empty() {
        return Err(Error::TooFew {
            what: "drift terms".into(),
            needed: 1,
            got: 0,
        });
    }
    let pos = positions_of(obs)?;
    let earth: Vec<f64> = pos
        .iter()
        .map(|p| earth_rate_ia_deg_h(p.0, p.1, latitude_rad))
        .collect();
    let rows: Vec<Vec<f64>> = pos
        .iter()
        .map(|p| {
            let a = specific_force(p.0, opts.axial);
            terms.iter().map(|t| t.regressor(a)).collect()
        })
        .collect();
    let names: Vec<String> = terms.iter().map(|t| t.name().to_string()).collect();
    let stats: Vec<PositionStats> = pos.iter().map(|p| p.2).collect();
    let n = pos.len();

    let (fit, weights, coefficients, dof) = match scale_factor {
        ScaleFactor::Known { k1, u, dof } => {
            if !(k1.is_finite() && k1 != 0.0) {
                return Err(Error::InvalidValue {
                    what: "scale factor K1 (must be finite and non-zero)".into(),
                    value: k1.to_string(),
                });
            }
            if !(u.is_finite() && u >= 0.0) {
                return Err(Error::InvalidValue {
                    what: "u(K1) (must be finite and >= 0)".into(),
                    value: u.to_string(),
                });
            }
            let design = Design::new(
                names.clone(),
                DMatrix::from_fn(n, terms.len(), |i, j| rows[i][j]),
            )?;
            let run = |k: f64| -> Result<(Fit, DVector<f64>)> {
                let s = 3600.0 / k;
                let st: Vec<PositionStats> = stats
                    .iter()
                    .zip(&earth)
                    .map(|(p, e)| {
                        let mut q = scale_stats(p, s);
                        q.mean -= e;
                        q
                    })
                    .collect();
                fit_means(&design, &st, scale_noise(opts.noise, s))
            };
            let (fit, w) = run(k1)?;
            // Derivative of the estimates with respect to K1: the fit is
            // linear in 1/K1, so a central difference is exact to rounding.
            let h = k1.abs() * 1e-6;
            let (fp, _) = run(k1 + h)?;
            let (fm, _) = run(k1 - h)?;
            let j = (fp.estimates.values() - fm.estimates.values()) / (2.0 * h);
            let e = &fit.estimates;
            let cov = e.covariance() + &j * j.transpose() * (u * u);
            let coefficients = Estimates::new(names.clone(), e.values().clone(), cov, e.dof())?;
            let dof = names
                .iter()
                .enumerate()
                .map(|(k, nm)| {
                    (
                        nm.clone(),
                        welch_satterthwaite(&[(e.u_at(k), e.dof()), (j[k].abs() * u, dof)]),
                    )
                })
                .collect();
            (fit, w, coefficients, dof)
        }
        ScaleFactor::Fit => {
            let mut all = vec!["K1".to_string()];
            all.extend(names.iter().cloned());
            let design = Design::new(
                all.clone(),
                DMatrix::from_fn(n, terms.len() + 1, |i, j| {
                    if j == 0 {
                        earth[i] / 3600.0
                    } else {
                        rows[i][j - 1]
                    }
                }),
            )?;
            let (fit, w) = fit_means(&design, &stats, opts.noise)?;
            let k1 = fit.estimates.values()[0];
            if k1 == 0.0 || !k1.is_finite() {
                return Err(Error::InvalidValue {
                    what: "fitted scale factor K1".into(),
                    value: k1.to_string(),
                });
            }
            let coefficients = fit.estimates.map_numeric(all.clone(), |x| {
                DVector::from_iterator(
                    x.len(),
                    x.iter()
                        .enumerate()
                        .map(|(k, v)| if k == 0 { *v } else { 3600.0 * v / x[0] }),
                )
            })?;
            let d = fit.estimates.dof();
            let dof = all.iter().map(|nm| (nm.clone(), d)).collect();
            (fit, w, coefficients, dof)
        }
    };
    let warnings = fit.quality_warnings(
        "index-angle errors of the head, drift during the test, or an unmodelled g-sensitive term",
    );
    let std_res = fit.standardized_residuals(Some(&weights));
    let positions = pos
        .iter()
        .enumerate()
        .map(|(i, p)| GyroPosition {
            angle_rad: p.0,
            azimuth_rad: p.1,
            earth_rate_deg_h: earth[i],
            stats: p.2,
            residual: fit.residuals[i],
            standardized_residual: std_res[i],
        })
        .collect();
    Ok(PositionsResult {
        coefficients,
        dof,
        fit,
        positions,
        terms,
        warnings,
    })
}
