//! Whole-revolution averaging of raw rate-table records (Li et al. 2012 §2:
//! "通过整周期采样, 三角函数项在整周平均值为0").
//!
//! On a turning table the gyro also senses the horizontal Earth rate,
//! `Ωe cos φ sin(γ + β)` with γ the table angle ([`crate::rigs::rate_table`]).
//! Its mean over whole revolutions is zero, so a record is reduced to the
//! mean of the samples of its first `N = ⌊T⌋` whole turns, `T` the turns it
//! covers. With samples at equal angle steps `Δ`, a sample stands for the
//! interval `Δ` ahead of it, so a record of `M` samples covers
//! `T = M |Δ| / 360°` with `Δ = (θ_last − θ_first)/(M − 1)` (unwrapped).
//! Averaging a partial turn leaves up to `Ωe cos φ / (π T)`-sized error in
//! the mean input rate; [`TurnPolicy::All`] shows it, and any record that is
//! not a whole number of turns earns a warning.

use crate::error::{Error, Result};

use super::gyro::{GyroConfig, GyroObservation};

/// One raw sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawSample {
    /// Time (s), not decreasing within a record (repeats from a coarse
    /// clock are accepted: time only gives the measured table rate).
    pub time_s: f64,
    /// Table angle γ (rad), as read on the table (wraps allowed).
    pub table_angle_rad: f64,
    /// Gyro output.
    pub output: f64,
}

/// A record: one configuration at one signed rate, sampled over turns.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Configuration.
    pub config: GyroConfig,
    /// Signed nominal table rate (°/s).
    pub rate_deg_s: f64,
    /// Samples in time order.
    pub samples: Vec<RawSample>,
}

/// Which samples of a record are averaged (`whole` or `all` at the edges).
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
pub enum TurnPolicy {
    /// The samples of the first whole turns (default; Earth rate cancels).
    #[default]
    Whole,
    /// Every sample, whole turns or not (shows partial-turn error).
    All,
}

/// The reduction of one record.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordMean {
    /// The averaged observation.
    pub observation: GyroObservation,
    /// Samples in the record.
    pub n_total: usize,
    /// Samples averaged.
    pub n_used: usize,
    /// Turns the record covers.
    pub turns_total: f64,
    /// Turns averaged.
    pub turns_used: f64,
    /// Table rate measured from angle and time (°/s, signed).
    pub measured_rate_deg_s: f64,
    /// Warnings about this record: partial turn or rate mismatch
    /// (`partial-turns`), repeated stamps (`time-repeats`), samples lost
    /// in gaps (`time-gaps`).
    pub warnings: Vec<crate::Warning>,
}

/// The largest fraction of a record's samples that may be lost in time
/// gaps (1 %): the Earth-rate term then cancels except over the missing
/// samples, at most `Ωe · missing / n` ≈ 0.15 °/h on the mean input rate;
/// more is refused.
pub const MAX_MISSING_FRACTION: f64 = 0.01;

/// Tolerance on "whole number of turns", in turns.
pub const WHOLE_TURN_TOL: f64 = 0.01;

fn describe(r: &Record) -> String {
    format!(
        "record alpha={} beta={} rate={}",
        r.config.alpha_rad.to_degrees(),
        r.config.beta_rad.to_degrees(),
        r.rate_deg_s
    )
}

/// Reduce one record (module docs).
pub fn average_record(r: &Record, policy: TurnPolicy) -> Result<RecordMean> {
    let m = r.samples.len();
    if m < 2 {
        return Err(Error::TooFew {
            what: format!("samples in {}", describe(r)),
            needed: 2,
            got: m,
        });
    }
    let unwrapped = unwrap_angles(r)?;
    let (missing, mut warnings) = check_time(r)?;
    let span = unwrapped[m - 1] - unwrapped[0];
    // Equal angle steps, counting the samples lost in gaps.
    let step = span / (m - 1 + missing) as f64;
    if step == 0.0 {
        return Err(Error::InvalidValue {
            what: format!("table angle in {} (it does not turn)", describe(r)),
            value: format!("{}", r.samples[0].table_angle_rad.to_degrees()),
        });
    }
    let turns_total = (m + missing) as f64 * step.abs() / std::f64::consts::TAU;
    let dt = r.samples[m - 1].time_s - r.samples[0].time_s;
    let measured = span.to_degrees() / dt;
    let whole = (turns_total + WHOLE_TURN_TOL).floor();
    let (n_used, turns_used) = samples_used(policy, &unwrapped, step, turns_total, whole, missing);
    let partial = partial_turn_notes(r, turns_total, whole, n_used < m, measured);
    if !partial.is_empty() {
        warnings.insert(
            0,
            crate::Warning::new(crate::WarningCode::PartialTurns, partial.join("; ")),
        );
    }
    let mean = r.samples[..n_used].iter().map(|s| s.output).sum::<f64>() / n_used as f64;
    Ok(RecordMean {
        observation: GyroObservation {
            alpha_rad: r.config.alpha_rad,
            beta_rad: r.config.beta_rad,
            rate_deg_s: r.rate_deg_s,
            output: mean,
        },
        n_total: m,
        n_used,
        turns_total,
        turns_used,
        measured_rate_deg_s: measured,
        warnings,
    })
}

