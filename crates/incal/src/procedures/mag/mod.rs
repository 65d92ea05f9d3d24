//! Magnetometer calibration: hard iron, soft iron and the alignment to
//! the accelerometer from a session turned through many orientations
//! (docs/src/mag.md).
//!
//! # Model and fit
//! `m = S⁻¹ b + h + e` with `|b| = F` ([`fit`]): the hard-iron offset
//! `h` (raw units) and the soft-iron correction `S` (symmetric positive
//! definite) by a constrained ellipsoid fit, every element with its u and
//! the correlation matrix; `b̂ = S (m − h)` is the calibrated field.
//! The scale of `S`: with the local field `F` given (`field_ut`, µT),
//! `|b̂| = F` (output in µT); without it `det S = 1` and `|b̂|` is the
//! ellipsoid's geometric-mean radius, `field_raw = det(C)^{−1/3}` (raw
//! units), the sensor's own scale kept. With a unit (`unit` not
//! `counts`), `field_ut` is that radius in µT, compared with `F`.
//!
//! # Alignment
//! With accelerometer columns, the rows at rest (`|f|` within
//! `static_tolerance` of its median, and `|ω| ≤ max_rate` when the gyro
//! is given) add the constant angle between gravity and the field: the
//! rotation vector `alignment_*_deg` from the calibrated magnetometer
//! axes to the accelerometer's and the inclination `inclination_deg`,
//! compared with `inclination_deg` given (En).
//!
//! # Checks
//! Refused, naming what is missing: fewer distinct orientations (more
//! than 5° apart) than the nine unknowns; a session that does not turn
//! about enough axes (the design aliased: the terms it cannot separate
//! are named); a magnetometer column at `full_scale`, or held at its
//! largest or smallest value for two or more rows where the fit misses
//! those rows by more than five standard deviations (saturated). Warned:
//! a thin coverage (spread below 0.3, naming the axis and the terms it
//! weakens), a field or inclination that disagrees with the given one.

pub mod apply;
pub mod document;
pub mod fit;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::options::{check_range, invalid};
use crate::warning::{Warning, WarningCode};
use fit::{Solved, M3, V3};
use input::{Record, MAG};

/// Rows fitted at most: a longer session is fitted on every k-th row
/// (the stride in the document).
pub const MAX_FIT_ROWS: usize = 100_000;
/// Orientations closer than this are one (degrees).
pub const ORIENTATION_DEG: f64 = 5.0;
/// A coverage spread below this is refused (module docs).
pub const SPREAD_REFUSED: f64 = 0.05;
/// A coverage spread below this is warned.
pub const SPREAD_WARNED: f64 = 0.3;
/// A scatter of the gravity–field angle's cosine above this (about 3°)
/// is warned: axes mapped differently, motion, or a disturbance.
pub const ANGLE_SD_WARNED: f64 = 0.05;
/// An equilibrated condition number above this is refused.
pub const COND_REFUSED: f64 = 1e8;

/// The magnetometer's raw unit.
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
#[serde(rename_all = "kebab-case")]
pub enum MagUnit {
    /// Microtesla.
    #[default]
    Ut,
    /// Nanotesla.
    Nt,
    /// Gauss (100 µT).
    Gauss,
    /// Milligauss (0.1 µT).
    Mgauss,
    /// Raw counts: no physical unit (no comparison with the local field,
    /// no flight-stack export).
    Counts,
}

impl MagUnit {
    /// µT per raw unit, `None` for counts.
    pub fn ut(self) -> Option<f64> {
        match self {
            MagUnit::Ut => Some(1.0),
            MagUnit::Nt => Some(1e-3),
            MagUnit::Gauss => Some(100.0),
            MagUnit::Mgauss => Some(0.1),
            MagUnit::Counts => None,
        }
    }

    /// The unit of a name of [`MagUnit::as_str`].
    pub fn from_name(name: &str) -> Option<MagUnit> {
        [
            MagUnit::Ut,
            MagUnit::Nt,
            MagUnit::Gauss,
            MagUnit::Mgauss,
            MagUnit::Counts,
        ]
        .into_iter()
        .find(|u| u.as_str() == name)
    }

