//! Monte Carlo propagation of distributions (JCGM 101:2008, "Evaluation of
//! measurement data — Supplement 1 to the GUM: Propagation of
//! distributions using a Monte Carlo method", BIPM, 2008).
//!
//! # Method
//! A reduction gives `y` (the coefficients) with the GUM's first-order
//! uncertainty (JCGM 100:2008). Its procedure says how its recording arose
//! ([`Synthesis`]): the fitted model, the sample noise as estimated (with
//! its degrees of freedom: a scaled inverse χ² draw of the variance, so the
//! trials carry the Student t of JCGM 101 §6.4.9) and every type-B input of
//! the rig with its distribution. Trial `r` draws one synthetic recording
//! from a ChaCha8 stream seeded with [`crate::sim::trial_seed`]`(seed, r)`
//! and reduces it with the same options; the trials' coefficients give the
//! Monte Carlo estimate, standard deviation, the probabilistically
//! symmetric and the shortest 95 % coverage intervals and the correlation
//! matrix ([`stats`]). The GUM interval `y ± U95` is then validated against
//! the Monte Carlo one at the numerical tolerance `δ` of the GUM `u` stated
//! to `digits` significant digits (§8.2).
//!
//! # Adaptive number of trials
//! [`Trials::Auto`] runs batches of [`BATCH`] trials (§7.9.4: `M =
//! max(100/(1 − p), 10⁴)`) until, for every coefficient, twice the standard
//! deviation of the batch means of the estimate, the standard deviation and
//! both interval ends is at most the tolerance of the Monte Carlo `u`
//! (§7.9.4 d–e), or [`MAX_TRIALS`] is reached (stated as not stabilised).
//!
//! # Reproducibility
//! Trials run in parallel; each draws from its own seed and the results are
//! kept in trial order, so the document is the same bits on one thread or
//! many.

pub mod stats;

use std::collections::BTreeMap;

use rand::rngs::ChaCha8Rng;
use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::document::ResultDocument;
use crate::error::Result;
use crate::warning::{Warning, WarningCode};

/// Coverage probability of every interval.
pub const COVERAGE: f64 = 0.95;
/// Trials in one batch of the adaptive procedure (JCGM 101 §7.9.4).
pub const BATCH: u64 = 10_000;
/// Most trials a run draws (a fixed `M` above it is refused; the adaptive
/// procedure stops there, not stabilised).
pub const MAX_TRIALS: u64 = 1_000_000;
/// Fewest trials a fixed `M` may ask for.
pub const MIN_TRIALS: u64 = 100;
/// Largest `M × coefficients` kept in memory (8 bytes each).
const MAX_VALUES: u64 = 50_000_000;
/// Share of failed trials above which a warning is given.
pub const FAILED_WARN: f64 = 0.01;

/// The number of trials: a fixed `M` or adaptive (`"auto"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(try_from = "TrialsText", into = "TrialsText")]
#[schemars(with = "TrialsText")]
pub enum Trials {
    /// Exactly `M` trials.
    Fixed(u64),
    /// Batches until the results are stable (JCGM 101 §7.9).
    Auto,
}

/// [`Trials`] as written: an integer, or the word `auto`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum TrialsText {
    /// A fixed number of trials.
    Count(u64),
    /// `"auto"`.
    Word(String),
}

impl TryFrom<TrialsText> for Trials {
    type Error = String;
    fn try_from(t: TrialsText) -> std::result::Result<Self, String> {
        match t {
            TrialsText::Count(m) => Ok(Trials::Fixed(m)),
            TrialsText::Word(w) if w == "auto" => Ok(Trials::Auto),
            TrialsText::Word(w) => Err(format!(
                "'{}' is neither a number of trials nor 'auto'",
                incal_io::clip(&w)
            )),
        }
    }
}

impl From<Trials> for TrialsText {
    fn from(t: Trials) -> Self {
        match t {
            Trials::Fixed(m) => TrialsText::Count(m),
            Trials::Auto => TrialsText::Word("auto".into()),
        }
    }
}

impl std::str::FromStr for Trials {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        if s == "auto" {
            return Ok(Trials::Auto);
        }
        s.parse::<u64>()
            .map(Trials::Fixed)
            .map_err(|_| format!("'{s}' is neither a number of trials nor 'auto'"))
    }
}

