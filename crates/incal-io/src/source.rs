//! Opening what the user names: a file path, or `-` for standard input.

use std::io::Read;
use std::path::Path;

use crate::error::{InputError, Result};
use crate::reader::{ReadOptions, Reader, Summary};
use crate::Table;

/// Display name of standard input in messages.
pub const STDIN_NAME: &str = "<stdin>";

/// True when `path` is `-`, the conventional name of stdin / stdout.
pub fn is_dash(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Display name of `path` for messages (`<stdin>` for `-`).
pub fn display_name(path: &Path) -> String {
    if is_dash(path) {
        STDIN_NAME.to_string()
    } else {
        path.display().to_string()
    }
}

/// An opened input: its display name, a reader, and its length when known.
pub struct Opened {
    /// Display name (`<stdin>` for `-`).
    pub name: String,
    /// The bytes.
    pub reader: Box<dyn Read + Send>,
    /// Length in bytes when known (0 otherwise).
    pub size: usize,
}

/// Open `path` (`-`: standard input). Fails with `NAME: cannot read: …`.
pub fn open(path: &Path) -> Result<Opened> {
    let name = display_name(path);
    if is_dash(path) {
        return Ok(Opened {
            name,
            reader: Box::new(std::io::stdin()),
            size: 0,
        });
    }
    let f = std::fs::File::open(path).map_err(|e| InputError::io(&name, &e))?;
    let meta = f.metadata().map_err(|e| InputError::io(&name, &e))?;
    if meta.is_dir() {
        return Err(InputError::file(&name, "cannot read: is a directory"));
    }
    Ok(Opened {
        name,
        reader: Box::new(f),
        size: usize::try_from(meta.len()).unwrap_or(0),
    })
}

/// Read the whole table at `path` (`-`: standard input).
pub fn read_table(path: &Path, opts: &ReadOptions) -> Result<Table> {
    let o = open(path)?;
    Table::read(&o.name, o.reader, opts, o.size)
}

/// Read the table at `path` row by row: `on_header` sees the header once and
/// returns what `on_row` needs (column indexes, say); `on_row` sees every
/// data row. Nothing of the file is kept; returns what a result records of it.
pub fn stream_table<C, E>(
    path: &Path,
    opts: &ReadOptions,
    on_header: impl FnOnce(&crate::Header) -> std::result::Result<C, E>,
    on_row: impl FnMut(&C, &crate::Row<'_>) -> std::result::Result<(), E>,
) -> std::result::Result<Summary, E>
where
    E: From<InputError>,
{
    let o = open(path)?;
    stream(&o.name, o.reader, opts, on_header, on_row)
}

/// As [`stream_table`], from any reader named `name`.
pub fn stream<C, E>(
    name: &str,
    src: impl Read,
    opts: &ReadOptions,
    on_header: impl FnOnce(&crate::Header) -> std::result::Result<C, E>,
    mut on_row: impl FnMut(&C, &crate::Row<'_>) -> std::result::Result<(), E>,
) -> std::result::Result<Summary, E>
where
    E: From<InputError>,
{
    let mut r = Reader::new(name, src, opts)?;
    let ctx = on_header(r.header())?;
    while let Some(row) = r.next_row()? {
        on_row(&ctx, &row)?;
    }
    Ok(r.finish()?)
}

/// Largest document read whole (result documents, calibrations, geometry
/// and limits files): 64 MiB, far above any document incal writes, so a
/// binary file or `/dev/zero` given as one is refused in bounded memory.
pub const MAX_DOCUMENT_BYTES: usize = 64 << 20;

/// The bytes of the document at `path` (`-`: standard input), with their
/// SHA-256 (of the bytes as stored, so it equals `sha256sum FILE`); a
/// leading UTF-8 byte-order mark is stripped from the bytes returned.
/// More than [`MAX_DOCUMENT_BYTES`] is refused (`NAME: larger than 64 MiB
/// …`) without reading further.
pub fn read_hashed(path: &Path) -> Result<(String, Vec<u8>, String)> {
    let o = open(path)?;
    if o.size > MAX_DOCUMENT_BYTES {
        return Err(too_large(&o.name));
    }
    let mut bytes = Vec::with_capacity(o.size);
    o.reader
        .take(MAX_DOCUMENT_BYTES as u64 + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| InputError::io(&o.name, &e))?;
    if bytes.len() > MAX_DOCUMENT_BYTES {
        return Err(too_large(&o.name));
    }
    let sha = crate::sha256_hex(&bytes);
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    Ok((o.name, bytes, sha))
}

fn too_large(name: &str) -> InputError {
    InputError::file(
        name,
        format!(
            "larger than {} MiB: not a document incal reads whole (a result, calibration, geometry or limits file)",
            MAX_DOCUMENT_BYTES >> 20
        ),
    )
}
