//! Raw binary records: little-endian `f32` or `f64` samples of `channels`
//! interleaved channels (one frame per row), read in place from a memory
//! map, never copied whole.
//!
//! The channels are named `ch1`, `ch2`, …; a [`ColumnMap`] selects them
//! (`ch1,ch3`) and renames them (`gx=ch1`) as it does CSV columns. The
//! record's SHA-256 is computed either on a thread of its own, reading the
//! file sequentially through the page cache the map's reading pass fills
//! ([`MappedRecord::hash`] with `background`), or by the reading pass
//! itself, window by window ([`RecordHash::update`]).

use std::path::{Path, PathBuf};

use sha2::Digest;

use crate::error::{clip, InputError, Result};
use crate::ColumnMap;

/// Bytes of a mapped record read between two releases of its pages
/// ([`MappedRecord::release`]): 16 MiB.
pub const WINDOW_BYTES: usize = 16 << 20;

/// Width of one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sample {
    /// Little-endian IEEE 754 binary32.
    F32le,
    /// Little-endian IEEE 754 binary64.
    F64le,
}

impl Sample {
    /// Bytes per sample: 4 or 8.
    #[inline]
    pub fn width(self) -> usize {
        match self {
            Sample::F32le => 4,
            Sample::F64le => 8,
        }
    }
}

/// The bytes of a record: a file's memory map, or a caller's buffer
/// borrowed for the record's life ([`MappedRecord::from_memory`]).
enum Bytes<'a> {
    Map(memmap2::Mmap),
    Borrowed(&'a [u8]),
}

impl std::ops::Deref for Bytes<'_> {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Bytes::Map(m) => m,
            Bytes::Borrowed(b) => b,
        }
    }
}

/// The display name of a record read from memory.
pub const MEMORY_NAME: &str = "<memory>";

/// A record of interleaved little-endian samples: a file's memory map
/// (`MappedRecord<'static>`, [`MappedRecord::open`]) or a buffer a front
/// end holds (a numpy array), borrowed in place for `'a`
/// ([`MappedRecord::from_memory`]).
pub struct MappedRecord<'a> {
    name: String,
    path: PathBuf,
    map: Bytes<'a>,
    channels: usize,
    f64le: bool,
    rows: usize,
}

impl std::fmt::Debug for MappedRecord<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MappedRecord")
            .field("name", &self.name)
            .field("channels", &self.channels)
            .field("f64le", &self.f64le)
            .field("rows", &self.rows)
            .finish()
    }
}

impl MappedRecord<'static> {
    /// Map the file at `path` as frames of `channels` samples. Refuses
    /// standard input (`-`: it cannot be mapped), no channel, a file that
    /// cannot be read or mapped, an empty file and a length that is not a
    /// whole number of frames.
    pub fn open(path: &Path, channels: usize, sample: Sample) -> Result<Self> {
        let name = crate::display_name(path);
        if crate::is_dash(path) {
            return Err(InputError::file(
                &name,
                "a binary record must be a file (memory-mapped), not standard input",
            ));
        }
        check_channels(&name, channels)?;
        let file = std::fs::File::open(path).map_err(|e| InputError::io(&name, &e))?;
        // SAFETY: the map is read-only and private to this process; the
        // file is not modified while incal runs (a concurrent writer would
        // give wrong numbers, not memory unsafety beyond what reading a
        // changing file does).
        let map = unsafe { memmap2::Mmap::map(&file) }
            .map_err(|e| InputError::file(&name, format!("cannot map: {e}")))?;
        MappedRecord::new(name, path.to_path_buf(), Bytes::Map(map), channels, sample)
    }
}

fn check_channels(name: &str, channels: usize) -> Result<()> {
    if channels == 0 {
        return Err(InputError::file(
            name,
            "a binary record needs at least 1 channel",
        ));
    }
    Ok(())
}

