//! Reading records: the list, one record in full, the record of a
//! document, and the history of a coefficient of an instrument across its
//! calibrations (with drift, repeatability and En from [`history`]).

use std::collections::HashMap;

use incal::document::ResultDocument;

use crate::db::{Conn, DbError, Mode, P};
use crate::write::instrument_of;
use crate::{history, sha256_hex, Error, InputHash, Result, Store};
use crate::{History, HistoryPoint, RecordSummary, StoredRecord, Supersession};

/// Calibrations of one coefficient spread over more than this (°C) earn a
/// note in its history: their differences may be temperature, not drift.
pub const TEMPERATURE_SPREAD_C: f64 = 5.0;

impl Store {
    /// The current calibrations of `serial` (records not superseded; of
    /// `procedure` when given, which is needed when the serial has records
    /// of several), each as its record and its result document, oldest
    /// first: what `incal thermal fit --db` fits. Bad input
    /// ([`Error::Input`]) when there are none or several procedures.
    pub fn current_calibrations(
        &self,
        serial: &str,
        procedure: Option<incal::document::Procedure>,
    ) -> Result<Vec<(StoredRecord, ResultDocument)>> {
        let want = procedure.map(|p| p.as_str());
        let records: Vec<_> = self
            .list(Some(serial))?
            .into_iter()
            .filter(|r| r.superseded_by.is_none())
            .filter(|r| want.is_none_or(|p| r.procedure == p))
            .collect();
        let mut procs: Vec<&str> = records.iter().map(|r| r.procedure.as_str()).collect();
        procs.sort_unstable();
        procs.dedup();
        if procs.len() > 1 {
            return Err(Error::Input(format!(
                "serial '{}' has records of {}: give the procedure",
                incal_io::clip(serial),
                procs.join(", ")
            )));
        }
        if records.is_empty() {
            return Err(Error::Input(format!(
                "no calibration of serial '{}'{} that is not superseded",
                incal_io::clip(serial),
                want.map(|p| format!(" by {p}")).unwrap_or_default()
            )));
        }
        records
            .iter()
            .map(|r| {
                let rec = self.show(r.id)?;
                let doc = ResultDocument::from_json(&rec.document)
                    .map_err(|e| Error::Input(format!("record {}: {e}", r.id)))?;
                Ok((rec, doc))
            })
            .collect()
    }

    /// Every instrument: its serial and its model as first recorded, by
    /// serial.
    pub fn instruments(&self) -> Result<Vec<(String, Option<String>)>> {
        let rows = self
            .conn
            .borrow_mut()
            .query("SELECT serial, model FROM instruments ORDER BY serial", &[])
            .map_err(self.db())?;
        rows.iter()
            .map(|r| Ok((r.t(0)?, r.ot(1)?)))
            .collect::<std::result::Result<Vec<_>, DbError>>()
            .map_err(self.db())
    }

    /// Instrument `serial`: `Some(model as first recorded)` when the store
    /// has it, `None` otherwise.
    pub fn instrument(&self, serial: &str) -> Result<Option<Option<String>>> {
        let row = self
            .conn
            .borrow_mut()
            .query_opt(
                "SELECT model FROM instruments WHERE serial = ?1",
                &[P::T(Some(serial))],
            )
            .map_err(self.db())?;
        row.map(|r| r.ot(0)).transpose().map_err(self.db())
    }

    /// Every record (of `serial` only, when given), by id.
    pub fn list(&self, serial: Option<&str>) -> Result<Vec<RecordSummary>> {
        let rows = self
            .conn
            .borrow_mut()
            .query(
                "SELECT r.id, i.serial, r.procedure, r.created_utc, r.document_sha256,
                        r.operator, r.station, s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE CAST(?1 AS TEXT) IS NULL OR i.serial = ?1
                 ORDER BY r.id",
                &[P::T(serial)],
            )
            .map_err(self.db())?;
        rows.iter()
            .map(|r| {
                Ok(RecordSummary {
                    id: r.i(0)?,
                    serial: r.t(1)?,
                    procedure: r.t(2)?,
                    created_utc: r.t(3)?,
                    sha256: r.t(4)?,
                    operator: r.ot(5)?,
                    station: r.ot(6)?,
                    superseded_by: r.oi(7)?,
                })
            })
            .collect::<std::result::Result<Vec<_>, DbError>>()
            .map_err(self.db())
    }

