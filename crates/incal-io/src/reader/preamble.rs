//! Where the header is: loggers write a preamble before it (`Fs,100`,
//! `Logging Type,0`, … then `ax,ay,az,gx,gy,gz`, as a common MPU-6050
//! logger does; instrument exports write a title, a serial, a date).
//!
//! # Rule
//! * `--header-line N` ([`ReadOptions::header_line`]): the record that
//!   starts on file line `N` is the header (refused when a cell of it is
//!   empty or a number); the records before it are the preamble.
//! * Otherwise the header is the first record, within the first
//!   [`SCAN_RECORDS`] records and [`SCAN_BYTES`] bytes, that
//!   1. has no empty cell and no cell that is a number (column names are
//!      not numbers; `Fs,100` is not a header),
//!   2. holds every header `--columns` names, and
//!   3. is followed by records of its width (up to [`FOLLOWING`] of them,
//!      counted with its delimiter), none of which passes 1: `Device,MPU6050`
//!      followed by `Fs,100` and then a header of six columns (or of two)
//!      is not a header.
//!
//!   When no record qualifies the first record is the header, as for a
//!   file without a preamble, so a file that cannot be read says so about
//!   its first line as before.
//! * Each preamble record is kept as a [`PreambleLine`]: its first cell
//!   is the key, the others (joined by `, `) the value. Procedures record
//!   them in the result document; a sample rate stated there is
//!   recognised by [`stated_rate_hz`].

use std::io::Read;

use super::{detect_delimiter, parse_f64, ReadOptions, Reader};
use crate::error::{InputError, Result};

/// Most records scanned for the header when it is not the first.
pub const SCAN_RECORDS: usize = 200;
/// Most bytes scanned for the header when it is not the first.
pub const SCAN_BYTES: usize = 1 << 17;
/// Records after a candidate header that must have its width.
pub const FOLLOWING: usize = 8;

/// One line of a preamble: the record's first cell and the rest.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PreambleLine {
    /// File line the record starts on.
    pub line: usize,
    /// Its first cell.
    pub key: String,
    /// Its other cells, joined by `, ` (trailing empty cells dropped).
    pub value: String,
}

/// The sample rate (Hz) a preamble states, with the line that states it:
/// a key that is, ignoring case, spaces and punctuation, one of `fs`,
/// `fs hz`, `sample rate`, `sampling rate`, `sampling frequency`,
/// `sample frequency`, `odr`, `output data rate` (each with an optional
/// `hz` suffix), whose value is a positive finite number
/// (optionally followed by `Hz`).
pub fn stated_rate_hz(preamble: &[PreambleLine]) -> Option<(f64, usize)> {
    const KEYS: [&str; 7] = [
        "fs",
        "samplerate",
        "samplingrate",
        "samplingfrequency",
        "samplefrequency",
        "odr",
        "outputdatarate",
    ];
    preamble.iter().find_map(|p| {
        let key: String = p
            .key
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_ascii_lowercase();
        let key = key.strip_suffix("hz").unwrap_or(&key);
        if !KEYS.contains(&key) {
            return None;
        }
        let v = p.value.trim();
        let v = v
            .strip_suffix("Hz")
            .or_else(|| v.strip_suffix("hz"))
            .unwrap_or(v)
            .trim();
        parse_f64(v.as_bytes())
            .filter(|r| r.is_finite() && *r > 0.0 && *r <= 1e9)
            .map(|r| (r, p.line))
    })
}

/// What the scan meets next.
enum Peek {
    /// A record's first line (buffer positions).
    Line(usize, usize),
    /// The end of the file.
    End,
    /// [`SCAN_BYTES`] held without reaching a record.
    Limit,
}

/// A record scanned while looking for the header.
struct Scanned {
    /// Offset of its first byte from the held start of the scan.
    offset: usize,
    /// `Reader::line` before it was read.
    line_before: usize,
    /// File line it starts on.
    line: usize,
    /// Its cells, split with its own delimiter.
    cells: Vec<String>,
    /// Its first line as text (for counting fields with another delimiter).
    raw: String,
    delimiter: u8,
}

