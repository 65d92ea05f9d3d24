//! The one CSV writer: a header, rows of numbers and text, `#` notes.

use std::borrow::Cow;
use std::io::Write;

/// A CSV writer: `,` delimiter, LF line ends, numbers in Rust's shortest
/// round-trip form (`{}`: reading a written file gives the same bits),
/// text quoted when it holds a delimiter, a quote, a line break or starts
/// with `#`. A non-finite number is refused, never written.
pub struct CsvWriter<W: Write> {
    out: W,
    width: usize,
    col: usize,
}

/// A cell to write.
#[derive(Debug, Clone, Copy)]
pub enum Cell<'a> {
    /// A number (must be finite).
    Num(f64),
    /// Text.
    Text(&'a str),
}

impl<W: Write> CsvWriter<W> {
    /// Start a file with its header row.
    pub fn new(mut out: W, header: &[&str]) -> std::io::Result<Self> {
        let mut first = true;
        for h in header {
            if !first {
                out.write_all(b",")?;
            }
            first = false;
            write_text(&mut out, h)?;
        }
        out.write_all(b"\n")?;
        Ok(Self {
            out,
            width: header.len(),
            col: 0,
        })
    }

    /// One cell of the current row.
    pub fn cell(&mut self, c: Cell<'_>) -> std::io::Result<()> {
        if self.col > 0 {
            self.out.write_all(b",")?;
        }
        match c {
            Cell::Num(x) => {
                if !x.is_finite() {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        "a non-finite number (inf or NaN) is never written",
                    ));
                }
                write!(self.out, "{x}")?;
            }
            Cell::Text(t) => write_text(&mut self.out, t)?,
        }
        self.col += 1;
        Ok(())
    }

    /// A whole row.
    pub fn row(&mut self, cells: &[Cell<'_>]) -> std::io::Result<()> {
        for c in cells {
            self.cell(*c)?;
        }
        self.end_row()
    }

    /// End the current row (it must hold as many cells as the header).
    pub fn end_row(&mut self) -> std::io::Result<()> {
        if self.col != self.width {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("row of {} cells under a header of {}", self.col, self.width),
            ));
        }
        self.col = 0;
        self.out.write_all(b"\n")
    }

    /// Flush and return the writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

fn write_text(out: &mut impl Write, t: &str) -> std::io::Result<()> {
    out.write_all(csv_text(t).as_bytes())
}

/// Text as one CSV cell: as is, or in double quotes (inner quotes doubled)
/// when it holds a delimiter (`,`, `;`, tab), a quote or a line break,
/// starts with `#` or has leading or trailing white space, so that incal's
/// reader (which detects `;` and tab, skips `#` lines and trims cells),
/// RFC 4180 readers and pandas all read it back as written.
pub fn csv_text(t: &str) -> Cow<'_, str> {
    let needs = t.starts_with('#')
        || t.bytes()
            .any(|c| matches!(c, b',' | b';' | b'\t' | b'"' | b'\n' | b'\r'))
        || t != t.trim();
    if needs {
        format!("\"{}\"", t.replace('"', "\"\"")).into()
    } else {
        t.into()
    }
}