    /// Record `id` in full, its document exactly as stored.
    pub fn show(&self, id: i64) -> Result<StoredRecord> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let row = tx
            .query_opt(
                "SELECT r.id, i.serial, i.model, r.procedure, r.created_utc, r.operator,
                        r.station, r.document, r.document_sha256, r.prev_hash, r.record_hash,
                        s.new_id
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE r.id = ?1",
                &[P::I(id)],
            )
            .map_err(self.db())?;
        let Some(r) = row else {
            return Err(Error::Input(format!("record {id}: no such record")));
        };
        let read = |tx: &mut Conn| -> std::result::Result<StoredRecord, DbError> {
            Ok(StoredRecord {
                id: r.i(0)?,
                serial: r.t(1)?,
                model: r.ot(2)?,
                procedure: r.t(3)?,
                created_utc: r.t(4)?,
                operator: r.ot(5)?,
                station: r.ot(6)?,
                document: r.t(7)?,
                sha256: r.t(8)?,
                prev_hash: r.t(9)?,
                record_hash: r.t(10)?,
                inputs: inputs_between(tx, id, id)?.remove(&id).unwrap_or_default(),
                supersedes: supersessions_between(tx, id, id)?.remove(&id),
                superseded_by: r.oi(11)?,
            })
        };
        let rec = read(&mut tx).map_err(self.db())?;
        tx.commit().map_err(self.db())?;
        Ok(rec)
    }

    /// Coefficient `coefficient` of instrument `serial` across its
    /// calibrations that are not superseded, with drift, repeatability and
    /// En ([`history`]). Records whose result has no such coefficient are
    /// left out; none at all, or a unit that changes between records, is
    /// an error; so are records of more than one procedure (a tumble's K2
    /// is K2 − K_pp, a centrifuge's is K2: [`Store::history_of`] picks one).
    pub fn history(&self, serial: &str, coefficient: &str) -> Result<History> {
        self.history_of(serial, coefficient, None, None)
    }

    /// [`Store::history`] over the records of `procedure` only (a
    /// procedure id, `tumble`), when given.
    pub fn history_of(
        &self,
        serial: &str,
        coefficient: &str,
        procedure: Option<&str>,
        temperature: Option<(f64, f64)>,
    ) -> Result<History> {
        self.history_if_any(serial, coefficient, procedure, temperature)?
            .map_err(Error::Input)
    }

    /// As [`Store::history`], with "nothing to show" (no records of the
    /// instrument, every one superseded, none with the coefficient) as
    /// `Ok(Err(why))` rather than an error: a report plots the histories
    /// there are.
    ///
    /// With `temperature = Some((t, tol))` only the records made within
    /// `tol` °C of `t` count (a coefficient that moves with temperature
    /// drifts only at one temperature); without it, records spread over
    /// more than [`TEMPERATURE_SPREAD_C`] earn a note.
    pub fn history_if_any(
        &self,
        serial: &str,
        coefficient: &str,
        procedure: Option<&str>,
        temperature: Option<(f64, f64)>,
    ) -> Result<std::result::Result<History, String>> {
        let (rows, known) = self.history_rows(serial, procedure)?;
        if rows.is_empty() {
            return Ok(Err(match (known, procedure) {
                (true, Some(p)) => {
                    format!("serial '{serial}': no {p} records (not superseded) of this instrument")
                }
                (true, None) => format!("serial '{serial}': every record is superseded"),
                (false, _) => format!("serial '{serial}': no records of this instrument"),
            }));
        }
        let Gathered {
            points,
            names,
            procedures,
            skipped_by_temperature,
        } = gather(rows, coefficient, temperature)?;
        if points.is_empty() && skipped_by_temperature > 0 {
            let (t, tol) = temperature.unwrap_or_default();
            return Ok(Err(format!(
                "serial '{serial}': no calibration with {coefficient} within {tol} degC of {t} degC ({skipped_by_temperature} at other or unknown temperatures)"
            )));
        }
        if points.is_empty() {
            return Ok(Err(format!(
                "serial '{serial}': no calibration has a coefficient '{coefficient}' (recorded: {})",
                names.join(", ")
            )));
        }
        if procedures.len() > 1 {
            return Err(Error::Input(format!(
                "coefficient {coefficient} of serial '{serial}' comes from {} records: one procedure's {coefficient} is not another's; give the procedure (--procedure {})",
                procedures.join(" and "),
                procedures[0]
            )));
        }
        let mut a = history::analyse(&points);
        let temps: Vec<f64> = points.iter().filter_map(|p| p.temperature_c).collect();
        let (lo, hi) = temps
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                (a.min(*t), b.max(*t))
            });
        if temperature.is_none() && hi - lo > TEMPERATURE_SPREAD_C {
            a.notes.push(format!(
                "the calibrations were made from {lo} to {hi} degC: a coefficient that moves with temperature shows that as drift; give --at-temperature-c to keep one temperature, or fit the thermal model (incal thermal fit)"
            ));
        }
        Ok(Ok(History {
            serial: serial.to_string(),
            coefficient: coefficient.to_string(),
            unit: points[0].unit.clone(),
            points,
            drift: a.drift,
            repeatability: a.repeatability,
            en_latest: a.en_latest,
            notes: a.notes,
        }))
    }

    /// The records of instrument `serial` (of `procedure` only, when
    /// given) that are not superseded, in time order (created_utc, then
    /// id): `(id, created_utc, document, procedure)`; and whether the store
    /// knows the instrument at all. One read transaction.
    fn history_rows(
        &self,
        serial: &str,
        procedure: Option<&str>,
    ) -> Result<(Vec<HistoryRow>, bool)> {
        let mut c = self.conn.borrow_mut();
        let mut tx = c.transaction(Mode::Read).map_err(self.db())?;
        let rows = tx
            .query(
                "SELECT r.id, r.created_utc, r.document, r.procedure
                 FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 LEFT JOIN supersessions s ON s.old_id = r.id
                 WHERE i.serial = ?1 AND s.old_id IS NULL
                   AND (CAST(?2 AS TEXT) IS NULL OR r.procedure = ?2)
                 ORDER BY r.created_utc, r.id",
                &[P::T(Some(serial)), P::T(procedure)],
            )
            .and_then(|rows| {
                rows.iter()
                    .map(|r| Ok((r.i(0)?, r.t(1)?, r.t(2)?, r.t(3)?)))
                    .collect::<std::result::Result<Vec<_>, DbError>>()
            })
            .map_err(self.db())?;
        let known = instrument_of(&mut tx, serial).map_err(self.db())?.is_some();
        tx.commit().map_err(self.db())?;
        Ok((rows, known))
    }

    /// The record of instrument `serial` whose stored document is
    /// `document` byte for byte (its SHA-256), the first if corrected
    /// since: `(id, record_hash)`, or `None`. A certificate of that
    /// document names the record.
    pub fn find(&self, serial: &str, document: &str) -> Result<Option<(i64, String)>> {
        let sha = sha256_hex(document.as_bytes());
        let row = self
            .conn
            .borrow_mut()
            .query_opt(
                "SELECT r.id, r.record_hash FROM records r
                 JOIN instruments i ON i.id = r.instrument_id
                 WHERE i.serial = ?1 AND r.document_sha256 = ?2
                 ORDER BY r.id LIMIT 1",
                &[P::T(Some(serial)), P::T(Some(&sha))],
            )
            .map_err(self.db())?;
        row.map(|r| Ok((r.i(0)?, r.t(1)?)))
            .transpose()
            .map_err(self.db())
    }
}

