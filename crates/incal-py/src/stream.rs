//! The streaming tools and the comparison for Python: `imu apply` and
//! `thermal apply` ([`incal::procedures::stream::Stream`]) on data in
//! place, and `compare` of two result documents, on the core directly.

use incal::procedures::stream::Stream;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

fn fail(m: String) -> (u8, Vec<u8>, String, String) {
    (2, Vec::new(), m, "[]".into())
}

/// `_stream(tool, model_name, model_text, name, path=None, columns=None,
/// sort_time=False) -> (code, csv: bytes, error, warnings JSON)`: `tool`
/// `imu-apply` (the calibration document `model_text`), `mag-apply` (a
/// magnetometer calibration) or `thermal-apply` (the thermal model) applied to the rows of the file
/// `path` or of `columns` (as `_reduce` takes them), written as CSV. The
/// GIL is released while the rows stream.
#[pyfunction]
#[pyo3(signature = (tool, model_name, model_text, name, path=None, columns=None, sort_time=false))]
#[allow(clippy::too_many_arguments)]
pub fn _stream<'py>(
    py: Python<'py>,
    tool: &str,
    model_name: &str,
    model_text: &str,
    name: &str,
    path: Option<std::path::PathBuf>,
    columns: Option<Vec<(String, Bound<'py, PyAny>)>>,
    sort_time: bool,
) -> PyResult<(u8, Py<PyBytes>, String, String)> {
    let held = crate::columns::hold(columns.unwrap_or_default())?;
    let cols = match crate::columns::borrow(name, &held)? {
        Ok(c) => c,
        Err(m) => return Ok((2, PyBytes::new(py, b"").unbind(), m, "[]".into())),
    };
    let (code, out, err, warnings) = py.detach(|| {
        let (input, read_name, frames): (Box<dyn std::io::Read + Send + '_>, String, bool) =
            match &path {
                Some(p) => match incal_io::open(p) {
                    Ok(o) => (o.reader, o.name, false),
                    Err(e) => return fail(e.to_string()),
                },
                None => (Box::new(cols), name.to_string(), true),
            };
        let doc = match incal::document::ResultDocument::from_json(model_text) {
            Ok(d) => d,
            Err(e) => return fail(format!("{model_name}: {e}")),
        };
        let read = incal_io::ReadOptions {
            frames,
            ..incal_io::ReadOptions::default()
        };
        let mut out = Vec::new();
        let done = match tool {
            "imu-apply" => incal::procedures::imu::apply::ImuCalibration::from_document(&doc)
                .map_err(|e| incal::Error::InFile {
                    file: model_name.to_string(),
                    source: Box::new(e),
                })
                .and_then(|calibration| {
                    let model = incal::procedures::imu::apply::ApplyModel {
                        calibration,
                        sort_time,
                    };
                    let read = incal_io::ReadOptions {
                        hash: false,
                        ..read.clone()
                    };
                    incal::procedures::imu::apply::Apply::stream(
                        model, &read_name, input, &read, &mut out,
                    )
                }),
            "thermal-apply" => incal::procedures::thermal::Model::of(&doc)
                .map_err(|e| incal::Error::InFile {
                    file: model_name.to_string(),
                    source: Box::new(e),
                })
                .and_then(|model| {
                    incal::procedures::thermal::apply::Compensate::stream(
                        model, &read_name, input, &read, &mut out,
                    )
                }),
            "mag-apply" => incal::procedures::mag::apply::MagCalibration::from_document(&doc)
                .map_err(|e| incal::Error::InFile {
                    file: model_name.to_string(),
                    source: Box::new(e),
                })
                .and_then(|cal| {
                    let read = incal_io::ReadOptions {
                        hash: false,
                        ..read.clone()
                    };
                    incal::procedures::mag::apply::Apply::stream(
                        cal, &read_name, input, &read, &mut out,
                    )
                }),
            other => return fail(format!("no streaming tool '{other}'")),
        };
        match done {
            Ok(s) => {
                let w = serde_json::to_string(&s.warnings).unwrap_or_else(|_| "[]".into());
                (0, out, String::new(), w)
            }
            Err(e) => fail(e.to_string()),
        }
    });
    Ok((code, PyBytes::new(py, &out).unbind(), err, warnings))
}

/// `_compare(name_a, text_a, name_b, text_b) -> (code, JSON, error)`:
/// the core's comparison of two result documents (`incal compare
/// --json`).
#[pyfunction]
pub fn _compare(name_a: &str, text_a: &str, name_b: &str, text_b: &str) -> (u8, String, String) {
    use incal::document::ResultDocument;
    let read = |name: &str, text: &str| {
        ResultDocument::from_json(text).map_err(|e| format!("{name}: {e}"))
    };
    let (a, b) = match (read(name_a, text_a), read(name_b, text_b)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => return (2, String::new(), e),
    };
    match incal::document::compare::compare_documents(name_a, &a, name_b, &b) {
        Ok(c) => (
            0,
            format!(
                "{}\n",
                serde_json::to_string_pretty(&c.to_json()).unwrap_or_default()
            ),
            String::new(),
        ),
        Err(e) => (2, String::new(), e.to_string()),
    }
}
