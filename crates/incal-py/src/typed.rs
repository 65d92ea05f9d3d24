//! The typed entry points: a procedure's reduction called on the core's
//! registry ([`incal::procedures::registry`]) with its options as JSON
//! (the procedure's own keys, validated by its `validate`), and the data
//! as a path or as columns in memory ([`incal_io::frames`]): numpy
//! float64 arrays are read in place, without a text round trip.

use incal::procedures::{registry, Silent};
use incal_io::frames::Columns;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

/// What a call did: the exit code the CLI would give (0 ok, 2 bad input
/// or options, 1 anything else), the document's JSON text, the error
/// message, and where the error is (JSON: `option`, `file`, `line`,
/// `column`; `{}` when it names none).
pub struct Outcome {
    code: u8,
    out: Vec<u8>,
    err: Vec<String>,
    place: String,
}

impl Outcome {
    fn failed(code: u8, message: String, place: serde_json::Value) -> Self {
        Outcome {
            code,
            out: Vec::new(),
            err: vec![message],
            place: place.to_string(),
        }
    }

    /// A call that gave `out`.
    fn ok(out: Vec<u8>) -> Self {
        Outcome {
            code: 0,
            out,
            err: Vec::new(),
            place: "{}".into(),
        }
    }

    /// The tuple the Python side reads: `(code, bytes, errors, place)`.
    fn into_py(self, py: Python<'_>) -> (u8, Py<PyBytes>, Vec<String>, String) {
        (
            self.code,
            PyBytes::new(py, &self.out).unbind(),
            self.err,
            self.place,
        )
    }
}

/// Options as JSON text, parsed (`options: …` when it is not JSON).
fn json_value(options: &str) -> incal::Result<serde_json::Value> {
    serde_json::from_str(options).map_err(|e| incal::Error::Unsupported(format!("options: {e}")))
}

/// Options of type `T` from JSON text, checked as the core reads them; an
/// error names the key.
fn typed_options<T: serde::de::DeserializeOwned + schemars::JsonSchema>(
    options: &str,
) -> Result<T, Outcome> {
    json_value(options)
        .and_then(|v| incal::options::from_json(&v))
        .map_err(|e| Outcome::failed(2, e.to_string(), place(&e)))
}

/// The identity, unit and limits to apply, from JSON text.
fn finish_of(finish: &str) -> Result<incal::document::finish::Finish, Outcome> {
    match finish_mc(finish)? {
        (f, None) => Ok(f),
        (_, Some(_)) => Err(Outcome::failed(
            2,
            "monte_carlo: this function reduces no recording it can draw again".into(),
            serde_json::json!({ "option": "monte_carlo" }),
        )),
    }
}

/// The `finish` JSON with the Monte Carlo keywords (`monte_carlo`, `seed`,
/// `mc_digits`) taken out as [`incal::montecarlo::MonteCarloOptions`].
fn finish_mc(
    finish: &str,
) -> Result<
    (
        incal::document::finish::Finish,
        Option<incal::montecarlo::MonteCarloOptions>,
    ),
    Outcome,
> {
    let bad = |key: &str, m: String| {
        Outcome::failed(
            2,
            format!("{key}: {m}"),
            serde_json::json!({ "option": key }),
        )
    };
    let mut v: serde_json::Value =
        serde_json::from_str(finish).map_err(|e| bad("identity and limits", e.to_string()))?;
    let mut mc = serde_json::Map::new();
    if let Some(m) = v.as_object_mut() {
        for (key, to) in [
            ("monte_carlo", "trials"),
            ("seed", "seed"),
            ("mc_digits", "digits"),
        ] {
            if let Some(x) = m.remove(key) {
                mc.insert(to.into(), x);
            }
        }
    }
    let mc = if mc.is_empty() {
        None
    } else if !mc.contains_key("trials") {
        return Err(bad("seed", "give it with monte_carlo".into()));
    } else {
        let o: incal::montecarlo::MonteCarloOptions =
            serde_json::from_value(serde_json::Value::Object(mc))
                .map_err(|e| bad("monte_carlo", e.to_string()))?;
        Some(o)
    };
    let f = serde_json::from_value(v).map_err(|e| bad("identity and limits", e.to_string()))?;
    Ok((f, mc))
}

