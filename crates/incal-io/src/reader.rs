//! The tabular reader: CSV text from any `impl Read`, row by row, with
//! bounded memory, hashing every byte on the way.
//!
//! # Format
//! * A header row, then data rows. Lines whose first non-blank character
//!   is `#` are comments; blank lines and rows whose cells are all empty
//!   are skipped; a UTF-8 byte-order mark at the start is skipped; lines
//!   end in LF, CRLF or CR.
//! * The delimiter is `,`, `;` or tab: given ([`ReadOptions::delimiter`])
//!   or detected from the header (the one of the three it holds most of,
//!   outside quotes; `,` when it holds none).
//! * Fields may be quoted (`"a, b"`, `"say ""hi"""`, a line break inside
//!   quotes); every cell is trimmed of spaces and tabs.
//! * Numbers use `.` as the decimal separator; a cell such as `1,5` in a
//!   `;`- or tab-separated file is refused with a message that says the
//!   file uses a decimal comma.
//! * A line longer than [`ReadOptions::max_line_bytes`] is refused, so
//!   memory stays bounded on any input (`/dev/zero`, a binary file).
//!
//! # Speed
//! The fast path (a line without a quote) finds line ends and delimiters
//! with `memchr`, checks UTF-8 only on lines with non-ASCII bytes, keeps
//! cells as ranges of the read buffer (no allocation per row) and parses
//! numbers with `fast-float2` (correctly rounded, as `str::parse`).

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Read;

mod frames;
pub mod preamble;
pub mod rails;
mod robot;

pub use preamble::{stated_rate_hz, PreambleLine, FOLLOWING, SCAN_BYTES, SCAN_RECORDS};
pub use rails::{at_rail, extreme_rails, rail_runs, Clipped};

use sha2::Digest;

pub use crate::digest::hex;

use crate::error::{clip, InputError, Result};
use crate::ColumnMap;

/// Longest line (or quoted record) read, in bytes: 1 MiB.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Largest magnitude of a number read from a cell: no instrument reading,
/// time or angle is that large, and sums of squares of such numbers stay
/// far from overflow.
pub const MAX_ABS_VALUE: f64 = 1e15;

const BOM: &[u8] = b"\xEF\xBB\xBF";
const CHUNK: usize = 1 << 18;

/// How a table is read.
#[derive(Debug, Clone)]
pub struct ReadOptions {
    /// The delimiter (`b','`, `b';'`, `b'\t'`); `None` detects it from the header.
    pub delimiter: Option<u8>,
    /// Columns selected and renamed (`--columns`).
    pub columns: ColumnMap,
    /// Longest line accepted, in bytes.
    pub max_line_bytes: usize,
    /// Hash the bytes read (SHA-256, for the result's inputs).
    pub hash: bool,
    /// The source is columns in memory in their canonical byte form
    /// ([`crate::frames`]), not CSV text.
    pub frames: bool,
    /// File line of the header row (`--header-line`, 1-based); `None`
    /// finds it after any preamble ([`preamble`]).
    pub header_line: Option<usize>,
    /// Cut a continuous log into plateaus of a rig channel first
    /// ([`crate::segments`]; reductions only, a stream refuses it).
    pub segment: Option<crate::segments::SegmentSpec>,
    /// A converter's full scale (`--full-scale`, in the columns' own
    /// unit): a value of at least this magnitude is at a rail
    /// ([`rails`]); the integer converters' ends always are.
    pub full_scale: Option<f64>,
    /// A robot log's topics and stamps (`--topic`, `--stamps`;
    /// [`crate::logs`]).
    pub log: crate::logs::LogOptions,
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self {
            delimiter: None,
            columns: ColumnMap::default(),
            max_line_bytes: MAX_LINE_BYTES,
            hash: true,
            frames: false,
            header_line: None,
            segment: None,
            full_scale: None,
            log: crate::logs::LogOptions::default(),
        }
    }
}

impl ReadOptions {
    /// Default options with this column map.
    pub fn with_columns(columns: ColumnMap) -> Self {
        Self {
            columns,
            ..Self::default()
        }
    }
}

/// Parse a `--delimiter` value: `,`, `;`, `tab` (or a tab character).
pub fn parse_delimiter(s: &str) -> std::result::Result<u8, String> {
    match s {
        "," | "comma" => Ok(b','),
        ";" | "semicolon" => Ok(b';'),
        "\t" | "tab" | "\\t" => Ok(b'\t'),
        _ => Err(format!(
            "'{}' is not a delimiter (give ',', ';' or tab)",
            clip(s)
        )),
    }
}

