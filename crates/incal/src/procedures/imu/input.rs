//! Reading IMU sessions: columns, segmentation and checks of the three
//! procedures' recordings, row by row through the input layer, and the CSV
//! writer of simulated sessions.
//!
//! # Columns
//! * `acc_x, acc_y, acc_z`: raw accelerometer outputs; `gyr_x, gyr_y,
//!   gyr_z`: raw gyro outputs (any unit: counts or physical). A triad is
//!   all three columns or none.
//! * `time_s` (optional): time (s), strictly increasing.
//! * Ferraris: `part`, one of [`super::ferraris::SECTIONS`] per row, or
//!   empty for rows between sections.
//! * Multi-position: `position` (a label: 1 to 3 face labels joined by `+`,
//!   see [`position_direction`]; `x_rot`, `y_rot`, `z_rot` for rotations;
//!   empty between positions) and/or `fx, fy, fz` (the unit up direction in
//!   the IMU frame); `nx, ny, nz` (optional: the unit north direction).
//!   Consecutive rows of one position are its samples.
//!
//! Other columns are ignored.

use std::io::Read;

use incal_io::{clip, InputError, Reader, Row};

use super::ferraris::SECTIONS;
use super::multipos::{RotationSection, StaticPosition};
use super::sim::{ImuSample, Layout};
use super::{SectionStats, V3};
use crate::error::{Error, Result};
use crate::timebase::TimeBase;
use crate::warning::{Warning, WarningCode};

/// Accelerometer columns of a session.
pub const ACC: [&str; 3] = ["acc_x", "acc_y", "acc_z"];
/// The six channels of a session sample, in its order.
pub const CHANNELS: [&str; 6] = ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"];
/// Gyro columns of a session.
pub const GYR: [&str; 3] = ["gyr_x", "gyr_y", "gyr_z"];
/// Labels of the rotation sections, about x, y and z.
pub const ROTATIONS: [&str; 3] = ["x_rot", "y_rot", "z_rot"];

use crate::error::short_f64 as num;

/// Direction of a position label: one to three face labels (`x_p`, `y_a`,
/// …) on different axes joined by `+`; the normalised sum of their unit
/// vectors (`x_p` is +x up, `x_a` is −x up). `x_p+y_p` is the edge between
/// two faces (45°), `x_p+y_p+z_p` a corner.
pub fn position_direction(label: &str) -> std::result::Result<V3, String> {
    let mut v = V3::zeros();
    let mut used = [false; 3];
    let parts: Vec<&str> = label.split('+').collect();
    if parts.is_empty() || parts.len() > 3 {
        return Err(format!(
            "position '{}' is not 1 to 3 face labels joined by '+'",
            clip(label)
        ));
    }
    for p in parts {
        let (axis, sign) = match p.trim() {
            "x_p" => (0, 1.0),
            "x_a" => (0, -1.0),
            "y_p" => (1, 1.0),
            "y_a" => (1, -1.0),
            "z_p" => (2, 1.0),
            "z_a" => (2, -1.0),
            other => {
                return Err(format!(
                    "position '{}': '{}' is not a face label (x_p, x_a, y_p, y_a, z_p, z_a)",
                    clip(label),
                    clip(other)
                ))
            }
        };
        if used[axis] {
            return Err(format!(
                "position '{}' names the {} axis twice",
                clip(label),
                super::AXES[axis]
            ));
        }
        used[axis] = true;
        v[axis] = sign;
    }
    let n = v.norm();
    Ok(v / n)
}

/// The columns of a triad: none of them (`None`), or all three (a partial
/// triad is refused naming the missing column).
fn triad_columns(h: &incal_io::Header, names: [&str; 3]) -> Result<Option<[usize; 3]>> {
    if names.iter().all(|n| h.opt_column(n).is_none()) {
        return Ok(None);
    }
    Ok(Some([
        h.column(names[0])?,
        h.column(names[1])?,
        h.column(names[2])?,
    ]))
}

/// Where a session holds its time and triads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionColumns {
    /// `time_s`, when present.
    pub time: Option<usize>,
    /// The accelerometer triad, when present.
    pub acc: Option<[usize; 3]>,
    /// The gyro triad, when present.
    pub gyr: Option<[usize; 3]>,
}

