//! `incal noise`: Allan-family deviations with confidence intervals, IEEE
//! Std 952 noise terms and bias stability of every channel of a record;
//! `incal simulate noise`: seeded records with known terms.

use std::io::IsTerminal;
use std::io::Write;
use std::path::{Path, PathBuf};

use clap::ValueEnum;
use incal::document::noise::{document, ChannelResult, Quantity};
use incal::noise::{
    phase_fill, phase_from_rate_with, phase_reference, stability_with_progress, terms,
    StabilityOptions, TauGrid,
};
use incal::sim::noise::{rate_record, NoiseTruth};
use incal::sim::trial_seed;
use rayon::prelude::*;

use crate::error::{usage, CliError, CliResult};
use crate::output::{input_file, ResultArgs};

/// What the channels measure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum QuantityArg {
    /// Gyro (rate in deg/s, rad/s or deg/h).
    Gyro,
    /// Accelerometer (g, mg or m/s2).
    Accel,
    /// Anything else (terms in the input unit).
    Generic,
}

/// Rate samples or their running sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DataArg {
    /// Rate ("frequency") samples in --unit.
    Rate,
    /// Angle or velocity-increment sums ("phase") in --unit times seconds.
    Angle,
}

/// File format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// Text with a header line, comma separated.
    Csv,
    /// Raw little-endian 32-bit floats, channels interleaved.
    F32le,
    /// Raw little-endian 64-bit floats, channels interleaved.
    F64le,
}

/// `incal noise`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Record: CSV with a header (optional time_s column; every other numeric column is a channel) or raw binary (--format).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Sample rate in Hz (τ0 = 1/F).
    #[arg(long)]
    pub rate_hz: f64,
    /// Channels to analyse (CSV column names, comma separated; default every column but time_s).
    #[arg(long, value_delimiter = ',')]
    pub columns: Vec<String>,
    /// What the channels measure: sets the units of the noise terms.
    #[arg(long, value_enum, default_value = "generic")]
    pub quantity: QuantityArg,
    /// Unit of the rate samples: deg/s, rad/s, deg/h (gyro); g, mg, m/s2 (accel); any text (generic). Default deg/s, g, 1.
    #[arg(long)]
    pub unit: Option<String>,
    /// rate: samples are rates; angle: samples are angle (velocity) sums in unit times s.
    #[arg(long, value_enum, default_value = "rate")]
    pub data: DataArg,
    /// Averaging times: octave, decade, all, or N points per decade.
    #[arg(long, default_value = "octave")]
    pub taus: String,
    /// Confidence of the deviation bounds (0 < P < 1).
    #[arg(long, default_value_t = 0.683)]
    pub confidence: f64,
    /// Averaging times (s) of the bias stability (std of the τ-averages), comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = vec![10.0, 100.0])]
    pub stability_tau_s: Vec<f64>,
    /// Input format.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: FormatArg,
    /// Interleaved channels of a binary input.
    #[arg(long)]
    pub channels: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// One thread (same numbers as the parallel default, bit for bit).
    #[arg(long)]
    pub sequential: bool,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// (quantity, unit text, factor from the input unit to the internal unit).
fn unit_of(q: QuantityArg, unit: Option<&str>) -> CliResult<(Quantity, String, f64)> {
    let bad = |u: &str, ok: &str| usage(format!("--unit: '{u}' is not a {ok} unit"));
    Ok(match q {
        QuantityArg::Gyro => {
            let u = unit.unwrap_or("deg/s");
            let f = match u {
                "deg/s" => 1.0,
                "rad/s" => 180.0 / std::f64::consts::PI,
                "deg/h" => 1.0 / 3600.0,
                _ => return Err(bad(u, "gyro (deg/s, rad/s, deg/h)")),
            };
            (Quantity::Gyro, u.to_string(), f)
        }
        QuantityArg::Accel => {
            let u = unit.unwrap_or("g");
            let f = match u {
                "g" => 1.0,
                "mg" => 1e-3,
                "m/s2" => 1.0 / incal::units::STANDARD_GRAVITY_M_S2,
                _ => return Err(bad(u, "accelerometer (g, mg, m/s2)")),
            };
            (Quantity::Accel, u.to_string(), f)
        }
        QuantityArg::Generic => {
            let u = unit.unwrap_or("1").to_string();
            (Quantity::Generic(u.clone()), u, 1.0)
        }
    })
}

