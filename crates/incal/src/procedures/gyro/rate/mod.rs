//! Rate-transfer test on a rate table (IEEE Std 952-1997 §12.3.3, IEEE Std
//! 1431-2004 §10.3.4): scale factor, bias, nonlinearity, asymmetry and
//! scale-factor repeatability.
//!
//! # Model
//! The input axis (IA) is along the table axis, up (`s = +1`) or down
//! (`s = −1`). The table turns at `ω_k` (deg/s, positive counter-clockwise
//! seen from above, the sense of the Earth's rotation), so the rate along IA
//! is
//!
//! ```text
//! ω_in = s (ω_k + Ω_e sin φ)                        (deg/s)
//! E    = K1 (ω_in + B + K2 ω_in² + K3 ω_in³)        (IEEE 952 eq. C.1, reduced)
//! ```
//!
//! which is linear in `a0 = K1 B`, `a1 = K1`, `a2 = K1 K2`, `a3 = K1 K3`:
//! the position means are fitted for `a` ([`crate::estimation::fit_means`])
//! and mapped to `K1 = a1` (output/(deg/s)), `B = 3600 a0/a1` (deg/h),
//! `K2 = a2/a1` (1/(deg/s)), `K3 = a3/a1` (1/(deg/s)²) with their
//! covariance (JCGM 100 §5.2).
//!
//! * **Asymmetry** (IEEE 952 §3, "scale factor asymmetry"): with input
//!   rates of both signs the model has separate slopes `K1⁺ = K1 + ΔK/2`
//!   for positive and `K1⁻ = K1 − ΔK/2` for negative rates and a shared
//!   bias, i.e. one more regressor `|ω_in|` with coefficient `c = ΔK/2`:
//!   `E = a0 + a1 ω + c |ω| + a2 ω² + a3 ω³`, one fit, one covariance;
//!   `asymmetry = ΔK/K1 · 10⁶ = 2c/a1 · 10⁶` ppm, and `K1_pos`, `K1_neg`
//!   derived. Left out of the model, an asymmetry leaks into B and K2
//!   (|ω| resembles a constant plus ω²); when the rates cannot separate
//!   `|ω|` from the other terms (e.g. two magnitudes with K2) the model
//!   falls back to one slope and a warning names the combination.
//! * **Nonlinearity** (IEEE 952 §3, "scale factor nonlinearity"): the largest
//!   deviation of the mean outputs from their least-squares straight line
//!   `E = c0 + c1 ω_in`, in ppm of the full-scale output `|c1| max|ω_in|`.
//! * **Repeatability**: with a `run` label, each run is fitted alone and the
//!   standard deviation of its K1 across runs is given in ppm of their mean,
//!   with `runs − 1` degrees of freedom.
//! * **Rate-table rate error** `ε` (relative, type B, `--rate-uncertainty-ppm`):
//!   the true rates are `(1 + ε) ω_k`, so the fitted K1, B, K2, K3 move by
//!   `(K1, −B, K2, 2 K3) ε`; that covariance is added with infinite degrees
//!   of freedom and each coefficient's dof is Welch–Satterthwaite.

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod range;
pub mod sim;

pub use plan::plan;

use nalgebra::{DMatrix, DVector};

use super::{earth_rate_deg_s, group, welch_satterthwaite};
use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::warning::{Warning, WarningCode};

/// One sample of a rate-transfer test.
#[derive(Debug, Clone, PartialEq)]
pub struct RateObservation {
    /// Commanded table rate (deg/s), positive counter-clockwise from above.
    pub rate_deg_s: f64,
    /// Gyro output (output units).
    pub output: f64,
    /// Run label (`None`: a single run).
    pub run: Option<String>,
}

/// Direction of the input axis on the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputAxis {
    /// IA up, along the table's positive rotation axis (`s = +1`).
    Up,
    /// IA down (`s = −1`).
    Down,
}