impl SessionColumns {
    /// The session columns of a header; `need_acc`/`need_gyr` make a
    /// triad required, and one of the two always is (the accelerometer's
    /// is named when neither is there).
    pub fn of(h: &incal_io::Header, need_acc: bool, need_gyr: bool) -> Result<SessionColumns> {
        let acc = triad_columns(h, ACC)?;
        let gyr = triad_columns(h, GYR)?;
        if need_acc && acc.is_none() {
            h.column(ACC[0])?;
        }
        if need_gyr && gyr.is_none() {
            h.column(GYR[0])?;
        }
        if acc.is_none() && gyr.is_none() {
            h.column(ACC[0])?;
        }
        Ok(SessionColumns {
            time: h.opt_column("time_s"),
            acc,
            gyr,
        })
    }
}

/// One row of a session: time (when the file has it) and the triads
/// present.
#[derive(Debug, Clone, Copy, PartialEq)]
struct SessionRow {
    time: Option<f64>,
    acc: Option<[f64; 3]>,
    gyr: Option<[f64; 3]>,
}

impl SessionRow {
    /// Accelerometer then gyro channels; a missing triad is zero.
    fn six(&self) -> [f64; 6] {
        let a = self.acc.unwrap_or([0.0; 3]);
        let g = self.gyr.unwrap_or([0.0; 3]);
        [a[0], a[1], a[2], g[0], g[1], g[2]]
    }
}

/// Reads session rows, keeping every `time_s` stamp; a stamp below the
/// one before is refused at its line (repeats are the time base's to
/// judge, [`crate::timebase`]).
struct SessionReader {
    cols: SessionColumns,
    stamps: Vec<f64>,
    /// `--sort-time`: keep stamps out of order (sorted after reading).
    sort: bool,
}

impl SessionReader {
    fn new(cols: SessionColumns) -> Self {
        Self {
            cols,
            stamps: Vec::new(),
            sort: false,
        }
    }

    /// The time base of the stamps read (none without `time_s`); a
    /// nominal rate that contradicts them is refused naming both.
    fn timebase(&self, file: &str, nominal_hz: Option<f64>) -> Result<Option<TimeBase>> {
        if self.cols.time.is_none() {
            return Ok(None);
        }
        crate::timebase::analyse(&self.stamps, nominal_hz)
            .map(Some)
            .map_err(|e| Error::Unsupported(e.to_string()).in_file(file))
    }

    fn read(&mut self, row: &Row<'_>) -> Result<SessionRow> {
        let triad = |c: Option<[usize; 3]>| -> Result<Option<[f64; 3]>> {
            match c {
                Some([x, y, z]) => Ok(Some([row.f64(x)?, row.f64(y)?, row.f64(z)?])),
                None => Ok(None),
            }
        };
        let acc = triad(self.cols.acc)?;
        let gyr = triad(self.cols.gyr)?;
        let time = match self.cols.time {
            None => None,
            Some(c) => {
                let x = row.f64(c)?;
                crate::timebase::push_stamp(&mut self.stamps, x, self.sort)
                    .map_err(|m| row.error(m))?;
                Some(x)
            }
        };
        Ok(SessionRow { time, acc, gyr })
    }
}

/// Refuse a rotation section that spans or borders a gap of the time
/// base: its integral (samples × 1/rate) would miss the rotation made
/// while no samples came (a gap right before or after the section may hide
/// its start or end). `spans`: each rotation section's label and the stamp
/// indices of its consecutive samples (first, last).
fn check_rotation_gaps(
    file: &str,
    tb: Option<&TimeBase>,
    spans: &[(String, usize, usize)],
) -> Result<()> {
    let Some(tb) = tb else { return Ok(()) };
    for g in &tb.gaps {
        // The gap lies between samples g.index − 1 and g.index.
        if let Some((label, _, _)) = spans
            .iter()
            .find(|(_, a, b)| *a <= g.index && g.index <= *b + 1)
        {
            return Err(Error::Unsupported(format!(
                "rotation section {} spans or borders a time gap of {} s after time_s {}: its integral would miss the rotation made in the gap; record that rotation again",
                clip(label),
                num(g.step_s),
                num(g.start_s)
            ))
            .in_file(file));
        }
    }
    Ok(())
}

/// Refuse a rotation section whose gyro channel about the rotation axis
/// holds one value in every sample: a dead channel would integrate the turn
/// to nothing and give a scale factor near zero with a small u.
fn check_rotation_alive(file: &str, label: &str, axis: usize, samples: &[[f64; 6]]) -> Result<()> {
    let c = 3 + axis;
    match samples.first() {
        Some(first) if samples.len() >= 3 && samples.iter().all(|s| s[c] == first[c]) => {
            Err(Error::Unsupported(format!(
                "rotation section {}: column gyr_{} is {} in every one of its {} samples: a dead gyro channel cannot measure the turn",
                clip(label),
                ["x", "y", "z"][axis],
                num(first[c]),
                samples.len()
            ))
            .in_file(file))
        }
        _ => Ok(()),
    }
}

