//! Reading a multi-position recording: columns `angle_deg` (head angle,
//! deg) and `output` (gyro output), optional `azimuth_deg` (azimuth of the
//! head axis, deg from north towards east; without it every row has the
//! azimuth of the options); other columns are ignored. One row per sample;
//! samples at the same angle and azimuth form one position.

use std::io::Read;

use super::{PositionObservation, MAX_ANGLE_DEG};
use crate::error::Result;

/// The observations of a multi-position recording, row by row;
/// `azimuth_deg` is the azimuth of a recording without an `azimuth_deg`
/// column (refused when both are missing). An angle or azimuth beyond
/// 1e4 deg is refused naming the file, line and column.
pub fn read<R: Read>(
    rows: &mut incal_io::Reader<R>,
    azimuth_deg: Option<f64>,
) -> Result<Vec<PositionObservation>> {
    let h = rows.header();
    let (ca, co, cz) = (
        h.column("angle_deg")?,
        h.column("output")?,
        h.opt_column("azimuth_deg"),
    );
    let azimuth_deg = match (cz, azimuth_deg) {
        (None, None) => {
            return Err(h
                .error("no azimuth: give the `azimuth_deg` option or an azimuth_deg column")
                .into())
        }
        (_, z) => z.unwrap_or(0.0),
    };
    let mut obs = Vec::new();
    while let Some(row) = rows.next_row()? {
        let angle = row.f64(ca)?;
        if angle.abs() > MAX_ANGLE_DEG {
            return Err(row
                .cell_error(ca, format!("{angle} is out of range (|angle| <= 1e4 deg)"))
                .into());
        }
        let az = match cz {
            Some(c) => row.f64(c)?,
            None => azimuth_deg,
        };
        if az.abs() > MAX_ANGLE_DEG {
            let msg = format!("{az} is out of range (|azimuth| <= 1e4 deg)");
            return Err(match cz {
                Some(c) => row.cell_error(c, msg),
                None => row.error(format!("azimuth_deg {msg}")),
            }
            .into());
        }
        obs.push(PositionObservation {
            angle_rad: angle.to_radians(),
            azimuth_rad: az.to_radians(),
            output: row.f64(co)?,
        });
    }
    obs.shrink_to_fit();
    Ok(obs)
}

/// Write observations in the multi-position input format
/// (`angle_deg,output`, or `angle_deg,azimuth_deg,output` with
/// `azimuth_column`). Angles are written to 1e-9 deg (the head's angle as
/// set), the output in full (shortest round-trip).
pub fn write<W: std::io::Write>(
    obs: &[PositionObservation],
    azimuth_column: bool,
    out: W,
) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let header: &[&str] = if azimuth_column {
        &["angle_deg", "azimuth_deg", "output"]
    } else {
        &["angle_deg", "output"]
    };
    let deg = |rad: f64| (rad.to_degrees() * 1e9).round() / 1e9;
    let mut w = CsvWriter::new(out, header)?;
    for o in obs {
        w.cell(Cell::Num(deg(o.angle_rad)))?;
        if azimuth_column {
            w.cell(Cell::Num(deg(o.azimuth_rad)))?;
        }
        w.cell(Cell::Num(o.output))?;
        w.end_row()?;
    }
    w.finish()
}
