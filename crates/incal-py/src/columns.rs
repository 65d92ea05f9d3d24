//! Columns handed over from Python: each a 1-D C-contiguous float64 numpy
//! array, borrowed in place for the call, or a list of str; then the
//! core's [`Columns`] borrowing them ([`incal_io::frames`]).

use std::borrow::Cow;

use incal_io::frames::{Column, Columns};
use numpy::{PyReadonlyArray1, PyUntypedArrayMethods};
use pyo3::prelude::*;

/// A column handed over from Python, kept borrowed for the call.
pub enum Held<'py> {
    /// A float64 array, read in place.
    Numbers(PyReadonlyArray1<'py, f64>),
    /// Text cells.
    Text(Vec<String>),
}

/// Take the `(name, column)` pairs Python gives, refusing anything but a
/// contiguous float64 array or a list of str (naming the column).
pub fn hold<'py>(columns: Vec<(String, Bound<'py, PyAny>)>) -> PyResult<Vec<(String, Held<'py>)>> {
    let mut held = Vec::with_capacity(columns.len());
    for (n, obj) in columns {
        if let Ok(a) = obj.extract::<PyReadonlyArray1<'py, f64>>() {
            if !a.is_c_contiguous() {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "column '{n}': the array is not contiguous"
                )));
            }
            held.push((n, Held::Numbers(a)));
        } else {
            let t: Vec<String> = obj.extract().map_err(|_| {
                pyo3::exceptions::PyTypeError::new_err(format!(
                    "column '{n}': a float64 numpy array or a list of str is needed"
                ))
            })?;
            held.push((n, Held::Text(t)));
        }
    }
    Ok(held)
}

/// The core's columns over what is held: `Ok(Err(message))` for columns
/// the core refuses (lengths that differ, a repeated name), named `name`.
pub fn borrow<'a>(
    name: &str,
    held: &'a [(String, Held<'_>)],
) -> PyResult<Result<Columns<'a>, String>> {
    let mut c = Columns::new();
    for (n, h) in held {
        let col = match h {
            Held::Numbers(a) => Column::F64(Cow::Borrowed(a.as_slice().map_err(|e| {
                pyo3::exceptions::PyValueError::new_err(format!("column '{n}': {e}"))
            })?)),
            Held::Text(t) => Column::Text(Cow::Borrowed(t)),
        };
        if let Err(m) = c.push(n, col) {
            return Ok(Err(format!("{name}: {m}")));
        }
    }
    Ok(Ok(c))
}
