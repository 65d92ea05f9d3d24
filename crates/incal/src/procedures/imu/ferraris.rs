//! The Ferraris six-position + three-rotation calibration (Ferraris,
//! Grimaldi & Parvis 1995), with imucal's conventions (`FerrarisCalibration`)
//! and the uncertainty of every matrix element.
//!
//! # Model (imucal's definitions)
//! Accelerometer: `a_raw = K_a R_a f + b_a`; gyro:
//! `ω_raw = K_g R_g ω + K_ga f + b_g`, with `f` the specific force in the
//! unit of `gravity_m_s2` (m/s²; its sign by `convention`) and `ω` in
//! deg/s. `K` are diagonal scale matrices, `R` have unit-norm rows (the
//! sensitive-axis directions).
//!
//! # Sections
//! Static: `x_p` (x up: the x accelerometer reads +g; with convention
//! `imucal` it reads −g), `x_a` (x down), and likewise `y_p, y_a, z_p, z_a`. Rotations: `x_rot`, `y_rot`, `z_rot`, one
//! rotation of the known angle A (`--rotation-deg`, default −360: clockwise
//! seen from the tip, as imucal) about the axis in its `_p` position.
//!
//! # Map (Ferraris 1995 eqs. 9–23, as imucal computes them)
//! With `U_p`, `U_a` the 3×3 matrices whose columns are the accelerometer
//! means of `x_p, y_p, z_p` and `x_a, y_a, z_a`:
//! `b_a = diag((U_p + U_a)/2)`; `U_d = U_p − U_a`;
//! `K_a = diag(‖row_i(U_d)‖ / 2g)`; `R_a = K_a⁻¹ U_d / 2g`.
//! `b_g` = mean of every gyro sample of the six static sections;
//! `K_ga = (G_p − G_a) / 2g` (gyro means, columns as above).
//! Rotation r: `W_r = (Σ ω_raw − n_r (b_g + K_ga a_cal)) / F_s` with
//! `a_cal = R_a⁻¹ K_a⁻¹ (ā_r − b_a)`; `M = W / A`;
//! `K_g = diag(‖row_i(M)‖)`; `R_g = K_g⁻¹ M`.
//!
//! # Uncertainty
//! The map is a function of the section means (six static sections: six
//! channels each, joint sample covariance / n), the rotations' accelerometer
//! means (covariance / n) and gyro integrals (the pooled static gyro
//! covariance × n_r / F_s²: white noise integrated over the rotation), and
//! the rotation angle (`u_rotation_deg`). It is propagated by the Jacobian
//! of the map (JCGM 100 eq. 13); degrees of freedom are the smallest
//! section's n − 1. Sample-mean uncertainties assume white noise within a
//! section; correlated noise makes them too small.

use nalgebra::{DMatrix, DVector};

use super::{
    check_gravity_magnitude, check_rate_hz, check_rotation_deg, component_name, element_name,
    SectionStats, M3, V3,
};
use crate::error::{Error, Result};
use crate::estimation::{numeric_jacobian, propagate, Estimates};
use crate::warning::{Warning, WarningCode};

/// The nine section labels, in imucal's order.
pub const SECTIONS: [&str; 9] = [
    "x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_rot", "y_rot", "z_rot",
];

/// The seven calibration quantities, in imucal's order.
pub const QUANTITIES: [&str; 7] = ["K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g"];

/// Sign convention of the static positions (`convention`; recorded in the
/// document only when not [`Convention::Standard`]).
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
pub enum Convention {
    /// `x_p`: the positive x axis points up and the x accelerometer reads
    /// +g (imucal's default, `grav > 0`).
    #[default]
    Standard,
    /// The positive axis is the one along which the accelerometer reads −g
    /// (imucal's `grav = -9.81`, as its documentation advises for such
    /// sensors): the map runs with −g.
    Imucal,
}

impl Convention {
    /// `standard` or `imucal`.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Standard => "standard",
            Convention::Imucal => "imucal",
        }
    }

    fn is_standard(&self) -> bool {
        *self == Convention::Standard
    }
}

fn standard_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}

fn imucal_rotation_deg() -> f64 {
    -360.0
}

