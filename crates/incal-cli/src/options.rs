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

/// `--fail-on` with `--limits`: which overall verdicts stop a script
/// (exit 3, after the result is written).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FailOn {
    /// Stop on fail, conditional-fail and not-determined (no conformity can be stated).
    Fail,
    /// Also stop on conditional-pass.
    Conditional,
}

/// Exit 3 (after the output) when `doc`'s overall verdict is one that
/// `fail_on` stops on, naming the coefficients behind it
/// ([`incal::document::finish::FailOn::stop`]).
pub fn check_fail_on(
    doc: &incal::document::ResultDocument,
    fail_on: Option<FailOn>,
) -> crate::error::CliResult<()> {
    use incal::document::finish::FailOn as Core;
    let Some(f) = fail_on else {
        return Ok(());
    };
    let core = match f {
        FailOn::Fail => Core::Fail,
        FailOn::Conditional => Core::Conditional,
    };
    match core.stop(doc) {
        Some(m) => Err(crate::error::CliError::Stop(format!(
            "{m}: stopped by --fail-on {}",
            core.as_str()
        ))),
        None => Ok(()),
    }
}

/// A records store as named in messages: its path, or its PostgreSQL URL
/// without the password.
pub fn store_name(path: &std::path::Path) -> String {
    incal_records::store_name(path)
}

/// A procedure named by its id (`imu-ferraris`; `_` for `-` accepted), for
/// the option or argument `what`; an unknown name lists every procedure.
pub fn procedure_id(what: &str, text: &str) -> crate::error::CliResult<incal::document::Procedure> {
    use incal::document::Procedure;
    Procedure::from_id(&text.replace('_', "-")).ok_or_else(|| {
        crate::error::CliError::Input(format!(
            "{what}: '{}' is not a procedure (one of: {})",
            incal_io::clip(text),
            Procedure::all()
                .iter()
                .map(|p| p.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })
}

/// A records-store error as one line naming the store once
/// (`NAME: …`): bad input and unusable stores exit 2, a broken chain and
/// database failures exit 1.
pub fn store_error(name: &str, e: incal_records::Error) -> crate::error::CliError {
    let msg = incal_records::store_message(name, &e);
    if e.is_input() {
        crate::error::CliError::Input(msg)
    } else {
        crate::error::CliError::Failure(anyhow::anyhow!("{msg}"))
    }
}

/// `--latitude-deg` everywhere: a finite number within −90…90 (clap value
/// parser, so a bad value is a usage error naming the option).
pub fn latitude_deg(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{}' is not a number", incal_io::clip(s)))?;
    if v.is_finite() && v.abs() <= 90.0 {
        Ok(v)
    } else {
        Err(format!(
            "latitude must be within -90..90 deg, got {}",
            incal_io::clip(s)
        ))
    }
}
