//! Option values shared by several commands: one name, one meaning.
//!
//! `--noise` is always the standard deviation of one output sample (one
//! row of an input CSV), in output units.

use incal::estimation::Noise;

use crate::error::{usage, CliResult};

/// `--noise` of one output sample: `Noise::Known`, or `Auto` (from the
/// data) when absent.
pub fn noise_option(noise: Option<f64>) -> CliResult<Noise> {
    match noise {
        None => Ok(Noise::Auto),
        Some(s) if s.is_finite() && s > 0.0 => Ok(Noise::Known { sigma: s }),
        Some(s) => Err(usage(format!("--noise must be a positive number, got {s}"))),
    }
}

/// The records store: `--db`, else `$INCAL_DB` (when not empty), else
/// `incal.db` in the working directory.
pub fn db_path(db: Option<&std::path::Path>) -> std::path::PathBuf {
    if let Some(p) = db {
        return p.to_path_buf();
    }
    match std::env::var_os("INCAL_DB") {
        Some(p) if !p.is_empty() => std::path::PathBuf::from(p),
        _ => std::path::PathBuf::from("incal.db"),
    }
}

/// `--latitude-deg` everywhere: a finite number within −90…90 (clap value
/// parser, so a bad value is a usage error naming the option).
pub fn latitude_deg(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{}' is not a number", crate::output::clip(s)))?;
    if v.is_finite() && v.abs() <= 90.0 {
        Ok(v)
    } else {
        Err(format!(
            "latitude must be within -90..90 deg, got {}",
            crate::output::clip(s)
        ))
    }
}

/// Largest number of rows (or samples) a simulator writes.
pub const MAX_SIM_ROWS: u64 = 10_000_000;

/// Refuse a simulation whose size (`factors`, named, multiplied) exceeds
/// [`MAX_SIM_ROWS`]; the message names the options and the limit.
pub fn sim_size(factors: &[(&str, f64)]) -> Result<(), crate::error::CliError> {
    let mut total = 1.0f64;
    for (_, f) in factors {
        total *= f.max(0.0);
    }
    if total.is_finite() && total <= MAX_SIM_ROWS as f64 {
        Ok(())
    } else {
        let names: Vec<&str> = factors.iter().map(|f| f.0).collect();
        Err(usage(format!(
            "the simulation would write {} rows ({}); the limit is {MAX_SIM_ROWS}",
            crate::output::num(total),
            names.join(" x ")
        )))
    }
}

/// An angle option (deg): finite and at most 1e4 in magnitude.
pub fn angle_deg(name: &str, v: f64) -> Result<f64, crate::error::CliError> {
    if v.is_finite() && v.abs() <= 1e4 {
        Ok(v)
    } else {
        Err(usage(format!(
            "{name}: {} is not an angle (|angle| <= 1e4 deg)",
            crate::output::num(v)
        )))
    }
}

/// A simulated value written to a CSV must be finite; a truth or plan that
/// overflows is refused instead of writing inf or NaN.
pub fn finite_output(x: f64) -> Result<f64, crate::error::CliError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(usage(
            "the truth and plan give a non-finite output (inf or NaN); choose physical values",
        ))
    }
}
