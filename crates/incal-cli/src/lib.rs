//! `incal`: the command-line tool of the incal calibration library (the
//! binary's `main` calls [`main_from`]).
//!
//! Thin by design: parse options, read files, call the core, print. Exit
//! codes: 0 ok, 1 failure, 2 bad usage or bad input, with one line on
//! stderr naming the file and line, or the option, and the problem. The one
//! exception: a command group without its subcommand (`incal`, `incal plan`)
//! prints its usage to stderr, still exit 2.

// The doc comments of the options are their `--help` text, read by people
// on a terminal: `[lab]`, `[a,b]` and `ax,ay,az[,gyr_x,…]` there are
// literal text, not links, and must print as written.
#![allow(rustdoc::broken_intra_doc_links)]

mod commands;
mod documents;
mod embed;
mod error;
mod input;
mod io;
mod options;
mod output;
mod run;

use std::ffi::OsString;
use std::io::Write;

use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::{CommandFactory, Parser, Subcommand};

use crate::error::CliResult;

/// Data reduction for inertial-instrument calibration.
#[derive(Parser, Debug)]
#[command(name = "incal", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The whole command tree (every subcommand and option), as clap sees it.
pub fn command() -> clap::Command {
    Cli::command()
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Simulate virtual instruments on every rig, calibrate, and print estimate, truth and uncertainty.
    Demo(commands::demo::Args),
    /// The procedures (each family's file in `commands/`, listed once in `commands/mod.rs`).
    #[command(flatten)]
    Procedure(Box<commands::Reductions>),
    /// Design a test plan and predict the uncertainty of every coefficient before the test.
    #[command(subcommand)]
    Plan(commands::Plans),
    /// Simulate a rig from a known truth and write the input CSV of the matching procedure.
    #[command(subcommand)]
    Simulate(commands::Simulations),
    /// Compare the coefficients of two result files: difference, per mille and En.
    Compare(commands::compare::Args),
    /// Write a robot log's topic (PX4 ULog, ROS 1 bag, MCAP) as incal's CSV: the text every reducing command reads from it.
    Convert(commands::convert::Args),
    /// Export a result in another tool's format: imucal's calibration JSON, Kalibr's imu.yaml, PX4 and ArduPilot parameters.
    #[command(subcommand)]
    Export(commands::export::Command),
    /// List every procedure incal reduces (id, commands, rig, chapter), from the procedure registry; --json for programs.
    Procedures(commands::procedures::Args),
    /// Print the JSON Schema of the result document (incal.result/1), or with --plan of the plan document (incal.plan/1).
    Schema(commands::schema::Args),
    /// Write one self-contained HTML report (printable certificate) of a result file, with plots.
    Report(commands::report::Args),
    /// Calibration records: store results per instrument (append-only, hash-chained), list, show, supersede, history and drift, verify.
    #[command(subcommand)]
    Record(commands::record::Command),
    /// The lab's web application on a records store: instruments and due dates, history plots, review and approval, certificates, for accounts with roles.
    Serve(commands::serve::Args),
    /// Accounts of the web application (viewer, engineer, signatory, admin), each change an event in the store's hash chain.
    #[command(subcommand)]
    User(commands::user::Command),
    /// Reduce many recordings with one procedure on the local machine's cores: results in order, per-file errors collected, records written by one writer.
    Batch(commands::batch::Args),
}

fn run(cli: Cli) -> CliResult<()> {
    use commands::Run;
    match cli.command {
        Command::Demo(a) => commands::demo::run(&a),
        Command::Procedure(c) => c.run(),
        Command::Plan(c) => c.run(),
        Command::Simulate(c) => c.run(),
        Command::Compare(a) => commands::compare::run(&a),
        Command::Convert(a) => commands::convert::run(&a),
        Command::Export(c) => commands::export::run(&c),
        Command::Schema(a) => commands::schema::run(&a),
        Command::Procedures(a) => commands::procedures::run(&a),
        Command::Report(a) => commands::report::run(&a),
        Command::Record(c) => commands::record::run(&c),
        Command::Batch(a) => commands::batch::run(&a),
        Command::Serve(a) => commands::serve::run(&a),
        Command::User(c) => commands::user::run(&c),
    }
}

/// Die quietly on a closed pipe (`incal demo | head`), as Unix filters do,
/// instead of panicking inside `println!`.
pub fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal disposition to its default at start-up,
    // before any thread exists, has no memory-safety preconditions.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Let every option value start with a hyphen: biases, misalignments,
/// latitudes and angles are often negative (`--k0 -1.2e-4`), and clap's own
/// negative-number detection rejects negative exponents (`-1e-3`). A stray
/// flag taken as a value (`--noise --json`) still fails, as an invalid number.
///
/// Options only, never positional arguments: a command's files stay files
/// and a flag after them stays a flag (`incal repeatability r1.json
/// r2.json --monte-carlo 200`).
fn allow_negative_values(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        let takes_value =
            a.get_action().takes_values() && a.get_num_args().is_none_or(|n| n.takes_values());
        if a.is_positional() || !takes_value {
            a
        } else {
            a.allow_hyphen_values(true)
        }
    })
    .mut_subcommands(allow_negative_values)
}