/// The header of a table: incal's column names (after `--columns`
/// renaming) and where they are.
#[derive(Debug, Clone)]
pub struct Header {
    file: String,
    names: Vec<String>,
    index: HashMap<String, usize>,
    line: usize,
    delimiter: u8,
    selected: Vec<usize>,
    /// Per column: its cells are 8-byte binary64 numbers (columns in
    /// memory, [`crate::frames`]); empty for CSV text.
    numeric: Vec<bool>,
}

impl Header {
    /// The file as the user named it.
    pub fn file(&self) -> &str {
        &self.file
    }
    /// Column names, in file order (renamed by `--columns`).
    pub fn names(&self) -> &[String] {
        &self.names
    }
    /// Number of columns.
    pub fn width(&self) -> usize {
        self.names.len()
    }
    /// File line of the header row.
    pub fn line(&self) -> usize {
        self.line
    }
    /// The delimiter in use.
    pub fn delimiter(&self) -> u8 {
        self.delimiter
    }
    /// Index of a required column; the error lists the columns there are.
    pub fn column(&self, name: &str) -> Result<usize> {
        self.index.get(name).copied().ok_or_else(|| {
            InputError::file(
                &self.file,
                format!(
                    "missing column '{}' (columns: {})",
                    clip(name),
                    self.listed()
                ),
            )
        })
    }
    /// The columns for a message: each clipped, at most 12 of them (a
    /// header that swallowed a quoted newline stays one line).
    fn listed(&self) -> String {
        const MAX: usize = 12;
        let mut shown: Vec<String> = self.names.iter().take(MAX).map(|n| clip(n)).collect();
        if self.names.len() > MAX {
            shown.push(format!("... {} in all", self.names.len()));
        }
        let s = shown.join(", ");
        if s.chars().count() > 200 {
            format!(
                "{}... ({} columns)",
                s.chars().take(200).collect::<String>(),
                self.names.len()
            )
        } else {
            s
        }
    }
    /// Index of an optional column.
    pub fn opt_column(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }
    /// The columns named by `--columns`, in the order given (empty when
    /// none was given).
    pub fn selected(&self) -> &[usize] {
        &self.selected
    }
    /// True when column `col` holds binary numbers, not text
    /// ([`crate::frames`]).
    pub fn is_numeric(&self, col: usize) -> bool {
        self.numeric.get(col).copied().unwrap_or(false)
    }
    /// A problem on the header row.
    pub fn error(&self, message: impl Into<String>) -> InputError {
        InputError::at(&self.file, self.line, message)
    }
}

/// What a finished read records of its file.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The file as the user named it.
    pub file: String,
    /// SHA-256 of every byte of the file, lower-case hex (equals
    /// `sha256sum FILE`); empty when hashing was off.
    pub sha256: String,
    /// Data rows read.
    pub rows: usize,
    /// Bytes read.
    pub bytes: u64,
    /// The environmental columns of the file ([`CONDITION_COLUMNS`]) that
    /// it has, summarised over its rows.
    pub conditions: Vec<Condition>,
    /// The lines before the header ([`preamble`]).
    pub preamble: Vec<PreambleLine>,
    /// Columns that sat at a converter's rail for two rows or more
    /// ([`rails`]).
    pub clipped: Vec<Clipped>,
}

/// Columns summarised as the environment of a recording, whatever the
/// procedure reads: the temperature (°C) and relative humidity (%).
pub const CONDITION_COLUMNS: [&str; 2] = ["temperature_c", "humidity_pct"];

/// One environmental column summarised over the rows (cells that are not
/// finite numbers are left out).
#[derive(Debug, Clone, PartialEq)]
pub struct Condition {
    /// Column name.
    pub name: String,
    /// Number of values summarised.
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// Where the cells of the current row live.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Cells {
    Buffer,
    Scratch,
}

