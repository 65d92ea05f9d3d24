//! The one error of the input layer: the file, where in it, and what.

use std::fmt;

/// A problem with an input file: which file, which line and column when
/// known, and what is wrong. Displayed as one line,
/// `FILE[:LINE]: [column 'C': ]MESSAGE`, the form every incal front end
/// prints (the CLI exits 2 with it; Python raises it).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputError {
    /// The file as the user named it (`<stdin>` for standard input).
    pub file: String,
    /// 1-based line of the file, when the problem has one.
    pub line: Option<usize>,
    /// The column (incal's name for it), when the problem is one cell.
    pub column: Option<String>,
    /// What is wrong, in one line.
    pub message: String,
}

impl InputError {
    /// A problem with the file as a whole.
    pub fn file(file: &str, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            line: None,
            column: None,
            message: message.into(),
        }
    }

    /// A problem on one line.
    pub fn at(file: &str, line: usize, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            line: Some(line),
            column: None,
            message: message.into(),
        }
    }

    /// A problem in one cell.
    pub fn cell(file: &str, line: usize, column: &str, message: impl Into<String>) -> Self {
        Self {
            file: file.to_string(),
            line: Some(line),
            column: Some(column.to_string()),
            message: message.into(),
        }
    }

    /// The file could not be read.
    pub fn io(file: &str, e: &std::io::Error) -> Self {
        Self::file(file, format!("cannot read: {e}"))
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.file)?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        f.write_str(": ")?;
        if let Some(c) = &self.column {
            write!(f, "column '{c}': ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for InputError {}

/// Result of the input layer.
pub type Result<T> = std::result::Result<T, InputError>;

/// Text echoed in a message (a cell, a header, an option's value, a key of
/// a profile): as given when short, else its first 40 characters and its
/// length, `first 40... (N characters)`; control characters (a line
/// break, a tab, an escape) shown as `?`. So a message stays one readable
/// line whatever the input holds. The one such function of incal: every
/// crate and front end echoes values through it.
pub fn clip(s: &str) -> String {
    clip_to(s, 40)
}

/// [`clip`] at `max` characters: control characters as `?`, and past
/// `max` the head and `... (N characters)`.
pub fn clip_to(s: &str, max: usize) -> String {
    let n = s.chars().count();
    let head: String = s
        .chars()
        .take(max)
        .map(|c| if c.is_control() { '?' } else { c })
        .collect();
    if n <= max {
        head
    } else {
        format!("{head}... ({n} characters)")
    }
}