/// A reader that has handed out no row is refused as the input layer
/// refuses an empty table (before any procedure-specific check).
fn some_rows<R: Read>(rows: &Reader<R>) -> Result<()> {
    if rows.rows() == 0 {
        return Err(InputError::file(rows.header().file(), "no data rows after the header").into());
    }
    Ok(())
}

/// The nine Ferraris sections of a session, in [`SECTIONS`] order, each a
/// list of 6-vectors (accelerometer x, y, z, gyro x, y, z).
pub type FerrarisSections = [Vec<[f64; 6]>; 9];

/// Read a Ferraris session: both triads and `part` are required; rows with
/// an empty part are skipped (their numbers are still checked); every
/// section needs at least 2 samples (the refusal names every missing or
/// short one).
///
/// With the sections, the time base of `time_s` when the session has it
/// (`rate_hz`, the nominal rate, must agree with it).
pub fn read_ferraris<R: Read>(
    rows: &mut Reader<R>,
    rate_hz: Option<f64>,
) -> Result<(FerrarisSections, Option<TimeBase>)> {
    let mut session = SessionReader::new(SessionColumns::of(rows.header(), true, true)?);
    let cp = rows.header().column("part")?;
    let mut secs: FerrarisSections = Default::default();
    // Stamp index of the first and last sample of each run of a rotation
    // section (for the gap check).
    let mut runs: Vec<(String, usize, usize)> = Vec::new();
    let mut index = 0usize;
    while let Some(row) = rows.next_row()? {
        let s = session.read(&row)?;
        index += 1;
        let text = row.text(cp);
        let label = text.trim();
        if label.is_empty() {
            continue;
        }
        if label.ends_with("_rot") {
            match runs.last_mut() {
                Some((l, _, last)) if l == label && *last + 2 == index => *last = index - 1,
                _ => runs.push((label.to_string(), index - 1, index - 1)),
            }
        }
        let k = SECTIONS.iter().position(|l| *l == label).ok_or_else(|| {
            row.error(format!(
                "part '{}' is not a Ferraris section (one of {}, or empty)",
                clip(label),
                SECTIONS.join(", ")
            ))
        })?;
        secs[k].push(s.six());
    }
    some_rows(rows)?;
    let missing: Vec<&str> = SECTIONS
        .iter()
        .zip(&secs)
        .filter(|(_, v)| v.len() < 2)
        .map(|(l, _)| *l)
        .collect();
    if !missing.is_empty() {
        return Err(Error::Unsupported(format!(
            "the Ferraris method needs all nine sections with at least 2 samples each; missing or too short: {}",
            missing.join(", ")
        )));
    }
    refuse_clipped_rotations(&secs)?;
    let tb = session.timebase(rows.header().file(), rate_hz)?;
    if tb.is_none() && rate_hz.is_none() {
        return Err(no_rate(rows.header()));
    }
    check_rotation_gaps(rows.header().file(), tb.as_ref(), &runs)?;
    for axis in 0..3 {
        check_rotation_alive(
            rows.header().file(),
            SECTIONS[6 + axis],
            axis,
            &secs[6 + axis],
        )?;
    }
    Ok((secs, tb))
}

/// The observations of a multi-position session.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiposInput {
    /// Static positions, in file order.
    pub statics: Vec<StaticPosition>,
    /// Rotation sections, in file order.
    pub rotations: Vec<RotationSection>,
    /// Whether the session has gyro columns.
    pub gyro: bool,
    /// The time base of `time_s`, when the session has it.
    pub timebase: Option<TimeBase>,
    /// What the input checks found: spikes left out of the static
    /// positions' means ([`super::screen`]), saturated channels.
    pub warnings: Vec<crate::warning::Warning>,
    /// The sample rate (Hz): as given, or the stamps'; `None` for a
    /// session without rotations and without either.
    pub rate_hz: Option<f64>,
}

/// What a row of a multi-position session is.
#[derive(Debug, Clone, PartialEq)]
enum Kind {
    /// Between positions.
    Skip,
    /// A static position: key (label, or the up direction as text), up,
    /// north.
    Static(String, V3, Option<V3>),
    /// A rotation: label, axis.
    Rotation(String, usize),
}

impl Kind {
    /// Whether two rows belong to one block (the north of a block is its
    /// first row's).
    fn same(&self, other: &Kind) -> bool {
        match (self, other) {
            (Kind::Static(a, _, _), Kind::Static(b, _, _)) => a == b,
            (Kind::Rotation(a, _), Kind::Rotation(b, _)) => a == b,
            (Kind::Skip, Kind::Skip) => true,
            _ => false,
        }
    }
}

