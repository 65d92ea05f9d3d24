//! `incal batch PROCEDURE SOURCES… [-- OPTIONS…]`: one procedure over many
//! recordings on the local machine's cores.
//!
//! Each recording is reduced exactly as `incal <procedure> --input FILE
//! --json OPTIONS…` reduces it (the same command, run in process on a
//! worker thread), so every result equals the one-file run. One bad
//! recording never stops the batch: its one-line message is collected and
//! printed, the others go on. Results are written to `--out-dir` (one
//! `STEM.json` each) and, with `--db`, added to a records store by one
//! writer (this thread), in the order of the recordings; an `add` repeated
//! by a second run finds the record and stores nothing twice.
//!
//! Exit code: 0 when every recording was reduced; 2 when some were refused
//! as bad input (each named on its own line); 1 when some failed
//! otherwise; 3 when all were reduced but some verdicts stop the line
//! (`-- --limits L.toml --fail-on fail`): those results are written and
//! recorded like the others, and named.

use std::ffi::OsString;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use incal::procedures::registry;
use serde::Serialize;
use serde_json::value::RawValue;

use super::units::{self, Unit};
use crate::embed::{run_embedded, Embedded};
use crate::error::{CliError, CliResult};
use crate::output::write_text;

/// Options of `incal batch`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[arg(help = procedure_help())]
    pub procedure: String,
    /// Recordings: files, or directories (every regular file in them, by name; hidden files skipped).
    pub sources: Vec<PathBuf>,
    /// A file listing recordings, one path per line (relative to the list's directory; blank lines and '#' comments skipped).
    #[arg(long, value_name = "FILE")]
    pub list: Option<PathBuf>,
    /// Worker threads (default: every core).
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Write each result document to DIR/STEM.json (STEM: the recording's file name without its extension).
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Add each result to this records store (SQLite file or postgresql:// URL), in the order of the recordings, by one writer.
    #[arg(long, value_name = "PATH|URL")]
    pub db: Option<PathBuf>,
    /// Give each recording's file stem as the instrument serial (--serial STEM): recordings named by serial, as a production line names them.
    #[arg(long)]
    pub serial_from_stem: bool,
    /// Print the summary as one JSON object (every result document inside) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the summary to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Several units on one fixture, each its own result: a list of output columns (out_1,out_2 or SERIAL=out_1,…; a column's name is then the serial), or a mapping file (CSV: serial, columns, optional slot and options); see docs: Many recordings at once.
    #[arg(long, value_name = "LIST|FILE", conflicts_with = "serial_from_stem")]
    pub units: Option<String>,
    /// With --units: the procedure's column that a unit's bare column is read as (default output).
    #[arg(long, value_name = "NAME", requires = "units")]
    pub unit_column: Option<String>,
    /// The procedure's options, after '--', as for the one-file command (e.g. -- --mount pendulum).
    #[arg(last = true, value_name = "OPTIONS")]
    pub options: Vec<String>,
}

/// One recording in the summary.
#[derive(Serialize)]
struct Item {
    input: String,
    /// The unit's serial (`--units`).
    #[serde(skip_serializing_if = "Option::is_none")]
    unit: Option<String>,
    ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    code: Option<u8>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    output: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    record: Option<i64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    already_stored: Option<bool>,
    /// The `--fail-on` message of a result whose verdict stops the line.
    #[serde(skip_serializing_if = "Option::is_none")]
    stopped: Option<String>,
    /// The result document exactly as the procedure wrote it (every
    /// number to the last bit, not re-parsed).
    #[serde(skip_serializing_if = "Option::is_none")]
    result: Option<Box<RawValue>>,
}

/// The `--json` summary.
#[derive(Serialize)]
struct Summary<'a> {
    procedure: String,
    recordings: usize,
    ok: usize,
    failed: usize,
    results: &'a [Item],
}

/// One reduction of the batch: a recording, or one unit of a fixture's
/// recording.
#[derive(Debug, Clone)]
struct Job {
    input: PathBuf,
    unit: Option<Unit>,
}

impl Job {
    /// As the summary names it: `runs/fix.csv [SN-1]`.
    fn label(&self) -> String {
        match &self.unit {
            Some(u) => format!("{} [{}]", self.input.display(), u.serial),
            None => self.input.display().to_string(),
        }
    }

    /// Its result's file name in `--out-dir`, without `.json`.
    fn stem(&self) -> String {
        match &self.unit {
            Some(u) => format!("{}.{}", stem(&self.input), u.serial),
            None => stem(&self.input),
        }
    }
}

/// What became of one reduction.
struct Outcome {
    job: Job,
    run: Embedded,
}