/// A CSV reader over any source: the header is read by [`Reader::new`],
/// then [`Reader::next_row`] hands out one data row at a time.
pub struct Reader<R> {
    file: String,
    src: robot::Source<R>,
    buf: Vec<u8>,
    pos: usize,
    end: usize,
    eof: bool,
    started: bool,
    hasher: Option<sha2::Sha256>,
    bytes: u64,
    line: usize,
    max_line: usize,
    header: Header,
    fields: Vec<(u32, u32)>,
    scratch: Vec<u8>,
    cells: Cells,
    row_line: usize,
    rows: usize,
    conditions: Vec<(usize, Condition)>,
    frames: bool,
    /// Start of bytes the buffer keeps while the header is looked for.
    hold: Option<usize>,
    preamble: Vec<PreambleLine>,
    rails: Vec<rails::Watch>,
    full_scale: Option<f64>,
    /// SHA-256 and length of a robot log's own bytes (its CSV is neither
    /// hashed nor counted).
    log: Option<(String, u64)>,
}

/// One data row; cells are trimmed text of the file.
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    header: &'a Header,
    data: &'a [u8],
    fields: &'a [(u32, u32)],
    line: usize,
}

impl<R: Read> Reader<R> {
    /// Start reading `src` (named `file` in messages): reads up to and
    /// including the header row. Refuses an empty file, an empty or
    /// repeated column name, and a `--columns` entry the header lacks.
    pub fn new(file: &str, src: R, opts: &ReadOptions) -> Result<Self> {
        let mut r = Reader {
            file: file.to_string(),
            src: robot::Source::Given(src),
            buf: vec![0; CHUNK],
            pos: 0,
            end: 0,
            eof: false,
            started: false,
            hasher: opts.hash.then(sha2::Sha256::new),
            bytes: 0,
            line: 0,
            max_line: opts.max_line_bytes.max(64),
            header: Header {
                file: file.to_string(),
                names: Vec::new(),
                index: HashMap::new(),
                line: 0,
                delimiter: b',',
                selected: Vec::new(),
                numeric: Vec::new(),
            },
            fields: Vec::new(),
            scratch: Vec::new(),
            cells: Cells::Buffer,
            row_line: 0,
            rows: 0,
            conditions: Vec::new(),
            frames: opts.frames,
            hold: None,
            preamble: Vec::new(),
            rails: Vec::new(),
            full_scale: opts.full_scale,
            log: None,
        };
        if opts.frames {
            r.read_frame_header(opts)?;
        } else {
            match r.robot_log(opts)? {
                Some(decoded) => r.read_header(&decoded)?,
                None => r.read_header(opts)?,
            }
        }
        r.rails = rails::Watch::columns(&r.header);
        r.conditions = CONDITION_COLUMNS
            .iter()
            .filter_map(|n| {
                r.header.opt_column(n).map(|k| {
                    (
                        k,
                        Condition {
                            name: n.to_string(),
                            count: 0,
                            mean: 0.0,
                            min: f64::INFINITY,
                            max: f64::NEG_INFINITY,
                        },
                    )
                })
            })
            .collect();
        Ok(r)
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The lines before the header ([`preamble`]).
    pub fn preamble(&self) -> &[PreambleLine] {
        &self.preamble
    }

    /// Data rows handed out so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The next data row, or `None` at the end of the file. A row of the
    /// wrong width, invalid UTF-8, an unclosed quote or an over-long line
    /// is an error naming the line.
    pub fn next_row(&mut self) -> Result<Option<Row<'_>>> {
        loop {
            if self.frames {
                if !self.next_frame()? {
                    return Ok(None);
                }
            } else if !self.next_record()? {
                return Ok(None);
            }
            if !self.frames && self.fields.iter().all(|&(a, b)| a == b) {
                continue;
            }
            if self.fields.len() != self.header.width() {
                return Err(InputError::at(
                    &self.file,
                    self.row_line,
                    format!(
                        "{} fields, but the header has {}",
                        self.fields.len(),
                        self.header.width()
                    ),
                ));
            }
            self.rows += 1;
            for (k, c) in &mut self.conditions {
                let (a, b) = self.fields[*k];
                let data = match self.cells {
                    Cells::Buffer => &self.buf,
                    Cells::Scratch => &self.scratch,
                };
                if let Some(v) = cell_value(&self.header, *k, &data[a as usize..b as usize])
                    .filter(|v| v.is_finite())
                {
                    c.count += 1;
                    c.mean += (v - c.mean) / c.count as f64;
                    c.min = c.min.min(v);
                    c.max = c.max.max(v);
                }
            }
            let data = match self.cells {
                Cells::Buffer => &self.buf,
                Cells::Scratch => &self.scratch,
            };
            for w in &mut self.rails {
                let k = w.col();
                let (a, b) = self.fields[k];
                w.push(
                    &data[a as usize..b as usize],
                    self.header.is_numeric(k),
                    self.row_line,
                    self.full_scale,
                );
            }
            return Ok(Some(Row {
                header: &self.header,
                data: match self.cells {
                    Cells::Buffer => &self.buf,
                    Cells::Scratch => &self.scratch,
                },
                fields: &self.fields,
                line: self.row_line,
            }));
        }
    }

