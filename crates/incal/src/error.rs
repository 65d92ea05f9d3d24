//! The one error type of the core library.
//!
//! Every variant carries enough context (term names, counts, the offending
//! value) for the command-line tool to print one line that says what is
//! wrong and where. The core never panics on input and never prints.

use thiserror::Error;

/// A linear combination of model terms that a plan cannot observe.
///
/// `coefficients[k]` multiplies the regressor (design-matrix column) of
/// `terms[k]`; the weighted sum of those columns is (numerically) zero, so
/// any amount of this combination can be added to the estimates without
/// changing the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Alias {
    /// Names of the terms whose regressors are linearly dependent.
    pub terms: Vec<String>,
    /// Coefficients of the dependency, largest magnitude scaled to 1.
    pub coefficients: Vec<f64>,
}

impl Alias {
    /// The combination alone, e.g. `K0 - K2 - 0.500*K_pp` (no reason
    /// attached): how the weakest direction of a well-posed design is named.
    pub fn combination(&self) -> String {
        let mut s = String::new();
        for (k, (name, c)) in self.terms.iter().zip(&self.coefficients).enumerate() {
            let mag = c.abs();
            if k == 0 {
                if *c < 0.0 {
                    s.push('-');
                }
            } else {
                s.push_str(if *c < 0.0 { " - " } else { " + " });
            }
            if (mag - 1.0).abs() < 5e-4 {
                s.push_str(name);
            } else {
                s.push_str(&format!("{mag:.3}*{name}"));
            }
        }
        s
    }
}

/// The aliases of a refusal: the terms no position sees grouped in one
/// clause (`b+, s+ (each regressor is zero at every position)`), then each
/// dependent combination; so the line stays short however many terms fail.
fn unseparable(aliases: &[Alias]) -> String {
    let zero: Vec<&str> = aliases
        .iter()
        .filter(|a| a.terms.len() == 1)
        .map(|a| a.terms[0].as_str())
        .collect();
    let mut parts = Vec::new();
    match zero.len() {
        0 => {}
        1 => parts.push(format!(
            "{} (its regressor is zero at every position)",
            zero[0]
        )),
        _ => parts.push(format!(
            "{} (each regressor is zero at every position)",
            zero.join(", ")
        )),
    }
    parts.extend(
        aliases
            .iter()
            .filter(|a| a.terms.len() > 1)
            .map(|a| a.to_string()),
    );
    parts.join("; ")
}

/// The combination with why it cannot be observed (for refusals).
impl std::fmt::Display for Alias {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.terms.len() == 1 {
            return write!(
                f,
                "{} (its regressor is zero at every position)",
                self.terms[0]
            );
        }
        write!(f, "{} (regressors linearly dependent)", self.combination())
    }
}

/// Errors of the incal core.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// The plan cannot separate some terms: the design matrix is rank deficient.
    #[error("plan cannot separate {}", unseparable(.aliases))]
    Unseparable {
        /// Every independent unobservable combination.
        aliases: Vec<Alias>,
    },
    /// The design is so ill-conditioned that the solution is numerically meaningless.
    #[error("plan is numerically unable to separate {terms}: condition number {condition:.3e} exceeds {limit:.1e}")]
    IllConditioned {
        /// Terms dominating the weakest direction of the design.
        terms: String,
        /// Condition number of the column-equilibrated design.
        condition: f64,
        /// Limit that was exceeded.
        limit: f64,
    },
    /// Fewer observations (or distinct positions) than terms.
    #[error("{what}: need at least {needed}, got {got}")]
    TooFew {
        /// What is counted (e.g. "distinct angles for 6 terms").
        what: String,
        /// Minimum required.
        needed: usize,
        /// Number available.
        got: usize,
    },
    /// A value is not finite or out of its domain.
    #[error("invalid {what}: {}", short_number(.value))]
    InvalidValue {
        /// Which quantity.
        what: String,
        /// Its offending value, as text.
        value: String,
    },
    /// A problem with an input file, from the input layer (file, line,
    /// column, message).
    #[error("{0}")]
    Input(#[from] incal_io::InputError),
    /// A problem found while reducing the data of a file: the file, then
    /// the core's message.
    #[error("{file}: {source}")]
    InFile {
        /// The file as the user named it.
        file: String,
        /// What is wrong.
        source: Box<Error>,
    },
    /// An option of a procedure is missing, out of its range or
    /// inconsistent with another: `key` is the option's snake_case key (as
    /// in the document's `options`), which each front end spells its own
    /// way (`--rate-hz` on the command line, `rate_hz=` in Python).
    #[error("{key}: {message}")]
    InvalidOption {
        /// The option's snake_case key.
        key: String,
        /// What is wrong with it, for people.
        message: String,
    },
    /// A requested term or option does not exist or does not apply.
    #[error("{0}")]
    Unsupported(String),
    /// Writing an output (a simulated recording) failed: the I/O error's
    /// message.
    #[error("cannot write: {0}")]
    Write(String),
}

