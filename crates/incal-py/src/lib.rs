//! The compiled part of the Python package `incal`, on the core crates
//! (`incal`, `incal-io`, `incal-records`, `incal-report`), never the
//! command line: the registry (`_registry`), its typed reductions on data
//! in place (`typed`: `_reduce`, `_reduce_record`), plans, simulators,
//! streaming tools, exports, the soak fit, reports and the records store.
//! The GIL is released while the core works. Everything else of the
//! package is Python in `python/incal/`.

use pyo3::prelude::*;

mod columns;
mod export;
mod records;
mod stream;
mod typed;

/// `_registry() -> str`: the procedure registry as JSON, one object per
/// procedure ([`incal::procedures::registry::Entry::to_json`]); the
/// package adds the command line's argument tables it ships
/// (`arguments.json`) for its keyword parameters.
#[pyfunction]
fn _registry() -> String {
    let entries: Vec<serde_json::Value> = incal::procedures::registry::REGISTRY
        .iter()
        .map(|e| e.to_json())
        .collect();
    serde_json::Value::Array(entries).to_string()
}

/// The version of the incal library inside the package.
#[pyfunction]
fn _version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _incal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_registry, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_reduce_record, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_plan, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_run_sheet, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_check_result, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_figures, m)?)?;
    m.add_function(wrap_pyfunction!(stream::_stream, m)?)?;
    m.add_function(wrap_pyfunction!(stream::_compare, m)?)?;
    m.add_function(wrap_pyfunction!(export::_export, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_thermal_fit, m)?)?;
    m.add_function(wrap_pyfunction!(records::_records, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_report, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_pdf, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_schema, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(_version, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_reduce, m)?)?;
    Ok(())
}
