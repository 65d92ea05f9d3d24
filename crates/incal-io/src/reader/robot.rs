//! A robot log in place of CSV ([`crate::logs`]): the reader's source is
//! either the stream it was given or, once a log's magic number is seen,
//! the log's decoded CSV in memory.

use std::io::{Cursor, Read};

use super::{ReadOptions, Reader};
use crate::error::{InputError, Result};
use crate::logs::{self, Format};

/// The bytes a [`Reader`] reads: the source as given, or a log's CSV.
pub(super) enum Source<R> {
    /// The caller's stream.
    Given(R),
    /// A robot log's decoded CSV.
    Decoded(Cursor<Vec<u8>>),
}

impl<R: Read> Read for Source<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            Self::Given(r) => r.read(buf),
            Self::Decoded(c) => c.read(buf),
        }
    }
}

impl<R: Read> Reader<R> {
    /// Before the header: when the source starts with a robot log's magic
    /// number, read it whole, decode the topic and read its CSV instead;
    /// returns the options of that CSV (its header line is known). A
    /// `--topic` on a file that is no log is refused.
    pub(super) fn robot_log(&mut self, opts: &ReadOptions) -> Result<Option<ReadOptions>> {
        while self.end < Format::MAGIC_BYTES && !self.eof {
            self.fill()?;
        }
        let Some(format) = Format::detect(&self.buf[..self.end]) else {
            if let Some(t) = opts.log.topics.first() {
                return Err(InputError::file(
                    &self.file,
                    format!(
                        "--topic '{}': not a PX4 ULog, a ROS 1 bag or an MCAP file (its first bytes say none of them)",
                        crate::clip(t)
                    ),
                ));
            }
            return Ok(None);
        };
        let mut bytes = self.buf[..self.end].to_vec();
        if let Source::Given(src) = &mut self.src {
            src.read_to_end(&mut bytes)
                .map_err(|e| InputError::io(&self.file, &e))?;
        }
        let c = logs::convert(&self.file, format, &bytes, &opts.log)?;
        self.src = Source::Decoded(Cursor::new(c.text.into_bytes()));
        self.pos = 0;
        self.end = 0;
        self.eof = false;
        self.hasher = None;
        self.log = Some((c.sha256, bytes.len() as u64));
        if let Some(n) = opts.header_line {
            return Err(InputError::file(
                &self.file,
                format!("--header-line {n}: a {} has no header line to name (its topic's columns are incal's)", format.name()),
            ));
        }
        let mut o = opts.clone();
        o.header_line = Some(c.header_line);
        o.delimiter = Some(b',');
        Ok(Some(o))
    }
}
