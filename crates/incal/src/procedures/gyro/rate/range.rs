//! Input range and saturation of the rate-transfer test (IEEE Std
//! 952-1997 §12.3.3 and IEEE Std 1431-2004: the input range is the range
//! over which the scale factor meets its nonlinearity specification).
//!
//! * **Clipped rates.** A rate whose output sits at the converter's
//!   limit: with `output_limit`, any sample with `|output| ≥ output_limit`;
//!   without it, at least half of the rate's samples (and at least 2)
//!   exactly equal to the record's largest or smallest output, in a record
//!   whose other rates scatter (a noiseless record has no rail to find).
//!   Clipped rates are named and never used in the fit.
//! * **Input range** (with `linearity_ppm`): for each candidate range `R`
//!   (each tested |rate|, from the largest down), the straight line
//!   `E = c0 + c1 ω_in` fitted to the means within `R` (weights `n_i`),
//!   and each mean's deviation in ppm of `|c1| max|ω_in|`; the input range is the
//!   largest `R` at which every deviation is at most `linearity_ppm` (the
//!   point estimates: a simple acceptance). It is a tested rate; the next
//!   tested rate above it fails. Rates beyond it are named and left out of
//!   the fit, so the coefficients hold over the input range.

use super::RateObservation;
use crate::estimation::PositionStats;

/// Which positions are clipped (module docs); one pass over the samples.
pub fn clipped(
    obs: &[RateObservation],
    pos: &[(f64, Option<String>, PositionStats)],
    output_limit: Option<f64>,
) -> Vec<bool> {
    let index: std::collections::HashMap<(u64, Option<&str>), usize> = pos
        .iter()
        .enumerate()
        .map(|(i, p)| ((p.0.to_bits(), p.1.as_deref()), i))
        .collect();
    let (lo, hi) = obs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, o| {
        (a.0.min(o.output), a.1.max(o.output))
    });
    // Per position: samples over the limit, samples at a rail.
    let mut over = vec![0usize; pos.len()];
    let mut rail = vec![0usize; pos.len()];
    for o in obs {
        if let Some(&i) = index.get(&(o.rate_deg_s.to_bits(), o.run.as_deref())) {
            if output_limit.is_some_and(|l| o.output.abs() >= l) {
                over[i] += 1;
            }
            if o.output == hi || o.output == lo {
                rail[i] += 1;
            }
        }
    }
    if output_limit.is_some() {
        return over.iter().map(|c| *c > 0).collect();
    }
    let n: Vec<usize> = pos.iter().map(|p| p.2.n).collect();
    let scatter: Vec<bool> = pos
        .iter()
        .map(|p| crate::validity::scatters(p.2.n, p.2.mean, p.2.std))
        .collect();
    crate::validity::at_rail(&n, &rail, &scatter)
}

/// Most distinct |rates| the input range is searched over (each
/// candidate refits the rates within it).
pub const MAX_CANDIDATES: usize = 1000;

/// The input range found (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct InputRange {
    /// The limit asked for (ppm of the range's full-scale output).
    pub linearity_ppm: f64,
    /// The input range (deg/s, the largest |commanded rate| within it),
    /// `None` when even the smallest candidate fails.
    pub range_deg_s: Option<f64>,
    /// Largest deviation within it (ppm of its full-scale output).
    pub ppm_at_range: Option<f64>,
    /// The next tested |rate| above it (which fails), if any.
    pub next_deg_s: Option<f64>,
    /// Positions beyond the range (indices into the positions given).
    pub beyond: Vec<usize>,
}

/// Search the input range (module docs) over positions at commanded
/// rates `rates` (deg/s: the candidates are their magnitudes) and input
/// rates `inputs` (deg/s, for the line) with `stats`. Fewer than 3
/// distinct rates in a candidate end the search.
pub fn input_range(
    rates: &[f64],
    inputs: &[f64],
    stats: &[PositionStats],
    linearity_ppm: f64,
) -> InputRange {
    let mut mags: Vec<f64> = rates.iter().map(|w| w.abs()).collect();
    mags.sort_by(f64::total_cmp);
    mags.dedup();
    let mut next = None;
    for &r in mags.iter().rev() {
        let within: Vec<usize> = (0..inputs.len()).filter(|&i| rates[i].abs() <= r).collect();
        let mut distinct: Vec<u64> = within.iter().map(|&i| inputs[i].to_bits()).collect();
        distinct.sort_unstable();
        distinct.dedup();
        if distinct.len() < 3 {
            break;
        }
        let full = within.iter().map(|&i| inputs[i].abs()).fold(0.0, f64::max);
        if let Some(ppm) = worst_ppm(&within, inputs, stats, full) {
            if ppm <= linearity_ppm {
                return InputRange {
                    linearity_ppm,
                    range_deg_s: Some(r),
                    ppm_at_range: Some(ppm),
                    next_deg_s: next,
                    beyond: (0..inputs.len()).filter(|&i| rates[i].abs() > r).collect(),
                };
            }
        }
        next = Some(r);
    }
    InputRange {
        linearity_ppm,
        range_deg_s: None,
        ppm_at_range: None,
        next_deg_s: next,
        beyond: Vec::new(),
    }
}

/// The largest deviation from the weighted straight line over `within`,
/// in ppm of `|c1| r`.
fn worst_ppm(within: &[usize], x: &[f64], stats: &[PositionStats], r: f64) -> Option<f64> {
    let w: Vec<f64> = within.iter().map(|&i| stats[i].n as f64).collect();
    let sw: f64 = w.iter().sum();
    let mx = within.iter().zip(&w).map(|(&i, w)| w * x[i]).sum::<f64>() / sw;
    let my = within
        .iter()
        .zip(&w)
        .map(|(&i, w)| w * stats[i].mean)
        .sum::<f64>()
        / sw;
    let sxx: f64 = within
        .iter()
        .zip(&w)
        .map(|(&i, w)| w * (x[i] - mx).powi(2))
        .sum();
    let sxy: f64 = within
        .iter()
        .zip(&w)
        .map(|(&i, w)| w * (x[i] - mx) * (stats[i].mean - my))
        .sum();
    if sxx <= 0.0 {
        return None;
    }
    let c1 = sxy / sxx;
    let fs = c1.abs() * r;
    if fs <= 0.0 || !fs.is_finite() {
        return None;
    }
    let worst = within
        .iter()
        .map(|&i| (stats[i].mean - my - c1 * (x[i] - mx)).abs())
        .fold(0.0f64, f64::max);
    Some(worst / fs * 1e6)
}
