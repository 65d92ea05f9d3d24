//! Tumble test of a pendulous accelerometer on a dividing head
//! (Wu et al. 2015; GJB 1037A 12-point; IEEE Std 1293 §10.4; docs/src/tumble.md).
//!
//! # Model
//! With the mount kinematics of [`Mount`], the output at head angle θ is
//! `E(θ) = Σ_t p_t φ_t(a(θ))` with the regressors `φ_t` of
//! [`Term::regressor`] and the linear parameters
//! `p_K1 = K1`, `p_t = K1·K_t` for every other term t. This is exactly
//! linear (no small-signal approximation): Wu et al. 2015's Fourier coefficients
//! A0…B3 (eq. 4–6) are a fixed linear transform of the same p when the
//! default six terms are fitted, so least squares over the same angles gives
//! the same K's.
//!
//! # Map to physical coefficients
//! `K1 = p_K1`, `K_t = p_t / p_K1`, Jacobian
//! `∂K_t/∂p_t = 1/p_K1`, `∂K_t/∂p_K1 = −p_t/p_K1²` (GUM propagation).
//!
//! # Uncertainty
//! Position means are weighted by their sample scatter; an index-angle error
//! ε of the head adds `(∂E/∂θ)² σ_ε²` to the variance of each position,
//! largest where the output changes fastest with θ (θ ≈ 0°, 180° for
//! IA-horizontal positions). `σ_ε` is estimated from the residuals by
//! [`crate::estimation::fit_means_excess`] (Paule–Mandel) and reported, so
//! the uncertainty is honest when the head is worse than assumed, and the
//! lab learns the head's index error (Wu et al. 2015 §3 leaves it unsolved).
//!
//! # Aliasing
//! In a 1 g field `a_i² + a_p² = 1` (pendulum) and `a_i² + a_o² = 1`
//! (gate), so `K0, K2, Kpp` (resp. `Koo`) cannot all be fitted; a plan at
//! 0/90/180/270° only has `a_i a_p = 0` and cannot see Kip. A requested term
//! set that the plan cannot separate is refused naming the combination
//! ([`crate::Error::Unseparable`]); a term that is not requested but is
//! absorbed by the fitted ones is reported in [`TumbleResult::absorbed`]
//! (e.g. with Kpp not modelled the reported K2 is `K2 − Kpp` and K0 is
//! `K0 + Kpp`).

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::estimation::{
    fit, fit_means, fit_means_excess, Design, Estimates, Fit, FitOptions, Noise, PositionStats,
    Variance,
};
use crate::models::{AccelerometerModel, Term};
use crate::rigs::Mount;

/// One recorded sample.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Dividing-head angle θ (rad).
    pub angle_rad: f64,
    /// Instrument output E (output units).
    pub output: f64,
    /// Optional pass label (e.g. `cw`, `ccw`).
    pub pass: Option<String>,
}

/// Default terms of a mount: K0, K1, K2, K3, the misalignment and the
/// cross-coupling the mount senses (Wu et al. 2015 eq. 2 and 11).
pub fn default_terms(mount: Mount) -> Vec<Term> {
    match mount {
        Mount::Pendulum => vec![
            Term::K0,
            Term::K1,
            Term::K2,
            Term::K3,
            Term::DeltaO,
            Term::Kip,
        ],
        Mount::Gate => vec![
            Term::K0,
            Term::K1,
            Term::K2,
            Term::K3,
            Term::DeltaP,
            Term::Kio,
        ],
    }
}

/// Options of [`calibrate`]. In the document: `{"mount": "pendulum",
/// "noise": null, "terms": ["K0", …]}` (`noise`: the known standard
/// deviation of one output sample, output units, or null for "from the
/// data"; `terms`: the mount's default terms when not given).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct TumbleOptions {
    /// Mount on the dividing head.
    pub mount: Mount,
    /// Terms to fit (must contain K1); default: [`default_terms`] of the mount.
    #[serde(default, deserialize_with = "terms_or_default")]
    #[schemars(with = "Option<Vec<Term>>")]
    pub terms: Vec<Term>,
    /// Noise policy (see [`crate::estimation::repeated`]).
    #[serde(default)]
    pub noise: Noise,
}

