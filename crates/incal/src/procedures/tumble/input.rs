//! Reading a tumble recording: columns `angle_deg` (head angle, deg) and
//! `output` (instrument output), optional `pass` (a label per row, e.g.
//! `cw`/`ccw`); other columns are ignored. One row per sample; samples
//! with the same pass and angle form one position.

use std::io::Read;

use super::Observation;
use crate::error::Result;

/// The largest head angle read (deg): ±1e4 deg is 27 turns either way. A
/// larger angle loses digits in its sine (3.6e14 deg gave K1 9.9944 for
/// 10): an offset that large is not a head reading.
pub const MAX_ANGLE_DEG: f64 = 1e4;

/// The observations of a tumble recording, row by row (the file itself is
/// never held: a 720 000-row file costs its observations only).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Vec<Observation>> {
    let h = rows.header();
    let (ca, co, cp) = (
        h.column("angle_deg")?,
        h.column("output")?,
        h.opt_column("pass"),
    );
    let mut obs = Vec::new();
    while let Some(row) = rows.next_row()? {
        let angle = row.f64(ca)?;
        if angle.abs() > MAX_ANGLE_DEG {
            return Err(row
                .cell_error(
                    ca,
                    format!("{angle} is beyond a dividing head's range (|angle| <= 1e4 deg)"),
                )
                .into());
        }
        let output = row.f64(co)?;
        let pass = match cp {
            Some(c) => {
                let label = row.label(c)?;
                if label.is_empty() {
                    return Err(row
                        .error("column 'pass': empty label (label every row of a multi-pass file)")
                        .into());
                }
                Some(label.to_string())
            }
            None => None,
        };
        obs.push(Observation {
            angle_rad: angle.to_radians(),
            output,
            pass,
        });
    }
    obs.shrink_to_fit();
    Ok(obs)
}

/// Write observations in the tumble input format (`angle_deg,output` and
/// `pass` when any observation has one). The angle is written to 1e-9 deg
/// (the head's angle as set), the output in full (shortest round-trip).
pub fn write<W: std::io::Write>(obs: &[Observation], out: W) -> std::io::Result<W> {
    let passes = obs.iter().any(|o| o.pass.is_some());
    write_each(passes, out, |row| obs.iter().cloned().try_for_each(row))
}

/// The CSV of observations produced one at a time by `each` (the pass
/// column when `passes`), in constant memory: the simulator's writer.
pub fn write_each<W: std::io::Write>(
    passes: bool,
    out: W,
    each: impl FnOnce(&mut dyn FnMut(Observation) -> std::io::Result<()>) -> std::io::Result<()>,
) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let header: &[&str] = if passes {
        &["angle_deg", "output", "pass"]
    } else {
        &["angle_deg", "output"]
    };
    let mut w = CsvWriter::new(out, header)?;
    each(&mut |o: Observation| {
        let angle = (o.angle_rad.to_degrees() * 1e9).round() / 1e9;
        w.cell(Cell::Num(angle))?;
        w.cell(Cell::Num(o.output))?;
        if passes {
            w.cell(Cell::Text(o.pass.as_deref().unwrap_or("")))?;
        }
        w.end_row()
    })?;
    w.finish()
}
