//! Columns in memory as a recording: the input a front end that already
//! holds the data (a pandas DataFrame, numpy arrays, a polars frame) hands
//! to the same [`Reader`](crate::Reader) every procedure reads, without a
//! text round trip.
//!
//! [`Columns`] borrows its number columns (`&[f64]`, no copy) and is a
//! `std::io::Read` that hands out the **canonical byte form** below; a
//! reader opened with [`ReadOptions::frames`](crate::ReadOptions::frames)
//! reads that form instead of CSV, so a procedure sees the same header and
//! rows as from a CSV file with the same cells, and the SHA-256 the reader
//! records (the document's `inputs[].sha256`) is the hash of this form:
//! the same columns always give the same hash.
//!
//! # Canonical byte form (`incal columns 1`)
//! * the 8 bytes `INCALCF1`;
//! * the number of columns, `u32` little-endian;
//! * per column: a kind byte (`0`: numbers, `1`: text), the name's length
//!   in bytes (`u32` LE) and the name (UTF-8);
//! * per row, per column in order: a number as its 8 IEEE-754 binary64
//!   bytes, little-endian; a text as its length (`u32` LE) and its UTF-8
//!   bytes.
//!
//! A number cell that is NaN is a missing sample where a procedure accepts
//! gaps ([`Row::f64_or_missing`](crate::Row::f64_or_missing)) and refused
//! elsewhere, naming the column and the row; rows are numbered from 0 in
//! messages (a DataFrame's `iloc` position, an array's index).

use std::borrow::Cow;
use std::io::Read;

/// The first 8 bytes of the canonical form.
pub const MAGIC: &[u8; 8] = b"INCALCF1";

/// One column in memory.
#[derive(Debug, Clone)]
pub enum Column<'a> {
    /// Numbers (borrowed in place, or owned after a conversion).
    F64(Cow<'a, [f64]>),
    /// Text cells (labels: positions, passes, runs).
    Text(Cow<'a, [String]>),
}

impl Column<'_> {
    fn len(&self) -> usize {
        match self {
            Column::F64(v) => v.len(),
            Column::Text(v) => v.len(),
        }
    }
}

/// Named columns of equal length, readable as the canonical byte form.
#[derive(Debug, Clone, Default)]
pub struct Columns<'a> {
    names: Vec<String>,
    cols: Vec<Column<'a>>,
    out: Vec<u8>,
    out_pos: usize,
    next_row: usize,
    started: bool,
}

impl<'a> Columns<'a> {
    /// No columns yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a column; refuses an empty or repeated name and a length that
    /// differs from the first column's (the message names both).
    pub fn push(&mut self, name: &str, column: Column<'a>) -> Result<(), String> {
        if name.is_empty() {
            return Err("a column has an empty name".into());
        }
        if self.names.iter().any(|n| n == name) {
            return Err(format!("column '{}' given twice", crate::clip(name)));
        }
        if let Some(first) = self.cols.first() {
            if first.len() != column.len() {
                return Err(format!(
                    "column '{}' has {} values, '{}' has {}",
                    crate::clip(name),
                    column.len(),
                    crate::clip(&self.names[0]),
                    first.len()
                ));
            }
        }
        self.names.push(name.to_string());
        self.cols.push(column);
        Ok(())
    }

    /// Column names, in order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of rows (0 without columns).
    pub fn rows(&self) -> usize {
        self.cols.first().map_or(0, Column::len)
    }

