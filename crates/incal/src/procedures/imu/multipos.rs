//! IMU triad calibration by least squares over known orientations (a
//! dividing head, a cube on a surface plate: 6, 12, 18, 24… positions),
//! with rotations of a known angle for the gyro scale.
//!
//! # Model (per axis j, on position means)
//! Accelerometer: `ā_j = b_j + Σ_k A_jk f_k`, `f = g·û` (û the known up
//! direction in the IMU frame). `--matrix full`: all nine `A_jk`;
//! `upper`: `A` upper-triangular (the IMU frame is the accelerometers'
//! own: x along the x accelerometer, y in the x–y accelerometer plane).
//! The scale factors are `S_j = A_jj` and the misalignments (cross-axis
//! sensitivities, rad) `M_jk = A_jk / A_jj`.
//!
//! Gyro: `ω̄_j = b_j + Σ_k G_jk f_k + Σ_k A_jk ω_k` with `ω` in deg/s:
//! the Earth rate `Ω (cos φ n̂ + sin φ û)` in a static position when the
//! latitude and the north direction n̂ are given, and `A/T · ê_axis` in a
//! rotation section (`x_rot`, `y_rot`, `z_rot`: one rotation of the known
//! angle A about that axis, pointing up, taking T = n/F_s seconds). `b`
//! and the g-sensitivity `G` always; `A` (scale `S_j = A_jj`,
//! misalignment `M_jk = A_jk/A_jj`) only when rotations or the Earth rate
//! make it observable.
//!
//! Means are weighted by `n / s²` with s² the pooled within-position
//! variance of the static positions, kept unless the residuals show lack of
//! fit (χ², 5 %); a position set that cannot separate a term is refused
//! naming the term (the core's alias analysis).

use nalgebra::{DMatrix, DVector};

use super::{check_gravity_magnitude, check_rate_hz, SectionStats, AXES, V3};
use crate::error::{Error, Result};
use crate::estimation::{fit, numeric_jacobian, Design, Estimates, Fit, FitOptions, Variance};
use crate::units::EARTH_RATE_RAD_S;
use crate::warning::Warning;

/// Accelerometer matrix convention (`full` or `upper` in documents).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum MatrixForm {
    /// Nine elements.
    #[default]
    Full,
    /// Upper-triangular (six elements).
    Upper,
}

impl MatrixForm {
    /// `full` or `upper`.
    pub fn name(self) -> &'static str {
        match self {
            MatrixForm::Full => "full",
            MatrixForm::Upper => "upper",
        }
    }
}

/// One static position.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticPosition {
    /// Label (as in the file, or the fx,fy,fz triple).
    pub label: String,
    /// Up direction in the IMU frame (unit vector: the specific force's).
    pub up: V3,
    /// North direction in the IMU frame, when known.
    pub north: Option<V3>,
    /// Samples (accelerometer then gyro channels; a missing triad is 0).
    pub stats: SectionStats,
}

/// One rotation section.
#[derive(Debug, Clone, PartialEq)]
pub struct RotationSection {
    /// Label (`x_rot`, `y_rot`, `z_rot`).
    pub label: String,
    /// IMU axis of the rotation (0, 1, 2), pointing up.
    pub axis: usize,
    /// Samples.
    pub stats: SectionStats,
}

/// Options of [`multipos`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MultiposOptions {
    /// Gravity (m/s²).
    pub gravity: f64,
    /// Accelerometer matrix convention.
    pub matrix: MatrixForm,
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Latitude (deg) for the Earth rate (needs the north direction).
    pub latitude_deg: Option<f64>,
    /// Rotation angle of each rotation section (deg).
    pub rotation_deg: f64,
    /// Whether the session has gyro channels.
    pub gyro: bool,
}

/// Options of the [`Multipos`] procedure (a session read from a file; the
/// session tells whether there is a gyro). In the document:
/// `{"gravity_m_s2", "matrix", "rate_hz", "latitude_deg", "rotation_deg"}`
/// (`latitude_deg` null when not given). Defaults (JSON callers, as the
/// CLI): g 9.80665 m/s², matrix `full`, no latitude, A −360 deg.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct MultiposSessionOptions {
    /// Gravity magnitude (m/s², > 0).
    #[serde(default = "standard_gravity")]
    pub gravity_m_s2: f64,
    /// Accelerometer matrix convention.
    #[serde(default)]
    pub matrix: MatrixForm,
    /// Sample rate (Hz): times the rotations. `None`: the rate of the
    /// session's `time_s` stamps (a session without them is then refused);
    /// given, it must agree with them.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Latitude φ (deg) for the Earth rate (the session then needs the
    /// north direction, `nx, ny, nz`).
    #[serde(default)]
    pub latitude_deg: Option<f64>,
    /// Rotation angle of each rotation section (deg; −360 is clockwise
    /// seen from the axis tip).
    #[serde(default = "imucal_rotation_deg")]
    pub rotation_deg: f64,
}

