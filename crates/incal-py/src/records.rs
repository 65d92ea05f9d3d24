//! The records store for Python (`incal.Records`), on the records crate
//! directly: the same checks, hash chain, JSON and errors as `incal
//! record`, without the command line.

use incal_records::{NewRecord, Store};
use pyo3::prelude::*;
use serde_json::{json, Value};

/// What a call asks ([`_records`]).
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct Args {
    id: Option<i64>,
    name: Option<String>,
    text: Option<String>,
    serial: Option<String>,
    operator: Option<String>,
    station: Option<String>,
    created_utc: Option<String>,
    reason: Option<String>,
    coefficient: Option<String>,
    procedure: Option<String>,
    head: Option<String>,
    path: Option<String>,
}

/// An error of a call: exit code 2 (bad input) or 1, and the one line.
type Failed = (u8, String);

fn input(m: impl Into<String>) -> Failed {
    (2, m.into())
}

fn store_error(location: &str) -> impl Fn(incal_records::Error) -> Failed + '_ {
    move |e| {
        let name = incal_records::store_name(std::path::Path::new(location));
        let code = if e.is_input() { 2 } else { 1 };
        (code, incal_records::store_message(&name, &e))
    }
}

/// A procedure named by its id (`_` for `-` accepted).
fn procedure(p: &str) -> Result<incal::document::Procedure, Failed> {
    incal::document::Procedure::from_id(&p.replace('_', "-")).ok_or_else(|| {
        input(format!(
            "procedure: '{}' is not a procedure",
            incal_io::clip(p)
        ))
    })
}

fn pretty(v: &Value) -> String {
    format!(
        "{}\n",
        serde_json::to_string_pretty(v).unwrap_or_else(|_| v.to_string())
    )
}

/// The request to store `a.text`, its identity checked against the
/// document (a record needs a serial, given or in the document).
fn new_record<'a>(a: &'a Args, need_serial: bool) -> Result<NewRecord<'a>, Failed> {
    let name = a.name.as_deref().unwrap_or("<Result>");
    let text = a.text.as_deref().ok_or_else(|| input("no result given"))?;
    if text.trim().is_empty() {
        return Err(input(format!("{name}: empty file")));
    }
    let doc = incal::document::ResultDocument::from_json(text)
        .map_err(|e| input(format!("{name}: {e}")))?;
    let req = NewRecord {
        document: text,
        serial: a.serial.as_deref(),
        operator: a.operator.as_deref(),
        station: a.station.as_deref(),
        created_utc: a.created_utc.as_deref(),
    };
    incal_records::check_identity(name, &doc, &req).map_err(|e| match e {
        incal_records::IdentityError::Option { key, rest } => input(format!("{key}{rest}")),
        incal_records::IdentityError::Document(m) => input(m),
    })?;
    if need_serial && doc.instrument.serial.is_none() && a.serial.is_none() {
        return Err(input(format!(
            "{name}: the result has no instrument.serial: give serial="
        )));
    }
    Ok(req)
}