/// Fields of a line split by `delim` outside quotes.
fn width(raw: &str, delim: u8) -> usize {
    let mut quoted = false;
    1 + raw
        .bytes()
        .filter(|&c| {
            if c == b'"' {
                quoted = !quoted;
            }
            c == delim && !quoted
        })
        .count()
}

/// Rule 1: every cell a name (not empty, not a number).
fn names(r: &Scanned) -> bool {
    r.cells.iter().all(|c| is_name(c))
}

/// A cell that can name a column: not empty, not a number.
fn is_name(c: &str) -> bool {
    !c.is_empty() && parse_f64(c.as_bytes()).is_none()
}

/// The header's index among `records` under the module's rule.
fn choose(records: &[Scanned], opts: &ReadOptions) -> Option<usize> {
    let wanted: Vec<&str> = opts.columns.entries().iter().map(|e| e.source()).collect();
    for (i, r) in records.iter().enumerate() {
        if !names(r) {
            continue;
        }
        if !wanted.iter().all(|w| r.cells.iter().any(|c| c == w)) {
            continue;
        }
        // A candidate needs a record after it: the last record of a file
        // whose rows are all names is no header (the first row is).
        let after = &records[i + 1..];
        if after.is_empty() {
            continue;
        }
        if after
            .iter()
            .take(FOLLOWING)
            .all(|n| width(&n.raw, r.delimiter) == r.cells.len() && !names(n))
        {
            return Some(i);
        }
    }
    None
}

/// A whole file's last record as its header: when it is all names and a
/// record before it holds a number (a logger's preamble, then a header
/// with no data rows after it: the file is refused as having no data rows,
/// not read from its preamble). A file of names only keeps its first row.
fn last_names(records: &[Scanned]) -> Option<usize> {
    let (last, before) = records.split_last()?;
    (names(last) && before.iter().any(|r| !names(r))).then(|| records.len() - 1)
}

