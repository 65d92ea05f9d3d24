//! The procedure registry (`incal::procedures::registry::REGISTRY`) is the
//! one list of procedures: every front end's list is derived from it or
//! checked here against it, and each gap is named where it is ("procedure
//! thermal-ramp: no chapter docs/src/x.md"). The fuzz targets are checked
//! in `crates/incal-fuzz`, Python's functions in its pytest suite (and
//! their stubs here too).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use incal::procedures::registry::{InputKind, REGISTRY};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The subcommand at `words` of the CLI's command tree, if any.
fn find<'a>(root: &'a clap::Command, words: &[&str]) -> Option<&'a clap::Command> {
    let mut cmd = root;
    for w in words {
        cmd = cmd.find_subcommand(w)?;
    }
    Some(cmd)
}

/// Every gap between the registry and the CLI's command tree.
fn cli_gaps() -> Vec<String> {
    let cli = incal_cli::command();
    let mut gaps = Vec::new();
    let mut claimed: BTreeSet<Vec<&str>> = BTreeSet::new();
    for e in REGISTRY {
        let mut paths = vec![("command", e.command)];
        paths.extend(e.plan.map(|p| ("plan", p)));
        paths.extend(e.simulate.map(|p| ("simulator", p)));
        for (what, words) in paths {
            claimed.insert(words.to_vec());
            match find(&cli, words) {
                None => gaps.push(format!(
                    "procedure {}: no CLI {what} 'incal {}'",
                    e.id,
                    words.join(" ")
                )),
                // A reduction may hold its tools (`incal mag apply`) when
                // it takes its own --input.
                Some(c)
                    if c.has_subcommands()
                        && !(what == "command"
                            && c.get_arguments().any(|a| a.get_long() == Some("input"))) =>
                {
                    gaps.push(format!(
                        "procedure {}: 'incal {}' is a group, not a command",
                        e.id,
                        words.join(" ")
                    ))
                }
                Some(_) => {}
            }
        }
        if e.input == InputKind::Recording {
            let has_input = find(&cli, e.command)
                .is_some_and(|c| c.get_arguments().any(|a| a.get_long() == Some("input")));
            if !has_input {
                gaps.push(format!(
                    "procedure {}: 'incal {}' takes no --input (the registry says it reduces a recording)",
                    e.id,
                    e.command_line()
                ));
            }
        }
    }
    // Every plan and simulator command belongs to a registered procedure.
    for group in ["plan", "simulate"] {
        let Some(g) = cli.find_subcommand(group) else {
            gaps.push(format!("CLI: no 'incal {group}'"));
            continue;
        };
        let mut leaves = Vec::new();
        collect_leaves(g, vec![group.to_string()], &mut leaves);
        for leaf in leaves {
            let words: Vec<&str> = leaf.iter().map(String::as_str).collect();
            if !claimed.contains(&words) {
                gaps.push(format!(
                    "CLI: 'incal {}' belongs to no procedure of the registry",
                    leaf.join(" ")
                ));
            }
        }
    }
    gaps
}

fn collect_leaves(cmd: &clap::Command, path: Vec<String>, out: &mut Vec<Vec<String>>) {
    if !cmd.has_subcommands() {
        out.push(path);
        return;
    }
    for s in cmd.get_subcommands() {
        if s.get_name() == "help" {
            continue;
        }
        let mut p = path.clone();
        p.push(s.get_name().to_string());
        collect_leaves(s, p, out);
    }
}

/// Every gap between the registry and the manual, the README, the
/// certificate's rigs, the schemas and Python's stubs.
fn document_gaps() -> Vec<String> {
    let mut gaps = Vec::new();
    let summary = read("docs/src/SUMMARY.md");
    let references = read("docs/src/references.md");
    let readme = read("README.md");
    let result_schema = read("schema/result.schema.json");
    let plan_schema = read("schema/plan.schema.json");
    let stubs: Vec<(&str, String)> = ["__init__", "plan", "simulate"]
        .iter()
        .map(|m| {
            let text = read(&format!("crates/incal-py/python/incal/{m}.pyi"));
            (*m, text)
        })
        .collect();
    for e in REGISTRY {
        let id = e.id;
        if !root().join("docs/src").join(e.chapter).exists() {
            gaps.push(format!("procedure {id}: no chapter docs/src/{}", e.chapter));
        }
        if !summary.contains(&format!("({})", e.chapter)) {
            gaps.push(format!(
                "procedure {id}: its chapter {} is not in docs/src/SUMMARY.md",
                e.chapter
            ));
        }
        if !readme.contains(&format!("(docs/src/{})", e.chapter)) {
            gaps.push(format!(
                "procedure {id}: no row of the README's table of procedures links docs/src/{}",
                e.chapter
            ));
        }
        for r in e.references {
            if !references.contains(&format!("<a id=\"{r}\"></a>")) {
                gaps.push(format!(
                    "procedure {id}: reference '{r}' is not in docs/src/references.md"
                ));
            }
        }
        if let Some(rig) = e.rig {
            if !incal_report::certificate::RIGS.contains(&rig) {
                gaps.push(format!(
                    "procedure {id}: rig '{rig}' is not a rig of the certificate's laboratory profile"
                ));
            }
        }
        let doc = format!("\"{}\"", e.document.as_str());
        if !result_schema.contains(&doc) {
            gaps.push(format!(
                "procedure {id}: schema/result.schema.json does not list {doc}"
            ));
        }
        if e.plan.is_some() && !plan_schema.contains(&doc) {
            gaps.push(format!(
                "procedure {id}: schema/plan.schema.json does not list {doc}"
            ));
        }
        let names = [
            ("__init__", Some(e.python())),
            ("plan", e.python_plan()),
            ("simulate", e.python_simulate()),
        ];
        for (module, name) in names {
            let Some(name) = name else { continue };
            let text = &stubs.iter().find(|(m, _)| *m == module).unwrap().1;
            if !text.contains(&format!("def {name}(")) {
                gaps.push(format!(
                    "procedure {id}: no stub 'def {name}(' in crates/incal-py/python/incal/{module}.pyi"
                ));
            }
        }
    }
    gaps
}

