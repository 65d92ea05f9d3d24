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
    header: Header,
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
        let mut lines: Vec<u32> = Vec::new();
        // The cells are at most the file: one allocation, no regrowth.
        let mut cells = String::with_capacity(size_hint);
        let mut ends: Vec<u32> = Vec::new();
        let too_big = || {
            CliError::Input(format!(
                "{name}: too large for one table (at most 4 GB of cells and 4e9 lines)"
            ))
        };
        let header = stream(
            name,
            source,
            |_| Ok(()),
            |_, row| {
                for col in 0..row.width() {
                    cells.push_str(row.text(col));
                    ends.push(u32::try_from(cells.len()).map_err(|_| too_big())?);
                }
                lines.push(u32::try_from(row.line()).map_err(|_| too_big())?);
                if lines.len() == 256 && size_hint > 0 {
                    // Size the row and cell indexes from the first rows' length
                    // (plus 10 %), instead of doubling (which holds up to three
                    // times the final size while it copies).
                    let per_row = (cells.len() as f64 / 256.0).max(1.0);
                    let rows = (size_hint as f64 / per_row * 1.1) as usize;
                    lines.reserve(rows.saturating_sub(lines.len()));
                    ends.reserve((rows * row.width()).saturating_sub(ends.len()));
                }
                Ok(())
            },
        )?;
        Ok(Table {
            path: name.to_string(),
            sha256: String::new(),
            header,
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
        self.header.column(name)
    }

    /// Index of an optional column.
    pub fn opt_column(&self, name: &str) -> Option<usize> {
        self.header.opt_column(name)
    }

    /// File line of data row `row`.
    pub fn line(&self, row: usize) -> usize {
        self.lines[row] as usize
    }

    /// Raw text of a cell.
    pub fn text(&self, row: usize, col: usize) -> &str {
        let k = row * self.header.headers.len() + col;
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.text[start..self.ends[k] as usize]
    }

    /// A finite number from a cell, or an error naming file, line, column.
    /// Magnitudes beyond [`MAX_ABS_VALUE`] are refused as out of range: no
    /// instrument reading, time or angle is that large, and sums of their
    /// squares would overflow.
    pub fn f64(&self, row: usize, col: usize) -> CliResult<f64> {
        number(
            &self.path,
            self.line(row),
            &self.header.headers[col],
            self.text(row, col),
        )
    }

    /// An error at data row `row`.
    pub fn error_at(&self, row: usize, msg: String) -> CliError {
        CliError::Input(format!("{}:{}: {msg}", self.path, self.line(row)))
    }
}

/// Largest magnitude of a number read from a CSV cell.
pub const MAX_ABS_VALUE: f64 = 1e15;

/// A finite number within [`MAX_ABS_VALUE`] from the text of a cell, or
/// the error `PATH:LINE: column 'C': ...`.
fn number(path: &str, line: usize, column: &str, text: &str) -> CliResult<f64> {
    let shown = crate::output::clip(text);
    let at = |msg: String| CliError::Input(format!("{path}:{line}: column '{column}': {msg}"));
    let v: f64 = text
        .trim()
        .parse()
        .map_err(|_| at(format!("'{shown}' is not a number")))?;
    if !v.is_finite() {
        return Err(at(format!("'{shown}' is not a finite number")));
    }
    if v.abs() > MAX_ABS_VALUE {
        return Err(at(format!("{shown} is out of range (|value| <= 1e15)")));
    }
    Ok(v)
}

/// The header of a CSV read row by row ([`stream`]).
#[derive(Debug, Clone)]
pub struct Header {
    /// Path as given by the user (for messages).
    pub path: String,
    headers: Vec<String>,
    index: HashMap<String, usize>,
}

impl Header {
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
}

/// One data row of a CSV read row by row ([`stream`]); every cell is UTF-8.
pub struct Row<'a> {
    header: &'a Header,
    rec: &'a csv::ByteRecord,
    line: usize,
}