/// Where a core error is: the option it names, or the file, line and
/// column of the input.
fn place(e: &incal::Error) -> serde_json::Value {
    match e {
        incal::Error::InvalidOption { key, .. } => serde_json::json!({ "option": key }),
        incal::Error::InFile { file, source } => {
            let mut p = place(source);
            if p.get("file").is_none() {
                p["file"] = serde_json::json!(file);
            }
            p
        }
        incal::Error::Input(i) => {
            serde_json::json!({ "file": i.file, "line": i.line, "column": i.column })
        }
        _ => serde_json::json!({}),
    }
}

/// Progress reported to a Python callable, `callback(stage, done, total)`,
/// from whichever thread the core reports on (the GIL taken for the call,
/// at most about 100 calls per stage). The first exception the callable
/// raises is kept and raised when the reduction returns; later reports
/// are dropped.
pub struct PyProgress {
    callback: Py<PyAny>,
    state: std::sync::Mutex<(String, u64, u64, u64)>,
    error: std::sync::Mutex<Option<PyErr>>,
}

impl PyProgress {
    fn new(callback: Py<PyAny>) -> Self {
        PyProgress {
            callback,
            state: std::sync::Mutex::new((String::new(), 0, 0, 0)),
            error: std::sync::Mutex::new(None),
        }
    }

    fn report(&self, stage: &str, done: u64, total: u64) {
        let Ok(mut error) = self.error.lock() else {
            return;
        };
        if error.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = self.callback.call1(py, (stage, done, total)) {
                *error = Some(e);
            }
        });
    }

    /// The callable's exception, if it raised one.
    fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }
}

impl incal::procedures::Progress for PyProgress {
    fn start(&self, what: &str, len: u64) {
        if let Ok(mut s) = self.state.lock() {
            *s = (what.to_string(), len, 0, 0);
        }
        self.report(what, 0, len);
    }
    fn advance(&self, n: u64) {
        let due = self.state.lock().ok().and_then(|mut s| {
            s.2 = s.2.saturating_add(n);
            let step = (s.1 / 100).max(1);
            (s.2 >= s.3 + step).then(|| {
                s.3 = s.2;
                (s.0.clone(), s.2, s.1)
            })
        });
        if let Some((what, done, len)) = due {
            self.report(&what, done, len);
        }
    }
    fn finish(&self) {
        let s = self.state.lock().ok().map(|s| (s.0.clone(), s.1));
        if let Some((what, len)) = s {
            self.report(&what, len, len);
        }
    }
}

/// The read options a Python call gives: `columns` (`NAME=HEADER,…`),
/// `delimiter`, `header_line` and the segmentation (`segment_by`,
/// `segment_tolerance`, `segment_settle_s`, `segment_min_s`,
/// `segment_values`), `full_scale`, and a robot log's `topic` (comma
/// separated) and `stamps`.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct ReadSpec {
    columns: Option<String>,
    delimiter: Option<String>,
    header_line: Option<String>,
    segment_by: Option<String>,
    segment_tolerance: Option<String>,
    segment_settle_s: Option<String>,
    segment_min_s: Option<String>,
    segment_values: Option<String>,
    full_scale: Option<String>,
    topic: Option<String>,
    stamps: Option<String>,
}

/// A number of a read option (`key`), or the option named.
fn read_number(key: &str, text: &str) -> Result<f64, String> {
    incal_io::parse_f64(text.trim().as_bytes())
        .ok_or_else(|| format!("{key}: '{}' is not a number", incal_io::clip(text)))
}