/// Options of [`ferraris`] and of the [`Ferraris`] procedure. In the
/// document: `{"rate_hz", "gravity_m_s2", "rotation_deg", "u_rotation_deg"}`,
/// and `convention` when it is not `standard`. Defaults (JSON callers, as
/// the CLI): g 9.80665 m/s², A −360 deg, u(A) 0, convention `standard`.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct FerrarisOptions {
    /// Sample rate F_s (Hz). `None`: the rate of the session's `time_s`
    /// stamps (a session without them is then refused); given, it must
    /// agree with them.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Gravity magnitude g (m/s², > 0; default the standard 9.80665,
    /// imucal uses 9.81). The sign convention is [`FerrarisOptions::convention`].
    #[serde(default = "standard_gravity")]
    pub gravity_m_s2: f64,
    /// Sign convention of the positions ([`Convention`]).
    #[serde(default, skip_serializing_if = "Convention::is_standard")]
    pub convention: Convention,
    /// Rotation angle A of each rotation section (deg; imucal default −360).
    #[serde(default = "imucal_rotation_deg")]
    pub rotation_deg: f64,
    /// Standard uncertainty of the rotation angle (deg).
    #[serde(default)]
    pub u_rotation_deg: f64,
}

impl FerrarisOptions {
    /// imucal's defaults at a sample rate.
    pub fn imucal(rate_hz: f64) -> Self {
        Self {
            rate_hz: Some(rate_hz),
            gravity_m_s2: 9.81,
            convention: Convention::Standard,
            rotation_deg: -360.0,
            u_rotation_deg: 0.0,
        }
    }

    /// These options with the rate of the session's stamps where no rate
    /// was given.
    pub fn at_stamps_rate(&self, timebase: Option<&crate::timebase::TimeBase>) -> Self {
        Self {
            rate_hz: self.rate_hz.or(timebase.map(|tb| tb.rate_hz)),
            ..*self
        }
    }

    /// The g the map runs with (imucal's `grav`): `gravity_m_s2`, negated
    /// for [`Convention::Imucal`].
    pub fn signed_gravity(&self) -> f64 {
        match self.convention {
            Convention::Standard => self.gravity_m_s2,
            Convention::Imucal => -self.gravity_m_s2,
        }
    }

    /// Refuse options the method cannot use ([`crate::Error::InvalidOption`]
    /// naming the key): a sample rate outside (0, 1e6] Hz, a gravity outside
    /// (0, 100] (a negative one points to `convention`), a rotation
    /// angle that is zero or beyond ±36 000 deg, a rotation-angle
    /// uncertainty outside [0, 360] deg.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.rate_hz {
            check_rate_hz(r)?;
        }
        check_gravity_magnitude(self.gravity_m_s2)?;
        check_rotation_deg(self.rotation_deg)?;
        crate::options::check_range("u_rotation_deg", self.u_rotation_deg, 0.0, 360.0, "deg")
    }
}

/// The Ferraris calibration as one [`crate::procedures::Procedure`]: a
/// session CSV ([`super::input::read_ferraris`]) into the result document
/// ([`FerrarisResult::document`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Ferraris;

impl crate::procedures::Procedure for Ferraris {
    const ID: crate::document::Procedure = crate::document::Procedure::ImuFerraris;
    type Options = FerrarisOptions;
    type Input = (
        super::input::FerrarisSections,
        Option<crate::timebase::TimeBase>,
    );

    fn example() -> FerrarisOptions {
        FerrarisOptions {
            rate_hz: Some(100.0),
            gravity_m_s2: 9.81,
            convention: Default::default(),
            rotation_deg: -360.0,
            u_rotation_deg: 0.0,
        }
    }

    fn validate(o: &FerrarisOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &FerrarisOptions,
    ) -> Result<Self::Input> {
        super::input::read_ferraris(rows, o.rate_hz)
    }

    fn recorded(
        input: &Self::Input,
        o: &FerrarisOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        crate::procedures::options_map(&o.at_stamps_rate(input.1.as_ref()))
    }

