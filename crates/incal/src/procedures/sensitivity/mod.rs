//! Environmental sensitivities: vibration rectification and
//! vibropendulous error, magnetic sensitivity, and the shift across a
//! shock, from runs at several levels of the stimulus
//! (docs/src/sensitivity.md).
//!
//! # Runs
//! A session is a sequence of runs ([`input`]), each at one level of the
//! stimulus (and of the applied input, where a scale factor is wanted);
//! the first `settle_s` seconds of each run are dropped. Each run's mean
//! is its bias at that level.
//!
//! # Uncertainty of the run means
//! Not `σ/√n`: the noise of the output is modelled from the runs' own
//! samples (white, flicker and random walk fitted to their pooled Allan
//! variance) and the run means' joint covariance follows from it
//! ([`noise`]): a run's u is the Allan deviation at its own length, and
//! runs far apart in time are allowed to have drifted apart by what the
//! flicker and random walk give. The flicker and walk are chosen with the
//! run means' own evidence ([`noise::NoiseModel::profile`]), in two
//! passes where a drift and a term of the order rule look alike
//! (`fit_column`).
//!
//! # Sensitivities
//! The run means are fitted by generalized least squares against the
//! stimulus ([`fit`]): quadratic in the vibration level (the vibration
//! rectification coefficient, IEEE Std 1293-2018 and IEEE Std 1431-2004
//! §12.17; the vibropendulous coefficient from runs at ±45° in the
//! input–pendulous plane), linear in the field (the magnetic sensitivity,
//! IEEE Std 952-2020 and IEEE Std 1431-2004 §12.16: per output axis and
//! field axis, °/h/mT or µg/mT), and the change across each shock with
//! its En against the runs before it. incal's one lack-of-fit rule
//! chooses the order. A term whose `|value| ≤ U95` is flagged
//! (`not-significant`).

pub mod document;
pub mod fit;
pub mod input;
mod montecarlo;
pub mod noise;
pub mod plan;
pub mod sim;

use nalgebra::DMatrix;

use crate::error::{Error, Result};
use crate::estimation::Estimates;
use crate::options::{check_range, invalid};
use crate::warning::{Warning, WarningCode};
use input::Record;

/// Samples a run keeps at least.
pub const MIN_RUN_SAMPLES: usize = 16;
/// Runs a session holds at most (the run means' covariance is runs ×
/// runs, factored many times).
pub const MAX_RUNS: usize = 500;

/// The stimulus.
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
pub enum Kind {
    /// From the file's stimulus columns.
    #[default]
    Auto,
    /// Vibration (`vib_g`): rectification and vibropendulous error.
    Vibration,
    /// Magnetic field (`field_*_mt`): magnetic sensitivity.
    Magnetic,
    /// Shock (`shock_g`): the shift across each shock.
    Shock,
}

impl Kind {
    /// The kind's name.
    pub fn as_str(self) -> &'static str {
        match self {
            Kind::Auto => "auto",
            Kind::Vibration => "vibration",
            Kind::Magnetic => "magnetic",
            Kind::Shock => "shock",
        }
    }

    /// The rig that applies it (the certificate's rig).
    pub fn rig(self) -> &'static str {
        match self {
            Kind::Magnetic => "helmholtz-coil",
            Kind::Shock => "shock-machine",
            Kind::Vibration | Kind::Auto => "shaker",
        }
    }
}

/// The instrument.
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
pub enum Sensor {
    /// An accelerometer: sensitivities in µg per unit of the stimulus.
    #[default]
    Accel,
    /// A gyro: sensitivities in °/h per unit of the stimulus.
    Gyro,
}

impl Sensor {
    /// Reporting units per input unit of a unit scale factor: 10⁶ µg per
    /// g, 3600 °/h per °/s (the simulator's scale factor; the plan's ppm).
    pub fn unit_scale_factor(self) -> f64 {
        match self {
            Sensor::Accel => 1e6,
            Sensor::Gyro => 3600.0,
        }
    }
}

/// How `vib_g` states the level.
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
pub enum Level {
    /// g rms (random or sine vibration).
    #[default]
    Rms,
    /// g peak of a sine (`g_rms = g_peak/√2`).
    Peak,
}

