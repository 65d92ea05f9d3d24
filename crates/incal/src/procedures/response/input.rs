//! Reading a stepped-sine recording: columns `freq_hz` (the dwell's
//! frequency, Hz), `reference` (the reference motion: the table's rate or
//! angle, or a reference accelerometer) and `output` (the instrument), and
//! `time_s` (s) or the option `rate_hz`, and optionally `time_ref_s`: the
//! reference's own stamps when it is sampled by another clock than the
//! output (each channel is then fitted at its own times, on one origin).
//! Consecutive rows with one
//! `freq_hz` form a dwell; a change of `freq_hz` starts the next (a
//! frequency visited twice is two dwells). Without a `freq_hz` column the
//! dwells are found from the reference ([`super::find`]) and their
//! frequencies estimated. Other columns are ignored.

use std::io::Read;

use crate::error::{Error, Result};
use crate::warning::{Warning, WarningCode};

/// The samples of one dwell.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Dwell {
    /// The dwell frequency (Hz).
    pub freq_hz: f64,
    /// File line of its first row.
    pub first_line: usize,
    /// File line of its last row.
    pub last_line: usize,
    /// Sample times (s).
    pub time_s: Vec<f64>,
    /// The reference's own sample times (s), empty when it shares `time_s`.
    pub time_ref_s: Vec<f64>,
    /// The reference channel.
    pub reference: Vec<f64>,
    /// The instrument's output.
    pub output: Vec<f64>,
    /// Found from the reference: `freq_hz` is only the start of the
    /// four-parameter fit.
    pub found: bool,
}

/// A stepped-sine recording read: its dwells and what finding them said.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Recorded {
    /// The dwells in file order.
    pub dwells: Vec<Dwell>,
    /// Warnings of the dwell search (runs too short to be dwells).
    pub warnings: Vec<crate::warning::Warning>,
}

impl Dwell {
    /// `dwell K (F Hz, lines A-B)` for messages (K from 1).
    pub fn label(&self, k: usize) -> String {
        format!(
            "dwell {} ({} Hz, lines {}-{})",
            k + 1,
            crate::error::short_number(&self.freq_hz.to_string()),
            self.first_line,
            self.last_line
        )
    }
}

/// The dwells of a recording, row by row. `rate_hz` gives the times when
/// the file has no `time_s` (sample index / rate, counted over the whole
/// file). Stamps must not decrease; a frequency must be positive. Without
/// a `freq_hz` column the dwells are found from the reference in windows
/// of `window_s` seconds ([`super::find`]).
pub fn read<R: Read>(
    rows: &mut incal_io::Reader<R>,
    rate_hz: Option<f64>,
    window_s: f64,
) -> Result<Recorded> {
    let h = rows.header();
    let (cf, cr, co) = (
        h.opt_column("freq_hz"),
        h.column("reference")?,
        h.column("output")?,
    );
    let ct = h.opt_column("time_s");
    if ct.is_none() && rate_hz.is_none() {
        return Err(h
            .error("no column 'time_s': give the sampling rate (rate_hz) or the stamps")
            .into());
    }
    let cref = reference_clock(h, ct)?;
    let mut dwells: Vec<Dwell> = Vec::new();
    let mut whole = super::find::Recording::default();
    let mut index = 0usize;
    let mut last_t = f64::NEG_INFINITY;
    let mut last_ref = f64::NEG_INFINITY;
    while let Some(row) = rows.next_row()? {
        let f = match cf {
            Some(cf) => {
                let f = row.f64(cf)?;
                if f <= 0.0 {
                    return Err(row
                        .cell_error(cf, format!("{f} is not a positive frequency"))
                        .into());
                }
                f
            }
            None => 0.0,
        };
        let t = match (ct, rate_hz) {
            (Some(c), _) => row.f64(c)?,
            (None, Some(r)) => index as f64 / r,
            (None, None) => 0.0,
        };
        if t < last_t {
            let c = ct.unwrap_or(cr);
            return Err(row
                .cell_error(
                    c,
                    format!("time {t} s is before the row above ({last_t} s)"),
                )
                .into());
        }
        last_t = t;
        index += 1;
        let t_ref = match cref {
            Some(c) => {
                let v = row.f64(c)?;
                if v < last_ref {
                    return Err(row
                        .cell_error(
                            c,
                            format!("time {v} s is before the row above ({last_ref} s)"),
                        )
                        .into());
                }
                last_ref = v;
                Some(v)
            }
            None => None,
        };
        let (r, y) = (row.f64(cr)?, row.f64(co)?);
        if cf.is_none() {
            whole.lines.push(row.line());
        }
        push(&mut dwells, row.line(), (t, t_ref), f, r, y);
    }
    if dwells.is_empty() {
        return Err(rows.header().error("no data rows").into());
    }
    let (dwells, mut warnings) = if cf.is_some() {
        (dwells, Vec::new())
    } else {
        // Without freq_hz every row went into one dwell (frequency 0).
        whole.samples = dwells.pop().unwrap_or_default();
        super::find::find(&whole, window_s)?
    };
    let dwells = without_clipped(dwells, &mut warnings)?;
    Ok(Recorded { dwells, warnings })
}

