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

/// One registry entry as JSON: the core's ([`Entry::to_json`]) with the
/// command line's argument tables (`arguments`: `reduce`, `plan`,
/// `simulate`), which Python's keyword parameters follow.
fn entry_json(e: &Entry) -> Value {
    let mut v = e.to_json();
    v["arguments"] = json!({
        "reduce": arguments(e.command),
        "plan": e.plan.map(arguments),
        "simulate": e.simulate.map(arguments),
    });
    v
}

/// The options of the command `words` as its argument table defines them
/// (every `--flag` but `--help`): `name` (the argument id, the key of the
/// core's options and of Python's keywords), `flag`, `aliases`, `help`,
/// `default` (as text), `values` (the allowed ones), `flag_only` (takes no
/// value), `multiple` (comma-separated), `required`.
fn arguments(words: &[&str]) -> Value {
    let mut cmd = crate::command();
    for w in words {
        match cmd.find_subcommand(w) {
            Some(c) => cmd = c.clone(),
            None => return Value::Null,
        }
    }
    let args: Vec<Value> = cmd
        .get_arguments()
        .filter(|a| a.get_long().is_some() && !matches!(a.get_id().as_str(), "help" | "version"))
        .map(|a| {
            let text = |v: &std::ffi::OsStr| v.to_string_lossy().into_owned();
            let values: Vec<String> = a
                .get_possible_values()
                .iter()
                .filter(|v| !v.is_hide_set())
                .map(|v| v.get_name().to_string())
                .collect();
            json!({
                "name": a.get_id().as_str(),
                "flag": format!("--{}", a.get_long().unwrap_or_default()),
                "aliases": a.get_all_aliases().unwrap_or_default(),
                "help": a.get_help().map(|h| h.to_string()),
                "default": a.get_default_values().iter().map(|v| text(v)).collect::<Vec<_>>(),
                "values": if a.get_action().takes_values() { values } else { Vec::new() },
                "flag_only": !a.get_action().takes_values(),
                "multiple": a.get_value_delimiter().is_some(),
                "required": a.is_required_set(),
            })
        })
        .collect();
    Value::Array(args)
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
