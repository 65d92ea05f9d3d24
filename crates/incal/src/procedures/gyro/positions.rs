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

use nalgebra::{DMatrix, DVector};

use super::{earth_rate_deg_h, group, scale_noise, scale_stats, welch_satterthwaite};
use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::rigs::rate_table::sin_cos_exact;
use crate::warning::Warning;

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
}

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

/// Options of the multi-position reduction.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionsOptions {
    /// Latitude φ (rad).
    pub latitude_rad: f64,
    /// Which gyro axis is along the head axis.
    pub axial: Axial,
    /// Drift terms.
    pub terms: Vec<DriftTerm>,
    /// Noise of one output sample (output units).
    pub noise: Noise,
    /// The scale factor.
    pub scale_factor: ScaleFactor,
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
pub fn calibrate(obs: &[PositionObservation], opts: &PositionsOptions) -> Result<PositionsResult> {
    super::check_latitude(opts.latitude_rad)?;
    let terms = normalized(&opts.terms);
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
        .map(|p| earth_rate_ia_deg_h(p.0, p.1, opts.latitude_rad))
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

    let (fit, weights, coefficients, dof) = match opts.scale_factor {
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

/// Predicted uncertainties for a plan: the reduction run on noise-free
/// means (zero drift, output `K1·Ω·IA/3600`) with a known noise per sample.
/// `angles_rad × azimuths_rad` are the positions, `samples` per position.
pub fn plan(
    angles_rad: &[f64],
    azimuths_rad: &[f64],
    samples: usize,
    noise: f64,
    k1_nominal: f64,
    opts: &PositionsOptions,
) -> Result<PositionsResult> {
    crate::validity::require_plan_inputs(samples, noise, k1_nominal, "nominal K1")?;
    let mut obs = Vec::new();
    for &z in azimuths_rad {
        for &a in angles_rad {
            let e = k1_nominal * earth_rate_ia_deg_h(a, z, opts.latitude_rad) / 3600.0;
            for _ in 0..samples {
                obs.push(PositionObservation {
                    angle_rad: a,
                    azimuth_rad: z,
                    output: e,
                });
            }
        }
    }
    let o = PositionsOptions {
        noise: Noise::Known { sigma: noise },
        ..opts.clone()
    };
    calibrate(&obs, &o)
}
