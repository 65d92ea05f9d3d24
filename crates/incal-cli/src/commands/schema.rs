//! `incal schema`: the JSON Schema of the result document
//! (`incal.result/1`, the same text as `schema/result.schema.json`), or with
//! `--plan` of the plan document (`incal.plan/1`, `schema/plan.schema.json`).

use std::path::PathBuf;

use crate::error::CliResult;
use crate::output::{json_text, write_text};

/// Options of `incal schema`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The schema of the plan document (incal.plan/1) instead of the result document.
    #[arg(long)]
    pub plan: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal schema`.
pub fn run(a: &Args) -> CliResult<()> {
    let schema = if a.plan {
        incal::document::plan::plan_json_schema()
    } else {
        incal::document::json_schema()
    };
    write_text(a.output.as_deref(), &json_text(&schema))
}