    /// The unit's name in documents.
    pub fn as_str(self) -> &'static str {
        match self {
            MagUnit::Ut => "uT",
            MagUnit::Nt => "nT",
            MagUnit::Gauss => "gauss",
            MagUnit::Mgauss => "mgauss",
            MagUnit::Counts => "counts",
        }
    }
}

/// The magnetometer's axes from the file's columns: `"x,y,z"` as is,
/// `"y,x,-z"` (an AK8963 beside its MPU-9250's accelerometer) takes the
/// file's `mag_y` as x, `mag_x` as y and `−mag_z` as z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axes {
    /// For each axis, the file column it comes from and its sign.
    pub from: [(usize, f64); 3],
}

impl Axes {
    /// Parse `"x,y,z"` (each of x, y, z once, optionally signed).
    pub fn parse(s: &str) -> Result<Axes> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let bad = || {
            invalid::<Axes>(
                "axes",
                format!(
                    "'{}' is not three of x, y, z, each once and optionally signed (e.g. y,x,-z)",
                    incal_io::clip(s)
                ),
            )
        };
        if parts.len() != 3 {
            return bad();
        }
        let mut from = [(0, 1.0); 3];
        let mut used = [false; 3];
        for (k, p) in parts.iter().enumerate() {
            let (sign, name) = match p.strip_prefix('-') {
                Some(r) => (-1.0, r),
                None => (1.0, p.strip_prefix('+').unwrap_or(p)),
            };
            let src = match name {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                _ => return bad(),
            };
            if used[src] {
                return bad();
            }
            used[src] = true;
            from[k] = (src, sign);
        }
        Ok(Axes { from })
    }

    /// The magnetometer's axes of a row of the file's columns.
    pub fn map(&self, raw: [f64; 3]) -> [f64; 3] {
        self.from.map(|(src, sign)| sign * raw[src])
    }
}

/// Options of the magnetometer calibration. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MagOptions {
    /// The local field's magnitude (µT; e.g. from the World Magnetic
    /// Model at the site): the calibrated field's magnitude. Without it
    /// the soft-iron matrix keeps the sensor's mean scale (`det = 1`).
    #[serde(default)]
    pub field_ut: Option<f64>,
    /// Standard uncertainty of `field_ut` (µT; default 0).
    #[serde(default)]
    pub u_field_ut: f64,
    /// The local inclination (degrees, down positive), compared with the
    /// fitted one when the session has an accelerometer.
    #[serde(default)]
    pub inclination_deg: Option<f64>,
    /// Standard uncertainty of `inclination_deg` (degrees; default 0).
    #[serde(default)]
    pub u_inclination_deg: f64,
    /// The magnetometer's raw unit (default uT).
    #[serde(default)]
    pub unit: MagUnit,
    /// The magnetometer's axes from the file's columns (default `x,y,z`;
    /// [`Axes`]).
    #[serde(default = "xyz")]
    pub axes: String,
    /// The magnetometer's full scale (raw units): a reading at or beyond
    /// it is saturated and refused.
    #[serde(default)]
    pub full_scale: Option<f64>,
    /// Do not fit the alignment to the accelerometer (default false: fit
    /// it when the file has one).
    #[serde(default)]
    pub no_alignment: bool,
    /// A row is at rest when `|f|` is within this fraction of its median
    /// (default 0.02).
    #[serde(default = "two_percent")]
    pub static_tolerance: f64,
    /// With gyro columns, a row is at rest only when `|ω|` is at most
    /// this (gyro units; default: the gyro is not used).
    #[serde(default)]
    pub max_rate: Option<f64>,
}

fn xyz() -> String {
    "x,y,z".into()
}
fn two_percent() -> f64 {
    0.02
}

impl Default for MagOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