/// An absent or null `terms` is empty here and becomes the mount's
/// default terms in [`TumbleOptions::terms`].
pub(crate) fn terms_or_default<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> std::result::Result<Vec<Term>, D::Error> {
    Ok(<Option<Vec<Term>> as serde::Deserialize>::deserialize(d)?.unwrap_or_default())
}

impl TumbleOptions {
    /// The default terms of `mount`, automatic noise.
    pub fn new(mount: Mount) -> Self {
        Self {
            mount,
            terms: default_terms(mount),
            noise: Noise::Auto,
        }
    }

    /// The options as reduced and recorded: the terms as given, or the
    /// mount's default terms when none were given.
    pub fn settled(&self) -> TumbleOptions {
        let mut o = self.clone();
        if o.terms.is_empty() {
            o.terms = default_terms(o.mount);
        }
        o
    }
}

/// The tumble test as one [`super::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Tumble;

impl super::Procedure for Tumble {
    const ID: crate::document::Procedure = crate::document::Procedure::Tumble;
    type Options = TumbleOptions;
    type Input = Vec<Observation>;

    fn example() -> TumbleOptions {
        TumbleOptions::new(crate::rigs::Mount::Pendulum)
    }

    fn validate(o: &TumbleOptions) -> Result<()> {
        o.noise.validate()?;
        if !o.settled().terms.contains(&Term::K1) {
            return crate::options::invalid("terms", "the term set must contain K1 (scale factor)");
        }
        Ok(())
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &TumbleOptions,
    ) -> Result<Vec<Observation>> {
        input::read(rows)
    }

    fn reduce(
        obs: &Vec<Observation>,
        o: &TumbleOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(obs, &o.settled())?.document(o.noise.sigma().is_some())
    }

    fn recorded(
        _: &Vec<Observation>,
        o: &TumbleOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        super::options_map(&o.settled())
    }

    fn synthesis(
        obs: &Vec<Observation>,
        o: &TumbleOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<Observation>>>> {
        montecarlo::synthesis(obs, o).map(Some)
    }
}

/// Result at one test position.
#[derive(Debug, Clone, PartialEq)]
pub struct PositionResult {
    /// Head angle (rad), in [0, 2π).
    pub angle_rad: f64,
    /// Pass label.
    pub pass: Option<String>,
    /// Samples, mean and scatter of the output.
    pub stats: PositionStats,
    /// Mean output minus fitted output (output units).
    pub residual: f64,
    /// Residual divided by its standard deviation.
    pub standardized_residual: f64,
}

/// A term that is not fitted but that the plan cannot tell apart from the
/// fitted ones: each listed fitted coefficient really estimates
/// `K_fitted + factor · K_absorbed`.
#[derive(Debug, Clone, PartialEq)]
pub struct Absorption {
    /// The term left out of the model.
    pub term: Term,
    /// Fitted coefficients that absorb it, with the factor.
    pub into: Vec<(Term, f64)>,
}

impl std::fmt::Display for Absorption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} is not modelled and this plan cannot separate it:",
            self.term
        )?;
        for (k, (t, c)) in self.into.iter().enumerate() {
            let sep = if k == 0 { " " } else { ", " };
            let sign = if *c < 0.0 { "-" } else { "+" };
            let mag = c.abs();
            if (mag - 1.0).abs() < 1e-6 {
                write!(f, "{sep}reported {t} is {t} {sign} {}", self.term)?;
            } else {
                write!(f, "{sep}reported {t} is {t} {sign} {mag:.4}*{}", self.term)?;
            }
        }
        Ok(())
    }
}

/// Comparison of two passes (e.g. clockwise and counter-clockwise).
#[derive(Debug, Clone, PartialEq)]
pub struct PassComparison {
    /// Label of the reference pass (first in the file).
    pub reference: String,
    /// Label of the other pass.
    pub other: String,
    /// Coefficients from the reference pass alone.
    pub reference_coefficients: Estimates,
    /// Coefficients from the other pass alone.
    pub other_coefficients: Estimates,
    /// `other − reference` with `u = sqrt(u_ref² + u_other²)` (independent data).
    pub difference: Estimates,
    /// Per angle visited in both passes: `(θ, ȳ_other − ȳ_ref, u)` with
    /// `u² = s_ref²/n_ref + s_other²/n_other` (NaN with single samples).
    /// A pattern here is hysteresis or drift between the passes.
    pub position_differences: Vec<(f64, f64, f64)>,
}

