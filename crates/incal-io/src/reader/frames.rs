//! The reader's side of columns in memory ([`crate::frames`]): the
//! canonical byte form read into the same header and rows as CSV text.
//! Every length is checked before it is used, so any bytes (a fuzz
//! input) give rows or one error, never a panic or unbounded memory.

use std::io::Read;

use super::{Header, ReadOptions, Reader, CHUNK, MAX_ABS_VALUE};
use crate::error::{clip, InputError, Result};

/// Most columns a frame header may declare.
const MAX_COLUMNS: usize = 1 << 16;

/// A binary64 cell's value (NaN for a cell that is not 8 bytes, which the
/// reader never hands out).
pub(super) fn decode(bytes: &[u8]) -> f64 {
    <[u8; 8]>::try_from(bytes).map_or(f64::NAN, f64::from_le_bytes)
}

/// A finite number within ±[`MAX_ABS_VALUE`] from a binary cell, or an
/// error naming the source, the row and the column.
pub(super) fn number(header: &Header, row: usize, col: usize, bytes: &[u8]) -> Result<f64> {
    let v = decode(bytes);
    let message = if v.is_nan() {
        "NaN is not a finite number (a missing value where none may be)".to_string()
    } else if !v.is_finite() {
        format!("{v} is not a finite number")
    } else if v.abs() > MAX_ABS_VALUE {
        format!("{v:e} is out of range (|value| <= 1e15)")
    } else {
        return Ok(v);
    };
    Err(InputError::cell(
        header.file(),
        row,
        &header.names()[col],
        message,
    ))
}

fn u32_at(buf: &[u8], at: usize) -> usize {
    let mut b = [0u8; 4];
    b.copy_from_slice(&buf[at..at + 4]);
    u32::from_le_bytes(b) as usize
}

impl<R: Read> Reader<R> {
    /// True when `n` bytes from `self.pos` are in the buffer (reading
    /// more as needed); false at the end of the source before them.
    fn need(&mut self, n: usize) -> Result<bool> {
        if n > self.max_line + CHUNK {
            return Err(InputError::file(
                &self.file,
                format!(
                    "a row of columns in memory longer than {} bytes",
                    self.max_line
                ),
            ));
        }
        while self.end - self.pos < n {
            if self.eof {
                return Ok(false);
            }
            self.fill()?;
        }
        Ok(true)
    }

    fn truncated(&self, what: &str) -> InputError {
        InputError::file(
            &self.file,
            format!("columns in memory end inside {what} (not incal's canonical column form)"),
        )
    }

    /// The header of the canonical form: names and kinds.
    pub(super) fn read_frame_header(&mut self, opts: &ReadOptions) -> Result<()> {
        if !self.need(12)? || &self.buf[self.pos..self.pos + 8] != crate::frames::MAGIC {
            return Err(InputError::file(
                &self.file,
                "not incal's canonical column form (expected INCALCF1)",
            ));
        }
        let width = u32_at(&self.buf, self.pos + 8);
        self.pos += 12;
        if width == 0 || width > MAX_COLUMNS {
            return Err(InputError::file(
                &self.file,
                format!("{width} columns (1 to {MAX_COLUMNS})"),
            ));
        }
        let mut names = Vec::with_capacity(width);
        let mut numeric = Vec::with_capacity(width);
        for _ in 0..width {
            if !self.need(5)? {
                return Err(self.truncated("the header"));
            }
            let kind = self.buf[self.pos];
            let len = u32_at(&self.buf, self.pos + 1);
            self.pos += 5;
            if kind > 1 || len == 0 || len > 4096 {
                return Err(InputError::file(
                    &self.file,
                    format!("column {}: kind {kind}, name of {len} bytes (a name of 1 to 4096 bytes, kind 0 or 1)", names.len() + 1),
                ));
            }
            if !self.need(len)? {
                return Err(self.truncated("the header"));
            }
            let name = std::str::from_utf8(&self.buf[self.pos..self.pos + len])
                .map_err(|_| InputError::file(&self.file, "a column name is not UTF-8"))?;
            names.push(name.to_string());
            numeric.push(kind == 0);
            self.pos += len;
        }
        self.header.numeric = numeric;
        self.set_names(names, 0, opts)
    }

    /// The next row of the canonical form into `self.fields` (ranges of
    /// the buffer); false at the end of the source.
    pub(super) fn next_frame(&mut self) -> Result<bool> {
        if !self.need(1)? {
            return Ok(false);
        }
        self.fields.clear();
        let width = self.header.width();
        if self.header.numeric.iter().all(|&n| n) {
            // Numbers only: a row is a fixed 8 bytes per column.
            if !self.need(8 * width)? {
                return Err(self.truncated(&format!("row {}", self.rows)));
            }
            let base = self.pos as u32;
            self.fields
                .extend((0..width as u32).map(|k| (base + 8 * k, base + 8 * k + 8)));
            self.pos += 8 * width;
            self.row_line = self.rows;
            self.cells = super::Cells::Buffer;
            return Ok(true);
        }
        let mut off = 0usize;
        for col in 0..width {
            if self.header.numeric[col] {
                if !self.need(off + 8)? {
                    return Err(self.truncated(&format!("row {}", self.rows)));
                }
                self.fields.push((off as u32, (off + 8) as u32));
                off += 8;
                continue;
            }
            if !self.need(off + 4)? {
                return Err(self.truncated(&format!("row {}", self.rows)));
            }
            let len = u32_at(&self.buf, self.pos + off);
            if len > self.max_line {
                return Err(InputError::cell(
                    &self.file,
                    self.rows,
                    &self.header.names[col],
                    format!("a text of {len} bytes (at most {})", self.max_line),
                ));
            }
            if !self.need(off + 4 + len)? {
                return Err(self.truncated(&format!("row {}", self.rows)));
            }
            let (a, b) = (self.pos + off + 4, self.pos + off + 4 + len);
            if std::str::from_utf8(&self.buf[a..b]).is_err() {
                return Err(InputError::cell(
                    &self.file,
                    self.rows,
                    &self.header.names[col],
                    format!(
                        "'{}' is not UTF-8",
                        clip(&String::from_utf8_lossy(&self.buf[a..b]))
                    ),
                ));
            }
            self.fields.push(((off + 4) as u32, (off + 4 + len) as u32));
            off += 4 + len;
        }
        // Offsets were kept relative to the row's start: reading more may
        // have moved the row within the buffer.
        let base = self.pos as u32;
        for f in &mut self.fields {
            f.0 += base;
            f.1 += base;
        }
        self.pos += off;
        self.row_line = self.rows;
        self.cells = super::Cells::Buffer;
        Ok(true)
    }
}
