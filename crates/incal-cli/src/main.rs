//! `incal`: the command-line tool of the incal calibration library.
//!
//! Thin by design: parse options, read files, call the core, print. Exit
//! codes: 0 ok, 1 failure, 2 bad usage or bad input (one line on stderr
//! naming the file, the line and the problem).

mod commands;
mod error;
mod input;
mod io;
mod output;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::error::CliResult;

/// Data reduction for inertial-instrument calibration.
#[derive(Parser, Debug)]
#[command(name = "incal", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Simulate virtual instruments on every rig, calibrate, and print estimate, truth and uncertainty.
    Demo(commands::demo::Args),
    /// Calibrate an accelerometer from a dividing-head tumble test (seed 000, GJB 1037A).
    Tumble(commands::tumble::Args),
    /// Calibrate an accelerometer on a precision centrifuge: radius, K2/K3, cross-axis and cross-coupling terms (seed 001).
    Centrifuge(commands::centrifuge::Args),
    /// Design a test plan and predict the uncertainty of every coefficient before the test.
    #[command(subcommand)]
    Plan(PlanCommand),
    /// Simulate a rig from a known truth and write the input CSV of the matching procedure.
    #[command(subcommand)]
    Simulate(SimulateCommand),
    /// Misalignment separation: gyro on a rate table, accelerometer on a vertical face (seed 003).
    #[command(subcommand)]
    Misalign(commands::misalign::Command),
    /// Compare the coefficients of two result files: difference, per mille and En.
    Compare(commands::compare::Args),
    /// Gyro-free inertial unit of six (or more) accelerometers: calibrate K0 and Ks, solve motion (seed 004).
    #[command(subcommand)]
    Gfimu(GfimuCommand),
}

#[derive(Subcommand, Debug)]
enum GfimuCommand {
    /// Calibrate every accelerometer's K0 and Ks from static positions (six-position test or any >= 6 orientations).
    Calibrate(commands::gfimu::CalibrateArgs),
    /// Solve a time series of outputs for f0, angular acceleration and angular rate.
    Solve(commands::gfimu::SolveArgs),
}

#[derive(Subcommand, Debug)]
enum PlanCommand {
    /// Tumble plan: GJB 12-point, small-angle 12-point for a range, or N-point.
    Tumble(commands::tumble::PlanArgs),
    /// Misalignment plan: predicted u of each angle for a configuration set.
    Misalign(commands::misalign::PlanArgs),
}

#[derive(Subcommand, Debug)]
enum SimulateCommand {
    /// Dividing-head tumble test.
    Tumble(commands::tumble::SimArgs),
    /// Gyro-free unit: six-position static test or rate-table motion.
    Gfimu(commands::gfimu::SimArgs),
    /// Misalignment test: gyro on a rate table or accelerometer on a vertical face.
    #[command(subcommand)]
    Misalign(commands::misalign::SimCommand),
    /// Precision centrifuge test (IA, PA, OA radial and 45-degree cross positions).
    Centrifuge(commands::centrifuge::SimArgs),
}

fn run(cli: Cli) -> CliResult<()> {
    match cli.command {
        Command::Demo(a) => commands::demo::run(&a),
        Command::Tumble(a) => commands::tumble::run(&a),
        Command::Centrifuge(a) => commands::centrifuge::run(&a),
        Command::Plan(PlanCommand::Tumble(a)) => commands::tumble::plan(&a),
        Command::Simulate(SimulateCommand::Tumble(a)) => commands::tumble::simulate(&a),
        Command::Simulate(SimulateCommand::Centrifuge(a)) => commands::centrifuge::simulate(&a),
        Command::Compare(a) => commands::compare::run(&a),
        Command::Gfimu(GfimuCommand::Calibrate(a)) => commands::gfimu::run_calibrate(&a),
        Command::Gfimu(GfimuCommand::Solve(a)) => commands::gfimu::run_solve(&a),
        Command::Simulate(SimulateCommand::Gfimu(a)) => commands::gfimu::simulate(&a),
        Command::Misalign(c) => commands::misalign::run(&c),
        Command::Plan(PlanCommand::Misalign(a)) => commands::misalign::plan(&a),
        Command::Simulate(SimulateCommand::Misalign(c)) => commands::misalign::simulate(&c),
    }
}

/// Die quietly on a closed pipe (`incal demo | head`), as Unix filters do,
/// instead of panicking inside `println!`.
fn restore_sigpipe() {
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
fn allow_negative_values(cmd: clap::Command) -> clap::Command {
    // Command-level, so it also reaches the args clap builds lazily.
    cmd.allow_hyphen_values(true)
        .mut_subcommands(allow_negative_values)
}

fn parse() -> Result<Cli, clap::Error> {
    use clap::{CommandFactory, FromArgMatches};
    let matches = allow_negative_values(Cli::command()).try_get_matches()?;
    Cli::from_arg_matches(&matches)
}

fn main() -> ExitCode {
    restore_sigpipe();
    let cli = match parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            // One line: clap's first line, without its "error: " prefix.
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("bad usage");
            let first = first.strip_prefix("error: ").unwrap_or(first);
            eprintln!("incal: {first} (see 'incal --help')");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("incal: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
