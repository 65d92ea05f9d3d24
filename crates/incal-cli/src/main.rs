//! The `incal` binary: [`incal_cli::main_from`] on the process arguments.

use std::process::ExitCode;

fn main() -> ExitCode {
    incal_cli::restore_sigpipe();
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    ExitCode::from(incal_cli::main_from(&args))
}