fn read_options(spec: &str) -> Result<incal_io::ReadOptions, Outcome> {
    let bad = |key: &str, m: String| {
        Outcome::failed(
            2,
            format!("{key}: {m}"),
            serde_json::json!({ "option": key }),
        )
    };
    let spec: ReadSpec = serde_json::from_str(spec).map_err(|e| bad("read", e.to_string()))?;
    let mut read = incal_io::ReadOptions::default();
    if let Some(c) = &spec.columns {
        read.columns = incal_io::ColumnMap::parse(c).map_err(|m| bad("columns", m))?;
    }
    if let Some(d) = &spec.delimiter {
        read.delimiter = Some(incal_io::parse_delimiter(d).map_err(|m| bad("delimiter", m))?);
    }
    if let Some(n) = &spec.header_line {
        let line = n
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| {
                bad(
                    "header_line",
                    format!("'{}' is not a line number (1, 2, ...)", incal_io::clip(n)),
                )
            })?;
        read.header_line = Some(line);
    }
    let number = |key: &str, v: &Option<String>| -> Result<Option<f64>, Outcome> {
        v.as_deref()
            .map(|t| read_number(key, t))
            .transpose()
            .map_err(|m| bad(key, m))
    };
    let values: Vec<f64> = match &spec.segment_values {
        None => Vec::new(),
        Some(t) => t
            .split(',')
            .filter(|c| !c.trim().is_empty())
            .map(|c| read_number("segment_values", c))
            .collect::<Result<_, _>>()
            .map_err(|m| bad("segment_values", m))?,
    };
    read.segment = incal_io::SegmentSpec::from_options(
        spec.segment_by.as_deref(),
        number("segment_tolerance", &spec.segment_tolerance)?,
        number("segment_settle_s", &spec.segment_settle_s)?,
        number("segment_min_s", &spec.segment_min_s)?,
        &values,
    )
    .map_err(|m| bad("segment_by", m))?;
    read.full_scale = number("full_scale", &spec.full_scale)?;
    if let Some(x) = read.full_scale {
        if !(x.is_finite() && x > 0.0) {
            return Err(bad(
                "full_scale",
                format!("{x} is not a positive full scale"),
            ));
        }
    }
    if let Some(t) = &spec.topic {
        read.log.topics = t
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect();
    }
    if let Some(s) = &spec.stamps {
        read.log.stamps = incal_io::logs::Stamps::parse(s).map_err(|m| bad("stamps", m))?;
    }
    Ok(read)
}

/// The data of a call: a path, or columns in memory.
enum Data<'a> {
    Path(std::path::PathBuf),
    Columns(Columns<'a>),
}

/// Reduce `data` by `procedure` with `options`, then add what `finish`
/// says (identity, output unit, limits). Runs without the GIL.
fn reduce(
    procedure: &str,
    name: &str,
    data: Data<'_>,
    options: &str,
    read: &str,
    finish: &str,
    progress: &dyn incal::procedures::Progress,
) -> Outcome {
    let Some(red) = registry::find(procedure).and_then(|e| e.reduction) else {
        return Outcome::failed(
            2,
            format!("no procedure '{procedure}' reduces a recording"),
            serde_json::json!({}),
        );
    };
    let options = match json_value(options) {
        Ok(v) => v,
        Err(e) => return Outcome::failed(2, e.to_string(), place(&e)),
    };
    let mut read = match read_options(read) {
        Ok(r) => r,
        Err(o) => return o,
    };
    let (finish, mc) = match finish_mc(finish) {
        Ok(f) => f,
        Err(o) => return o,
    };
    let mc = mc.as_ref();
    let reduced = match data {
        Data::Path(p) => match incal_io::open(&p) {
            Ok(mut src) => (red.run)(&src.name, &mut src.reader, &read, &options, progress, mc),
            Err(e) => Err(incal::Error::Input(e)),
        },
        Data::Columns(c) => {
            // The canonical form hashed on a thread of its own while the
            // procedure reads it (the same hash the reader would record).
            read.frames = true;
            read.hash = false;
            std::thread::scope(|s| {
                let hash = s.spawn(|| c.sha256());
                let mut view = c.view();
                let mut doc = (red.run)(name, &mut view, &read, &options, progress, mc)?;
                let sha256 = hash.join().map_err(|_| {
                    incal::Error::Unsupported(format!("{name}: input hash: its thread failed"))
                })?;
                if let Some(input) = doc.inputs.iter_mut().find(|i| i.role == "input") {
                    input.sha256 = sha256;
                }
                Ok(doc)
            })
        }
    };
    finished(reduced, &finish)
}

/// The document of a reduction with `finish` applied, as an outcome
/// (`fail_on` stops with code 3 and the document kept).
fn finished(
    reduced: incal::Result<incal::document::ResultDocument>,
    finish: &incal::document::finish::Finish,
) -> Outcome {
    let doc = reduced.and_then(|mut doc| finish.apply(&mut doc).map(|()| doc));
    match doc {
        Ok(doc) => {
            // fail_on stops after the result is made: it is handed back
            // with the error.
            let stop = finish.stop(&doc);
            Outcome {
                code: if stop.is_some() { 3 } else { 0 },
                out: format!("{}\n", doc.to_json()).into_bytes(),
                err: stop
                    .map(|m| {
                        format!(
                            "{m}: stopped by fail_on='{}'",
                            finish.fail_on.map_or("", |f| f.as_str())
                        )
                    })
                    .into_iter()
                    .collect(),
                place: "{}".into(),
            }
        }
        Err(e) => Outcome::failed(2, e.to_string(), place(&e)),
    }
}