/// The columns of a multi-position session.
struct MultiposColumns {
    position: Option<usize>,
    up: Option<[usize; 3]>,
    north: Option<[usize; 3]>,
}

impl MultiposColumns {
    fn of(h: &incal_io::Header, latitude: bool) -> Result<Self> {
        let position = h.opt_column("position");
        let up = match (h.opt_column("fx"), h.opt_column("fy"), h.opt_column("fz")) {
            (Some(x), Some(y), Some(z)) => Some([x, y, z]),
            (None, None, None) => None,
            _ => {
                for c in ["fx", "fy", "fz"] {
                    h.column(c)?;
                }
                None
            }
        };
        if position.is_none() && up.is_none() {
            h.column("position")?;
        }
        let north = match (h.opt_column("nx"), h.opt_column("ny"), h.opt_column("nz")) {
            (Some(x), Some(y), Some(z)) => Some([x, y, z]),
            _ => None,
        };
        if latitude && north.is_none() {
            h.column("nx")?;
        }
        Ok(Self {
            position,
            up,
            north,
        })
    }

    /// What row `row` is (its label, its direction from the label and/or
    /// fx,fy,fz, which must agree, and its north).
    fn kind(&self, row: &Row<'_>) -> Result<Kind> {
        let label = self.position.map(|c| row.text(c).trim().to_string());
        if let Some(l) = &label {
            if let Some(axis) = ROTATIONS.iter().position(|r| r == l) {
                // The direction columns carry nothing on a rotation row,
                // but what is there must still be a number.
                for c in self.up.iter().chain(self.north.iter()).flatten() {
                    if !row.text(*c).trim().is_empty() {
                        row.f64(*c)?;
                    }
                }
                return Ok(Kind::Rotation(l.clone(), axis));
            }
            if l.is_empty() && self.up.is_none() {
                return Ok(Kind::Skip);
            }
        }
        let from_label = match &label {
            Some(l) if !l.is_empty() => Some(position_direction(l).map_err(|e| row.error(e))?),
            _ => None,
        };
        let from_f = match self.up {
            Some([x, y, z]) => {
                let v = V3::new(row.f64(x)?, row.f64(y)?, row.f64(z)?);
                let n = v.norm();
                if (n - 1.0).abs() > 1e-3 {
                    return Err(row
                        .error(format!(
                            "fx,fy,fz must be a unit vector, its norm is {}",
                            num(n)
                        ))
                        .into());
                }
                Some(v / n)
            }
            None => None,
        };
        let up = match (from_label, from_f) {
            (Some(l), Some(f)) => {
                if (l - f).norm() > 1e-3 {
                    return Err(row
                        .error(format!(
                            "position '{}' points ({}, {}, {}) but fx,fy,fz say ({}, {}, {})",
                            clip(label.as_deref().unwrap_or("")),
                            num(l[0]),
                            num(l[1]),
                            num(l[2]),
                            num(f[0]),
                            num(f[1]),
                            num(f[2])
                        ))
                        .into());
                }
                f
            }
            (Some(l), None) => l,
            (None, Some(f)) => f,
            (None, None) => return Ok(Kind::Skip),
        };
        let north = match self.north {
            Some([x, y, z]) => {
                let v = V3::new(row.f64(x)?, row.f64(y)?, row.f64(z)?);
                if (v.norm() - 1.0).abs() > 1e-3 || v.dot(&up).abs() > 1e-3 {
                    return Err(row
                        .error("nx,ny,nz must be a unit vector normal to the up direction")
                        .into());
                }
                Some(v)
            }
            None => None,
        };
        let key = label
            .filter(|l| !l.is_empty())
            .unwrap_or_else(|| format!("({}, {}, {})", num(up[0]), num(up[1]), num(up[2])));
        Ok(Kind::Static(key, up, north))
    }
}

/// A block of consecutive rows of one kind being gathered.
struct Block {
    kind: Kind,
    line: usize,
    /// Row index of its first sample (for the gap check).
    first: usize,
    samples: Vec<[f64; 6]>,
}

