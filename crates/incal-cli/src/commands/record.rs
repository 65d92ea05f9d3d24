//! `incal record …`: calibration records in an embedded store (the
//! `incal-records` crate): add a result, list, show, supersede (the only
//! way to correct: nothing is updated or deleted), history and drift of
//! one coefficient, verify the hash chain.
//!
//! The store is `--db PATH`, else `$INCAL_DB`, else `incal.db` in the
//! working directory. Bad input (a file that is not an incal result, a
//! serial missing or in conflict, an unknown record) is exit 2 with one
//! line; a chain that does not verify is exit 1 with
//! `incal: record N: …`.

use std::path::{Path, PathBuf};

use clap::Subcommand;
use incal::document::ResultDocument;
use incal_records::{Error as StoreError, NewRecord, Store};
use serde_json::json;

use crate::error::{CliError, CliResult};
use incal_report::records;

use crate::output::{json_text, render, write_text};

/// `incal record …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Store a result document (from a reducing command's --json) as a new record; prints its id.
    Add(AddArgs),
    /// List the records (all, or of one serial) and what supersedes what.
    List(ListArgs),
    /// Show one record: its identity and the stored result document, unchanged.
    Show(ShowArgs),
    /// Correct a record: store a new result that supersedes it, with a reason (nothing is deleted).
    Supersede(SupersedeArgs),
    /// One coefficient of one instrument across its calibrations: drift per day, repeatability, En of the latest.
    History(HistoryArgs),
    /// Recompute the hash chain and every stored document's hash; exit 1 naming the first record that does not match.
    Verify(VerifyArgs),
    /// Write every record, in chain order, as JSON lines (one record per line, every field the hash covers): to move a store to another (SQLite or PostgreSQL).
    Export(ExportArgs),
    /// Append the records of an export to this store, keeping ids, times and hashes, all or none; records already held are skipped, a store with another chain is refused.
    Import(ImportArgs),
}

/// The store every subcommand uses.
#[derive(clap::Args, Debug, Clone)]
pub struct DbArgs {
    /// The records store: an SQLite file, or a PostgreSQL database (postgresql://user@host:port/db); default: $INCAL_DB, else incal.db in the working directory.
    #[arg(long, value_name = "PATH|URL")]
    pub db: Option<PathBuf>,
}

impl DbArgs {
    /// `--db`, else `$INCAL_DB` (when not empty), else `incal.db`.
    pub(crate) fn path(&self) -> PathBuf {
        crate::options::db_path(self.db.as_deref())
    }

    /// The store as named in messages (a URL without its password).
    pub(crate) fn name(&self) -> String {
        crate::options::store_name(&self.path())
    }
}

