//! Options of the centrifuge calibration: the one [`CentrifugeOptions`]
//! (engineering units as given, radians from its accessors), how K0 and K1
//! are resolved (explicit values or the `--from` chain to a tumble result,
//! [`CentrifugeOptions::resolve`]), and the checks every option must pass.

use crate::document::ResultDocument;
use crate::error::{Error, Result};
use crate::estimation::Noise;
use crate::models::Term;
use crate::options::{check_latitude_deg, check_positive, check_range, invalid};
use crate::warning::{Warning, WarningCode};

use super::radius::ValueU;

/// A result document K0 and K1 are taken from (the 1 g calibration the
/// centrifuge run chains to): its name as the user gave it, the SHA-256 of
/// its bytes, and the document.
#[derive(Debug, Clone, PartialEq, serde::Deserialize)]
#[serde(try_from = "crate::document::file::DocumentFile")]
pub struct ChainedResult {
    /// The file as named by the user (`<stdin>` for standard input).
    pub name: String,
    /// SHA-256 of the file's bytes (hex).
    pub sha256: String,
    /// The result document (it must be a tumble result).
    pub document: ResultDocument,
}

impl TryFrom<crate::document::file::DocumentFile> for ChainedResult {
    type Error = String;

    /// The document of a file option (`from`), parsed and checked.
    fn try_from(f: crate::document::file::DocumentFile) -> std::result::Result<Self, String> {
        let (sha256, document) = f.parse()?;
        Ok(ChainedResult {
            name: f.name,
            sha256,
            document,
        })
    }
}

impl ChainedResult {
    /// Record the chain in the centrifuge result document `doc`: this file
    /// among its inputs (role `from`), the tumble result's instrument, and
    /// the decision `chained-input`.
    pub(super) fn record_in(&self, doc: &mut ResultDocument) {
        // The path as given: `-` for standard input.
        let path = if self.name == incal_io::source::STDIN_NAME {
            "-"
        } else {
            self.name.as_str()
        };
        doc.inputs.push(crate::document::InputFile {
            role: "from".into(),
            path: path.into(),
            sha256: self.sha256.clone(),
            rows: None,
        });
        // The instrument is the tumble result's: a chained result keeps
        // its serial, model and --meta pairs.
        doc.instrument = self.document.instrument.clone();
        doc.decisions.push(crate::document::Decision {
            code: crate::document::DecisionCode::ChainedInput,
            message: format!(
                "K0 and K1 from the tumble result {}{} (covariance of K0 and K1 included)",
                self.name,
                self.document
                    .instrument
                    .serial
                    .as_ref()
                    .map_or(String::new(), |s| format!(" of serial {s}"))
            ),
        });
    }
}

/// Options of the centrifuge procedure ([`super::CentrifugeTest`]) and of
/// [`calibrate`](super::calibrate), in engineering units as given; the
/// radians come from [`CentrifugeOptions::latitude_rad`] and
/// [`CentrifugeOptions::alignment_tolerance_rad`].
///
/// K0 and K1 with their u come from `k0`/`u_k0` and `k1`/`u_k1`, or
/// from the tumble result `from` (`coefficients.K0`, `coefficients.K1` and
/// their covariance). An explicit value wins over `from`; an explicit
/// value without its u is taken as exact with a warning (never a silent
/// 0); a u without its value is refused when the value comes from `from`.
/// The covariance of K0 and K1 is taken from `from` when both come from
/// it, else `cov_k0_k1` (with explicit `k0` and `k1`; default 0).
/// [`CentrifugeOptions::resolve`] settles them.
///
/// In the document's `options` (as used, [`crate::procedures::Procedure::recorded`]):
/// `k0`, `u_k0`, `k1`, `u_k1`, `cov_k0_k1`, `radius_m`, `latitude_deg`,
/// `gravity_m_s2`, `opposite_sense`, `order`, `alignment_tolerance_deg`,
/// `noise` (σ of one output sample, output units, or null for "from the
/// data"), `u_omega_ppm`; `terms` and `from` are not recorded (the chained
/// file is among the document's inputs).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct CentrifugeOptions {
    /// The tumble result K0 and K1 come from, if any: the file as a
    /// front end read it (name, SHA-256, text; the CLI's `--from`).
    #[serde(default, skip_serializing)]
    #[schemars(with = "Option<crate::document::file::DocumentFile>")]
    pub from: Option<ChainedResult>,
    /// Bias K0 (g) from the 1 g calibration; overrides `from`.
    #[serde(default)]
    pub k0: Option<f64>,
    /// Standard uncertainty of K0 (g); with `k0`.
    #[serde(default)]
    pub u_k0: Option<f64>,
    /// Scale factor K1 (output/g) from the 1 g calibration; overrides `from`.
    #[serde(default)]
    pub k1: Option<f64>,
    /// Standard uncertainty of K1 (output/g); with `k1`.
    #[serde(default)]
    pub u_k1: Option<f64>,
    /// Covariance of K0 and K1 (g·output/g), e.g. from the calibration
    /// they came from; with explicit `k0` and `k1` (default 0).
    #[serde(default)]
    pub cov_k0_k1: Option<f64>,
    /// Nominal test radius R0 (m): start of the regression iteration.
    pub radius_m: f64,
    /// Latitude Φ (deg, north positive).
    pub latitude_deg: f64,
    /// Local gravity g_L (m/s²): the g unit of every coefficient.
    #[serde(default = "standard_gravity")]
    pub gravity_m_s2: f64,
    /// The table spins opposite to Earth's sense.
    #[serde(default)]
    pub opposite_sense: bool,
    /// Model order of the radius regression and the station fits (2 or 3).
    #[serde(default = "default_order")]
    pub order: usize,
    /// Bound of the fixture angle error (deg, ≥ 0), for the type-B Δc2.
    #[serde(default)]
    pub alignment_tolerance_deg: f64,
    /// Output noise policy (σ of one sample, output units; null: from the data).
    #[serde(default)]
    pub noise: Noise,
    /// Coefficients required (`None`: every one the data supports); not
    /// recorded in the document.
    #[serde(default, skip_serializing)]
    pub terms: Option<Vec<Term>>,
    /// Relative standard uncertainty of the table rate (ppm, 0…1e5): a
    /// type-B input of the static (eq. 6) radius, `u(R)/R = 2 u(ω)/ω`.
    #[serde(default)]
    pub u_omega_ppm: f64,
}

