//! CSV input through the one input layer ([`incal_io`]): the options every
//! reading command shares (`--columns`, `--delimiter`) and the conversion
//! of its errors (exit 2, one line naming file, line and column).

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
    /// File line of the header row (1-based), for a file whose logger writes lines before it (default: found, the lines before it recorded as the document's preamble).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub header_line: Option<u64>,
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
            header_line: self.header_line.map(|n| n as usize),
            ..ReadOptions::default()
        })
    }
}
