//! The one runner of every reducing command: open the input, read and
//! reduce it through the core's procedure shape, render or write the
//! result (identity, limits, JSON or text).

use std::path::Path;

use incal::procedures::{reduce_source, Procedure, Progress};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::ResultArgs;

/// Read `input` (`-`: standard input) with `read`, reduce it by procedure
/// `P` with `options`, and emit the result as `result` says.
pub fn reduce<P: Procedure>(
    input: &Path,
    read: &ReadArgs,
    options: &P::Options,
    result: &ResultArgs,
    progress: &dyn Progress,
) -> CliResult<()> {
    let read = read.options()?;
    let src = incal_io::open(input)?;
    let doc =
        reduce_source::<P, _>(&src.name, src.reader, &read, options, progress).map_err(core)?;
    result.emit(doc)
}

/// `incal simulate …` of a procedure with a typed simulator: the options
/// are refused before the output file is opened, then the recording is
/// streamed to `output` (standard output when `None`).
pub fn simulate<S: incal::procedures::Simulate>(
    options: &S::Options,
    output: Option<&std::path::Path>,
) -> CliResult<()> {
    S::validate(options).map_err(crate::error::core)?;
    crate::io::write_stream(output, |out| {
        S::simulate(options, out).map_err(|e| match e {
            incal::Error::Write(m) => std::io::Error::other(m),
            // A value the simulation cannot represent: bad input, not a
            // disk failure (the writer removes the half-written file).
            other => std::io::Error::new(std::io::ErrorKind::InvalidData, other.to_string()),
        })
    })
}
