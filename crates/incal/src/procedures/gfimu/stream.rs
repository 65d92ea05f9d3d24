//! The streaming motion solution (`gfimu solve`): a motion series read row
//! by row through the input layer ([`incal_io::Reader`]), each sample
//! solved by [`Solver::step`] and written at once, so a record of any
//! length runs in constant memory. Not a reduction: its output is the
//! solution itself, in one of three forms ([`SolutionFormat`]).
//!
//! # Output
//! * CSV: the header [`SOLUTION_CSV_HEADER`], one row per sample (u
//!   columns empty when the calibration gives no noise), then `#` lines
//!   `mode`, every `warning` and, when the run stopped early, `error`.
//! * JSON: one object `{"procedure": "gfimu-solve", "input", "units",
//!   "geometry", "samples": […], "uncertainty": […] | null, "mode",
//!   "warnings"[, "error"]}`; u sits in its own array after the samples
//!   (kept in a scratch store meanwhile, [`Scratch`]).
//! * JSON lines: one object per sample (u inside), then one
//!   `{"summary": {…}}` line.
//!
//! Every number is its shortest round-trip decimal. A run stopped by its
//! input (a bad row, a diverged solution) keeps the samples before it and
//! closes the output with the reason, so a JSON document stays valid.
//!
//! # Threads
//! The series is parsed on a second thread, a few thousand rows ahead of
//! the solver; the output is the same bytes as a serial run.

use std::io::{Read, Seek, SeekFrom, Write};
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

use incal_io::InputError;
use serde::Serialize;

use super::solve::{MotionSample, Solver};
use crate::error::{Error, Result};
use crate::estimation::Diagnostics;
use crate::models::gfimu::Geometry;
use crate::warning::Warning;

/// The form of a streamed solution (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SolutionFormat {
    /// CSV: the header and one row per sample, nothing else.
    Csv,
    /// One JSON object.
    Json,
    /// One JSON object per line, then a summary line.
    JsonLines,
}

/// CSV header of the solution: time (s), f0 (g), ω̇ (rad/s²), ω (rad/s),
/// then the standard uncertainty of each.
pub const SOLUTION_CSV_HEADER: &str = "time_s,f0_x_g,f0_y_g,f0_z_g,omega_dot_x_rad_s2,omega_dot_y_rad_s2,omega_dot_z_rad_s2,omega_x_rad_s,omega_y_rad_s,omega_z_rad_s,u_f0_x_g,u_f0_y_g,u_f0_z_g,u_omega_dot_x_rad_s2,u_omega_dot_y_rad_s2,u_omega_dot_z_rad_s2,u_omega_x_rad_s,u_omega_y_rad_s,u_omega_z_rad_s\n";

/// The longest time step `gfimu solve` bridges, in sample periods (up to
/// four samples lost). The ω integration steps over a gap with the
/// trapezoid rule, whose error grows as the cube of the step: a 5-period
/// step adds the error of 125 ordinary steps, small beside the thousands
/// of a record; a longer gap is refused naming its line.
pub const MAX_GAP_PERIODS: f64 = 5.0;

/// Rows parsed per batch handed from the reader thread to the solver.
const BATCH_ROWS: usize = 4096;

/// Scratch storage for the JSON document's `uncertainty` array while the
/// samples stream out (it follows them in the document): a temporary file
/// for a long series, or memory ([`std::io::Cursor`]).
pub trait Scratch: Read + Write + Seek {}

impl<T: Read + Write + Seek> Scratch for T {}

/// A motion series opened for solving: its header read and the columns of
/// `time_s` and of every accelerometer found ([`super::input::series_columns`]).
pub struct MotionSeries<R> {
    rows: incal_io::Reader<R>,
    cols: Vec<usize>,
}

impl<R: Read> MotionSeries<R> {
    /// Start reading the series `src` (named `name` in messages) for
    /// `geometry`: refuses an empty file and a missing column.
    pub fn open(
        name: &str,
        src: R,
        read: &incal_io::ReadOptions,
        geometry: &Geometry,
    ) -> Result<Self> {
        let rows = incal_io::Reader::new(name, src, read)?;
        let cols = super::input::series_columns(rows.header(), geometry)?;
        Ok(Self { rows, cols })
    }

    /// The file as the user named it.
    pub fn file(&self) -> &str {
        self.rows.header().file()
    }
}

