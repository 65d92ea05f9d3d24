//! Reading a centrifuge recording: columns `plane` (`ip`, `io` or `po`),
//! `phi_deg` (fixture angle φ0, deg), `polarity` (+1 or −1),
//! `omega_rad_s` (table rate ω, rad/s; 0 = at rest) and `output`
//! (instrument output E); other columns are ignored. One row per sample;
//! the grouping into points and stations is the reduction's
//! ([`super::calibrate`]).

use std::io::Read;

use super::Observation;
use crate::error::Result;
use crate::rigs::centrifuge::{Plane, Position};

/// The observations of a centrifuge recording, row by row.
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Vec<Observation>> {
    let h = rows.header();
    let (cp, cf, cs, cw, co) = (
        h.column("plane")?,
        h.column("phi_deg")?,
        h.column("polarity")?,
        h.column("omega_rad_s")?,
        h.column("output")?,
    );
    let mut obs = Vec::new();
    while let Some(row) = rows.next_row()? {
        let plane =
            Plane::parse(&row.text(cp)).map_err(|e| row.error(format!("column 'plane': {e}")))?;
        let phi = row.f64(cf)?;
        let pol = row.f64(cs)?;
        let polarity: i8 = if pol == 1.0 {
            1
        } else if pol == -1.0 {
            -1
        } else {
            return Err(row
                .error(format!(
                    "column 'polarity': '{}' must be +1 or -1",
                    row.text(cs)
                ))
                .into());
        };
        let omega_rad_s = row.f64(cw)?;
        let output = row.f64(co)?;
        obs.push(Observation {
            position: Position {
                plane,
                phi_rad: phi.to_radians(),
                polarity,
            },
            omega_rad_s,
            output,
        });
    }
    obs.shrink_to_fit();
    Ok(obs)
}

/// Write observations in the centrifuge input format
/// (`plane,phi_deg,polarity,omega_rad_s,output`). The angle is written to
/// 1e-9 deg (the fixture angle as set), rate and output in full (shortest
/// round trip). A non-finite value is refused, never written.
pub fn write<W: std::io::Write>(obs: &[Observation], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut w = CsvWriter::new(
        out,
        &["plane", "phi_deg", "polarity", "omega_rad_s", "output"],
    )?;
    for o in obs {
        let phi = (o.position.phi_rad.to_degrees() * 1e9).round() / 1e9;
        w.row(&[
            Cell::Text(o.position.plane.name()),
            Cell::Num(phi),
            Cell::Num(f64::from(o.position.polarity)),
            Cell::Num(o.omega_rad_s),
            Cell::Num(o.output),
        ])?;
    }
    w.finish()
}
