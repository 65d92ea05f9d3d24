//! Reading and writing misalignment recordings.
//!
//! Gyro on a rate table, one of two layouts:
//! - record means: `alpha_deg,beta_deg,rate,output`, one row per
//!   whole-revolution mean (`rate`: signed table rate, deg/s);
//! - raw records: the same columns plus `time_s` and `table_angle_deg`,
//!   one row per sample. A record is a run of rows with one
//!   `(alpha_deg, beta_deg, rate)`; a new record also starts where the time
//!   goes back (records of one configuration written one after another,
//!   each from its own t = 0). Each record is reduced by
//!   [`super::averaging::average_record`].
//!
//! Accelerometer on a vertical face: `beta_deg,output`, one row per
//! sample; rows with the same β form one position. Other columns are
//! ignored in every layout.

use std::io::Read;

use super::accel::AccelObservation;
use super::averaging::{average_record, RawSample, Record, RecordMean, TurnPolicy};
use super::gyro::{GyroConfig, GyroObservation};
use crate::error::Result;

/// The observations of a gyro recording, and for raw records the
/// reduction of each record with its first file line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GyroInput {
    /// One observation per record mean (or per row of a means file).
    pub observations: Vec<GyroObservation>,
    /// Raw records only: first file line and reduction of each record.
    pub records: Vec<(usize, RecordMean)>,
}

/// Read a gyro recording in either layout (module docs); `average` says
/// which samples of a raw record are averaged.
pub fn read_gyro<R: Read>(
    rows: &mut incal_io::Reader<R>,
    average: TurnPolicy,
) -> Result<GyroInput> {
    let h = rows.header();
    let (ca, cb, cr, co) = (
        h.column("alpha_deg")?,
        h.column("beta_deg")?,
        h.column("rate")?,
        h.column("output")?,
    );
    let raw = h.opt_column("time_s").is_some() || h.opt_column("table_angle_deg").is_some();
    if !raw {
        let mut observations = Vec::new();
        while let Some(row) = rows.next_row()? {
            let rate = row.f64(cr)?;
            if rate == 0.0 {
                return Err(row.cell_error(cr, "the table rate must not be 0").into());
            }
            observations.push(GyroObservation {
                alpha_rad: row.f64(ca)?.to_radians(),
                beta_rad: row.f64(cb)?.to_radians(),
                rate_deg_s: rate,
                output: row.f64(co)?,
            });
        }
        return Ok(GyroInput {
            observations,
            records: Vec::new(),
        });
    }
    let (ct, cg) = (h.column("time_s")?, h.column("table_angle_deg")?);
    let file = h.file().to_string();
    let mut records: Vec<(usize, Record)> = Vec::new();
    let mut last: Option<(f64, f64, f64)> = None;
    while let Some(row) = rows.next_row()? {
        let key = (row.f64(ca)?, row.f64(cb)?, row.f64(cr)?);
        if key.2 == 0.0 {
            return Err(row.cell_error(cr, "the table rate must not be 0").into());
        }
        let s = RawSample {
            time_s: row.f64(ct)?,
            table_angle_rad: row.f64(cg)?.to_radians(),
            output: row.f64(co)?,
        };
        let prev_time = records
            .last()
            .and_then(|(_, r)| r.samples.last())
            .map(|p| p.time_s);
        let restart = matches!(prev_time, Some(p) if s.time_s < p);
        if last != Some(key) || restart {
            records.push((
                row.line(),
                Record {
                    config: GyroConfig::deg(key.0, key.1),
                    rate_deg_s: key.2,
                    samples: Vec::new(),
                },
            ));
            last = Some(key);
        }
        if let Some((_, r)) = records.last_mut() {
            r.samples.push(s);
        }
    }
    let mut out = GyroInput::default();
    for (line, r) in &records {
        let mean = average_record(r, average)
            .map_err(|e| incal_io::InputError::at(&file, *line, e.to_string()))?;
        out.observations.push(mean.observation);
        out.records.push((*line, mean));
    }
    Ok(out)
}

/// Read an accelerometer recording (`beta_deg,output`).
pub fn read_accel<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Vec<AccelObservation>> {
    let h = rows.header();
    let (cb, co) = (h.column("beta_deg")?, h.column("output")?);
    let mut obs = Vec::new();
    while let Some(row) = rows.next_row()? {
        obs.push(AccelObservation {
            beta_rad: row.f64(cb)?.to_radians(),
            output: row.f64(co)?,
        });
    }
    Ok(obs)
}

