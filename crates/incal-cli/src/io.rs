//! Reading input files (or standard input for `-`) and writing output files
//! (or standard output), with every failure turned into one line that names
//! the file: unreadable input is bad input (exit 2), an unwritable output is
//! a failure (exit 1).

use std::io::Write;
use std::path::Path;

use incal_io::is_dash;

use crate::error::{CliError, CliResult};

/// The display name and the bytes of the file `path`; `-` reads standard
/// input (display name `<stdin>`). A UTF-8 byte-order mark at the start is
/// stripped. Fails (exit 2) with `NAME: cannot read: ...`.
pub fn read_bytes(path: &Path) -> CliResult<(String, Vec<u8>)> {
    read_hashed(path).map(|(name, bytes, _)| (name, bytes))
}

/// As [`read_bytes`], with the SHA-256 of the bytes as stored (BOM
/// included, so it equals `sha256sum FILE`) for the result's inputs. A
/// document larger than [`incal_io::MAX_DOCUMENT_BYTES`] is refused.
pub fn read_hashed(path: &Path) -> CliResult<(String, Vec<u8>, String)> {
    incal_io::read_hashed(path).map_err(|e| CliError::Input(e.to_string()))
}

/// As [`read_bytes`], checked to be UTF-8; invalid UTF-8 fails (exit 2) with
/// `NAME:LINE: not valid UTF-8`.
pub fn read_text(path: &Path) -> CliResult<(String, String)> {
    let (name, bytes) = read_bytes(path)?;
    match String::from_utf8(bytes) {
        Ok(text) => Ok((name, text)),
        Err(e) => {
            let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
            Err(CliError::Input(format!("{name}:{line}: not valid UTF-8")))
        }
    }
}

/// The name of an output in messages: its path, or `stdout` for `None`
/// and `-`.
pub fn output_name(path: Option<&Path>) -> String {
    match path {
        Some(p) if !is_dash(p) => p.display().to_string(),
        _ => "stdout".to_string(),
    }
}

/// A buffered writer to the file `path`, or to standard output when `path`
/// is `None` or `-` (for outputs streamed row by row). A file that cannot
/// be created is a failure (exit 1): `PATH: cannot write: ...`.
pub fn open_output(path: Option<&Path>) -> CliResult<std::io::BufWriter<Box<dyn Write>>> {
    let out: Box<dyn Write> = match path {
        Some(p) if !is_dash(p) => Box::new(std::fs::File::create(p).map_err(|e| {
            CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", p.display()))
        })?),
        _ => crate::embed::stdout(),
    };
    Ok(std::io::BufWriter::with_capacity(1 << 16, out))
}

/// Write `text` to the file `path`, or to standard output when `path` is
/// `None` or `-`. Any write or flush error is a failure (exit 1) with one
/// line: `stdout: ...` or `PATH: cannot write: ...`.
///
/// A regular file (or a new one) is written beside its place and renamed
/// into it once whole, so a full disk leaves neither an empty nor a half
/// file, and an earlier file of that name stays as it was; a device
/// (`/dev/stdout`, `/dev/full`) is written in place.
pub fn write_text(path: Option<&Path>, text: &str) -> CliResult<()> {
    match path {
        Some(p) if !is_dash(p) => {
            let failed = |e: std::io::Error| {
                CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", p.display()))
            };
            let direct = || -> std::io::Result<()> {
                let mut file = std::fs::File::create(p)?;
                file.write_all(text.as_bytes())?;
                file.flush()
            };
            let regular = std::fs::metadata(p).map_or(true, |m| m.is_file());
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
            let (true, Some(name)) = (regular, name) else {
                return direct().map_err(failed);
            };
            let tmp = p.with_file_name(format!(".{name}.incal-{}", std::process::id()));
            let whole = || -> std::io::Result<()> {
                let mut file = std::fs::File::create(&tmp)?;
                file.write_all(text.as_bytes())?;
                file.sync_all()?;
                std::fs::rename(&tmp, p)
            };
            match whole() {
                Ok(()) => Ok(()),
                Err(e) => {
                    let _ = std::fs::remove_file(&tmp);
                    // A directory that takes no new file but a writable
                    // file in it: written in place.
                    if e.kind() == std::io::ErrorKind::PermissionDenied {
                        return direct().map_err(failed);
                    }
                    Err(failed(e))
                }
            }
        }
        _ => {
            let mut out = crate::embed::stdout();
            out.write_all(text.as_bytes())
                .and_then(|()| out.flush())
                .map_err(|e| CliError::Failure(anyhow::anyhow!("stdout: {e}")))
        }
    }
}