impl Row<'_> {
    /// File line of the row.
    pub fn line(&self) -> usize {
        self.line
    }
    /// Number of cells (the header's width).
    pub fn width(&self) -> usize {
        self.rec.len()
    }
    /// Raw text of a cell.
    pub fn text(&self, col: usize) -> &str {
        // Checked to be UTF-8 before the row is handed out.
        std::str::from_utf8(&self.rec[col]).unwrap_or("")
    }
    /// A finite number from a cell (as [`Table::f64`]).
    pub fn f64(&self, col: usize) -> CliResult<f64> {
        number(
            &self.header.path,
            self.line,
            &self.header.headers[col],
            self.text(col),
        )
    }
    /// An error at this row.
    pub fn error(&self, msg: String) -> CliError {
        CliError::Input(format!("{}:{}: {msg}", self.header.path, self.line))
    }
}

/// Read CSV from `source` row by row: `on_header` sees the header once,
/// `on_row` every data row with what `on_header` returned (comments `#`, blank rows and a UTF-8 BOM
/// skipped; a row of the wrong width, invalid UTF-8 or no data row at all
/// refused with the file and line). Returns the header; nothing of the
/// file is kept.
pub fn stream<C>(
    name: &str,
    source: impl std::io::Read,
    on_header: impl FnOnce(&Header) -> CliResult<C>,
    mut on_row: impl FnMut(&C, &Row) -> CliResult<()>,
) -> CliResult<Header> {
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
        .from_reader(buffered);
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
    let head = Header {
        path: name.to_string(),
        headers,
        index,
    };
    let ctx = on_header(&head)?;
    let mut rec = csv::ByteRecord::new();
    let mut rows = 0usize;
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
        if rec.iter().any(|f| std::str::from_utf8(f).is_err()) {
            return Err(err(Some(line), "invalid UTF-8".into()));
        }
        on_row(
            &ctx,
            &Row {
                header: &head,
                rec: &rec,
                line,
            },
        )?;
        rows += 1;
    }
    if rows == 0 {
        return Err(err(None, "no data rows after the header".into()));
    }
    Ok(head)
}

/// A file read row by row ([`stream_file`]): what a result records of it.
#[derive(Debug, Clone)]
pub struct Streamed {
    /// Path as given by the user (for messages).
    pub path: String,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
    /// Data rows.
    pub rows: usize,
}

impl Streamed {
    /// The record of this file as an input of a result.
    pub fn input_file(&self, role: &str) -> incal::document::InputFile {
        let path = if self.path == "<stdin>" {
            "-"
        } else {
            &self.path
        };
        crate::output::input_file(role, path, self.sha256.clone(), Some(self.rows))
    }
}

/// [`stream`] the file `path` (`-`: standard input), hashing it on the way.
pub fn stream_file<C>(
    path: &Path,
    on_header: impl FnOnce(&Header) -> CliResult<C>,
    mut on_row: impl FnMut(&C, &Row) -> CliResult<()>,
) -> CliResult<Streamed> {
    use sha2::Digest;
    let name = io::display_name(path);
    let cannot = |e: std::io::Error| CliError::Input(format!("{name}: cannot read: {e}"));
    let inner: Box<dyn std::io::Read> = if io::is_dash(path) {
        Box::new(std::io::stdin().lock())
    } else {
        Box::new(std::fs::File::open(path).map_err(cannot)?)
    };
    let mut hashing = Hashing {
        inner,
        hasher: sha2::Sha256::new(),
    };
    let mut rows = 0;
    stream(&name, &mut hashing, on_header, |c, r| {
        rows += 1;
        on_row(c, r)
    })?;
    std::io::copy(&mut hashing, &mut std::io::sink()).map_err(cannot)?;
    let d = hashing.hasher.finalize();
    Ok(Streamed {
        path: name,
        sha256: d.iter().map(|b| format!("{b:02x}")).collect(),
        rows,
    })
}

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