fn standard_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}

fn imucal_rotation_deg() -> f64 {
    -360.0
}

impl MultiposSessionOptions {
    /// Refuse options the method cannot use ([`crate::Error::InvalidOption`]
    /// naming the key): a gravity outside (0, 100], a sample rate outside
    /// (0, 1e6] Hz, a latitude beyond ±90 deg, a rotation angle that is
    /// zero or beyond ±36 000 deg.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.rate_hz {
            super::check_rate_hz(r)?;
        }
        super::check_gravity_magnitude(self.gravity_m_s2)?;
        super::check_rotation_deg(self.rotation_deg)?;
        if let Some(lat) = self.latitude_deg {
            crate::options::check_latitude_deg(lat)?;
        }
        Ok(())
    }

    /// The options of [`multipos`] for a session with (`gyro`) or without
    /// gyro columns, at the session's sample rate `rate_hz` (Hz; `None`
    /// for a session without rotations, which need no rate: NaN, refused by
    /// [`multipos`] only where rotations are timed).
    pub fn model(&self, gyro: bool, rate_hz: Option<f64>) -> MultiposOptions {
        MultiposOptions {
            gravity: self.gravity_m_s2,
            matrix: self.matrix,
            rate_hz: rate_hz.unwrap_or(f64::NAN),
            latitude_deg: self.latitude_deg,
            rotation_deg: self.rotation_deg,
            gyro,
        }
    }
}

/// The multi-position calibration as one [`crate::procedures::Procedure`]:
/// a session CSV ([`super::input::read_multipos`]) into the result
/// document ([`MultiposResult::document`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Multipos;

impl crate::procedures::Procedure for Multipos {
    const ID: crate::document::Procedure = crate::document::Procedure::ImuMultipos;
    type Options = MultiposSessionOptions;
    type Input = super::input::MultiposInput;

    fn example() -> MultiposSessionOptions {
        MultiposSessionOptions {
            gravity_m_s2: 9.81,
            matrix: MatrixForm::Full,
            rate_hz: Some(100.0),
            latitude_deg: None,
            rotation_deg: -360.0,
        }
    }

    fn validate(o: &MultiposSessionOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &MultiposSessionOptions,
    ) -> Result<Self::Input> {
        super::input::read_multipos(rows, o.latitude_deg.is_some(), o.rate_hz)
    }

    fn recorded(
        input: &Self::Input,
        o: &MultiposSessionOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        crate::procedures::options_map(&MultiposSessionOptions {
            rate_hz: input.rate_hz,
            ..*o
        })
    }

    fn reduce(
        input: &Self::Input,
        o: &MultiposSessionOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let mut doc = multipos(
            &input.statics,
            &input.rotations,
            &o.model(input.gyro, input.rate_hz),
        )?
        .document()?;
        if let Some(tb) = &input.timebase {
            doc.warnings.extend(tb.warnings());
        }
        doc.warnings.extend(input.warnings.iter().cloned());
        Ok(doc)
    }

