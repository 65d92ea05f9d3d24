//! `incal procedures [--json]`: every procedure incal reduces, from the
//! procedure registry (`incal::procedures::registry`): its id, the
//! commands that reduce, plan and simulate it, the rig, the references and
//! the chapter of the manual. Front ends that are not Rust (Python) read
//! their tables of procedures from `--json`.

use std::path::PathBuf;

use incal::procedures::registry::{Entry, REGISTRY};
use serde_json::{json, Value};

use crate::error::CliResult;
use crate::output::{json_text, write_text};

/// Options of `incal procedures`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print the registry as JSON (one object per procedure) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// One registry entry as JSON.
fn entry_json(e: &Entry) -> Value {
    let words = |w: Option<&[&str]>| w.map(|w| w.join(" "));
    json!({
        "id": e.id,
        "document": e.document.as_str(),
        "title": e.title,
        "command": e.command_line(),
        "plan": words(e.plan),
        "simulate": words(e.simulate),
        "input": e.input,
        "rig": e.rig,
        "method": e.method,
        "references": e.references,
        "chapter": e.chapter,
        "run_sheet": e.run_sheet.is_some(),
        "fuzz": e.fuzz,
        "example": e.example.map(|x| json!({"simulate": x.simulate, "options": x.options})),
        "python": {
            "function": e.python(),
            "plan": e.python_plan(),
            "simulate": e.python_simulate(),
        },
        "options": {
            "reduce": e.reduction.map(|t| (t.schema)()),
            "plan": e.planner.map(|t| (t.schema)()),
            "simulate": e.simulator.map(|t| (t.schema)()),
        },
    })
}

/// The registry as a table for people.
fn table() -> String {
    let mut rows = vec![[
        "id".to_string(),
        "command".into(),
        "plan".into(),
        "simulate".into(),
        "rig".into(),
    ]];
    for e in REGISTRY {
        let words = |w: Option<&[&str]>| w.map_or("-".to_string(), |w| w.join(" "));
        rows.push([
            e.id.to_string(),
            e.command_line(),
            words(e.plan),
            words(e.simulate),
            e.rig.unwrap_or("-").to_string(),
        ]);
    }
    let width: Vec<usize> = (0..5)
        .map(|k| rows.iter().map(|r| r[k].chars().count()).max().unwrap_or(0))
        .collect();
    let mut s = String::new();
    for r in &rows {
        let cells: Vec<String> = r
            .iter()
            .zip(&width)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect();
        s.push_str(cells.join("  ").trim_end());
        s.push('\n');
    }
    s
}

/// `incal procedures`.
pub fn run(a: &Args) -> CliResult<()> {
    let text = if a.json {
        json_text(&Value::Array(REGISTRY.iter().map(entry_json).collect()))
    } else {
        table()
    };
    write_text(a.output.as_deref(), &text)
}
