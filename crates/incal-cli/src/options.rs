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