/// What a reduction's Monte Carlo run is asked for (`--monte-carlo M|auto
/// --seed N --mc-digits D`; Python `monte_carlo=`, `seed=`, `mc_digits=`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MonteCarloOptions {
    /// Trials: a number (at least 100, at most 10⁶) or `auto`.
    pub trials: Trials,
    /// Seed of the first trial's stream (every trial's seed derives from it).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Significant digits of a standard uncertainty that set the numerical
    /// tolerance δ (1 to 3; JCGM 101 §7.9.2).
    #[serde(default = "default_digits")]
    pub digits: u32,
}

fn default_seed() -> u64 {
    1
}

fn default_digits() -> u32 {
    1
}

impl MonteCarloOptions {
    /// `trials` with the default seed (1) and digits (1).
    pub fn new(trials: Trials) -> Self {
        Self {
            trials,
            seed: default_seed(),
            digits: default_digits(),
        }
    }

    /// `trials` trials exactly, seeded from `seed`, default digits (1).
    pub fn fixed(trials: u64, seed: u64) -> Self {
        Self {
            trials: Trials::Fixed(trials),
            seed,
            digits: default_digits(),
        }
    }

    /// Refuse a number of trials outside [`MIN_TRIALS`]…[`MAX_TRIALS`] and
    /// digits outside 1…3 (the key named as the front ends spell it).
    pub fn validate(&self) -> Result<()> {
        if let Trials::Fixed(m) = self.trials {
            if !(MIN_TRIALS..=MAX_TRIALS).contains(&m) {
                return crate::options::invalid(
                    "monte_carlo",
                    format!("{m} trials: give {MIN_TRIALS} to {MAX_TRIALS}, or auto"),
                );
            }
        }
        if !(1..=3).contains(&self.digits) {
            return crate::options::invalid(
                "mc_digits",
                format!("{}: give 1, 2 or 3 significant digits", self.digits),
            );
        }
        Ok(())
    }
}

/// One input a procedure's trials draw, for the document's table: what it
/// is, its distribution and where its parameters come from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Drawn {
    /// The input quantity (`sample noise at each position`).
    pub input: String,
    /// Its distribution (`normal`, `rectangular`, `scaled inverse χ², ν = 6`).
    pub distribution: String,
    /// Its parameters as drawn, with units (`σ = 2.1e-6 output`).
    pub parameters: String,
    /// Where they come from (`each position's scatter`, `--u-angle-deg`).
    pub source: String,
}

impl Drawn {
    /// A row of the table.
    pub fn new(input: &str, distribution: &str, parameters: String, source: &str) -> Self {
        Self {
            input: input.into(),
            distribution: distribution.into(),
            parameters,
            source: source.into(),
        }
    }
}

/// A procedure's recipe for synthetic recordings: one draw per trial from
/// the fitted model and the input distributions, and the table of what it
/// draws ([`crate::procedures::Procedure::synthesis`]).
pub struct Synthesis<I> {
    /// One synthetic input from the trial's stream.
    pub draw: DrawFn<I>,
    /// What is drawn.
    pub drawn: Vec<Drawn>,
    /// The coefficients of one synthetic input by name, without the
    /// document around them: a procedure's faster path to exactly the
    /// values its reduction reports (a test checks they are equal);
    /// `None`: the reduction itself runs.
    pub values: Option<ValuesFn<I>>,
    /// Errors of the method itself, not of the recording (an
    /// interpolation's error the GUM budget holds as a type-B term): each
    /// is drawn once per trial and added to its coefficient's value.
    pub method: Vec<MethodError>,
    /// Type-B inputs that multiply coefficients after the reduction (a
    /// stated reference the reduction scales by: the local field of a
    /// magnetometer): each is drawn once per trial, after the method
    /// errors, and multiplies its coefficients.
    pub factors: Vec<Factor>,
}

/// A factor of [`Synthesis::factors`]: `1 + N(0, u_rel²)` multiplying
/// every coefficient of `coefficients` in a trial (the reduction's output
/// `y = F · c` with the reference `F` stated, its relative standard
/// uncertainty `u_rel`).
#[derive(Debug, Clone, PartialEq)]
pub struct Factor {
    /// The coefficients' names in the document.
    pub coefficients: Vec<String>,
    /// The reference's relative standard uncertainty.
    pub u_rel: f64,
}

/// A method error of [`Synthesis::method`]: `N(0, u²)` added to the
/// coefficient `coefficient` of every trial (units of the coefficient).
#[derive(Debug, Clone, PartialEq)]
pub struct MethodError {
    /// The coefficient's name in the document.
    pub coefficient: String,
    /// Its standard uncertainty as the GUM budget took it.
    pub u: f64,
}