/// Degrees to 1e-9 deg: a plan's angles as set, written round-trip exact.
fn deg9(rad: f64) -> f64 {
    (rad.to_degrees() * 1e9).round() / 1e9
}

/// Write gyro record means (`alpha_deg,beta_deg,rate,output`).
pub fn write_gyro_means<W: std::io::Write>(obs: &[GyroObservation], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut w = CsvWriter::new(out, &["alpha_deg", "beta_deg", "rate", "output"])?;
    for o in obs {
        for x in [deg9(o.alpha_rad), deg9(o.beta_rad), o.rate_deg_s, o.output] {
            w.cell(Cell::Num(x))?;
        }
        w.end_row()?;
    }
    w.finish()
}

/// Write raw gyro records
/// (`alpha_deg,beta_deg,rate,time_s,table_angle_deg,output`).
pub fn write_gyro_records<W: std::io::Write>(records: &[Record], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut w = CsvWriter::new(
        out,
        &[
            "alpha_deg",
            "beta_deg",
            "rate",
            "time_s",
            "table_angle_deg",
            "output",
        ],
    )?;
    for r in records {
        let (a, b) = (deg9(r.config.alpha_rad), deg9(r.config.beta_rad));
        for s in &r.samples {
            for x in [
                a,
                b,
                r.rate_deg_s,
                s.time_s,
                deg9(s.table_angle_rad),
                s.output,
            ] {
                w.cell(Cell::Num(x))?;
            }
            w.end_row()?;
        }
    }
    w.finish()
}

/// Write accelerometer outputs (`beta_deg,output`).
pub fn write_accel<W: std::io::Write>(obs: &[AccelObservation], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut w = CsvWriter::new(out, &["beta_deg", "output"])?;
    for o in obs {
        w.cell(Cell::Num(deg9(o.beta_rad)))?;
        w.cell(Cell::Num(o.output))?;
        w.end_row()?;
    }
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedures::misalign::sim::{simulate_gyro_records, GyroSim};
    use crate::rigs::rate_table::GyroMounting;

    fn reader(bytes: &[u8]) -> incal_io::Reader<&[u8]> {
        incal_io::Reader::new("t.csv", bytes, &incal_io::ReadOptions::default()).unwrap()
    }

    #[test]
    fn raw_records_written_and_read_back_give_the_same_means() {
        let cfg = GyroSim {
            mounting: GyroMounting::default(),
            scale_factor: -2.9,
            bias: 0.01,
            bias_shift: 0.0,
            configs: GyroConfig::paper(),
            rates_deg_s: vec![20.0],
            records: 2,
            turns: 1.0,
            samples_per_turn: 12,
            noise: 1e-3,
            latitude_rad: 0.8,
            seed: 4,
        };
        cfg.validate().unwrap();
        let records = simulate_gyro_records(&cfg);
        let bytes = write_gyro_records(&records, Vec::new()).unwrap();
        let got = read_gyro(&mut reader(&bytes), TurnPolicy::Whole).unwrap();
        // Two records of one configuration and rate follow each other: the
        // time going back starts the second.
        assert_eq!(got.records.len(), records.len());
        assert_eq!(got.records[1].0, 2 + 12);
        for ((_, m), r) in got.records.iter().zip(&records) {
            let mean = r.samples.iter().map(|s| s.output).sum::<f64>() / 12.0;
            assert!((m.observation.output - mean).abs() < 1e-12);
        }
    }

    #[test]
    fn a_zero_rate_and_a_record_without_span_are_refused_at_their_line() {
        let e = read_gyro(
            &mut reader(b"alpha_deg,beta_deg,rate,output\n0,0,20,1\n0,0,0,1\n"),
            TurnPolicy::Whole,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("t.csv:3") && e.contains("rate"), "{e}");
        let e = read_gyro(
            &mut reader(b"alpha_deg,beta_deg,rate,time_s,table_angle_deg,output\n0,0,20,0,0,1\n0,0,20,0,1,1\n"),
            TurnPolicy::Whole,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("t.csv:2") && e.contains("does not advance"),
            "{e}"
        );
        // A repeated stamp inside a record is accepted and counted.
        let got = read_gyro(
            &mut reader(b"alpha_deg,beta_deg,rate,time_s,table_angle_deg,output\n0,0,20,0,0,1\n0,0,20,0,10,1\n0,0,20,1,20,1\n"),
            TurnPolicy::All,
        )
        .unwrap();
        let w = &got.records[0].1.warnings;
        assert!(
            w.iter().any(|w| w.code == crate::WarningCode::TimeRepeats),
            "{w:?}"
        );
    }
}