/// The help of the PROCEDURE argument: every id `incal batch` runs, from
/// the procedure registry.
fn procedure_help() -> String {
    format!(
        "The procedure, by its id: {} ('_' for '-' is accepted; a document id such as 'thermal' names its one procedure that reduces a recording).",
        registry::batch_ids().join(", ")
    )
}

/// The registry entry of a procedure id that `incal batch` runs (a
/// recording in, a result document out), or the one-line refusal listing
/// the ids it runs.
pub fn entry(id: &str) -> CliResult<&'static registry::Entry> {
    registry::batch(id).ok_or_else(|| {
        CliError::Input(format!(
            "batch: '{}' is not a procedure (one of: {})",
            incal_io::clip(id),
            registry::batch_ids().join(", ")
        ))
    })
}

/// The command words of a procedure id (`imu-ferraris` → `imu ferraris`).
pub fn command_words(id: &str) -> CliResult<Vec<String>> {
    Ok(entry(id)?.command.iter().map(|w| w.to_string()).collect())
}

/// The recordings named by the sources and the list, in order.
fn recordings(a: &Args) -> CliResult<Vec<PathBuf>> {
    let mut out = Vec::new();
    for s in &a.sources {
        if s.is_dir() {
            let entries = std::fs::read_dir(s).map_err(|e| {
                CliError::Input(format!("{}: cannot read the directory: {e}", s.display()))
            })?;
            let mut files: Vec<PathBuf> = entries
                .filter_map(|e| e.ok())
                .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
                .map(|e| e.path())
                .filter(|p| p.is_file())
                .collect();
            files.sort();
            out.extend(files);
        } else {
            // A missing file is that recording's failure, said by the
            // procedure as for one file.
            out.push(s.clone());
        }
    }
    if let Some(list) = &a.list {
        let (name, text) = crate::io::read_text(list)?;
        let base = list.parent().unwrap_or(Path::new(""));
        for line in text.lines() {
            let t = line.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let p = Path::new(t);
            out.push(if p.is_absolute() || incal_io::is_dash(list) {
                p.to_path_buf()
            } else {
                base.join(p)
            });
        }
        if out.is_empty() {
            return Err(CliError::Input(format!("{name}: lists no recordings")));
        }
    }
    if out.is_empty() {
        return Err(CliError::Input(
            "batch: no recordings (give files, directories or --list)".into(),
        ));
    }
    Ok(out)
}