/// The table angle of every sample (rad), unwrapped: each step from one
/// sample to the next wrapped to (−180°, 180°]. Refuses a decreasing time.
fn unwrap_angles(r: &Record) -> Result<Vec<f64>> {
    let mut unwrapped = Vec::with_capacity(r.samples.len());
    let mut acc = r.samples[0].table_angle_rad;
    unwrapped.push(acc);
    for w in r.samples.windows(2) {
        if w[1].time_s < w[0].time_s {
            return Err(Error::InvalidValue {
                what: format!("time in {} (must not decrease)", describe(r)),
                value: format!("{} after {}", w[1].time_s, w[0].time_s),
            });
        }
        let d = (w[1].table_angle_rad - w[0].table_angle_rad + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        acc += d;
        unwrapped.push(acc);
    }
    Ok(unwrapped)
}

/// The time stamps under the policy of [`crate::timebase`]: repeats are
/// accepted (only the first and last stamps are used), samples lost in
/// gaps are counted on the grid. Returns the number of samples lost and
/// the warnings (`time-repeats`, `time-gaps`); more than
/// [`MAX_MISSING_FRACTION`] lost is refused.
fn check_time(r: &Record) -> Result<(usize, Vec<crate::Warning>)> {
    let m = r.samples.len();
    let stamps: Vec<f64> = r.samples.iter().map(|s| s.time_s).collect();
    let tb = crate::timebase::analyse(&stamps, None).map_err(|e| Error::InvalidValue {
        what: format!("time in {}", describe(r)),
        value: e.to_string(),
    })?;
    let missing: usize = tb
        .gaps
        .iter()
        .map(|g| ((g.step_s / tb.period_s).round() as usize).saturating_sub(1))
        .sum();
    let mut warnings = Vec::new();
    if tb.repeats > 0 {
        warnings.push(crate::Warning::new(
            crate::WarningCode::TimeRepeats,
            format!(
                "{}: {} time_s stamps repeat the one before (stamp resolution {} s): time gives only the measured table rate, from the record's first and last stamps",
                describe(r),
                tb.repeats,
                crate::error::short_f64((tb.resolution_s * 1e9).round() / 1e9)
            ),
        ));
    }
    if missing > 0 {
        let frac = missing as f64 / (m + missing) as f64;
        let longest = tb.gaps.iter().map(|g| g.step_s).fold(0.0, f64::max);
        let what = format!(
            "{} gap(s) in time_s lose {} samples ({:.3} %), the longest {:.4} s after t = {} s",
            tb.gaps.len(),
            missing,
            100.0 * frac,
            longest,
            crate::error::short_f64(tb.gaps[0].start_s)
        );
        if frac > MAX_MISSING_FRACTION {
            return Err(Error::InvalidValue {
                what: format!("time in {}", describe(r)),
                value: format!(
                    "{what}; more than {} % of a record lost leaves the Earth-rate term uncancelled; re-record it",
                    100.0 * MAX_MISSING_FRACTION
                ),
            });
        }
        let we_deg_h = crate::units::EARTH_RATE_RAD_S.to_degrees() * 3600.0;
        warnings.push(crate::Warning::new(
            crate::WarningCode::TimeGaps,
            format!(
                "{}: {what}: the Earth-rate term cancels except over them, at most {:.3} deg/h on the record's mean input rate; samples counted by table angle",
                describe(r),
                we_deg_h * missing as f64 / m as f64
            ),
        ));
    }
    Ok((missing, warnings))
}

/// Samples averaged and the turns they cover under `policy`: the first
/// `whole` turns (at least one) for [`TurnPolicy::Whole`], counted by
/// angle step when samples were lost in gaps; else every sample.
/// `step` is the signed angle step (rad), `turns_total` the turns of the
/// record.
fn samples_used(
    policy: TurnPolicy,
    unwrapped: &[f64],
    step: f64,
    turns_total: f64,
    whole: f64,
    missing: usize,
) -> (usize, f64) {
    let m = unwrapped.len();
    match policy {
        TurnPolicy::Whole if whole >= 1.0 && missing == 0 => {
            let n = ((whole * std::f64::consts::TAU / step.abs()).round() as usize).clamp(2, m);
            (n, n as f64 * step.abs() / std::f64::consts::TAU)
        }
        TurnPolicy::Whole if whole >= 1.0 => {
            // Samples lost: count the samples by angle, each standing for
            // one step ahead of it.
            let end = whole * std::f64::consts::TAU - 0.5 * step.abs();
            let n = unwrapped
                .iter()
                .take_while(|a| (*a - unwrapped[0]).abs() < end)
                .count()
                .clamp(2, m);
            (n, whole.min(turns_total))
        }
        _ => (m, turns_total),
    }
}

/// The notes of the `partial-turns` warning: a record that is not a whole
/// number of turns (`truncated`: averaged over its first `whole` turns
/// rather than as is), and a measured rate (°/s) off the nominal one by
/// its sign or by more than 1 %.
fn partial_turn_notes(
    r: &Record,
    turns_total: f64,
    whole: f64,
    truncated: bool,
    measured: f64,
) -> Vec<String> {
    let mut partial = Vec::new();
    let frac = (turns_total - turns_total.round()).abs();
    if frac > WHOLE_TURN_TOL || turns_total < 1.0 - WHOLE_TURN_TOL {
        if truncated {
            partial.push(format!(
                "{} covers {:.3} turns, not a whole number: averaged over its first {} whole turn(s)",
                describe(r),
                turns_total,
                whole
            ));
        } else {
            partial.push(format!(
                "{} covers {:.3} turns, not a whole number, and is averaged as is: the Earth-rate term does not cancel",
                describe(r),
                turns_total
            ));
        }
    }
    if measured.signum() != r.rate_deg_s.signum()
        || (measured - r.rate_deg_s).abs() > 0.01 * r.rate_deg_s.abs()
    {
        partial.push(format!(
            "{}: table angle and time give a rate of {measured:.4} deg/s",
            describe(r)
        ));
    }
    partial
}

/// Reduce every record; each mean is one sample of its position.
pub fn average_records(records: &[Record], policy: TurnPolicy) -> Result<Vec<RecordMean>> {
    records.iter().map(|r| average_record(r, policy)).collect()
}