    fn reduce(
        input: &Self::Input,
        o: &FerrarisOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let mut doc = ferraris(&input.0, &o.at_stamps_rate(input.1.as_ref()))?.document()?;
        if let Some(tb) = &input.1 {
            doc.warnings.extend(tb.warnings());
        }
        Ok(doc)
    }

    fn synthesis(
        input: &Self::Input,
        o: &FerrarisOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Self::Input>>> {
        super::montecarlo::ferraris_synthesis(input, o).map(Some)
    }
}

/// The calibration in imucal's definitions.
#[derive(Debug, Clone, PartialEq)]
pub struct FerrarisMatrices {
    /// Accelerometer scale (diagonal), output/(m/s²).
    pub k_a: M3,
    /// Accelerometer misalignment (unit rows).
    pub r_a: M3,
    /// Accelerometer bias (output).
    pub b_a: V3,
    /// Gyro scale (diagonal), output/(deg/s).
    pub k_g: M3,
    /// Gyro misalignment (unit rows).
    pub r_g: M3,
    /// Gyro g-sensitivity, output/(m/s²).
    pub k_ga: M3,
    /// Gyro bias (output).
    pub b_g: V3,
}

impl FerrarisMatrices {
    /// The 51 elements in the order of [`element_names`].
    pub fn to_vec(&self) -> Vec<f64> {
        let mut v = Vec::with_capacity(51);
        for (q, k) in QUANTITIES.iter().enumerate() {
            match *k {
                "b_a" | "b_g" => {
                    let b = if q == 2 { &self.b_a } else { &self.b_g };
                    v.extend(b.iter());
                }
                _ => {
                    let m = self.matrix(k).unwrap_or_else(M3::zeros);
                    for i in 0..3 {
                        for j in 0..3 {
                            v.push(m[(i, j)]);
                        }
                    }
                }
            }
        }
        v
    }

    /// The matrix called `name` (`K_a`, `R_a`, `K_g`, `R_g`, `K_ga`).
    pub fn matrix(&self, name: &str) -> Option<M3> {
        match name {
            "K_a" => Some(self.k_a),
            "R_a" => Some(self.r_a),
            "K_g" => Some(self.k_g),
            "R_g" => Some(self.r_g),
            "K_ga" => Some(self.k_ga),
            _ => None,
        }
    }

    /// Calibrated accelerometer sample: `f = R_a⁻¹ K_a⁻¹ (a_raw − b_a)`.
    pub fn calibrate_acc(&self, raw: &V3) -> Option<V3> {
        let m = (self.k_a * self.r_a).try_inverse()?;
        Some(m * (raw - self.b_a))
    }