/// The channels of a record: names and samples.
struct Record {
    names: Vec<String>,
    data: Samples,
    sha256: Sha256,
    rows: usize,
    /// Per selected channel the array the analysis runs on ([`Build`]),
    /// when the reading pass already built it (mapped files whose arrays
    /// all fit in the file's size).
    built: Option<Vec<Vec<f64>>>,
}

/// The SHA-256 of the input file (hex): computed while reading, or still
/// being computed on a thread of its own ([`hash_in_background`]).
enum Sha256 {
    Done(String),
    Pending(std::thread::JoinHandle<CliResult<String>>),
}

impl Sha256 {
    /// The hex digest, waiting for the hashing thread if it is still
    /// running.
    fn get(self) -> CliResult<String> {
        match self {
            Sha256::Done(h) => Ok(h),
            Sha256::Pending(t) => t
                .join()
                .unwrap_or_else(|_| Err(CliError::Input("input hash: its thread failed".into()))),
        }
    }
}

/// SHA-256 of the file at `path` on a thread of its own, reading it
/// sequentially (through the page cache the memory map's reading pass
/// fills) in a buffer of 1 MiB. SHA-256 runs on one core only (each block
/// chains on the one before) at about 1.3 GB/s here: on the reading
/// pass's critical path it held every 10⁸-sample record for about 0.6 s
/// while the other core, done with the phase, waited; off it, the hash
/// shares the cores with the deviations. The file must still be `len`
/// bytes long (the map's length), or the hash would not be of the bytes
/// analysed.
fn hash_in_background(path: &Path, len: usize) -> std::thread::JoinHandle<CliResult<String>> {
    let path = path.to_path_buf();
    std::thread::spawn(move || {
        let name = path.display().to_string();
        let err = |e: std::io::Error| CliError::Input(format!("{name}: cannot read: {e}"));
        let f = std::fs::File::open(&path).map_err(err)?;
        let mut h = <sha2::Sha256 as sha2::Digest>::new();
        // The hasher is an io::Write; copy reads through the BufReader's
        // buffer, 1 MiB at a time.
        let total = std::io::copy(&mut std::io::BufReader::with_capacity(1 << 20, f), &mut h)
            .map_err(err)?;
        if total != len as u64 {
            return Err(CliError::Input(format!(
                "{name}: the file changed while it was read ({len} bytes mapped, {total} read)"
            )));
        }
        Ok(crate::output::hex(&sha2::Digest::finalize(h)))
    })
}

/// The array each channel is analysed as: the phase of rate samples
/// ([`phase_from_rate_with`]) or the angle samples themselves, times
/// `factor` (input unit to internal unit).
#[derive(Debug, Clone, Copy)]
struct Build {
    factor: f64,
    tau0: f64,
    rate: bool,
}

impl Build {
    /// Length of the array for `rows` samples.
    fn len(&self, rows: usize) -> usize {
        rows + usize::from(self.rate)
    }

    /// The whole array from samples `get(r)` (already × factor): the same
    /// bits as the windows of [`Build::window`].
    fn whole(&self, rows: usize, get: impl Fn(usize) -> f64) -> Vec<f64> {
        if self.rate {
            phase_from_rate_with(rows, self.tau0, get)
        } else {
            (0..rows).map(get).collect()
        }
    }

    /// Rows `r0..r0 + out.len()` of the array, `y(i)` the i-th of them
    /// (already × factor); `acc`: the phase before them, returned moved on
    /// (for angle data `acc + Σ 0·value`: 0 while every value is finite,
    /// NaN for good after one that is not).
    fn window(&self, out: &mut [f64], acc: f64, c: f64, y: impl Fn(usize) -> f64) -> f64 {
        if self.rate {
            phase_fill(out, acc, c, self.tau0, y)
        } else {
            let mut s = acc;
            for (i, o) in out.iter_mut().enumerate() {
                *o = y(i);
                s += 0.0 * *o;
            }
            s
        }
    }
}