impl From<std::io::Error> for Error {
    /// A writer that refuses a value (a non-finite number: `InvalidData`)
    /// is an option outside what the simulator can represent; any other
    /// I/O error is a failure to write.
    fn from(e: std::io::Error) -> Error {
        if e.kind() == std::io::ErrorKind::InvalidData {
            Error::InvalidValue {
                what: "simulated value (an option is outside what the simulator can represent)"
                    .into(),
                value: e.to_string(),
            }
        } else {
            Error::Write(e.to_string())
        }
    }
}

/// Result alias of the core library.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// `Err(...)` of [`Error::invalid_value`].
    pub fn invalid<T>(what: impl Into<String>, value: impl std::fmt::Display) -> Result<T> {
        Err(Error::invalid_value(what, value))
    }

    /// A value out of its domain. When `what` is an option key alone or
    /// followed by what it must be in parentheses (`"samples (at least
    /// 1)"`), it is [`Error::InvalidOption`] on that key (`samples: at least
    /// 1, got 0`); any other `what` (`"sample rate (Hz)"`, a quantity of the
    /// data) is [`Error::InvalidValue`].
    pub fn invalid_value(what: impl Into<String>, value: impl std::fmt::Display) -> Error {
        let what = what.into();
        let value = short_number(&value.to_string());
        let (head, reason) = match what.split_once(" (") {
            Some((h, r)) if r.ends_with(')') => (h, Some(&r[..r.len() - 1])),
            Some(_) => (what.as_str(), None),
            None => (what.as_str(), None),
        };
        let is_key = !head.is_empty()
            && head
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_')
            && head.chars().next().is_some_and(|c| c.is_ascii_lowercase());
        if is_key && (reason.is_some() || head == what) {
            Error::InvalidOption {
                key: head.to_string(),
                message: match reason {
                    Some(r) => format!("{r}, got {value}"),
                    None => format!("invalid value {value}"),
                },
            }
        } else {
            Error::InvalidValue { what, value }
        }
    }

    /// This error as found in the data of `file` (an input-layer error
    /// already names its file and is left as it is).
    pub fn in_file(self, file: &str) -> Error {
        match self {
            Error::Input(_) | Error::InFile { .. } => self,
            other => Error::InFile {
                file: file.to_string(),
                source: Box::new(other),
            },
        }
    }
}

/// A value echoed in a message: a long number (`1e300` prints 301 digits)
/// in scientific notation, anything else as it is.
pub fn short_number(value: &str) -> String {
    match value.parse::<f64>() {
        Ok(x) if value.len() > 24 => format!("{x:.6e}"),
        _ => value.to_string(),
    }
}

/// A number echoed in a message: as Rust prints it when short, else in
/// scientific notation ([`short_number`] of its text).
pub fn short_f64(x: f64) -> String {
    short_number(&x.to_string())
}

/// Return `Err(InvalidValue)` unless `x` is finite.
pub fn finite(what: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::InvalidValue {
            what: what.to_string(),
            value: format!("{x}"),
        })
    }
}