impl<'a> MappedRecord<'a> {
    /// The record held in `bytes` (a numpy array's buffer), read in place
    /// for as long as the record lives, never copied: named
    /// [`MEMORY_NAME`]; its SHA-256 is of `bytes`. The same checks as
    /// [`MappedRecord::open`].
    pub fn from_memory(bytes: &'a [u8], channels: usize, sample: Sample) -> Result<Self> {
        check_channels(MEMORY_NAME, channels)?;
        MappedRecord::new(
            MEMORY_NAME.to_string(),
            PathBuf::from(MEMORY_NAME),
            Bytes::Borrowed(bytes),
            channels,
            sample,
        )
    }

    fn new(
        name: String,
        path: PathBuf,
        map: Bytes<'a>,
        channels: usize,
        sample: Sample,
    ) -> Result<Self> {
        let frame = sample.width() * channels;
        if map.is_empty() {
            return Err(InputError::file(&name, "empty file"));
        }
        if map.len() % frame != 0 {
            return Err(InputError::file(
                &name,
                format!(
                    "{} bytes is not a whole number of {channels}-channel frames of {frame} bytes",
                    map.len()
                ),
            ));
        }
        let rows = map.len() / frame;
        Ok(Self {
            name,
            path,
            map,
            channels,
            f64le: sample == Sample::F64le,
            rows,
        })
    }

    /// The file as the user named it (for messages and result documents).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Frames (rows) in the record.
    #[inline]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Channels per frame.
    #[inline]
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// True for `f64` samples, false for `f32`.
    #[inline]
    pub fn f64le(&self) -> bool {
        self.f64le
    }

    /// Bytes per sample: 4 or 8.
    #[inline]
    pub fn width(&self) -> usize {
        if self.f64le {
            8
        } else {
            4
        }
    }

    /// Bytes per frame (row).
    #[inline]
    pub fn frame(&self) -> usize {
        self.channels * self.width()
    }

    /// Rows per release window ([`WINDOW_BYTES`], at least one row).
    #[inline]
    pub fn window_rows(&self) -> usize {
        (WINDOW_BYTES / self.frame()).max(1)
    }

    /// The bytes of rows `[from, to)`.
    #[inline]
    pub fn bytes(&self, from: usize, to: usize) -> &[u8] {
        let frame = self.frame();
        &self.map[from * frame..to * frame]
    }

    /// Sample `r` of channel `c` (0-based), as `f64`.
    #[inline]
    pub fn get(&self, c: usize, r: usize) -> f64 {
        decode(self.f64le, &self.map, r * self.frame() + c * self.width())
    }

    /// Give the pages of rows `[from, to)` back to the kernel once they
    /// are read, so a record is never resident twice (the map and what is
    /// built from it): peak memory stays near one copy. A page read again
    /// is faulted in from the file.
    pub fn release(&self, from: usize, to: usize) {
        let frame = self.frame();
        if let Bytes::Map(m) = &self.map {
            release_bytes(m, from * frame, to * frame);
        }
    }

    /// The channels `selection` picks, in its order, with their names: every
    /// channel (`ch1`, `ch2`, …) when it is empty; a bare `NAME` selects
    /// channel `NAME`, `NAME=chK` reads channel K as `NAME`. A channel that
    /// does not exist is refused, naming the channels there are.
    pub fn select(&self, selection: &ColumnMap) -> Result<Vec<(usize, String)>> {
        let n = self.channels;
        if selection.is_empty() {
            return Ok((0..n).map(|k| (k, format!("ch{}", k + 1))).collect());
        }
        selection
            .entries()
            .iter()
            .map(|e| {
                let src = e.source();
                (1..=n)
                    .find(|k| format!("ch{k}") == src)
                    .map(|k| (k - 1, e.name.clone()))
                    .ok_or_else(|| {
                        InputError::file(
                            &self.name,
                            format!("no channel '{}' (channels: ch1..ch{n})", clip(src)),
                        )
                    })
            })
            .collect()
    }