/// Where the samples are: parsed columns (CSV), or the memory map of a
/// binary file (read in place: the phase is the only copy).
enum Samples {
    Columns(Vec<Vec<f64>>),
    Mapped {
        map: memmap2::Mmap,
        channels: usize,
        f64le: bool,
        index: Vec<usize>,
    },
}

/// Bytes of a mapped file read between two releases of its pages
/// ([`Samples::release`]).
const WINDOW_BYTES: usize = 16 << 20;

impl Samples {
    /// Bytes per sample of a mapped file (0 for columns).
    fn width(&self) -> usize {
        match self {
            Samples::Columns(_) => 0,
            Samples::Mapped { f64le, .. } => {
                if *f64le {
                    8
                } else {
                    4
                }
            }
        }
    }

    /// Bytes per row (frame) of a mapped file (0 for columns).
    fn frame(&self) -> usize {
        match self {
            Samples::Columns(_) => 0,
            Samples::Mapped { channels, .. } => channels * self.width(),
        }
    }

    /// Rows per release window of a mapped file (every row for columns).
    fn window_rows(&self) -> usize {
        match self {
            Samples::Columns(_) => usize::MAX,
            Samples::Mapped { .. } => (WINDOW_BYTES / self.frame()).max(1),
        }
    }

    /// Give the pages of rows `[from, to)` of a mapped file back to the
    /// kernel once they are read, so a record is never resident twice (the
    /// map and the phase built from it): peak memory stays near one copy.
    /// A page read again is faulted in from the file; columns: nothing.
    fn release(&self, from: usize, to: usize) {
        if let Samples::Mapped { map, .. } = self {
            let frame = self.frame();
            release_bytes(map, from * frame, to * frame);
        }
    }

    /// Sample `r` of selected channel `k`, read in order from row 0: at
    /// each window boundary the window before is released
    /// ([`Samples::release`]). Call `release(0, rows)` after the last row.
    fn get_streamed(&self, k: usize, r: usize, window: usize) -> f64 {
        if r > 0 && r % window == 0 {
            self.release(r - window, r);
        }
        self.get(k, r)
    }

    /// The bytes of rows `[from, to)` of a mapped file (empty for columns).
    fn bytes(&self, from: usize, to: usize) -> &[u8] {
        match self {
            Samples::Columns(_) => &[],
            Samples::Mapped { map, .. } => {
                let frame = self.frame();
                &map[from * frame..to * frame]
            }
        }
    }

    /// Byte offset of selected channel `k` in a frame (0 for columns).
    fn offset(&self, k: usize) -> usize {
        match self {
            Samples::Columns(_) => 0,
            Samples::Mapped { index, .. } => index[k] * self.width(),
        }
    }

    /// Sample `r` of selected channel `k`.
    fn get(&self, k: usize, r: usize) -> f64 {
        match self {
            Samples::Columns(c) => c[k][r],
            Samples::Mapped { map, f64le, .. } => {
                decode(*f64le, map, r * self.frame() + self.offset(k))
            }
        }
    }
}

/// The little-endian float at byte `at` of `bytes` (f64 or f32).
#[inline(always)]
fn decode(f64le: bool, bytes: &[u8], at: usize) -> f64 {
    if f64le {
        f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or([0; 8]))
    } else {
        f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap_or([0; 4])) as f64
    }
}

/// `madvise(MADV_DONTNEED)` on bytes `[a, b)` of a read-only file map.
fn release_bytes(map: &memmap2::Mmap, a: usize, b: usize) {
    let b = b.min(map.len());
    if b <= a {
        return;
    }
    #[cfg(unix)]
    {
        // SAFETY: the map is a private, read-only mapping of a file that
        // is never written through it; dropping its pages only makes the
        // next read fault them in again from the file (same bytes). Any
        // slice borrowed from the map stays valid (the mapping remains).
        let _ = unsafe { map.unchecked_advise_range(memmap2::UncheckedAdvice::DontNeed, a, b - a) };
    }
}

