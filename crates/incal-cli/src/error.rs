//! CLI errors and exit codes: 0 ok, 1 failure, 2 bad usage or bad input.

use std::fmt;

/// An error that ends the command.
#[derive(Debug)]
pub enum CliError {
    /// Bad usage or bad input (exit code 2): one line, naming file and line.
    Input(String),
    /// Anything else (exit code 1), e.g. an output file cannot be written.
    Failure(anyhow::Error),
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Input(m) => f.write_str(m),
            CliError::Failure(e) => write!(f, "{e:#}"),
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

/// A core-library error about the options (no file involved): exit 2.
pub fn core(e: incal::Error) -> CliError {
    CliError::Input(e.to_string())
}