/// Options of the sensitivity reduction. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensitivityOptions {
    /// The stimulus (default auto: from the file's columns).
    #[serde(default)]
    pub kind: Kind,
    /// The instrument (default accel).
    #[serde(default)]
    pub sensor: Sensor,
    /// The output columns, comma-separated (default `output`); with
    /// several, every coefficient is named with the column's axis
    /// (`gyro_x` → `_x`).
    #[serde(default = "output")]
    pub output_columns: String,
    /// The output columns' unit: accel `g` (default), `mg`, `ug`,
    /// `m_s2`; gyro `deg_s` (default), `deg_h`, `rad_s`.
    #[serde(default)]
    pub unit: Option<String>,
    /// How `vib_g` states the level (default rms).
    #[serde(default)]
    pub level: Level,
    /// Sampling rate (Hz) when the file has no `time_s`.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// Seconds dropped at the start of each run (default 0): the
    /// transient after the stimulus is set.
    #[serde(default)]
    pub settle_s: f64,
    /// The rig (default from the kind: shaker, helmholtz-coil,
    /// shock-machine): the certificate's traceability.
    #[serde(default)]
    pub rig: Option<String>,
}

fn output() -> String {
    "output".into()
}

impl Default for SensitivityOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

/// The rigs a sensitivity is measured on.
pub const RIGS: [&str; 3] = ["shaker", "helmholtz-coil", "shock-machine"];

impl SensitivityOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        self.column_names()?;
        self.output_scale()?;
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-6, 1e9, "Hz")?;
        }
        check_range("settle_s", self.settle_s, 0.0, 1e7, "s")?;
        if let Some(r) = &self.rig {
            if !RIGS.contains(&r.as_str()) {
                return invalid(
                    "rig",
                    format!("'{}': give one of {}", incal_io::clip(r), RIGS.join(", ")),
                );
            }
        }
        Ok(())
    }

    /// The output columns.
    pub fn column_names(&self) -> Result<Vec<String>> {
        let v: Vec<String> = self
            .output_columns
            .split(',')
            .map(|s| s.trim().to_string())
            .collect();
        if v.iter().any(String::is_empty) {
            return invalid("output_columns", "an empty column name");
        }
        for (i, c) in v.iter().enumerate() {
            if v[..i].contains(c) {
                return invalid("output_columns", format!("'{}' twice", incal_io::clip(c)));
            }
        }
        Ok(v)
    }

    /// The unit coefficients are reported in: `ug` or `deg/h`.
    pub fn report_unit(&self) -> &'static str {
        match self.sensor {
            Sensor::Accel => "ug",
            Sensor::Gyro => "deg/h",
        }
    }

    /// The input's unit: `g` or `deg/s`.
    pub fn input_unit(&self) -> &'static str {
        match self.sensor {
            Sensor::Accel => "g",
            Sensor::Gyro => "deg/s",
        }
    }

    /// Reporting units per unit of the file's output columns.
    pub fn output_scale(&self) -> Result<f64> {
        let (default, table): (&str, &[(&str, f64)]) = match self.sensor {
            Sensor::Accel => (
                "g",
                &[
                    ("g", 1e6),
                    ("mg", 1e3),
                    ("ug", 1.0),
                    ("m_s2", 1e6 / 9.80665),
                ],
            ),
            Sensor::Gyro => (
                "deg_s",
                &[
                    ("deg_s", 3600.0),
                    ("deg_h", 1.0),
                    ("rad_s", 3600.0 * 180.0 / std::f64::consts::PI),
                ],
            ),
        };
        let u = self.unit.as_deref().unwrap_or(default);
        match table.iter().find(|(n, _)| *n == u) {
            Some((_, k)) => Ok(*k),
            None => invalid(
                "unit",
                format!(
                    "'{}' is not a unit of the {} output: give one of {}",
                    incal_io::clip(u),
                    match self.sensor {
                        Sensor::Accel => "accelerometer's",
                        Sensor::Gyro => "gyro's",
                    },
                    table.iter().map(|t| t.0).collect::<Vec<_>>().join(", ")
                ),
            ),
        }
    }

    /// The column's axis label in coefficient names (`gyro_x` → `x`),
    /// `None` with one column.
    pub fn labels(&self) -> Result<Vec<Option<String>>> {
        let cols = self.column_names()?;
        if cols.len() == 1 {
            return Ok(vec![None]);
        }
        let short: Vec<String> = cols
            .iter()
            .map(|c| c.rsplit('_').next().unwrap_or(c).to_string())
            .collect();
        let unique = short
            .iter()
            .enumerate()
            .all(|(i, s)| !short[..i].contains(s));
        Ok(if unique { short } else { cols }
            .into_iter()
            .map(Some)
            .collect())
    }
}

