//! One time-stamp policy for every time series (IMU sessions today; the
//! other time-series inputs follow).
//!
//! Real acquisition systems stamp samples with a clock coarser than the
//! sampling (a 200 Hz IMU stamped to 10 ms repeats every other stamp),
//! with jitter, and with gaps where samples were lost. The policy:
//!
//! - Stamps must not decrease: a stamp below the one before is refused
//!   naming its row ([`TimeError::Decreasing`]).
//! - Repeated stamps are accepted. The resolution `r` of the clock is the
//!   smallest positive step; the nominal period `T` is the span divided by
//!   the steps, gaps excluded (two passes). When stamps repeat and every
//!   stamp lies within `r` of `t₀ + kT` (`k` the sample index, counted on
//!   across gaps by the samples each gap skips), the times are
//!   *regularised* to that grid; otherwise they are taken as given.
//! - A gap is a step above `1.5 T` (plus `r` when the clock is coarser than
//!   `T`): counted, the longest and the total time reported
//!   ([`TimeBase::gaps`]).
//! - A nominal rate (`--rate-hz`) that differs from the stamps' rate by
//!   more than [`RATE_TOLERANCE`] (relative) is refused naming both rates
//!   ([`TimeError::RateContradiction`]).
//!
//! Each procedure says what it does with gaps; this module only finds them.

use crate::warning::{Warning, WarningCode};

/// Largest relative difference between a nominal rate and the rate of the
/// stamps that is taken as agreement (2 %: MEMS output data rates are
/// specified to a few per cent; a factor of 2 or 1.25 is a wrong option).
pub const RATE_TOLERANCE: f64 = 0.02;

/// A gap in a time series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gap {
    /// Index of the first sample after the gap.
    pub index: usize,
    /// Time of the sample before the gap (s).
    pub start_s: f64,
    /// The step across the gap (s).
    pub step_s: f64,
}

/// What the stamps of a series say, and the times a reduction uses.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeBase {
    /// Sample rate of the stamps (Hz), `1/T`.
    pub rate_hz: f64,
    /// Nominal period `T` (s).
    pub period_s: f64,
    /// Resolution of the stamps (s): the smallest positive step.
    pub resolution_s: f64,
    /// Steps of zero (a stamp equal to the one before).
    pub repeats: usize,
    /// The times were put on the grid `t₀ + kT` (module docs).
    pub regularised: bool,
    /// Steps above the gap threshold.
    pub gaps: Vec<Gap>,
    /// The times the reduction uses: regularised or as given.
    pub times: Vec<f64>,
}

/// Why a series' stamps cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum TimeError {
    /// Fewer than two samples, or every stamp the same.
    NoSpan,
    /// Stamp `index` is below the one before.
    Decreasing {
        /// Index of the offending sample.
        index: usize,
        /// Its stamp (s).
        stamp: f64,
        /// The stamp before (s).
        previous: f64,
    },
    /// The nominal rate contradicts the stamps.
    RateContradiction {
        /// The nominal rate given (Hz).
        given_hz: f64,
        /// The rate of the stamps (Hz).
        stamps_hz: f64,
    },
}

impl std::fmt::Display for TimeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TimeError::NoSpan => write!(f, "time_s does not advance (fewer than two distinct stamps)"),
            TimeError::Decreasing { stamp, previous, .. } => write!(
                f,
                "time_s {} is below the stamp before ({}): stamps must not decrease",
                short(*stamp),
                short(*previous)
            ),
            TimeError::RateContradiction { given_hz, stamps_hz } => write!(
                f,
                "rate_hz {} Hz contradicts the time_s stamps ({}, gaps excluded): give the rate of the recording",
                short(*given_hz),
                hz(*stamps_hz)
            ),
        }
    }
}

use crate::error::short_f64 as short;

/// Append the next stamp `t` of a series being read: a stamp below the one
/// before is refused (the message, for the reader to place at its line)
/// unless the series is to be sorted afterwards (`sort`, [`time_order`]);
/// repeats are accepted (the time base judges them, [`analyse`]).
pub fn push_stamp(stamps: &mut Vec<f64>, t: f64, sort: bool) -> Result<(), String> {
    if let Some(&prev) = stamps.last() {
        if t < prev && !sort {
            return Err(TimeError::Decreasing {
                index: stamps.len(),
                stamp: t,
                previous: prev,
            }
            .to_string());
        }
    }
    stamps.push(t);
    Ok(())
}