/// [`Synthesis::draw`]: one synthetic input from a trial's stream.
pub type DrawFn<I> = Box<dyn Fn(&mut ChaCha8Rng) -> Result<I> + Send + Sync>;

/// [`Synthesis::values`]: an input's coefficients as `(name, value)`.
pub type ValuesFn<I> = Box<dyn Fn(&I) -> Result<Vec<(String, f64)>> + Send + Sync>;

/// A variance `s²` estimated with `dof` degrees of freedom as one trial
/// draws it: `s² ν / χ²_ν` (the scaled inverse χ² whose normal mixture is
/// the scaled and shifted t of JCGM 101 §6.4.9); `s²` itself for an
/// infinite `dof` or one above 10⁶, 0 for a non-positive `s²`.
pub fn scaled_variance(rng: &mut ChaCha8Rng, s2: f64, dof: f64) -> f64 {
    use rand_distr::Distribution;
    if !(s2 > 0.0 && s2.is_finite()) {
        return 0.0;
    }
    if !(dof.is_finite() && dof <= 1e6) {
        return s2;
    }
    match rand_distr::ChiSquared::new(dof) {
        Ok(c) => {
            let x: f64 = c.sample(rng);
            if x > 0.0 {
                s2 * dof / x
            } else {
                s2
            }
        }
        Err(_) => s2,
    }
}

/// `σ² χ²_ν / ν`: the sample variance of `ν + 1` white normal samples of
/// variance `σ² = s2` (`s2` itself, at least 0, for `ν ≤ 0` or `s2 ≤
/// 0`): a synthetic section's scatter drawn without its samples.
pub fn sample_variance(rng: &mut ChaCha8Rng, s2: f64, nu: f64) -> f64 {
    use rand_distr::Distribution;
    if nu.is_nan() || nu <= 0.0 || s2 <= 0.0 {
        return s2.max(0.0);
    }
    match rand_distr::ChiSquared::new(nu) {
        Ok(c) => {
            let x: f64 = c.sample(rng);
            s2 * x / nu
        }
        Err(_) => s2,
    }
}

/// The sample noise a procedure's trials draw, from what its reduction
/// used: the known σ (`known`, infinite dof), else the pooled scatter of
/// the settings (`stats`, `Σ(n − 1)` dof), else the fit's residual σ
/// (`fit_sigma` with `fit_dof`, one sample per setting); `setting` names
/// a setting in the table (`position`, `rate`). Returns `(s², ν)` for
/// [`scaled_variance`] and the row of the table of what is drawn.
pub fn sample_noise(
    known: Option<f64>,
    stats: &[crate::estimation::PositionStats],
    fit_sigma: f64,
    fit_dof: f64,
    setting: &str,
) -> (f64, f64, Drawn) {
    let (s2, dof, source) = match known {
        Some(s) => (s * s, f64::INFINITY, "the known σ (noise)".to_string()),
        None => match crate::estimation::pooled_variance(stats) {
            (s2, dof) if dof > 0 && s2 > 0.0 => {
                (s2, dof as f64, format!("the {setting}s' pooled scatter"))
            }
            _ => (
                fit_sigma.powi(2),
                fit_dof,
                format!("the residuals (one sample per {setting})"),
            ),
        },
    };
    let distribution = if dof.is_finite() {
        format!("normal, variance scaled inverse χ² (ν = {dof})")
    } else {
        "normal, σ known".into()
    };
    let row = Drawn {
        input: "output noise of each sample".into(),
        distribution,
        parameters: format!("σ = {:.3e} output", s2.sqrt()),
        source,
    };
    (s2, dof, row)
}

/// The sample noise `(s², ν, row)` of [`sample_noise`] as the GUM's u
/// used it: where the fit failed its lack-of-fit test and took its
/// variance from the residuals (`fit.variance_source` = residuals with a
/// χ² test, [`crate::estimation::Variance::AtLeast`]), the variance is
/// scaled by that factor `χ²/(n − p)` and has the fit's `n − p` degrees of
/// freedom, so the trials' position means scatter as the reduction said
/// they do; otherwise unchanged.
pub fn with_lack_of_fit(
    (s2, dof, mut row): (f64, f64, Drawn),
    fit: &crate::estimation::Fit,
) -> (f64, f64, Drawn) {
    let scaled = fit.chi2_p_value.is_some()
        && fit.variance_source == crate::estimation::linear::VarianceSource::Residuals
        && fit.variance_factor > 1.0
        && fit.variance_factor.is_finite()
        && fit.dof > 0;
    if !scaled {
        return (s2, dof, row);
    }
    let (s2, dof) = (s2 * fit.variance_factor, fit.dof as f64);
    row.distribution = format!("normal, variance scaled inverse χ² (ν = {dof})");
    row.parameters = format!("σ = {:.3e} output", s2.sqrt());
    row.source = format!(
        "{}, scaled by the fit's lack of fit χ²/(n − p) = {:.3}",
        row.source, fit.variance_factor
    );
    (s2, dof, row)
}