    /// Calibrated gyro sample (deg/s):
    /// `ω = R_g⁻¹ K_g⁻¹ (ω_raw − b_g − K_ga f)`, `f` the calibrated
    /// accelerometer sample of the same instant.
    pub fn calibrate_gyr(&self, raw: &V3, f: &V3) -> Option<V3> {
        let m = (self.k_g * self.r_g).try_inverse()?;
        Some(m * (raw - self.b_g - self.k_ga * f))
    }
}

/// Names of the 51 elements: `K_a.xx … K_a.zz, R_a.xx …, b_a.x, b_a.y,
/// b_a.z, K_g.xx …, R_g.xx …, K_ga.xx …, b_g.x …`.
pub fn element_names() -> Vec<String> {
    let mut v = Vec::with_capacity(51);
    for k in QUANTITIES {
        if k.starts_with("b_") {
            v.extend((0..3).map(|i| component_name(k, i)));
        } else {
            for i in 0..3 {
                for j in 0..3 {
                    v.push(element_name(k, i, j));
                }
            }
        }
    }
    v
}

/// Result of [`ferraris`].
#[derive(Debug, Clone)]
pub struct FerrarisResult {
    /// The matrices (the exact imucal computation).
    pub matrices: FerrarisMatrices,
    /// Every element with its covariance ([`element_names`]).
    pub estimates: Estimates,
    /// The statistics of the nine sections in [`SECTIONS`] order.
    pub sections: Vec<SectionStats>,
    /// Warnings (sign conventions).
    pub warnings: Vec<Warning>,
    /// The options used.
    pub options: FerrarisOptions,
}

const N_IN: usize = 55;

/// The map from the input vector (section means, rotation integrals,
/// angle) to the matrices. `counts`: samples of each section.
fn map(x: &[f64], counts: &[usize; 9], opts: &FerrarisOptions) -> Option<FerrarisMatrices> {
    let g = opts.signed_gravity();
    let acc = |s: usize| V3::new(x[6 * s], x[6 * s + 1], x[6 * s + 2]);
    let gyr = |s: usize| V3::new(x[6 * s + 3], x[6 * s + 4], x[6 * s + 5]);
    // Columns: x, y, z positions; sections 0,2,4 are _p and 1,3,5 _a.
    let u_p = M3::from_columns(&[acc(0), acc(2), acc(4)]);
    let u_n = M3::from_columns(&[acc(1), acc(3), acc(5)]);
    let u_s = u_p + u_n;
    let b_a = V3::new(u_s[(0, 0)], u_s[(1, 1)], u_s[(2, 2)]) / 2.0;
    let u_d = u_p - u_n;
    let mut k_a = M3::zeros();
    for i in 0..3 {
        k_a[(i, i)] = (u_d.row(i).norm_squared() / (4.0 * g * g)).sqrt();
    }
    let r_a = k_a.try_inverse()? * u_d / (2.0 * g);
    let n_static: usize = counts[..6].iter().sum();
    let mut b_g = V3::zeros();
    for (s, &n) in counts[..6].iter().enumerate() {
        b_g += gyr(s) * n as f64;
    }
    b_g /= n_static as f64;
    let g_p = M3::from_columns(&[gyr(0), gyr(2), gyr(4)]);
    let g_n = M3::from_columns(&[gyr(1), gyr(3), gyr(5)]);
    let k_ga = (g_p - g_n) / (2.0 * g);
    let acc_cal = (k_a * r_a).try_inverse()?;
    let mut w = M3::zeros();
    for r in 0..3 {
        let s = 6 + r;
        let n = counts[s] as f64;
        let a_cal = acc_cal * (acc(s) - b_a);
        // `ferraris` refuses options without a rate before any map.
        let col = (gyr(s) - n * (b_g + k_ga * a_cal)) / opts.rate_hz.unwrap_or(f64::NAN);
        w.set_column(r, &col);
    }
    let angle = x[N_IN - 1];
    let m = w / angle;
    let mut k_g = M3::zeros();
    for i in 0..3 {
        k_g[(i, i)] = m.row(i).norm_squared().sqrt();
    }
    let r_g = k_g.try_inverse()? * m;
    Some(FerrarisMatrices {
        k_a,
        r_a,
        b_a,
        k_g,
        r_g,
        k_ga,
        b_g,
    })
}

/// The statistics of the nine sections after the channel check: static
/// positions with their spikes left out of the mean, rotations as
/// recorded (spikes reported only); the warnings of both.
fn section_stats(sections: &[Vec<[f64; 6]>; 9]) -> Result<(Vec<SectionStats>, Vec<Warning>)> {
    let mut stats = Vec::with_capacity(9);
    let mut warnings = Vec::new();
    let mut channels = super::screen::ChannelCheck::default();
    sections.iter().flatten().for_each(|s| channels.push(s));
    channels.finish(&super::input::CHANNELS.map(Some), &mut warnings)?;
    let mut spikes = Vec::new();
    let mut replaced = Vec::new();
    let scale = super::screen::gyro_still_scale(sections[..6].iter().map(|s| &s[..]));
    for (k, s) in sections.iter().enumerate() {
        if s.len() < 2 {
            return Err(Error::TooFew {
                what: format!("samples in section {}", SECTIONS[k]),
                needed: 2,
                got: s.len(),
            });
        }
        if k < 6 {
            // Static positions: spikes left out of the mean.
            let (kept, n) = super::screen::without_spikes(s);
            spikes.push((SECTIONS[k].to_string(), n));
            stats.push(SectionStats::of(&kept)?);
        } else {
            // Rotations: as recorded (spikes reported only).
            let n = super::screen::rotation_spikes(s, scale);
            replaced.push((SECTIONS[k].to_string(), n));
            stats.push(SectionStats::of(s)?);
        }
    }
    warnings.extend(super::screen::spikes_warning(
        &spikes,
        super::screen::LEFT_OUT,
    ));
    warnings.extend(super::screen::spikes_warning(
        &replaced,
        super::screen::NOT_CHANGED,
    ));
    Ok((stats, warnings))
}

/// The gyro covariance pooled within the six static sections (raw
/// units², weights n − 1).
pub(super) fn pooled_static_gyro(stats: &[SectionStats]) -> [[f64; 3]; 3] {
    let mut pooled = [[0.0; 3]; 3];
    let mut pooled_dof = 0.0;
    for st in &stats[..6] {
        let w = (st.n - 1) as f64;
        for (j, row) in pooled.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                *v += w * st.cov[3 + j][3 + k];
            }
        }
        pooled_dof += w;
    }
    for row in pooled.iter_mut() {
        for v in row.iter_mut() {
            *v /= pooled_dof;
        }
    }
    pooled
}