fn stem(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The recordings of the batch, after the checks made once before any is
/// reduced: options the batch sets itself, `--jobs`, the procedure's own
/// options (a usage error is the batch's, not every recording's) and
/// `--out-dir` names that would collide (the directory is created).
fn checked_inputs(a: &Args, words: &[String]) -> CliResult<Vec<Job>> {
    for o in &a.options {
        let flag = o.split('=').next().unwrap_or_default();
        if matches!(flag, "--input" | "--json" | "-o" | "--output")
            || ((a.serial_from_stem || a.units.is_some()) && flag == "--serial")
            || (a.units.is_some() && flag == "--columns")
        {
            return Err(CliError::Input(format!(
                "batch: {flag} is set by the batch for each recording; leave it out of the options"
            )));
        }
    }
    if a.jobs == Some(0) {
        return Err(CliError::Input("--jobs: must be at least 1".into()));
    }
    let units = match &a.units {
        Some(v) => Some(units::parse(
            v,
            a.unit_column.as_deref().unwrap_or("output"),
        )?),
        None => None,
    };
    let inputs: Vec<Job> = recordings(a)?
        .into_iter()
        .flat_map(|input| match &units {
            Some(us) => us
                .iter()
                .map(|u| Job {
                    input: input.clone(),
                    unit: Some(u.clone()),
                })
                .collect(),
            None => vec![Job { input, unit: None }],
        })
        .collect();
    // The procedure's options are checked once: a usage error is the
    // batch's, not every recording's. With units, each unit's command
    // line: an error every unit has is the batch's, one that some have is
    // those units' (named).
    let lines = units.as_ref().map_or(1, Vec::len);
    let errors: Vec<(Option<String>, &Job)> = inputs
        .iter()
        .take(lines)
        .map(|j| (crate::usage_error(&argv(a, words, j)), j))
        .collect();
    if let (Some(first), true) = (&errors[0].0, errors.iter().all(|e| e.0 == errors[0].0)) {
        return Err(CliError::Input(first.clone()));
    }
    if let Some((Some(message), j)) = errors.iter().find(|e| e.0.is_some()) {
        let serial = j.unit.as_ref().map_or("", |u| u.serial.as_str());
        return Err(CliError::Input(format!(
            "--units: unit {serial}: {message}"
        )));
    }
    if let Some(dir) = &a.out_dir {
        let mut seen = std::collections::HashMap::new();
        for j in &inputs {
            // Case apart, two names are one file on some systems.
            if let Some(other) = seen.insert(j.stem().to_lowercase(), j.label()) {
                return Err(CliError::Input(format!(
                    "--out-dir: {} and {} would both write {}.json",
                    other,
                    j.label(),
                    j.stem()
                )));
            }
        }
        std::fs::create_dir_all(dir).map_err(|e| {
            CliError::Failure(anyhow::anyhow!("{}: cannot create: {e}", dir.display()))
        })?;
    }
    Ok(inputs)
}

/// The summary for people: one line per recording, then the count.
fn text_summary(items: &[Item], failed: usize, noun: &str) -> String {
    let n = items.len();
    let mut s = String::new();
    for it in items {
        if it.ok {
            s.push_str(&format!("ok    {}", it.input));
            if let Some(o) = &it.output {
                s.push_str(&format!(" -> {o}"));
            }
            if let Some(r) = it.record {
                s.push_str(&format!(" (record {r})"));
            }
            if let Some(m) = &it.stopped {
                s.push_str(&format!(" STOP {m}"));
            }
        } else {
            s.push_str(&format!(
                "FAIL  {}",
                it.error.as_deref().unwrap_or_default()
            ));
        }
        s.push('\n');
    }
    s.push_str(&format!(
        "{} of {n} {noun} reduced, {failed} failed\n",
        n - failed
    ));
    s
}

/// The first recording reduced alone, then the rest: an option the
/// procedure refuses (its one line names the option, `--key: …`) would be
/// refused for every recording, so it is said once, as bad usage (exit 2),
/// and nothing else is reduced.
fn first_then_rest(a: &Args, words: &[String], inputs: &[Job]) -> CliResult<Vec<Outcome>> {
    let Some((first, rest)) = inputs.split_first() else {
        return Ok(Vec::new());
    };
    let mut outcomes = reduce_all(a, words, std::slice::from_ref(first));
    if let Some(o) = outcomes.first() {
        let line = o.run.stderr.last().map(String::as_str).unwrap_or_default();
        // A unit's own options are its own: their refusal is that unit's.
        let own = first.unit.as_ref().is_some_and(|u| !u.options.is_empty());
        if o.run.code == 2 && line.starts_with("--") && !own {
            return Err(CliError::Input(format!(
                "{line} (the options of every recording; nothing reduced)"
            )));
        }
    }
    outcomes.extend(reduce_all(a, words, rest));
    Ok(outcomes)
}

/// `incal batch`.
pub fn run(a: &Args) -> CliResult<()> {
    let procedure = entry(&a.procedure)?;
    let words = command_words(procedure.id)?;
    let inputs = checked_inputs(a, &words)?;
    let mut store = match &a.db {
        Some(db) => Some(incal_records::Store::open(db).map_err(|e| store_error(db, e))?),
        None => None,
    };
    let outcomes = first_then_rest(a, &words, &inputs)?;
    let mut items = Vec::with_capacity(outcomes.len());
    let (mut failed_input, mut failed_other, mut stopped) = (0usize, 0usize, 0usize);
    for o in outcomes {
        let input = o.job.label();
        let unit = o.job.unit.as_ref().map(|u| u.serial.clone());
        // Exit 3 with a document: a verdict that stops the line (the
        // result itself is whole).
        let stop = (o.run.code == 3 && !o.run.stdout.is_empty())
            .then(|| o.run.stderr.last().cloned().unwrap_or_default());
        if o.run.code != 0 && stop.is_none() {
            let message = o
                .run
                .stderr
                .last()
                .cloned()
                .unwrap_or_else(|| format!("{input}: failed (exit {})", o.run.code));
            let message = match &unit {
                Some(u) => format!("{message} (unit {u})"),
                None => message,
            };
            crate::embed::stderr_line(&message);
            if o.run.code == 2 {
                failed_input += 1;
            } else {
                failed_other += 1;
            }
            items.push(Item {
                input,
                unit,
                ok: false,
                code: Some(o.run.code),
                error: Some(message),
                output: None,
                record: None,
                already_stored: None,
                stopped: None,
                result: None,
            });
            continue;
        }
        let warnings = if stop.is_some() {
            &o.run.stderr[..o.run.stderr.len().saturating_sub(1)]
        } else {
            &o.run.stderr[..]
        };
        for w in warnings {
            crate::embed::stderr_line(w);
        }
        if let Some(m) = &stop {
            stopped += 1;
            crate::embed::stderr_line(&format!("{input}: {m}"));
        }
        let text = String::from_utf8_lossy(&o.run.stdout).into_owned();
        let mut item = Item {
            input,
            unit,
            ok: true,
            code: None,
            error: None,
            output: None,
            record: None,
            already_stored: None,
            stopped: stop,
            result: None,
        };
        if let Some(dir) = &a.out_dir {
            let path = dir.join(format!("{}.json", o.job.stem()));
            std::fs::write(&path, &text).map_err(|e| {
                CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", path.display()))
            })?;
            item.output = Some(path.display().to_string());
        }
        if let (Some(s), Some(db)) = (store.as_mut(), &a.db) {
            let added = s
                .add(&incal_records::NewRecord::new(&text))
                .map_err(|e| store_error(db, e))?;
            item.record = Some(added.id);
            item.already_stored = Some(added.existing);
        }
        if a.json {
            let doc = RawValue::from_string(text.trim_end().to_string()).map_err(|e| {
                CliError::Failure(anyhow::anyhow!(
                    "{}: the result is not JSON: {e}",
                    item.input
                ))
            })?;
            item.result = Some(doc);
        }
        items.push(item);
    }
    let n = items.len();
    let failed = failed_input + failed_other;
    let noun = if a.units.is_some() {
        "units"
    } else {
        "recordings"
    };
    let summary = if a.json {
        let summary = Summary {
            procedure: procedure.id.to_string(),
            recordings: n,
            ok: n - failed,
            failed,
            results: &items,
        };
        let text = serde_json::to_string_pretty(&summary)
            .map_err(|e| CliError::Failure(anyhow::anyhow!("cannot print the summary: {e}")))?;
        format!("{text}\n")
    } else {
        text_summary(&items, failed, noun)
    };
    write_text(a.output.as_deref(), &summary)?;
    match (failed_input, failed_other) {
        (0, 0) if stopped > 0 => Err(CliError::Stop(format!(
            "batch: {stopped} of {n} results stopped by --fail-on (named above)"
        ))),
        (0, 0) => Ok(()),
        (_, 0) => Err(CliError::Input(format!(
            "batch: {failed} of {n} {noun} refused (named above)"
        ))),
        _ => Err(CliError::Failure(anyhow::anyhow!(
            "batch: {failed} of {n} {noun} failed (named above)"
        ))),
    }
}

fn store_error(db: &Path, e: incal_records::Error) -> CliError {
    crate::options::store_error(&crate::options::store_name(db), e)
}

/// The command line that reduces one recording (or one unit of it: its
/// serial, columns and slot, the batch's options, then its own).
fn argv(a: &Args, words: &[String], job: &Job) -> Vec<OsString> {
    let mut argv: Vec<OsString> = vec!["incal".into()];
    argv.extend(words.iter().map(OsString::from));
    argv.push("--input".into());
    argv.push(job.input.as_os_str().to_owned());
    argv.push("--json".into());
    if a.serial_from_stem {
        argv.push("--serial".into());
        argv.push(stem(&job.input).into());
    }
    let (unit, own) = match &job.unit {
        Some(u) => {
            let mut args = u.args();
            let own = args.split_off(args.len() - u.options.len());
            (args, own)
        }
        None => (Vec::new(), Vec::new()),
    };
    argv.extend(unit.iter().map(OsString::from));
    argv.extend(a.options.iter().map(OsString::from));
    argv.extend(own.iter().map(OsString::from));
    argv
}

/// Every recording reduced, on `--jobs` threads pulling the next one in
/// turn; the outcomes in the order of the recordings (a recording's
/// result does not depend on the thread that reduced it).
fn reduce_all(a: &Args, words: &[String], inputs: &[Job]) -> Vec<Outcome> {
    let jobs = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(inputs.len())
        .max(1);
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<Embedded>>> = inputs.iter().map(|_| Mutex::new(None)).collect();
    let bar = (std::io::stderr().is_terminal() && !crate::embed::capturing()).then(|| {
        let b = indicatif::ProgressBar::new(inputs.len() as u64);
        b.set_style(
            indicatif::ProgressStyle::with_template("incal batch: {pos}/{len} {wide_bar} {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b
    });
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                let Some(input) = inputs.get(k) else { break };
                let out = run_embedded(&argv(a, words, input));
                if let Ok(mut slot) = slots[k].lock() {
                    *slot = Some(out);
                }
                if let Some(b) = &bar {
                    b.inc(1);
                }
            });
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    inputs
        .iter()
        .zip(slots)
        .map(|(job, slot)| Outcome {
            job: job.clone(),
            run: slot.into_inner().ok().flatten().unwrap_or(Embedded {
                code: 1,
                stdout: Vec::new(),
                stderr: vec![format!("{}: not reduced", job.label())],
            }),
        })
        .collect()
}
