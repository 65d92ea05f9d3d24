//! The one runner of every reducing command: open the input, read and
//! reduce it through the core's procedure shape, render or write the
//! result (identity, limits, JSON or text).

use std::path::Path;

use incal::procedures::{reduce_source_with, Procedure, Progress};

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
    let mc = result.monte_carlo();
    let doc =
        reduce_source_with::<P, _>(&src.name, src.reader, &read, options, progress, mc.as_ref())
            .map_err(core)?;
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

/// `--truth-out FILE` of a simulator whose recording does not carry its
/// truth ([`incal::procedures::Simulate::truth`]), written after the
/// recording: the JSON the core gives, as Python's simulators return it.
pub fn write_truth<S: incal::procedures::Simulate>(
    options: &S::Options,
    path: Option<&std::path::Path>,
) -> CliResult<()> {
    let Some(path) = path else { return Ok(()) };
    if let Some(truth) = S::truth(options).map_err(crate::error::core)? {
        crate::io::write_text(
            Some(path),
            &format!("{}\n", crate::output::json_text(&truth)),
        )?;
    }
    Ok(())
}

/// The one runner of a streaming tool ([`incal::procedures::stream`]):
/// the input opened (`-` is standard input) and read with `read`, the
/// output opened before the first row (`None` or `-` is standard output),
/// the tool run. A bad row is bad input (exit 2, naming the file and
/// line; the rows before stay written); an output that cannot be written
/// is a failure (exit 1). Returns what the tool did: the command shows its
/// notes and warnings ([`show_streamed`]) as it needs.
pub fn stream<S: incal::procedures::stream::Stream>(
    model: S::Model,
    input: &std::path::Path,
    read: &incal_io::ReadOptions,
    output: Option<&std::path::Path>,
) -> CliResult<incal::procedures::stream::Streamed> {
    if read.segment.is_some() {
        return Err(crate::error::CliError::Input(
            "--segment-by: a streaming tool writes every row it reads; segment the log in a reduction".into(),
        ));
    }
    let src = incal_io::open(input)?;
    let mut out = crate::io::open_output(output)?;
    let out_name = crate::io::output_name(output);
    let done = S::stream(model, &src.name, src.reader, read, &mut out).and_then(|s| {
        std::io::Write::flush(&mut out)?;
        Ok(s)
    });
    done.map_err(|e| match e {
        incal::Error::Write(m) => {
            crate::error::CliError::Failure(anyhow::anyhow!("{out_name}: cannot write: {m}"))
        }
        other => crate::error::core(other),
    })
}

/// A streaming tool's notes (`note: …`) and warnings (`warning [code]:
/// …`) on standard error, one line each.
pub fn show_streamed(s: &incal::procedures::stream::Streamed) {
    for n in &s.notes {
        crate::embed::stderr_line(&format!("note: {n}"));
    }
    for w in &s.warnings {
        crate::embed::stderr_line(&format!("warning [{}]: {}", w.code, w.message));
    }
}
