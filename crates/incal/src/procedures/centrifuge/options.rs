//! Options of the centrifuge calibration: the reduction's
//! [`CentrifugeOptions`], the front end's [`CentrifugeRun`] and how it
//! resolves K0 and K1 (explicit values or the `--from` chain to a tumble
//! result), and the checks every option must pass.

use crate::document::ResultDocument;
use crate::error::{Error, Result};
use crate::estimation::Noise;
use crate::models::Term;
use crate::warning::{Warning, WarningCode};

use super::radius::ValueU;

/// Options of [`calibrate`](super::calibrate).
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
    /// Options of [`calibrate`](super::calibrate).
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

/// Refuse options the reduction cannot use (finite K0 and K1, K1 ≠ 0,
/// u ≥ 0, |cov(K0, K1)| ≤ u(K0)·u(K1), positive radius and gravity,
/// order 2 or 3, …).
pub(super) fn check_options(o: &CentrifugeOptions) -> Result<()> {
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
pub(super) fn check_order(order: usize) -> Result<()> {
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
pub(super) fn check_u_omega_ppm(u_omega_ppm: f64) -> Result<()> {
    if u_omega_ppm.is_finite() && (0.0..=MAX_U_OMEGA_PPM).contains(&u_omega_ppm) {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            what: "u_omega_ppm (within 0..1e5)".into(),
            value: u_omega_ppm.to_string(),
        })
    }
}
