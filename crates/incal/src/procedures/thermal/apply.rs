//! Compensation: raw data with its `temperature_c` column corrected by a
//! thermal model (`incal thermal apply MODEL.json --input RAW.csv`).
//!
//! Every column named like an entry of the model is corrected for the
//! change of that entry from `T_ref`:
//!
//! `y_c = y − (p(T*) − p(T_ref))`, `T* = clamp(T, t_min, t_max)`,
//!
//! with `p` the polynomial (1) of the module docs. Clamping keeps the
//! polynomial inside the range it was fitted on (as PX4 and ArduPilot
//! do); the samples clamped are counted and warned about. The value at
//! `T_ref` (`c_0`) is left to the sensor's regular calibration, so a
//! static channel keeps its level. Every other column is copied as it
//! is; rows keep their order.

use std::io::{Read, Write};

use super::{poly, Model};
use crate::error::{Error, Result};

/// What a compensation did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ApplySummary {
    /// Rows written.
    pub rows: usize,
    /// Rows whose temperature was outside the valid range of at least one
    /// corrected channel (clamped).
    pub clamped: usize,
    /// Columns corrected.
    pub corrected: Vec<String>,
}

/// Compensate `input` (named `name`) with `model`, writing CSV to `out`.
pub fn apply<R: Read, W: Write>(
    model: &Model,
    name: &str,
    input: R,
    out: W,
) -> Result<ApplySummary> {
    apply_with(model, name, input, &incal_io::ReadOptions::default(), out)
}

/// [`apply`] with the input layer's options `read`.
pub fn apply_with<R: Read, W: Write>(
    model: &Model,
    name: &str,
    input: R,
    read: &incal_io::ReadOptions,
    out: W,
) -> Result<ApplySummary> {
    let mut rows = incal_io::Reader::new(name, input, read)?;
    let h = rows.header().clone();
    let temp = h.column("temperature_c").map_err(Error::from)?;
    let mut targets = Vec::new();
    for (k, col) in h.names().iter().enumerate() {
        if let Some((e, c)) = model.get(col) {
            let at_ref = poly(c, e.t_ref_c, e.t_ref_c);
            targets.push((k, e.clone(), c.to_vec(), at_ref));
        }
    }
    if targets.is_empty() {
        return Err(Error::Unsupported(format!(
            "{name}: no column is named like a channel of the model ({}); thermal apply corrects the columns the model was fitted on",
            model.names()
        )));
    }
    let io = Error::from;
    let header: Vec<&str> = h.names().iter().map(String::as_str).collect();
    let mut w = incal_io::CsvWriter::new(out, &header).map_err(io)?;
    let mut n = 0usize;
    let mut clamped = 0usize;
    while let Some(row) = rows.next_row()? {
        let t = row.f64(temp)?;
        let mut was_clamped = false;
        let mut fixed: Vec<Option<f64>> = vec![None; row.width()];
        for (k, e, c, at_ref) in &targets {
            if let Some(v) = row.f64_or_missing(*k)? {
                let tc = t.clamp(e.t_min_c, e.t_max_c);
                was_clamped |= tc != t;
                let out = v - (poly(c, e.t_ref_c, tc) - at_ref);
                if !(out.is_finite() && out.abs() <= incal_io::MAX_ABS_VALUE) {
                    return Err(row
                        .cell_error(*k, format!("the compensated value {out:e} is beyond 1e15"))
                        .into());
                }
                fixed[*k] = Some(out);
            }
        }
        for (k, f) in fixed.iter().enumerate() {
            match f {
                Some(v) => w.cell(incal_io::Cell::Num(*v)).map_err(io)?,
                None => w.cell(incal_io::Cell::Text(&row.text(k))).map_err(io)?,
            }
        }
        w.end_row().map_err(io)?;
        n += 1;
        clamped += usize::from(was_clamped);
    }
    rows.finish()?;
    w.finish().map_err(io)?;
    Ok(ApplySummary {
        rows: n,
        clamped,
        corrected: targets
            .iter()
            .map(|(k, ..)| h.names()[*k].clone())
            .collect(),
    })
}

/// `thermal apply` as a [`crate::procedures::stream::Stream`]: a thermal
/// model ([`Model::of`] a thermal result) applied to raw data with its
/// `temperature_c` column.
#[derive(Debug, Clone, Copy)]
pub struct Compensate;

impl crate::procedures::stream::Stream for Compensate {
    type Model = Model;

    /// [`apply`]; rows whose temperature was clamped to the model's valid
    /// range are a `model-range` warning.
    fn stream(
        model: Model,
        name: &str,
        input: Box<dyn Read + Send + '_>,
        read: &incal_io::ReadOptions,
        out: &mut dyn Write,
    ) -> Result<crate::procedures::stream::Streamed> {
        let s = apply_with(&model, name, input, read, out)?;
        let mut warnings = Vec::new();
        if s.clamped > 0 {
            warnings.push(crate::Warning::new(
                crate::warning::WarningCode::ModelRange,
                format!(
                    "{} of {} rows lie outside the model's valid temperature range: their temperature was clamped to it",
                    s.clamped, s.rows
                ),
            ));
        }
        Ok(crate::procedures::stream::Streamed {
            rows: s.rows as u64,
            notes: Vec::new(),
            warnings,
        })
    }
}