impl MagOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        if let Some(f) = self.field_ut {
            check_range("field_ut", f, 1e-3, 1e7, "uT")?;
        }
        check_range("u_field_ut", self.u_field_ut, 0.0, 1e6, "uT")?;
        if let Some(i) = self.inclination_deg {
            check_range("inclination_deg", i, -90.0, 90.0, "deg")?;
        }
        check_range(
            "u_inclination_deg",
            self.u_inclination_deg,
            0.0,
            90.0,
            "deg",
        )?;
        Axes::parse(&self.axes)?;
        if let Some(f) = self.full_scale {
            check_range("full_scale", f, 1e-12, 1e15, "")?;
        }
        check_range("static_tolerance", self.static_tolerance, 1e-6, 0.5, "")?;
        if let Some(r) = self.max_rate {
            check_range("max_rate", r, 0.0, 1e9, "")?;
        }
        Ok(())
    }
}

/// A calibrated session.
#[derive(Debug, Clone)]
pub struct MagResult {
    /// The options.
    pub options: MagOptions,
    /// The fit (unit-sphere parameters, module docs of [`fit`]).
    pub solved: Solved,
    /// The reported coefficients with their joint covariance.
    pub coefficients: Estimates,
    /// Rows read, rows fitted, and the stride between fitted rows.
    pub rows: (usize, usize, usize),
    /// Distinct orientations (counted up to 1000).
    pub orientations: usize,
    /// Coverage spread and the axis it is thinnest along.
    pub coverage: (f64, V3),
    /// Equilibrated condition number of the design at the start.
    pub condition: f64,
    /// Rows at rest used by the alignment.
    pub rest_rows: usize,
    /// The readings of the table (at most [`document::POINTS`], evenly
    /// spaced) with their row (from 0, in the session's order).
    pub points: Vec<(usize, V3)>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

impl MagResult {
    /// The hard-iron offset (raw units).
    pub fn hard_iron(&self) -> V3 {
        let v = |n: &str| self.coefficients.value(n).unwrap_or(0.0);
        V3::new(v(fit::HARD[0]), v(fit::HARD[1]), v(fit::HARD[2]))
    }

    /// The soft-iron correction `S` (output units per raw unit).
    pub fn soft_iron(&self) -> M3 {
        let c: Vec<f64> = fit::SOFT
            .iter()
            .map(|n| self.coefficients.value(n).unwrap_or(0.0))
            .collect();
        fit::sym(&c)
    }

    /// The unit of the calibrated field: µT with `field_ut`, else raw.
    pub fn output_unit(&self) -> &'static str {
        match self.options.field_ut {
            Some(_) => "uT",
            None => self.options.unit.as_str(),
        }
    }
}

/// Calibrate a session (module docs).
pub fn calibrate(rec: &Record, o: &MagOptions) -> Result<MagResult> {
    o.validate()?;
    let axes = Axes::parse(&o.axes)?;
    if let Some(fs) = o.full_scale {
        full_scale(rec, &axes, fs)?;
    }
    let n = rec.mag.len();
    let stride = n.div_ceil(MAX_FIT_ROWS).max(1);
    let rows: Vec<usize> = (0..n).step_by(stride).collect();
    let mag: Vec<V3> = rows.iter().map(|&k| V3::from(rec.mag[k])).collect();
    if rec.mag.iter().all(|m| *m == rec.mag[0]) {
        return Err(Error::Unsupported(
            "every reading is the same: the unit was not turned (or the magnetometer does not answer)".into(),
        ));
    }
    let (h0, c0) = fit::algebraic(&mag);
    let orientations = fit::orientations(&mag, &h0, &c0, ORIENTATION_DEG, 1000);
    if orientations < fit::UNKNOWNS {
        return Err(Error::Unsupported(format!(
            "{orientations} distinct orientations (directions more than {ORIENTATION_DEG}° apart): the ellipsoid has {} unknowns; turn the unit through more orientations",
            fit::UNKNOWNS
        )));
    }
    let coverage = fit::coverage(&mag, &h0, &c0);
    let mut warnings = Vec::new();
    let condition = check_design(&mag, &h0, &c0, coverage, &mut warnings)?;
    saturated(rec, &axes, &rows, &h0, &c0)?;
    let rest = at_rest(rec, &rows, o, &mut warnings);
    let solved = fit::solve(&mag, &rest, &h0, &c0)
        .map_err(|e| Error::Unsupported(format!("the ellipsoid fit failed: {e}")))?;
    if let Some((sd, _)) = solved.dot.filter(|d| d.0 > ANGLE_SD_WARNED) {
        warnings.push(Warning::new(
            WarningCode::LackOfFit,
            format!("the angle between gravity and the calibrated field scatters by {:.1}° (sd of its cosine {sd:.3}) over the rows at rest: the magnetometer's axes may be mapped differently from the accelerometer's (axes), the unit moved in those rows, or the field is disturbed near the rig", sd.asin().to_degrees()),
        ));
    }
    let coefficients = outputs(&solved, o)?;
    let result = MagResult {
        options: o.clone(),
        coefficients,
        rows: (n, rows.len(), stride),
        orientations,
        coverage,
        condition,
        rest_rows: rest.len(),
        points: (0..n)
            .step_by(n.div_ceil(document::POINTS).max(1))
            .map(|k| (k, V3::from(rec.mag[k])))
            .collect(),
        solved,
        warnings,
    };
    Ok(compare(result))
}