/// The map's input vector (module docs: section means, rotation
/// accelerometer means and gyro integrals, angle) and its covariance.
fn inputs(stats: &[SectionStats], opts: &FerrarisOptions) -> (DVector<f64>, DMatrix<f64>) {
    let mut x = DVector::zeros(N_IN);
    let mut c = DMatrix::zeros(N_IN, N_IN);
    // Pooled static gyro covariance (within sections).
    let pooled = pooled_static_gyro(stats);
    for (s, st) in stats.iter().enumerate() {
        let n = st.n as f64;
        let o = 6 * s;
        if s < 6 {
            for j in 0..6 {
                x[o + j] = st.mean[j];
                for k in 0..6 {
                    c[(o + j, o + k)] = st.cov[j][k] / n;
                }
            }
        } else {
            for j in 0..3 {
                x[o + j] = st.mean[j];
                x[o + 3 + j] = st.sum[3 + j];
                for k in 0..3 {
                    c[(o + j, o + k)] = st.cov[j][k] / n;
                    // Σ ω over n samples of white noise: n Σ_g (raw units²);
                    // the map divides by F_s.
                    c[(o + 3 + j, o + 3 + k)] = n * pooled[j][k];
                }
            }
        }
    }
    x[N_IN - 1] = opts.rotation_deg;
    c[(N_IN - 1, N_IN - 1)] = opts.u_rotation_deg.powi(2);
    (x, c)
}

/// The matrices at the input `x`, refused (naming the cause) when the
/// sections do not determine a scale or give a non-finite calibration.
fn checked_map(
    x: &DVector<f64>,
    counts: &[usize; 9],
    opts: &FerrarisOptions,
) -> Result<FerrarisMatrices> {
    let matrices = map(x.as_slice(), counts, opts).ok_or_else(|| Error::Unsupported(
        "the sections do not determine a scale: a row of the accelerometer differences or of the rotation integrals is zero (check the section labels)".into(),
    ))?;
    if matrices.to_vec().iter().any(|v| !v.is_finite()) {
        return Err(Error::Unsupported(
            "the sections give a non-finite calibration (check the section labels)".into(),
        ));
    }
    for i in 0..3 {
        if matrices.k_a[(i, i)] == 0.0 || matrices.k_g[(i, i)] == 0.0 {
            return Err(Error::Unsupported(format!(
                "the sections do not determine the {} scale (zero difference between the positions or zero rotation integral)",
                super::AXES[i]
            )));
        }
    }
    Ok(matrices)
}