/// Read a multi-position session (columns in the module docs): the
/// accelerometer triad is required, the gyro's optional; `latitude`
/// requires the north direction. Consecutive rows with the same label (or
/// the same up direction) are one position; a position needs at least 2
/// samples, a rotation the gyro columns.
///
/// The nominal `rate_hz`, when given, is checked against `time_s`; without
/// it the stamps give the rate, and a session with rotations but without
/// `time_s` is refused.
pub fn read_multipos<R: Read>(
    rows: &mut Reader<R>,
    latitude: bool,
    rate_hz: Option<f64>,
) -> Result<MultiposInput> {
    let cols = SessionColumns::of(rows.header(), true, false)?;
    let gyro = cols.gyr.is_some();
    let mut session = SessionReader::new(cols);
    let mc = MultiposColumns::of(rows.header(), latitude)?;
    let file = rows.header().file().to_string();
    let mut input = MultiposInput {
        statics: Vec::new(),
        rotations: Vec::new(),
        gyro,
        timebase: None,
        warnings: Vec::new(),
        rate_hz: None,
    };
    let mut spikes = Vec::new();
    let mut still_scales = Vec::new();
    let mut pending: Vec<(String, usize, Vec<[f64; 6]>)> = Vec::new();
    let mut runs: Vec<(String, usize, usize)> = Vec::new();
    let mut index = 0usize;
    let mut channels = super::screen::ChannelCheck::default();
    let mut flush = |b: Block, input: &mut MultiposInput| -> Result<()> {
        match b.kind {
            Kind::Skip => {}
            Kind::Static(key, up, north) => {
                if b.samples.len() < 2 {
                    return Err(InputError::at(
                        &file,
                        b.line,
                        format!("position {key} has a single sample (at least 2 are needed)"),
                    )
                    .into());
                }
                let (kept, n) = super::screen::without_spikes(&b.samples);
                spikes.push((key.clone(), n));
                still_scales.push(super::screen::triad_scale(&kept, 3));
                input.statics.push(StaticPosition {
                    label: key,
                    up,
                    north,
                    stats: SectionStats::of(&kept)?,
                });
            }
            Kind::Rotation(label, axis) => {
                if !gyro {
                    return Err(InputError::at(
                        &file,
                        b.line,
                        format!("rotation {label} without gyro columns"),
                    )
                    .into());
                }
                // Summarised at the end, when the still scatter that
                // scales their spike screening is known.
                runs.push((label.clone(), b.first, b.first + b.samples.len() - 1));
                pending.push((label, axis, b.samples));
            }
        }
        Ok(())
    };
    let mut block: Option<Block> = None;
    while let Some(row) = rows.next_row()? {
        let s = session.read(&row)?.six();
        channels.push(&s);
        index += 1;
        let kind = mc.kind(&row)?;
        match &mut block {
            Some(b) if b.kind.same(&kind) => b.samples.push(s),
            _ => {
                if let Some(b) = block.take() {
                    flush(b, &mut input)?;
                }
                block = Some(Block {
                    kind,
                    line: row.line(),
                    first: index - 1,
                    samples: vec![s],
                });
            }
        }
    }
    if let Some(b) = block.take() {
        flush(b, &mut input)?;
    }
    some_rows(rows)?;
    let scale = super::screen::median_scale(&still_scales);
    let mut replaced = Vec::new();
    let pending = without_clipped_rotations(pending, &mut input.warnings)?;
    for (label, axis, samples) in pending {
        check_rotation_alive(&file, &label, axis, &samples)?;
        let n = super::screen::rotation_spikes(&samples, scale);
        replaced.push((label.clone(), n));
        input.rotations.push(RotationSection {
            label,
            axis,
            stats: SectionStats::of(&samples)?,
        });
    }
    input.timebase = session.timebase(&file, rate_hz)?;
    input.rate_hz = rate_hz.or(input.timebase.as_ref().map(|tb| tb.rate_hz));
    if input.rate_hz.is_none() && !input.rotations.is_empty() {
        return Err(no_rate(rows.header()));
    }
    check_rotation_gaps(&file, input.timebase.as_ref(), &runs)?;
    channels.finish(&super::screen::session_channels(gyro), &mut input.warnings)?;
    input.warnings.extend(super::screen::spikes_warning(
        &spikes,
        super::screen::LEFT_OUT,
    ));
    input.warnings.extend(super::screen::spikes_warning(
        &replaced,
        super::screen::NOT_CHANGED,
    ));
    Ok(input)
}

/// `gyr_x at -32768 (12 samples)`: where a section is clipped.
fn clipped_text(n: usize, first: Option<(usize, f64)>) -> String {
    match first {
        Some((k, rail)) => format!("{} at {rail} ({n} samples)", CHANNELS[3 + k]),
        None => format!("{n} samples"),
    }
}

