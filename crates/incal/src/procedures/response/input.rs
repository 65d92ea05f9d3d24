//! Reading a stepped-sine recording: columns `freq_hz` (the dwell's
//! frequency, Hz), `reference` (the reference motion: the table's rate or
//! angle, or a reference accelerometer) and `output` (the instrument), and
//! `time_s` (s) or the option `rate_hz`. Consecutive rows with one
//! `freq_hz` form a dwell; a change of `freq_hz` starts the next (a
//! frequency visited twice is two dwells). Other columns are ignored.

use std::io::Read;

use crate::error::Result;

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
    /// The reference channel.
    pub reference: Vec<f64>,
    /// The instrument's output.
    pub output: Vec<f64>,
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
/// file). Stamps must not decrease; a frequency must be positive.
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, rate_hz: Option<f64>) -> Result<Vec<Dwell>> {
    let h = rows.header();
    let (cf, cr, co) = (
        h.column("freq_hz")?,
        h.column("reference")?,
        h.column("output")?,
    );
    let ct = h.opt_column("time_s");
    if ct.is_none() && rate_hz.is_none() {
        return Err(h
            .error("no column 'time_s': give the sampling rate (rate_hz) or the stamps")
            .into());
    }
    let mut dwells: Vec<Dwell> = Vec::new();
    let mut index = 0usize;
    let mut last_t = f64::NEG_INFINITY;
    while let Some(row) = rows.next_row()? {
        let f = row.f64(cf)?;
        if f <= 0.0 {
            return Err(row
                .cell_error(cf, format!("{f} is not a positive frequency"))
                .into());
        }
        let t = match (ct, rate_hz) {
            (Some(c), _) => row.f64(c)?,
            (None, Some(r)) => index as f64 / r,
            (None, None) => 0.0,
        };
        if t < last_t {
            let c = ct.unwrap_or(cf);
            return Err(row
                .cell_error(
                    c,
                    format!("time {t} s is before the row above ({last_t} s)"),
                )
                .into());
        }
        last_t = t;
        index += 1;
        let (r, y) = (row.f64(cr)?, row.f64(co)?);
        push(&mut dwells, row.line(), t, f, r, y);
    }
    if dwells.is_empty() {
        return Err(rows.header().error("no data rows").into());
    }
    Ok(dwells)
}

/// One row of a stepped-sine recording as the simulator writes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time (s).
    pub time_s: f64,
    /// Dwell frequency (Hz).
    pub freq_hz: f64,
    /// Reference channel.
    pub reference: f64,
    /// Instrument output.
    pub output: f64,
}

/// The CSV `time_s,freq_hz,reference,output` of samples produced one at a
/// time by `each`, in constant memory.
pub fn write_each<W: std::io::Write>(
    out: W,
    each: impl FnOnce(&mut dyn FnMut(Sample) -> std::io::Result<()>) -> std::io::Result<()>,
) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut w = CsvWriter::new(out, &["time_s", "freq_hz", "reference", "output"])?;
    each(&mut |s: Sample| {
        w.cell(Cell::Num(s.time_s))?;
        w.cell(Cell::Num(s.freq_hz))?;
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
            s.time_s,
            s.freq_hz,
            s.reference,
            s.output,
        );
    }
    dwells
}

/// One row into the dwells: onto the last when it has the same
/// frequency, else as a new dwell.
fn push(dwells: &mut Vec<Dwell>, line: usize, t: f64, f: f64, r: f64, y: f64) {
    match dwells.last_mut() {
        Some(d) if d.freq_hz == f => {
            d.last_line = line;
            d.time_s.push(t);
            d.reference.push(r);
            d.output.push(y);
        }
        _ => dwells.push(Dwell {
            freq_hz: f,
            first_line: line,
            last_line: line,
            time_s: vec![t],
            reference: vec![r],
            output: vec![y],
        }),
    }
}