fn read_csv(path: &Path, columns: &[String]) -> CliResult<(String, Record)> {
    let (name, bytes, sha) = crate::io::read_hashed(path)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        CliError::Input(format!("{name}:{line}: not valid UTF-8"))
    })?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(CliError::Input(format!(
            "{name}: empty file: a header line is needed"
        )));
    };
    let head: Vec<String> = header.split(',').map(|h| h.trim().to_string()).collect();
    let pick: Vec<usize> = if columns.is_empty() {
        (0..head.len()).filter(|&k| head[k] != "time_s").collect()
    } else {
        columns
            .iter()
            .map(|c| {
                head.iter().position(|h| h == c).ok_or_else(|| {
                    CliError::Input(format!(
                        "{name}:1: no column '{c}' (columns: {})",
                        head.join(", ")
                    ))
                })
            })
            .collect::<CliResult<_>>()?
    };
    if pick.is_empty() {
        return Err(CliError::Input(format!(
            "{name}:1: no channel column besides time_s"
        )));
    }
    let mut data = vec![Vec::new(); pick.len()];
    let mut rows = 0;
    for (ln, line) in lines {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != head.len() {
            return Err(CliError::Input(format!(
                "{name}:{}: {} fields, the header has {}",
                ln + 1,
                cells.len(),
                head.len()
            )));
        }
        for (d, &k) in data.iter_mut().zip(&pick) {
            let s = cells[k].trim();
            let v: f64 = s.parse().map_err(|_| {
                CliError::Input(format!(
                    "{name}:{}: column {}: '{s}' is not a number",
                    ln + 1,
                    head[k]
                ))
            })?;
            if !v.is_finite() {
                return Err(CliError::Input(format!(
                    "{name}:{}: column {}: '{s}' is not a finite number",
                    ln + 1,
                    head[k]
                )));
            }
            d.push(v);
        }
        rows += 1;
    }
    Ok((
        name,
        Record {
            names: pick.iter().map(|&k| head[k].clone()).collect(),
            data: Samples::Columns(data),
            sha256: Sha256::Done(sha),
            built: None,
            rows,
        },
    ))
}

