//! Reading a threshold recording: the commanded input, `rate_deg_s` (a
//! gyro on a rate table, deg/s) or `tilt_deg` (an accelerometer on a
//! dividing head, deg from level: the input is `sin(tilt)` in g), and the
//! `output`; optional `time_s` (s, only for the option `settle_s`). One
//! row per sample; consecutive rows with the same commanded input form
//! one plateau.

use std::io::Read;

use crate::error::Result;

/// The instrument, from the input column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sensor {
    /// A gyro: `rate_deg_s`, inputs in deg/s.
    Gyro,
    /// An accelerometer: `tilt_deg`, inputs in g (`sin(tilt)`).
    Accel,
}

impl Sensor {
    /// The input's unit string.
    pub fn unit(self) -> &'static str {
        match self {
            Sensor::Gyro => "deg/s",
            Sensor::Accel => "g",
        }
    }

    /// The suffix of the coefficients' names (`threshold_deg_s`,
    /// `threshold_g`).
    pub fn suffix(self) -> &'static str {
        match self {
            Sensor::Gyro => "deg_s",
            Sensor::Accel => "g",
        }
    }

    /// The input column.
    pub fn column(self) -> &'static str {
        match self {
            Sensor::Gyro => "rate_deg_s",
            Sensor::Accel => "tilt_deg",
        }
    }
}

/// A threshold recording, row by row.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// The commanded input of each row as written (deg/s or deg of tilt).
    pub command: Vec<f64>,
    /// The output of each row.
    pub output: Vec<f64>,
    /// Time of each row (s), when the file has `time_s`.
    pub time_s: Option<Vec<f64>>,
    /// The file line of each row.
    pub lines: Vec<usize>,
}

impl Record {
    /// The input of row `k` in engineering units: deg/s, or g
    /// (`sin(tilt)`).
    pub fn input(&self, k: usize) -> f64 {
        match self.sensor {
            Sensor::Gyro => self.command[k],
            Sensor::Accel => self.command[k].to_radians().sin(),
        }
    }
}

/// Read a threshold recording (module docs). A commanded rate beyond
/// 1e5 deg/s or a tilt beyond ±360° is refused naming the cell.
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Record> {
    let h = rows.header();
    let (sensor, ci) = match (h.opt_column("rate_deg_s"), h.opt_column("tilt_deg")) {
        (Some(c), None) => (Sensor::Gyro, c),
        (None, Some(c)) => (Sensor::Accel, c),
        (Some(_), Some(_)) => {
            return Err(h
                .error("both 'rate_deg_s' and 'tilt_deg': one input column (a gyro's rate or an accelerometer's tilt)")
                .into())
        }
        (None, None) => {
            return Err(h
                .error("no input column: 'rate_deg_s' (gyro on a rate table) or 'tilt_deg' (accelerometer on a dividing head)")
                .into())
        }
    };
    let co = h.column("output")?;
    let ct = h.opt_column("time_s");
    let limit = match sensor {
        Sensor::Gyro => 1e5,
        Sensor::Accel => 360.0,
    };
    let mut rec = Record {
        sensor,
        command: Vec::new(),
        output: Vec::new(),
        time_s: ct.map(|_| Vec::new()),
        lines: Vec::new(),
    };
    while let Some(row) = rows.next_row()? {
        let u = row.f64(ci)?;
        if u.abs() > limit {
            return Err(row
                .cell_error(
                    ci,
                    format!(
                        "{u} is beyond any {} (|input| <= {limit})",
                        match sensor {
                            Sensor::Gyro => "rate table",
                            Sensor::Accel => "dividing head",
                        }
                    ),
                )
                .into());
        }
        rec.command.push(u);
        rec.output.push(row.f64(co)?);
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
    if rec.output.len() < 8 {
        return Err(rows
            .header()
            .error(format!(
                "{} data rows: a threshold test needs plateaus of several samples",
                rec.output.len()
            ))
            .into());
    }
    Ok(rec)
}

/// The CSV `time_s,<input column>,output` of a record.
pub fn write<W: std::io::Write>(rec: &Record, out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut header = Vec::new();
    if rec.time_s.is_some() {
        header.push("time_s");
    }
    header.extend([rec.sensor.column(), "output"]);
    let mut w = CsvWriter::new(out, &header)?;
    for k in 0..rec.output.len() {
        if let Some(t) = &rec.time_s {
            w.cell(Cell::Num(t[k]))?;
        }
        w.cell(Cell::Num(rec.command[k]))?;
        w.cell(Cell::Num(rec.output[k]))?;
        w.end_row()?;
    }
    w.finish()
}