fn standard_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}

fn default_order() -> usize {
    3
}

/// The options as used and the warnings of how K0 and K1 were chosen.
#[derive(Debug, Clone, PartialEq)]
pub struct Resolved {
    /// The options with `k0`, `u_k0`, `k1`, `u_k1` and `cov_k0_k1` as
    /// used (every one given) and no `from`.
    pub options: CentrifugeOptions,
    /// Warnings about K0 and K1 (an explicit value without its u).
    pub warnings: Vec<Warning>,
}

impl CentrifugeOptions {
    /// Latitude Φ (rad).
    pub fn latitude_rad(&self) -> f64 {
        self.latitude_deg.to_radians()
    }

    /// Bound of the fixture angle error (rad).
    pub fn alignment_tolerance_rad(&self) -> f64 {
        self.alignment_tolerance_deg.to_radians()
    }

    /// K0 (g) with its u as given (NaN when not given: resolve first).
    pub fn k0_u(&self) -> ValueU {
        ValueU {
            value: self.k0.unwrap_or(f64::NAN),
            u: self.u_k0.unwrap_or(0.0),
        }
    }

    /// K1 (output/g) with its u as given (NaN when not given: resolve first).
    pub fn k1_u(&self) -> ValueU {
        ValueU {
            value: self.k1.unwrap_or(f64::NAN),
            u: self.u_k1.unwrap_or(0.0),
        }
    }

    /// The covariance of K0 and K1 as given (0 when not given).
    pub fn cov_k0_k1(&self) -> f64 {
        self.cov_k0_k1.unwrap_or(0.0)
    }

    /// K0 or K1 (`name`) from its explicit value and u or from the result
    /// `from`; `key`/`ukey` name the options.
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
                        return invalid(
                            ukey,
                            format!(
                                "must be >= 0 and below {bound}, got {}",
                                crate::error::short_number(&u.to_string())
                            ),
                        );
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
                    return invalid(
                        ukey,
                        format!(
                            "goes with {key} (the u of a chained result comes from that result)"
                        ),
                    );
                }
                let c = f.document.coefficients.get(name).ok_or_else(|| {
                    Error::Unsupported(format!("$.coefficients.{name}: missing")).in_file(&f.name)
                })?;
                Ok(ValueU {
                    value: c.value,
                    u: c.u,
                })
            }
            (None, None) => invalid(
                key,
                format!("give {key} (with {ukey}) or a tumble result to chain to (from)"),
            ),
        }
    }

    /// The options as used: K0 and K1 chosen as the type docs say (with
    /// the warnings of that choice), every other option as given.
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
        let k0 = self.pick("k0", "u_k0", "K0", self.k0, self.u_k0, &mut warnings)?;
        let k1 = self.pick("k1", "u_k1", "K1", self.k1, self.u_k1, &mut warnings)?;
        // The covariance holds only when both come from the same result.
        let cov_k0_k1 = match (&self.from, self.k0, self.k1, self.cov_k0_k1) {
            (_, Some(_), Some(_), Some(c)) => c,
            (_, _, _, Some(_)) => return invalid(
                "cov_k0_k1",
                "goes with k0 and k1 (the covariance of a chained result comes from that result)",
            ),
            (Some(f), None, None, None) => f.document.covariance("K0", "K1").ok_or_else(|| {
                Error::Unsupported("$.correlation: no entry for K0 and K1".into()).in_file(&f.name)
            })?,
            _ => 0.0,
        };
        Ok(Resolved {
            options: CentrifugeOptions {
                from: None,
                k0: Some(k0.value),
                u_k0: Some(k0.u),
                k1: Some(k1.value),
                u_k1: Some(k1.u),
                cov_k0_k1: Some(cov_k0_k1),
                radius_m: self.radius_m,
                latitude_deg: self.latitude_deg,
                gravity_m_s2: self.gravity_m_s2,
                opposite_sense: self.opposite_sense,
                order: self.order,
                alignment_tolerance_deg: self.alignment_tolerance_deg,
                noise: self.noise,
                terms: self.terms.clone(),
                u_omega_ppm: self.u_omega_ppm,
            },
            warnings,
        })
    }
}

