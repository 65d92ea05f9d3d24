//! `incal batch … --units`: several units on one fixture, recorded in one
//! file, each reduced as its own result with its own serial.
//!
//! `--units LIST` names each unit's output column (`out_1`, or
//! `SERIAL=out_1`): the unit's reduction reads it as the procedure's
//! output column (`--unit-column`, default `output`). `--units FILE` names
//! a mapping file, a CSV with the columns `serial` and `columns` (a bare
//! column, read as `--unit-column`, or a whole `--columns` value such as
//! `acc_x=u1_ax,acc_y=u1_ay,acc_z=u1_az`) and, optionally, `slot`
//! (recorded as `meta.slot`) and `options` (the unit's own options,
//! separated by spaces: its orientation in the slot as the procedure
//! expresses it, such as `mag`'s `--axes`).

use std::path::Path;

use crate::error::{CliError, CliResult};

/// One unit of a fixture.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Unit {
    /// Its serial (`--serial`).
    pub serial: String,
    /// Its columns (`--columns`).
    pub columns: String,
    /// Its slot on the fixture (`--meta slot=…`).
    pub slot: Option<String>,
    /// Its own options, after the batch's.
    pub options: Vec<String>,
}

impl Unit {
    /// The options that make a one-file command line reduce this unit.
    pub fn args(&self) -> Vec<String> {
        // `--flag=value`: a serial such as `-001` is a value, not a flag.
        let mut a = vec![
            format!("--serial={}", self.serial),
            format!("--columns={}", self.columns),
        ];
        if let Some(s) = &self.slot {
            a.push(format!("--meta=slot={s}"));
        }
        a.extend(self.options.iter().cloned());
        a
    }
}

/// A unit's columns: a bare column is read as `target`.
fn columns_of(cell: &str, target: &str) -> String {
    if cell.contains('=') {
        cell.to_string()
    } else {
        format!("{target}={cell}")
    }
}

/// The units `--units` names: a mapping file when `value` is a file,
/// else a list. Refuses an empty entry, a serial given twice, and a
/// mapping file without `serial` and `columns`, naming the line.
pub fn parse(value: &str, target: &str) -> CliResult<Vec<Unit>> {
    let units = if Path::new(value).is_file() {
        from_file(Path::new(value), target)?
    } else {
        from_list(value, target)?
    };
    // Serials name result files: no path separators or control
    // characters, and unique whatever their case.
    let mut seen = std::collections::HashSet::new();
    for u in &units {
        if u.serial
            .chars()
            .any(|c| c.is_control() || "/\\:".contains(c))
        {
            return Err(CliError::Input(format!(
                "--units: serial '{}' holds '/', '\\', ':' or a control character (it names the unit's result file)",
                incal_io::clip(&u.serial)
            )));
        }
        if !seen.insert(u.serial.to_lowercase()) {
            return Err(CliError::Input(format!(
                "--units: serial '{}' given twice",
                incal_io::clip(&u.serial)
            )));
        }
        for o in &u.options {
            let flag = o.split('=').next().unwrap_or_default();
            if matches!(
                flag,
                "--input" | "--json" | "-o" | "--output" | "--serial" | "--columns"
            ) {
                return Err(CliError::Input(format!(
                    "--units: unit {}: {flag} is set by the batch; leave it out of the unit's options",
                    u.serial
                )));
            }
        }
    }
    if units.is_empty() {
        return Err(CliError::Input("--units: no units".into()));
    }
    Ok(units)
}

fn from_list(value: &str, target: &str) -> CliResult<Vec<Unit>> {
    value
        .split(',')
        .map(|e| {
            let e = e.trim();
            let (serial, column) = e.split_once('=').unwrap_or((e, e));
            let (serial, column) = (serial.trim(), column.trim());
            if serial.is_empty() || column.is_empty() {
                return Err(CliError::Input(format!(
                    "--units: '{}': give COLUMN or SERIAL=COLUMN (or a mapping file that exists)",
                    incal_io::clip(e)
                )));
            }
            Ok(Unit {
                serial: serial.to_string(),
                columns: columns_of(column, target),
                slot: None,
                options: Vec::new(),
            })
        })
        .collect()
}

fn from_file(path: &Path, target: &str) -> CliResult<Vec<Unit>> {
    let t = incal_io::read_table(path, &incal_io::ReadOptions::default())?;
    let serial = t.column("serial")?;
    let columns = t.column("columns")?;
    let (slot, options) = (t.opt_column("slot"), t.opt_column("options"));
    let mut out = Vec::with_capacity(t.row_count());
    for r in 0..t.row_count() {
        let cell = |c: usize| t.text(r, c).trim().to_string();
        let (s, c) = (cell(serial), cell(columns));
        if s.is_empty() || c.is_empty() {
            return Err(t
                .error_at(r, "a unit needs its serial and its columns")
                .into());
        }
        out.push(Unit {
            serial: s,
            columns: columns_of(&c, target),
            slot: slot.map(cell).filter(|x| !x.is_empty()),
            options: options
                .map(|k| cell(k).split_whitespace().map(String::from).collect())
                .unwrap_or_default(),
        });
    }
    Ok(out)
}
