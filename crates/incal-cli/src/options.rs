//! Option values shared by several commands: one name, one meaning.
//!
//! `--noise` is always the standard deviation of one output sample (one
//! row of an input CSV), in output units.

/// The records store: `--db`, else `$INCAL_DB` (when not empty), else
/// `incal.db` in the working directory.
pub fn db_path(db: Option<&std::path::Path>) -> std::path::PathBuf {
    db_choice(db).0
}

/// [`db_path`], and whether the store was named (`--db` or `$INCAL_DB`)
/// rather than the default `incal.db`: a named store must exist.
pub fn db_choice(db: Option<&std::path::Path>) -> (std::path::PathBuf, bool) {
    if let Some(p) = db {
        return (p.to_path_buf(), true);
    }
    match std::env::var_os("INCAL_DB") {
        Some(p) if !p.is_empty() => (std::path::PathBuf::from(p), true),
        _ => (std::path::PathBuf::from("incal.db"), false),
    }
}

/// A records store as named in messages: its path, or its PostgreSQL URL
/// without the password.
pub fn store_name(path: &std::path::Path) -> String {
    match path.to_str() {
        Some(u) if incal_records::is_postgres_url(u) => incal_records::display_url(u),
        _ => path.display().to_string(),
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
