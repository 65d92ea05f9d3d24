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
    /// A gap longer than a streaming reduction bridges ([`StampStream`]).
    GapTooLong {
        /// Time of the sample before the gap (s).
        start_s: f64,
        /// The step across the gap (s).
        step_s: f64,
        /// The period of the stamps (s).
        period_s: f64,
        /// The longest step bridged, in periods.
        max_periods: f64,
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
            TimeError::GapTooLong { start_s, step_s, period_s, max_periods } => write!(
                f,
                "time_s jumps {} s after t = {} s, a gap of {} periods (period {} s): gaps up to {} periods are bridged, this one is not; reduce the parts before and after it separately",
                short4(*step_s),
                short(*start_s),
                short4(step_s / period_s),
                short((period_s * 1e9).round() / 1e9),
                short(*max_periods)
            ),
            TimeError::RateContradiction { given_hz, stamps_hz } => write!(
                f,
                "`rate_hz` {} Hz contradicts the time_s stamps ({}, gaps excluded): give the rate of the recording",
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

/// The rate (Hz) of `n` increasing stamps that must be evenly spaced
/// (`stamp(k)` = time in s and file line of sample `k`, `n ≥ 2`): the
/// span over the steps. Refused naming the line: a step above 1.5
/// periods (`remedy` says what to do), and a nominal `rate_hz` that
/// differs from it by more than [`RATE_TOLERANCE`].
pub fn even_rate(
    n: usize,
    stamp: impl Fn(usize) -> (f64, usize),
    rate_hz: Option<f64>,
    remedy: &str,
) -> crate::error::Result<f64> {
    let rate = (n - 1) as f64 / (stamp(n - 1).0 - stamp(0).0);
    let period = 1.0 / rate;
    if let Some(k) = (1..n).find(|&k| stamp(k).0 - stamp(k - 1).0 > 1.5 * period) {
        let ((t0, _), (t1, line)) = (stamp(k - 1), stamp(k));
        return Err(crate::error::Error::Unsupported(format!(
            "line {line}: a gap of {:.6} s after {t0} s (the period is {period:.6} s): {remedy}",
            t1 - t0
        )));
    }
    if let Some(r) = rate_hz {
        if ((r - rate) / rate).abs() > RATE_TOLERANCE {
            return crate::options::invalid(
                "rate_hz",
                format!("{r} Hz contradicts the stamps' {rate:.6} Hz"),
            );
        }
    }
    Ok(rate)
}

/// The `time-sorted` warning for `moved` of `rows` rows put in order.
pub fn sorted_warning(moved: usize, rows: usize) -> crate::warning::Warning {
    crate::warning::Warning::new(
        crate::warning::WarningCode::TimeSorted,
        format!("{moved} of {rows} rows were out of time order and were put in order by time_s (--sort-time)"),
    )
}

/// Put `v` in `order` ([`time_order`]).
pub fn permute<T: Clone>(v: &mut Vec<T>, order: &[usize]) {
    *v = order.iter().map(|&k| v[k].clone()).collect();
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
        let steps = if self.regularised {
            Steps::Regularised
        } else {
            Steps::AsGiven
        };
        stamp_warnings(
            self.repeats,
            self.resolution_s,
            self.rate_hz,
            steps,
            &GapSummary::of(&self.gaps, self.period_s),
        )
    }
}

/// How a reduction took its time steps (for the `time-repeats` warning).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Steps {
    /// From the sample index ([`TimeBase::regularised`]).
    Regularised,
    /// The stamps as given (they stray from a grid by more than their
    /// resolution).
    AsGiven,
    /// The stamps as given by a streaming reduction ([`StampStream`]): a
    /// repeated stamp is a step of zero, the next step spans both periods.
    Streamed,
}

/// The gaps of a series in brief: constant memory for streams.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GapSummary {
    /// Number of gaps.
    pub count: usize,
    /// The longest step across a gap (s).
    pub longest_s: f64,
    /// Time missing in all: each gap's step less one period (s).
    pub missing_s: f64,
    /// Time of the sample before the first gap (s).
    pub first_start_s: f64,
}

impl GapSummary {
    /// The summary of `gaps` at period `period_s`.
    pub fn of(gaps: &[Gap], period_s: f64) -> Self {
        let mut s = GapSummary::default();
        for g in gaps {
            s.add(g, period_s);
        }
        s
    }

    fn add(&mut self, g: &Gap, period_s: f64) {
        if self.count == 0 {
            self.first_start_s = g.start_s;
        }
        self.count += 1;
        self.longest_s = self.longest_s.max(g.step_s);
        self.missing_s += g.step_s - period_s;
    }
}

