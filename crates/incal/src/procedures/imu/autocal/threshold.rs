//! Static detection: the still intervals at thresholds `k·‖var(initial
//! interval)‖` for k = 2…10, an accelerometer fit at each threshold that
//! has enough usable intervals, and the threshold kept (tedaldi: the
//! smallest cost ½Σr²; incal: the most usable intervals, the smallest k
//! on a tie).

use nalgebra::DVector;

use super::super::detect::{self, Interval};
use super::accel::{acc_observations, acc_residuals, acc_start, check_separation, minimize_acc};
use super::session::Session;
use super::{Method, ThresholdTrial};
use crate::error::{Error, Result};

/// The accelerometer fit at one threshold.
pub(super) struct Candidate {
    /// Multiplier k.
    pub k: f64,
    /// The misalignments the gravity directions hardly separate
    /// ([`super::accel::check_separation`]), if any.
    pub separation: Option<Error>,
    /// The usable still intervals.
    pub intervals: Vec<Interval>,
    /// The accelerometer parameters at the minimum.
    pub x: DVector<f64>,
    /// ½Σr² at the minimum.
    pub cost: f64,
}

/// Usable intervals a threshold needs (tedaldi: `min_intervals`; incal: 9,
/// the parameters of each fit).
fn needed(s: &Session) -> usize {
    match s.opts.method {
        Method::Tedaldi => s.opts.min_intervals,
        Method::Incal => 9,
    }
}

/// The accelerometer fit on the intervals `ivs` of threshold `k`, from
/// the starting point of [`acc_start`] (the fallback `x0`). A session that
/// cannot separate a misalignment at first order is named: refused when
/// the fit cannot converge, else kept in the candidate for a warning.
fn fit_at(s: &Session, k: f64, ivs: Vec<Interval>, x0: &DVector<f64>) -> Result<Candidate> {
    let (acc, opts, g) = (&s.acc[..], s.opts, s.g);
    let used = |iv: &Interval| s.used(iv);
    let (samples, weights) = acc_observations(acc, &ivs, &used, opts, None)?;
    let start = acc_start(acc, &ivs, &used, g, x0, &opts.init);
    let separation = check_separation(acc, &ivs, &used, &start).err();
    let x = minimize_acc(&samples, g, start, weights.as_ref())
        .map_err(|e| separation.clone().unwrap_or(e))?;
    let r = acc_residuals(&x, &samples, g);
    let cost = 0.5 * r.norm_squared();
    Ok(Candidate {
        k,
        separation,
        intervals: ivs,
        x,
        cost,
    })
}

/// Try every threshold k = 2…10 (module docs): the candidate kept and
/// every trial, or the refusal naming the most intervals found.
pub(super) fn search(s: &Session) -> Result<(Candidate, Vec<ThresholdTrial>)> {
    let x0 = s.acc_fallback();
    let mut trials = Vec::new();
    let mut best: Option<Candidate> = None;
    let mut most_found = 0;
    for k in 2..=10 {
        let k = k as f64;
        let ivs: Vec<Interval> = detect::intervals_from_norms(&s.norms, k * s.norm_th)
            .into_iter()
            .filter(|iv| s.used(iv).is_some())
            .collect();
        most_found = most_found.max(ivs.len());
        // incal: most intervals wins, the smallest k on a tie: fit only
        // when this k beats the best so far.
        let beaten = s.opts.method == Method::Incal
            && best
                .as_ref()
                .is_some_and(|b| b.intervals.len() >= ivs.len());
        if ivs.len() < needed(s) || beaten {
            trials.push(ThresholdTrial {
                k,
                intervals: ivs.len(),
                cost: None,
            });
            continue;
        }
        let c = fit_at(s, k, ivs, &x0)?;
        trials.push(ThresholdTrial {
            k,
            intervals: c.intervals.len(),
            cost: Some(c.cost),
        });
        let better = match (&best, s.opts.method) {
            (None, _) => true,
            (Some(b), Method::Tedaldi) => c.cost < b.cost,
            (Some(b), Method::Incal) => c.intervals.len() > b.intervals.len(),
        };
        if better {
            best = Some(c);
        }
    }
    let Some(best) = best else {
        return Err(Error::TooFew {
            what: format!(
                "still intervals of at least {} samples (thresholds k = 2..10 times the initial variance norm {:.3e}; the most found was {most_found}): record more orientations, hold each longer, or check --init-static-s covers a still start",
                s.opts.min_samples + 2 * s.trim,
                s.norm_th
            ),
            needed: needed(s),
            got: most_found,
        });
    };
    Ok((best, trials))
}
