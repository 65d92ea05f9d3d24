//! CSV input through the one input layer ([`incal_io`]): the options every
//! reading command shares (`--columns`, `--delimiter`) and the conversion
//! of its errors (exit 2, one line naming file, line and column).

use std::path::Path;

use incal_io::{ColumnMap, ReadOptions};

use crate::error::{CliError, CliResult};

impl From<incal_io::InputError> for CliError {
    fn from(e: incal_io::InputError) -> Self {
        CliError::Input(e.to_string())
    }
}

/// How every command reads its CSV input: the same two options everywhere.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ReadArgs {
    /// Columns to read and how the file names them, comma separated: NAME=HEADER reads the header HEADER as incal's column NAME (e.g. "angle_deg=Angle [deg],output=Out"); a bare NAME selects a column by its own header.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub columns: Vec<String>,
    /// Delimiter of the input CSV: ',', ';' or tab (default: detected from the header row).
    #[arg(long, value_name = "CHAR")]
    pub delimiter: Option<String>,
}

impl ReadArgs {
    /// The input layer's options.
    pub fn options(&self) -> CliResult<ReadOptions> {
        let columns = ColumnMap::from_entries(&self.columns)
            .map_err(|e| CliError::Input(format!("--columns: {e}")))?;
        let delimiter = match &self.delimiter {
            None => None,
            Some(d) => Some(
                incal_io::parse_delimiter(d)
                    .map_err(|e| CliError::Input(format!("--delimiter: {e}")))?,
            ),
        };
        Ok(ReadOptions {
            delimiter,
            columns,
            ..ReadOptions::default()
        })
    }
}

/// A CSV file read into memory through the input layer, with what the
/// commands not yet moved into the core use of it.
#[derive(Debug, Clone)]
pub struct Table {
    /// Path as given by the user (for messages).
    pub path: String,
    inner: incal_io::Table,
}

impl Table {
    /// Read `path` (`-`: standard input) with the default options.
    pub fn read(path: &Path) -> CliResult<Table> {
        Self::read_with(path, &ReadArgs::default())
    }

    /// Read `path` with the command's `--columns` and `--delimiter`.
    pub fn read_with(path: &Path, read: &ReadArgs) -> CliResult<Table> {
        let inner = incal_io::read_table(path, &read.options()?)?;
        Ok(Table {
            path: inner.file().to_string(),
            inner,
        })
    }

    /// The record of this file as an input of a result.
    pub fn input_file(&self, role: &str) -> incal::document::InputFile {
        input_file(self.inner.summary(), role)
    }

    /// Number of data rows (at least 1 after a successful read).
    pub fn row_count(&self) -> usize {
        self.inner.row_count()
    }

    /// Index of a required column.
    pub fn column(&self, name: &str) -> CliResult<usize> {
        Ok(self.inner.column(name)?)
    }

    /// Index of an optional column.
    pub fn opt_column(&self, name: &str) -> Option<usize> {
        self.inner.opt_column(name)
    }

    /// File line of data row `row`.
    pub fn line(&self, row: usize) -> usize {
        self.inner.line(row)
    }

    /// A finite number within ±1e15 from a cell, or an error naming file,
    /// line and column.
    pub fn f64(&self, row: usize, col: usize) -> CliResult<f64> {
        Ok(self.inner.f64(row, col)?)
    }

    /// An error at data row `row`.
    pub fn error_at(&self, row: usize, msg: String) -> CliError {
        self.inner.error_at(row, msg).into()
    }
}

/// The record of a file read through the input layer as an input of a result.
pub fn input_file(s: &incal_io::Summary, role: &str) -> incal::document::InputFile {
    let path = if s.file == incal_io::source::STDIN_NAME {
        "-"
    } else {
        &s.file
    };
    crate::output::input_file(role, path, s.sha256.clone(), Some(s.rows))
}