/// The warnings of the policy from its figures ([`TimeBase::warnings`],
/// [`StampStream::warnings`]).
pub fn stamp_warnings(
    repeats: usize,
    resolution_s: f64,
    rate_hz: f64,
    steps: Steps,
    gaps: &GapSummary,
) -> Vec<Warning> {
    let mut out = Vec::new();
    if repeats > 0 {
        out.push(Warning::new(
            WarningCode::TimeRepeats,
            format!(
                "{} time_s stamps repeat the one before (stamp resolution {} s, sample rate {} from the stamps): {}",
                repeats,
                short((resolution_s * 1e9).round() / 1e9),
                hz(rate_hz),
                match steps {
                    Steps::Regularised => "the time steps were taken from the sample index (every stamp is within one resolution of that grid)",
                    Steps::AsGiven => "the stamps were taken as given (they stray from a regular grid by more than their resolution)",
                    Steps::Streamed => "the stamps were taken as given (a streaming reduction: a repeated stamp is a step of zero and the next step spans both periods)",
                }
            ),
        ));
    }
    if gaps.count > 0 {
        out.push(Warning::new(
            WarningCode::TimeGaps,
            format!(
                "{} gap(s) in time_s (steps above 1.5 periods): the longest {} s, {} s missing in all, the first after t = {} s",
                gaps.count,
                short4(gaps.longest_s),
                short4(gaps.missing_s),
                short(gaps.first_start_s)
            ),
        ));
    }
    out
}

/// Stamps read before a [`StampStream`] sets its period: enough for a
/// mean step within a few per cent under a 10 ms clock at 200 Hz.
pub const WARM_UP: usize = 256;

/// The policy for a reduction that reads each sample once in constant
/// memory (`gfimu solve`, `imu apply`): decreasing stamps are refused,
/// repeats are counted and taken as given ([`Steps::Streamed`]; a grid
/// needs the whole series), and gaps are found against the period of the
/// stamps so far (set from the first [`WARM_UP`] stamps by [`analyse`],
/// then the running mean step, gaps excluded). A gap longer than
/// `max_gap_periods` periods is refused ([`TimeError::GapTooLong`]).
#[derive(Debug, Clone)]
pub struct StampStream {
    max_gap_periods: f64,
    warm: Vec<(f64, usize)>,
    first: f64,
    prev: Option<f64>,
    n: usize,
    repeats: usize,
    resolution: f64,
    gap_steps: usize,
    gap_span: f64,
    gaps: GapSummary,
    period: Option<f64>,
}

impl StampStream {
    /// A stream refusing gaps longer than `max_gap_periods` periods
    /// (`f64::INFINITY`: every gap is only counted).
    pub fn new(max_gap_periods: f64) -> Self {
        StampStream {
            max_gap_periods,
            warm: Vec::with_capacity(WARM_UP),
            first: 0.0,
            prev: None,
            n: 0,
            repeats: 0,
            resolution: f64::INFINITY,
            gap_steps: 0,
            gap_span: 0.0,
            gaps: GapSummary::default(),
            period: None,
        }
    }

    /// Take the next stamp `t`, read at `line` (the error names the line
    /// of the offending stamp: `(line, error)`).
    pub fn push(&mut self, t: f64, line: usize) -> Result<(), (usize, TimeError)> {
        if let Some(prev) = self.prev {
            let d = t - prev;
            if d < 0.0 || !d.is_finite() {
                return Err((
                    line,
                    TimeError::Decreasing {
                        index: self.n,
                        stamp: t,
                        previous: prev,
                    },
                ));
            }
            if d == 0.0 {
                self.repeats += 1;
            } else if d < self.resolution {
                self.resolution = d;
            }
            if let Some(p) = self.period {
                self.step(prev, d, p, line)?;
            }
        } else {
            self.first = t;
        }
        self.prev = Some(t);
        self.n += 1;
        if self.period.is_none() {
            self.warm.push((t, line));
            if self.warm.len() == WARM_UP {
                self.settle()?;
            }
        }
        Ok(())
    }

    /// The gap threshold at period `p` ([`analyse`]'s rule).
    fn threshold(&self, p: f64) -> f64 {
        1.5 * p
            + if self.repeats > 0 {
                self.resolution
            } else {
                0.0
            }
    }

    /// Judge the step `d` after the stamp `prev` at period `p`, and move
    /// the running period on.
    fn step(&mut self, prev: f64, d: f64, p: f64, line: usize) -> Result<(), (usize, TimeError)> {
        if d > self.threshold(p) {
            let gap = Gap {
                index: self.n,
                start_s: prev,
                step_s: d,
            };
            // In whole periods: stamps carry rounding.
            if (d / p).round() > self.max_gap_periods {
                return Err((
                    line,
                    TimeError::GapTooLong {
                        start_s: prev,
                        step_s: d,
                        period_s: p,
                        max_periods: self.max_gap_periods,
                    },
                ));
            }
            self.gaps.add(&gap, p);
            self.gap_steps += 1;
            self.gap_span += d;
        }
        let steps = self.n - self.gap_steps;
        let span = prev + d - self.first - self.gap_span;
        if steps > 0 && span > 0.0 {
            self.period = Some(span / steps as f64);
        }
        Ok(())
    }