/// `_reduce(procedure, name, options, read, finish, path=None,
/// columns=None) -> (code, document: bytes, errors: list[str], place:
/// str)`: the registry's reduction of `procedure` (its id) on the file
/// `path`, or on `columns` (a list of `(name, column)`, each a 1-D
/// C-contiguous float64 numpy array, read in place, or a list of str)
/// named `name` in the document and in messages. `options`, `read`
/// (`columns`, `delimiter`) and `finish` (`serial`, `model`, `meta`,
/// `output_unit`, `limits`) are JSON objects. The GIL is released while
/// the core reads and reduces.
#[pyfunction]
#[pyo3(signature = (procedure, name, options, read, finish, path=None, columns=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn _reduce<'py>(
    py: Python<'py>,
    procedure: &str,
    name: &str,
    options: &str,
    read: &str,
    finish: &str,
    path: Option<std::path::PathBuf>,
    columns: Option<Vec<(String, Bound<'py, PyAny>)>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(u8, Py<PyBytes>, Vec<String>, String)> {
    let held = crate::columns::hold(columns.unwrap_or_default())?;
    let data = match path {
        Some(p) => Data::Path(p),
        None => match crate::columns::borrow(name, &held)? {
            Ok(c) => Data::Columns(c),
            Err(m) => return Ok((2, PyBytes::new(py, b"").unbind(), vec![m], "{}".into())),
        },
    };
    let progress = progress.map(PyProgress::new);
    let out = py.detach(|| match &progress {
        Some(p) => reduce(procedure, name, data, options, read, finish, p),
        None => reduce(procedure, name, data, options, read, finish, &Silent),
    });
    if let Some(e) = progress.as_ref().and_then(PyProgress::take_error) {
        return Err(e);
    }
    Ok(out.into_py(py))
}

/// `_reduce_record(name, options, read, finish, record, channels, f64le)
/// -> (code, document, errors, place)`: the noise analysis of a binary
/// record held by Python (`record`: the bytes of a C-contiguous float64 or
/// float32 array, as a 1-D uint8 numpy view, `channels` interleaved),
/// read in place ([`incal_io::binary::MappedRecord::from_memory`]) while
/// the GIL is released. `read` selects and renames channels (`columns`).
/// With `path` instead of `record`, the binary file at `path` is read
/// through its memory map (`incal noise --format f64le|f32le`).
#[pyfunction]
#[pyo3(signature = (options, read, finish, channels, f64le, record=None, path=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn _reduce_record<'py>(
    py: Python<'py>,
    options: &str,
    read: &str,
    finish: &str,
    channels: usize,
    f64le: bool,
    record: Option<PyReadonlyArray1<'py, u8>>,
    path: Option<std::path::PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(u8, Py<PyBytes>, Vec<String>, String)> {
    let progress = progress.map(PyProgress::new);
    let bytes = match &record {
        Some(r) => Some(
            r.as_slice()
                .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?,
        ),
        None => None,
    };
    let out = py.detach(|| {
        let sample = if f64le {
            incal_io::binary::Sample::F64le
        } else {
            incal_io::binary::Sample::F32le
        };
        let rec = match (bytes, &path) {
            (Some(b), _) => incal_io::binary::MappedRecord::from_memory(b, channels, sample),
            (None, Some(p)) => incal_io::binary::MappedRecord::open(p, channels, sample),
            (None, None) => Err(incal_io::InputError::file("<memory>", "no record given")),
        };
        match &progress {
            Some(p) => noise_record(options, read, finish, rec, p),
            None => noise_record(options, read, finish, rec, &Silent),
        }
    });
    if let Some(e) = progress.as_ref().and_then(PyProgress::take_error) {
        return Err(e);
    }
    Ok(out.into_py(py))
}

fn noise_record(
    options: &str,
    read: &str,
    finish: &str,
    rec: incal_io::Result<incal_io::binary::MappedRecord<'_>>,
    progress: &dyn incal::procedures::Progress,
) -> Outcome {
    use incal::procedures::noise::{reduce_mapped, NoiseOptions};
    let options: NoiseOptions = match typed_options(options) {
        Ok(o) => o,
        Err(o) => return o,
    };
    let read = match read_options(read) {
        Ok(r) => r,
        Err(o) => return o,
    };
    let finish = match finish_of(finish) {
        Ok(f) => f,
        Err(o) => return o,
    };
    let doc = rec
        .map_err(incal::Error::Input)
        .and_then(|rec| reduce_mapped(&rec, &read.columns, &options, progress));
    finished(doc, &finish)
}

