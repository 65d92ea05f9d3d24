//! Reading a noise record: the channels of a CSV record through the input
//! layer ([`read`]), or of a mapped binary record in one checking pass
//! (`read_mapped`); and the samples as the analysis reads them
//! (`Samples`).
//!
//! A CSV record has a header; every column but `time_s` and the
//! environmental ones (`temperature_c`, `humidity_pct`: summarised into the
//! document's `environment`; `temperature_c` also kept for the temperature
//! bins) is a channel unless `--columns` (the input layer's [`incal_io::ColumnMap`]) selects
//! and renames them. Every sample must be a finite number within ±10¹⁵
//! ([`MAX_ABS_VALUE`], the input layer's range), binary records too.

use std::io::Read;

use incal_io::binary::{decode, MappedRecord, RecordHash};
use incal_io::MAX_ABS_VALUE;

use super::Build;
use crate::error::{Error, Result};
use crate::noise::phase_reference;
use crate::procedures::Progress;

/// The channels of a CSV record.
#[derive(Debug, Clone, PartialEq)]
pub struct Channels {
    /// Channel names (the columns' names after `--columns`).
    pub names: Vec<String>,
    /// Samples of each channel, in the input unit; `NaN` where a cell was
    /// empty or `NaN` (a missing sample).
    pub samples: Vec<Vec<f64>>,
    /// Rows (samples per channel, duplicates dropped).
    pub rows: usize,
    /// The sample rate used (Hz): `rate_hz` when given (checked against
    /// the stamps), else the stamps' rate.
    pub rate_hz: f64,
    /// The time base of the `time_s` stamps, when the record has them
    /// ([`crate::timebase`]).
    pub timebase: Option<crate::timebase::TimeBase>,
    /// Gaps in the stamps as (index of the first sample after the gap,
    /// sample periods missing before it), in sample order.
    pub gaps: Vec<(usize, usize)>,
    /// Rows dropped as exact repeats of the row before (same stamp, same
    /// value in every channel) where the stamps do not lie on a grid.
    pub duplicates: usize,
    /// Rows moved into time order (`sort_time`; 0 when in order).
    pub sorted: usize,
    /// The record's `temperature_c` at every row (°C; NaN where empty),
    /// when it has that column and it is not a selected channel.
    pub temperature_c: Option<Vec<f64>>,
}

impl Channels {
    /// True when a channel has a missing sample or the stamps a gap: the
    /// deviations are then computed gap-aware.
    pub fn has_gaps(&self) -> bool {
        !self.gaps.is_empty() || self.samples.iter().any(|s| s.iter().any(|v| v.is_nan()))
    }
}