    /// Finish: hash whatever is left unread (nothing, normally) and return
    /// what a result records of the file. Refuses a file without data rows.
    pub fn finish(mut self) -> Result<Summary> {
        if self.rows == 0 {
            return Err(InputError::file(
                &self.file,
                "no data rows after the header",
            ));
        }
        while !self.eof {
            self.pos = self.end;
            self.fill()?;
        }
        Ok(Summary {
            file: self.file,
            sha256: match &self.log {
                Some((s, _)) => s.clone(),
                None => self.hasher.map(|h| hex(&h.finalize())).unwrap_or_default(),
            },
            rows: self.rows,
            bytes: self.log.as_ref().map_or(self.bytes, |l| l.1),
            conditions: self
                .conditions
                .into_iter()
                .map(|(_, c)| c)
                .filter(|c| c.count > 0)
                .collect(),
            preamble: self.preamble,
            clipped: {
                let (header, fs) = (&self.header, self.full_scale);
                self.rails
                    .into_iter()
                    .flat_map(|w| w.finish(header, fs))
                    .collect()
            },
        })
    }

    fn cell_bytes(&self) -> &[u8] {
        match self.cells {
            Cells::Buffer => &self.buf,
            Cells::Scratch => &self.scratch,
        }
    }

    /// Read more bytes into the buffer, moving or growing it as needed.
    /// Returns the number of bytes read (0 at the end of the source).
    fn fill(&mut self) -> Result<usize> {
        let base = self.hold.unwrap_or(self.pos);
        if base > 0 && (self.end == self.buf.len() || base >= self.buf.len() / 2) {
            self.buf.copy_within(base..self.end, 0);
            self.end -= base;
            self.pos -= base;
            if self.hold.is_some() {
                self.hold = Some(0);
            }
        }
        if self.end == self.buf.len() {
            let grown = (self.buf.len() * 2).min(self.max_line + 2 * CHUNK);
            if grown <= self.buf.len() {
                // Unreachable while lines are checked against max_line.
                return Err(InputError::at(
                    &self.file,
                    self.line + 1,
                    format!("line longer than {} bytes", self.max_line),
                ));
            }
            self.buf.resize(grown, 0);
        }
        let n = loop {
            match self.src.read(&mut self.buf[self.end..]) {
                Ok(n) => break n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(InputError::io(&self.file, &e)),
            }
        };
        if let Some(h) = &mut self.hasher {
            h.update(&self.buf[self.end..self.end + n]);
        }
        self.bytes += n as u64;
        self.end += n;
        if n == 0 {
            self.eof = true;
        }
        Ok(n)
    }

    fn too_long(&self) -> InputError {
        InputError::at(
            &self.file,
            self.line + 1,
            format!(
                "line longer than {} bytes (is this a CSV text file?)",
                self.max_line
            ),
        )
    }

    /// The next physical line, as a range of the buffer without its end
    /// of line; `self.line` is its number.
    fn next_line(&mut self) -> Result<Option<(usize, usize)>> {
        if !self.started {
            // A byte-order mark (spreadsheet exports) is skipped, however
            // the source hands out its first bytes.
            while self.end < BOM.len() && !self.eof {
                self.fill()?;
            }
            self.started = true;
            if self.buf[..self.end].starts_with(BOM) {
                self.pos = BOM.len();
            }
        }
        let mut scan = self.pos;
        loop {
            if let Some(i) = memchr::memchr2(b'\n', b'\r', &self.buf[scan..self.end]) {
                let t = scan + i;
                let mut skip = 1;
                if self.buf[t] == b'\r' {
                    if t + 1 == self.end && !self.eof {
                        let off = t - self.pos;
                        self.fill()?;
                        scan = self.pos + off;
                        continue;
                    }
                    if t + 1 < self.end && self.buf[t + 1] == b'\n' {
                        skip = 2;
                    }
                }
                if t - self.pos > self.max_line {
                    return Err(self.too_long());
                }
                let start = self.pos;
                self.pos = t + skip;
                self.line += 1;
                return Ok(Some((start, t)));
            }
            if self.end - self.pos > self.max_line {
                return Err(self.too_long());
            }
            if self.eof {
                if self.pos == self.end {
                    return Ok(None);
                }
                let start = self.pos;
                self.pos = self.end;
                self.line += 1;
                return Ok(Some((start, self.end)));
            }
            let off = self.end - self.pos;
            self.fill()?;
            scan = self.pos + off;
        }
    }

