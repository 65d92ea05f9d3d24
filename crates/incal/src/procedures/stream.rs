//! Streaming tools: a model applied to a recording row by row, written out
//! as the rows arrive (`imu apply`, `thermal apply`, `gfimu solve`).
//!
//! One shape for all three ([`Stream`]): the front end builds the model
//! (a calibration or thermal model read from a result document, a
//! gyro-free unit's solver) with its options; the tool reads the rows
//! through the input layer, writes to any [`std::io::Write`] and returns
//! what it did ([`Streamed`]): the rows, notes and warnings for the front
//! end to show (a terminal's standard error, Python warnings). The core
//! never prints.

use std::io::{Read, Write};

use crate::error::Result;
use crate::warning::Warning;

/// What a streaming tool did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Streamed {
    /// Rows written.
    pub rows: u64,
    /// Facts about the run for people (e.g. the solution mode).
    pub notes: Vec<String>,
    /// Warnings of the run (repeated or sorted time stamps, clamped
    /// temperatures, …).
    pub warnings: Vec<Warning>,
}

/// A streaming tool (module docs).
pub trait Stream {
    /// The model and its options, as the front end built them.
    type Model;

    /// Apply `model` to the rows of `input` (named `name` in messages) read
    /// with `read`, writing to `out` as the rows arrive. A bad row stops
    /// the run with an error naming the file and line (what was written
    /// before stays); an output that cannot be written is
    /// [`crate::Error::Write`].
    fn stream(
        model: Self::Model,
        name: &str,
        input: Box<dyn Read + Send + '_>,
        read: &incal_io::ReadOptions,
        out: &mut dyn Write,
    ) -> Result<Streamed>;
}
