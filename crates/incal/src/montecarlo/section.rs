//! The document's `monte_carlo` section and the adaptive procedure's
//! stability test (JCGM 101:2008 §7.9.4, §8.2).

use std::collections::BTreeMap;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::stats::{correlation, mean_std, shortest, symmetric, tolerance, validate};
use super::{failures, warnings, Drawn, MonteCarloOptions, Trial, BATCH, COVERAGE};
use crate::document::ResultDocument;
use crate::error::Result;
use crate::warning::Warning;

/// The Monte Carlo of one coefficient (same unit as the coefficient).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct McCoefficient {
    /// Mean of the trials.
    pub mean: f64,
    /// Standard deviation of the trials (the Monte Carlo u).
    pub std: f64,
    /// Probabilistically symmetric 95 % coverage interval `[low, high]`.
    pub symmetric: [f64; 2],
    /// Shortest 95 % coverage interval `[low, high]`.
    pub shortest: [f64; 2],
    /// The GUM interval `y ± U95` of the reduction.
    pub gum: [f64; 2],
    /// `|y − U95 − low|` against the symmetric interval.
    pub d_low: f64,
    /// `|y + U95 − high|` against the symmetric interval.
    pub d_high: f64,
    /// Numerical tolerance δ of the GUM u at the run's digits.
    pub delta: f64,
    /// Both `d` at most δ (JCGM 101 §8.2).
    pub validated: bool,
    /// `GUM validated`, or `not validated: use the Monte Carlo interval`.
    pub decision: String,
    /// The trials binned, for the plot of the distribution.
    pub histogram: McHistogram,
}

/// The trials of one coefficient in [`HISTOGRAM_BINS`] equal bins from
/// `low` to `high` (the 0.05 % and 99.95 % points of the trials, widened to
/// hold the GUM interval); trials beyond are not counted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct McHistogram {
    /// Lower edge of the first bin.
    pub low: f64,
    /// Upper edge of the last bin.
    pub high: f64,
    /// Trials per bin.
    pub counts: Vec<u64>,
}

/// Bins of [`McHistogram`].
pub const HISTOGRAM_BINS: usize = 40;

/// The histogram of `sorted` (ascending) over the central 99.9 % of the
/// trials and the interval `gum`.
fn histogram(sorted: &[f64], gum: [f64; 2]) -> McHistogram {
    let m = sorted.len();
    let at = |p: f64| sorted[((p * m as f64) as usize).min(m - 1)];
    let mut low = at(0.0005).min(gum[0]);
    let mut high = at(0.9995).max(gum[1]);
    if high <= low {
        // Every trial equal: one bin's width around the value.
        let w = low.abs().max(f64::MIN_POSITIVE) * 1e-9;
        low -= w;
        high += w;
    }
    let width = (high - low) / HISTOGRAM_BINS as f64;
    let mut counts = vec![0u64; HISTOGRAM_BINS];
    for &x in sorted {
        if x >= low && x <= high {
            let k = (((x - low) / width) as usize).min(HISTOGRAM_BINS - 1);
            counts[k] += 1;
        }
    }
    McHistogram { low, high, counts }
}

/// The trials the reduction refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct McFailures {
    /// How many.
    pub count: u64,
    /// Per reason (numbers shown as `#`), commonest first.
    pub reasons: Vec<McReason>,
}

/// One reason trials failed, and how many times.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct McReason {
    /// The reduction's message, numbers as `#`.
    pub reason: String,
    /// Trials refused for it.
    pub count: u64,
}

/// The correlation matrix of the trials.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct McCorrelation {
    /// Coefficient names, in order.
    pub names: Vec<String>,
    /// `matrix[j][k]`: correlation of `names[j]` and `names[k]`.
    pub matrix: Vec<Vec<f64>>,
}

/// A document's `monte_carlo` section (JCGM 101:2008; module docs of
/// [`crate::montecarlo`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MonteCarlo {
    /// The method, as the certificate states it.
    pub method: String,
    /// What was asked: the number of trials or `auto`.
    pub requested: super::TrialsText,
    /// Trials that succeeded (the statistics are over these).
    pub trials: u64,
    /// The seed every trial's stream derives from.
    pub seed: u64,
    /// Coverage probability of the intervals.
    pub coverage: f64,
    /// Significant digits of u that set δ.
    pub digits: u32,
    /// Adaptive runs: every result stable to its tolerance before the cap
    /// (`null` for a fixed number of trials).
    pub stabilised: Option<bool>,
    /// Adaptive runs: the largest ratio, over coefficients, of twice the
    /// standard deviation of the batch means (estimate, u and interval
    /// ends) to the tolerance of the Monte Carlo u; at most 1 when
    /// stabilised (`null` for a fixed number of trials).
    pub tolerance_ratio: Option<f64>,
    /// Trials the reduction refused.
    pub failed: McFailures,
    /// What the trials draw.
    pub drawn: Vec<Drawn>,
    /// Per coefficient, by name.
    pub coefficients: BTreeMap<String, McCoefficient>,
    /// Correlation of the coefficients over the trials.
    pub correlation: McCorrelation,
}