    /// A reader of the same columns from their first byte, borrowing them
    /// (nothing copied): to read the canonical form twice at once, e.g.
    /// hash it on one thread while a procedure reads it on another.
    pub fn view(&self) -> Columns<'_> {
        let cols = self
            .cols
            .iter()
            .map(|c| match c {
                Column::F64(v) => Column::F64(Cow::Borrowed(&v[..])),
                Column::Text(v) => Column::Text(Cow::Borrowed(&v[..])),
            })
            .collect();
        Columns {
            names: self.names.clone(),
            cols,
            ..Columns::default()
        }
    }

    /// The SHA-256 (lowercase hex) of the canonical byte form, as the
    /// reader records it for the document's `inputs` when it hashes.
    pub fn sha256(&self) -> String {
        use sha2::Digest;
        let mut view = self.view();
        let mut hasher = sha2::Sha256::new();
        let mut buf = vec![0u8; 1 << 16];
        loop {
            match Read::read(&mut view, &mut buf) {
                Ok(0) | Err(_) => break,
                Ok(n) => hasher.update(&buf[..n]),
            }
        }
        crate::digest::hex(&hasher.finalize())
    }

    /// Encode the header (once) and whole rows until `out` holds about
    /// `target` bytes.
    fn refill(&mut self, target: usize) {
        self.out.clear();
        self.out_pos = 0;
        if !self.started {
            self.started = true;
            self.out.extend_from_slice(MAGIC);
            push_len(&mut self.out, self.cols.len());
            for (name, col) in self.names.iter().zip(&self.cols) {
                self.out.push(matches!(col, Column::Text(_)) as u8);
                push_len(&mut self.out, name.len());
                self.out.extend_from_slice(name.as_bytes());
            }
        }
        let rows = self.rows();
        let numbers: Option<Vec<&[f64]>> = self
            .cols
            .iter()
            .map(|c| match c {
                Column::F64(v) => Some(&v[..]),
                Column::Text(_) => None,
            })
            .collect();
        if let Some(numbers) = numbers {
            // Numbers only: whole rows of 8 bytes per column, sized at once.
            let width = 8 * numbers.len().max(1);
            let take = (target.saturating_sub(self.out.len()) / width)
                .max(1)
                .min(rows - self.next_row);
            self.out.reserve(take * width);
            for r in self.next_row..self.next_row + take {
                for col in &numbers {
                    self.out.extend_from_slice(&col[r].to_le_bytes());
                }
            }
            self.next_row += take;
            return;
        }
        while self.out.len() < target && self.next_row < rows {
            let r = self.next_row;
            for col in &self.cols {
                match col {
                    Column::F64(v) => self.out.extend_from_slice(&v[r].to_le_bytes()),
                    Column::Text(v) => {
                        push_len(&mut self.out, v[r].len());
                        self.out.extend_from_slice(v[r].as_bytes());
                    }
                }
            }
            self.next_row += 1;
        }
    }
}

/// A length as `u32` LE (saturated: the reader refuses what is too long).
fn push_len(out: &mut Vec<u8>, n: usize) {
    out.extend_from_slice(&u32::try_from(n).unwrap_or(u32::MAX).to_le_bytes());
}

impl Read for Columns<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.out_pos == self.out.len() {
            self.refill(buf.len().max(1 << 12));
        }
        let n = buf.len().min(self.out.len() - self.out_pos);
        buf[..n].copy_from_slice(&self.out[self.out_pos..self.out_pos + n]);
        self.out_pos += n;
        Ok(n)
    }
}

/// The text a number cell reads as where a procedure wants text (a label
/// column given as numbers): an integral value as an integer (`3`),
/// anything else in the shortest form that reads back the same value
/// (`0.1`, `-2.25e-7`).
pub fn number_text(v: f64) -> String {
    let mut s = String::new();
    push_number(&mut s, v);
    s
}

/// Append [`number_text`]`(v)` to `out` without allocating: integers by
/// `itoa`, other finite values by `ryu` (the same shortest digits as Rust's
/// `{:?}`, and the same notation: plain in [10⁻⁴, 10¹⁶), `1.5e-7` below
/// 10⁻⁴, where ryu's plain `0.0000dd` of [10⁻⁵, 10⁻⁴) is rewritten as
/// `d.de-5`), the rest (plain digits from 10¹⁶) by `{:?}`.
///
/// Where `v` lies exactly halfway between two shortest decimals
/// (12442012941949.3125 between …312 and …313), ryu rounds half to even and
/// Rust's `{:?}` half up; such a value is written by `{:?}` too.
pub fn push_number(out: &mut String, v: f64) {
    let a = v.abs();
    if v.fract() == 0.0 && a < 1e15 {
        out.push_str(itoa::Buffer::new().format(v as i64));
        return;
    }
    let mut b = ryu::Buffer::new();
    let text = match v.is_finite() && a < 1e16 {
        true if a < 1e-4 => b.format_finite(a),
        true => b.format_finite(v),
        false => "",
    };
    if text.is_empty() || may_be_a_tie(v, text) {
        use std::fmt::Write;
        let _ = write!(out, "{v:?}");
    } else if !(1e-5..1e-4).contains(&a) {
        if v < 0.0 && a < 1e-4 {
            out.push('-');
        }
        out.push_str(text);
    } else {
        let digits = text.strip_prefix("0.0000").unwrap_or(text);
        if v < 0.0 {
            out.push('-');
        }
        out.push_str(&digits[..1]);
        if digits.len() > 1 {
            out.push('.');
            out.push_str(&digits[1..]);
        }
        out.push_str("e-5");
    }
}

