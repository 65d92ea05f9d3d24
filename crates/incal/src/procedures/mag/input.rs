//! Reading a magnetometer session: `mag_x, mag_y, mag_z` (the raw field,
//! any unit: µT, gauss, counts), optional `acc_x, acc_y, acc_z` (the
//! accelerometer of the same unit, any unit: its direction is used),
//! optional `gyr_x, gyr_y, gyr_z` (its gyro, for finding the rows at rest)
//! and optional `time_s` (s, strictly increasing). A triad is all three
//! columns or none; other columns are ignored. Every cell of a used column
//! must be a finite number: a missing magnetometer sample is a row left
//! out by the logger, not an empty cell.

use std::io::Read;

use crate::error::Result;

/// The magnetometer columns.
pub const MAG: [&str; 3] = ["mag_x", "mag_y", "mag_z"];
/// The accelerometer columns.
pub const ACC: [&str; 3] = ["acc_x", "acc_y", "acc_z"];
/// The gyro columns.
pub const GYR: [&str; 3] = ["gyr_x", "gyr_y", "gyr_z"];

/// One session, one row per sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Record {
    /// The raw field of each row, in the magnetometer's axes after the
    /// option `axes` (raw units).
    pub mag: Vec<[f64; 3]>,
    /// The accelerometer of each row, if the file has it.
    pub acc: Option<Vec<[f64; 3]>>,
    /// The gyro of each row, if the file has it.
    pub gyr: Option<Vec<[f64; 3]>>,
    /// Time of each row (s), if the file has `time_s`.
    pub time_s: Option<Vec<f64>>,
    /// The file line of each row (for messages).
    pub lines: Vec<usize>,
}

/// A triad's columns: all three, none, or an error naming the missing one.
fn triad(h: &incal_io::Header, names: [&str; 3]) -> Result<Option<[usize; 3]>> {
    let cols = names.map(|n| h.opt_column(n));
    if cols.iter().all(Option::is_none) {
        return Ok(None);
    }
    let mut out = [0; 3];
    for (k, c) in cols.iter().enumerate() {
        out[k] = match c {
            Some(c) => *c,
            None => h.column(names[k])?,
        };
    }
    Ok(Some(out))
}

/// Read a session (module docs); `axes` maps the file's magnetometer
/// columns to the magnetometer's axes ([`super::Axes`]).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, axes: &super::Axes) -> Result<Record> {
    let h = rows.header();
    // No triad at all: the error of the first column names it.
    let cm = match triad(h, MAG)? {
        Some(c) => c,
        None => [h.column(MAG[0])?; 3],
    };
    let ca = triad(h, ACC)?;
    let cg = triad(h, GYR)?;
    let ct = h.opt_column("time_s");
    let mut rec = Record {
        acc: ca.map(|_| Vec::new()),
        gyr: cg.map(|_| Vec::new()),
        time_s: ct.map(|_| Vec::new()),
        ..Record::default()
    };
    let three = |row: &incal_io::Row<'_>, c: [usize; 3]| -> Result<[f64; 3]> {
        Ok([row.f64(c[0])?, row.f64(c[1])?, row.f64(c[2])?])
    };
    while let Some(row) = rows.next_row()? {
        rec.mag.push(axes.map(three(&row, cm)?));
        if let (Some(c), Some(v)) = (ca, rec.acc.as_mut()) {
            v.push(three(&row, c)?);
        }
        if let (Some(c), Some(v)) = (cg, rec.gyr.as_mut()) {
            v.push(three(&row, c)?);
        }
        if let (Some(c), Some(v)) = (ct, rec.time_s.as_mut()) {
            let t = row.f64(c)?;
            if let Some(last) = v.last() {
                if t <= *last {
                    return Err(row
                        .cell_error(
                            c,
                            format!("time {t} s does not follow the row above ({last} s)"),
                        )
                        .into());
                }
            }
            v.push(t);
        }
        rec.lines.push(row.line());
    }
    let n = rec.mag.len();
    if n < super::fit::UNKNOWNS + 1 {
        return Err(rows
            .header()
            .error(format!(
                "{n} data rows: a magnetometer calibration has {} unknowns and needs more rows than that",
                super::fit::UNKNOWNS
            ))
            .into());
    }
    Ok(rec)
}

/// The CSV of a session: `time_s` (if any), `mag_x, mag_y, mag_z`, then
/// the accelerometer and gyro triads present.
pub fn write<W: std::io::Write>(rec: &Record, out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut header: Vec<&str> = Vec::new();
    if rec.time_s.is_some() {
        header.push("time_s");
    }
    header.extend(MAG);
    if rec.acc.is_some() {
        header.extend(ACC);
    }
    if rec.gyr.is_some() {
        header.extend(GYR);
    }
    let mut w = CsvWriter::new(out, &header)?;
    for k in 0..rec.mag.len() {
        if let Some(t) = &rec.time_s {
            w.cell(Cell::Num(t[k]))?;
        }
        for v in rec.mag[k] {
            w.cell(Cell::Num(v))?;
        }
        for tri in [&rec.acc, &rec.gyr].into_iter().flatten() {
            for v in tri[k] {
                w.cell(Cell::Num(v))?;
            }
        }
        w.end_row()?;
    }
    w.finish()
}
