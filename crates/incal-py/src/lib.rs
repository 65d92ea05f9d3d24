//! The compiled part of the Python package `incal`: one function, `_run`,
//! that runs an incal command line in process ([`incal_cli::embed`]) with
//! the GIL released. Everything else of the package is Python in
//! `python/incal/`: it turns keyword arguments into the CLI's options, so
//! a document from Python is the CLI's `--json` for the same data and
//! options by construction.

use pyo3::prelude::*;
use pyo3::types::PyBytes;

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

/// `_run_array(args, array) -> (code, stdout, stderr)`: as [`_run`], with
/// a C-contiguous float64 or float32 numpy array as the binary record that
/// `--input -` opens (`incal noise --format f64le|f32le`), read in place
/// without a copy while the GIL is released. Any other array is refused
/// (the Python side makes a contiguous copy first).
#[pyfunction]
fn _run_array(
    py: Python<'_>,
    args: Vec<String>,
    array: &Bound<'_, PyAny>,
) -> PyResult<(u8, Py<PyBytes>, Vec<String>)> {
    use numpy::{PyReadonlyArrayDyn, PyUntypedArrayMethods};
    let mut argv: Vec<std::ffi::OsString> = vec!["incal".into()];
    argv.extend(args.into_iter().map(Into::into));
    /// Run on the array's bytes, in place (f64 or f32 samples).
    fn on<T: numpy::Element + Copy>(
        py: Python<'_>,
        argv: &[std::ffi::OsString],
        a: PyReadonlyArrayDyn<'_, T>,
    ) -> PyResult<incal_cli::embed::Embedded> {
        let contiguous =
            || pyo3::exceptions::PyValueError::new_err("the array is not C-contiguous");
        if !a.is_c_contiguous() {
            return Err(contiguous());
        }
        let s = a.as_slice().map_err(|_| contiguous())?;
        // SAFETY: plain float values viewed as their bytes (any bit
        // pattern is a valid u8); the borrow `a` keeps the array alive and
        // read-only until the call returns.
        let bytes = unsafe {
            std::slice::from_raw_parts(s.as_ptr().cast::<u8>(), std::mem::size_of_val(s))
        };
        Ok(py.detach(|| incal_cli::embed::run_embedded_with_memory(argv, bytes)))
    }
    let out = if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, f64>>() {
        on(py, &argv, a)?
    } else if let Ok(a) = array.extract::<PyReadonlyArrayDyn<'_, f32>>() {
        on(py, &argv, a)?
    } else {
        return Err(pyo3::exceptions::PyTypeError::new_err(
            "a float64 or float32 numpy array is needed",
        ));
    };
    Ok((out.code, PyBytes::new(py, &out.stdout).unbind(), out.stderr))
}

/// The version of the incal library inside the package.
#[pyfunction]
fn _version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

#[pymodule]
fn _incal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_run, m)?)?;
    m.add_function(wrap_pyfunction!(_run_array, m)?)?;
    m.add_function(wrap_pyfunction!(_version, m)?)?;
    m.add_function(wrap_pyfunction!(typed::_reduce, m)?)?;
    Ok(())
}