fn parse(args: &[OsString]) -> Result<Cli, clap::Error> {
    use clap::FromArgMatches;
    let matches = allow_negative_values(Cli::command()).try_get_matches_from(args)?;
    Cli::from_arg_matches(&matches)
}

/// The command the user was running, as far as the arguments name one
/// (`incal`, `incal tumble`, `incal simulate misalign gyro`): the words of
/// `args` (after the program name) that name a subcommand of the one before.
fn command_path(root: &clap::Command, args: &[OsString]) -> String {
    let mut cmd = root;
    let mut path = vec![root.get_name().to_string()];
    for arg in args.iter().skip(1) {
        let Some(word) = arg.to_str() else { break };
        if word.starts_with('-') {
            continue;
        }
        match cmd.find_subcommand(word) {
            Some(sub) => {
                path.push(sub.get_name().to_string());
                cmd = sub;
            }
            None => break,
        }
    }
    path.join(" ")
}

/// A string or list of strings from clap's structured error context.
fn context_strings(e: &clap::Error, kind: ContextKind) -> Vec<String> {
    match e.get(kind) {
        Some(ContextValue::String(s)) => vec![s.clone()],
        Some(ContextValue::Strings(v)) => v.clone(),
        Some(ContextValue::StyledStr(s)) => vec![s.to_string()],
        Some(ContextValue::StyledStrs(v)) => v.iter().map(|s| s.to_string()).collect(),
        _ => Vec::new(),
    }
}

/// `, did you mean 'X'?` for clap's suggestions (and `; TIP` for its
/// other tips), or nothing.
fn did_you_mean(e: &clap::Error, kind: ContextKind) -> String {
    let mut out = String::new();
    let quoted: Vec<String> = context_strings(e, kind)
        .iter()
        .map(|s| format!("'{s}'"))
        .collect();
    if !quoted.is_empty() {
        out.push_str(&format!(", did you mean {}?", quoted.join(" or ")));
    }
    for tip in context_strings(e, ContextKind::Suggested) {
        out.push_str(&format!("; {}", one_line(&tip)));
    }
    out
}

/// Lines of `text` trimmed and joined into one (`; ` between them, or a
/// space after a line ending in `:`).
fn one_line(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines().map(str::trim).filter(|l| !l.is_empty()) {
        if !out.is_empty() {
            out.push_str(if out.ends_with(':') { " " } else { "; " });
        }
        out.push_str(line);
    }
    out
}

/// clap's own message as one line, without the `error: ` prefix, the usage
/// and the "For more information" hint.
fn clap_message(e: &clap::Error) -> String {
    let text = e.to_string();
    let kept: Vec<&str> = text
        .lines()
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .collect();
    let msg = one_line(&kept.join("\n"));
    let msg = msg.strip_prefix("error: ").unwrap_or(&msg).to_string();
    if msg.is_empty() {
        "bad usage".to_string()
    } else {
        msg
    }
}

/// The one-line message (without the `incal: ` prefix) of a usage error of
/// `command` (e.g. `incal tumble`): names the option and, for a choice, the
/// values allowed.
fn usage_message(e: &clap::Error, command: &str) -> String {
    let see = format!(" (see '{command} --help')");
    let first = |kind| context_strings(e, kind).into_iter().next();
    match e.kind() {
        ErrorKind::MissingRequiredArgument => {
            let missing = context_strings(e, ContextKind::InvalidArg);
            if missing.is_empty() {
                return clap_message(e) + &see;
            }
            let what = if missing.iter().all(|m| m.starts_with('-')) {
                "option"
            } else {
                "argument"
            };
            let plural = if missing.len() > 1 { "s" } else { "" };
            format!(
                "missing required {what}{plural} {}{see}",
                missing.join(", ")
            )
        }
        ErrorKind::InvalidValue => {
            let (Some(arg), Some(value)) = (
                first(ContextKind::InvalidArg),
                first(ContextKind::InvalidValue),
            ) else {
                return clap_message(e) + &see;
            };
            let head = if value.is_empty() {
                format!("a value is required for '{arg}' but none was supplied")
            } else {
                format!("invalid value '{value}' for '{arg}'")
            };
            let valid = context_strings(e, ContextKind::ValidValue);
            if valid.is_empty() {
                head + &see
            } else {
                format!("{head} (possible values: {})", valid.join(", "))
            }
        }
        ErrorKind::UnknownArgument => match first(ContextKind::InvalidArg) {
            Some(arg) => {
                let what = if arg.starts_with('-') {
                    "unknown option"
                } else {
                    "unexpected argument"
                };
                let hint = did_you_mean(e, ContextKind::SuggestedArg);
                format!("{what} '{arg}'{hint}{see}")
            }
            None => clap_message(e) + &see,
        },
        ErrorKind::InvalidSubcommand => match first(ContextKind::InvalidSubcommand) {
            Some(sub) => {
                let hint = did_you_mean(e, ContextKind::SuggestedSubcommand);
                format!("unknown command '{sub}'{hint}{see}")
            }
            None => clap_message(e) + &see,
        },
        _ => clap_message(e) + &see,
    }
}