/// Refuse options the reduction cannot use (finite K0 and K1, K1 ≠ 0,
/// u ≥ 0, |cov(K0, K1)| ≤ u(K0)·u(K1), positive radius and gravity,
/// latitude within ±90°, order 2 or 3, …), naming the option. `o` as
/// resolved ([`CentrifugeOptions::resolve`]).
pub(super) fn check_options(o: &CentrifugeOptions) -> Result<()> {
    let (k0, k1, cov) = (o.k0_u(), o.k1_u(), o.cov_k0_k1());
    let num = |v: f64| crate::error::short_number(&v.to_string());
    if !k0.value.is_finite() {
        return invalid(
            "k0",
            format!("must be a finite number, got {}", num(k0.value)),
        );
    }
    if !(k1.value.is_finite() && k1.value != 0.0) {
        return invalid(
            "k1",
            format!("must be a finite, non-zero number, got {}", num(k1.value)),
        );
    }
    for (key, u) in [("u_k0", k0.u), ("u_k1", k1.u)] {
        if !(u.is_finite() && u >= 0.0) {
            return invalid(
                key,
                format!("must be a non-negative number, got {}", num(u)),
            );
        }
    }
    if !cov.is_finite() || cov.abs() > k0.u * k1.u * (1.0 + 1e-9) {
        return invalid(
            "cov_k0_k1",
            format!(
                "must be finite and at most u(K0)·u(K1) in magnitude, got {}",
                num(cov)
            ),
        );
    }
    check_positive("radius_m", o.radius_m)?;
    check_positive("gravity_m_s2", o.gravity_m_s2)?;
    check_latitude_deg(o.latitude_deg)?;
    // A tolerance is a small angle; the plan refuses one above 10 deg too.
    if !(o.alignment_tolerance_deg.is_finite() && (0.0..=10.0).contains(&o.alignment_tolerance_deg))
    {
        return invalid(
            "alignment_tolerance_deg",
            format!(
                "must be within 0..10 deg, got {}",
                num(o.alignment_tolerance_deg)
            ),
        );
    }
    o.noise.validate()?;
    check_u_omega_ppm(o.u_omega_ppm)?;
    check_order(o.order)
}

/// Refuse a model order other than 2 or 3 (option `order`).
pub(super) fn check_order(order: usize) -> Result<()> {
    if (2..=3).contains(&order) {
        Ok(())
    } else {
        invalid(
            "order",
            format!("the model order must be 2 or 3, got {order}"),
        )
    }
}

/// Largest relative standard uncertainty of the table rate (ppm, 10 %).
const MAX_U_OMEGA_PPM: f64 = 1e5;

