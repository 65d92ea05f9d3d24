//! Reading a tumble recording: columns `angle_deg` (head angle, deg) and
//! `output` (instrument output), optional `pass` (a label per row, e.g.
//! `cw`/`ccw`); other columns are ignored. One row per sample; samples
//! with the same pass and angle form one position.

use std::io::Read;

use super::Observation;
use crate::error::Result;

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
        let output = row.f64(co)?;
        let pass = match cp {
            Some(c) => {
                let label = row.text(c);
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