/// Raw interleaved little-endian floats, memory-mapped: each channel is
/// converted to f64 straight from the map (the file is never copied whole).
fn read_binary(
    path: &Path,
    channels: usize,
    f64le: bool,
    columns: &[String],
    build: Build,
    parallel: bool,
    bar: Option<&indicatif::ProgressBar>,
) -> CliResult<(String, Record)> {
    let name = path.display().to_string();
    if path.as_os_str() == "-" {
        return Err(usage(
            "--format f32le/f64le: the input must be a file (memory-mapped), not standard input",
        ));
    }
    let file = std::fs::File::open(path)
        .map_err(|e| CliError::Input(format!("{name}: cannot read: {e}")))?;
    // SAFETY: the map is read-only and private to this process; the file
    // is not modified while incal runs (a concurrent writer would give wrong
    // numbers, not memory unsafety beyond what reading a changing file does).
    let map = unsafe { memmap2::Mmap::map(&file) }
        .map_err(|e| CliError::Input(format!("{name}: cannot map: {e}")))?;
    let width = if f64le { 8 } else { 4 };
    let frame = width * channels;
    if map.is_empty() {
        return Err(CliError::Input(format!("{name}: empty file")));
    }
    if map.len() % frame != 0 {
        return Err(CliError::Input(format!(
            "{name}: {} bytes is not a whole number of {channels}-channel frames of {frame} bytes",
            map.len()
        )));
    }
    let rows = map.len() / frame;
    if let Some(b) = bar {
        b.set_length(rows as u64);
    }
    let all: Vec<String> = (1..=channels).map(|k| format!("ch{k}")).collect();
    let pick: Vec<usize> = if columns.is_empty() {
        (0..channels).collect()
    } else {
        columns
            .iter()
            .map(|c| {
                all.iter().position(|h| h == c).ok_or_else(|| {
                    CliError::Input(format!(
                        "{name}: no channel '{c}' (channels: ch1..ch{channels})"
                    ))
                })
            })
            .collect::<CliResult<_>>()?
    };
    let data = Samples::Mapped {
        map,
        channels,
        f64le,
        index: pick.clone(),
    };
    // One pass, window by window, each released after (one copy
    // resident): per channel the first non-finite sample (refused before
    // any result) and, when the selected channels' arrays take no more
    // memory than the file, the arrays themselves; the hash of the bytes
    // on a thread of its own that runs on while the deviations start (in
    // this pass with --sequential: one thread).
    let background = parallel.then(|| hash_in_background(path, rows * frame));
    let fused = pick.len() * 8 <= frame;
    let win = data.window_rows();
    let f = build.factor;
    let refs: Vec<f64> = (0..pick.len())
        .map(|k| {
            if fused && build.rate {
                phase_reference(rows, |r| data.get(k, r) * f)
            } else {
                0.0
            }
        })
        .collect();
    let mut built: Vec<Vec<f64>> = (0..if fused { pick.len() } else { 0 })
        .map(|_| vec![0.0; build.len(rows)])
        .collect();
    let mut accs = vec![0.0; pick.len()];
    let mut h = <sha2::Sha256 as sha2::Digest>::new();
    // Per channel the first bad row: a non-finite sample (true) or, with
    // finite samples, the phase overflowing (false).
    let mut bad: Vec<Option<(usize, bool)>> = vec![None; pick.len()];
    let mut r0 = 0;
    while r0 < rows {
        let r1 = (r0 + win).min(rows);
        let mut check = || {
            let bytes = data.bytes(r0, r1);
            for (k, b) in bad.iter_mut().enumerate() {
                if b.is_some() {
                    continue;
                }
                let off = data.offset(k);
                let y = |i: usize| decode(f64le, bytes, i * frame + off) * f;
                let first_bad = || (0..r1 - r0).find(|&i| !y(i).is_finite());
                if fused {
                    let at = usize::from(build.rate) + r0;
                    let out = &mut built[k][at..at + (r1 - r0)];
                    accs[k] = build.window(out, accs[k], refs[k], y);
                    // A non-finite sample makes the running sum non-finite
                    // for good: look for it only then.
                    if !accs[k].is_finite() {
                        *b = Some(match first_bad() {
                            Some(i) => (r0 + i, true),
                            None => (
                                r0 + out.iter().position(|v| !v.is_finite()).unwrap_or(0),
                                false,
                            ),
                        });
                    }
                } else if let Some(i) = first_bad() {
                    *b = Some((r0 + i, true));
                }
            }
        };
        if background.is_none() {
            sha2::Digest::update(&mut h, data.bytes(r0, r1));
        }
        check();
        data.release(r0, r1);
        if let Some(b) = bar {
            b.set_position(r1 as u64);
        }
        r0 = r1;
    }
    let sha = match background {
        Some(t) => Sha256::Pending(t),
        None => Sha256::Done(crate::output::hex(&sha2::Digest::finalize(h))),
    };
    for (k, &c) in pick.iter().enumerate() {
        if let Some((r, sample)) = bad[k] {
            let what = if sample {
                "not a finite number"
            } else {
                "the running sum (phase) of the samples overflows"
            };
            return Err(CliError::Input(format!(
                "{name}: sample {} of {}: {what}",
                r + 1,
                all[c]
            )));
        }
    }
    Ok((
        name,
        Record {
            names: pick.iter().map(|&k| all[k].clone()).collect(),
            data,
            sha256: sha,
            rows,
            built: fused.then_some(built),
        },
    ))
}

/// A progress bar of `len` steps counted as `what` on stderr, when it is a
/// terminal and not `--quiet` (none otherwise).
fn progress(quiet: bool, len: u64, what: &str) -> Option<indicatif::ProgressBar> {
    (!quiet && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::new(len);
        b.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{msg}} [{{bar:40}}] {{pos}}/{{len}} {what} {{elapsed}}"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_message("incal noise");
        b
    })
}