/// Output form and destination.
#[derive(clap::Args, Debug, Clone)]
pub struct OutArgs {
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Who, where and when of a new record.
#[derive(clap::Args, Debug, Clone)]
pub struct WhoArgs {
    /// Serial of the instrument: needed when the result has no instrument.serial, and must equal it otherwise.
    #[arg(long)]
    pub serial: Option<String>,
    /// Who made the calibration (default: the result's instrument.operator, from --meta operator=...).
    #[arg(long)]
    pub operator: Option<String>,
    /// Where: rig, bench or lab (default: the result's instrument.station, from --meta station=...).
    #[arg(long)]
    pub station: Option<String>,
    /// The record's time, RFC 3339 (e.g. 2024-11-05T14:00:00Z or 2024-11-05), instead of now: for entering past calibrations. History dates the calibration by it.
    #[arg(long, value_name = "TIME")]
    pub created_utc: Option<String>,
}

/// Options of `incal record add`.
#[derive(clap::Args, Debug)]
pub struct AddArgs {
    /// The result document (JSON written by a reducing command with --json); - reads standard input.
    pub result: PathBuf,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub who: WhoArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record supersede`.
#[derive(clap::Args, Debug)]
pub struct SupersedeArgs {
    /// Id of the record to correct.
    pub id: i64,
    /// The corrected result document; - reads standard input.
    pub result: PathBuf,
    /// Why the record is corrected (kept in the audit trail).
    #[arg(long, required = true)]
    pub reason: String,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub who: WhoArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record list`.
#[derive(clap::Args, Debug)]
pub struct ListArgs {
    /// Only the records of this serial.
    #[arg(long)]
    pub serial: Option<String>,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record show`.
#[derive(clap::Args, Debug)]
pub struct ShowArgs {
    /// Record id.
    pub id: i64,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record history`.
#[derive(clap::Args, Debug)]
pub struct HistoryArgs {
    /// Serial of the instrument.
    #[arg(long, required = true)]
    pub serial: String,
    /// Coefficient name as in the results (K0, K1, dtheta_y2, ...).
    #[arg(long, required = true)]
    pub coefficient: String,
    /// Only the records of this procedure (tumble, centrifuge, ...): needed when the coefficient comes from records of more than one.
    #[arg(long)]
    pub procedure: Option<String>,
    /// Only the calibrations made near this temperature, degC (their temperature_c: --meta or the recording's column); a coefficient that moves with temperature drifts only at one temperature.
    #[arg(long, allow_hyphen_values = true)]
    pub at_temperature_c: Option<f64>,
    /// With --at-temperature-c: how near, degC.
    #[arg(long, default_value_t = 2.0, requires = "at_temperature_c")]
    pub within_c: f64,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record export`.
#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    #[command(flatten)]
    pub db: DbArgs,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Options of `incal record import`.
#[derive(clap::Args, Debug)]
pub struct ImportArgs {
    /// The export (JSON lines from 'incal record export'); - reads standard input.
    pub export: PathBuf,
    #[command(flatten)]
    pub db: DbArgs,
    #[command(flatten)]
    pub out: OutArgs,
}

/// Options of `incal record verify`.
#[derive(clap::Args, Debug)]
pub struct VerifyArgs {
    #[command(flatten)]
    pub db: DbArgs,
    /// Also check that the chain still holds this head (a record_hash written down earlier, e.g. on a certificate): a store truncated or rebuilt since fails.
    #[arg(long, value_name = "HEX")]
    pub head: Option<String>,
    #[command(flatten)]
    pub out: OutArgs,
}

/// `incal record …`.
pub fn run(c: &Command) -> CliResult<()> {
    match c {
        Command::Add(a) => add(a),
        Command::List(a) => list(a),
        Command::Show(a) => show(a),
        Command::Supersede(a) => supersede(a),
        Command::History(a) => history(a),
        Command::Verify(a) => verify(a),
        Command::Export(a) => export(a),
        Command::Import(a) => import(a),
    }
}

fn export(a: &ExportArgs) -> CliResult<()> {
    let store = open(&a.db, false)?;
    // A broken chain is not exported: said as verify says it.
    store.check_chain().map_err(store_err(&a.db))?;
    let mut chain = None;
    crate::io::write_binary_stream(a.output.as_deref(), |w| {
        chain = Some(
            store
                .export(w)
                .map_err(|e| std::io::Error::other(e.to_string()))?,
        );
        Ok(())
    })?;
    if let Some(c) = chain {
        crate::embed::stderr_line(&if c.events > 0 {
            format!(
                "exported {} records and {} events; head {}",
                c.records, c.events, c.head
            )
        } else {
            format!("exported {} records; head {}", c.records, c.head)
        });
    }
    Ok(())
}

fn import(a: &ImportArgs) -> CliResult<()> {
    let opened = incal_io::open(&a.export).map_err(|e| CliError::Input(e.to_string()))?;
    let reader = std::io::BufReader::with_capacity(1 << 16, opened.reader);
    // A refused import leaves no store it created.
    let done = Store::import_at(&a.db.path(), reader, &opened.name).map_err(store_err(&a.db))?;
    let text = if a.out.json {
        json_text(&json!({
            "added": done.added,
            "present": done.present,
            "chain": {"records": done.chain.records, "head": done.chain.head},
        }))
    } else {
        format!(
            "imported {} records ({} already present); chain: {} records, hash chain intact; head {}\n",
            done.added, done.present, done.chain.records, done.chain.head
        )
    };
    write_text(a.out.output.as_deref(), &text)
}

/// A store error as a CLI error: bad input and unusable stores exit 2,
/// a broken chain and database failures exit 1.
/// A store error as one line naming the store once (`PATH: …`).
fn store_err(db: &DbArgs) -> impl Fn(StoreError) -> CliError + '_ {
    move |e| crate::options::store_error(&db.name(), e)
}

fn open(db: &DbArgs, create: bool) -> CliResult<Store> {
    let path = db.path();
    if create {
        Store::open(&path)
    } else {
        Store::open_existing(&path)
    }
    .map_err(store_err(db))
}

/// The result file's text (BOM stripped, UTF-8 checked), checked to be an
/// incal result and to agree with --serial, --operator and --station.
fn read_result(path: &Path, who: &WhoArgs) -> CliResult<(String, String, ResultDocument)> {
    let (name, text) = crate::io::read_text(path)?;
    if text.trim().is_empty() {
        return Err(CliError::Input(format!("{name}: empty file")));
    }
    let doc =
        ResultDocument::from_json(&text).map_err(|e| CliError::Input(format!("{name}: {e}")))?;
    incal_records::check_identity(&name, &doc, &request(&text, who)).map_err(|e| match e {
        incal_records::IdentityError::Option { key, rest } => {
            CliError::Input(format!("--{}{rest}", key.replace('_', "-")))
        }
        incal_records::IdentityError::Document(m) => CliError::Input(m),
    })?;
    Ok((name, text, doc))
}

fn request<'a>(text: &'a str, who: &'a WhoArgs) -> NewRecord<'a> {
    NewRecord {
        document: text,
        serial: who.serial.as_deref(),
        operator: who.operator.as_deref(),
        station: who.station.as_deref(),
        created_utc: who.created_utc.as_deref(),
    }
}

/// The new record's id (with `--json`, also its document's hash; a
/// document already stored for the instrument is said on stderr). The record is committed before this runs, so a
/// failure here says so (exit 3): the same `add` again finds the record.
fn print_added(out: &OutArgs, added: &incal_records::Added) -> CliResult<()> {
    let text = if out.json {
        json_text(&json!({"id": added.id, "sha256": added.sha256}))
    } else {
        format!("{}\n", added.id)
    };
    write_text(out.output.as_deref(), &text).map_err(|e| {
        // Said once and truly: stored now, or held already.
        let what = if added.existing {
            "already holds this document"
        } else {
            "stored"
        };
        CliError::Stored(format!(
            "record {} {what}; writing the output failed: {e}",
            added.id
        ))
    })?;
    if added.existing {
        crate::embed::stderr_line(&format!(
            "record {} already holds this document for this instrument: nothing stored",
            added.id
        ));
    }
    Ok(())
}

fn add(a: &AddArgs) -> CliResult<()> {
    let (name, text, doc) = read_result(&a.result, &a.who)?;
    if doc.instrument.serial.is_none() && a.who.serial.is_none() {
        return Err(CliError::Input(format!(
            "{name}: the result has no instrument.serial: give --serial"
        )));
    }
    let mut store = open(&a.db, true)?;
    let added = store
        .add(&request(&text, &a.who))
        .map_err(store_err(&a.db))?;
    print_added(&a.out, &added)
}

fn supersede(a: &SupersedeArgs) -> CliResult<()> {
    if a.reason.trim().is_empty() {
        return Err(CliError::Input("--reason: empty".into()));
    }
    // No serial anywhere is fine here: the old record's is taken.
    let (_, text, _) = read_result(&a.result, &a.who)?;
    let mut store = Store::open_to_write(a.db.path()).map_err(store_err(&a.db))?;
    let added = store
        .supersede(a.id, &request(&text, &a.who), &a.reason)
        .map_err(store_err(&a.db))?;
    print_added(&a.out, &added)
}

fn list(a: &ListArgs) -> CliResult<()> {
    let store = open(&a.db, false)?;
    let chain = store.check_chain().map_err(store_err(&a.db))?;
    let records = store.list(a.serial.as_deref()).map_err(store_err(&a.db))?;
    let text = if a.out.json {
        json_text(&records::list_json(&records, &chain))
    } else {
        records::list_text(&records, &chain)
    };
    write_text(a.out.output.as_deref(), &text)
}

/// `incal record show --json`: the record's identity and the stored
/// document embedded verbatim (the exact stored text, so it is the
/// original JSON value, every number to the last bit).
fn show(a: &ShowArgs) -> CliResult<()> {
    let store = open(&a.db, false)?;
    store.check_chain().map_err(store_err(&a.db))?;
    let r = store.show(a.id).map_err(store_err(&a.db))?;
    let broken = |why: String| {
        CliError::Failure(anyhow::anyhow!(
            "record {}: {why} (run 'incal record verify')",
            r.id
        ))
    };
    let text = if a.out.json {
        records::show_json(&r).map_err(broken)?
    } else {
        let doc = ResultDocument::from_json(&r.document)
            .map_err(|e| broken(format!("the stored document no longer reads: {e}")))?;
        let mut s = records::header_text(&r);
        s.push('\n');
        s.push_str(&render(&doc));
        s
    };
    write_text(a.out.output.as_deref(), &text)
}

fn history(a: &HistoryArgs) -> CliResult<()> {
    // A procedure id (`imu-ferraris`), '_' for '-' accepted.
    let procedure = match &a.procedure {
        Some(p) => Some(crate::options::procedure_id("--procedure", p)?.as_str()),
        None => None,
    };
    let store = open(&a.db, false)?;
    store.check_chain().map_err(store_err(&a.db))?;
    let h = store
        .history_of(
            &a.serial,
            &a.coefficient,
            procedure,
            a.at_temperature_c.map(|t| (t, a.within_c)),
        )
        .map_err(store_err(&a.db))?;
    let text = if a.out.json {
        json_text(&records::history_json(&h))
    } else {
        records::history_text(&h)
    };
    write_text(a.out.output.as_deref(), &text)
}

fn verify(a: &VerifyArgs) -> CliResult<()> {
    let store = open(&a.db, false)?;
    let v = match &a.head {
        Some(h) => {
            if h.len() != 64 || !h.bytes().all(|b| b.is_ascii_hexdigit()) {
                return Err(CliError::Input(format!(
                    "--head: '{}' is not a record hash (64 hexadecimal digits)",
                    incal::error::short_number(h)
                )));
            }
            store.verify_head(&h.to_ascii_lowercase())
        }
        None => store.verify(),
    }
    .map_err(store_err(&a.db))?;
    let text = if a.out.json {
        json_text(&json!({"records": v.records, "events": v.events, "head": v.head}))
    } else if v.events > 0 {
        format!(
            "ok: {} records and {} events, hash chain intact; head {}\n",
            v.records, v.events, v.head
        )
    } else {
        format!(
            "ok: {} records, hash chain intact; head {}\n",
            v.records, v.head
        )
    };
    write_text(a.out.output.as_deref(), &text)
}
