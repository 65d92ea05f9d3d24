//! CSV input: a header row, then data rows; lines starting with `#` are
//! comments; every problem names the file and the line.

use std::collections::HashMap;
use std::path::Path;

use crate::error::{CliError, CliResult};
use crate::io;

/// A CSV file read into memory, with the line number of every row.
///
/// The cells are kept in one text buffer with an end offset per cell (no
/// allocation per field): a 720 000-row file costs two allocations that
/// grow, not two million small strings.
#[derive(Debug, Clone)]
pub struct Table {
    /// Path as given by the user (for messages).
    pub path: String,
    /// SHA-256 of the file's bytes (lower-case hex), for the result's inputs.
    pub sha256: String,
    headers: Vec<String>,
    index: HashMap<String, usize>,
    /// File line of each data row.
    lines: Vec<u32>,
    /// Every cell's text, row after row.
    text: String,
    /// End offset in `text` of every cell (`row * width + col`).
    ends: Vec<u32>,
}

/// A reader that hashes every byte it passes on (SHA-256), so a file is
/// hashed while it is parsed, without a second copy of it in memory.
struct Hashing<R> {
    inner: R,
    hasher: sha2::Sha256,
}

impl<R: std::io::Read> std::io::Read for Hashing<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use sha2::Digest;
        let n = self.inner.read(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
}

impl Table {
    /// Read `path` (`-`: standard input, named `<stdin>` in messages; a
    /// leading UTF-8 byte-order mark is skipped). Fails (exit 2) when it
    /// cannot be read, is empty, has no data rows, repeats a column name or
    /// has a row of the wrong width.
    ///
    /// The file is parsed as it is read (and hashed on the way): memory is
    /// the cells' text plus 4 bytes per cell and per row, not two copies of
    /// the file.
    pub fn read(path: &Path) -> CliResult<Table> {
        use sha2::Digest;
        let name = io::display_name(path);
        let cannot = |e: std::io::Error| CliError::Input(format!("{name}: cannot read: {e}"));
        let (inner, size): (Box<dyn std::io::Read>, usize) = if io::is_dash(path) {
            (Box::new(std::io::stdin().lock()), 0)
        } else {
            let f = std::fs::File::open(path).map_err(cannot)?;
            let size = f.metadata().map_or(0, |m| m.len() as usize);
            (Box::new(f), size)
        };
        let mut hashing = Hashing {
            inner,
            hasher: sha2::Sha256::new(),
        };
        let mut t = Self::from_reader(&name, &mut hashing, size)?;
        // Hash whatever the CSV reader left unread (nothing, normally).
        std::io::copy(&mut hashing, &mut std::io::sink()).map_err(cannot)?;
        let d = hashing.hasher.finalize();
        t.sha256 = d.iter().map(|b| format!("{b:02x}")).collect();
        Ok(t)
    }

    /// Parse CSV text (see [`Table::read`]).
    #[cfg(test)]
    pub fn parse(name: &str, text: &[u8]) -> CliResult<Table> {
        let mut t = Self::from_reader(name, text, text.len())?;
        t.sha256 = crate::output::sha256_hex(text);
        Ok(t)
    }

    /// Parse CSV from `source` (`size_hint`: its length in bytes when
    /// known, to size the text buffer once). The SHA-256 is left empty.
    fn from_reader(name: &str, source: impl std::io::Read, size_hint: usize) -> CliResult<Table> {
        use std::io::BufRead;
        let mut buffered = std::io::BufReader::with_capacity(1 << 16, source);
        // A UTF-8 byte-order mark (spreadsheet exports) is skipped.
        if buffered
            .fill_buf()
            .map_err(|e| CliError::Input(format!("{name}: cannot read: {e}")))?
            .starts_with(b"\xEF\xBB\xBF")
        {
            buffered.consume(3);
        }
        let text = buffered;
        let err = |line: Option<usize>, msg: String| {
            CliError::Input(match line {
                Some(l) => format!("{name}:{l}: {msg}"),
                None => format!("{name}: {msg}"),
            })
        };
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .comment(Some(b'#'))
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(text);
        let mut header = csv::StringRecord::new();
        loop {
            match reader.read_record(&mut header) {
                Ok(false) => return Err(err(None, "empty file (expected a header row)".into())),
                Err(e) => {
                    let line = e.position().map(|p| p.line() as usize);
                    return Err(err(line, format!("not valid CSV: {}", short_csv_error(&e))));
                }
                Ok(true) if header.iter().all(|f| f.is_empty()) => continue,
                Ok(true) => break,
            }
        }
        let header_line = header.position().map_or(1, |p| p.line() as usize);
        let headers: Vec<String> = header.iter().map(|h| h.to_string()).collect();
        let mut index = HashMap::new();
        for (k, h) in headers.iter().enumerate() {
            if h.is_empty() {
                return Err(err(
                    Some(header_line),
                    format!("empty column name in column {}", k + 1),
                ));
            }
            if index.insert(h.clone(), k).is_some() {
                return Err(err(
                    Some(header_line),
                    format!("column '{h}' appears twice"),
                ));
            }
        }
        let width = headers.len();
        let mut lines: Vec<u32> = Vec::new();
        // The cells are at most the file: one allocation, no regrowth.
        let mut cells = String::with_capacity(size_hint);
        let mut ends: Vec<u32> = Vec::new();
        let too_big = || {
            err(
                None,
                "too large for one table (at most 4 GB of cells and 4e9 lines)".into(),
            )
        };
        let mut rec = csv::ByteRecord::new();
        loop {
            let more = reader.read_byte_record(&mut rec).map_err(|e| {
                let line = e.position().map(|p| p.line() as usize);
                err(line, format!("not valid CSV: {}", short_csv_error(&e)))
            })?;
            if !more {
                break;
            }
            let line = rec.position().map_or(0, |p| p.line() as usize);
            if rec.iter().all(|f| f.is_empty()) {
                continue;
            }
            if rec.len() != width {
                return Err(err(
                    Some(line),
                    format!("{} fields, but the header has {width}", rec.len()),
                ));
            }
            for f in rec.iter() {
                let t =
                    std::str::from_utf8(f).map_err(|_| err(Some(line), "invalid UTF-8".into()))?;
                cells.push_str(t);
                ends.push(u32::try_from(cells.len()).map_err(|_| too_big())?);
            }
            lines.push(u32::try_from(line).map_err(|_| too_big())?);
            if lines.len() == 256 && size_hint > 0 {
                // Size the row and cell indexes from the first rows' length
                // (plus 10 %), instead of doubling (which holds up to three
                // times the final size while it copies).
                let per_row = (cells.len() as f64 / 256.0).max(1.0);
                let rows = (size_hint as f64 / per_row * 1.1) as usize;
                lines.reserve(rows.saturating_sub(lines.len()));
                ends.reserve((rows * width).saturating_sub(ends.len()));
            }
        }
        if lines.is_empty() {
            return Err(err(None, "no data rows after the header".into()));
        }
        Ok(Table {
            path: name.to_string(),
            sha256: String::new(),
            headers,
            index,
            lines,
            text: cells,
            ends,
        })
    }