/// The 51 elements with the covariance propagated from the inputs'
/// (`x`, `c`) by the Jacobian of the map (JCGM 100 eq. 13); dof the
/// smallest section's n − 1.
fn propagated(
    matrices: &FerrarisMatrices,
    x: &DVector<f64>,
    c: &DMatrix<f64>,
    counts: &[usize; 9],
    opts: &FerrarisOptions,
) -> Result<Estimates> {
    let f = |z: &DVector<f64>| -> DVector<f64> {
        match map(z.as_slice(), counts, opts) {
            Some(m) => DVector::from_vec(m.to_vec()),
            None => DVector::from_element(51, f64::NAN),
        }
    };
    let steps: Vec<f64> = (0..N_IN)
        .map(|k| 1e-6 * x[k].abs().max(c[(k, k)].sqrt()).max(1e-9))
        .collect();
    let j = numeric_jacobian(&f, x, &steps);
    let cov = propagate(c, &j);
    if cov.iter().any(|v| !v.is_finite()) {
        return Err(Error::Unsupported(
            "the uncertainty of the Ferraris map is not finite (check the section labels)".into(),
        ));
    }
    let dof = counts
        .iter()
        .map(|&n| (n - 1) as f64)
        .fold(f64::INFINITY, f64::min);
    Estimates::new(
        element_names(),
        DVector::from_vec(matrices.to_vec()),
        cov,
        dof,
    )
}

/// Warnings of a negative diagonal of `R_a` (positions reading −g) or of
/// `R_g` (rotations opposite to the stated angle).
fn sign_warnings(matrices: &FerrarisMatrices, opts: &FerrarisOptions) -> Vec<Warning> {
    let mut warnings = Vec::new();
    let neg = |m: &M3| {
        (0..3)
            .filter(|&i| m[(i, i)] < 0.0)
            .map(|i| super::AXES[i])
            .collect::<Vec<_>>()
    };
    let na = neg(&matrices.r_a);
    if !na.is_empty() {
        warnings.push(Warning::new(
            WarningCode::SignConvention,
            format!(
                "R_a has a negative diagonal on {}: the positions read -g where convention {} says +g (swapped _p/_a labels, or use --convention {})",
                na.join(", "),
                opts.convention.name(),
                match opts.convention {
                    Convention::Standard => Convention::Imucal.name(),
                    Convention::Imucal => Convention::Standard.name(),
                }
            ),
        ));
    }
    let ng = neg(&matrices.r_g);
    if !ng.is_empty() {
        warnings.push(Warning::new(
            WarningCode::SignConvention,
            format!(
                "R_g has a negative diagonal on {}: the rotations turned opposite to --rotation-deg {} (use --rotation-deg {} for a counter-clockwise rotation)",
                ng.join(", "),
                opts.rotation_deg,
                -opts.rotation_deg
            ),
        ));
    }
    warnings
}