impl InputAxis {
    /// `s = ±1`.
    pub fn sign(self) -> f64 {
        match self {
            InputAxis::Up => 1.0,
            InputAxis::Down => -1.0,
        }
    }
    /// `up` or `down`.
    pub fn name(self) -> &'static str {
        match self {
            InputAxis::Up => "up",
            InputAxis::Down => "down",
        }
    }
    /// Parse `up` or `down` (case-insensitive).
    pub fn parse(s: &str) -> Result<InputAxis> {
        match s.trim().to_ascii_lowercase().as_str() {
            "up" => Ok(InputAxis::Up),
            "down" => Ok(InputAxis::Down),
            other => Err(Error::Unsupported(format!(
                "unknown input-axis direction '{other}' (use up or down)"
            ))),
        }
    }
}

crate::named_enum!(InputAxis, [InputAxis::Up, InputAxis::Down]);
crate::named_enum!(
    RateTerm,
    [RateTerm::B, RateTerm::K1, RateTerm::K2, RateTerm::K3]
);

/// A term of the rate model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum RateTerm {
    /// Bias (deg/h).
    B,
    /// Scale factor (output/(deg/s)); always fitted.
    K1,
    /// Second-order nonlinearity (1/(deg/s)).
    K2,
    /// Third-order nonlinearity (1/(deg/s)²).
    K3,
}

impl RateTerm {
    /// Parse `K1`, `B`, `K2`, `K3` (case-insensitive).
    pub fn parse(s: &str) -> Result<RateTerm> {
        match s.trim().to_ascii_uppercase().as_str() {
            "K1" => Ok(RateTerm::K1),
            "B" => Ok(RateTerm::B),
            "K2" => Ok(RateTerm::K2),
            "K3" => Ok(RateTerm::K3),
            other => Err(Error::Unsupported(format!(
                "unknown rate-test term '{other}' (terms: K1, B, K2, K3)"
            ))),
        }
    }
    /// The coefficient name.
    pub fn name(self) -> &'static str {
        match self {
            RateTerm::B => "B",
            RateTerm::K1 => "K1",
            RateTerm::K2 => "K2",
            RateTerm::K3 => "K3",
        }
    }
    /// Unit string of the coefficient.
    pub fn unit(self) -> &'static str {
        match self {
            RateTerm::B => "deg/h",
            RateTerm::K1 => "output/(deg/s)",
            RateTerm::K2 => "1/(deg/s)",
            RateTerm::K3 => "1/(deg/s)^2",
        }
    }
    /// Power of ω_in of the regressor.
    fn power(self) -> i32 {
        match self {
            RateTerm::B => 0,
            RateTerm::K1 => 1,
            RateTerm::K2 => 2,
            RateTerm::K3 => 3,
        }
    }
}

/// Unit string of any rate-test coefficient (`K1`, `B`, `K2`, `K3`,
/// `asymmetry` in ppm, `K1_pos`/`K1_neg`).
pub fn coefficient_unit(name: &str) -> &'static str {
    match name {
        "asymmetry" => "ppm",
        "K1_pos" | "K1_neg" => "output/(deg/s)",
        other => RateTerm::parse(other).map_or("1", |t| t.unit()),
    }
}

/// Largest table rate a recording or a plan may hold (deg/s).
pub const MAX_RATE_DEG_S: f64 = 1e5;

/// Largest relative uncertainty of the table rate (ppm).
pub const MAX_RATE_UNCERTAINTY_PPM: f64 = 1e5;

/// Default terms of the reduction: B and K1.
pub fn default_terms() -> Vec<RateTerm> {
    vec![RateTerm::B, RateTerm::K1]
}

/// Options of the rate-transfer test, validated once by
/// [`GyroRateOptions::validate`]. In the document's `options`:
/// `{"ia": "up", "latitude_deg": 45.0, "noise": null,
/// "rate_uncertainty_ppm": 0.0, "terms": ["B", "K1"]}` (`latitude_deg` as
/// given; `noise` the known σ of one output sample or null for "from the
/// data"; `terms` as fitted: sorted, K1 added).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GyroRateOptions {
    /// Latitude φ of the rate table (deg, −90…90).
    pub latitude_deg: f64,
    /// Input axis up or down.
    #[serde(default = "default_ia")]
    pub ia: InputAxis,
    /// Terms (K1 is added when missing; default B and K1).
    #[serde(default = "default_terms", serialize_with = "serialize_terms")]
    pub terms: Vec<RateTerm>,
    /// Noise of one output sample.
    #[serde(default)]
    pub noise: Noise,
    /// Relative standard uncertainty of the table rate (ppm, type B,
    /// 0…[`MAX_RATE_UNCERTAINTY_PPM`]).
    #[serde(default)]
    pub rate_uncertainty_ppm: f64,
    /// Largest nonlinearity over the input range (ppm of the range's
    /// full-scale output): with it the input range is found and rates
    /// beyond it are left out of the fit ([`range`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linearity_ppm: Option<f64>,
    /// The output's limit (output units): a rate with a sample at or
    /// beyond it is clipped (default: clipped rates found at the record's
    /// rails, [`range`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_limit: Option<f64>,
}