/// Put `stamps` in time order (a stable sort) and return the order, for
/// the series read with them ([`permute`]), and how many rows it moved
/// (rows whose position changed); `None`, and `stamps` untouched, when
/// they are already in order. For `--sort-time`: a recording whose rows
/// came out of time order (two acquisition threads, a merged file) is put
/// in order instead of refused.
pub fn time_order(stamps: &mut Vec<f64>) -> Option<(Vec<usize>, usize)> {
    if stamps.windows(2).all(|w| w[0] <= w[1]) {
        return None;
    }
    let mut order: Vec<usize> = (0..stamps.len()).collect();
    order.sort_by(|&a, &b| stamps[a].total_cmp(&stamps[b]));
    let moved = order.iter().enumerate().filter(|(i, &k)| *i != k).count();
    permute(stamps, &order);
    Some((order, moved))
}

/// The indices of the first sample after each gap of `times` under
/// [`analyse`]'s rule (none when the times have no span).
pub fn gap_indices(times: &[f64]) -> Vec<usize> {
    analyse(times, None)
        .map(|tb| tb.gaps.iter().map(|g| g.index).collect())
        .unwrap_or_default()
}

/// The `time-sorted` warning for `moved` of `rows` rows put in order.
pub fn sorted_warning(moved: usize, rows: usize) -> crate::warning::Warning {
    crate::warning::Warning::new(
        crate::warning::WarningCode::TimeSorted,
        format!("{moved} of {rows} rows were out of time order and were put in order by time_s (--sort-time)"),
    )
}

/// Put `v` in `order` ([`time_order`]).
pub fn permute<T: Copy>(v: &mut Vec<T>, order: &[usize]) {
    *v = order.iter().map(|&k| v[k]).collect();
}

/// A duration in a message: 4 decimals, scientific when huge.
fn short4(x: f64) -> String {
    if x.abs() < 1e9 {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}

/// A rate in a message: 4 decimals, scientific when huge.
fn hz(x: f64) -> String {
    if x.abs() < 1e9 {
        format!("{x:.4} Hz")
    } else {
        format!("{x:.4e} Hz")
    }
}

/// Steps above `threshold`: their count and summed length.
fn gap_steps(stamps: &[f64], threshold: f64) -> (usize, f64) {
    let mut count = 0;
    let mut total = 0.0;
    for w in stamps.windows(2) {
        let d = w[1] - w[0];
        if d > threshold {
            count += 1;
            total += d;
        }
    }
    (count, total)
}

/// Analyse `stamps` (s) under the policy of the module docs; `nominal_hz`,
/// when given, must agree with the stamps.
pub fn analyse(stamps: &[f64], nominal_hz: Option<f64>) -> Result<TimeBase, TimeError> {
    let n = stamps.len();
    if n < 2 {
        return Err(TimeError::NoSpan);
    }
    let mut repeats = 0;
    let mut resolution = f64::INFINITY;
    for (i, w) in stamps.windows(2).enumerate() {
        let d = w[1] - w[0];
        if d < 0.0 || !d.is_finite() {
            return Err(TimeError::Decreasing {
                index: i + 1,
                stamp: w[1],
                previous: w[0],
            });
        }
        if d == 0.0 {
            repeats += 1;
        } else if d < resolution {
            resolution = d;
        }
    }
    let span = stamps[n - 1] - stamps[0];
    if span.is_nan() || span <= 0.0 {
        return Err(TimeError::NoSpan);
    }
    // Period: the span over the steps, gaps excluded; the threshold depends
    // on the period, so twice. The clock's resolution joins the threshold
    // when it is coarser than the sampling (steps of 0 and 2T are normal).
    let mut period = span / (n - 1) as f64;
    let threshold = |p: f64| 1.5 * p + if repeats > 0 { resolution } else { 0.0 };
    for _ in 0..2 {
        let (count, total) = gap_steps(stamps, threshold(period));
        let steps = (n - 1 - count) as f64;
        if steps > 0.0 && span - total > 0.0 {
            period = (span - total) / steps;
        }
    }
    let limit = threshold(period);
    let gaps: Vec<Gap> = stamps
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[1] - w[0] > limit)
        .map(|(i, w)| Gap {
            index: i + 1,
            start_s: w[0],
            step_s: w[1] - w[0],
        })
        .collect();
    // The grid index of every sample: k counts samples, and a gap adds the
    // samples it skipped. The period is then the least-squares slope of the
    // stamps on k (floor-quantised stamps bias the span, not the slope).
    let grid_index = |p: f64| -> Vec<f64> {
        let mut ks = Vec::with_capacity(n);
        let mut k = 0.0f64;
        let mut next_gap = gaps.iter().peekable();
        for i in 0..n {
            if let Some(g) = next_gap.peek() {
                if g.index == i {
                    k += (g.step_s / p).round() - 1.0;
                    next_gap.next();
                }
            }
            ks.push(k);
            k += 1.0;
        }
        ks
    };
    let mut ks = grid_index(period);
    let mut t0 = stamps[0];
    for _ in 0..2 {
        let km = ks.iter().sum::<f64>() / n as f64;
        let tm = stamps.iter().sum::<f64>() / n as f64;
        let (mut sxy, mut sxx) = (0.0, 0.0);
        for (k, t) in ks.iter().zip(stamps) {
            sxy += (k - km) * (t - tm);
            sxx += (k - km) * (k - km);
        }
        if sxx > 0.0 && sxy > 0.0 {
            period = sxy / sxx;
            t0 = tm - period * km;
        }
        ks = grid_index(period);
    }
    let rate_hz = 1.0 / period;
    if let Some(given) = nominal_hz {
        if (given - rate_hz).abs() > RATE_TOLERANCE * rate_hz {
            return Err(TimeError::RateContradiction {
                given_hz: given,
                stamps_hz: rate_hz,
            });
        }
    }
    let grid: Vec<f64> = ks.iter().map(|k| t0 + k * period).collect();
    let tolerance = if resolution.is_finite() {
        resolution
    } else {
        period
    };
    let regularised = repeats > 0
        && stamps
            .iter()
            .zip(&grid)
            .all(|(t, g)| (t - g).abs() <= tolerance * (1.0 + 1e-9));
    Ok(TimeBase {
        rate_hz,
        period_s: period,
        resolution_s: if resolution.is_finite() {
            resolution
        } else {
            0.0
        },
        repeats,
        regularised,
        gaps,
        times: if regularised { grid } else { stamps.to_vec() },
    })
}