/// Ferraris calibration from the nine sections' samples, each a 6-vector
/// (accelerometer x, y, z, gyro x, y, z) in [`SECTIONS`] order.
///
/// Fails (naming the section) when a section has fewer than 2 samples,
/// and when the positions do not determine a scale (a zero row of `U_d` or
/// of the rotation integrals).
pub fn ferraris(sections: &[Vec<[f64; 6]>; 9], opts: &FerrarisOptions) -> Result<FerrarisResult> {
    opts.validate()?;
    if opts.rate_hz.is_none() {
        return crate::options::invalid(
            "rate_hz",
            "the sample rate is needed to integrate the rotations",
        );
    }
    let (stats, mut warnings) = section_stats(sections)?;
    let counts: [usize; 9] = std::array::from_fn(|k| stats[k].n);
    let (x, c) = inputs(&stats, opts);
    let matrices = checked_map(&x, &counts, opts)?;
    let estimates = propagated(&matrices, &x, &c, &counts, opts)?;
    warnings.extend(sign_warnings(&matrices, opts));
    Ok(FerrarisResult {
        matrices,
        estimates,
        sections: stats,
        warnings,
        options: *opts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Nine sections of an ideal sensor whose `_p` positions read `plus`
    /// (+g, or −g for imucal's negative-g convention).
    fn ideal_sections(plus: f64) -> [Vec<[f64; 6]>; 9] {
        let mut secs: [Vec<[f64; 6]>; 9] = Default::default();
        for (k, s) in secs.iter_mut().enumerate() {
            for i in 0..100 {
                let e = 1e-3 * ((i % 7) as f64 - 3.0);
                // Every channel varies: one reading 0 in 800 of 900 rows
                // would be taken for a clipped one.
                let mut v = [e, -e, 0.5 * e, e, 0.3 * e, -e];
                if k < 6 {
                    let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                    v[k / 2] += sign * plus;
                } else {
                    let a = k - 6;
                    v[a] += plus;
                    v[3 + a] += -360.0;
                }
                s.push(v);
            }
        }
        secs
    }

    /// Ideal sensor (imucal's own unit test): every matrix is the identity.
    #[test]
    fn ideal_sensor_gives_identity() {
        let r = ferraris(&ideal_sections(9.81), &FerrarisOptions::imucal(100.0)).unwrap();
        let m = &r.matrices;
        assert!((m.k_a - M3::identity()).abs().max() < 1e-3);
        assert!((m.r_a - M3::identity()).abs().max() < 1e-3);
        assert!((m.k_g - M3::identity()).abs().max() < 1e-3);
        assert!((m.r_g - M3::identity()).abs().max() < 1e-3);
        assert!(m.k_ga.abs().max() < 1e-3);
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        assert!(r.estimates.u("K_a.xx").unwrap() > 0.0);
    }

    /// Positions that read −g: identity under convention `imucal` (imucal's
    /// `grav = -9.81`), a sign warning naming the convention otherwise.
    #[test]
    fn imucal_convention_is_the_negative_g_map() {
        let secs = ideal_sections(-9.81);
        let imucal = FerrarisOptions {
            convention: Convention::Imucal,
            ..FerrarisOptions::imucal(100.0)
        };
        let r = ferraris(&secs, &imucal).unwrap();
        assert!((r.matrices.r_a - M3::identity()).abs().max() < 1e-3);
        assert!((r.matrices.r_g - M3::identity()).abs().max() < 1e-3);
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        let r = ferraris(&secs, &FerrarisOptions::imucal(100.0)).unwrap();
        assert!(
            r.warnings
                .iter()
                .any(|w| w.message.contains("--convention imucal")),
            "{:?}",
            r.warnings
        );
    }

    fn key_of(e: Error) -> (String, String) {
        match e {
            Error::InvalidOption { key, message } => (key, message),
            other => panic!("expected InvalidOption, got {other:?}"),
        }
    }

    #[test]
    fn options_round_trip_and_a_bad_one_names_its_key() {
        use crate::options::from_json;
        // The document's options, as recorded.
        let doc = json!({"gravity_m_s2": 9.80665, "rate_hz": 100.0, "rotation_deg": -360.0, "u_rotation_deg": 0.0});
        let o: FerrarisOptions = from_json(&doc).unwrap();
        assert_eq!(serde_json::to_value(o).unwrap(), doc);
        assert_eq!(o, from_json(&json!({"rate_hz": 100})).unwrap());
        let imucal = FerrarisOptions {
            convention: Convention::Imucal,
            ..o
        };
        let v = serde_json::to_value(imucal).unwrap();
        assert_eq!(v["convention"], "imucal");
        assert_eq!(from_json::<FerrarisOptions>(&v).unwrap(), imucal);
        assert_eq!(imucal.signed_gravity(), -9.80665);
        let bad = |v| key_of(from_json::<FerrarisOptions>(&v).unwrap_err()).0;
        assert_eq!(bad(json!({"rate_hz": 100, "gravity": 9.81})), "gravity");
        assert_eq!(
            bad(json!({"rate_hz": 100, "convention": "up"})),
            "convention"
        );
        let invalid = |o: FerrarisOptions| key_of(o.validate().unwrap_err());
        let (key, message) = invalid(FerrarisOptions {
            gravity_m_s2: -9.81,
            ..o
        });
        assert_eq!(key, "gravity_m_s2");
        assert!(message.contains("--convention imucal"), "{message}");
        assert_eq!(
            invalid(FerrarisOptions {
                rate_hz: Some(0.0),
                ..o
            })
            .0,
            "rate_hz"
        );
        assert_eq!(
            invalid(FerrarisOptions {
                rotation_deg: 0.0,
                ..o
            })
            .0,
            "rotation_deg"
        );
        assert_eq!(
            invalid(FerrarisOptions {
                u_rotation_deg: -1.0,
                ..o
            })
            .0,
            "u_rotation_deg"
        );
    }
}