/// Everything a tumble calibration produces.
#[derive(Debug, Clone, PartialEq)]
pub struct TumbleResult {
    /// Mount used.
    pub mount: Mount,
    /// Fitted terms, in order.
    pub terms: Vec<Term>,
    /// Physical coefficients (g units, K1 in output/g, angles in rad).
    pub coefficients: Estimates,
    /// The linear fit of `p` (K1·K_t), with residuals and diagnostics.
    pub fit: Fit,
    /// Per-position summaries and residuals.
    pub positions: Vec<PositionResult>,
    /// Unmodelled terms absorbed by the fitted ones.
    pub absorbed: Vec<Absorption>,
    /// Index-angle error of the head estimated from the residuals,
    /// standard deviation (rad); `None` when it cannot be estimated (one
    /// sample per position and no known noise).
    pub index_error_rad: Option<f64>,
    /// Pass-to-pass comparisons (empty without pass labels).
    pub passes: Vec<PassComparison>,
    /// Passes that could not be fitted on their own, with the reason.
    pub pass_errors: Vec<(String, String)>,
    /// Warnings (weak conditioning, lack of fit).
    pub warnings: Vec<crate::Warning>,
}

/// Design matrix of the linear parameters `p` at head angles `angles_rad`.
pub fn design(mount: Mount, terms: &[Term], angles_rad: &[f64]) -> Result<Design> {
    let rows: Vec<Vec<f64>> = angles_rad
        .iter()
        .map(|&t| {
            let a = mount.specific_force(t);
            terms.iter().map(|term| term.regressor(&a)).collect()
        })
        .collect();
    Design::from_rows(terms.iter().map(|t| t.name().to_string()).collect(), &rows)
}

fn k1_index(terms: &[Term]) -> Result<usize> {
    terms
        .iter()
        .position(|t| *t == Term::K1)
        .ok_or_else(|| Error::Unsupported("the term set must contain K1 (scale factor)".into()))
}

fn check_terms(terms: &[Term]) -> Result<usize> {
    for (k, t) in terms.iter().enumerate() {
        if terms[..k].contains(t) {
            return Err(Error::Unsupported(format!("term {t} listed twice")));
        }
    }
    k1_index(terms)
}

/// Map linear parameters `p` to physical coefficients (module docs).
pub fn to_physical(linear: &Estimates, terms: &[Term]) -> Result<Estimates> {
    let k = k1_index(terms)?;
    let k1 = linear.values()[k];
    if k1 == 0.0 || !k1.is_finite() {
        return Err(Error::InvalidValue {
            what: "fitted scale factor K1".into(),
            value: k1.to_string(),
        });
    }
    let n = terms.len();
    linear.map(
        terms.iter().map(|t| t.name().to_string()).collect(),
        |p| DVector::from_fn(n, |j, _| if j == k { p[k] } else { p[j] / p[k] }),
        |p| {
            let mut jac = DMatrix::zeros(n, n);
            for j in 0..n {
                if j == k {
                    jac[(j, k)] = 1.0;
                } else {
                    jac[(j, j)] = 1.0 / p[k];
                    jac[(j, k)] = -p[j] / (p[k] * p[k]);
                }
            }
            jac
        },
    )
}

/// Normalise an angle to [0, 2π) and give the grouping key (µ° resolution).
fn angle_key(angle_rad: f64) -> (i64, f64) {
    let a = angle_rad.rem_euclid(std::f64::consts::TAU);
    let key = (a.to_degrees() * 1e6).round() as i64 % 360_000_000;
    (key, (key as f64 / 1e6).to_radians())
}

/// Group samples into positions (same pass and angle), in order of first
/// appearance.
fn group(obs: &[Observation]) -> Vec<(f64, Option<String>, Vec<f64>)> {
    let mut index: BTreeMap<(Option<String>, i64), usize> = BTreeMap::new();
    let mut out: Vec<(f64, Option<String>, Vec<f64>)> = Vec::new();
    // Samples of one position come in runs: the previous row's slot is
    // tried first, so the map is searched once per run, not once per row.
    let mut last: Option<(f64, usize)> = None;
    for o in obs {
        if let Some((angle_rad, slot)) = last {
            if angle_rad == o.angle_rad && out[slot].1 == o.pass {
                out[slot].2.push(o.output);
                continue;
            }
        }
        let (key, angle) = angle_key(o.angle_rad);
        let slot = *index.entry((o.pass.clone(), key)).or_insert_with(|| {
            out.push((angle, o.pass.clone(), Vec::new()));
            out.len() - 1
        });
        out[slot].2.push(o.output);
        last = Some((o.angle_rad, slot));
    }
    out
}