    /// The record's SHA-256: on a thread of its own when `background`
    /// ([`RecordHash::update`] then does nothing), else from the bytes the
    /// reading pass hands to [`RecordHash::update`] (every byte, in order).
    ///
    /// SHA-256 runs on one core only (each block chains on the one before,
    /// about 1.3 GB/s): on the reading pass's critical path it held a
    /// 10⁸-sample record for about 0.6 s while the other core, done with
    /// its work, waited; off it, the hash shares the cores with what comes
    /// after the pass.
    pub fn hash(&self, background: bool) -> RecordHash {
        // A buffer in memory is hashed by the pass: no thread may read it
        // after the record is gone.
        match (background, &self.map) {
            (true, Bytes::Map(_)) => RecordHash::Background(hash_in_background(
                self.name.clone(),
                self.path.clone(),
                self.map.len(),
            )),
            // A borrowed buffer is hashed by the caller on a scoped thread
            // of its own ([`MappedRecord::memory`]).
            (true, Bytes::Borrowed(_)) => RecordHash::Caller,
            _ => RecordHash::InPass(sha2::Sha256::new()),
        }
    }

    /// The whole buffer of a record read from memory (`None` for a file's
    /// map): what [`RecordHash::Caller`] leaves to the caller to hash, on
    /// a thread of its own while the record is read and analysed.
    pub fn memory(&self) -> Option<&'a [u8]> {
        match self.map {
            Bytes::Borrowed(b) => Some(b),
            Bytes::Map(_) => None,
        }
    }
}

/// The SHA-256 of a mapped record, being computed ([`MappedRecord::hash`]).
#[derive(Debug)]
pub enum RecordHash {
    /// Hashed by the reading pass.
    InPass(sha2::Sha256),
    /// Hashed on a thread of its own.
    Background(std::thread::JoinHandle<Result<String>>),
    /// Hashed by the caller ([`MappedRecord::memory`]): `finish` has no
    /// digest to give.
    Caller,
}

impl RecordHash {
    /// The next bytes of the record (in order), when hashed in the pass.
    #[inline]
    pub fn update(&mut self, bytes: &[u8]) {
        if let RecordHash::InPass(h) = self {
            h.update(bytes);
        }
    }

    /// The digest in lower-case hex, waiting for the hashing thread if it
    /// is still running.
    pub fn finish(self, name: &str) -> Result<String> {
        match self {
            RecordHash::InPass(h) => Ok(crate::hex(&h.finalize())),
            RecordHash::Background(t) => t
                .join()
                .unwrap_or_else(|_| Err(InputError::file(name, "input hash: its thread failed"))),
            RecordHash::Caller => Err(InputError::file(
                name,
                "input hash: left to the caller, who gave none",
            )),
        }
    }
}

/// SHA-256 of the file at `path` on a thread of its own, reading it
/// sequentially in a buffer of 1 MiB. The file must still be `len` bytes
/// long (the map's length), or the hash would not be of the bytes read.
fn hash_in_background(
    name: String,
    path: PathBuf,
    len: usize,
) -> std::thread::JoinHandle<Result<String>> {
    std::thread::spawn(move || {
        let err = |e: std::io::Error| InputError::io(&name, &e);
        let f = std::fs::File::open(&path).map_err(err)?;
        let mut h = sha2::Sha256::new();
        // The hasher is an io::Write; copy reads through the BufReader's
        // buffer, 1 MiB at a time.
        let total = std::io::copy(&mut std::io::BufReader::with_capacity(1 << 20, f), &mut h)
            .map_err(err)?;
        if total != len as u64 {
            return Err(InputError::file(
                &name,
                format!("the file changed while it was read ({len} bytes mapped, {total} read)"),
            ));
        }
        Ok(crate::hex(&h.finalize()))
    })
}

/// The little-endian float at byte `at` of `bytes` (`f64` when `f64le`,
/// else `f32` widened), 0 past the end.
#[inline(always)]
pub fn decode(f64le: bool, bytes: &[u8], at: usize) -> f64 {
    if f64le {
        f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap_or([0; 8]))
    } else {
        f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap_or([0; 4])) as f64
    }
}

/// `madvise(MADV_DONTNEED)` on bytes `[a, b)` of a read-only file map
/// (nothing elsewhere than on Unix).
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
