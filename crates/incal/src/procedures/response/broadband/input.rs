//! Reading a broadband recording (chirp, random or multisine): columns
//! `reference` and `output`, and `time_s` (s) or the option `rate_hz`.
//! The spectral estimate needs evenly spaced samples: stamps must not
//! decrease, a step above 1.5 periods (a gap) is refused naming its line,
//! and a `rate_hz` given beside the stamps must agree with them within
//! [`crate::timebase::RATE_TOLERANCE`].
//!
//! A reference sampled by another clock gives its own stamps in
//! `time_ref_s` (needs `time_s`): the offset `δ = mean(time_ref_s −
//! time_s)` (the reference's sample of row n is taken at `t_n + δ`) is
//! put back into the phase (broadband) or the step time (step). The two
//! clocks must run at one rate: a difference that moves by more than half
//! a period over the record is refused naming its line (resample the
//! record onto one clock first).

use std::io::Read;

use crate::error::{Error, Result};

/// One evenly sampled record.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Record {
    /// The sampling rate (Hz): from the stamps, or as given.
    pub rate_hz: f64,
    /// The reference channel.
    pub reference: Vec<f64>,
    /// The instrument's output.
    pub output: Vec<f64>,
    /// The reference's clock against the output's (s): its sample of row
    /// n is taken at `t_n + δ` (0 on one clock).
    pub reference_offset_s: f64,
}

/// The record of a recording, row by row.
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, rate_hz: Option<f64>) -> Result<Record> {
    let h = rows.header();
    let (cr, co) = (h.column("reference")?, h.column("output")?);
    let ct = h.opt_column("time_s");
    if ct.is_none() && rate_hz.is_none() {
        return Err(h
            .error("no column 'time_s': give the sampling rate (rate_hz) or the stamps")
            .into());
    }
    let cref = crate::procedures::response::input::reference_clock(h, ct)?;
    let mut rec = Record::default();
    let mut stamps: Vec<(f64, usize)> = Vec::new();
    let mut offsets: Vec<f64> = Vec::new();
    while let Some(row) = rows.next_row()? {
        if let Some(c) = ct {
            let t = row.f64(c)?;
            if let Some(r) = cref {
                offsets.push(row.f64(r)? - t);
            }
            if let Some((last, _)) = stamps.last() {
                if t <= *last {
                    return Err(row
                        .cell_error(
                            c,
                            format!("time {t} s does not follow the row above ({last} s)"),
                        )
                        .into());
                }
            }
            stamps.push((t, row.line()));
        }
        rec.reference.push(row.f64(cr)?);
        rec.output.push(row.f64(co)?);
    }
    let n = rec.reference.len();
    if n < 16 {
        return Err(rows
            .header()
            .error(format!("{n} data rows: a spectrum needs at least 16"))
            .into());
    }
    rec.rate_hz = if stamps.is_empty() {
        rate_hz.unwrap_or(1.0)
    } else {
        crate::timebase::even_rate(
            n,
            |k| stamps[k],
            rate_hz,
            "a spectrum needs evenly spaced samples; cut the record at the gap",
        )?
    };
    if !offsets.is_empty() {
        rec.reference_offset_s = one_offset(&offsets, &stamps, rec.rate_hz)?;
    }
    Ok(rec)
}

/// The reference clock's one offset against the output's: the mean of
/// `time_ref_s − time_s`, refused when a row's differs from it by more
/// than half a period (the clocks run at different rates, or jump).
fn one_offset(offsets: &[f64], stamps: &[(f64, usize)], rate_hz: f64) -> Result<f64> {
    let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
    let half = 0.5 / rate_hz;
    if let Some((d, (_, line))) = offsets
        .iter()
        .zip(stamps)
        .find(|(d, _)| (**d - mean).abs() > half)
    {
        return Err(Error::Unsupported(format!(
            "line {line}: time_ref_s - time_s is {d:.9} s against a mean of {mean:.9} s: the two clocks drift apart by more than half a period over the record; resample it onto one clock"
        )));
    }
    Ok(mean)
}

/// The CSV `time_s,reference,output` of a record (with `time_ref_s`
/// when the reference has its own clock).
pub fn write<W: std::io::Write>(rec: &Record, out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let own = rec.reference_offset_s != 0.0;
    let header: &[&str] = if own {
        &["time_s", "time_ref_s", "reference", "output"]
    } else {
        &["time_s", "reference", "output"]
    };
    let mut w = CsvWriter::new(out, header)?;
    for (k, (x, y)) in rec.reference.iter().zip(&rec.output).enumerate() {
        w.cell(Cell::Num(k as f64 / rec.rate_hz))?;
        if own {
            w.cell(Cell::Num(k as f64 / rec.rate_hz + rec.reference_offset_s))?;
        }
        w.cell(Cell::Num(*x))?;
        w.cell(Cell::Num(*y))?;
        w.end_row()?;
    }
    w.finish()
}
