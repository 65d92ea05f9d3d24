//! `incal schema`: the JSON Schema of the result document
//! (`incal.result/1`), the same text as `schema/result.schema.json`.

use std::path::PathBuf;

use crate::error::CliResult;
use crate::output::{json_text, write_text};

/// Options of `incal schema`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal schema`.
pub fn run(a: &Args) -> CliResult<()> {
    write_text(
        a.output.as_deref(),
        &json_text(&incal::document::json_schema()),
    )
}