/// One output column's fit and its reported coefficients.
#[derive(Debug, Clone)]
pub struct ColumnResult {
    /// The column.
    pub column: String,
    /// Its label in names (`None`: one column).
    pub label: Option<String>,
    /// The noise model.
    pub noise: noise::NoiseModel,
    /// The fit.
    pub fit: fit::OutputFit,
    /// The run means' covariance (positive definite, module docs of
    /// [`noise`]).
    pub covariance: DMatrix<f64>,
    /// The reported coefficients.
    pub coefficients: Estimates,
}

/// A reduced session.
#[derive(Debug, Clone)]
pub struct SensitivityResult {
    /// The options, `kind` and `rig` settled.
    pub options: SensitivityOptions,
    /// The session.
    pub record: Record,
    /// Per output column.
    pub columns: Vec<ColumnResult>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

/// A coefficient's name for an output column.
pub fn coefficient_name(term: &str, label: Option<&str>) -> String {
    match (label, term.strip_prefix("magnetic_")) {
        (None, _) => term.to_string(),
        (Some(l), Some(rest)) => format!("magnetic_{l}_{rest}"),
        (Some(l), None) => format!("{term}_{l}"),
    }
}

/// Each run's kept span, for the noise model's run covariance.
pub(crate) fn spans(rec: &Record) -> Vec<noise::Span> {
    rec.runs
        .iter()
        .map(|r| noise::Span {
            start_s: r.start_s,
            length_s: r.duration_s,
        })
        .collect()
}

/// Reduce a session (module docs).
pub fn reduce(rec: &Record, o: &SensitivityOptions) -> Result<SensitivityResult> {
    reduce_terms(rec, o, None)
}

/// [`reduce`], with each output column's terms fixed to those named in
/// `terms` (in column order; the Monte Carlo's trials keep the terms the
/// order rule chose for the recording) instead of the order rule.
pub(crate) fn reduce_terms(
    rec: &Record,
    o: &SensitivityOptions,
    terms: Option<&[Vec<String>]>,
) -> Result<SensitivityResult> {
    o.validate()?;
    if rec.runs.is_empty() {
        return Err(Error::Unsupported("no runs".into()));
    }
    let model = fit::model(rec)?;
    fit::require_separable(&model.base)?;
    if rec.runs.len() < 2 {
        return Err(Error::Unsupported(format!(
            "{} run: a sensitivity needs runs at two levels of the stimulus or more",
            rec.runs.len()
        )));
    }
    let labels = o.labels()?;
    let spans = spans(rec);
    let mut columns = Vec::new();
    let mut warnings = Vec::new();
    for (j, column) in rec.columns.iter().enumerate() {
        let samples: Vec<&[f64]> = rec.runs.iter().map(|r| r.samples[j].as_slice()).collect();
        let points = noise::pooled_avar(&samples, rec.dt_s);
        let y: Vec<f64> = samples
            .iter()
            .map(|s| s.iter().sum::<f64>() / s.len() as f64)
            .collect();
        let fixed = terms.map(|t| t[j].as_slice());
        let (nm, f) = fit_column(&points, &spans, &model, &y, fixed).map_err(|e| {
            match rec.columns.len() {
                1 => e,
                _ => Error::Unsupported(format!("column '{column}': {e}")),
            }
        })?;
        let cov = nm.run_covariance(&spans)?;
        let label = labels[j].clone();
        let coefficients = reported(&f, label.as_deref())?;
        flag(&coefficients, &mut warnings);
        columns.push(ColumnResult {
            column: column.clone(),
            label,
            noise: nm,
            fit: f,
            covariance: cov,
            coefficients,
        });
    }
    let mut options = o.clone();
    options.kind = rec.kind;
    options
        .rig
        .get_or_insert_with(|| rec.kind.rig().to_string());
    Ok(SensitivityResult {
        options,
        record: rec.clone(),
        columns,
        warnings,
    })
}

/// The noise model and the fit of one column, in two passes: the noise
/// ([`choose_noise`]) under the richest model of the order rule that
/// leaves the run means a residual (so that a missing term is not taken
/// for drift), the order rule with it; then the noise again under the
/// terms the rule chose (their residuals tell the drift best) and the
/// fit of those terms with it, the first pass's steps kept. `fixed`:
/// the terms named there instead of the order rule's (the noise chosen
/// as for the rule's).
fn fit_column(
    points: &[noise::AvarPoint],
    spans: &[noise::Span],
    model: &fit::Model,
    y: &[f64],
    fixed: Option<&[String]>,
) -> Result<(noise::NoiseModel, fit::OutputFit)> {
    let mut richest = model.base.clone();
    for t in &model.extras {
        let mut more = richest.clone();
        more.push(t.clone());
        if more.len() + 1 > y.len() || !fit::separable(&more) {
            break;
        }
        richest = more;
    }
    let first = choose_noise(points, spans, &richest, y)?;
    let first = noise::NoiseModel {
        dof: satterthwaite(&first, spans, &model.base)?,
        ..first
    };
    let forced = fixed.map(|names| fit::Model {
        base: model
            .base
            .iter()
            .chain(&model.extras)
            .filter(|t| names.contains(&t.name))
            .cloned()
            .collect(),
        extras: Vec::new(),
    });
    let f1 = fit::fit_output(
        forced.as_ref().unwrap_or(model),
        y,
        &first.run_covariance(spans)?,
        first.dof,
    )?;
    // The noise under the chosen terms, and under the base terms alone:
    // where the runs cannot tell a drift from a term of the order rule
    // the two differ, and the one giving the larger u is kept.
    let mut nm = choose_noise(points, spans, &f1.terms, y)?;
    if f1.terms.len() > model.base.len() {
        let other = choose_noise(points, spans, &model.base, y)?;
        let sum = |m: &noise::NoiseModel| -> Result<f64> {
            Ok(reported_variances(m, spans, &f1.terms)?.iter().sum())
        };
        if sum(&other)? > sum(&nm)? {
            nm = other;
        }
    }
    let nm = noise::NoiseModel {
        dof: satterthwaite(&nm, spans, &f1.terms)?,
        ..nm
    };
    let chosen = fit::Model {
        base: f1.terms.clone(),
        extras: Vec::new(),
    };
    let mut f = fit::fit_output(&chosen, y, &nm.run_covariance(spans)?, nm.dof)?;
    f.trials = f1.trials;
    Ok((nm, f))
}

/// The covariance `(AᵀΣ⁻¹A)⁻¹` of `terms` fitted to run means of
/// covariance `cov` (the fit's, when the runs scatter as the noise says;
/// also the plan's prediction).
pub fn terms_covariance(terms: &[fit::Term], cov: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let a = fit::design_matrix(terms);
    let inv = cov
        .clone()
        .try_inverse()
        .ok_or_else(|| Error::Unsupported("singular covariance of the run means".into()))?;
    (a.transpose() * inv * &a)
        .try_inverse()
        .ok_or_else(|| Error::Unsupported("the runs cannot separate the sensitivities".into()))
}

/// The reported terms' variances under noise `nm`.
fn reported_variances(
    nm: &noise::NoiseModel,
    spans: &[noise::Span],
    terms: &[fit::Term],
) -> Result<Vec<f64>> {
    let c = terms_covariance(terms, &nm.run_covariance(spans)?)?;
    Ok((0..terms.len())
        .filter(|&k| terms[k].reported)
        .map(|k| c[(k, k)])
        .collect())
}

/// The noise model of one column ([`noise::NoiseModel::profile`]): the
/// within-run Allan variances say what the noise is at short τ, the run
/// means under `terms` (their restricted `−2ℓ`, [`fit::reml`]) how far
/// runs drift apart.
fn choose_noise(
    points: &[noise::AvarPoint],
    spans: &[noise::Span],
    terms: &[fit::Term],
    y: &[f64],
) -> Result<noise::NoiseModel> {
    noise::NoiseModel::profile(points, |m| {
        let cov = m.run_covariance(spans).ok()?;
        fit::reml(terms, y, &cov)
    })
}

/// The degrees of freedom of the sensitivities' u (Welch–Satterthwaite,
/// JCGM 100 G.4): each reported term's `u²` is a function of the noise
/// terms `θ` (white, flicker, walk) with the Allan fit's covariance
/// `C_θ` ([`noise::NoiseModel::terms_covariance`]), so
/// `ν = 2u⁴ / (gᵀ C_θ g)` with `g = ∂u²/∂θ` by differences; the least
/// over the terms (at least 1).
fn satterthwaite(
    nm: &noise::NoiseModel,
    spans: &[noise::Span],
    terms: &[fit::Term],
) -> Result<f64> {
    let u2 = |m: &noise::NoiseModel| reported_variances(m, spans, terms);
    let base = u2(nm)?;
    let ct = nm.terms_covariance();
    let theta = [nm.white, nm.flicker, nm.walk];
    let e = 1e-4;
    let mut g = vec![[0.0; 3]; base.len()];
    for k in (0..3).filter(|&k| theta[k] > 0.0) {
        let up = u2(&nm.scaled(k, e))?;
        for (i, v) in up.iter().enumerate() {
            g[i][k] = (v - base[i]) / (e * theta[k]);
        }
    }
    let mut dof = f64::INFINITY;
    for (i, gi) in g.iter().enumerate() {
        let mut var = 0.0;
        for a in 0..3 {
            for b in 0..3 {
                var += gi[a] * ct[(a, b)] * gi[b];
            }
        }
        if var > 0.0 {
            dof = dof.min(2.0 * base[i] * base[i] / var);
        }
    }
    Ok(dof.max(1.0))
}

/// The reported coefficients of one column (module docs of [`fit`]).
fn reported(f: &fit::OutputFit, label: Option<&str>) -> Result<Estimates> {
    let e = &f.fit.estimates;
    let sf = f.terms.iter().position(|t| t.name == "scale_factor");
    let picks: Vec<(usize, bool)> = f
        .terms
        .iter()
        .enumerate()
        .filter(|(_, t)| t.reported)
        .map(|(k, t)| (k, t.sf))
        .collect();
    let names = picks
        .iter()
        .map(|(k, _)| coefficient_name(&f.terms[*k].name, label))
        .collect();
    if let (Some(k), true) = (sf, picks.iter().any(|p| p.1)) {
        let (v, u) = (e.values()[k], e.u_at(k));
        if v.abs() <= e.coverage_factor(0.95) * u {
            return Err(Error::Unsupported(format!(
                "the scale factor from the input column is {v:.4e} ± {u:.2e}: not distinguishable from zero, so its sensitivity in ppm means nothing; is input the drive of this output?"
            )));
        }
    }
    let picks2 = picks.clone();
    e.map_numeric(names, move |x| {
        nalgebra::DVector::from_iterator(
            picks2.len(),
            picks2.iter().map(|(k, is_sf)| match (is_sf, sf) {
                (true, Some(s)) => 1e6 * x[*k] / x[s],
                _ => x[*k],
            }),
        )
    })
}

/// Warn of the coefficients not distinguishable from zero.
fn flag(e: &Estimates, warnings: &mut Vec<Warning>) {
    let k = e.coverage_factor(0.95);
    let weak: Vec<String> = e
        .names()
        .iter()
        .filter_map(|n| {
            let (v, u) = e.get(n)?;
            (v.abs() <= k * u).then(|| n.clone())
        })
        .collect();
    if !weak.is_empty() {
        warnings.push(Warning::new(
            WarningCode::NotSignificant,
            format!(
                "{} not distinguishable from zero (|value| <= U95): the stimulus's effect is within the noise; a larger stimulus or longer runs would resolve it",
                weak.join(", ")
            ),
        ));
    }
}

/// The sensitivity reduction as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Sensitivity;

impl crate::procedures::Procedure for Sensitivity {
    const ID: crate::document::Procedure = crate::document::Procedure::Sensitivity;
    type Options = SensitivityOptions;
    type Input = Record;

    fn example() -> SensitivityOptions {
        SensitivityOptions::default()
    }

    fn validate(o: &SensitivityOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &SensitivityOptions,
    ) -> Result<Record> {
        input::read(rows, o)
    }

    fn reduce(
        rec: &Record,
        o: &SensitivityOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        reduce(rec, o)?.document()
    }

    fn recorded(
        rec: &Record,
        o: &SensitivityOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        let mut settled = o.clone();
        settled.kind = rec.kind;
        settled
            .rig
            .get_or_insert_with(|| rec.kind.rig().to_string());
        crate::procedures::options_map(&settled)
    }

    fn synthesis(
        rec: &Record,
        o: &SensitivityOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}