impl<R: Read> Reader<R> {
    /// Read up to the header row (module docs), leaving the reader on it,
    /// split into `self.fields` with its delimiter set; returns the
    /// preamble.
    pub(super) fn find_header(&mut self, opts: &ReadOptions) -> Result<Vec<PreambleLine>> {
        // Hold the buffer from the start on, so the scan can rewind.
        self.hold = Some(self.pos);
        let mut records: Vec<Scanned> = Vec::new();
        let want_line = opts.header_line;
        let mut complete = false;
        loop {
            let held = self.pos - self.hold.unwrap_or(0);
            if records.len() >= SCAN_RECORDS || held > SCAN_BYTES {
                break;
            }
            match (want_line, records.last()) {
                (Some(n), Some(last)) if last.line >= n => break,
                // Without a preamble to look for, the first record and the
                // records that must follow it are enough.
                (None, _)
                    if choose(&records, opts).is_some_and(|i| records.len() > i + FOLLOWING) =>
                {
                    break
                }
                _ => {}
            }
            let (a, b) = match self.peek_record_start(true)? {
                Peek::Line(a, b) => (a, b),
                Peek::End => {
                    complete = true;
                    break;
                }
                Peek::Limit if records.is_empty() => return self.first_record_as_header(opts),
                Peek::Limit => break,
            };
            let raw = String::from_utf8_lossy(&self.buf[a..b]).into_owned();
            let delimiter = opts
                .delimiter
                .unwrap_or_else(|| detect_delimiter(raw.as_bytes()));
            let offset = a - self.hold.unwrap_or(0);
            self.pos = a;
            self.line -= 1;
            let line_before = self.line;
            self.header.delimiter = delimiter;
            match self.next_record() {
                Ok(true) => {}
                Ok(false) => {
                    complete = true;
                    break;
                }
                // A later record that cannot be split on its own terms
                // (its own delimiter): the scan ends before it.
                Err(_) if !records.is_empty() => break,
                Err(e) => return Err(e),
            }
            let data = self.cell_bytes();
            let cells = self
                .fields
                .iter()
                .map(|&(x, y)| String::from_utf8_lossy(&data[x as usize..y as usize]).into_owned())
                .collect();
            records.push(Scanned {
                offset,
                line_before,
                line: self.row_line,
                cells,
                raw,
                delimiter,
            });
        }
        let index = match want_line {
            Some(n) => records.iter().position(|r| r.line == n).ok_or_else(|| {
                InputError::file(
                    &self.file,
                    format!(
                        "--header-line {n}: no record starts on line {n} (a blank or comment \
                         line, inside a quoted field, past the end of the file or past the \
                         first {SCAN_RECORDS} records)"
                    ),
                )
            })?,
            None => {
                if records.is_empty() {
                    return Err(InputError::file(
                        &self.file,
                        "empty file (expected a header row)",
                    ));
                }
                choose(&records, opts)
                    .or_else(|| complete.then(|| last_names(&records)).flatten())
                    .unwrap_or(0)
            }
        };
        let h = &records[index];
        if let (Some(n), Some(c)) = (want_line, h.cells.iter().find(|c| !is_name(c))) {
            return Err(InputError::at(
                &self.file,
                n,
                format!(
                    "--header-line {n}: this line holds '{}', not a column name",
                    crate::error::clip(c)
                ),
            ));
        }
        let base = self.hold.take().unwrap_or(0);
        self.pos = base + h.offset;
        self.line = h.line_before;
        self.header.delimiter = h.delimiter;
        if !self.next_record()? {
            return Err(InputError::file(
                &self.file,
                "empty file (expected a header row)",
            ));
        }
        Ok(records[..index]
            .iter()
            .map(|r| PreambleLine {
                line: r.line,
                key: r.cells.first().cloned().unwrap_or_default(),
                value: {
                    let mut rest: Vec<&str> = r.cells.iter().skip(1).map(String::as_str).collect();
                    while rest.last() == Some(&"") {
                        rest.pop();
                    }
                    rest.join(", ")
                },
            })
            .collect())
    }

    /// Skip blank and comment lines; the next record's first line as
    /// buffer positions, the reader left after it. With `limit`, the scan
    /// stops once [`SCAN_BYTES`] are held.
    fn peek_record_start(&mut self, limit: bool) -> Result<Peek> {
        loop {
            if limit && self.hold.is_some_and(|h| self.pos - h > SCAN_BYTES) {
                return Ok(Peek::Limit);
            }
            let Some((a, b)) = self.next_line()? else {
                return Ok(Peek::End);
            };
            let first = self.buf[a..b].iter().position(|&c| c != b' ' && c != b'\t');
            match first {
                None => continue,
                Some(k) if self.buf[a + k] == b'#' => continue,
                Some(_) => return Ok(Peek::Line(a, b)),
            }
        }
    }

    /// More than [`SCAN_BYTES`] of comments before any record: no preamble
    /// is looked for, the first record is the header (the reader as it was
    /// before preambles), the buffer no longer held.
    fn first_record_as_header(&mut self, opts: &ReadOptions) -> Result<Vec<PreambleLine>> {
        self.hold = None;
        let Peek::Line(a, b) = self.peek_record_start(false)? else {
            return Err(InputError::file(
                &self.file,
                "empty file (expected a header row)",
            ));
        };
        self.header.delimiter = opts
            .delimiter
            .unwrap_or_else(|| detect_delimiter(&self.buf[a..b]));
        self.pos = a;
        self.line -= 1;
        if !self.next_record()? {
            return Err(InputError::file(
                &self.file,
                "empty file (expected a header row)",
            ));
        }
        Ok(Vec::new())
    }
}