impl TimeBase {
    /// The warnings of the policy: `time-repeats` when stamps repeat (how
    /// many, the resolution, whether the times were regularised) and
    /// `time-gaps` when there are gaps (count, longest, total).
    pub fn warnings(&self) -> Vec<Warning> {
        let mut out = Vec::new();
        if self.repeats > 0 {
            out.push(Warning::new(
                WarningCode::TimeRepeats,
                format!(
                    "{} time_s stamps repeat the one before (stamp resolution {} s, sample rate {} from the stamps): {}",
                    self.repeats,
                    short((self.resolution_s * 1e9).round() / 1e9),
                    hz(self.rate_hz),
                    if self.regularised {
                        "the time steps were taken from the sample index (every stamp is within one resolution of that grid)"
                    } else {
                        "the stamps were taken as given (they stray from a regular grid by more than their resolution)"
                    }
                ),
            ));
        }
        if !self.gaps.is_empty() {
            let longest = self.gaps.iter().map(|g| g.step_s).fold(0.0, f64::max);
            let total: f64 = self.gaps.iter().map(|g| g.step_s - self.period_s).sum();
            out.push(Warning::new(
                WarningCode::TimeGaps,
                format!(
                    "{} gap(s) in time_s (steps above 1.5 periods): the longest {} s, {} s missing in all, the first after t = {} s",
                    self.gaps.len(),
                    short4(longest),
                    short4(total),
                    short(self.gaps[0].start_s)
                ),
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_order_is_stable_and_counts_the_rows_moved() {
        let mut sorted = vec![0.0, 0.0, 1.0];
        assert!(time_order(&mut sorted).is_none());
        let mut st = vec![0.0, 2.0, 1.0, 1.0, 3.0];
        let (order, moved) = time_order(&mut st).unwrap();
        assert_eq!(order, vec![0, 2, 3, 1, 4]);
        assert_eq!(moved, 3);
        assert_eq!(st, vec![0.0, 1.0, 1.0, 2.0, 3.0]);
        let mut v = vec!['a', 'b', 'c', 'd', 'e'];
        permute(&mut v, &order);
        assert_eq!(v, vec!['a', 'c', 'd', 'b', 'e']);
    }

    #[test]
    fn quantised_stamps_are_regularised_and_their_rate_found() {
        // 200 Hz stamped to 10 ms: every other stamp repeats.
        let stamps: Vec<f64> = (0..2000)
            .map(|k| ((k as f64 * 0.005) / 0.01).floor() * 0.01)
            .collect();
        let tb = analyse(&stamps, Some(200.0)).unwrap();
        assert!((tb.rate_hz - 200.0).abs() < 0.2, "{}", tb.rate_hz);
        assert_eq!(tb.repeats, 1000);
        assert!(tb.regularised);
        assert!(tb.gaps.is_empty(), "{:?}", tb.gaps);
        assert!((tb.times[1] - tb.times[0] - 1.0 / tb.rate_hz).abs() < 1e-12);
        assert_eq!(tb.warnings()[0].code, WarningCode::TimeRepeats);
    }

    #[test]
    fn gaps_are_found_and_counted_on_the_grid() {
        let mut stamps: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
        // 50 samples lost after sample 499.
        for t in stamps.iter_mut().skip(500) {
            *t += 0.5;
        }
        let tb = analyse(&stamps, Some(100.0)).unwrap();
        assert_eq!(tb.gaps.len(), 1);
        assert_eq!(tb.gaps[0].index, 500);
        assert!((tb.gaps[0].step_s - 0.51).abs() < 1e-9);
        assert!((tb.rate_hz - 100.0).abs() < 1e-6);
        assert!(!tb.regularised, "no repeats: as given");
        let w = tb.warnings();
        assert_eq!(w[0].code, WarningCode::TimeGaps);
        assert!(
            w[0].message.contains("0.5000 s missing"),
            "{}",
            w[0].message
        );
    }

    #[test]
    fn decreasing_stamps_and_a_wrong_rate_are_refused() {
        assert_eq!(
            analyse(&[0.0, 0.01, 0.005], None),
            Err(TimeError::Decreasing {
                index: 2,
                stamp: 0.005,
                previous: 0.01
            })
        );
        let stamps: Vec<f64> = (0..500).map(|k| k as f64 * 0.01).collect();
        let e = analyse(&stamps, Some(200.0)).unwrap_err();
        assert!(matches!(e, TimeError::RateContradiction { .. }));
        assert!(e.to_string().contains("200 Hz") && e.to_string().contains("100.0000 Hz"));
        assert!(analyse(&stamps, Some(101.0)).is_ok(), "1 % is agreement");
        assert_eq!(analyse(&[1.0, 1.0], None), Err(TimeError::NoSpan));
        // A denormal stamp is echoed short (found by the fuzz targets),
        // by the readers' check too.
        let mut st = vec![0.01];
        let m = push_stamp(&mut st, 1e-320, false).unwrap_err();
        assert!(m.len() < 120 && m.contains("e-321"), "{m}");
        assert_eq!(st, [0.01]);
        push_stamp(&mut st, 0.01, false).unwrap();
        assert_eq!(st, [0.01, 0.01], "a repeat is kept");
        push_stamp(&mut st, 0.001, true).unwrap();
        assert_eq!(st, [0.01, 0.01, 0.001], "kept for sorting");
        let m = analyse(&[0.01, 1e-320], None).unwrap_err().to_string();
        assert!(m.len() < 120 && m.contains("e-321"), "{m}");
    }

    #[test]
    fn jittered_stamps_without_repeats_are_kept_as_given() {
        // 100 Hz with up to ±3 ms of jitter: no repeat, no gap, as given.
        let stamps: Vec<f64> = (0..1000)
            .map(|k| k as f64 * 0.01 + 0.003 * ((k * 7919) % 13) as f64 / 6.0 - 0.003)
            .collect();
        assert!(stamps.windows(2).all(|w| w[1] > w[0]));
        let tb = analyse(&stamps, Some(100.0)).unwrap();
        assert_eq!(tb.repeats, 0);
        assert!(tb.gaps.is_empty(), "{:?}", tb.gaps);
        assert!(!tb.regularised);
        assert_eq!(tb.times, stamps);
        assert!((tb.rate_hz - 100.0).abs() < 0.01, "{}", tb.rate_hz);
        assert!(tb.warnings().is_empty());
    }
}