    fn check_utf8(&self, a: usize, b: usize) -> Result<()> {
        let s = &self.buf[a..b];
        if !s.is_ascii() && std::str::from_utf8(s).is_err() {
            return Err(InputError::at(&self.file, self.line, "invalid UTF-8"));
        }
        Ok(())
    }

    /// The next record that is not a comment or a blank line, split into
    /// `self.fields`. Returns false at the end of the file.
    fn next_record(&mut self) -> Result<bool> {
        let (a, b) = loop {
            let Some((a, b)) = self.next_line()? else {
                return Ok(false);
            };
            let first = self.buf[a..b].iter().position(|&c| c != b' ' && c != b'\t');
            match first {
                None => continue,
                Some(k) if self.buf[a + k] == b'#' => continue,
                Some(_) => break (a, b),
            }
        };
        self.check_utf8(a, b)?;
        self.row_line = self.line;
        let delim = self.header.delimiter;
        self.fields.clear();
        if memchr::memchr(b'"', &self.buf[a..b]).is_none() {
            self.cells = Cells::Buffer;
            let mut start = a;
            for d in memchr::memchr_iter(delim, &self.buf[a..b]) {
                let e = a + d;
                push_trimmed(&mut self.fields, &self.buf, start, e);
                start = e + 1;
            }
            push_trimmed(&mut self.fields, &self.buf, start, b);
            return Ok(true);
        }
        self.cells = Cells::Scratch;
        self.split_quoted(a, b)?;
        Ok(true)
    }

    /// The slow path: a record with quotes, unquoted into `self.scratch`;
    /// a quote left open continues on the next line.
    fn split_quoted(&mut self, a: usize, b: usize) -> Result<()> {
        let delim = self.header.delimiter;
        let first_line = self.line;
        self.scratch.clear();
        let mut line: Vec<u8> = self.buf[a..b].to_vec();
        let mut i = 0;
        let mut in_quotes = false;
        let mut field_start = 0usize;
        let mut at_field_start = true;
        let mut after_close = false;
        loop {
            while i < line.len() {
                let c = line[i];
                if in_quotes {
                    if c == b'"' {
                        if line.get(i + 1) == Some(&b'"') {
                            self.scratch.push(b'"');
                            i += 2;
                            continue;
                        }
                        in_quotes = false;
                        after_close = true;
                    } else {
                        self.scratch.push(c);
                    }
                    i += 1;
                    continue;
                }
                if c == delim {
                    push_trimmed(
                        &mut self.fields,
                        &self.scratch,
                        field_start,
                        self.scratch.len(),
                    );
                    field_start = self.scratch.len();
                    at_field_start = true;
                    after_close = false;
                } else if after_close {
                    if c != b' ' && c != b'\t' {
                        return Err(InputError::at(
                            &self.file,
                            self.line,
                            "text after a closing quote (quote the whole field)",
                        ));
                    }
                } else if c == b'"' && at_field_start {
                    in_quotes = true;
                    // Spaces before an opening quote are not part of the cell.
                    self.scratch.truncate(field_start);
                } else {
                    if c != b' ' && c != b'\t' {
                        at_field_start = false;
                    }
                    self.scratch.push(c);
                }
                i += 1;
            }
            if !in_quotes {
                break;
            }
            // A line break inside quotes belongs to the cell.
            let Some((a2, b2)) = self.next_line()? else {
                return Err(InputError::at(
                    &self.file,
                    first_line,
                    "quoted field not closed before the end of the file",
                ));
            };
            self.check_utf8(a2, b2)?;
            if self.scratch.len() + (b2 - a2) > self.max_line {
                return Err(self.too_long());
            }
            self.scratch.push(b'\n');
            line.clear();
            line.extend_from_slice(&self.buf[a2..b2]);
            i = 0;
        }
        push_trimmed(
            &mut self.fields,
            &self.scratch,
            field_start,
            self.scratch.len(),
        );
        Ok(())
    }

