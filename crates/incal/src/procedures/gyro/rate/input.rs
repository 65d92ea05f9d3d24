//! Reading a rate-transfer recording: columns `rate_deg_s` (commanded
//! table rate, deg/s, positive counter-clockwise seen from above) and
//! `output` (gyro output), optional `run` (a label per row); other columns
//! are ignored. One row per sample; samples with the same rate and run
//! form one position.

use std::io::Read;

use super::{RateObservation, MAX_RATE_DEG_S};
use crate::error::Result;

/// The observations of a rate-transfer recording, row by row. A rate
/// beyond [`MAX_RATE_DEG_S`] or an empty run label is refused naming the
/// file, line and column.
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Vec<RateObservation>> {
    let h = rows.header();
    let (cr, co, crun) = (
        h.column("rate_deg_s")?,
        h.column("output")?,
        h.opt_column("run"),
    );
    let mut obs = Vec::new();
    while let Some(row) = rows.next_row()? {
        let rate = row.f64(cr)?;
        if rate.abs() > MAX_RATE_DEG_S {
            return Err(row
                .cell_error(
                    cr,
                    format!("{rate} is beyond any rate table (|rate| <= 1e5 deg/s)"),
                )
                .into());
        }
        let run = match crun {
            Some(c) => {
                let label = row.label(c)?;
                if label.is_empty() {
                    return Err(row
                        .cell_error(c, "empty run label (label every row of a multi-run file)")
                        .into());
                }
                Some(label.to_string())
            }
            None => None,
        };
        obs.push(RateObservation {
            rate_deg_s: rate,
            output: row.f64(co)?,
            run,
        });
    }
    obs.shrink_to_fit();
    Ok(obs)
}

/// Write observations in the rate-transfer input format
/// (`rate_deg_s,output`, and `run` when any observation has one), every
/// number in full (shortest round-trip).
pub fn write<W: std::io::Write>(obs: &[RateObservation], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let runs = obs.iter().any(|o| o.run.is_some());
    let header: &[&str] = if runs {
        &["rate_deg_s", "output", "run"]
    } else {
        &["rate_deg_s", "output"]
    };
    let mut w = CsvWriter::new(out, header)?;
    for o in obs {
        w.cell(Cell::Num(o.rate_deg_s))?;
        w.cell(Cell::Num(o.output))?;
        if runs {
            w.cell(Cell::Text(o.run.as_deref().unwrap_or("")))?;
        }
        w.end_row()?;
    }
    w.finish()
}