#[test]
fn every_front_end_lists_what_the_registry_lists() {
    let mut gaps = cli_gaps();
    gaps.extend(document_gaps());
    assert!(gaps.is_empty(), "{}", gaps.join("\n"));
}

/// Files that may name many procedure ids: the registry itself and the
/// script that writes the fuzz seeds (one simulator command per seed file,
/// checked by `crates/incal-fuzz/tests/it/registry.rs`). Generated files
/// (schemas, snapshots, seeds) and prose (the manual, where a chapter names
/// the procedures it covers) are not source.
const ALLOWED: &[&str] = &[
    "crates/incal/src/procedures/registry.rs",
    "crates/incal-fuzz/make-seeds.sh",
];

/// Source files that hold a hand-kept list of procedure ids: four or more
/// distinct ids written as string literals in one file, outside the
/// registry and the files checked against it ([`ALLOWED`]).
fn hand_lists() -> Vec<String> {
    let ids: BTreeSet<&str> = REGISTRY
        .iter()
        .flat_map(|e| [e.id, e.document.as_str()])
        .collect();
    let mut found = Vec::new();
    let mut files = Vec::new();
    for dir in ["crates", "scripts", "fuzz"] {
        walk(&root().join(dir), &mut files);
    }
    for f in files {
        let rel = f
            .strip_prefix(root())
            .unwrap_or(&f)
            .to_string_lossy()
            .replace('\\', "/");
        let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
        let source = matches!(ext, "rs" | "py" | "sh" | "toml");
        let test =
            rel.contains("/tests/") || rel.contains("/benches/") || rel.contains("/examples/");
        if !source || test || ALLOWED.contains(&rel.as_str()) {
            continue;
        }
        let Ok(text) = std::fs::read_to_string(&f) else {
            continue;
        };
        let named: Vec<&str> = ids
            .iter()
            .copied()
            .filter(|id| text.contains(&format!("\"{id}\"")))
            .collect();
        if named.len() >= 4 {
            found.push(format!(
                "{rel}: a hand list of procedure ids ({}): derive it from the registry",
                named.join(", ")
            ));
        }
    }
    found
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        let name = e.file_name();
        let name = name.to_string_lossy();
        if name.starts_with('.') || name == "target" || name == "snapshots" || name == "seeds" {
            continue;
        }
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

#[test]
fn no_other_source_file_keeps_a_list_of_procedure_ids() {
    let found = hand_lists();
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn batch_runs_every_procedure_that_reduces_a_recording() {
    let help = incal_cli::command()
        .find_subcommand("batch")
        .and_then(|b| {
            b.get_arguments()
                .find(|a| a.get_id() == "procedure")
                .and_then(|a| a.get_help().map(|h| h.to_string()))
        })
        .unwrap_or_default();
    for e in REGISTRY {
        let named = help.contains(e.id);
        assert_eq!(
            named,
            e.input == InputKind::Recording,
            "procedure {}: batch's help {} it",
            e.id,
            if named { "names" } else { "does not name" }
        );
    }
}

/// Python's keyword parameters follow the command line's argument tables;
/// the package ships them (`arguments.json`, so it needs no CLI) and this
/// test keeps that file equal to `incal procedures --json`'s `arguments`.
/// Regenerate with `INCAL_UPDATE_SCHEMA=1 cargo test -p incal-cli --test
/// it registry`.
#[test]
fn python_ships_the_command_lines_argument_tables() {
    let out = crate::common::run(&["procedures", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let registry: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut tables = serde_json::Map::new();
    for e in registry.as_array().unwrap() {
        tables.insert(e["id"].as_str().unwrap().into(), e["arguments"].clone());
    }
    let want = format!(
        "{}\n",
        serde_json::to_string_pretty(&serde_json::Value::Object(tables)).unwrap()
    );
    let rel = "crates/incal-py/python/incal/arguments.json";
    if std::env::var_os("INCAL_UPDATE_SCHEMA").is_some() {
        std::fs::write(root().join(rel), &want).unwrap();
    }
    assert!(
        read(rel) == want,
        "{rel} is stale: run INCAL_UPDATE_SCHEMA=1 cargo test -p incal-cli --test it registry"
    );
}
