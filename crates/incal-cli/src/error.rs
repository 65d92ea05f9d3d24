//! CLI errors and exit codes: 0 ok, 1 failure, 2 bad usage or bad input,
//! 3 a record stored whose output could not be written.

use std::fmt;

/// An error that ends the command.
#[derive(Debug)]
pub enum CliError {
    /// Bad usage or bad input (exit code 2): one line, naming file and line.
    Input(String),
    /// Anything else (exit code 1), e.g. an output file cannot be written.
    Failure(anyhow::Error),
    /// A record was stored but its output could not be written (exit code
    /// 3): retrying the same `add` finds the record and writes nothing new.
    Stored(String),
    /// The output was written and the user asked to stop on what it says
    /// (`--fail-on`: a fail verdict, results that differ): exit code 3.
    Stop(String),
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Input(m) => f.write_str(m),
            CliError::Failure(e) => write!(f, "{e:#}"),
            CliError::Stored(m) | CliError::Stop(m) => f.write_str(m),
        }
    }
}

impl From<anyhow::Error> for CliError {
    fn from(e: anyhow::Error) -> Self {
        CliError::Failure(e)
    }
}

impl CliError {
    /// Exit code of this error.
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => 2,
            CliError::Failure(_) => 1,
            CliError::Stored(_) | CliError::Stop(_) => 3,
        }
    }
}

/// Result of a command.
pub type CliResult<T> = Result<T, CliError>;

/// Bad input or usage, without a file.
pub fn usage(msg: impl Into<String>) -> CliError {
    CliError::Input(msg.into())
}

/// A core-library error while processing `file`: bad input (exit 2).
pub fn in_file(file: &str, e: impl fmt::Display) -> CliError {
    CliError::Input(format!("{file}: {e}"))
}

/// A core-library error (exit 2). An option is named by its snake_case
/// key ([`incal::Error::InvalidOption`]), spelled here as the flag the user
/// typed, from the argument table ([`flag_of`]): `--samples: at least 1
/// per position, got 0`; nothing else in a message is rewritten.
pub fn core(e: incal::Error) -> CliError {
    match e {
        incal::Error::InvalidOption { key, message } => {
            CliError::Input(format!("{}: {}", flag_of(&key), spell_keys(&message)))
        }
        incal::Error::InFile { file, source } => match core(*source) {
            CliError::Input(m) => CliError::Input(format!("{file}: {m}")),
            other => other,
        },
        // Option keys a message names in backticks, spelled as flags.
        other => CliError::Input(spell_keys(&other.to_string())),
    }
}

/// An option's key (`rate_hz`, or a path `runs[2].rate_deg_s`) as the
/// command line spells it: the long flag of the argument whose id is the
/// key (`--rate-hz`), from the argument definitions of every command; a
/// key no argument carries is left as it is.
pub fn flag_of(key: &str) -> String {
    static FLAGS: std::sync::OnceLock<std::collections::BTreeMap<String, String>> =
        std::sync::OnceLock::new();
    let flags = FLAGS.get_or_init(|| {
        fn walk(c: &clap::Command, out: &mut std::collections::BTreeMap<String, String>) {
            for a in c.get_arguments() {
                if let Some(long) = a.get_long() {
                    out.entry(a.get_id().to_string())
                        .or_insert_with(|| format!("--{long}"));
                }
            }
            for s in c.get_subcommands() {
                walk(s, out);
            }
        }
        let mut out = std::collections::BTreeMap::new();
        walk(&crate::command(), &mut out);
        out
    });
    let last = key.rsplit('.').next().unwrap_or(key);
    let last = last.split('[').next().unwrap_or(last);
    match flags.get(last) {
        Some(flag) if last == key => flag.clone(),
        Some(flag) => format!("{flag} ({key})"),
        None => key.to_string(),
    }
}

/// A core message with the other options it names in backticks
/// (`` `u_k1` ``) spelled as flags (`--u-k1`), by [`flag_of`].
pub fn spell_keys(message: &str) -> String {
    let mut out = String::with_capacity(message.len());
    let mut parts = message.split('`');
    out.push_str(parts.next().unwrap_or(""));
    let mut inside = true;
    for p in parts {
        if inside {
            out.push_str(&flag_of(p));
        } else {
            out.push_str(p);
        }
        inside = !inside;
    }
    out
}