/// Whether the shortest decimal `text` (ryu's, of `|v|` or `v`) may have been
/// rounded from an exact halfway point: the exact binary value `m·2^-k`
/// (`m` odd) has `k` decimal places, and a tie is one place past the text's
/// last digit, so only `k = d + 1` (with `d` the text's decimal places) can
/// be one.
fn may_be_a_tie(v: f64, text: &str) -> bool {
    let bits = v.to_bits();
    let field = ((bits >> 52) & 0x7ff) as i32;
    let mut mantissa = bits & ((1u64 << 52) - 1);
    if field != 0 {
        mantissa |= 1u64 << 52;
    }
    if mantissa == 0 {
        return false;
    }
    let exp2 = field.max(1) - 1075 + mantissa.trailing_zeros() as i32;
    if exp2 >= 0 {
        return false;
    }
    let (digits, exp10) = match text.split_once('e') {
        Some((d, e)) => (d, e.parse::<i32>().unwrap_or(0)),
        None => (text, 0),
    };
    let places = match digits.split_once('.') {
        Some((_, "0")) | None => 0,
        Some((_, f)) => f.len() as i32,
    };
    -exp2 == places - exp10 + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ReadOptions, Table};

    fn frames() -> ReadOptions {
        ReadOptions {
            frames: true,
            ..ReadOptions::default()
        }
    }

    fn bytes(c: &Columns<'_>) -> Vec<u8> {
        let mut c = c.clone();
        let mut out = Vec::new();
        c.read_to_end(&mut out).unwrap();
        out
    }

    fn sample<'a>(angle: &'a [f64], out: &'a [f64], pos: &'a [String]) -> Columns<'a> {
        let mut c = Columns::new();
        c.push("angle_deg", Column::F64(Cow::Borrowed(angle)))
            .unwrap();
        c.push("output", Column::F64(Cow::Borrowed(out))).unwrap();
        c.push("position", Column::Text(Cow::Borrowed(pos)))
            .unwrap();
        c
    }

    #[test]
    fn columns_read_as_the_csv_with_the_same_cells() {
        let angle = [0.0, 30.0, 3.0];
        let out = [1.5, -2.25e-7, 0.1];
        let pos: Vec<String> = ["a", "b, c", "é"].map(String::from).to_vec();
        let csv = "angle_deg,output,position\n0,1.5,a\n30,-2.25e-7,\"b, c\"\n3,0.1,é\n";
        let a = Table::from_bytes("f.csv", csv.as_bytes(), &ReadOptions::default()).unwrap();
        let b = Table::read("<DataFrame>", sample(&angle, &out, &pos), &frames(), 0).unwrap();
        assert_eq!(a.header().names(), b.header().names());
        assert_eq!(a.row_count(), b.row_count());
        for r in 0..3 {
            for c in 0..3 {
                assert_eq!(a.text(r, c), b.text(r, c), "row {r} col {c}");
            }
            for c in 0..2 {
                assert_eq!(a.f64(r, c).unwrap(), b.f64(r, c).unwrap());
            }
            // Rows of columns in memory are numbered from 0.
            assert_eq!(b.line(r), r);
        }
        assert_eq!(
            b.text(2, 0),
            "3",
            "an integral number reads as an integer label"
        );
        assert!(b.f64(0, 2).is_err(), "a text cell is not a number");
    }

    #[test]
    fn the_hash_is_of_the_canonical_form_and_the_same_for_the_same_columns() {
        let angle = [0.0, 30.0];
        let out = [1.5, 2.5];
        let pos: Vec<String> = vec!["a".into(), "b".into()];
        let c = sample(&angle, &out, &pos);
        let t = Table::read("x", c.clone(), &frames(), 0).unwrap();
        let canonical = bytes(&c);
        assert_eq!(&canonical[..8], MAGIC);
        assert_eq!(t.sha256(), crate::sha256_hex(&canonical));
        // Hashed beside the reader (a view each), the same hash; numbers
        // only too (whole rows at once).
        assert_eq!(c.sha256(), t.sha256());
        assert_eq!(bytes(&c.view()), canonical);
        let mut numbers = Columns::new();
        numbers
            .push("angle_deg", Column::F64(Cow::Borrowed(&angle)))
            .unwrap();
        let n = Table::read("n", numbers.view(), &frames(), 0).unwrap();
        assert_eq!(numbers.sha256(), n.sha256());
        let again = Table::read("y", sample(&angle, &out, &pos), &frames(), 0).unwrap();
        assert_eq!(t.sha256(), again.sha256());
        let other = [1.5, 2.5000000000000004];
        let changed = Table::read("z", sample(&angle, &other, &pos), &frames(), 0).unwrap();
        assert_ne!(t.sha256(), changed.sha256());
    }

    #[test]
    fn nan_is_missing_or_refused_naming_the_column_and_row() {
        let angle = [0.0, 1.0, 2.0];
        let out = [1.0, f64::NAN, f64::INFINITY];
        let pos: Vec<String> = vec!["a".into(); 3];
        let c = sample(&angle, &out, &pos);
        let mut r = crate::Reader::new("<arrays>", c, &frames()).unwrap();
        let row = r.next_row().unwrap().unwrap();
        assert_eq!(row.f64(1).unwrap(), 1.0);
        let row = r.next_row().unwrap().unwrap();
        assert_eq!(row.f64_or_missing(1).unwrap(), None);
        let e = row.f64(1).unwrap_err().to_string();
        assert_eq!(
            e,
            "<arrays>:1: column 'output': NaN is not a finite number (a missing value where none may be)"
        );
        let row = r.next_row().unwrap().unwrap();
        assert!(row
            .f64_or_missing(1)
            .unwrap_err()
            .to_string()
            .contains("inf is not a finite number"));
    }

    #[test]
    fn columns_are_selected_and_renamed_as_in_csv() {
        let angle = [0.0, 30.0];
        let out = [1.5, 2.5];
        let pos: Vec<String> = vec!["a".into(), "b".into()];
        let opts = ReadOptions {
            columns: crate::ColumnMap::parse("y=output").unwrap(),
            ..frames()
        };
        let t = Table::read("x", sample(&angle, &out, &pos), &opts, 0).unwrap();
        assert_eq!(t.header().names(), ["angle_deg", "y", "position"]);
        assert_eq!(t.header().selected(), [1]);
    }

    #[test]
    fn a_column_of_another_length_or_a_repeated_name_is_refused() {
        let a = [0.0, 1.0];
        let b = [0.0];
        let mut c = Columns::new();
        c.push("a", Column::F64(Cow::Borrowed(&a))).unwrap();
        assert_eq!(
            c.push("b", Column::F64(Cow::Borrowed(&b))).unwrap_err(),
            "column 'b' has 1 values, 'a' has 2"
        );
        assert!(c.push("a", Column::F64(Cow::Borrowed(&a))).is_err());
        let empty = Columns::new();
        let e = Table::read("x", empty, &frames(), 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("0 columns"), "{e}");
    }

    #[test]
    fn number_text_is_the_debug_notation() {
        let cases = [
            0.0,
            -0.0,
            3.0,
            -2.5,
            0.1,
            1e-4,
            9.99e-5,
            -1.25e-5,
            1e-5,
            2.25e-7,
            5e-324,
            1e15,
            // 12442012941949.3125, halfway between …312 and …313
            f64::from_bits(4802703913775856288),
            -f64::from_bits(4802703913775856288),
        ];
        let wide = [
            1e16,
            1.5e16,
            123456789.123,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
        ];
        for v in cases.into_iter().chain(wide) {
            let want = if v.fract() == 0.0 && v.abs() < 1e15 {
                format!("{}", v as i64)
            } else {
                format!("{v:?}")
            };
            assert_eq!(number_text(v), want, "{v:e}");
        }
    }

    proptest::proptest! {
        /// Any finite f64 reads as Rust's `{:?}` would write it (the fast
        /// path changes no text).
        #[test]
        fn number_text_matches_debug_for_any_bits(bits in proptest::prelude::any::<u64>()) {
            let v = f64::from_bits(bits);
            proptest::prop_assume!(v.fract() != 0.0 || v.abs() >= 1e15);
            proptest::prop_assert_eq!(number_text(v), format!("{v:?}"));
        }

        /// Values with few binary places, where exact halfway points between
        /// two shortest decimals are common.
        #[test]
        fn number_text_matches_debug_at_halfway_points(m in 0u64..(1 << 52), k in 1i32..60) {
            // An odd numerator over 2^k: never an integer.
            let v = (2 * m + 1) as f64 / 2f64.powi(k);
            proptest::prop_assert_eq!(number_text(v), format!("{v:?}"));
            proptest::prop_assert_eq!(number_text(-v), format!("{:?}", -v));
        }

        /// The rewritten decade [10⁻⁵, 10⁻⁴) too.
        #[test]
        fn number_text_matches_debug_near_1e_5(v in 1e-5f64..1e-4, negative in proptest::prelude::any::<bool>()) {
            let v = if negative { -v } else { v };
            proptest::prop_assert_eq!(number_text(v), format!("{v:?}"));
        }

        /// Any bytes after the magic give rows or one error: never a panic.
        #[test]
        fn any_bytes_are_read_or_refused(tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..400)) {
            let mut data = MAGIC.to_vec();
            data.extend_from_slice(&tail);
            if let Ok(mut r) = crate::Reader::new("x", &data[..], &frames()) {
                while let Ok(Some(row)) = r.next_row() {
                    for c in 0..row.width() {
                        let _ = (row.f64(c), row.text(c));
                    }
                }
            }
        }
    }
}