/// The samples of `x` at a rail of `rails` in runs of two or more.
fn clipped_count(x: &[f64], rails: &[f64]) -> usize {
    incal_io::rail_runs(x, rails).iter().filter(|&&f| f).count()
}

/// A channel's rails over every dwell ([`incal_io::extreme_rails`]).
fn rails<'a>(x: impl Iterator<Item = &'a [f64]>) -> Vec<f64> {
    incal_io::extreme_rails(x.flatten().copied())
}

/// Dwells whose output or reference holds samples at a converter's rail
/// (their sine fit would see a flattened wave) are left out with a
/// `clipped` warning naming them; refused when none is left.
fn without_clipped(dwells: Vec<Dwell>, warnings: &mut Vec<Warning>) -> Result<Vec<Dwell>> {
    let out_rails = rails(dwells.iter().map(|d| &d.output[..]));
    let ref_rails = rails(dwells.iter().map(|d| &d.reference[..]));
    if out_rails.is_empty() && ref_rails.is_empty() {
        return Ok(dwells);
    }
    let n = dwells.len();
    let (mut kept, mut left) = (Vec::new(), Vec::new());
    for (k, d) in dwells.into_iter().enumerate() {
        let (a, b) = (
            clipped_count(&d.output, &out_rails),
            clipped_count(&d.reference, &ref_rails),
        );
        if a + b == 0 {
            kept.push(d);
        } else {
            let what = match (a, b) {
                (0, b) => format!("reference {b} samples"),
                (a, 0) => format!("output {a} samples"),
                (a, b) => format!("output {a}, reference {b} samples"),
            };
            left.push(format!("{}: {what}", d.label(k)));
        }
    }
    if left.is_empty() {
        return Ok(kept);
    }
    if kept.is_empty() {
        return Err(Error::Unsupported(format!(
            "samples at a converter's rail in {} of {n} dwells ({}): a clipped sine has the wrong amplitude and phase, and no dwell is left",
            left.len(),
            left.join("; ")
        )));
    }
    warnings.push(Warning::new(
        WarningCode::Clipped,
        format!(
            "{} of {n} dwells hold samples at a converter's rail and are left out (a clipped sine has the wrong amplitude and phase): {}",
            left.len(),
            left.join("; ")
        ),
    ));
    Ok(kept)
}

/// The column `time_ref_s` (the reference's own clock) when the header
/// has one; refused without the output's `time_s` (`ct`). Every response
/// reader's.
pub fn reference_clock(h: &incal_io::Header, ct: Option<usize>) -> Result<Option<usize>> {
    let cref = h.opt_column("time_ref_s");
    if cref.is_some() && ct.is_none() {
        return Err(h
            .error("column 'time_ref_s' (the reference's clock) needs 'time_s' (the output's)")
            .into());
    }
    Ok(cref)
}

/// One row of a stepped-sine recording as the simulator writes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time (s).
    pub time_s: f64,
    /// The reference's own time (s), when it has its own clock.
    pub time_ref_s: Option<f64>,
    /// Dwell frequency (Hz).
    pub freq_hz: f64,
    /// Reference channel.
    pub reference: f64,
    /// Instrument output.
    pub output: f64,
}

