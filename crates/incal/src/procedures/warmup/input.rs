//! Reading a warm-up recording: `time_s` (s, or the option `rate_hz`),
//! the output column (`output` unless the option `column` names
//! another), and optionally `status` (a sample is valid where it is not
//! 0) and `temperature_c`. An empty or `NaN` output cell is a sample the
//! instrument did not give (before turn-on, a dropped sample), never a
//! number. Rows evenly spaced: a gap of more than 1.5 periods in `time_s`
//! is refused naming its line.

use std::io::Read;

use crate::error::Result;

/// A warm-up record: one row per sample, evenly spaced.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    /// Time of each row (s, on the file's clock; from 0 at `rate_hz`
    /// when the file has no `time_s`).
    pub time_s: Vec<f64>,
    /// The output, `None` where the cell is empty or `NaN`.
    pub output: Vec<Option<f64>>,
    /// The status column, if any (valid where not 0).
    pub status: Option<Vec<f64>>,
    /// The temperature column (°C), if any.
    pub temperature_c: Option<Vec<f64>>,
    /// The sampling rate (Hz).
    pub rate_hz: f64,
    /// The file line of each row (for messages).
    pub lines: Vec<usize>,
}

/// Read a warm-up record (module docs).
pub fn read<R: Read>(
    rows: &mut incal_io::Reader<R>,
    rate_hz: Option<f64>,
    column: &str,
) -> Result<Record> {
    let h = rows.header();
    let co = h.column(column)?;
    let ct = h.opt_column("time_s");
    let cs = h.opt_column("status");
    let cc = h.opt_column("temperature_c");
    if ct.is_none() && rate_hz.is_none() {
        return Err(h
            .error("no column 'time_s': give the sampling rate (rate_hz) or the stamps")
            .into());
    }
    let mut rec = Record {
        status: cs.map(|_| Vec::new()),
        temperature_c: cc.map(|_| Vec::new()),
        ..Record::default()
    };
    while let Some(row) = rows.next_row()? {
        let k = rec.output.len();
        let t = match (ct, rate_hz) {
            (Some(c), _) => row.f64(c)?,
            (None, Some(r)) => k as f64 / r,
            (None, None) => unreachable!("checked above"),
        };
        if let (Some(c), Some(last)) = (ct, rec.time_s.last()) {
            if t <= *last {
                return Err(row
                    .cell_error(
                        c,
                        format!("time {t} s does not follow the row above ({last} s)"),
                    )
                    .into());
            }
        }
        rec.time_s.push(t);
        rec.output.push(row.f64_or_missing(co)?);
        if let (Some(c), Some(v)) = (cs, rec.status.as_mut()) {
            v.push(row.f64(c)?);
        }
        if let (Some(c), Some(v)) = (cc, rec.temperature_c.as_mut()) {
            v.push(row.f64(c)?);
        }
        rec.lines.push(row.line());
    }
    let n = rec.output.len();
    if n < 20 {
        return Err(rows
            .header()
            .error(format!("{n} data rows: a warm-up record needs at least 20"))
            .into());
    }
    rec.rate_hz = match ct {
        Some(_) => crate::timebase::even_rate(
            n,
            |k| (rec.time_s[k], rec.lines[k]),
            rate_hz,
            "write the rows the instrument missed with an empty output cell",
        )?,
        None => rate_hz.unwrap_or(1.0),
    };
    Ok(rec)
}

/// The CSV `time_s,output,status[,temperature_c]` of a record (an empty
/// output cell where the sample is missing).
pub fn write<W: std::io::Write>(rec: &Record, out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut header = vec!["time_s", "output"];
    if rec.status.is_some() {
        header.push("status");
    }
    if rec.temperature_c.is_some() {
        header.push("temperature_c");
    }
    let mut w = CsvWriter::new(out, &header)?;
    for (k, y) in rec.output.iter().enumerate() {
        w.cell(Cell::Num(rec.time_s[k]))?;
        match y {
            Some(v) => w.cell(Cell::Num(*v))?,
            None => w.cell(Cell::Text(""))?,
        }
        if let Some(s) = &rec.status {
            w.cell(Cell::Num(s[k]))?;
        }
        if let Some(c) = &rec.temperature_c {
            w.cell(Cell::Num(c[k]))?;
        }
        w.end_row()?;
    }
    w.finish()
}