/// Refuse a reading at or beyond the full scale, naming its column and
/// line.
fn full_scale(rec: &Record, axes: &Axes, fs: f64) -> Result<()> {
    for (k, m) in rec.mag.iter().enumerate() {
        for (a, v) in m.iter().enumerate() {
            if v.abs() >= fs {
                let hits = rec.mag.iter().filter(|m| m[a].abs() >= fs).count();
                return Err(Error::Unsupported(format!(
                    "line {}: {} = {v} is at the full scale {fs} ({hits} rows in all): saturated readings bend the ellipsoid; record within the range or leave those rows out",
                    rec.lines[k],
                    MAG[axes.from[a].0]
                )));
            }
        }
    }
    Ok(())
}

/// The design's conditioning at the start: refused when aliased, warned
/// when thin (module docs). Returns the condition number.
fn check_design(
    mag: &[V3],
    h0: &V3,
    c0: &M3,
    (spread, axis): (f64, V3),
    warnings: &mut Vec<Warning>,
) -> Result<f64> {
    let d = fit::diagnose(mag, &fit::pack(h0, c0))?;
    // The terms along the axis the session was turned about (a field
    // component that never changes cannot be told from an offset, nor
    // its scale and couplings), then those of the design's weakest
    // direction.
    let mut weak: Vec<String> = Vec::new();
    let mut add = |t: String| {
        if !weak.contains(&t) {
            weak.push(t);
        }
    };
    let xyz = ["x", "y", "z"];
    for i in (0..3).filter(|&i| axis[i].abs() > 0.3) {
        add(fit::HARD[i].to_string());
        add(format!("soft_iron_{}{}", xyz[i], xyz[i]));
        for j in (0..3).filter(|&j| j != i) {
            let (a, b) = (i.min(j), i.max(j));
            add(format!("soft_iron_{}{}", xyz[a], xyz[b]));
        }
    }
    for (t, c) in d.weakest.terms.iter().zip(&d.weakest.coefficients) {
        if c.abs() > 0.2 {
            add(t.clone());
        }
    }
    let about = format!(
        "the session turned about ({:.2}, {:.2}, {:.2}) (coverage spread {spread:.3}, 1 for directions all over the sphere)",
        axis.x, axis.y, axis.z
    );
    if !d.is_separable() || d.condition > COND_REFUSED || spread < SPREAD_REFUSED {
        return Err(Error::Unsupported(format!(
            "{about}: the fit cannot separate {}; turn the unit about two more axes",
            weak.join(", ")
        )));
    }
    if spread < SPREAD_WARNED {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!("{about}: {} are weakly determined (condition {:.0}); turn the unit about more axes", weak.join(", "), d.condition),
        ));
    }
    Ok(d.condition)
}