/// Refuse a relative u of the table rate outside 0…1e5 ppm (option
/// `u_omega_ppm`).
pub(super) fn check_u_omega_ppm(u_omega_ppm: f64) -> Result<()> {
    check_range("u_omega_ppm", u_omega_ppm, 0.0, MAX_U_OMEGA_PPM, "ppm")
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn key_of(r: Result<impl std::fmt::Debug>) -> String {
        crate::options::refused_key(r)
    }

    #[test]
    fn options_round_trip_the_document_and_name_a_bad_key() {
        // The document's options of `incal centrifuge --k0 1.2e-4 --u-k0 2e-6
        // --k1 1.3 --u-k1 1.3e-6 --radius-m 0.71 --latitude-deg 39.9`.
        let doc = json!({"alignment_tolerance_deg": 0.0, "cov_k0_k1": 0.0,
            "gravity_m_s2": 9.80665, "k0": 1.2e-4, "k1": 1.3, "latitude_deg": 39.9,
            "noise": null, "opposite_sense": false, "order": 3, "radius_m": 0.71,
            "u_k0": 2e-6, "u_k1": 1.3e-6, "u_omega_ppm": 0.0});
        let given: CentrifugeOptions = crate::options::from_json(&json!({"k0": 1.2e-4,
            "u_k0": 2e-6, "k1": 1.3, "u_k1": 1.3e-6, "radius_m": 0.71, "latitude_deg": 39.9}))
        .unwrap();
        let used = given.resolve().unwrap().options;
        assert_eq!(serde_json::to_value(&used).unwrap(), doc);
        let back: CentrifugeOptions = crate::options::from_json(&doc).unwrap();
        assert_eq!(back, used);
        assert_eq!(back.resolve().unwrap().options, used);
        assert_eq!(used.latitude_rad(), 39.9f64.to_radians());
        // A value without its u is taken as exact, with a warning.
        let mut no_u = given.clone();
        no_u.u_k1 = None;
        assert_eq!(no_u.resolve().unwrap().warnings.len(), 1);

        let from = |v: serde_json::Value| crate::options::from_json::<CentrifugeOptions>(&v);
        assert_eq!(key_of(from(json!({"radius_m": 0.71}))), "latitude_deg");
        assert_eq!(
            key_of(from(
                json!({"radius_m": 0.71, "latitude_deg": 1.0, "radius": 1.0})
            )),
            "radius"
        );
        let bad = |f: &dyn Fn(&mut CentrifugeOptions)| {
            let mut o = used.clone();
            f(&mut o);
            key_of(super::super::CentrifugeTest::validate_options(&o))
        };
        assert_eq!(bad(&|o| o.latitude_deg = 91.0), "latitude_deg");
        assert_eq!(bad(&|o| o.order = 4), "order");
        assert_eq!(bad(&|o| o.radius_m = 0.0), "radius_m");
        assert_eq!(bad(&|o| o.u_k1 = Some(2.0)), "u_k1");
        assert_eq!(bad(&|o| o.u_omega_ppm = -1.0), "u_omega_ppm");
        assert_eq!(bad(&|o| o.cov_k0_k1 = Some(1.0)), "cov_k0_k1");
        assert_eq!(bad(&|o| o.k0 = None), "k0");
        assert_eq!(
            bad(&|o| o.alignment_tolerance_deg = -1.0),
            "alignment_tolerance_deg"
        );
    }

    #[test]
    fn plan_and_simulator_options_take_the_command_line_defaults() {
        use crate::procedures::{Plan, Simulate};
        let sim: super::super::sim::CentrifugeSimOptions =
            crate::options::from_json(&json!({})).unwrap();
        assert_eq!(sim, Default::default());
        assert_eq!(sim.seed, 1);
        let v = serde_json::to_value(&sim).unwrap();
        assert_eq!(
            crate::options::from_json::<super::super::sim::CentrifugeSimOptions>(&v).unwrap(),
            sim
        );
        let mut a = Vec::new();
        super::super::CentrifugeTest::simulate(&sim, &mut a).unwrap();
        let mut b = Vec::new();
        crate::procedures::simulate_json::<super::super::CentrifugeTest>(
            &json!({"seed": 1}),
            &mut b,
        )
        .unwrap();
        assert_eq!(a, b);
        assert!(a.starts_with(b"plane,phi_deg,polarity,omega_rad_s,output\n"));
        let plan: super::super::plan::CentrifugePlanOptions =
            crate::options::from_json(&json!({"samples": 3})).unwrap();
        let doc = super::super::CentrifugeTest::plan(&plan).unwrap();
        assert_eq!(doc.options["k1"], json!(1.3));
        assert!(!doc.options.contains_key("k2"));
        let back: super::super::plan::CentrifugePlanOptions =
            crate::options::from_json(&json!(doc.options)).unwrap();
        assert_eq!(back, plan);
        let refused = |v: serde_json::Value| {
            let o: super::super::plan::CentrifugePlanOptions =
                crate::options::from_json(&v).unwrap();
            key_of(super::super::CentrifugeTest::plan(&o))
        };
        assert_eq!(refused(json!({"samples": 1})), "samples");
        assert_eq!(refused(json!({"u_k1": 2.0})), "u_k1");
        assert_eq!(
            refused(json!({"positions": ["ip:0", "ip:360"]})),
            "positions"
        );
        assert_eq!(refused(json!({"r_plus_m": 1e300})), "r_plus_m");
        assert_eq!(refused(json!({"k1": 0.0})), "k1");
    }
}