fn run(location: &str, op: &str, a: &Args) -> Result<String, Failed> {
    let err = store_error(location);
    let existing = || Store::open_existing(location).map_err(&err);
    match op {
        "add" => {
            let req = new_record(a, true)?;
            let mut store = Store::open(location).map_err(&err)?;
            let added = store.add(&req).map_err(&err)?;
            Ok(pretty(
                &json!({"id": added.id, "sha256": added.sha256, "existing": added.existing}),
            ))
        }
        "supersede" => {
            let reason = a.reason.as_deref().unwrap_or("");
            if reason.trim().is_empty() {
                return Err(input("reason: empty"));
            }
            let req = new_record(a, false)?;
            let id = a.id.ok_or_else(|| input("no record id given"))?;
            let mut store = Store::open_to_write(location).map_err(&err)?;
            let added = store.supersede(id, &req, reason).map_err(&err)?;
            Ok(pretty(
                &json!({"id": added.id, "sha256": added.sha256, "existing": added.existing}),
            ))
        }
        "list" => {
            let store = existing()?;
            let chain = store.check_chain().map_err(&err)?;
            let records = store.list(a.serial.as_deref()).map_err(&err)?;
            Ok(pretty(&incal_report::records::list_json(&records, &chain)))
        }
        "show" => {
            let store = existing()?;
            store.check_chain().map_err(&err)?;
            let id = a.id.ok_or_else(|| input("no record id given"))?;
            let r = store.show(id).map_err(&err)?;
            incal_report::records::show_json(&r)
                .map_err(|why| (1, format!("record {}: {why} (run Records.verify())", r.id)))
        }
        "history" => {
            let store = existing()?;
            store.check_chain().map_err(&err)?;
            let serial = a.serial.as_deref().ok_or_else(|| input("serial: needed"))?;
            let coefficient = a
                .coefficient
                .as_deref()
                .ok_or_else(|| input("coefficient: needed"))?;
            let procedure = match &a.procedure {
                Some(p) => Some(procedure(p)?.as_str()),
                None => None,
            };
            let h = store
                .history_of(serial, coefficient, procedure, None)
                .map_err(&err)?;
            Ok(pretty(&incal_report::records::history_json(&h)))
        }
        "calibrations" => {
            let serial = a.serial.as_deref().ok_or_else(|| input("serial: needed"))?;
            let procedure = match &a.procedure {
                Some(p) => Some(procedure(p)?),
                None => None,
            };
            let store = existing()?;
            store.check_chain().map_err(&err)?;
            let found = store
                .current_calibrations(serial, procedure)
                .map_err(&err)?;
            let docs: Vec<Value> = found
                .iter()
                .map(|(r, _)| {
                    json!({"name": format!("record {}", r.id), "sha256": r.sha256, "text": r.document})
                })
                .collect();
            Ok(pretty(&Value::Array(docs)))
        }
        "verify" => {
            let store = existing()?;
            let v = match &a.head {
                Some(h) => {
                    if h.len() != 64 || !h.bytes().all(|b| b.is_ascii_hexdigit()) {
                        return Err(input(format!(
                            "head: '{}' is not a record hash (64 hexadecimal digits)",
                            incal_io::clip(h)
                        )));
                    }
                    store.verify_head(&h.to_ascii_lowercase())
                }
                None => store.verify(),
            }
            .map_err(&err)?;
            Ok(pretty(&json!({"records": v.records, "head": v.head})))
        }
        "export" => {
            let store = existing()?;
            store.check_chain().map_err(&err)?;
            let path = a.path.as_deref().ok_or_else(|| input("no path given"))?;
            export(&store, path).map(|c| pretty(&json!({"records": c.records, "head": c.head})))
        }
        "import" => {
            let path = a.path.as_deref().ok_or_else(|| input("no path given"))?;
            let opened =
                incal_io::open(std::path::Path::new(path)).map_err(|e| input(e.to_string()))?;
            let reader = std::io::BufReader::with_capacity(1 << 16, opened.reader);
            let at = std::path::Path::new(location);
            let done = Store::import_at(at, reader, &opened.name).map_err(&err)?;
            Ok(pretty(&json!({
                "added": done.added,
                "present": done.present,
                "chain": {"records": done.chain.records, "head": done.chain.head},
            })))
        }
        other => Err(input(format!("no records operation '{other}'"))),
    }
}

/// Export the store to `path` through a file beside it, renamed into
/// place once complete (a failed export leaves no half file).
fn export(store: &Store, path: &str) -> Result<incal_records::Verified, Failed> {
    let target = std::path::Path::new(path);
    let tmp = target.with_extension("incal-partial");
    let failed = |e: String| (1, format!("{path}: cannot write: {e}"));
    let done = (|| {
        let f = std::fs::File::create(&tmp).map_err(|e| e.to_string())?;
        let mut w = std::io::BufWriter::new(f);
        let chain = store.export(&mut w).map_err(|e| e.to_string())?;
        std::io::Write::flush(&mut w).map_err(|e| e.to_string())?;
        std::fs::rename(&tmp, target).map_err(|e| e.to_string())?;
        Ok(chain)
    })();
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done.map_err(failed)
}

/// `_records(location, op, args) -> (code, JSON text, error)`: one
/// operation on the store at `location` (a path or a `postgresql://`
/// URL): `add`, `supersede`, `list`, `show`, `history`, `verify`,
/// `export`, `import`, `calibrations` (the current calibrations of
/// `serial`: `[{name, sha256, text}]`), with `args` as JSON (`text` and `name` of a result,
/// `serial`, `operator`, `station`, `created_utc`, `id`, `reason`,
/// `coefficient`, `procedure`, `head`, `path`). The GIL is released.
#[pyfunction]
pub fn _records(py: Python<'_>, location: &str, op: &str, args: &str) -> (u8, String, String) {
    py.detach(|| {
        let a: Args = match serde_json::from_str(args) {
            Ok(a) => a,
            Err(e) => return (2, String::new(), format!("records {op}: {e}")),
        };
        match run(location, op, &a) {
            Ok(out) => (0, out, String::new()),
            Err((code, m)) => (code, String::new(), m),
        }
    })
}