/// The fitted rows at rest with their unit specific force (indices into
/// the fitted rows), empty without an accelerometer or with alignment
/// off; a warning when too few or too alike to align.
fn at_rest(
    rec: &Record,
    rows: &[usize],
    o: &MagOptions,
    warnings: &mut Vec<Warning>,
) -> Vec<(usize, V3)> {
    let Some(acc) = rec.acc.as_ref().filter(|_| !o.no_alignment) else {
        return Vec::new();
    };
    let mut norms: Vec<f64> = rows.iter().map(|&k| V3::from(acc[k]).norm()).collect();
    norms.sort_by(f64::total_cmp);
    let median = norms[norms.len() / 2];
    let still = |k: usize| {
        let f = V3::from(acc[k]).norm();
        let quiet = match (&rec.gyr, o.max_rate) {
            (Some(g), Some(m)) => V3::from(g[k]).norm() <= m,
            _ => true,
        };
        median > 0.0 && (f - median).abs() <= o.static_tolerance * median && quiet
    };
    let rest: Vec<(usize, V3)> = rows
        .iter()
        .enumerate()
        .filter(|(_, &k)| still(k))
        .map(|(i, &k)| (i, V3::from(acc[k]).normalize()))
        .collect();
    let dirs: Vec<V3> = rest.iter().map(|(_, f)| *f).collect();
    let spread = if dirs.len() > 1 {
        fit::coverage(&dirs, &V3::zeros(), &M3::identity()).0
    } else {
        0.0
    };
    if rest.len() < 20 || spread < SPREAD_REFUSED {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!("{} rows at rest with gravity directions of spread {spread:.3}: too few or too alike to align the magnetometer to the accelerometer; the alignment is not reported (hold the unit still in several orientations)", rest.len()),
        ));
        return Vec::new();
    }
    rest
}

/// Refuse a column held at its extreme where an ellipsoid fitted
/// without those rows misses them (module docs): `rows` the fitted rows.
fn saturated(rec: &Record, axes: &Axes, rows: &[usize], h0: &V3, c0: &M3) -> Result<()> {
    let n = rec.mag.len();
    let mut held: Vec<(usize, f64, Vec<usize>)> = Vec::new();
    for a in 0..3 {
        let (lo, hi) = rec
            .mag
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, u), m| (l.min(m[a]), u.max(m[a])));
        for edge in [lo, hi] {
            let at: Vec<usize> = (0..n).filter(|&k| rec.mag[k][a] == edge).collect();
            if at.windows(2).any(|w| w[1] == w[0] + 1) {
                held.push((a, edge, at));
            }
        }
    }
    if held.is_empty() {
        return Ok(());
    }
    let mut out = vec![false; n];
    for (_, _, at) in &held {
        for k in at {
            out[*k] = true;
        }
    }
    let kept: Vec<V3> = rows
        .iter()
        .filter(|&&k| !out[k])
        .map(|&k| V3::from(rec.mag[k]))
        .collect();
    if kept.len() <= 2 * fit::UNKNOWNS {
        return Ok(());
    }
    // An ellipsoid that does not converge without them says nothing here:
    // the main fit reports its own trouble.
    let Ok(s) = fit::solve(&kept, &[], h0, c0) else {
        return Ok(());
    };
    let (h, c) = fit::unpack(s.fit.estimates.values());
    let sd = s.magnitude.0.max(f64::MIN_POSITIVE);
    for (a, edge, at) in held {
        let missed = at
            .iter()
            .filter(|&&k| ((c * (V3::from(rec.mag[k]) - h)).norm() - s.target).abs() > 5.0 * sd)
            .count();
        if missed * 2 > at.len() {
            return Err(Error::Unsupported(format!(
                "line {}: {} sits at {edge} in {} rows, held over consecutive rows, and an ellipsoid fitted without them misses {missed} of them by more than 5 standard deviations: saturated; give the full scale (full_scale) or record within the range",
                rec.lines[at[0]],
                MAG[axes.from[a].0],
                at.len()
            )));
        }
    }
    Ok(())
}