/// A record a history reads: `(id, created_utc, document, procedure)`.
type HistoryRow = (i64, String, String, String);

/// What the records of a history give: the calibrations with the
/// coefficient, and what was passed over.
struct Gathered {
    /// The coefficient in each record that has it (at the temperature
    /// asked), in the records' order.
    points: Vec<HistoryPoint>,
    /// The coefficients of the records without it.
    names: Vec<String>,
    /// The procedures of the points, in order of first appearance.
    procedures: Vec<String>,
    /// Records with the coefficient left out for their temperature.
    skipped_by_temperature: usize,
}

/// Coefficient `coefficient` in each record of `rows`: with
/// `temperature = Some((t, tol))` only records made within `tol` °C of
/// `t`; a stored document that no longer reads is [`Error::Tampered`], a
/// unit that changes between records [`Error::Input`].
fn gather(
    rows: Vec<HistoryRow>,
    coefficient: &str,
    temperature: Option<(f64, f64)>,
) -> Result<Gathered> {
    let mut points: Vec<HistoryPoint> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    let mut procedures: Vec<String> = Vec::new();
    let mut skipped_by_temperature = 0usize;
    for (id, created_utc, text, proc_id) in rows {
        let doc = ResultDocument::from_json(&text).map_err(|e| Error::Tampered {
            id,
            problem: format!("the stored document no longer reads as a result: {e}"),
        })?;
        let Some(c) = doc.coefficients.get(coefficient) else {
            for n in doc.coefficients.names() {
                if !names.contains(&n) {
                    names.push(n);
                }
            }
            continue;
        };
        let temperature_c = incal::procedures::thermal::soak::temperature_of(&doc).ok();
        if let Some((t, tol)) = temperature {
            if !temperature_c.is_some_and(|x| (x - t).abs() <= tol) {
                skipped_by_temperature += 1;
                continue;
            }
        }
        if !procedures.contains(&proc_id) {
            procedures.push(proc_id);
        }
        if let Some(first) = points.first() {
            if first.unit != c.unit {
                return Err(Error::Input(format!(
                    "coefficient {coefficient} is in '{}' in record {} but in '{}' in record {id}",
                    first.unit, first.id, c.unit
                )));
            }
        }
        points.push(HistoryPoint {
            id,
            created_utc,
            value: c.value,
            u: c.u,
            u95: c.u95,
            dof: c.dof,
            unit: c.unit.clone(),
            temperature_c,
        });
    }
    Ok(Gathered {
        points,
        names,
        procedures,
        skipped_by_temperature,
    })
}

