//! Whole-revolution averaging of raw rate-table records (seed 003 §2:
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
    /// Time (s), strictly increasing within a record.
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

/// Which samples of a record are averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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
    /// A warning about this record (partial turn, rate mismatch).
    pub warning: Option<crate::Warning>,
}

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
    // Unwrap the table angle: steps wrapped to (−180°, 180°].
    let mut unwrapped = Vec::with_capacity(m);
    let mut acc = r.samples[0].table_angle_rad;
    unwrapped.push(acc);
    for w in r.samples.windows(2) {
        if w[1].time_s <= w[0].time_s {
            return Err(Error::InvalidValue {
                what: format!("time in {} (must increase)", describe(r)),
                value: format!("{} after {}", w[1].time_s, w[0].time_s),
            });
        }
        let d = (w[1].table_angle_rad - w[0].table_angle_rad + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        acc += d;
        unwrapped.push(acc);
    }
    let span = unwrapped[m - 1] - unwrapped[0];
    let step = span / (m - 1) as f64;
    if step == 0.0 {
        return Err(Error::InvalidValue {
            what: format!("table angle in {} (it does not turn)", describe(r)),
            value: format!("{}", r.samples[0].table_angle_rad.to_degrees()),
        });
    }
    let turns_total = m as f64 * step.abs() / std::f64::consts::TAU;
    let dt = r.samples[m - 1].time_s - r.samples[0].time_s;
    let measured = span.to_degrees() / dt;
    let whole = (turns_total + WHOLE_TURN_TOL).floor();
    let (n_used, turns_used) = match policy {
        TurnPolicy::Whole if whole >= 1.0 => {
            let n = ((whole * std::f64::consts::TAU / step.abs()).round() as usize).clamp(2, m);
            (n, n as f64 * step.abs() / std::f64::consts::TAU)
        }
        _ => (m, turns_total),
    };
    let mut warnings = Vec::new();
    let frac = (turns_total - turns_total.round()).abs();
    if frac > WHOLE_TURN_TOL || turns_total < 1.0 - WHOLE_TURN_TOL {
        if n_used < m {
            warnings.push(format!(
                "{} covers {:.3} turns, not a whole number: averaged over its first {} whole turn(s)",
                describe(r),
                turns_total,
                whole
            ));
        } else {
            warnings.push(format!(
                "{} covers {:.3} turns, not a whole number, and is averaged as is: the Earth-rate term does not cancel",
                describe(r),
                turns_total
            ));
        }
    }
    if measured.signum() != r.rate_deg_s.signum()
        || (measured - r.rate_deg_s).abs() > 0.01 * r.rate_deg_s.abs()
    {
        warnings.push(format!(
            "{}: table angle and time give a rate of {measured:.4} deg/s",
            describe(r)
        ));
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
        warning: if warnings.is_empty() {
            None
        } else {
            Some(crate::Warning::new(
                crate::WarningCode::PartialTurns,
                warnings.join("; "),
            ))
        },
    })
}

/// Reduce every record; each mean is one sample of its position.
pub fn average_records(records: &[Record], policy: TurnPolicy) -> Result<Vec<RecordMean>> {
    records.iter().map(|r| average_record(r, policy)).collect()
}