/// The reported coefficients (module docs), with their joint covariance.
fn outputs(s: &Solved, o: &MagOptions) -> Result<Estimates> {
    let e = &s.fit.estimates;
    let aligned = e.len() > fit::UNKNOWNS;
    let p = e.len();
    // The reference field as one more input (type B, independent).
    let (mut names, mut values) = (e.names().to_vec(), e.values().as_slice().to_vec());
    let mut cov = DMatrix::zeros(p + 1, p + 1);
    cov.view_mut((0, 0), (p, p)).copy_from(e.covariance());
    names.push("field_reference".into());
    values.push(o.field_ut.unwrap_or(1.0));
    cov[(p, p)] = o.u_field_ut.powi(2);
    let all = Estimates::new(names, DVector::from_vec(values), cov, e.dof())?;
    let mut out: Vec<String> = fit::HARD
        .iter()
        .chain(fit::SOFT.iter())
        .map(|s| s.to_string())
        .collect();
    out.push("field_raw".into());
    let ut = o.unit.ut();
    if ut.is_some() {
        out.push("field_ut".into());
    }
    if aligned {
        out.extend(
            [
                "alignment_x_deg",
                "alignment_y_deg",
                "alignment_z_deg",
                "inclination_deg",
            ]
            .map(String::from),
        );
    }
    let given = o.field_ut.is_some();
    all.map_numeric(out, move |x| {
        let c = fit::sym(&x.as_slice()[3..fit::UNKNOWNS]);
        let radius = c.determinant().abs().powf(-1.0 / 3.0);
        let scale = if given { x[p] } else { radius };
        let mut v: Vec<f64> = x.as_slice()[..3].to_vec();
        v.extend(x.as_slice()[3..fit::UNKNOWNS].iter().map(|c| scale * c));
        v.push(radius);
        if let Some(k) = ut {
            v.push(k * radius);
        }
        if aligned {
            v.extend(
                x.as_slice()[fit::UNKNOWNS..p]
                    .iter()
                    .map(|a| a.to_degrees()),
            );
        }
        DVector::from_vec(v)
    })
}

/// Compare the fitted field and inclination with the given ones.
fn compare(mut r: MagResult) -> MagResult {
    let k = r.coefficients.coverage_factor(0.95);
    if let (Some(f), Some(v)) = (r.options.field_ut, r.coefficients.value("field_ut")) {
        let ratio = v / f;
        if !(0.5..=2.0).contains(&ratio) {
            r.warnings.push(Warning::new(
                WarningCode::UnitSuspect,
                format!("the ellipsoid's radius is {v:.4} uT read as {} and the local field is {f} uT (ratio {ratio:.3}): is the unit right?", r.options.unit.as_str()),
            ));
        }
    }
    if let (Some(i0), Some((i, u))) = (
        r.options.inclination_deg,
        r.coefficients.get("inclination_deg"),
    ) {
        let big_u = (k * k * u * u + 4.0 * r.options.u_inclination_deg.powi(2)).sqrt();
        let en = (i - i0) / big_u.max(f64::MIN_POSITIVE);
        if en.abs() > 1.0 {
            r.warnings.push(Warning::new(
                WarningCode::FieldMismatch,
                format!("the fitted inclination {i:.3}° differs from the local {i0}° by {:.3}° (En = {en:.2}): a magnetic disturbance near the rig, an uncalibrated accelerometer, or the wrong site", i - i0),
            ));
        }
    }
    r
}

/// The magnetometer calibration as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Mag;

impl crate::procedures::Procedure for Mag {
    const ID: crate::document::Procedure = crate::document::Procedure::Mag;
    type Options = MagOptions;
    type Input = Record;

    fn example() -> MagOptions {
        MagOptions {
            field_ut: Some(50.0),
            inclination_deg: Some(60.0),
            ..MagOptions::default()
        }
    }

    fn validate(o: &MagOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(rows: &mut incal_io::Reader<R>, o: &MagOptions) -> Result<Record> {
        input::read(rows, &Axes::parse(&o.axes)?)
    }

    fn reduce(
        rec: &Record,
        o: &MagOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(rec, o)?.document()
    }

    fn synthesis(
        rec: &Record,
        o: &MagOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
