//! Physical validity checks shared by every procedure: what a calibration
//! engineer would refuse on sight, refused by name before a number that
//! means nothing reaches a result.

use crate::error::{Error, Result};
use crate::estimation::Estimates;

/// A scale factor must be observable: the output must follow the input.
/// Refused when `|K| ≤ k95·u(K)` (not different from zero at 95 %), which
/// is what a constant output or an output unrelated to the input gives;
/// every coefficient divided by it would be noise divided by noise.
pub fn require_scale_factor(e: &Estimates, name: &str) -> Result<()> {
    let Some((v, u)) = e.get(name) else {
        return Ok(());
    };
    let k95 = e.coverage_factor(0.95);
    if v == 0.0 || !v.is_finite() || v.abs() <= k95 * u {
        return Err(Error::Unsupported(format!(
            "scale factor {name} is not observable: the output does not follow the input ({name} = {v:.3e}, U95 = {:.3e})",
            k95 * u
        )));
    }
    Ok(())
}

/// Every output sample identical: nothing about the instrument can be
/// estimated from it.
pub fn require_varying(outputs: impl IntoIterator<Item = f64>, what: &str) -> Result<()> {
    let mut it = outputs.into_iter();
    if let Some(first) = it.next() {
        if it.all(|v| v == first) {
            return Err(Error::Unsupported(format!(
                "{what} is {first} in every row: the scale factor is not observable"
            )));
        }
    }
    Ok(())
}