fn default_ia() -> InputAxis {
    InputAxis::Up
}

/// The terms as fitted (sorted, K1 added), as documents record them.
fn serialize_terms<S: serde::Serializer>(
    terms: &[RateTerm],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    serde::Serialize::serialize(&term_names(terms), s)
}

impl GyroRateOptions {
    /// Refuse options no reduction can use: a latitude outside ±90°, a
    /// known noise that is not a positive number, a rate uncertainty
    /// outside 0…1e5 ppm.
    pub fn validate(&self) -> Result<()> {
        crate::options::check_latitude_deg(self.latitude_deg)?;
        self.noise.validate()?;
        if let Some(l) = self.linearity_ppm {
            crate::options::check_range("linearity_ppm", l, 1e-6, 1e6, "ppm")?;
        }
        if let Some(l) = self.output_limit {
            crate::options::check_positive("output_limit", l)?;
            crate::options::check_range("output_limit", l, 0.0, 1e300, "")?;
        }
        crate::options::check_range(
            "rate_uncertainty_ppm",
            self.rate_uncertainty_ppm,
            0.0,
            MAX_RATE_UNCERTAINTY_PPM,
            "ppm",
        )
    }

    /// Latitude φ (rad): the one conversion of the option.
    pub fn latitude_rad(&self) -> f64 {
        self.latitude_deg.to_radians()
    }
}

/// The names of the terms as fitted (sorted, K1 added).
pub(crate) fn term_names(terms: &[RateTerm]) -> Vec<&'static str> {
    normalized_terms(terms).iter().map(|t| t.name()).collect()
}

/// The rate-transfer test as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct GyroRate;

impl crate::procedures::Procedure for GyroRate {
    const ID: crate::document::Procedure = crate::document::Procedure::GyroRate;
    type Options = GyroRateOptions;
    type Input = Vec<RateObservation>;

    fn example() -> GyroRateOptions {
        GyroRateOptions {
            latitude_deg: 45.0,
            ia: InputAxis::Up,
            terms: default_terms(),
            noise: crate::estimation::Noise::Auto,
            rate_uncertainty_ppm: 0.0,
            linearity_ppm: None,
            output_limit: None,
        }
    }

    fn validate(o: &GyroRateOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &GyroRateOptions,
    ) -> Result<Vec<RateObservation>> {
        input::read(rows)
    }

    fn reduce(
        obs: &Vec<RateObservation>,
        o: &GyroRateOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(obs, o)?.document(o.noise.sigma().is_some(), o.rate_uncertainty_ppm)
    }

    fn synthesis(
        obs: &Vec<RateObservation>,
        o: &GyroRateOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<RateObservation>>>> {
        montecarlo::synthesis(obs, o).map(Some)
    }
}

/// One rate of the test (samples at the same rate and run).
#[derive(Debug, Clone, PartialEq)]
pub struct RatePosition {
    /// Commanded table rate (deg/s).
    pub rate_deg_s: f64,
    /// Input rate along IA (deg/s).
    pub input_deg_s: f64,
    /// Run label.
    pub run: Option<String>,
    /// Sample statistics of the output.
    pub stats: PositionStats,
    /// Residual of the model fit (output units).
    pub residual: f64,
    /// Standardized residual of the model fit.
    pub standardized_residual: f64,
    /// Deviation from the least-squares straight line (output units).
    pub line_deviation: f64,
}

/// Scale factor of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunK1 {
    /// Run label.
    pub run: String,
    /// Rates in the run.
    pub rates: usize,
    /// K1 of the run alone (output/(deg/s)).
    pub k1: f64,
    /// Its standard uncertainty.
    pub u: f64,
}