/// `incal noise`.
pub fn run(a: &Args) -> CliResult<()> {
    if !(a.rate_hz.is_finite() && a.rate_hz > 0.0) {
        return Err(usage("--rate-hz must be a positive number"));
    }
    if !(a.confidence > 0.0 && a.confidence < 1.0) {
        return Err(usage("--confidence must be between 0 and 1 (e.g. 0.683)"));
    }
    let grid = TauGrid::parse(&a.taus).ok_or_else(|| {
        usage(format!(
            "--taus: '{}' is not octave, decade, all or a number of points per decade (1-1000)",
            a.taus
        ))
    })?;
    if let Some(t) = a
        .stability_tau_s
        .iter()
        .find(|t| !(t.is_finite() && **t > 0.0))
    {
        return Err(usage(format!(
            "--stability-tau-s: {t} is not a positive time"
        )));
    }
    let (quantity, unit, factor) = unit_of(a.quantity, a.unit.as_deref())?;
    let tau0 = 1.0 / a.rate_hz;
    let build = Build {
        factor,
        tau0,
        rate: a.data == DataArg::Rate,
    };
    let (name, rec) = match a.format {
        FormatArg::Csv => {
            if a.channels.is_some() {
                return Err(usage("--channels goes with --format f32le or f64le"));
            }
            read_csv(&a.input, &a.columns)?
        }
        FormatArg::F32le | FormatArg::F64le => {
            let ch = a.channels.ok_or_else(|| {
                usage("--format f32le/f64le needs --channels N (interleaved channels)")
            })?;
            if ch == 0 {
                return Err(usage("--channels must be at least 1"));
            }
            // The reading pass (about a second per 10^8 samples) shows
            // its own bar, as the averaging times do after it.
            let bar = progress(a.quiet, 0, "rows read");
            let read = read_binary(
                &a.input,
                ch,
                a.format == FormatArg::F64le,
                &a.columns,
                build,
                !a.sequential,
                bar.as_ref(),
            );
            if let Some(b) = bar {
                b.finish_and_clear();
            }
            read?
        }
    };
    let min = if a.data == DataArg::Rate { 4 } else { 5 };
    if rec.rows < min {
        return Err(CliError::Input(format!(
            "{name}: {} samples; at least {min} are needed for one averaging time",
            rec.rows
        )));
    }
    let opts = StabilityOptions {
        tau0_s: tau0,
        grid,
        confidence: a.confidence,
        parallel: !a.sequential,
    };
    let total = (grid.factors(rec.rows + 1).len() * rec.names.len()) as u64;
    let bar = progress(a.quiet, total, "averaging times");
    let one = |k: usize| -> CliResult<ChannelResult> {
        let d = &rec.data;
        let win = d.window_rows();
        // Read in windows, each released once read: the phase is the only
        // resident copy of the channel.
        let get = |r: usize| d.get_streamed(k, r, win) * factor;
        let whole;
        let x: &[f64] = match &rec.built {
            Some(b) => &b[k],
            None => {
                whole = build.whole(rec.rows, get);
                d.release(0, rec.rows);
                &whole
            }
        };
        let tick = |_: usize| {
            if let Some(b) = &bar {
                b.inc(1);
            }
        };
        let st = stability_with_progress(x, &opts, &tick)
            .map_err(|e| CliError::Input(format!("{name}: channel {}: {e}", rec.names[k])))?;
        let fit = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, tau0)
            .map_err(|e| CliError::Input(format!("{name}: channel {}: {e}", rec.names[k])))?;
        let slope = terms::slope_readings(&st.taus_s, &st.oadev);
        let bias_stability = a
            .stability_tau_s
            .iter()
            .map(|&t| (t, terms::bias_stability(x, tau0, t)))
            .collect();
        Ok(ChannelResult {
            name: rec.names[k].clone(),
            samples: rec.rows,
            stability: st,
            fit,
            slope,
            bias_stability,
            to_input: 1.0 / factor,
        })
    };
    let results: Vec<ChannelResult> = if a.sequential {
        (0..rec.names.len()).map(one).collect::<CliResult<_>>()?
    } else {
        (0..rec.names.len())
            .into_par_iter()
            .map(one)
            .collect::<CliResult<_>>()?
    };
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let tables = grid != TauGrid::All;
    let mut doc =
        document(&results, &quantity, &unit, a.confidence, tables).map_err(crate::error::core)?;
    let shown = if name == "<stdin>" {
        "-".to_string()
    } else {
        name.clone()
    };
    doc.inputs.push(input_file(
        "input",
        &shown,
        rec.sha256.get()?,
        Some(rec.rows),
    ));
    for (k, v) in [
        ("rate-hz", serde_json::json!(a.rate_hz)),
        (
            "quantity",
            serde_json::json!(format!("{:?}", a.quantity).to_lowercase()),
        ),
        ("unit", serde_json::json!(unit)),
        (
            "data",
            serde_json::json!(format!("{:?}", a.data).to_lowercase()),
        ),
        ("taus", serde_json::json!(a.taus)),
        ("stability-tau-s", serde_json::json!(a.stability_tau_s)),
    ] {
        doc.options.insert(k.to_string(), v);
    }
    a.result.emit(doc)
}