    fn read_header(&mut self, opts: &ReadOptions) -> Result<()> {
        self.preamble = self.find_header(opts)?;
        let line = self.row_line;
        let data = self.cell_bytes();
        let mut names: Vec<String> = Vec::with_capacity(self.fields.len());
        for &(x, y) in &self.fields {
            names.push(String::from_utf8_lossy(&data[x as usize..y as usize]).into_owned());
        }
        self.set_names(names, line, opts)
    }

    /// The header's names (refused empty or repeated), renamed and
    /// selected by `--columns`.
    fn set_names(&mut self, mut names: Vec<String>, line: usize, opts: &ReadOptions) -> Result<()> {
        let file = self.file.clone();
        let at = |m: String| InputError::at(&file, line, m);
        for (k, h) in names.iter().enumerate() {
            if h.is_empty() {
                return Err(at(format!("empty column name in column {}", k + 1)));
            }
        }
        let original = names.clone();
        let mut selected = Vec::with_capacity(opts.columns.entries().len());
        for e in opts.columns.entries() {
            let src = e.source();
            let Some(k) = original.iter().position(|h| h == src) else {
                return Err(at(format!(
                    "no column '{}'{} (columns: {})",
                    clip(src),
                    if e.header.is_some() {
                        format!(" to read as '{}'", clip(&e.name))
                    } else {
                        String::new()
                    },
                    original.join(", ")
                )));
            };
            names[k] = e.name.clone();
            selected.push(k);
        }
        let mut index = HashMap::with_capacity(names.len());
        for (k, h) in names.iter().enumerate() {
            if index.insert(h.clone(), k).is_some() {
                let renamed = !opts.columns.is_empty() && original[k] != *h;
                return Err(at(format!(
                    "column '{}' appears twice{}",
                    clip(h),
                    if renamed { " (after --columns)" } else { "" }
                )));
            }
        }
        self.header.names = names;
        self.header.index = index;
        self.header.line = line;
        self.header.selected = selected;
        Ok(())
    }
}

fn push_trimmed(fields: &mut Vec<(u32, u32)>, data: &[u8], mut a: usize, mut b: usize) {
    while a < b && (data[a] == b' ' || data[a] == b'\t') {
        a += 1;
    }
    while b > a && (data[b - 1] == b' ' || data[b - 1] == b'\t') {
        b -= 1;
    }
    // Lines are at most max_line (<< 4 GiB) bytes; the buffer likewise.
    fields.push((a as u32, b as u32));
}

/// The delimiter of a header line: the most frequent of `,` `;` tab
/// outside quotes (`,` on a tie or when none is there).
fn detect_delimiter(line: &[u8]) -> u8 {
    let (mut comma, mut semi, mut tab) = (0usize, 0usize, 0usize);
    let mut quoted = false;
    for &c in line {
        match c {
            b'"' => quoted = !quoted,
            b',' if !quoted => comma += 1,
            b';' if !quoted => semi += 1,
            b'\t' if !quoted => tab += 1,
            _ => {}
        }
    }
    if semi > comma && semi >= tab {
        b';'
    } else if tab > comma && tab > semi {
        b'\t'
    } else {
        b','
    }
}