/// Result of the rate-transfer test.
#[derive(Debug, Clone, PartialEq)]
pub struct RateResult {
    /// `K1`, `B`, `K2`, `K3` (those fitted), in the units of [`RateTerm::unit`],
    /// including the rate-table type-B component.
    pub coefficients: Estimates,
    /// Effective degrees of freedom of each coefficient (Welch–Satterthwaite).
    pub dof: Vec<(String, f64)>,
    /// True when the asymmetry is in the model (`asymmetry`, `K1_pos` and
    /// `K1_neg` are then among the coefficients).
    /// input rates have both signs.
    pub asymmetric: bool,
    /// Nonlinearity: largest deviation from the straight line, ppm of full scale.
    pub nonlinearity_ppm_fs: f64,
    /// Full-scale output used for the nonlinearity (output units).
    pub full_scale_output: f64,
    /// Fit of the model (in the `a` parameters).
    pub fit: Fit,
    /// Per-rate statistics and residuals.
    pub positions: Vec<RatePosition>,
    /// K1 of each run (two or more runs).
    pub runs: Vec<RunK1>,
    /// Scale-factor repeatability (ppm) and its degrees of freedom.
    pub repeatability: Option<(f64, f64)>,
    /// Terms fitted, in model order.
    pub terms: Vec<RateTerm>,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// The clipped rates (deg/s, commanded), left out of the fit.
    pub clipped_deg_s: Vec<f64>,
    /// The input range, with `linearity_ppm`.
    pub range: Option<range::InputRange>,
    /// The commanded rates beyond the input range, left out of the fit.
    pub beyond_deg_s: Vec<f64>,
}

/// Input rate along IA (deg/s): `s (ω_table + Ω_e sin φ)`.
pub fn input_rate_deg_s(rate_deg_s: f64, latitude_rad: f64, ia: InputAxis) -> f64 {
    ia.sign() * (rate_deg_s + earth_rate_deg_s() * latitude_rad.sin())
}

fn normalized_terms(terms: &[RateTerm]) -> Vec<RateTerm> {
    let mut t: Vec<RateTerm> = terms.to_vec();
    if !t.contains(&RateTerm::K1) {
        t.push(RateTerm::K1);
    }
    t.sort();
    t.dedup();
    t
}

/// Group samples into positions (rate, run), in order of first appearance.
pub fn positions_of(obs: &[RateObservation]) -> Result<Vec<(f64, Option<String>, PositionStats)>> {
    for o in obs {
        if !(o.rate_deg_s.is_finite() && o.output.is_finite()) {
            return Err(Error::InvalidValue {
                what: "rate or output".into(),
                value: format!("{} / {}", o.rate_deg_s, o.output),
            });
        }
    }
    group(
        obs.iter()
            .map(|o| ((o.rate_deg_s.to_bits(), o.run.clone()), o.output)),
    )
    .into_iter()
    .map(|((bits, run), v)| Ok((f64::from_bits(bits), run, PositionStats::of(&v)?)))
    .collect()
}

/// Design with one column per term (`ω_in^power`), plus `|ω_in|` named
/// `asymmetry` when `asym`.
fn design(inputs: &[f64], terms: &[RateTerm], asym: bool) -> Result<Design> {
    let mut names: Vec<String> = terms.iter().map(|t| t.name().to_string()).collect();
    if asym {
        names.push("asymmetry".into());
    }
    let p = names.len();
    Design::new(
        names,
        DMatrix::from_fn(inputs.len(), p, |i, j| match terms.get(j) {
            Some(t) => inputs[i].powi(t.power()),
            None => inputs[i].abs(),
        }),
    )
}

/// Map `a` (terms in order, then `c` of `|ω|` when present) to the
/// physical coefficients (module docs).
fn to_physical(a: &DVector<f64>, terms: &[RateTerm]) -> DVector<f64> {
    let k = terms.iter().position(|t| *t == RateTerm::K1).unwrap_or(0);
    let a1 = a[k];
    DVector::from_iterator(
        a.len(),
        a.iter().enumerate().map(|(j, v)| match terms.get(j) {
            Some(RateTerm::K1) => a1,
            Some(RateTerm::B) => 3600.0 * v / a1,
            Some(_) => v / a1,
            None => 2.0 * v / a1 * 1e6,
        }),
    )
}