/// `incal simulate noise`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// What to simulate: gyro (rate in deg/s, the --arw-deg-rth ... options) or accel (in g, the --vrw-ug-rthz ... options).
    #[arg(long, value_enum, default_value = "gyro")]
    pub quantity: QuantityArg,
    /// Accelerometer: velocity random walk N, ug/sqrt(Hz).
    #[arg(long, default_value_t = 0.0)]
    pub vrw_ug_rthz: f64,
    /// Accelerometer: bias instability B, ug (flicker, Kasdin & Walter).
    #[arg(long, default_value_t = 0.0)]
    pub bias_instability_ug: f64,
    /// Accelerometer: acceleration random walk K, ug/sqrt(s).
    #[arg(long, default_value_t = 0.0)]
    pub accel_rw_ug_rts: f64,
    /// Accelerometer: velocity quantization Q, m/s.
    #[arg(long, default_value_t = 0.0)]
    pub quantization_m_s: f64,
    /// Accelerometer: acceleration ramp R, ug/s.
    #[arg(long, default_value_t = 0.0)]
    pub accel_ramp_ug_s: f64,
    /// Angle random walk N, deg/sqrt(h).
    #[arg(long, default_value_t = 0.0)]
    pub arw_deg_rth: f64,
    /// Bias instability B, deg/h (flicker rate, Kasdin & Walter).
    #[arg(long, default_value_t = 0.0)]
    pub bias_instability_deg_h: f64,
    /// Rate random walk K, deg/h/sqrt(h).
    #[arg(long, default_value_t = 0.0)]
    pub rrw_deg_h_rth: f64,
    /// Angle quantization Q, arcsec.
    #[arg(long, default_value_t = 0.0)]
    pub quantization_arcsec: f64,
    /// Rate ramp R, deg/h^2.
    #[arg(long, default_value_t = 0.0)]
    pub rate_ramp_deg_h2: f64,
    /// Sample rate, Hz.
    #[arg(long)]
    pub rate_hz: f64,
    /// Record length, s.
    #[arg(long)]
    pub duration_s: f64,
    /// Channels (independent, seeded from --seed).
    #[arg(long, default_value_t = 1)]
    pub channels: usize,
    /// Random seed.
    #[arg(long)]
    pub seed: u64,
    /// Output format: csv (time_s,ch1,...) or raw interleaved f32le / f64le.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: FormatArg,
    /// Output file (- = standard output, csv only).
    #[arg(long, short = 'o')]
    pub output: PathBuf,
}