/// One line on standard error; a standard error that cannot be written to
/// is ignored (there is nowhere left to report it).
fn say(line: &str) {
    embed::stderr_line(&one_line(line));
}

/// Exit code for a command-line that did not parse: help and version on
/// stdout (0, or 1 when stdout cannot be written), the usage of a group
/// given without its subcommand on stderr (2), otherwise one line (2).
/// The one-line usage error of a command line, if it does not parse
/// (`incal batch` checks the procedure's options once, before any
/// recording is reduced).
pub(crate) fn usage_error(args: &[OsString]) -> Option<String> {
    match parse(args) {
        Ok(_) => None,
        Err(e) => Some(usage_message(&e, &command_path(&Cli::command(), args))),
    }
}

fn parse_failure(e: &clap::Error, args: &[OsString]) -> u8 {
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion if embed::capturing() => {
            let mut out = embed::stdout();
            let _ = write!(out, "{}", e.render());
            0
        }
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let printed = e.print().and_then(|()| std::io::stdout().flush());
            if printed.is_ok() {
                0
            } else {
                1
            }
        }
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            // clap sends this one to stderr: the usage and the commands.
            if embed::capturing() {
                say(&usage_message(e, &command_path(&Cli::command(), args)));
            } else {
                let _ = e.print();
            }
            2
        }
        _ => {
            let command = command_path(&Cli::command(), args);
            say(&usage_message(e, &command));
            2
        }
    }
}

/// Run `incal` with `args` (the program name first) and return the exit
/// code: 0 success, 2 bad usage or input, 1 any other failure (crate docs).
/// The binary's `main` is this on the process arguments.
pub fn main_from(args: &[OsString]) -> u8 {
    let cli = match parse(args) {
        Ok(c) => c,
        Err(e) => return parse_failure(&e, args),
    };
    match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            say(&e.to_string());
            e.exit_code()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The usage message for `args`, which must fail to parse.
    fn message(args: &[&str]) -> String {
        let args: Vec<OsString> = args.iter().map(OsString::from).collect();
        let e = allow_negative_values(Cli::command())
            .try_get_matches_from(&args)
            .unwrap_err();
        usage_message(&e, &command_path(&Cli::command(), &args))
    }

    #[test]
    fn command_path_follows_subcommands_only() {
        let path = |args: &[&str]| {
            let args: Vec<OsString> = args.iter().map(OsString::from).collect();
            command_path(&Cli::command(), &args)
        };
        assert_eq!(path(&["incal"]), "incal");
        assert_eq!(path(&["incal", "--bogus"]), "incal");
        assert_eq!(path(&["incal", "tumble", "--mount", "x"]), "incal tumble");
        assert_eq!(
            path(&["incal", "simulate", "misalign", "gyro", "--seed", "1"]),
            "incal simulate misalign gyro"
        );
        assert_eq!(path(&["incal", "tumbel", "tumble"]), "incal");
    }

    #[test]
    fn messages_name_the_option_in_one_line() {
        assert_eq!(
            message(&["incal", "tumble", "--input", "x.csv"]),
            "missing required option --mount <MOUNT> (see 'incal tumble --help')"
        );
        assert_eq!(
            message(&["incal", "tumble", "--mount", "x", "--input", "x.csv"]),
            "invalid value 'x' for '--mount <MOUNT>' (possible values: pendulum, gate)"
        );
        assert_eq!(
            message(&["incal", "tumble", "--bogus"]),
            "unknown option '--bogus' (see 'incal tumble --help')"
        );
        assert_eq!(
            message(&["incal", "simulate", "tumbel"]),
            "unknown command 'tumbel', did you mean 'tumble'? (see 'incal simulate --help')"
        );
        let m = message(&["incal", "simulate", "tumble", "--seed", "x"]);
        assert!(
            m.starts_with("invalid value 'x' for '--seed <SEED>': "),
            "{m}"
        );
        assert_eq!(m.lines().count(), 1);
    }

    #[test]
    fn one_line_joins_lines() {
        assert_eq!(one_line("a\n\n  b\n"), "a; b");
        assert_eq!(
            one_line("cannot be used with:\n\t--x\n"),
            "cannot be used with: --x"
        );
        assert_eq!(one_line("plain"), "plain");
    }
}