/// Fit the model to position statistics: the `a` fit, its weights and the
/// physical estimates (without the type-B rate error).
fn fit_model(
    inputs: &[f64],
    stats: &[PositionStats],
    terms: &[RateTerm],
    asym: bool,
    noise: Noise,
) -> Result<(Fit, DVector<f64>, Estimates)> {
    let d = design(inputs, terms, asym)?;
    let (fit, w) = fit_means(&d, stats, noise)?;
    let k = terms.iter().position(|t| *t == RateTerm::K1).unwrap_or(0);
    let a1 = fit.estimates.values()[k];
    if a1 == 0.0 || !a1.is_finite() {
        return Err(Error::InvalidValue {
            what: "scale factor K1 (the output does not follow the rate)".into(),
            value: a1.to_string(),
        });
    }
    let names = d.names().to_vec();
    let t2 = terms.to_vec();
    let phys = fit
        .estimates
        .map_numeric(names, move |a| to_physical(a, &t2))?;
    Ok((fit, w, phys))
}

/// A fit, its weights, the physical estimates, whether the asymmetry is in
/// the model, and why not.
type BestFit = (Fit, DVector<f64>, Estimates, bool, Option<Warning>);

/// The model with the asymmetry when the rates have both signs and can
/// separate it; else the symmetric model and why not.
fn fit_best(
    inputs: &[f64],
    stats: &[PositionStats],
    terms: &[RateTerm],
    noise: Noise,
) -> Result<BestFit> {
    let both = inputs.iter().any(|w| *w > 0.0) && inputs.iter().any(|w| *w < 0.0);
    if !both {
        let (f, w, e) = fit_model(inputs, stats, terms, false, noise)?;
        let warn = Warning::new(
            WarningCode::OnePolarity,
            "input rates of one sign only: the scale-factor asymmetry is not determined",
        );
        return Ok((f, w, e, false, Some(warn)));
    }
    match fit_model(inputs, stats, terms, true, noise) {
        Ok((f, w, e)) => Ok((f, w, e, true, None)),
        Err(
            err @ (Error::Unseparable { .. } | Error::IllConditioned { .. } | Error::TooFew { .. }),
        ) => {
            let (f, w, e) = fit_model(inputs, stats, terms, false, noise)?;
            let warn = Warning::new(
                WarningCode::PartFailed,
                format!("asymmetry not determined (one slope fitted): {err}"),
            );
            Ok((f, w, e, false, Some(warn)))
        }
        Err(e) => Err(e),
    }
}

/// Reduce a rate-transfer test (module docs).
pub fn calibrate(obs: &[RateObservation], opts: &GyroRateOptions) -> Result<RateResult> {
    opts.validate()?;
    let terms = normalized_terms(&opts.terms);
    let mut early = Vec::new();
    let (pos, clipped_deg_s, range, beyond_deg_s) = in_range(obs, opts, &mut early)?;
    check_distinct_rates(&pos, &terms)?;
    crate::validity::require_varying(obs.iter().map(|o| o.output), "output")?;
    let inputs: Vec<f64> = pos
        .iter()
        .map(|p| input_rate_deg_s(p.0, opts.latitude_rad(), opts.ia))
        .collect();
    let stats: Vec<PositionStats> = pos.iter().map(|p| p.2).collect();
    let (fit, weights, phys, asymmetric, asym_warning) =
        fit_best(&inputs, &stats, &terms, opts.noise)?;
    crate::validity::require_scale_factor(&phys, "K1")?;
    let mut warnings = fit.quality_warnings(
        "table-rate errors, a nonlinearity not modelled (add K2/K3), or drift between rates",
    );
    warnings.extend(asym_warning);
    warnings.extend(early);

    let (base, mut dof) = with_rate_error(&phys, &terms, opts.rate_uncertainty_ppm)?;
    let coefficients = if asymmetric {
        with_slopes(base, &terms, &mut dof)?
    } else {
        base
    };
    let line = Nonlinearity::of(&inputs, &stats, &weights)?;
    let std_res = fit.standardized_residuals(Some(&weights));
    let positions = pos
        .iter()
        .enumerate()
        .map(|(i, (rate, run, st))| RatePosition {
            rate_deg_s: *rate,
            input_deg_s: inputs[i],
            run: run.clone(),
            stats: *st,
            residual: fit.residuals[i],
            standardized_residual: std_res[i],
            line_deviation: line.residuals[i],
        })
        .collect();
    let runs = runs_alone(
        &pos,
        &inputs,
        &stats,
        &terms,
        asymmetric,
        opts.noise,
        &mut warnings,
    );
    let repeatability = repeatability(&runs);
    Ok(RateResult {
        coefficients,
        dof,
        asymmetric,
        nonlinearity_ppm_fs: line.ppm_fs,
        full_scale_output: line.full_scale_output,
        fit,
        positions,
        runs,
        repeatability,
        terms,
        warnings,
        clipped_deg_s,
        range,
        beyond_deg_s,
    })
}