/// Stream an output through `write` to the file `path`, or to standard
/// output when `path` is `None` or `-`: the writer is buffered and flushed
/// here. Any failure, opening, writing (a full disk) or a value the
/// writer refuses, is a failure (exit 1) with one line naming the output.
pub fn write_stream<W>(path: Option<&Path>, write: W) -> CliResult<()>
where
    W: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    write_stream_checked(path, true, write)
}

/// [`write_stream`] for a binary stream (`noise` simulation in f32/f64):
/// no text cells to check.
pub fn write_binary_stream<W>(path: Option<&Path>, write: W) -> CliResult<()>
where
    W: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    write_stream_checked(path, false, write)
}

fn write_stream_checked<W>(path: Option<&Path>, check: bool, write: W) -> CliResult<()>
where
    W: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let name = output_name(path);
    if !check {
        let mut out = open_output(path)?;
        return write(&mut out)
            .and_then(|()| out.flush())
            .map_err(|e| CliError::Failure(anyhow::anyhow!("{name}: cannot write: {e}")));
    }
    let out = open_output(path)?;
    let mut guard = FiniteGuard {
        inner: out,
        cell: Vec::with_capacity(16),
        line: 1,
        found: None,
    };
    let r = write(&mut guard).and_then(|()| guard.flush());
    if let Some((line, token)) = guard.found.take() {
        // Half a file with inf in it is worse than none.
        drop(guard);
        if let Some(p) = path.filter(|p| !is_dash(p)) {
            let _ = std::fs::remove_file(p);
        }
        return Err(CliError::Input(format!(
            "{name}: the simulation gave a value incal cannot read back ({token}: not finite, or beyond ±1e15) on line {line}: an option is outside what the simulator can represent (nothing written)"
        )));
    }
    match r {
        // A writer that refuses a value it cannot write (non-finite) says
        // so with InvalidData: an option out of range, not a disk failure.
        Err(e) if e.kind() == std::io::ErrorKind::InvalidData => {
            drop(guard);
            if let Some(p) = path.filter(|p| !is_dash(p)) {
                let _ = std::fs::remove_file(p);
            }
            Err(CliError::Input(format!(
                "{name}: {e}: an option is outside what the simulator can represent (nothing written)"
            )))
        }
        r => r.map_err(|e| CliError::Failure(anyhow::anyhow!("{name}: cannot write: {e}"))),
    }
}

/// A writer that refuses a CSV cell spelling a non-finite number (`NaN`,
/// `inf`, `-inf`) or a number beyond ±10¹⁵ (which incal's own reader
/// refuses): a simulator must never write one, whatever its options
/// (a hardening guard). Cells are split at `,`, `;`, tab and line ends; a
/// cell longer than 40 bytes is no such token.
struct FiniteGuard<W: Write> {
    inner: W,
    cell: Vec<u8>,
    line: usize,
    found: Option<(usize, String)>,
}

/// True for a cell that reads as a number beyond [`incal_io::MAX_ABS_VALUE`].
/// Only a cell with an exponent or 16 digits before its point can be one,
/// so the common cell is never parsed.
fn beyond_range(t: &[u8]) -> bool {
    let digits = t
        .iter()
        .skip_while(|b| matches!(b, b'-' | b'+'))
        .take_while(|b| b.is_ascii_digit())
        .count();
    if digits < 16 && !t.iter().any(|b| matches!(b, b'e' | b'E')) {
        return false;
    }
    std::str::from_utf8(t)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .is_some_and(|v| v.abs() > incal_io::MAX_ABS_VALUE)
}