/// Which unmodelled terms the fitted ones absorb at these angles: regress
/// each unmodelled regressor on the design; an exact fit means aliasing.
fn absorbed(mount: Mount, terms: &[Term], angles_rad: &[f64]) -> Result<Vec<Absorption>> {
    let d = design(mount, terms, angles_rad)?;
    let mut out = Vec::new();
    for t in Term::ALL.iter().filter(|t| !terms.contains(t)) {
        let y = DVector::from_iterator(
            angles_rad.len(),
            angles_rad
                .iter()
                .map(|&a| t.regressor(&mount.specific_force(a))),
        );
        let scale = y.amax();
        if scale == 0.0 {
            continue; // this mount never senses the term
        }
        let f = fit(
            &d,
            &y,
            &FitOptions {
                variance: Variance::Known { dof: f64::INFINITY },
                ..FitOptions::default()
            },
        )?;
        if f.residuals.amax() <= 1e-9 * scale {
            let into: Vec<(Term, f64)> = terms
                .iter()
                .zip(f.estimates.values().iter())
                .filter(|(_, c)| c.abs() > 1e-9)
                .map(|(t, c)| (*t, *c))
                .collect();
            if !into.is_empty() {
                out.push(Absorption { term: *t, into });
            }
        }
    }
    Ok(out)
}

/// `∂E/∂θ` at each angle for linear parameters `p` (central difference of
/// the design rows; output units per rad).
fn output_slope(
    mount: Mount,
    terms: &[Term],
    angles_rad: &[f64],
    p: &DVector<f64>,
) -> Result<DVector<f64>> {
    let h = 1e-6;
    let plus: Vec<f64> = angles_rad.iter().map(|a| a + h).collect();
    let minus: Vec<f64> = angles_rad.iter().map(|a| a - h).collect();
    let d = (design(mount, terms, &plus)?.matrix() - design(mount, terms, &minus)?.matrix())
        / (2.0 * h);
    Ok(d * p)
}

struct SingleFit {
    coefficients: Estimates,
    fit: Fit,
    positions: Vec<PositionResult>,
    angles: Vec<f64>,
    index_error_rad: Option<f64>,
}

/// Fit the model to one set of observations (no pass comparison).
fn fit_observations(obs: &[Observation], opts: &TumbleOptions) -> Result<SingleFit> {
    check_terms(&opts.terms)?;
    if obs.is_empty() {
        return Err(Error::TooFew {
            what: "observations".into(),
            needed: opts.terms.len(),
            got: 0,
        });
    }
    let groups = group(obs);
    let mut distinct: Vec<i64> = groups.iter().map(|g| angle_key(g.0).0).collect();
    distinct.sort_unstable();
    distinct.dedup();
    if distinct.len() < opts.terms.len() {
        return Err(Error::TooFew {
            what: format!("distinct angles for {} terms", opts.terms.len()),
            needed: opts.terms.len(),
            got: distinct.len(),
        });
    }
    let angles: Vec<f64> = groups.iter().map(|g| g.0).collect();
    let stats: Vec<PositionStats> = groups
        .iter()
        .map(|g| PositionStats::of(&g.2))
        .collect::<Result<_>>()?;
    let d = design(opts.mount, &opts.terms, &angles)?;
    let (first, _) = fit_means(&d, &stats, opts.noise)?;
    let slope = output_slope(opts.mount, &opts.terms, &angles, first.estimates.values())?;
    let ex = fit_means_excess(&d, &stats, opts.noise, &slope)?;
    let (f, weights) = (ex.fit, ex.weights);
    let coefficients = to_physical(&f.estimates, &opts.terms)?;
    let std_res = f.standardized_residuals(Some(&weights));
    let positions = groups
        .iter()
        .zip(&stats)
        .enumerate()
        .map(|(i, (g, s))| PositionResult {
            angle_rad: g.0,
            pass: g.1.clone(),
            stats: *s,
            residual: f.residuals[i],
            standardized_residual: std_res[i],
        })
        .collect();
    Ok(SingleFit {
        coefficients,
        fit: f,
        positions,
        angles,
        index_error_rad: ex.excess_variance.map(f64::sqrt),
    })
}