/// The positions left for the fit, with the clipped rates, the input
/// range and the rates beyond it ([`range`]): each named in a warning.
#[allow(clippy::type_complexity)]
fn in_range(
    obs: &[RateObservation],
    opts: &GyroRateOptions,
    warnings: &mut Vec<Warning>,
) -> Result<(
    Vec<(f64, Option<String>, PositionStats)>,
    Vec<f64>,
    Option<range::InputRange>,
    Vec<f64>,
)> {
    let all = positions_of(obs)?;
    let clip = range::clipped(obs, &all, opts.output_limit);
    let clipped: Vec<f64> = (0..all.len())
        .filter(|&i| clip[i])
        .map(|i| all[i].0)
        .collect();
    let mut pos: Vec<_> = all
        .into_iter()
        .zip(&clip)
        .filter(|(_, c)| !**c)
        .map(|(p, _)| p)
        .collect();
    if !clipped.is_empty() {
        let at = match opts.output_limit {
            Some(l) => format!("a sample at or beyond output_limit {l}"),
            None => "most samples at the record's extreme output".into(),
        };
        warnings.push(Warning::new(
            WarningCode::Saturated,
            format!(
                "the output clips at {} deg/s ({at}): left out of the fit",
                list(&clipped)
            ),
        ));
    }
    let Some(limit) = opts.linearity_ppm else {
        return Ok((pos, clipped, None, Vec::new()));
    };
    let inputs: Vec<f64> = pos
        .iter()
        .map(|p| input_rate_deg_s(p.0, opts.latitude_rad(), opts.ia))
        .collect();
    let stats: Vec<PositionStats> = pos.iter().map(|p| p.2).collect();
    let rates: Vec<f64> = pos.iter().map(|p| p.0).collect();
    // Each candidate range refits the line over the rates within it: the
    // search is bounded by refusing records of more distinct rates than
    // any rate-transfer test holds (a ramp logged as steady rates).
    let mut mags: Vec<u64> = rates.iter().map(|r| r.abs().to_bits()).collect();
    mags.sort_unstable();
    mags.dedup();
    if mags.len() > range::MAX_CANDIDATES {
        return crate::options::invalid(
            "linearity_ppm",
            format!(
                "the record holds {} distinct |rates|: the input range is searched over at most {} (a rate-transfer test holds each rate; is this a ramp?)",
                mags.len(),
                range::MAX_CANDIDATES
            ),
        );
    }
    let r = range::input_range(&rates, &inputs, &stats, limit);
    let beyond: Vec<f64> = r.beyond.iter().map(|&i| pos[i].0).collect();
    match r.range_deg_s {
        Some(range) if !beyond.is_empty() => warnings.push(Warning::new(
            WarningCode::ModelRange,
            format!(
                "the nonlinearity exceeds {limit} ppm beyond the input range {range} deg/s: the rates {} deg/s are left out of the fit",
                list(&beyond)
            ),
        )),
        Some(_) => {}
        None => warnings.push(Warning::new(
            WarningCode::ModelRange,
            format!("no range of three rates or more meets a nonlinearity of {limit} ppm: no input range, every rate fitted"),
        )),
    }
    let keep: Vec<bool> = (0..pos.len()).map(|i| !r.beyond.contains(&i)).collect();
    let mut k = 0;
    pos.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    Ok((pos, clipped, Some(r), beyond))
}