/// `incal simulate noise`: rate samples in deg/s (gyro) or g (accel).
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let gyro_opts = [
        ("--arw-deg-rth", a.arw_deg_rth),
        ("--bias-instability-deg-h", a.bias_instability_deg_h),
        ("--rrw-deg-h-rth", a.rrw_deg_h_rth),
        ("--quantization-arcsec", a.quantization_arcsec),
        ("--rate-ramp-deg-h2", a.rate_ramp_deg_h2),
    ];
    let accel_opts = [
        ("--vrw-ug-rthz", a.vrw_ug_rthz),
        ("--bias-instability-ug", a.bias_instability_ug),
        ("--accel-rw-ug-rts", a.accel_rw_ug_rts),
        ("--quantization-m-s", a.quantization_m_s),
        ("--accel-ramp-ug-s", a.accel_ramp_ug_s),
    ];
    // One option, one meaning: a term option of the other quantity is refused.
    let (mine, other, what) = match a.quantity {
        QuantityArg::Gyro => (&gyro_opts, &accel_opts, "gyro"),
        QuantityArg::Accel => (&accel_opts, &gyro_opts, "accel"),
        QuantityArg::Generic => {
            return Err(usage(
                "simulate noise: --quantity gyro or accel (a generic quantity has no term units to simulate)",
            ))
        }
    };
    if let Some((n, _)) = other.iter().find(|(_, v)| *v != 0.0) {
        return Err(usage(format!("{n} is not a term of --quantity {what}")));
    }
    for (n, v) in mine.iter().take(4) {
        if !(v.is_finite() && *v >= 0.0) {
            return Err(usage(format!("{n} must be a non-negative number")));
        }
    }
    if !mine[4].1.is_finite() {
        return Err(usage(format!("{} must be a finite number", mine[4].0)));
    }
    if !(a.rate_hz.is_finite() && a.rate_hz > 0.0) {
        return Err(usage("--rate-hz must be a positive number"));
    }
    let n = a.duration_s * a.rate_hz;
    if !(n.is_finite() && (4.0..=1e9).contains(&n)) {
        return Err(usage(
            "--duration-s times --rate-hz must give between 4 and 1e9 samples",
        ));
    }
    if a.channels == 0 || a.channels > 64 {
        return Err(usage("--channels must be 1 to 64"));
    }
    let n = n.round() as usize;
    let tau0 = 1.0 / a.rate_hz;
    let truth = match a.quantity {
        // Gyro units to the deg/s base of the simulator.
        QuantityArg::Gyro => NoiseTruth {
            q: a.quantization_arcsec / 3600.0,
            n: a.arw_deg_rth / 60.0,
            b: a.bias_instability_deg_h / 3600.0,
            k: a.rrw_deg_h_rth / 216_000.0,
            r: a.rate_ramp_deg_h2 / (3600.0 * 3600.0),
        },
        // Accelerometer units to the g base (ug/sqrt(Hz) = 1e-6 g*sqrt(s)).
        _ => NoiseTruth {
            q: a.quantization_m_s / incal::units::STANDARD_GRAVITY_M_S2,
            n: a.vrw_ug_rthz * 1e-6,
            b: a.bias_instability_ug * 1e-6,
            k: a.accel_rw_ug_rts * 1e-6,
            r: a.accel_ramp_ug_s * 1e-6,
        },
    };
    let binary = matches!(a.format, FormatArg::F32le | FormatArg::F64le);
    if binary && a.output.as_os_str() == "-" {
        return Err(usage(
            "--format f32le/f64le writes a file, not standard output",
        ));
    }
    // The output is opened before the (possibly long) simulation, so a
    // path that cannot be written fails at once.
    let cannot = |e: std::io::Error| {
        CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", a.output.display()))
    };
    let file = if a.output.as_os_str() == "-" {
        None
    } else {
        Some(std::fs::File::create(&a.output).map_err(cannot)?)
    };
    let chans: Vec<Vec<f64>> = (0..a.channels)
        .into_par_iter()
        .map(|c| rate_record(&truth, tau0, n, trial_seed(a.seed, c as u64)))
        .collect();
    if a.format == FormatArg::Csv {
        let mut text = String::with_capacity(n * 24 * a.channels);
        text.push_str("time_s");
        for c in 1..=a.channels {
            text.push_str(&format!(",ch{c}"));
        }
        text.push('\n');
        for i in 0..n {
            text.push_str(&format!("{}", i as f64 * tau0));
            for ch in &chans {
                text.push_str(&format!(",{}", ch[i]));
            }
            text.push('\n');
        }
        return match file {
            Some(mut f) => f.write_all(text.as_bytes()).map_err(cannot),
            None => crate::io::write_text(Some(&a.output), &text),
        };
    }
    // Binary: streamed through a buffer (no second copy of the record).
    let mut out = std::io::BufWriter::with_capacity(1 << 20, file.expect("checked above"));
    for i in 0..n {
        for ch in &chans {
            if a.format == FormatArg::F64le {
                out.write_all(&ch[i].to_le_bytes())
            } else {
                out.write_all(&(ch[i] as f32).to_le_bytes())
            }
            .map_err(cannot)?;
        }
    }
    out.flush().map_err(cannot)
}