/// Per angle visited by both passes: mean of `other` minus mean of
/// `reference`, with the standard uncertainty from the sample scatter.
fn position_differences(
    positions: &[PositionResult],
    reference: &str,
    other: &str,
) -> Vec<(f64, f64, f64)> {
    let var = |p: &PositionResult| p.stats.std.powi(2) / p.stats.n as f64;
    positions
        .iter()
        .filter(|a| a.pass.as_deref() == Some(reference))
        .filter_map(|a| {
            positions
                .iter()
                .filter(|b| b.pass.as_deref() == Some(other))
                .find(|b| angle_key(b.angle_rad).0 == angle_key(a.angle_rad).0)
                .map(|b| {
                    (
                        a.angle_rad,
                        b.stats.mean - a.stats.mean,
                        (var(a) + var(b)).sqrt(),
                    )
                })
        })
        .collect()
}

/// The coefficients [`calibrate`] reports, without the absorbed terms,
/// the pass comparisons and the warnings (the Monte Carlo's trials).
pub(crate) fn coefficients(obs: &[Observation], opts: &TumbleOptions) -> Result<Estimates> {
    crate::validity::require_varying(obs.iter().map(|o| o.output), "output")?;
    let c = fit_observations(obs, opts)?.coefficients;
    crate::validity::require_scale_factor(&c, "K1")?;
    Ok(c)
}

/// Calibrate from tumble observations (see module docs).
///
/// Samples with the same pass label and angle form one position; their mean
/// is fitted and their scatter enters the uncertainty. With two or more pass
/// labels each pass is also fitted alone and the differences are reported.
pub fn calibrate(obs: &[Observation], opts: &TumbleOptions) -> Result<TumbleResult> {
    crate::validity::require_varying(obs.iter().map(|o| o.output), "output")?;
    let SingleFit {
        coefficients,
        fit,
        positions,
        angles,
        index_error_rad,
    } = fit_observations(obs, opts)?;
    crate::validity::require_scale_factor(&coefficients, "K1")?;
    let absorbed = absorbed(opts.mount, &opts.terms, &angles)?;
    let warnings = fit.quality_warnings(
        "drift or an unmodelled term (beyond what the index-error model explains)",
    );
    let mut labels: Vec<String> = Vec::new();
    for o in obs {
        if let Some(p) = &o.pass {
            if !labels.contains(p) {
                labels.push(p.clone());
            }
        }
    }
    let mut passes = Vec::new();
    let mut pass_errors = Vec::new();
    if labels.len() >= 2 {
        let mut per_pass: Vec<(String, Estimates)> = Vec::new();
        for label in &labels {
            let sub: Vec<Observation> = obs
                .iter()
                .filter(|o| o.pass.as_ref() == Some(label))
                .cloned()
                .collect();
            match fit_observations(&sub, opts) {
                Ok(single) => per_pass.push((label.clone(), single.coefficients)),
                Err(e) => pass_errors.push((label.clone(), e.to_string())),
            }
        }
        if let Some((ref_label, ref_c)) = per_pass.first().cloned() {
            for (label, c) in per_pass.iter().skip(1) {
                let diff = Estimates::new(
                    c.names().to_vec(),
                    c.values() - ref_c.values(),
                    c.covariance() + ref_c.covariance(),
                    c.dof().min(ref_c.dof()),
                )?;
                passes.push(PassComparison {
                    position_differences: position_differences(&positions, &ref_label, label),
                    reference: ref_label.clone(),
                    other: label.clone(),
                    reference_coefficients: ref_c.clone(),
                    other_coefficients: c.clone(),
                    difference: diff,
                });
            }
        }
    }
    Ok(TumbleResult {
        mount: opts.mount,
        terms: opts.terms.clone(),
        coefficients,
        fit,
        positions,
        absorbed,
        index_error_rad,
        passes,
        pass_errors,
        warnings,
    })
}

/// Output of `model` at head angle `theta_rad` on `mount`.
pub fn output(model: &AccelerometerModel, mount: Mount, theta_rad: f64) -> f64 {
    model.output(&mount.specific_force(theta_rad))
}