    /// Set the period from the stamps read so far, and judge their steps.
    fn settle(&mut self) -> Result<(), (usize, TimeError)> {
        let warm = std::mem::take(&mut self.warm);
        let stamps: Vec<f64> = warm.iter().map(|w| w.0).collect();
        let tb = analyse(&stamps, None).map_err(|e| (warm[warm.len() - 1].1, e))?;
        let p = tb.period_s;
        self.period = Some(p);
        // Replay the steps through the running rule (same counts as a
        // stream that had known the period from the start).
        let (n, first) = (self.n, self.first);
        self.n = 1;
        self.first = first;
        for w in warm.windows(2) {
            let d = w[1].0 - w[0].0;
            let period = self.period.unwrap_or(p);
            self.step(w[0].0, d, period, w[1].1)?;
            self.n += 1;
        }
        self.n = n;
        Ok(())
    }

    /// Close the stream: a short series settles its period here.
    pub fn finish(&mut self) -> Result<(), (usize, TimeError)> {
        if self.period.is_none() && self.warm.len() >= 2 {
            self.settle()?;
        }
        Ok(())
    }

    /// Sample rate of the stamps (Hz), when known.
    pub fn rate_hz(&self) -> Option<f64> {
        self.period.map(|p| 1.0 / p)
    }

    /// The gaps found so far.
    pub fn gaps(&self) -> &GapSummary {
        &self.gaps
    }

    /// The warnings of the policy for the stamps read ([`stamp_warnings`]).
    pub fn warnings(&self) -> Vec<Warning> {
        match self.period {
            Some(p) => stamp_warnings(
                self.repeats,
                if self.resolution.is_finite() {
                    self.resolution
                } else {
                    0.0
                },
                1.0 / p,
                Steps::Streamed,
                &self.gaps,
            ),
            None => Vec::new(),
        }
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

    #[test]
    fn the_stream_finds_the_gaps_the_whole_series_finds() {
        // 200 Hz stamped to 10 ms, with gaps of 1, 3 and 40 samples, one
        // inside the warm-up.
        let mut stamps = Vec::new();
        let mut k = 0usize;
        for i in 0..5000usize {
            if i == 100 || i == 2000 {
                k += 3;
            }
            if i == 4000 {
                k += 40;
            }
            if i == 3000 {
                k += 1;
            }
            stamps.push(((k as f64 * 0.005) / 0.01).floor() * 0.01);
            k += 1;
        }
        let whole = analyse(&stamps, None).unwrap();
        let mut s = StampStream::new(f64::INFINITY);
        for (i, t) in stamps.iter().enumerate() {
            s.push(*t, i + 2).unwrap();
        }
        s.finish().unwrap();
        assert_eq!(s.gaps().count, whole.gaps.len(), "{:?}", whole.gaps);
        assert!((s.rate_hz().unwrap() - 200.0).abs() < 1.0);
        let w = s.warnings();
        assert_eq!(w[0].code, WarningCode::TimeRepeats);
        assert!(w[0].message.contains("streaming"), "{}", w[0].message);
        assert_eq!(w[1].code, WarningCode::TimeGaps);
        // Bridging at most 10 periods: the 41-period step is refused at its
        // line, naming its time.
        let mut s = StampStream::new(10.0);
        let e = stamps
            .iter()
            .enumerate()
            .try_for_each(|(i, t)| s.push(*t, i + 2))
            .unwrap_err();
        assert_eq!(e.0, 4000 + 2);
        let m = e.1.to_string();
        assert!(m.contains("gap of") && m.contains("10 periods"), "{m}");
    }

    #[test]
    fn the_stream_refuses_decreasing_stamps_at_their_line() {
        let mut s = StampStream::new(f64::INFINITY);
        s.push(0.0, 2).unwrap();
        s.push(0.01, 3).unwrap();
        s.push(0.01, 4).unwrap();
        let (line, e) = s.push(0.005, 5).unwrap_err();
        assert_eq!(line, 5);
        assert!(matches!(e, TimeError::Decreasing { .. }));
        // A short clean series settles at its end, without warnings.
        let mut s = StampStream::new(f64::INFINITY);
        for k in 0..10 {
            s.push(k as f64 * 0.01, k + 2).unwrap();
        }
        s.finish().unwrap();
        assert!((s.rate_hz().unwrap() - 100.0).abs() < 1e-9);
        assert!(s.warnings().is_empty());
    }
}