/// The column `j` of the successful trials among `trials[from..to]`.
fn column(trials: &[Trial], j: usize) -> Vec<f64> {
    trials
        .iter()
        .filter_map(|t| t.as_ref().ok().map(|v| v[j]))
        .collect()
}

/// Estimate, u and symmetric interval ends of one set of values.
fn four(mut x: Vec<f64>) -> [f64; 4] {
    let (m, s) = mean_std(&x);
    x.sort_by(f64::total_cmp);
    let (lo, hi) = symmetric(&x, COVERAGE);
    [m, s, lo, hi]
}

/// The largest `2 s / δ` over coefficients and the four results of the
/// batches of [`BATCH`] trials (JCGM 101 §7.9.4), `δ` from the Monte Carlo
/// u of all trials; infinite when a batch has fewer than two successes.
pub(super) fn ratio(trials: &[Trial], n: usize, mc: &MonteCarloOptions) -> f64 {
    let h = trials.len() / BATCH as usize;
    if h < 2 {
        return f64::INFINITY;
    }
    let mut worst: f64 = 0.0;
    for j in 0..n {
        let all = column(trials, j);
        let delta = tolerance(mean_std(&all).1, mc.digits);
        let per: Vec<[f64; 4]> = trials
            .chunks(BATCH as usize)
            .take(h)
            .map(|b| four(column(b, j)))
            .collect();
        for q in 0..4 {
            let vals: Vec<f64> = per.iter().map(|p| p[q]).collect();
            // The standard deviation of the average of h batch results.
            let s = mean_std(&vals).1 / (h as f64).sqrt();
            let r = 2.0 * s / delta;
            worst = if r.is_finite() {
                worst.max(r)
            } else {
                f64::INFINITY
            };
        }
    }
    worst
}

/// The section from the trials: statistics per coefficient, validation of
/// `doc`'s GUM intervals, correlation, failures (`adaptive`: whether an
/// adaptive run stabilised, and its last tolerance ratio); and its warnings.
pub(super) fn summarise(
    doc: &ResultDocument,
    names: &[String],
    trials: &[Trial],
    mc: &MonteCarloOptions,
    adaptive: Option<(bool, f64)>,
    drawn: Vec<Drawn>,
) -> Result<(MonteCarlo, Vec<Warning>)> {
    let ok: Vec<Vec<f64>> = trials.iter().filter_map(|t| t.clone().ok()).collect();
    let failed = failures(trials);
    if ok.len() < 2 {
        let why = failed.first().map_or("no trial ran", |f| f.0.as_str());
        return crate::options::invalid(
            "monte_carlo",
            format!(
                "{} of {} trials failed: {why}",
                trials.len() - ok.len(),
                trials.len()
            ),
        );
    }
    let mut coefficients = BTreeMap::new();
    for (j, name) in names.iter().enumerate() {
        let Some(c) = doc.coefficients.get(name) else {
            continue;
        };
        let mut x: Vec<f64> = ok.iter().map(|t| t[j]).collect();
        let (mean, std) = mean_std(&x);
        x.sort_by(f64::total_cmp);
        let (lo, hi) = symmetric(&x, COVERAGE);
        let (slo, shi) = shortest(&x, COVERAGE);
        let delta = tolerance(c.u, mc.digits);
        let (d_low, d_high, validated) = validate(c.value, c.u95, lo, hi, delta);
        coefficients.insert(
            name.clone(),
            McCoefficient {
                mean,
                std,
                symmetric: [lo, hi],
                shortest: [slo, shi],
                gum: [c.value - c.u95, c.value + c.u95],
                d_low,
                d_high,
                delta: if delta.is_finite() { delta } else { 0.0 },
                validated,
                decision: if validated {
                    "GUM validated".into()
                } else {
                    "not validated: use the Monte Carlo interval".into()
                },
                histogram: histogram(&x, [c.value - c.u95, c.value + c.u95]),
            },
        );
    }
    let section = MonteCarlo {
        method: "JCGM 101:2008 (GUM Supplement 1), propagation of distributions by a Monte Carlo method: synthetic recordings from the fitted model and the input distributions, each reduced as the recording was".into(),
        requested: mc.trials.into(),
        trials: ok.len() as u64,
        seed: mc.seed,
        coverage: COVERAGE,
        digits: mc.digits,
        stabilised: adaptive.map(|a| a.0),
        tolerance_ratio: adaptive.map(|a| finite_or_max(a.1)),
        failed: McFailures {
            count: (trials.len() - ok.len()) as u64,
            reasons: failed
                .into_iter()
                .map(|(reason, count)| McReason { reason, count })
                .collect(),
        },
        drawn,
        coefficients,
        correlation: McCorrelation {
            names: names.to_vec(),
            matrix: correlation(&ok, names.len()),
        },
    };
    let w = warnings(&section);
    Ok((section, w))
}

/// A ratio for the document, at most 10⁶ (an infinite one, from a batch
/// without two successes, too) so the document holds finite numbers only.
fn finite_or_max(r: f64) -> f64 {
    if r.is_finite() {
        r.min(1e6)
    } else {
        1e6
    }
}