/// Ferraris: a rotation holding gyro samples at a converter's rail
/// ([`super::screen::GyroRails`]) integrates to the wrong angle, and the
/// method has no other rotation about its axis: refused, naming each.
fn refuse_clipped_rotations(secs: &FerrarisSections) -> Result<()> {
    let rails = super::screen::GyroRails::of(secs.iter().flatten().map(|s| [s[3], s[4], s[5]]));
    let clipped: Vec<String> = (6..9)
        .filter_map(|k| {
            let (n, first) = rails.count(&secs[k]);
            (n > 0).then(|| format!("{} ({})", SECTIONS[k], clipped_text(n, first)))
        })
        .collect();
    if clipped.is_empty() {
        return Ok(());
    }
    Err(Error::Unsupported(format!(
        "gyro samples at a converter's rail in {}: a clipped rotation integrates to the wrong angle, and the Ferraris method has no other rotation about that axis (record it again within the gyro's range)",
        clipped.join(", ")
    )))
}

/// Multi-position: rotations holding gyro samples at a converter's rail
/// are left out with a `clipped` warning naming them; refused when an axis
/// that had a rotation has none left.
#[allow(clippy::type_complexity)]
fn without_clipped_rotations(
    pending: Vec<(String, usize, Vec<[f64; 6]>)>,
    warnings: &mut Vec<Warning>,
) -> Result<Vec<(String, usize, Vec<[f64; 6]>)>> {
    let rails = super::screen::GyroRails::of(
        pending
            .iter()
            .flat_map(|(_, _, s)| s.iter().map(|x| [x[3], x[4], x[5]])),
    );
    let (mut kept, mut left) = (Vec::new(), Vec::new());
    for (label, axis, samples) in pending {
        match rails.count(&samples) {
            (0, _) => kept.push((label, axis, samples)),
            (n, first) => left.push((label, axis, clipped_text(n, first))),
        }
    }
    if left.is_empty() {
        return Ok(kept);
    }
    let names: Vec<String> = left.iter().map(|(l, _, t)| format!("{l}: {t}")).collect();
    if let Some((label, axis, _)) = left
        .iter()
        .find(|(_, a, _)| !kept.iter().any(|(_, k, _)| k == a))
    {
        return Err(Error::Unsupported(format!(
            "gyro samples at a converter's rail in every rotation about {} ({label}; {}): a clipped rotation integrates to the wrong angle, and none about that axis is left (record one again within the gyro's range)",
            ["x", "y", "z"][*axis],
            names.join(", ")
        )));
    }
    warnings.push(Warning::new(
        WarningCode::Clipped,
        format!(
            "{} of {} rotations hold gyro samples at a converter's rail ({}) and are left out of the gyro fit (a clipped rotation integrates to the wrong angle)",
            left.len(),
            left.len() + kept.len(),
            names.join(", ")
        ),
    ));
    Ok(kept)
}

/// The record of an autocalibration: time (s; from `time_s` under the
/// time-stamp policy of [`crate::timebase`], else sample index / rate), raw
/// accelerometer and, when present, raw gyro samples.
#[derive(Debug, Clone, PartialEq)]
pub struct AutocalInput {
    /// Time of every sample (s), non-decreasing: the policy's times
    /// (regularised when the stamps repeat on a regular grid).
    pub time: Vec<f64>,
    /// The `time_s` stamps as read, when the file has them (imu_tk's
    /// method takes its time steps from these, repeats and all).
    pub stamps: Option<Vec<f64>>,
    /// The time base of the stamps, when the file has them.
    pub timebase: Option<TimeBase>,
    /// Raw accelerometer samples.
    pub acc: Vec<[f64; 3]>,
    /// Raw gyro samples of the same instants.
    pub gyr: Option<Vec<[f64; 3]>>,
    /// Rows moved into time order (`--sort-time`; 0 when in order).
    pub sorted: usize,
    /// The sample rate (Hz): as given, or the stamps'.
    pub rate_hz: f64,
}

/// A record without `time_s` and without a rate: refused on its header.
pub(crate) fn no_rate(header: &incal_io::Header) -> Error {
    header
        .error("no time_s column and no rate_hz: give the sample rate (--rate-hz)")
        .into()
}