/// The sample noise of a fit of setting means in output units, as its u
/// used it: [`sample_noise`] with the fit's residual σ and `n − p`, then
/// [`with_lack_of_fit`].
pub fn fit_noise(
    known: Option<f64>,
    stats: &[crate::estimation::PositionStats],
    fit: &crate::estimation::Fit,
    setting: &str,
) -> (f64, f64, Drawn) {
    with_lack_of_fit(
        sample_noise(known, stats, fit.sigma, fit.dof as f64, setting),
        fit,
    )
}

/// A lower factor `L` with `L Lᵀ = c` for a symmetric positive
/// semi-definite `c` (Cholesky, else the eigen-decomposition with negative
/// eigenvalues clamped to 0): the factor [`correlated`] draws with.
pub fn factor(c: &nalgebra::DMatrix<f64>) -> nalgebra::DMatrix<f64> {
    if let Some(l) = c.clone().cholesky() {
        return l.l();
    }
    let e = c.clone().symmetric_eigen();
    let d = nalgebra::DMatrix::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0).sqrt()));
    &e.eigenvectors * d
}

/// One draw of `N(0, L Lᵀ)`: `L z` with `z ~ N(0, I)` (`l` from
/// [`factor`]).
pub fn correlated(rng: &mut ChaCha8Rng, l: &nalgebra::DMatrix<f64>) -> nalgebra::DVector<f64> {
    let z = nalgebra::DVector::from_iterator(
        l.ncols(),
        (0..l.ncols()).map(|_| crate::sim::normal(rng, 1.0)),
    );
    l * z
}

mod section;
pub use section::{
    McCoefficient, McCorrelation, McFailures, McHistogram, McReason, MonteCarlo, HISTOGRAM_BINS,
};

/// The outcome of one trial: the coefficients in the base document's
/// order, or the reason the reduction refused the synthetic recording.
type Trial = std::result::Result<Vec<f64>, String>;

