//! # incal-io — the input layer of incal
//!
//! One tabular reader for every CSV input of every procedure and front end
//! (CLI, Python, fuzzing), and one CSV writer. It knows no procedure: it
//! turns bytes into a header and rows of cells, and every problem into one
//! [`InputError`] naming the file, the line and the column.
//!
//! * [`Reader`]: row by row over any `impl Read`, bounded memory, SHA-256
//!   of every byte while reading ([`Summary::sha256`]).
//! * [`Table`]: the whole table in memory, for procedures that segment rows.
//! * [`ColumnMap`]: `--columns` selection and renaming (`NAME=HEADER`).
//! * [`CsvWriter`]: the writer of simulators and converters.
//! * [`clip`], [`sha256_hex`], [`csv_text`]: the one echo of a value in a
//!   message, the one hex form of a digest and the one quoting of a CSV
//!   cell, for every crate of incal.
//!
//! The accepted format is described in [`reader`].

#![warn(missing_docs)]

pub mod binary;
pub mod columns;
pub mod digest;
pub mod error;
pub mod frames;
pub mod logs;
pub mod reader;
pub mod segments;
pub mod source;
pub mod table;
pub mod writer;

pub use columns::{ColumnEntry, ColumnMap};
pub use digest::{hex, sha256_hex};
pub use error::{clip, clip_to, InputError, Result};
pub use reader::{
    at_rail, extreme_rails, parse_delimiter, parse_f64, rail_runs, stated_rate_hz, Clipped,
    Condition, Header, PreambleLine, ReadOptions, Reader, Row, Summary, CONDITION_COLUMNS,
    MAX_ABS_VALUE, MAX_LINE_BYTES,
};
pub use segments::{Segment, SegmentSpec, Segmented};
pub use source::{
    display_name, is_dash, open, read_hashed, read_table, stream, stream_table, MAX_DOCUMENT_BYTES,
};
pub use table::{Table, TableRow};
pub use writer::{csv_text, Cell, CsvWriter};

#[cfg(test)]
mod tests;