/// Why a streamed solve stopped.
#[derive(Debug)]
pub enum StreamError {
    /// The input stopped it (a bad row, a diverged solution, no rows): the
    /// samples before stay, and the output was closed with this reason.
    Input(Error),
    /// The output could not be written: nothing more was written.
    Write(std::io::Error),
}

impl std::fmt::Display for StreamError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::Input(e) => write!(f, "{e}"),
            StreamError::Write(e) => write!(f, "cannot write the solution: {e}"),
        }
    }
}

impl std::error::Error for StreamError {}

impl From<std::io::Error> for StreamError {
    fn from(e: std::io::Error) -> Self {
        StreamError::Write(e)
    }
}

/// Units of the solution's quantities (JSON; keys in this order).
#[derive(Serialize)]
struct Units {
    f0_g: &'static str,
    omega_dot_rad_s2: &'static str,
    omega_rad_s: &'static str,
    time_s: &'static str,
    u_f0_g: &'static str,
    u_omega_dot_rad_s2: &'static str,
    u_omega_rad_s: &'static str,
}

const UNITS: Units = Units {
    f0_g: "g",
    omega_dot_rad_s2: "rad/s^2",
    omega_rad_s: "rad/s",
    time_s: "s",
    u_f0_g: "g",
    u_omega_dot_rad_s2: "rad/s^2",
    u_omega_rad_s: "rad/s",
};

/// The `geometry` object of the JSON outputs: rank and condition number
/// of the calibrated motion system (null when infinite).
#[derive(Serialize)]
struct GeometryJson {
    condition_number: Option<f64>,
    rank: usize,
}

impl GeometryJson {
    fn of(d: &Diagnostics) -> Self {
        Self {
            condition_number: d.condition.is_finite().then_some(d.condition),
            rank: d.rank,
        }
    }
}

/// One sample of the JSON document (u in its own array).
#[derive(Serialize)]
struct SampleJson {
    time_s: f64,
    f0_g: [f64; 3],
    omega_dot_rad_s2: [f64; 3],
    omega_rad_s: [f64; 3],
}

/// One sample of the JSON lines, u inside (`null` when unknown).
#[derive(Serialize)]
struct SampleLine {
    time_s: f64,
    f0_g: [f64; 3],
    omega_dot_rad_s2: [f64; 3],
    omega_rad_s: [f64; 3],
    u_f0_g: Option<[f64; 3]>,
    u_omega_dot_rad_s2: Option<[f64; 3]>,
    u_omega_rad_s: Option<[f64; 3]>,
}

/// One element of the JSON document's `uncertainty` array.
#[derive(Serialize)]
struct UJson {
    u_f0_g: [f64; 3],
    u_omega_dot_rad_s2: [f64; 3],
    u_omega_rad_s: [f64; 3],
}

/// The last line of the JSON lines.
#[derive(Serialize)]
struct SummaryLine<'a> {
    summary: Summary<'a>,
}

#[derive(Serialize)]
struct Summary<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<&'a str>,
    geometry: GeometryJson,
    mode: &'a str,
    procedure: &'static str,
    units: Units,
    warnings: &'a [Warning],
}