impl<'a> Row<'a> {
    /// File line of the row (its first line, for a quoted record that spans lines).
    pub fn line(&self) -> usize {
        self.line
    }
    /// Number of cells (the header's width).
    pub fn width(&self) -> usize {
        self.fields.len()
    }
    /// The header.
    pub fn header(&self) -> &'a Header {
        self.header
    }
    /// Raw bytes of a cell (trimmed).
    pub fn bytes(&self, col: usize) -> &'a [u8] {
        let (a, b) = self.fields[col];
        &self.data[a as usize..b as usize]
    }
    /// Text of a cell (trimmed; every line was checked to be UTF-8); a
    /// number column in memory reads as [`crate::frames::number_text`].
    pub fn text(&self, col: usize) -> Cow<'a, str> {
        cell_text(self.header, col, self.bytes(col))
    }
    /// A label cell (a pass, a run, a position name), trimmed; refused
    /// naming the cell when it holds `#` (a note written after the label
    /// would make a new label) or a control character (NUL, ESC, …).
    pub fn label(&self, col: usize) -> Result<Cow<'a, str>> {
        let t = match self.text(col) {
            Cow::Borrowed(t) => Cow::Borrowed(t.trim()),
            Cow::Owned(t) => Cow::Owned(t),
        };
        if t.contains('#') {
            return Err(self.cell_error(
                col,
                "a label must not contain '#' (a note after the label?)",
            ));
        }
        if t.chars().any(char::is_control) {
            return Err(self.cell_error(col, "a label must not contain control characters"));
        }
        Ok(t)
    }
    /// A finite number within ±[`MAX_ABS_VALUE`] from a cell, or an error
    /// naming the file, line and column.
    pub fn f64(&self, col: usize) -> Result<f64> {
        cell_number(self.header, self.line, col, self.bytes(col))
    }
    /// As [`Row::f64`], but an empty cell or `NaN` (any case) is a missing
    /// sample (`None`) for a reduction that handles gaps; infinities and
    /// text are still refused.
    pub fn f64_or_missing(&self, col: usize) -> Result<Option<f64>> {
        let b = self.bytes(col);
        if self.header.is_numeric(col) {
            if frames::decode(b).is_nan() {
                return Ok(None);
            }
        } else if b.is_empty() || b.eq_ignore_ascii_case(b"nan") {
            return Ok(None);
        }
        self.f64(col).map(Some)
    }
    /// A problem on this row.
    pub fn error(&self, message: impl Into<String>) -> InputError {
        InputError::at(&self.header.file, self.line, message)
    }
    /// A problem in one cell of this row.
    pub fn cell_error(&self, col: usize, message: impl Into<String>) -> InputError {
        InputError::cell(
            &self.header.file,
            self.line,
            &self.header.names[col],
            message,
        )
    }
}

/// Parse a number as incal reads every cell: `.` decimal separator,
/// exponent allowed, finite, at most [`MAX_ABS_VALUE`] in magnitude.
/// `None` when the text is not a number at all.
pub fn parse_f64(bytes: &[u8]) -> Option<f64> {
    fast_float2::parse::<f64, _>(bytes).ok()
}

/// A number from the cell at (`line`, column `col`) of a table with this header.
pub(crate) fn cell_number(header: &Header, line: usize, col: usize, bytes: &[u8]) -> Result<f64> {
    if header.is_numeric(col) {
        return frames::number(header, line, col, bytes);
    }
    number(header, line, &header.names[col], bytes)
}

/// The value of a cell when it is a number (binary or text), else `None`.
pub(crate) fn cell_value(header: &Header, col: usize, bytes: &[u8]) -> Option<f64> {
    if header.is_numeric(col) {
        Some(frames::decode(bytes))
    } else {
        parse_f64(bytes)
    }
}

/// The text of a cell of a table with this header.
pub(crate) fn cell_text<'a>(header: &Header, col: usize, bytes: &'a [u8]) -> Cow<'a, str> {
    if header.is_numeric(col) {
        Cow::Owned(crate::frames::number_text(frames::decode(bytes)))
    } else {
        Cow::Borrowed(std::str::from_utf8(bytes).unwrap_or(""))
    }
}

fn number(header: &Header, line: usize, column: &str, bytes: &[u8]) -> Result<f64> {
    let v = match parse_f64(bytes) {
        Some(v) => v,
        None => {
            let shown = clip(&String::from_utf8_lossy(bytes));
            let msg = if header.delimiter != b',' && decimal_comma(bytes) {
                format!(
                    "'{shown}' has a decimal comma: incal reads '.' as the decimal separator (export the file with '.')"
                )
            } else {
                format!("'{shown}' is not a number")
            };
            return Err(InputError::cell(&header.file, line, column, msg));
        }
    };
    if !v.is_finite() {
        let shown = clip(&String::from_utf8_lossy(bytes));
        return Err(InputError::cell(
            &header.file,
            line,
            column,
            format!("'{shown}' is not a finite number"),
        ));
    }
    if v.abs() > MAX_ABS_VALUE {
        let shown = clip(&String::from_utf8_lossy(bytes));
        return Err(InputError::cell(
            &header.file,
            line,
            column,
            format!("{shown} is out of range (|value| <= 1e15)"),
        ));
    }
    Ok(v)
}

/// True when `bytes` reads as a number once its one comma is a point.
fn decimal_comma(bytes: &[u8]) -> bool {
    if bytes.iter().filter(|&&c| c == b',').count() != 1 {
        return false;
    }
    let fixed: Vec<u8> = bytes
        .iter()
        .map(|&c| if c == b',' { b'.' } else { c })
        .collect();
    parse_f64(&fixed).is_some()
}