/// The channels of a CSV record: the columns the header selects (every
/// one but `time_s` when none is selected), each cell a finite number or
/// missing (empty or `NaN`: a gap); a `time_s` column is checked against
/// the nominal `rate_hz` (a wrong rate scales every noise coefficient),
/// gives the rate when none is given, and its gaps and time base are kept.
/// Where stamps repeat off any grid, a row equal to the row before in its
/// stamp and every channel is a logger's repeat, not a sample: dropped and
/// counted. With `sort_time`, rows out of time order are put in order by
/// `time_s` instead of refused.
pub fn read<R: Read>(
    rows: &mut incal_io::Reader<R>,
    rate_hz: Option<f64>,
    sort_time: bool,
) -> Result<Channels> {
    let h = rows.header();
    let pick: Vec<usize> = if h.selected().is_empty() {
        (0..h.width())
            .filter(|&k| {
                let n = h.names()[k].as_str();
                n != "time_s" && !incal_io::CONDITION_COLUMNS.contains(&n)
            })
            .collect()
    } else {
        h.selected().to_vec()
    };
    if pick.iter().any(|&k| h.names()[k] == "time_s") {
        return Err(h
            .error("time_s is the record's time stamps, not a channel: select the data columns")
            .into());
    }
    if pick.is_empty() {
        return Err(h
            .error("no channel column besides time_s and the environment's (temperature_c, humidity_pct)")
            .into());
    }
    let names: Vec<String> = pick.iter().map(|&k| h.names()[k].clone()).collect();
    let time = h.opt_column("time_s").filter(|c| !pick.contains(c));
    if time.is_none() && rate_hz.is_none() {
        return Err(h
            .error("no time_s column and no rate_hz: give the sample rate (`rate_hz`)")
            .into());
    }
    let mut stamps = time.map(|_| Vec::new());
    // The temperature rides along as one more column through the sorting
    // and the repeats, and is split off at the end.
    let temperature = h.opt_column("temperature_c").filter(|c| !pick.contains(c));
    let mut pick = pick;
    pick.extend(temperature);
    let mut samples = vec![Vec::new(); pick.len()];
    while let Some(row) = rows.next_row()? {
        for (d, &k) in samples.iter_mut().zip(&pick) {
            d.push(row.f64_or_missing(k)?.unwrap_or(f64::NAN));
        }
        if let (Some(c), Some(st)) = (time, stamps.as_mut()) {
            crate::timebase::push_stamp(st, row.f64(c)?, sort_time).map_err(|m| row.error(m))?;
        }
    }
    let mut sorted = 0;
    if let Some(st) = stamps.as_mut() {
        if let Some((order, moved)) = crate::timebase::time_order(st) {
            for d in &mut samples {
                crate::timebase::permute(d, &order);
            }
            sorted = moved;
        }
    }
    let analyse = |st: &[f64]| {
        crate::timebase::analyse(st, rate_hz).map_err(|e| Error::Unsupported(e.to_string()))
    };
    let mut duplicates = 0;
    let timebase = match stamps.as_mut() {
        Some(st) => {
            let mut tb = analyse(st)?;
            if tb.repeats > 0 && !tb.regularised {
                duplicates = drop_repeats(st, &mut samples);
                if duplicates > 0 {
                    tb = analyse(st)?;
                }
            }
            Some(tb)
        }
        None => None,
    };
    let gaps = timebase
        .as_ref()
        .map(|tb| {
            tb.gaps
                .iter()
                .map(|g| {
                    (
                        g.index,
                        ((g.step_s / tb.period_s).round() as usize).max(2) - 1,
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    let rate_hz = rate_hz
        .or(timebase.as_ref().map(|tb| tb.rate_hz))
        .ok_or_else(|| Error::Unsupported("no sample rate".into()))?;
    for d in &mut samples {
        d.shrink_to_fit();
    }
    let temperature_c = temperature.and_then(|_| samples.pop());
    Ok(Channels {
        temperature_c,
        names,
        rows: samples[0].len(),
        samples,
        rate_hz,
        timebase,
        gaps,
        duplicates,
        sorted,
    })
}

/// Drop every row whose stamp and channel values all equal the row
/// before's (compared bit for bit; a missing sample equals a missing
/// one); the number dropped.
fn drop_repeats(stamps: &mut Vec<f64>, samples: &mut [Vec<f64>]) -> usize {
    let n = stamps.len();
    let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
    let keep: Vec<bool> = (0..n)
        .map(|i| {
            i == 0 || stamps[i] != stamps[i - 1] || samples.iter().any(|d| !same(d[i], d[i - 1]))
        })
        .collect();
    let dropped = keep.iter().filter(|k| !**k).count();
    if dropped > 0 {
        let filter = |v: &mut Vec<f64>| {
            let mut it = keep.iter();
            v.retain(|_| *it.next().unwrap_or(&true));
        };
        filter(stamps);
        for d in samples.iter_mut() {
            filter(d);
        }
    }
    dropped
}

/// Where the samples are: parsed columns (CSV), or the memory map of a
/// binary record (read in place: the phase is the only copy).
pub(crate) enum Samples<'a> {
    /// One vector per channel.
    Columns(&'a [Vec<f64>]),
    /// A mapped record and, per analysed channel, its channel in the frame.
    Mapped {
        rec: &'a MappedRecord<'a>,
        index: Vec<usize>,
    },
}

impl Samples<'_> {
    /// Rows per release window of a mapped record (every row for columns).
    pub(crate) fn window_rows(&self) -> usize {
        match self {
            Samples::Columns(_) => usize::MAX,
            Samples::Mapped { rec, .. } => rec.window_rows(),
        }
    }

    /// Give the pages of rows `[from, to)` of a mapped record back to the
    /// kernel once they are read ([`MappedRecord::release`]); columns:
    /// nothing.
    pub(crate) fn release(&self, from: usize, to: usize) {
        if let Samples::Mapped { rec, .. } = self {
            rec.release(from, to);
        }
    }

    /// Sample `r` of analysed channel `k`, read in order from row 0: at
    /// each window boundary the window before is released
    /// ([`Samples::release`]). Call `release(0, rows)` after the last row.
    #[inline]
    pub(crate) fn get_streamed(&self, k: usize, r: usize, window: usize) -> f64 {
        if r > 0 && r % window == 0 {
            self.release(r - window, r);
        }
        self.get(k, r)
    }

    /// Sample `r` of analysed channel `k`.
    #[inline]
    pub(crate) fn get(&self, k: usize, r: usize) -> f64 {
        match self {
            Samples::Columns(c) => c[k][r],
            Samples::Mapped { rec, index } => rec.get(index[k], r),
        }
    }
}

/// What the reading pass of a mapped record gives.
pub(crate) struct MappedRead {
    /// Per analysed channel its array ([`Build`]), when the pass built
    /// them (the arrays take no more memory than the file).
    pub(crate) built: Option<Vec<Vec<f64>>>,
    /// The record's SHA-256, done or under way.
    pub(crate) hash: RecordHash,
}

/// One pass over a mapped record, window by window, each released after
/// (one copy resident): per channel of `pick` (channel in the frame, name)
/// the first non-finite sample (refused before any result) and, when the
/// selected channels' arrays take no more memory than the file, the arrays
/// themselves; the hash of the bytes on a thread of its own that runs on
/// while the deviations start (`parallel`), or in this pass (one thread).
/// `progress` counts the rows read.
pub(crate) fn read_mapped(
    rec: &MappedRecord,
    pick: &[(usize, String)],
    build: Build,
    parallel: bool,
    progress: &dyn Progress,
) -> Result<MappedRead> {
    progress.start("rows read", rec.rows() as u64);
    let out = pass(rec, pick, build, parallel, progress);
    progress.finish();
    out
}

fn pass(
    rec: &MappedRecord,
    pick: &[(usize, String)],
    build: Build,
    parallel: bool,
    progress: &dyn Progress,
) -> Result<MappedRead> {
    let rows = rec.rows();
    let frame = rec.frame();
    let f64le = rec.f64le();
    let mut hash = rec.hash(parallel);
    let fused = pick.len() * 8 <= frame;
    let win = rec.window_rows();
    let f = build.factor;
    let refs: Vec<f64> = pick
        .iter()
        .map(|&(c, _)| {
            if fused && build.rate {
                phase_reference(rows, |r| rec.get(c, r) * f)
            } else {
                0.0
            }
        })
        .collect();
    let mut built: Vec<Vec<f64>> = (0..if fused { pick.len() } else { 0 })
        .map(|_| vec![0.0; build.len(rows)])
        .collect();
    let mut accs = vec![0.0; pick.len()];
    // Per channel the first bad row: a non-finite sample (true) or, with
    // finite samples, the phase overflowing (false).
    let mut bad: Vec<Option<(usize, bool)>> = vec![None; pick.len()];
    let mut r0 = 0;
    while r0 < rows {
        let r1 = (r0 + win).min(rows);
        let bytes = rec.bytes(r0, r1);
        hash.update(bytes);
        for (k, b) in bad.iter_mut().enumerate() {
            if b.is_some() {
                continue;
            }
            let off = pick[k].0 * rec.width();
            let raw = |i: usize| decode(f64le, bytes, i * frame + off);
            // A sample beyond the input layer's range reads as NaN, so the
            // running sum below finds it as it finds a non-finite one.
            let y = |i: usize| {
                let v = raw(i);
                if v.abs() <= MAX_ABS_VALUE {
                    v * f
                } else {
                    f64::NAN
                }
            };
            let first_bad = || (0..r1 - r0).find(|&i| !y(i).is_finite());
            if fused {
                let at = usize::from(build.rate) + r0;
                let out = &mut built[k][at..at + (r1 - r0)];
                accs[k] = build.window(out, accs[k], refs[k], y);
                // A non-finite sample makes the running sum non-finite
                // for good: look for it only then.
                if !accs[k].is_finite() {
                    *b = Some(match first_bad() {
                        Some(i) => (r0 + i, true),
                        None => (
                            r0 + out.iter().position(|v| !v.is_finite()).unwrap_or(0),
                            false,
                        ),
                    });
                }
            } else if let Some(i) = first_bad() {
                *b = Some((r0 + i, true));
            }
        }
        rec.release(r0, r1);
        progress.advance((r1 - r0) as u64);
        r0 = r1;
    }
    for (k, (c, name)) in pick.iter().enumerate() {
        if let Some((r, sample)) = bad[k] {
            let v = rec.get(*c, r);
            let what = if sample && v.is_finite() {
                format!("{v:e} is beyond the readable range ±{MAX_ABS_VALUE:e}")
            } else if sample {
                "not a finite number".to_string()
            } else {
                "the running sum (phase) of the samples overflows".to_string()
            };
            return Err(Error::Unsupported(format!(
                "sample {} of {name}: {what}",
                r + 1
            )));
        }
    }
    Ok(MappedRead {
        built: fused.then_some(built),
        hash,
    })
}