fn arr(v: &nalgebra::Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Compact JSON of `v` appended to `buf` (writing to memory cannot fail;
/// the values written here serialise without error).
fn push_json<T: Serialize + ?Sized>(buf: &mut Vec<u8>, v: &T) {
    let _ = serde_json::to_writer(&mut *buf, v);
}

/// A finite number as its shortest round-trip decimal (as in JSON).
fn push_num(buf: &mut Vec<u8>, x: f64) {
    push_json(buf, &x);
}

/// What comes before the first sample: the CSV header, or the JSON
/// object's opening up to its `samples` array.
fn head(buf: &mut Vec<u8>, file: &str, format: SolutionFormat, d: &Diagnostics) {
    match format {
        SolutionFormat::Csv => buf.extend_from_slice(SOLUTION_CSV_HEADER.as_bytes()),
        SolutionFormat::JsonLines => {}
        SolutionFormat::Json => {
            buf.extend_from_slice(b"{\n  \"procedure\": \"gfimu-solve\",\n  \"input\": ");
            push_json(buf, file);
            buf.extend_from_slice(b",\n  \"units\": ");
            push_json(buf, &UNITS);
            buf.extend_from_slice(b",\n  \"geometry\": ");
            push_json(buf, &GeometryJson::of(d));
            buf.extend_from_slice(b",\n  \"samples\": [\n");
        }
    }
}

/// What comes after the last sample (and, in a JSON document, after the
/// `uncertainty` array): the JSON object's mode and warnings, or the
/// JSON-lines summary; with `error`, the reason the run stopped early
/// (`"error"`). The CSV form has nothing after its rows, so any CSV
/// reader takes it as it is: its mode and warnings are in [`Solved`] and
/// the reason for an early stop in the error.
fn tail(buf: &mut Vec<u8>, format: SolutionFormat, solver: &Solver, error: Option<&str>) {
    match format {
        SolutionFormat::Csv => {}
        SolutionFormat::Json => {
            buf.extend_from_slice(b",\n  \"mode\": ");
            push_json(buf, solver.mode().name());
            buf.extend_from_slice(b",\n  \"warnings\": ");
            push_json(buf, solver.warnings());
            if let Some(e) = error {
                buf.extend_from_slice(b",\n  \"error\": ");
                push_json(buf, e);
            }
            buf.extend_from_slice(b"\n}\n");
        }
        SolutionFormat::JsonLines => {
            push_json(
                buf,
                &SummaryLine {
                    summary: Summary {
                        error,
                        geometry: GeometryJson::of(solver.diagnostics()),
                        mode: solver.mode().name(),
                        procedure: "gfimu-solve",
                        units: UNITS,
                        warnings: solver.warnings(),
                    },
                },
            );
            buf.push(b'\n');
        }
    }
}

/// One solved sample into `buf` (cleared first) in the output's form.
/// False when a number is not finite.
fn sample_line(buf: &mut Vec<u8>, m: &MotionSample, format: SolutionFormat, first: bool) -> bool {
    let values = [m.f0_g, m.omega_dot_rad_s2, m.omega_rad_s];
    let us = [m.u_f0_g, m.u_omega_dot_rad_s2, m.u_omega_rad_s];
    let finite = m.time_s.is_finite()
        && values.iter().all(|v| v.iter().all(|x| x.is_finite()))
        && us.iter().flatten().all(|v| v.iter().all(|x| x.is_finite()));
    if !finite {
        return false;
    }
    buf.clear();
    match format {
        SolutionFormat::Csv => {
            push_num(buf, m.time_s);
            for v in values {
                for x in v.iter() {
                    buf.push(b',');
                    push_num(buf, *x);
                }
            }
            for u in us {
                match u {
                    Some(v) => {
                        for x in v.iter() {
                            buf.push(b',');
                            push_num(buf, *x);
                        }
                    }
                    None => buf.extend_from_slice(b",,,"),
                }
            }
            buf.push(b'\n');
        }
        SolutionFormat::Json => {
            buf.extend_from_slice(if first { b"    " } else { b",\n    " });
            push_json(
                buf,
                &SampleJson {
                    time_s: m.time_s,
                    f0_g: arr(&m.f0_g),
                    omega_dot_rad_s2: arr(&m.omega_dot_rad_s2),
                    omega_rad_s: arr(&m.omega_rad_s),
                },
            );
        }
        SolutionFormat::JsonLines => {
            push_json(
                buf,
                &SampleLine {
                    time_s: m.time_s,
                    f0_g: arr(&m.f0_g),
                    omega_dot_rad_s2: arr(&m.omega_dot_rad_s2),
                    omega_rad_s: arr(&m.omega_rad_s),
                    u_f0_g: m.u_f0_g.as_ref().map(arr),
                    u_omega_dot_rad_s2: m.u_omega_dot_rad_s2.as_ref().map(arr),
                    u_omega_rad_s: m.u_omega_rad_s.as_ref().map(arr),
                },
            );
            buf.push(b'\n');
        }
    }
    true
}

/// One element of the JSON document's `uncertainty` array into `buf`, or
/// false when this sample has no u (the array is then `null`, as for a
/// calibration without noise).
fn u_line(buf: &mut Vec<u8>, m: &MotionSample, first: bool) -> bool {
    let (Some(f), Some(wd), Some(w)) = (m.u_f0_g, m.u_omega_dot_rad_s2, m.u_omega_rad_s) else {
        return false;
    };
    buf.clear();
    buf.extend_from_slice(if first { b"    " } else { b",\n    " });
    push_json(
        buf,
        &UJson {
            u_f0_g: arr(&f),
            u_omega_dot_rad_s2: arr(&wd),
            u_omega_rad_s: arr(&w),
        },
    );
    true
}

/// One batch of parsed rows: line numbers and `[t, e_1 … e_N]` per row.
struct Batch {
    lines: Vec<usize>,
    values: Vec<f64>,
}

impl Batch {
    fn new(stride: usize) -> Self {
        Self {
            lines: Vec::with_capacity(BATCH_ROWS),
            values: Vec::with_capacity(BATCH_ROWS * stride),
        }
    }
}

/// What the reader thread sends: a batch, the error that stopped it
/// (after every good row before it), or the summary of a file read to
/// its end.
enum Parsed {
    Rows(Batch),
    Failed(Error),
    Done(incal_io::Summary, Vec<Warning>),
}

/// The reader thread: parse every data row into batches of numbers, in
/// order; stop at the first bad row and send its error. A row is checked
/// here (numbers, and the time stamps under the streaming policy,
/// [`crate::timebase::StampStream`]: decreasing stamps and gaps above
/// [`MAX_GAP_PERIODS`] periods refused) so the solver sees only clean
/// samples; the line numbers travel with the rows for the solver's errors.
fn parse_series<R: Read>(
    series: MotionSeries<R>,
    tx: &SyncSender<Parsed>,
    recycled: &Receiver<Batch>,
) {
    let MotionSeries { mut rows, cols } = series;
    let stride = cols.len();
    let mut batch = Batch::new(stride);
    let mut stamps = crate::timebase::StampStream::new(MAX_GAP_PERIODS);
    let file = rows.header().file().to_string();
    let time_name = rows.header().names()[cols[0]].clone();
    let stamp_error = |(line, e): (usize, crate::timebase::TimeError)| -> Error {
        InputError::cell(&file, line, &time_name, e.to_string()).into()
    };
    let mut read = || -> Result<bool> {
        while let Some(row) = rows.next_row()? {
            let line = row.line();
            for (i, &k) in cols.iter().enumerate() {
                let v = row.f64(k)?;
                if i == 0 {
                    stamps.push(v, line).map_err(stamp_error)?;
                }
                batch.values.push(v);
            }
            batch.lines.push(line);
            if batch.lines.len() == BATCH_ROWS {
                // Reuse a batch the solver is done with (no allocation and
                // no fresh pages per batch).
                let next = match recycled.try_recv() {
                    Ok(mut b) => {
                        b.lines.clear();
                        b.values.clear();
                        b
                    }
                    Err(_) => Batch::new(stride),
                };
                let full = std::mem::replace(&mut batch, next);
                if tx.send(Parsed::Rows(full)).is_err() {
                    // The solver stopped (its own error): nothing to add.
                    return Ok(false);
                }
            }
        }
        Ok(true)
    };
    let result = read().and_then(|more| {
        stamps.finish().map_err(stamp_error)?;
        Ok(more)
    });
    if !batch.lines.is_empty() {
        let _ = tx.send(Parsed::Rows(batch));
    }
    let last = match result {
        Ok(true) => match rows.finish() {
            Ok(s) => Parsed::Done(s, stamps.warnings()),
            Err(e) => Parsed::Failed(e.into()),
        },
        Ok(false) => return,
        Err(e) => Parsed::Failed(e),
    };
    let _ = tx.send(last);
}

/// Solve the series row by row with `solver` and write the solution to
/// `out` in `format` (module docs); `scratch` holds the JSON document's
/// `uncertainty` array meanwhile (memory when `None`). Returns what the
/// input layer records of the series (rows, SHA-256). A run stopped by
/// its input closes the output with the reason and returns
/// [`StreamError::Input`] naming the file and line.
pub fn solve_stream<R: Read + Send, W: Write>(
    series: MotionSeries<R>,
    mut solver: Solver,
    format: SolutionFormat,
    out: &mut W,
    scratch: Option<&mut dyn Scratch>,
) -> std::result::Result<Solved, StreamError> {
    let name = series.file().to_string();
    let stride = series.cols.len();
    let mut buf = Vec::with_capacity(4096);
    head(&mut buf, &name, format, solver.diagnostics());
    out.write_all(&buf)?;
    let mut memory = std::io::Cursor::new(Vec::new());
    let scratch: &mut dyn Scratch = match scratch {
        Some(s) => s,
        None => &mut memory,
    };
    let scratch_start = scratch.stream_position()?;
    // The u array while the samples stream out; None once a sample has no u.
    let mut spill = (format == SolutionFormat::Json)
        .then(|| std::io::BufWriter::with_capacity(1 << 16, &mut *scratch));
    let mut rows = 0u64;
    let mut line_buf = Vec::with_capacity(512);
    let mut summary = None;
    let outcome = std::thread::scope(|scope| -> std::result::Result<(), StreamError> {
        let (tx, rx) = sync_channel::<Parsed>(8);
        let (back_tx, back_rx) = sync_channel::<Batch>(8);
        scope.spawn(move || parse_series(series, &tx, &back_rx));
        let at =
            |line: usize, msg: String| StreamError::Input(InputError::at(&name, line, msg).into());
        for msg in rx.iter() {
            let batch = match msg {
                Parsed::Rows(b) => b,
                Parsed::Failed(e) => return Err(StreamError::Input(e)),
                Parsed::Done(s, w) => {
                    summary = Some(s);
                    solver.add_warnings(w);
                    break;
                }
            };
            for (&line, row) in batch.lines.iter().zip(batch.values.chunks_exact(stride)) {
                // Dropping the receiver (on return) stops the reader.
                let m = solver
                    .step(row[0], &row[1..])
                    .map_err(|err| at(line, err.to_string()))?;
                rows += 1;
                if !sample_line(&mut line_buf, &m, format, rows == 1) {
                    return Err(at(
                        line,
                        format!(
                            "the solution is not finite at this sample (t = {} s)",
                            m.time_s
                        ),
                    ));
                }
                out.write_all(&line_buf)?;
                if let Some(sp) = spill.as_mut() {
                    if u_line(&mut line_buf, &m, rows == 1) {
                        sp.write_all(&line_buf)?;
                    } else {
                        spill = None;
                    }
                }
            }
            // Full or gone: either way the reader allocates instead.
            let _ = back_tx.try_send(batch);
        }
        Ok(())
    });
    // A write failure: nothing more can be written.
    if let Err(StreamError::Write(e)) = outcome {
        return Err(StreamError::Write(e));
    }
    let outcome = match (outcome, summary) {
        (Ok(()), Some(s)) => Ok(s),
        (Ok(()), None) => Err(StreamError::Input(
            InputError::file(&name, "the series ended without its summary").into(),
        )),
        (Err(e), _) => Err(e),
    };
    let error = match &outcome {
        Err(e) => Some(e.to_string()),
        Ok(_) => None,
    };
    buf.clear();
    if format == SolutionFormat::Json {
        buf.extend_from_slice(b"\n  ],\n  \"uncertainty\": ");
        match spill.take() {
            Some(sp) => {
                let scratch = sp.into_inner().map_err(|e| e.into_error())?;
                buf.extend_from_slice(b"[\n");
                out.write_all(&buf)?;
                buf.clear();
                let end = scratch.stream_position()?;
                scratch.seek(SeekFrom::Start(scratch_start))?;
                std::io::copy(&mut scratch.take(end - scratch_start), out)?;
                buf.extend_from_slice(b"\n  ]");
            }
            None => buf.extend_from_slice(b"null"),
        }
    }
    tail(&mut buf, format, &solver, error.as_deref());
    out.write_all(&buf)?;
    out.flush()?;
    outcome.map(|summary| Solved {
        summary,
        mode: solver.mode().name().to_string(),
        warnings: solver.warnings().to_vec(),
    })
}

/// A finished solve: what the input layer records of the series (rows,
/// SHA-256), the solution mode and the warnings (the JSON forms carry the
/// last two in the output; a front end says them beside a CSV).
#[derive(Debug, Clone)]
pub struct Solved {
    /// Rows and SHA-256 of the series.
    pub summary: incal_io::Summary,
    /// The solution mode's name.
    pub mode: String,
    /// Warnings of the run.
    pub warnings: Vec<crate::Warning>,
}

/// `gfimu solve` as a [`crate::procedures::stream::Stream`]: a motion
/// series solved sample by sample ([`solve_stream`]).
#[derive(Debug, Clone, Copy)]
pub struct Solve;

/// The model of [`Solve`]: the solver (calibration, geometry, options),
/// the geometry whose columns the series has, the output's form, and the
/// scratch that holds a JSON document's `uncertainty` array meanwhile
/// (memory when `None`).
pub struct SolveModel {
    /// The solver ([`Solver::for_calibration`]).
    pub solver: Solver,
    /// The array's geometry (the series' columns).
    pub geometry: Geometry,
    /// CSV, one JSON document or JSON lines.
    pub format: SolutionFormat,
    /// Where the `uncertainty` array waits (module docs).
    pub scratch: Option<Box<dyn Scratch + Send>>,
}

impl crate::procedures::stream::Stream for Solve {
    type Model = SolveModel;

    /// The solution mode is the one note; the warnings are the run's (a
    /// JSON output holds them too).
    fn stream(
        model: SolveModel,
        name: &str,
        input: Box<dyn Read + Send + '_>,
        read: &incal_io::ReadOptions,
        mut out: &mut dyn Write,
    ) -> Result<crate::procedures::stream::Streamed> {
        let SolveModel {
            solver,
            geometry,
            format,
            mut scratch,
        } = model;
        let series = MotionSeries::open(name, input, read, &geometry)?;
        let scratch = scratch.as_mut().map(|s| &mut **s as &mut dyn Scratch);
        match solve_stream(series, solver, format, &mut out, scratch) {
            Ok(s) => Ok(crate::procedures::stream::Streamed {
                rows: s.summary.rows as u64,
                notes: vec![format!("solution mode {}", s.mode)],
                warnings: s.warnings,
            }),
            Err(StreamError::Input(e)) => Err(e),
            Err(StreamError::Write(e)) => {
                Err(Error::Write(format!("cannot write the solution: {e}")))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedures::gfimu::input::{write_motion, ArrayGeometry, Layout};
    use crate::procedures::gfimu::sim::{motion_samples, GfimuTruth, MotionProfile};
    use crate::procedures::gfimu::SolveOptions;

    fn series(array: &ArrayGeometry) -> (Vec<u8>, GfimuTruth) {
        let g = &array.geometry;
        let truth = GfimuTruth::typical(g, 1.0);
        let m = MotionProfile::rate_table();
        let s = motion_samples(g, &truth, &m, 1e-4, 7).unwrap();
        (
            write_motion(s, g, &["a note".into()], Vec::new()).unwrap(),
            truth,
        )
    }

    fn run(
        csv: &[u8],
        array: &ArrayGeometry,
        truth: &GfimuTruth,
        format: SolutionFormat,
    ) -> (String, std::result::Result<incal_io::Summary, StreamError>) {
        let g = &array.geometry;
        let solver =
            Solver::new(g, &truth.calibration(Some(1e-4)), &SolveOptions::default()).unwrap();
        let s = MotionSeries::open("m.csv", csv, &Default::default(), g).unwrap();
        let mut out = Vec::new();
        let r = solve_stream(s, solver, format, &mut out, None).map(|s| s.summary);
        (String::from_utf8(out).unwrap(), r)
    }

    /// The three forms carry the same samples; the JSON document holds
    /// its u array (kept in memory meanwhile) and the input is hashed.
    #[test]
    fn every_form_streams_every_sample() {
        let array = ArrayGeometry::builtin(Layout::Twelve, 0.1).unwrap();
        let (csv, truth) = series(&array);
        let (json, r) = run(&csv, &array, &truth, SolutionFormat::Json);
        let summary = r.unwrap();
        assert_eq!(summary.rows, 201);
        assert_eq!(summary.sha256.len(), 64);
        let d: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(d["samples"].as_array().unwrap().len(), 201);
        assert_eq!(d["uncertainty"].as_array().unwrap().len(), 201);
        assert_eq!(d["mode"], "direct");
        let (lines, _) = run(&csv, &array, &truth, SolutionFormat::JsonLines);
        assert_eq!(lines.lines().count(), 202);
        let (text, _) = run(&csv, &array, &truth, SolutionFormat::Csv);
        assert!(text.starts_with(SOLUTION_CSV_HEADER));
        // A plain CSV: the header and one row per sample, nothing else.
        assert_eq!(text.lines().count(), 202);
        assert!(text.lines().all(|l| !l.starts_with('#')));
    }

    /// A bad row stops the run at its line; the document before it stays
    /// valid JSON and says why it stopped.
    #[test]
    fn a_bad_row_closes_the_document() {
        let array = ArrayGeometry::builtin(Layout::Paper, 0.1).unwrap();
        let (csv, truth) = series(&array);
        let text = String::from_utf8(csv).unwrap();
        let mut lines: Vec<String> = text.lines().map(String::from).collect();
        // Line 20 of the file: a data row (notes and header come first).
        let f: Vec<&str> = lines[19].split(',').collect();
        lines[19] = format!("{},x,{}", f[0], f[2..].join(","));
        let bad = lines.join("\n");
        let (json, r) = run(bad.as_bytes(), &array, &truth, SolutionFormat::Json);
        let e = r.unwrap_err().to_string();
        assert!(e.starts_with("m.csv:20: column 'a'"), "{e}");
        let d: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(d["error"], e.as_str());
        // Lines 3..=19 (after the note and the header) were solved.
        assert_eq!(d["samples"].as_array().unwrap().len(), 17);
    }
}