/// The CSV `time_s,freq_hz,reference,output` (with `time_ref_s` when
/// `own_clock`, without `freq_hz` unless `freq_column`) of samples
/// produced one at a time by `each`, in constant memory.
pub fn write_each<W: std::io::Write>(
    out: W,
    (own_clock, freq_column): (bool, bool),
    each: impl FnOnce(&mut dyn FnMut(Sample) -> std::io::Result<()>) -> std::io::Result<()>,
) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut header: Vec<&str> = vec!["time_s"];
    if own_clock {
        header.push("time_ref_s");
    }
    if freq_column {
        header.push("freq_hz");
    }
    header.extend(["reference", "output"]);
    let mut w = CsvWriter::new(out, &header)?;
    each(&mut |s: Sample| {
        w.cell(Cell::Num(s.time_s))?;
        if own_clock {
            w.cell(Cell::Num(s.time_ref_s.unwrap_or(s.time_s)))?;
        }
        if freq_column {
            w.cell(Cell::Num(s.freq_hz))?;
        }
        w.cell(Cell::Num(s.reference))?;
        w.cell(Cell::Num(s.output))?;
        w.end_row()
    })?;
    w.finish()
}

/// Samples in time order into dwells as [`read`] forms them (a change of
/// `freq_hz` starts a dwell; lines counted from 2, below a header): the
/// in-memory path of the simulator's rows.
pub fn dwells_from(samples: impl IntoIterator<Item = Sample>) -> Vec<Dwell> {
    let mut dwells: Vec<Dwell> = Vec::new();
    for (k, s) in samples.into_iter().enumerate() {
        push(
            &mut dwells,
            k + 2,
            (s.time_s, s.time_ref_s),
            s.freq_hz,
            s.reference,
            s.output,
        );
    }
    dwells
}

/// One row into the dwells: onto the last when it has the same
/// frequency, else as a new dwell.
fn push(
    dwells: &mut Vec<Dwell>,
    line: usize,
    (t, t_ref): (f64, Option<f64>),
    f: f64,
    r: f64,
    y: f64,
) {
    if !matches!(dwells.last(), Some(d) if d.freq_hz == f) {
        dwells.push(Dwell {
            freq_hz: f,
            first_line: line,
            ..Dwell::default()
        });
    }
    if let Some(d) = dwells.last_mut() {
        d.last_line = line;
        d.time_s.push(t);
        if let Some(tr) = t_ref {
            d.time_ref_s.push(tr);
        }
        d.reference.push(r);
        d.output.push(y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dwell of a sine of `amplitude` counts, clamped to the 16-bit range.
    fn dwell(k: usize, amplitude: f64) -> Dwell {
        let x: Vec<f64> = (0..400)
            .map(|i| {
                (amplitude * (0.1 * i as f64).sin())
                    .round()
                    .clamp(-32768.0, 32767.0)
            })
            .collect();
        Dwell {
            freq_hz: (k + 1) as f64,
            first_line: 2 + 400 * k,
            last_line: 401 + 400 * k,
            time_s: (0..400).map(|i| i as f64 * 0.01).collect(),
            time_ref_s: Vec::new(),
            reference: x.iter().map(|v| v / 1000.0).collect(),
            output: x,
            found: false,
        }
    }

    #[test]
    fn clipped_dwells_are_left_out_or_refused_when_two_are_not_left() {
        let mut w = Vec::new();
        let all = vec![dwell(0, 20_000.0), dwell(1, 50_000.0), dwell(2, 10_000.0)];
        let kept = without_clipped(all.clone(), &mut w).unwrap();
        assert_eq!(kept, vec![all[0].clone(), all[2].clone()]);
        assert!(
            w[0].message
                .contains("1 of 3 dwells hold samples at a converter's rail and are left out")
                && w[0]
                    .message
                    .contains("dwell 2 (2 Hz, lines 402-801): output"),
            "{}",
            w[0].message
        );
        // Below the rail: untouched.
        let mut none = Vec::new();
        let fine = vec![dwell(0, 20_000.0), dwell(1, 30_000.0)];
        assert_eq!(without_clipped(fine.clone(), &mut none).unwrap(), fine);
        assert!(none.is_empty());
        // Every dwell clipped: nothing is left.
        let e = without_clipped(vec![dwell(0, 40_000.0), dwell(1, 50_000.0)], &mut w)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("in 2 of 2 dwells (dwell 1 (1 Hz, lines 2-401): output"),
            "{e}"
        );
        assert!(e.contains("no dwell is left"), "{e}");
    }
}
