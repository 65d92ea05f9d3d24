//! A whole table in memory, for procedures that segment or revisit rows.

use std::io::Read;

use crate::error::{InputError, Result};
use crate::reader::{Header, ReadOptions, Reader, Summary};

/// A CSV table read into memory: the cells' text in one buffer with an end
/// offset per cell, and the file line of every row (no allocation per
/// cell: a 720 000-row file costs a few growing buffers).
#[derive(Debug, Clone)]
pub struct Table {
    header: Header,
    summary: Summary,
    lines: Vec<u32>,
    text: Vec<u8>,
    ends: Vec<u32>,
}

impl Table {
    /// Read a whole table from `src` (named `file` in messages). `size_hint`:
    /// the source's length in bytes when known (0 otherwise), to size the
    /// buffers once.
    pub fn read(file: &str, src: impl Read, opts: &ReadOptions, size_hint: usize) -> Result<Table> {
        let mut reader = Reader::new(file, src, opts)?;
        let header = reader.header().clone();
        let width = header.width();
        let too_big = || {
            InputError::file(
                file,
                "too large for one table (at most 4 GB of cells and 4e9 lines)",
            )
        };
        let mut lines: Vec<u32> = Vec::new();
        let mut text: Vec<u8> = Vec::with_capacity(size_hint);
        let mut ends: Vec<u32> = Vec::new();
        while let Some(row) = reader.next_row()? {
            for col in 0..width {
                text.extend_from_slice(row.bytes(col));
                ends.push(u32::try_from(text.len()).map_err(|_| too_big())?);
            }
            lines.push(u32::try_from(row.line()).map_err(|_| too_big())?);
            if lines.len() == 256 && size_hint > 0 {
                // Size the indexes from the first rows' length (plus 10 %)
                // instead of doubling, which holds up to three times the
                // final size while it copies.
                let per_row = (text.len() as f64 / 256.0).max(1.0);
                let rows = (size_hint as f64 / per_row * 1.1) as usize;
                lines.reserve(rows.saturating_sub(lines.len()));
                ends.reserve((rows * width).saturating_sub(ends.len()));
            }
        }
        let summary = reader.finish()?;
        Ok(Table {
            header,
            summary,
            lines,
            text,
            ends,
        })
    }

    /// Read a table from bytes in memory (fuzzing, tests, front ends that
    /// already hold the file).
    pub fn from_bytes(file: &str, bytes: &[u8], opts: &ReadOptions) -> Result<Table> {
        Self::read(file, bytes, opts, bytes.len())
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }
    /// The file as the user named it.
    pub fn file(&self) -> &str {
        self.header.file()
    }
    /// SHA-256 of the file's bytes (empty when hashing was off).
    pub fn sha256(&self) -> &str {
        &self.summary.sha256
    }
    /// What the read recorded of the file.
    pub fn summary(&self) -> &Summary {
        &self.summary
    }
    /// Number of data rows (at least 1).
    pub fn row_count(&self) -> usize {
        self.lines.len()
    }
    /// Index of a required column.
    pub fn column(&self, name: &str) -> Result<usize> {
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
    /// Raw bytes of a cell.
    pub fn bytes(&self, row: usize, col: usize) -> &[u8] {
        let k = row * self.header.width() + col;
        let start = if k == 0 { 0 } else { self.ends[k - 1] as usize };
        &self.text[start..self.ends[k] as usize]
    }
    /// Text of a cell (a number column in memory reads as
    /// [`crate::frames::number_text`]).
    pub fn text(&self, row: usize, col: usize) -> std::borrow::Cow<'_, str> {
        crate::reader::cell_text(&self.header, col, self.bytes(row, col))
    }
    /// A number from a cell (as `Row::f64`).
    pub fn f64(&self, row: usize, col: usize) -> Result<f64> {
        self.row(row).f64(col)
    }
    /// One row, for the accessors a streamed row has.
    pub fn row(&self, row: usize) -> TableRow<'_> {
        TableRow { table: self, row }
    }
    /// A problem at data row `row`.
    pub fn error_at(&self, row: usize, message: impl Into<String>) -> InputError {
        InputError::at(self.file(), self.line(row), message)
    }
    /// Every number of column `col`, in row order (the first bad cell is an error).
    pub fn column_f64(&self, col: usize) -> Result<Vec<f64>> {
        (0..self.row_count()).map(|r| self.f64(r, col)).collect()
    }
}

/// A row of a [`Table`].
#[derive(Debug, Clone, Copy)]
pub struct TableRow<'a> {
    table: &'a Table,
    row: usize,
}

impl<'a> TableRow<'a> {
    /// File line of the row.
    pub fn line(&self) -> usize {
        self.table.line(self.row)
    }
    /// Text of a cell.
    pub fn text(&self, col: usize) -> std::borrow::Cow<'a, str> {
        self.table.text(self.row, col)
    }
    /// A number from a cell, or an error naming file, line and column.
    pub fn f64(&self, col: usize) -> Result<f64> {
        crate::reader::cell_number(
            self.table.header(),
            self.line(),
            col,
            self.table.bytes(self.row, col),
        )
    }
    /// A problem on this row.
    pub fn error(&self, message: impl Into<String>) -> InputError {
        self.table.error_at(self.row, message)
    }
}