    fn synthesis(
        input: &Self::Input,
        o: &MultiposSessionOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Self::Input>>> {
        super::montecarlo::multipos_synthesis(input, o).map(Some)
    }
}

/// Result of [`multipos`].
#[derive(Debug, Clone)]
pub struct MultiposResult {
    /// Every parameter (`acc.b_x`, `acc.A_xy`, `acc.S_x`, `acc.M_xy`,
    /// `gyr.b_x`, `gyr.G_xy`, `gyr.A_xy`, `gyr.S_x`, `gyr.M_xy`).
    pub estimates: Estimates,
    /// The six (or three) axis fits: `acc.x`, …, `gyr.z`.
    pub fits: Vec<(String, Fit)>,
    /// The positions used.
    pub statics: Vec<StaticPosition>,
    /// The rotations used.
    pub rotations: Vec<RotationSection>,
    /// Whether the gyro scale and misalignment were estimated.
    pub gyro_scale: bool,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// Options.
    pub options: MultiposOptions,
}

/// Channel `ch`'s variance pooled within the static positions and its
/// degrees of freedom `Σ(n − 1)` (0 when there are none).
pub(super) fn pooled(statics: &[StaticPosition], ch: usize) -> (f64, f64) {
    let mut s = 0.0;
    let mut d = 0.0;
    for p in statics {
        let w = (p.stats.n - 1) as f64;
        s += w * p.stats.cov[ch][ch];
        d += w;
    }
    (if d > 0.0 { s / d } else { 0.0 }, d)
}

/// Fit one axis: rows `x`, means `y`, counts `n`, channel `ch` (for the
/// pooled variance); names of the columns.
fn axis_fit(
    names: Vec<String>,
    rows: &[Vec<f64>],
    y: &[f64],
    n: &[f64],
    statics: &[StaticPosition],
    ch: usize,
) -> Result<Fit> {
    let design = Design::from_rows(names, rows)?;
    let (s2, dof) = pooled(statics, ch);
    let (w, variance) = if s2 > 0.0 && dof > 0.0 {
        (
            DVector::from_iterator(n.len(), n.iter().map(|k| k / s2)),
            Variance::AtLeast { dof },
        )
    } else {
        (
            DVector::from_iterator(n.len(), n.iter().copied()),
            Variance::FromResiduals,
        )
    };
    fit(
        &design,
        &DVector::from_vec(y.to_vec()),
        &FitOptions {
            weights: Some(w),
            variance,
            ..FitOptions::default()
        },
    )
}

/// Block-diagonal concatenation of estimates.
fn concat(parts: &[Estimates]) -> Result<Estimates> {
    let n: usize = parts.iter().map(|e| e.len()).sum();
    let mut names = Vec::with_capacity(n);
    let mut v = DVector::zeros(n);
    let mut c = DMatrix::zeros(n, n);
    let mut at = 0;
    let mut dof = f64::INFINITY;
    for e in parts {
        let m = e.len();
        names.extend(e.names().iter().cloned());
        v.rows_mut(at, m).copy_from(e.values());
        c.view_mut((at, at), (m, m)).copy_from(e.covariance());
        dof = dof.min(e.dof());
        at += m;
    }
    Estimates::new(names, v, c, dof)
}

/// Refuse a position with fewer than 2 samples or an up direction that
/// is not a unit vector, naming it.
fn check_positions(statics: &[StaticPosition]) -> Result<()> {
    for p in statics {
        if p.stats.n < 2 {
            return Err(Error::TooFew {
                what: format!("samples in position {}", p.label),
                needed: 2,
                got: p.stats.n,
            });
        }
        if (p.up.norm() - 1.0).abs() > 1e-3 {
            return Err(Error::InvalidValue {
                what: format!(
                    "up direction of position {} (must be a unit vector)",
                    p.label
                ),
                value: format!("norm {}", p.up.norm()),
            });
        }
    }
    Ok(())
}

/// The accelerometer fit of axis `j`: `ā_j = b_j + Σ_k A_jk g û_k` over
/// the positions (`k ≥ j` only for `--matrix upper`).
fn acc_axis(statics: &[StaticPosition], opts: &MultiposOptions, j: usize) -> Result<Fit> {
    let g = opts.gravity;
    let ks: Vec<usize> = match opts.matrix {
        MatrixForm::Full => vec![0, 1, 2],
        MatrixForm::Upper => (j..3).collect(),
    };
    let mut names = vec![format!("acc.b_{}", AXES[j])];
    names.extend(ks.iter().map(|&k| format!("acc.A_{}{}", AXES[j], AXES[k])));
    let rows: Vec<Vec<f64>> = statics
        .iter()
        .map(|p| {
            let mut r = vec![1.0];
            r.extend(ks.iter().map(|&k| g * p.up[k]));
            r
        })
        .collect();
    let y: Vec<f64> = statics.iter().map(|p| p.stats.mean[j]).collect();
    let n: Vec<f64> = statics.iter().map(|p| p.stats.n as f64).collect();
    axis_fit(names, &rows, &y, &n, statics, j)
}

/// The Earth rate in a position (deg/s, IMU frame) when the latitude and
/// the position's north are given, else zero.
fn earth_rate(opts: &MultiposOptions, p: &StaticPosition) -> V3 {
    match (opts.latitude_deg, p.north) {
        (Some(lat), Some(n)) => {
            let phi = lat.to_radians();
            (n * phi.cos() + p.up * phi.sin()) * EARTH_RATE_RAD_S.to_degrees()
        }
        _ => V3::zeros(),
    }
}

/// The gyro fit of axis `j` (module docs): bias and g-sensitivity over
/// the positions and rotations, and the scale terms `A_jk` when
/// `gyro_scale` (the Earth rate in the positions, `A/T` about the axis of
/// each rotation).
fn gyro_axis(
    statics: &[StaticPosition],
    rotations: &[RotationSection],
    opts: &MultiposOptions,
    gyro_scale: bool,
    j: usize,
) -> Result<Fit> {
    let g = opts.gravity;
    let mut names = vec![format!("gyr.b_{}", AXES[j])];
    names.extend((0..3).map(|k| format!("gyr.G_{}{}", AXES[j], AXES[k])));
    if gyro_scale {
        names.extend((0..3).map(|k| format!("gyr.A_{}{}", AXES[j], AXES[k])));
    }
    let mut rows = Vec::new();
    let mut y = Vec::new();
    let mut n = Vec::new();
    for p in statics {
        let mut r = vec![1.0];
        r.extend((0..3).map(|k| g * p.up[k]));
        if gyro_scale {
            let w = earth_rate(opts, p);
            r.extend((0..3).map(|k| w[k]));
        } else {
            // The Earth rate is left in the bias when the scale is
            // not estimated (it is below MEMS resolution).
        }
        rows.push(r);
        y.push(p.stats.mean[3 + j]);
        n.push(p.stats.n as f64);
    }
    for r in rotations {
        let t = r.stats.n as f64 / opts.rate_hz;
        let mut up = V3::zeros();
        up[r.axis] = 1.0;
        let mut row = vec![1.0];
        row.extend((0..3).map(|k| g * up[k]));
        row.extend((0..3).map(|k| {
            if k == r.axis {
                opts.rotation_deg / t
            } else {
                0.0
            }
        }));
        rows.push(row);
        y.push(r.stats.mean[3 + j]);
        n.push(r.stats.n as f64);
    }
    axis_fit(names, &rows, &y, &n, statics, 3 + j)
}

/// The derived terms of `base`: for each triad fitted with a scale, the
/// scale factors `S_j = A_jj` then the misalignments `M_jk = A_jk / A_jj`;
/// their names and the indices `(A_jj, None)` or `(A_jj, Some(A_jk))`.
// Axis indices j, k address vectors, matrices and names alike.
#[allow(clippy::needless_range_loop)]
fn derived_terms(base: &Estimates, gyro_scale: bool) -> (Vec<String>, Vec<(usize, Option<usize>)>) {
    let idx = |name: &str| base.index(name);
    let mut derived_names = Vec::new();
    let mut derived: Vec<(usize, Option<usize>)> = Vec::new();
    for (t, on) in [("acc", true), ("gyr", gyro_scale)] {
        if !on {
            continue;
        }
        for j in 0..3 {
            let Some(jj) = idx(&format!("{t}.A_{}{}", AXES[j], AXES[j])) else {
                continue;
            };
            derived_names.push(format!("{t}.S_{}", AXES[j]));
            derived.push((jj, None));
        }
        for j in 0..3 {
            for k in 0..3 {
                if j == k {
                    continue;
                }
                let (Some(jj), Some(jk)) = (
                    idx(&format!("{t}.A_{}{}", AXES[j], AXES[j])),
                    idx(&format!("{t}.A_{}{}", AXES[j], AXES[k])),
                ) else {
                    continue;
                };
                derived_names.push(format!("{t}.M_{}{}", AXES[j], AXES[k]));
                derived.push((jj, Some(jk)));
            }
        }
    }
    (derived_names, derived)
}

/// `base` augmented with the derived scale factors and misalignments
/// ([`derived_terms`]), their covariance by the Jacobian of the ratios;
/// refused when a scale term is zero or the result is not finite.
fn with_derived(base: Estimates, gyro_scale: bool) -> Result<Estimates> {
    let (derived_names, derived) = derived_terms(&base, gyro_scale);
    let gfun = |x: &DVector<f64>| {
        DVector::from_iterator(
            derived.len(),
            derived.iter().map(|&(jj, jk)| match jk {
                None => x[jj],
                Some(jk) => x[jk] / x[jj],
            }),
        )
    };
    for &(jj, _) in &derived {
        if base.values()[jj] == 0.0 {
            return Err(Error::Unsupported(format!(
                "{} is zero: no scale factor (check the positions' directions)",
                base.names()[jj]
            )));
        }
    }
    let steps: Vec<f64> = (0..base.len())
        .map(|k| 1e-6 * base.values()[k].abs().max(base.u_at(k)).max(1e-12))
        .collect();
    let jac = numeric_jacobian(&gfun, base.values(), &steps);
    let estimates = base.augment(derived_names, gfun, |_| jac.clone())?;
    if estimates.values().iter().any(|v| !v.is_finite()) {
        return Err(Error::Unsupported(
            "multi-position fit gave a non-finite result".into(),
        ));
    }
    Ok(estimates)
}

/// Least-squares calibration over known orientations.
// Axis indices j, k address vectors, matrices and names alike.
#[allow(clippy::needless_range_loop)]
pub fn multipos(
    statics: &[StaticPosition],
    rotations: &[RotationSection],
    opts: &MultiposOptions,
) -> Result<MultiposResult> {
    check_gravity_magnitude(opts.gravity)?;
    // Only the rotations are timed.
    if !rotations.is_empty() {
        check_rate_hz(opts.rate_hz)?;
    }
    check_positions(statics)?;
    let mut warnings = Vec::new();
    // Accelerometer, one fit per axis.
    let mut fits = Vec::new();
    let mut parts = Vec::new();
    for j in 0..3 {
        let f = acc_axis(statics, opts, j)?;
        warnings.extend(
            f.quality_warnings("the positions are not where the labels say, or the sensor moved"),
        );
        parts.push(f.estimates.clone());
        fits.push((format!("acc.{}", AXES[j]), f));
    }
    // Gyro.
    let earth = opts.latitude_deg.is_some() && statics.iter().all(|p| p.north.is_some());
    let gyro_scale = opts.gyro && (!rotations.is_empty() || earth);
    if opts.gyro {
        for j in 0..3 {
            let f = gyro_axis(statics, rotations, opts, gyro_scale, j)?;
            warnings.extend(f.quality_warnings(
                "the positions are not where the labels say, the sensor moved, or a rotation was not of the stated angle",
            ));
            parts.push(f.estimates.clone());
            fits.push((format!("gyr.{}", AXES[j]), f));
        }
    }
    let estimates = with_derived(concat(&parts)?, gyro_scale)?;
    Ok(MultiposResult {
        estimates,
        fits,
        statics: statics.to_vec(),
        rotations: rotations.to_vec(),
        gyro_scale,
        warnings,
        options: *opts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn key_of(e: Error) -> String {
        crate::options::refused_key::<()>(Err(e))
    }

    #[test]
    fn options_round_trip_and_a_bad_one_names_its_key() {
        use crate::options::from_json;
        // The document's options, as recorded (no latitude: null).
        let doc = json!({"gravity_m_s2": 9.80665, "latitude_deg": null, "matrix": "full", "rate_hz": 100.0, "rotation_deg": -360.0});
        let o: MultiposSessionOptions = from_json(&doc).unwrap();
        assert_eq!(serde_json::to_value(o).unwrap(), doc);
        assert_eq!(o, from_json(&json!({"rate_hz": 100})).unwrap());
        let upper = json!({"rate_hz": 50, "matrix": "upper", "latitude_deg": -33.9});
        let u: MultiposSessionOptions = from_json(&upper).unwrap();
        assert_eq!((u.matrix, u.latitude_deg), (MatrixForm::Upper, Some(-33.9)));
        let bad = |v| key_of(from_json::<MultiposSessionOptions>(&v).unwrap_err());
        assert_eq!(bad(json!({"rate_hz": 100, "matrix": "lower"})), "matrix");
        assert_eq!(bad(json!({"rate_hz": 100, "latitude": 45})), "latitude");
        // Without a rate: the stamps' (refused later without them).
        assert_eq!(
            from_json::<MultiposSessionOptions>(&json!({"matrix": "full"}))
                .unwrap()
                .rate_hz,
            None
        );
        let invalid = |o: MultiposSessionOptions| key_of(o.validate().unwrap_err());
        assert_eq!(
            invalid(MultiposSessionOptions {
                latitude_deg: Some(91.0),
                ..o
            }),
            "latitude_deg"
        );
        assert_eq!(
            invalid(MultiposSessionOptions {
                gravity_m_s2: -9.81,
                ..o
            }),
            "gravity_m_s2"
        );
        assert_eq!(
            invalid(MultiposSessionOptions {
                rotation_deg: 0.0,
                ..o
            }),
            "rotation_deg"
        );
    }
}
