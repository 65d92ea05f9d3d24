//! The compiled part of the Python package `incal`: the registry's typed
//! reductions on data in place (`typed`: `_reduce`, `_reduce_record`),
//! and `_run`, which runs an incal command line in process
//! ([`incal_cli::embed`]) for what is not typed yet. The GIL is released
//! while the core works. Everything else of the package is Python in
//! `python/incal/`.

use pyo3::prelude::*;
use pyo3::types::PyBytes;

mod columns;
mod export;
mod records;
mod stream;
mod typed;

/// `_run(args, stdin=None) -> (code, stdout: bytes, stderr: list[str])`:
/// the command line `args` (without the program name) as the `incal`
/// binary runs it, `stdin` (bytes) as its standard input.
#[pyfunction]
#[pyo3(signature = (args, stdin=None))]
fn _run(
    py: Python<'_>,
    args: Vec<String>,
    stdin: Option<Vec<u8>>,
) -> (u8, Py<PyBytes>, Vec<String>) {
    let mut argv: Vec<std::ffi::OsString> = vec!["incal".into()];
    argv.extend(args.into_iter().map(Into::into));
    let out = py.detach(move || incal_cli::embed::run_embedded(&argv, stdin));
    (out.code, PyBytes::new(py, &out.stdout).unbind(), out.stderr)
}

/// The version of the incal library inside the package.
#[pyfunction]
fn _version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _incal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_run, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_reduce_record, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_plan, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_check_result, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_figures, m)?)?;
    m.add_function(wrap_pyfunction!(stream::_stream, m)?)?;
    m.add_function(wrap_pyfunction!(stream::_compare, m)?)?;
    m.add_function(wrap_pyfunction!(export::_export, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_thermal_fit, m)?)?;
    m.add_function(wrap_pyfunction!(records::_records, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_report, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_schema, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(_version, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_reduce, m)?)?;
    Ok(())
}
