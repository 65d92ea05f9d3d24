//! incal's commands in process, for `incal batch`: [`run_embedded`] runs
//! one command line as the binary does on this thread and returns what
//! the command would have written to standard output and standard error
//! instead of writing it, so each recording's outcome is reported whole
//! and in order.

use std::cell::RefCell;
use std::ffi::OsString;
use std::io::Write;

thread_local! {
    /// Standard output and error lines of the command running on this
    /// thread, while one runs embedded.
    static CAPTURE: RefCell<Option<(Vec<u8>, Vec<String>)>> = const { RefCell::new(None) };
}

/// What an embedded command did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Embedded {
    /// The exit code the binary would return (0, 1, 2 or 3).
    pub code: u8,
    /// What it wrote to standard output (a result document with `--json`,
    /// a simulated CSV, a plan, …).
    pub stdout: Vec<u8>,
    /// Its standard error lines, without the `incal: ` prefix (the error
    /// of a failed command is the last one; warnings before it).
    pub stderr: Vec<String>,
}

/// Run the command line `args` (program name first, as for the binary)
/// on this thread; the output is returned, not written. Files named with
/// `-o` are written as the binary writes them.
pub fn run_embedded(args: &[OsString]) -> Embedded {
    CAPTURE.with(|c| *c.borrow_mut() = Some((Vec::new(), Vec::new())));
    let code = crate::main_from(args);
    let (stdout, stderr) = CAPTURE.with(|c| c.borrow_mut().take()).unwrap_or_default();
    Embedded {
        code,
        stdout,
        stderr,
    }
}

/// True while a command runs embedded on this thread.
pub(crate) fn capturing() -> bool {
    CAPTURE.with(|c| c.borrow().is_some())
}

/// One line for standard error (without `incal: `): kept when embedded,
/// else written.
///
/// Control characters (ESC, a carriage return, a bell from a file name or
/// a stored text) are shown as `?`, so nothing a user's data holds reaches
/// the terminal raw.
pub(crate) fn stderr_line(line: &str) {
    let line: String = line
        .chars()
        .map(|c| match c {
            '\t' => ' ',
            c if c.is_control() => '?',
            c => c,
        })
        .collect();
    let line = line.as_str();
    let kept = CAPTURE.with(|c| match c.borrow_mut().as_mut() {
        Some((_, err)) => {
            err.push(line.to_string());
            true
        }
        None => false,
    });
    if !kept {
        let _ = writeln!(std::io::stderr().lock(), "incal: {line}");
    }
}

/// Standard output: the process's, or the embedded command's buffer.
pub(crate) fn stdout() -> Box<dyn Write> {
    if capturing() {
        Box::new(Captured)
    } else {
        Box::new(std::io::stdout().lock())
    }
}

/// A writer appending to the embedded command's standard output.
struct Captured;

impl Write for Captured {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        CAPTURE.with(|c| {
            if let Some((out, _)) = c.borrow_mut().as_mut() {
                out.extend_from_slice(buf);
            }
        });
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