/// Rates as a short list (`-500, 500`, at most 8 then `…`).
fn list(rates: &[f64]) -> String {
    let mut v: Vec<String> = rates.iter().take(8).map(|r| format!("{r}")).collect();
    if rates.len() > 8 {
        v.push(format!("and {} more", rates.len() - 8));
    }
    v.join(", ")
}

/// Refuse fewer distinct table rates than terms.
fn check_distinct_rates(
    pos: &[(f64, Option<String>, PositionStats)],
    terms: &[RateTerm],
) -> Result<()> {
    let distinct_rates = {
        let mut r: Vec<u64> = pos.iter().map(|p| p.0.to_bits()).collect();
        r.sort();
        r.dedup();
        r.len()
    };
    if distinct_rates < terms.len() {
        return Err(Error::TooFew {
            what: format!(
                "distinct table rates for the terms {}",
                terms
                    .iter()
                    .map(|t| t.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            needed: terms.len(),
            got: distinct_rates,
        });
    }
    Ok(())
}

/// Add the type-B rate-table error `ε` (relative, `rate_uncertainty_ppm`)
/// to the physical estimates: the coefficients move by
/// `J ε = (K1, −B, K2, 2 K3, 0) ε` (module docs), covariance
/// `J Jᵀ u²(ε)` with infinite degrees of freedom. Returns the estimates
/// and each coefficient's Welch–Satterthwaite dof.
fn with_rate_error(
    phys: &Estimates,
    terms: &[RateTerm],
    rate_uncertainty_ppm: f64,
) -> Result<(Estimates, Vec<(String, f64)>)> {
    // Type-B rate-table error: (K1, −B, K2, 2 K3, 0) ε.
    let eps = rate_uncertainty_ppm * 1e-6;
    let j = DVector::from_iterator(
        phys.len(),
        (0..phys.len()).map(|k| {
            let v = phys.values()[k];
            match terms.get(k) {
                Some(RateTerm::K1) | Some(RateTerm::K2) => v,
                Some(RateTerm::B) => -v,
                Some(RateTerm::K3) => 2.0 * v,
                None => 0.0,
            }
        }),
    );
    let cov_b = &j * j.transpose() * (eps * eps);
    let base = Estimates::new(
        phys.names().to_vec(),
        phys.values().clone(),
        phys.covariance() + &cov_b,
        phys.dof(),
    )?;
    let dof: Vec<(String, f64)> = phys
        .names()
        .iter()
        .enumerate()
        .map(|(k, n)| {
            (
                n.clone(),
                welch_satterthwaite(&[
                    (phys.u_at(k), phys.dof()),
                    (j[k].abs() * eps, f64::INFINITY),
                ]),
            )
        })
        .collect();
    Ok((base, dof))
}

/// Append the slopes `K1_pos = K1 (1 + A·10⁻⁶/2)` and
/// `K1_neg = K1 (1 − A·10⁻⁶/2)` (A the `asymmetry` in ppm, the last
/// coefficient of `base`) with their covariance; both take the dof of K1.
fn with_slopes(
    base: Estimates,
    terms: &[RateTerm],
    dof: &mut Vec<(String, f64)>,
) -> Result<Estimates> {
    let ik = terms.iter().position(|t| *t == RateTerm::K1).unwrap_or(0);
    let ia = base.len() - 1;
    let n = base.len();
    let e = base.augment(
        vec!["K1_pos".into(), "K1_neg".into()],
        move |x| {
            let dk = x[ia] * 1e-6 * x[ik];
            DVector::from_vec(vec![x[ik] + 0.5 * dk, x[ik] - 0.5 * dk])
        },
        move |x| {
            // K1± = K1 (1 ± A·1e-6/2): ∂/∂K1 = 1 ± A·1e-6/2, ∂/∂A = ±K1·1e-6/2.
            let mut m = DMatrix::zeros(2, n);
            let h = 0.5e-6;
            m[(0, ik)] = 1.0 + h * x[ia];
            m[(1, ik)] = 1.0 - h * x[ia];
            m[(0, ia)] = h * x[ik];
            m[(1, ia)] = -h * x[ik];
            m
        },
    )?;
    let d_k1 = dof.iter().find(|d| d.0 == "K1").map_or(e.dof(), |d| d.1);
    dof.push(("K1_pos".into(), d_k1));
    dof.push(("K1_neg".into(), d_k1));
    Ok(e)
}

/// The scale-factor nonlinearity (module docs): the means' deviations from
/// their least-squares straight line `E = c0 + c1 ω_in`, fitted with the
/// model's weights.
struct Nonlinearity {
    /// Deviation of each mean from the line (output units).
    residuals: DVector<f64>,
    /// Full-scale output `|c1| max|ω_in|` (output units).
    full_scale_output: f64,
    /// Largest deviation in ppm of the full-scale output (0 when it is 0).
    ppm_fs: f64,
}

impl Nonlinearity {
    /// Fit the straight line to the means at the input rates `inputs`
    /// (deg/s) with `weights`.
    fn of(inputs: &[f64], stats: &[PositionStats], weights: &DVector<f64>) -> Result<Nonlinearity> {
        // Straight line for the nonlinearity, with the same weights.
        let line_terms = [RateTerm::B, RateTerm::K1];
        let line = crate::estimation::fit(
            &design(inputs, &line_terms, false)?,
            &DVector::from_iterator(stats.len(), stats.iter().map(|s| s.mean)),
            &crate::estimation::FitOptions {
                weights: Some(weights.clone()),
                ..Default::default()
            },
        )?;
        let max_in = inputs.iter().fold(0.0f64, |m, w| m.max(w.abs()));
        let full_scale_output = line.estimates.values()[1].abs() * max_in;
        let max_dev = line.residuals.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        let ppm_fs = if full_scale_output > 0.0 {
            max_dev / full_scale_output * 1e6
        } else {
            0.0
        };
        Ok(Nonlinearity {
            residuals: line.residuals,
            full_scale_output,
            ppm_fs,
        })
    }
}

/// Each run alone, with the same model (two or more run labels): its K1;
/// a run that cannot be fitted alone earns a warning.
fn runs_alone(
    pos: &[(f64, Option<String>, PositionStats)],
    inputs: &[f64],
    stats: &[PositionStats],
    terms: &[RateTerm],
    asymmetric: bool,
    noise: Noise,
    warnings: &mut Vec<Warning>,
) -> Vec<RunK1> {
    let mut runs = Vec::new();
    let mut labels: Vec<String> = Vec::new();
    for p in pos {
        if let Some(r) = &p.1 {
            if !labels.contains(r) {
                labels.push(r.clone());
            }
        }
    }
    if labels.len() >= 2 {
        for label in &labels {
            let idx: Vec<usize> = (0..pos.len())
                .filter(|&i| pos[i].1.as_deref() == Some(label.as_str()))
                .collect();
            let inp: Vec<f64> = idx.iter().map(|&i| inputs[i]).collect();
            let st: Vec<PositionStats> = idx.iter().map(|&i| stats[i]).collect();
            match fit_model(&inp, &st, terms, asymmetric, noise) {
                Ok((_, _, e)) => runs.push(RunK1 {
                    run: label.clone(),
                    rates: idx.len(),
                    k1: e.value("K1").unwrap_or(f64::NAN),
                    u: e.u("K1").unwrap_or(f64::NAN),
                }),
                Err(e) => warnings.push(Warning::new(
                    WarningCode::PartFailed,
                    format!("run {label} alone: {e}"),
                )),
            }
        }
    }
    runs
}

/// Scale-factor repeatability: the standard deviation of the runs' K1 in
/// ppm of their mean, with `runs − 1` degrees of freedom (two or more
/// runs).
fn repeatability(runs: &[RunK1]) -> Option<(f64, f64)> {
    (runs.len() >= 2).then(|| {
        let n = runs.len() as f64;
        let mean = runs.iter().map(|r| r.k1).sum::<f64>() / n;
        let sd = (runs.iter().map(|r| (r.k1 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        (sd / mean.abs() * 1e6, n - 1.0)
    })
}