    /// The record of this file as an input of a result.
    pub fn input_file(&self, role: &str) -> incal::document::InputFile {
        // The path as given: `-` for standard input (named `<stdin>` in messages).
        let path = if self.path == "<stdin>" {
            "-"
        } else {
            &self.path
        };
        crate::output::input_file(role, path, self.sha256.clone(), Some(self.lines.len()))
    }

    /// Number of data rows (at least 1 after a successful read).
    pub fn row_count(&self) -> usize {
        self.lines.len()
    }

    /// Index of a required column.
    pub fn column(&self, name: &str) -> CliResult<usize> {
        self.index.get(name).copied().ok_or_else(|| {
            CliError::Input(format!(
                "{}: missing column '{name}' (columns: {})",
                self.path,
                self.headers.join(", ")
            ))
        })
    }

    /// Index of an optional column.
    pub fn opt_column(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    /// File line of data row `row`.
    pub fn line(&self, row: usize) -> usize {
        self.lines[row] as usize
    }

    /// Raw text of a cell.
    pub fn text(&self, row: usize, col: usize) -> &str {
        let k = row * self.headers.len() + col;
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.text[start..self.ends[k] as usize]
    }

    /// A finite number from a cell, or an error naming file, line, column.
    /// Magnitudes beyond [`MAX_ABS_VALUE`] are refused as out of range: no
    /// instrument reading, time or angle is that large, and sums of their
    /// squares would overflow.
    pub fn f64(&self, row: usize, col: usize) -> CliResult<f64> {
        let text = self.text(row, col);
        let shown = crate::output::clip(text);
        let v: f64 = text.trim().parse().map_err(|_| {
            self.error_at(
                row,
                format!("column '{}': '{shown}' is not a number", self.headers[col]),
            )
        })?;
        if !v.is_finite() {
            return Err(self.error_at(
                row,
                format!(
                    "column '{}': '{shown}' is not a finite number",
                    self.headers[col]
                ),
            ));
        }
        if v.abs() > MAX_ABS_VALUE {
            return Err(self.error_at(
                row,
                format!(
                    "column '{}': {shown} is out of range (|value| <= 1e15)",
                    self.headers[col]
                ),
            ));
        }
        Ok(v)
    }

    /// An error at data row `row`.
    pub fn error_at(&self, row: usize, msg: String) -> CliError {
        CliError::Input(format!("{}:{}: {msg}", self.path, self.line(row)))
    }
}

/// Largest magnitude of a number read from a CSV cell.
pub const MAX_ABS_VALUE: f64 = 1e15;

fn short_csv_error(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::Utf8 { .. } => "invalid UTF-8".into(),
        _ => e
            .to_string()
            .lines()
            .next()
            .unwrap_or("parse error")
            .to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_line_of_bad_number() {
        let t = Table::parse("f.csv", b"# note\nangle_deg,output\n0,1\n30,abc\n").unwrap();
        let c = t.column("output").unwrap();
        assert!(t.f64(0, c).is_ok());
        let e = t.f64(1, c).unwrap_err().to_string();
        assert_eq!(e, "f.csv:4: column 'output': 'abc' is not a number");
    }

    #[test]
    fn nan_and_inf_are_refused() {
        let t = Table::parse("f.csv", b"a\nNaN\ninf\n").unwrap();
        assert!(t.f64(0, 0).unwrap_err().to_string().contains("f.csv:2"));
        assert!(t
            .f64(1, 0)
            .unwrap_err()
            .to_string()
            .contains("not a finite"));
    }

    #[test]
    fn empty_and_header_only_are_refused() {
        assert!(Table::parse("f.csv", b"")
            .unwrap_err()
            .to_string()
            .contains("empty file"));
        assert!(Table::parse("f.csv", b"a,b\n")
            .unwrap_err()
            .to_string()
            .contains("no data rows"));
        let e = Table::parse("f.csv", b"a,b\n1,2\n3\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("f.csv:3:"), "{e}");
    }

    #[test]
    fn missing_column_is_named() {
        let t = Table::parse("f.csv", b"angle_deg\n1\n").unwrap();
        let e = t.column("output").unwrap_err().to_string();
        assert!(e.contains("missing column 'output'"));
    }
}