/// `_plan(procedure, options) -> (code, plan document: bytes, errors,
/// place)`: the registry's typed plan of `procedure` (its id) with
/// `options` as JSON.
#[pyfunction]
pub fn _plan(
    py: Python<'_>,
    procedure: &str,
    options: &str,
) -> (u8, Py<PyBytes>, Vec<String>, String) {
    let out = py.detach(|| {
        let Some(plan) = registry::find(procedure).and_then(|e| e.planner) else {
            return Outcome::failed(
                2,
                format!("no plan for '{procedure}'"),
                serde_json::json!({}),
            );
        };
        let doc = json_value(options).and_then(|v| (plan.run)(&v));
        match doc.and_then(|d| {
            serde_json::to_string(&d).map_err(|e| incal::Error::Unsupported(e.to_string()))
        }) {
            Ok(text) => Outcome::ok(text.into_bytes()),
            Err(e) => Outcome::failed(2, e.to_string(), place(&e)),
        }
    });
    out.into_py(py)
}

/// `_run_sheet(text) -> (code, csv, error)`: the operator's run sheet of
/// the plan document `text` as CSV
/// ([`incal::document::plan::PlanDocument::run_sheet_csv`]).
#[pyfunction]
pub fn _run_sheet(text: &str) -> (u8, String, String) {
    let plan: incal::document::plan::PlanDocument = match serde_json::from_str(text) {
        Ok(p) => p,
        Err(e) => return (2, String::new(), format!("<plan>: {e}")),
    };
    match plan.run_sheet_csv() {
        Ok(csv) => (0, csv, String::new()),
        Err(e @ incal::Error::InvalidOption { .. }) => (2, String::new(), e.to_string()),
        Err(e) => (1, String::new(), e.to_string()),
    }
}

/// `_simulate(procedure, options) -> (code, recording: bytes, errors,
/// place, truth)`: the registry's typed simulator of `procedure` (its id)
/// with `options` as JSON: the CSV it writes, and its truth as JSON text
/// (`null` where the CSV's comment lines carry it).
#[pyfunction]
pub fn _simulate(
    py: Python<'_>,
    procedure: &str,
    options: &str,
) -> (u8, Py<PyBytes>, Vec<String>, String, String) {
    let (out, truth) = py.detach(|| {
        let Some(sim) = registry::find(procedure).and_then(|e| e.simulator) else {
            let no = format!("no simulator for '{procedure}'");
            return (Outcome::failed(2, no, serde_json::json!({})), None);
        };
        let mut csv = Vec::new();
        match json_value(options).and_then(|v| (sim.run)(&v, &mut csv)) {
            Ok(truth) => (Outcome::ok(csv), truth),
            Err(e) => (Outcome::failed(2, e.to_string(), place(&e)), None),
        }
    });
    let (code, csv, err, place) = out.into_py(py);
    let truth = truth.unwrap_or(serde_json::Value::Null).to_string();
    (code, csv, err, place, truth)
}

/// `_check_result(text) -> None | str`: `None` when `text` is a valid
/// result document (the schema and what it cannot say:
/// [`incal::document::ResultDocument::from_json`]), else the problem,
/// naming the JSON path.
#[pyfunction]
pub fn _check_result(text: &str) -> Option<String> {
    incal::document::ResultDocument::from_json(text).err()
}

/// `_figures(text) -> list[str]`: the certificate's plots of the result
/// document `text` as SVG ([`incal_report::figures_svg`]).
#[pyfunction]
pub fn _figures(text: &str) -> PyResult<Vec<String>> {
    let doc = incal::document::ResultDocument::from_json(text)
        .map_err(pyo3::exceptions::PyValueError::new_err)?;
    incal_report::figures_svg(&doc)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
}

/// `_thermal_fit(documents, options, finish) -> (code, document, errors,
/// place)`: `incal thermal fit` of result documents given as `(name,
/// sha256, text)` ([`incal::procedures::thermal::soak::fit_documents`]),
/// options `t_ref_c` and `degree` as JSON, then `finish`.
#[pyfunction]
pub fn _thermal_fit(
    py: Python<'_>,
    documents: Vec<(String, String, String)>,
    options: &str,
    finish: &str,
) -> (u8, Py<PyBytes>, Vec<String>, String) {
    use incal::procedures::thermal::soak;
    let out = py.detach(|| {
        let o: soak::SoakOptions = match typed_options(options) {
            Ok(o) => o,
            Err(o) => return o,
        };
        let finish = match finish_of(finish) {
            Ok(f) => f,
            Err(o) => return o,
        };
        let mut inputs = Vec::with_capacity(documents.len());
        for (name, sha256, text) in documents {
            match incal::document::ResultDocument::from_json(&text) {
                Ok(doc) => inputs.push(soak::SoakInput { name, sha256, doc }),
                Err(e) => {
                    return Outcome::failed(
                        2,
                        format!("{name}: {e}"),
                        serde_json::json!({ "file": name }),
                    )
                }
            }
        }
        finished(soak::fit_documents(&inputs, &o), &finish)
    });
    out.into_py(py)
}