/// Read an autocalibration record: the accelerometer triad is required,
/// the gyro's optional; without `time_s` the time is `k / rate_hz` (then
/// required), with it `rate_hz`, when given, must agree with the stamps.
pub fn read_autocal<R: Read>(
    rows: &mut Reader<R>,
    rate_hz: Option<f64>,
    sort_time: bool,
) -> Result<AutocalInput> {
    let cols = SessionColumns::of(rows.header(), true, false)?;
    let mut session = SessionReader::new(cols);
    session.sort = sort_time;
    let mut acc = Vec::new();
    let mut gyr = cols.gyr.map(|_| Vec::new());
    while let Some(row) = rows.next_row()? {
        let s = session.read(&row)?;
        acc.push(s.acc.unwrap_or([0.0; 3]));
        if let (Some(g), Some(v)) = (gyr.as_mut(), s.gyr) {
            g.push(v);
        }
    }
    some_rows(rows)?;
    let mut sorted = 0;
    if let Some((order, moved)) = crate::timebase::time_order(&mut session.stamps) {
        crate::timebase::permute(&mut acc, &order);
        if let Some(g) = gyr.as_mut() {
            crate::timebase::permute(g, &order);
        }
        sorted = moved;
    }
    let timebase = session.timebase(rows.header().file(), rate_hz)?;
    let (time, rate_hz) = match (&timebase, rate_hz) {
        (Some(tb), r) => (tb.times.clone(), r.unwrap_or(tb.rate_hz)),
        (None, Some(r)) => ((0..acc.len()).map(|k| k as f64 / r).collect(), r),
        (None, None) => return Err(no_rate(rows.header())),
    };
    let stamps = timebase.as_ref().map(|_| session.stamps);
    Ok(AutocalInput {
        time,
        stamps,
        timebase,
        acc,
        gyr,
        sorted,
        rate_hz,
    })
}