/// Run the Monte Carlo of procedure `P` on the reduction `doc` of `input`
/// with `options`: the document's `monte_carlo` section and its warnings
/// (module docs). Refused when the procedure has no synthesis, or when
/// fewer than two trials succeed (naming the commonest reason).
pub fn run<P: crate::procedures::Procedure>(
    input: &P::Input,
    options: &P::Options,
    doc: &ResultDocument,
    mc: &MonteCarloOptions,
    progress: &dyn crate::procedures::Progress,
) -> Result<(MonteCarlo, Vec<Warning>)> {
    mc.validate()?;
    let Some(synthesis) = P::synthesis(input, options, doc)? else {
        return crate::options::invalid(
            "monte_carlo",
            format!(
                "{} draws no synthetic recordings yet: no Monte Carlo for it",
                P::ID
            ),
        );
    };
    let names = doc.coefficients.names();
    if names.is_empty() {
        return crate::options::invalid("monte_carlo", "the result has no coefficients");
    }
    let cap = (MAX_VALUES / names.len() as u64).min(MAX_TRIALS);
    let one = |k: u64| -> Trial {
        let mut rng = crate::sim::rng(crate::sim::trial_seed(mc.seed, k));
        let x = (synthesis.draw)(&mut rng).map_err(|e| e.to_string())?;
        let mut got: Vec<(String, f64)> = match &synthesis.values {
            Some(f) => f(&x).map_err(|e| e.to_string())?,
            None => P::reduce(&x, options, &crate::procedures::Silent)
                .map_err(|e| e.to_string())?
                .coefficients
                .iter()
                .map(|(n, c)| (n.to_string(), c.value))
                .collect(),
        };
        for m in &synthesis.method {
            let e = crate::sim::normal(&mut rng, m.u);
            if let Some(g) = got.iter_mut().find(|g| g.0 == m.coefficient) {
                g.1 += e;
            }
        }
        for f in &synthesis.factors {
            let k = 1.0 + crate::sim::normal(&mut rng, f.u_rel);
            for g in got.iter_mut().filter(|g| f.coefficients.contains(&g.0)) {
                g.1 *= k;
            }
        }
        names
            .iter()
            .map(|n| match got.iter().find(|g| g.0 == *n) {
                Some(g) if g.1.is_finite() => Ok(g.1),
                Some(_) => Err(format!("{n} is not finite")),
                None => Err(format!("{n} is not reported")),
            })
            .collect()
    };
    let batch = |from: u64, len: u64| -> Vec<Trial> {
        let out = (from..from + len).into_par_iter().map(one).collect();
        progress.advance(len);
        out
    };
    let mut trials: Vec<Trial> = Vec::new();
    let mut adaptive = None;
    match mc.trials {
        Trials::Fixed(m) => {
            if m > cap {
                return crate::options::invalid(
                    "monte_carlo",
                    format!("{m} trials of {} coefficients: at most {cap}", names.len()),
                );
            }
            progress.start("Monte Carlo trials", m);
            // In batches, so progress is shown as they finish (each trial
            // keeps its own seed: the batches change nothing else).
            while (trials.len() as u64) < m {
                let from = trials.len() as u64;
                trials.extend(batch(from, BATCH.min(m - from)));
            }
        }
        Trials::Auto => {
            progress.start("Monte Carlo trials (adaptive)", cap);
            // The ratio of the last batch is the section's: computed once.
            let mut worst = f64::INFINITY;
            while (trials.len() as u64) + BATCH <= cap {
                let from = trials.len() as u64;
                trials.extend(batch(from, BATCH));
                if trials.len() as u64 >= 2 * BATCH {
                    worst = section::ratio(&trials, names.len(), mc);
                    if worst <= 1.0 {
                        break;
                    }
                }
            }
            adaptive = Some((worst <= 1.0, worst));
        }
    }
    progress.finish();
    section::summarise(doc, &names, &trials, mc, adaptive, synthesis.drawn)
}

/// The reason of a failed trial with its numbers replaced by `#`, so trials
/// refused for the same reason count together.
fn reason_key(message: &str) -> String {
    let mut out = String::new();
    let mut in_number = false;
    // A digit right after a letter or `_` is part of a name (K1, U95).
    let mut in_word = false;
    for ch in message.chars() {
        if ch.is_ascii_digit() && !in_word {
            if !in_number {
                out.push('#');
            }
            in_number = true;
            continue;
        }
        if in_number && (ch == '.' || ch == 'e' || ch == '-' || ch.is_ascii_digit()) {
            continue;
        }
        in_number = false;
        in_word = ch.is_alphanumeric() || ch == '_';
        out.push(ch);
    }
    incal_io::clip_to(&out, 200)
}

/// Failed trials grouped by reason, commonest first (ties by reason).
fn failures(trials: &[Trial]) -> Vec<(String, u64)> {
    let mut count: BTreeMap<String, u64> = BTreeMap::new();
    for t in trials {
        if let Err(e) = t {
            *count.entry(reason_key(e)).or_default() += 1;
        }
    }
    let mut v: Vec<(String, u64)> = count.into_iter().collect();
    v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    v
}

/// The warnings of a run: a coefficient whose GUM interval is not
/// validated, and failed trials above [`FAILED_WARN`].
fn warnings(mc: &MonteCarlo) -> Vec<Warning> {
    let mut out = Vec::new();
    let not: Vec<&str> = mc
        .coefficients
        .iter()
        .filter(|(_, c)| !c.validated)
        .map(|(n, _)| n.as_str())
        .collect();
    if !not.is_empty() {
        out.push(Warning::new(
            WarningCode::GumNotValidated,
            format!(
                "the GUM interval y ± U95 of {} differs from the Monte Carlo interval by more than δ (JCGM 101 §8): use the Monte Carlo interval",
                not.join(", ")
            ),
        ));
    }
    let total = mc.trials + mc.failed.count;
    if total > 0 && mc.failed.count as f64 > FAILED_WARN * total as f64 {
        let why = mc.failed.reasons.first().map_or("", |r| r.reason.as_str());
        out.push(Warning::new(
            WarningCode::TrialsFailed,
            format!(
                "{} of {total} Monte Carlo trials were refused by the reduction (most: {why}): the intervals describe the trials that succeeded",
                mc.failed.count
            ),
        ));
    }
    out
}

#[cfg(test)]
mod tests;