/// `_report(text, finish, db=None, lab=None, issue="{}") -> (code, html,
/// error)`: the HTML report of the result document `text`
/// ([`incal_report::render_html_with`], dated now), the limits of `finish`
/// applied first (`incal report --limits`); with `db` (a store's path or
/// URL) the record stamp and history plots
/// ([`incal_report::stored::of_document`]); with `lab` (a laboratory
/// profile's TOML text) a calibration certificate, `issue` its `customer`,
/// `date` and `environment`.
#[pyfunction]
#[pyo3(signature = (text, finish, db=None, lab=None, issue="{}"))]
pub fn _report(
    py: Python<'_>,
    text: &str,
    finish: &str,
    db: Option<&str>,
    lab: Option<&str>,
    issue: &str,
) -> (u8, String, String) {
    py.detach(|| match report(text, finish, db, lab, issue) {
        Ok(html) => (0, html, String::new()),
        Err((code, m)) => (code, String::new(), m),
    })
}

/// `_pdf(html) -> (code, pdf path, error)`: the HTML report at `html`
/// printed to PDF beside it by headless Chromium
/// ([`incal_report::pdf::print`]); a failure is code 1.
#[pyfunction]
pub fn _pdf(py: Python<'_>, html: std::path::PathBuf) -> (u8, String, String) {
    py.detach(|| match incal_report::pdf::print(&html) {
        Ok(pdf) => (0, pdf.display().to_string(), String::new()),
        Err(e) => (1, String::new(), format!("pdf: {e}")),
    })
}

/// [`_report`]'s work: an error as its exit code and one line.
fn report(
    text: &str,
    finish: &str,
    db: Option<&str>,
    lab: Option<&str>,
    issue: &str,
) -> Result<String, (u8, String)> {
    use incal_report::stored;
    let input = |m: String| (2u8, m);
    let finish: incal::document::finish::Finish =
        serde_json::from_str(finish).map_err(|e| input(format!("limits: {e}")))?;
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct IssueArgs {
        customer: Option<String>,
        date: Option<String>,
        environment: Option<String>,
    }
    let i: IssueArgs = serde_json::from_str(issue).map_err(|e| input(format!("report: {e}")))?;
    if let Some(d) = &i.date {
        if !incal_report::certificate::is_date(d) {
            let clipped = incal_io::clip(d);
            return Err(input(format!("date: '{clipped}' is not a date YYYY-MM-DD")));
        }
    }
    let mut doc = incal::document::ResultDocument::from_json(text)
        .map_err(|e| input(format!("<Result>: {e}")))?;
    finish.apply(&mut doc).map_err(|e| input(e.to_string()))?;
    let profile = match lab {
        Some(t) => Some(
            incal_report::certificate::LabProfile::parse(t)
                .map_err(|e| input(format!("lab: {e}")))?,
        ),
        None => None,
    };
    let store = match (db, doc.instrument.serial.is_some()) {
        (Some(location), true) => {
            let name = incal_records::store_name(std::path::Path::new(location));
            Some(incal_records::Store::open_existing(location).map_err(|e| {
                let code = if e.is_input() { 2 } else { 1 };
                (code, incal_records::store_message(&name, &e))
            })?)
        }
        _ => None,
    };
    let issue = stored::Issue {
        customer: i.customer,
        date: i.date,
        environment: i.environment,
    };
    stored::report_html(&doc, text, store.as_ref(), profile, &issue).map_err(|e| match e {
        stored::StoredError::Input(m) => (2, m),
        stored::StoredError::Failure(m) => (1, m),
    })
}

/// `_schema() -> str`: the JSON Schema of the result document
/// (`incal.result/1`, [`incal::document::json_schema`]), as `incal schema`
/// writes it.
#[pyfunction]
pub fn _schema() -> String {
    incal::document::json_schema().to_string()
}
