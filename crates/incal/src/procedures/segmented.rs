//! A continuous rig log read as the labelled recording a procedure expects
//! ([`incal_io::segments`]): every reduction reads through [`open`], which
//! cuts the log into plateaus of `--segment-by`'s column when asked and
//! otherwise reads the file as it is; [`record`] writes what it did into
//! the document (the table `segments` and the object `segmentation`).

use std::io::Read;

use crate::document::{Cell, ResultDocument, Table};
use crate::error::Result;
use crate::units::Unit;

/// What a segmented read keeps of the file itself.
pub struct Original {
    /// The file's own summary (its SHA-256, rows and preamble).
    pub summary: incal_io::Summary,
    /// The plateaus.
    pub segmented: incal_io::Segmented,
    /// How they were found.
    pub spec: incal_io::SegmentSpec,
}

/// The rows a procedure reads: the file's, or its plateaus' when
/// `read.segment` is set (then with the file's own summary).
pub type Opened<'a> = (incal_io::Reader<Box<dyn Read + 'a>>, Option<Original>);

/// Open `src` (named `name`) for a reduction (module docs).
pub fn open<'a, R: Read + 'a>(
    name: &str,
    src: R,
    read: &incal_io::ReadOptions,
) -> Result<Opened<'a>> {
    let Some(spec) = &read.segment else {
        let boxed: Box<dyn Read + 'a> = Box::new(src);
        return Ok((incal_io::Reader::new(name, boxed, read)?, None));
    };
    let whole = incal_io::ReadOptions {
        segment: None,
        ..read.clone()
    };
    let table = incal_io::Table::read(name, src, &whole, 0)?;
    let mut segmented = incal_io::segments::segment(&table, spec)?;
    let columns = incal_io::ColumnMap::from_entries(&segmented.selected)
        .map_err(|m| crate::Error::Unsupported(format!("--columns: {m}")))?;
    let again = incal_io::ReadOptions {
        delimiter: Some(b','),
        columns,
        hash: false,
        frames: false,
        header_line: None,
        segment: None,
        max_line_bytes: read.max_line_bytes,
        full_scale: read.full_scale,
        log: incal_io::logs::LogOptions::default(),
    };
    // The text moves to the reader; the document needs only the plateaus.
    let text: Box<dyn Read + 'a> =
        Box::new(std::io::Cursor::new(std::mem::take(&mut segmented.text)));
    let rows = incal_io::Reader::new(name, text, &again)?;
    Ok((
        rows,
        Some(Original {
            summary: table.summary().clone(),
            segmented,
            spec: spec.clone(),
        }),
    ))
}

/// Record the plateaus in `doc`: the table `segments` (one row per
/// plateau: its times, first kept and last file line, rows kept and
/// dropped while settling, the mean, scatter and the mean's standard
/// uncertainty `s/√n` of the rig channel, and the nominal value given to
/// it) and `segmentation` (the column, the settings
/// and the rows dropped while moving, and `carried`: the option and ppm
/// [`carry`] added).
pub fn record(
    doc: &mut ResultDocument,
    original: &Original,
    carried: Option<(&str, f64)>,
) -> Result<()> {
    let s = Unit::Other("s".into());
    let mut t = Table::new(
        "segments",
        &format!("Plateaus of {}", original.spec.column),
        &[
            ("start", Some(s.clone())),
            ("kept_from", Some(s.clone())),
            ("end", Some(s)),
            ("first_line", None),
            ("last_line", None),
            ("rows_kept", None),
            ("rows_settling", None),
            ("mean", None),
            ("scatter", None),
            ("u_mean", None),
            ("value", None),
        ],
    );
    for g in &original.segmented.segments {
        t.push(vec![
            Cell::num(g.start_s),
            Cell::num(g.kept_from_s),
            Cell::num(g.end_s),
            Cell::num(g.lines.0 as f64),
            Cell::num(g.lines.1 as f64),
            Cell::num(g.rows_kept as f64),
            Cell::num(g.rows_dropped as f64),
            Cell::num(g.mean),
            Cell::num(g.scatter),
            Cell::num(g.scatter / (g.rows_kept as f64).sqrt()),
            Cell::num(g.value),
        ])?;
    }
    doc.tables.push(t);
    let spec = &original.spec;
    doc.extra.insert(
        "segmentation".into(),
        serde_json::json!({
            "column": spec.column,
            "tolerance": spec.tolerance,
            "settle_s": spec.settle_s,
            "min_s": spec.min_s,
            "values": if spec.values.is_empty() { serde_json::Value::Null } else { serde_json::json!(spec.values) },
            "plateaus": original.segmented.segments.len(),
            "rows_moving": original.segmented.moving_rows,
            "carried": carried.map(|(k, ppm)| serde_json::json!({"option": k, "ppm": ppm})),
        }),
    );
    Ok(())
}

/// Options that take the rig channel's relative standard uncertainty
/// (ppm, type B), by the column they are about.
const CARRIED: [(&str, &str); 2] = [
    ("rate_deg_s", "rate_uncertainty_ppm"),
    ("omega_rad_s", "u_omega_ppm"),
];

/// Carry the plateaus' own uncertainty into the procedure's type-B input
/// where their means are the nominal values (no plan list): the largest
/// relative standard uncertainty of a plateau's mean, `s/(√n |x̄|)` over the
/// plateaus away from zero, added in quadrature to the option that takes
/// it (`rate_uncertainty_ppm` of gyro rate, `u_omega_ppm` of the
/// centrifuge). `None` when nothing is carried; the key and ppm added
/// otherwise.
pub fn carry<P: super::Procedure>(
    options: &P::Options,
    original: &Original,
) -> Result<Option<(P::Options, &'static str, f64)>> {
    if !original.spec.values.is_empty() {
        return Ok(None);
    }
    let Some((_, key)) = CARRIED.iter().find(|(c, _)| *c == original.spec.column) else {
        return Ok(None);
    };
    let Ok(serde_json::Value::Object(mut m)) = serde_json::to_value(options) else {
        return Ok(None);
    };
    let Some(given) = m.get(*key).and_then(|v| v.as_f64()) else {
        return Ok(None);
    };
    let ppm = original
        .segmented
        .segments
        .iter()
        .filter(|s| {
            s.mean.abs() > 1e3 * s.scatter.max(f64::MIN_POSITIVE) / (s.rows_kept as f64).sqrt()
        })
        .map(|s| 1e6 * s.scatter / ((s.rows_kept as f64).sqrt() * s.mean.abs()))
        .fold(0.0, f64::max);
    if ppm == 0.0 {
        return Ok(None);
    }
    m.insert((*key).into(), serde_json::json!(given.hypot(ppm)));
    let carried: P::Options = crate::options::from_json(&serde_json::Value::Object(m))?;
    P::validate(&carried)?;
    Ok(Some((carried, key, ppm)))
}