/// The input files of records `lo..=hi`, by record, in order.
pub(crate) fn inputs_between(
    tx: &mut Conn,
    lo: i64,
    hi: i64,
) -> std::result::Result<HashMap<i64, Vec<InputHash>>, DbError> {
    let rows = tx.query(
        "SELECT record_id, role, path, sha256 FROM record_inputs
         WHERE record_id >= ?1 AND record_id <= ?2 ORDER BY record_id, position",
        &[P::I(lo), P::I(hi)],
    )?;
    let mut out: HashMap<i64, Vec<InputHash>> = HashMap::new();
    for r in rows {
        out.entry(r.i(0)?).or_default().push(InputHash {
            role: r.t(1)?,
            path: r.t(2)?,
            sha256: r.t(3)?,
        });
    }
    Ok(out)
}

/// The supersessions made by records `lo..=hi`, by the correcting record.
pub(crate) fn supersessions_between(
    tx: &mut Conn,
    lo: i64,
    hi: i64,
) -> std::result::Result<HashMap<i64, Supersession>, DbError> {
    let rows = tx.query(
        "SELECT old_id, new_id, reason, created_utc FROM supersessions
         WHERE new_id >= ?1 AND new_id <= ?2",
        &[P::I(lo), P::I(hi)],
    )?;
    let mut out = HashMap::new();
    for r in rows {
        let s = Supersession {
            old_id: r.i(0)?,
            new_id: r.i(1)?,
            reason: r.t(2)?,
            created_utc: r.t(3)?,
        };
        out.insert(s.new_id, s);
    }
    Ok(out)
}
