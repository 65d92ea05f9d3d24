//! The runs of a repeatability analysis: from a table (one row per run:
//! `value`, `u`, optional `day` and `dof`) or from result documents of
//! one procedure (the coefficient's value, u and dof; the day from the
//! instrument's `day` entry, `--meta day=…`, or from the record's date
//! in the store).

use std::io::Read;

use super::Run;
use crate::document::ResultDocument;
use crate::error::{Error, Result};

/// Read a table of runs (module docs).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>) -> Result<Vec<Run>> {
    let h = rows.header();
    let (cv, cu) = (h.column("value")?, h.column("u")?);
    let cd = h.opt_column("day");
    let cn = h.opt_column("dof");
    let file = h.file().to_string();
    let mut runs = Vec::new();
    while let Some(row) = rows.next_row()? {
        let u = row.f64(cu)?;
        if u <= 0.0 {
            return Err(row
                .cell_error(cu, format!("u = {u}: a run's u must be positive"))
                .into());
        }
        let dof = match cn {
            Some(c) => {
                let v = row.f64(c)?;
                if v < 1.0 {
                    return Err(row.cell_error(c, format!("dof = {v}: at least 1")).into());
                }
                v
            }
            None => f64::INFINITY,
        };
        let day = match cd {
            Some(c) => {
                let d = row.label(c)?.to_string();
                if d.is_empty() {
                    return Err(row.cell_error(c, "an empty day").into());
                }
                Some(d)
            }
            None => None,
        };
        runs.push(Run {
            source: format!("{file}: line {}", row.line()),
            day,
            value: row.f64(cv)?,
            u,
            dof,
        });
    }
    Ok(runs)
}

/// One result document and where it came from.
#[derive(Debug, Clone)]
pub struct DocumentRun {
    /// The file or record, for messages.
    pub name: String,
    /// The record's date (`YYYY-MM-DD`) when it comes from the store.
    pub date: Option<String>,
    /// The document.
    pub doc: ResultDocument,
}

/// The runs of `coefficient` in documents of one procedure (module
/// docs); also the coefficient's unit. Refused, naming the document: a
/// document of another procedure or without the coefficient.
pub fn runs_from_documents(
    docs: &[DocumentRun],
    coefficient: &str,
) -> Result<(Vec<Run>, Option<String>)> {
    let Some(first) = docs.first() else {
        return Err(Error::Unsupported("no result documents".into()));
    };
    let procedure = first.doc.procedure;
    let mut unit = None;
    let mut runs = Vec::new();
    for d in docs {
        if d.doc.procedure != procedure {
            return Err(Error::Unsupported(format!(
                "{}: a {} document among {} documents: one procedure at a time",
                d.name, d.doc.procedure, procedure
            )));
        }
        let c = d.doc.coefficients.get(coefficient).ok_or_else(|| {
            Error::Unsupported(format!(
                "{}: no coefficient '{}' (it has {})",
                d.name,
                incal_io::clip(coefficient),
                d.doc.coefficients.names().join(", ")
            ))
        })?;
        let this = c.unit.as_str().to_string();
        match &unit {
            None => unit = Some(this),
            Some(u) if *u != this => {
                return Err(Error::Unsupported(format!(
                    "{}: {} is in {this}, the documents before in {u}: one unit at a time",
                    d.name,
                    incal_io::clip(coefficient)
                )))
            }
            Some(_) => {}
        }
        let day = d
            .doc
            .instrument
            .meta
            .get("day")
            .cloned()
            .or_else(|| d.date.clone());
        runs.push(Run {
            source: d.name.clone(),
            day,
            value: c.value,
            u: c.u,
            dof: c.dof_value(),
        });
    }
    Ok((runs, unit))
}

/// The CSV `day,value,u[,dof]` of runs.
pub fn write<W: std::io::Write>(runs: &[Run], out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let with_dof = runs.iter().any(|r| r.dof.is_finite());
    let header: &[&str] = if with_dof {
        &["day", "value", "u", "dof"]
    } else {
        &["day", "value", "u"]
    };
    let mut w = CsvWriter::new(out, header)?;
    for r in runs {
        w.cell(Cell::Text(r.day.as_deref().unwrap_or("")))?;
        w.cell(Cell::Num(r.value))?;
        w.cell(Cell::Num(r.u))?;
        if with_dof {
            w.cell(Cell::Num(r.dof))?;
        }
        w.end_row()?;
    }
    w.finish()
}
