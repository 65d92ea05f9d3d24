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

/// The inputs every test plan needs, checked once for all plans: at least
/// one sample per position, a positive finite noise per sample, and a
/// finite non-zero nominal scale factor (`k1_what` names its unit).
pub fn require_plan_inputs(samples: usize, noise: f64, k1: f64, k1_what: &str) -> Result<()> {
    if samples == 0 {
        return Err(Error::TooFew {
            what: "samples per position".into(),
            needed: 1,
            got: 0,
        });
    }
    if !(noise.is_finite() && noise > 0.0) {
        return Err(Error::InvalidValue {
            what: "noise (must be > 0)".into(),
            value: noise.to_string(),
        });
    }
    if !(k1.is_finite() && k1 != 0.0) {
        return Err(Error::InvalidValue {
            what: format!("{k1_what} (must be finite and non-zero)"),
            value: k1.to_string(),
        });
    }
    Ok(())
}

/// Which positions sit at a converter's rail (saturation): position `i`
/// has `n[i]` samples of which `rail[i]` equal the record's largest or
/// smallest output exactly; it is clipped when `rail[i] ≥ 2` and
/// `2·rail[i] ≥ n[i]`, provided some other position scatters beyond
/// rounding (`scatter[i]`: its sample standard deviation relative to its
/// mean exceeds 1e-9), since a noiseless record has no rail to find.
pub fn at_rail(n: &[usize], rail: &[usize], scatter: &[bool]) -> Vec<bool> {
    let clipped: Vec<bool> = (0..n.len())
        .map(|i| rail[i] >= 2 && 2 * rail[i] >= n[i])
        .collect();
    let noisy = (0..n.len()).any(|i| !clipped[i] && scatter[i]);
    if noisy {
        clipped
    } else {
        vec![false; n.len()]
    }
}

/// Whether samples of standard deviation `std` about `mean` scatter
/// beyond the rounding of a mean of equal samples.
pub fn scatters(n: usize, mean: f64, std: f64) -> bool {
    n > 1 && std > 1e-9 * mean.abs().max(f64::MIN_POSITIVE)
}