impl<W: Write> FiniteGuard<W> {
    fn end_cell(&mut self) {
        let t = self.cell.trim_ascii();
        let bad = matches!(
            t.to_ascii_lowercase().as_slice(),
            b"nan"
                | b"+nan"
                | b"-nan"
                | b"inf"
                | b"+inf"
                | b"-inf"
                | b"infinity"
                | b"+infinity"
                | b"-infinity"
        ) || beyond_range(t);
        if bad && self.found.is_none() {
            self.found = Some((self.line, String::from_utf8_lossy(t).into_owned()));
        }
        self.cell.clear();
    }
}

impl<W: Write> Write for FiniteGuard<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        for &b in buf {
            match b {
                b',' | b';' | b'\t' | b'\r' => self.end_cell(),
                b'\n' => {
                    self.end_cell();
                    self.line += 1;
                }
                _ if self.cell.len() < 40 => self.cell.push(b),
                _ => {}
            }
        }
        if self.found.is_some() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "a non-finite value in the output",
            ));
        }
        self.inner.write_all(buf)?;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.end_cell();
        if self.found.is_some() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "a non-finite value in the output",
            ));
        }
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A fresh file path in a directory private to this test process.
    fn temp_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("incal-io-unit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn reads_a_file_by_its_path() {
        let p = temp_path("plain.csv");
        std::fs::write(&p, "a,b\n1,2\n").unwrap();
        let (name, bytes) = read_bytes(&p).unwrap();
        assert_eq!(name, p.display().to_string());
        assert_eq!(bytes, b"a,b\n1,2\n");
        let (name, text) = read_text(&p).unwrap();
        assert_eq!(name, p.display().to_string());
        assert_eq!(text, "a,b\n1,2\n");
    }

    #[test]
    fn strips_a_leading_bom_only() {
        let p = temp_path("bom.csv");
        std::fs::write(&p, b"\xEF\xBB\xBFa,b\n1,2\n").unwrap();
        assert_eq!(read_bytes(&p).unwrap().1, b"a,b\n1,2\n");
        assert_eq!(read_text(&p).unwrap().1, "a,b\n1,2\n");
        // A BOM elsewhere is data, not a mark.
        let q = temp_path("bom-inside.csv");
        std::fs::write(&q, b"a\n\xEF\xBB\xBF1\n").unwrap();
        assert_eq!(read_bytes(&q).unwrap().1, b"a\n\xEF\xBB\xBF1\n");
    }

    #[test]
    fn missing_file_is_bad_input_naming_it() {
        let p = temp_path("does-not-exist.csv");
        let e = read_bytes(&p).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let m = e.to_string();
        assert!(
            m.starts_with(&format!("{}: cannot read: ", p.display())),
            "{m}"
        );
        assert_eq!(m.lines().count(), 1);
    }

    #[test]
    fn invalid_utf8_names_file_and_line() {
        let p = temp_path("latin1.csv");
        std::fs::write(&p, b"a,b\n1,2\n3,\xB0\n").unwrap();
        let e = read_text(&p).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert_eq!(e.to_string(), format!("{}:3: not valid UTF-8", p.display()));
    }

    #[test]
    fn writes_a_file_and_replaces_it() {
        let p = temp_path("out.csv");
        write_text(Some(&p), "first\n").unwrap();
        write_text(Some(&p), "x\n").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "x\n");
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn full_device_is_a_failure_naming_it() {
        let e = write_text(Some(Path::new("/dev/full")), "angle_deg,output\n0,1\n").unwrap_err();
        assert_eq!(e.exit_code(), 1);
        let m = e.to_string();
        assert!(m.starts_with("/dev/full: cannot write: "), "{m}");
        assert!(m.contains("os error 28"), "{m}");
        assert_eq!(m.lines().count(), 1);
    }

    #[test]
    fn unwritable_path_is_a_failure_naming_it() {
        let p = temp_path("no-such-dir").join("out.csv");
        let e = write_text(Some(&p), "x\n").unwrap_err();
        assert_eq!(e.exit_code(), 1);
        assert!(
            e.to_string()
                .starts_with(&format!("{}: cannot write: ", p.display())),
            "{e}"
        );
    }
}