/// Write a simulated session in the input format of the procedure its
/// layout names: `time_s`, then `part` (Ferraris), nothing (random
/// orientations: the autocalibration's record) or `position, fx, fy, fz`
/// and `nx, ny, nz` when the north is written (multi-position; rotation
/// rows carry their axis as the direction), then `acc_x … gyr_z`.
/// Numbers in Rust's shortest round-trip form.
pub fn write<W: std::io::Write>(
    samples: &[ImuSample],
    layout: &Layout,
    out: W,
) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let mut header = vec!["time_s"];
    match layout {
        Layout::Ferraris => header.push("part"),
        Layout::Random => {}
        Layout::Positions { north, .. } => {
            header.extend(["position", "fx", "fy", "fz"]);
            if *north {
                header.extend(["nx", "ny", "nz"]);
            }
        }
    }
    header.extend(CHANNELS);
    let mut w = CsvWriter::new(out, &header)?;
    for s in samples {
        w.cell(Cell::Num(s.time_s))?;
        match layout {
            Layout::Ferraris => w.cell(Cell::Text(&s.part))?,
            Layout::Random => {}
            Layout::Positions { labels, north } => {
                let (label, up) = match ROTATIONS.iter().position(|r| *r == s.part) {
                    Some(k) => {
                        let mut up = V3::zeros();
                        up[k] = 1.0;
                        (s.part.as_str(), up)
                    }
                    None => {
                        let label = s
                            .part
                            .strip_prefix('p')
                            .and_then(|k| k.parse::<usize>().ok())
                            .and_then(|k| labels.get(k.wrapping_sub(1)))
                            .map_or(s.part.as_str(), |l| l.trim());
                        (label, s.up.unwrap_or_else(V3::zeros))
                    }
                };
                w.cell(Cell::Text(label))?;
                for x in up.iter() {
                    w.cell(Cell::Num(*x))?;
                }
                if *north {
                    let n = s.north.unwrap_or_else(V3::zeros);
                    for x in n.iter() {
                        w.cell(Cell::Num(*x))?;
                    }
                }
            }
        }
        for x in s.acc.iter().chain(s.gyr.iter()) {
            w.cell(Cell::Num(*x))?;
        }
        w.end_row()?;
    }
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reader(text: &str) -> Reader<&[u8]> {
        Reader::new("s.csv", text.as_bytes(), &incal_io::ReadOptions::default()).unwrap()
    }

    #[test]
    fn labels_give_directions() {
        let v = position_direction("x_p+y_a").unwrap();
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!((v - V3::new(h, -h, 0.0)).norm() < 1e-15);
        assert!(position_direction("x_p+x_a")
            .unwrap_err()
            .contains("names the x axis twice"));
        assert!(position_direction("up")
            .unwrap_err()
            .contains("is not a face label"));
    }

    #[test]
    fn multipos_rows_are_segmented_by_label() {
        let mut r = reader(
            "position,acc_x,acc_y,acc_z\nx_p,1,2,3\nx_p,1,2,4\n,0,0,0\nx_a,5,6,7\nx_a,5,6,8\n",
        );
        let m = read_multipos(&mut r, false, None).unwrap();
        assert_eq!(m.statics.len(), 2);
        assert_eq!(m.statics[1].label, "x_a");
        assert_eq!(m.statics[1].stats.n, 2);
        assert!(!m.gyro);
        let mut r = reader("position,acc_x,acc_y,acc_z\nx_p,1,2,3\nx_a,1,2,3\nx_a,1,2,3\n");
        let e = read_multipos(&mut r, false, None).unwrap_err().to_string();
        assert!(
            e.starts_with("s.csv:2:") && e.contains("single sample"),
            "{e}"
        );
    }

    #[test]
    fn time_must_not_decrease_and_may_repeat() {
        let mut r = reader("time_s,acc_x,acc_y,acc_z\n0.01,1,2,3\n0,1,2,3\n");
        let e = read_autocal(&mut r, Some(100.0), false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.csv:3") && e.contains("must not decrease"),
            "{e}"
        );
        // 200 Hz stamped to 10 ms: accepted, regularised.
        let mut text = String::from("time_s,acc_x,acc_y,acc_z\n");
        for k in 0..40 {
            text.push_str(&format!("{:.2},1,2,3\n", (k / 2) as f64 * 0.01));
        }
        let a = read_autocal(&mut reader(&text), Some(200.0), false).unwrap();
        let tb = a.timebase.as_ref().unwrap();
        assert_eq!(tb.repeats, 20);
        assert!(tb.regularised);
        // The slope of a 40-sample staircase: 0.2 % short of 5 ms (1/n² bias).
        assert!(
            (a.time[1] - a.time[0] - 0.005).abs() < 2e-5,
            "{:?}",
            &a.time[..3]
        );
        assert_eq!(a.stamps.as_ref().unwrap()[1], 0.0);
        // Without a rate the stamps give it; without stamps it is needed.
        let b = read_autocal(&mut reader(&text), None, false).unwrap();
        assert_eq!((b.time.clone(), b.rate_hz), (a.time.clone(), tb.rate_hz));
        let e = read_autocal(&mut reader("acc_x,acc_y,acc_z\n1,2,3\n"), None, false)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("s.csv:1: no time_s column and no rate_hz"),
            "{e}"
        );
        // The same file announced at 100 Hz is refused naming both rates.
        let e = read_autocal(&mut reader(&text), Some(100.0), false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("100 Hz") && e.contains("200.3759 Hz"), "{e}");
    }

    /// A rotation of `n` gyro samples about `axis`, its peak `peak`.
    fn rotation(axis: usize, n: usize, peak: f64) -> Vec<[f64; 6]> {
        (0..n)
            .map(|i| {
                let mut s = [0.0, 0.0, 1000.0, 3.0, -2.0, 1.0];
                s[3 + axis] = (peak * (std::f64::consts::PI * i as f64 / n as f64).sin()).round();
                s
            })
            .collect()
    }

    #[test]
    fn a_clipped_rotation_is_left_out_when_another_turns_about_its_axis() {
        let clip = |mut r: Vec<[f64; 6]>, axis: usize| {
            r.iter_mut()
                .for_each(|s| s[3 + axis] = s[3 + axis].min(32767.0));
            r
        };
        let pending = vec![
            ("x_rot".to_string(), 0, clip(rotation(0, 200, 40_000.0), 0)),
            ("x_rot".to_string(), 0, rotation(0, 600, 13_000.0)),
            ("y_rot".to_string(), 1, rotation(1, 600, 13_000.0)),
        ];
        let mut warnings = Vec::new();
        let kept = without_clipped_rotations(pending.clone(), &mut warnings).unwrap();
        assert_eq!(kept, pending[1..].to_vec());
        assert_eq!(warnings.len(), 1);
        assert!(
            warnings[0].message.starts_with(
                "1 of 3 rotations hold gyro samples at a converter's rail (x_rot: gyr_x at 32767 ("
            ),
            "{}",
            warnings[0].message
        );
        // Without the slow x rotation, nothing about x is left: refused.
        let e =
            without_clipped_rotations(vec![pending[0].clone(), pending[2].clone()], &mut warnings)
                .unwrap_err()
                .to_string();
        assert!(
            e.contains("in every rotation about x (x_rot; x_rot: gyr_x at 32767"),
            "{e}"
        );
        // The same peak below the rail: nothing left out.
        let mut none = Vec::new();
        let all = vec![("x_rot".to_string(), 0, rotation(0, 200, 30_000.0))];
        assert_eq!(
            without_clipped_rotations(all.clone(), &mut none).unwrap(),
            all
        );
        assert!(none.is_empty());
    }
}
