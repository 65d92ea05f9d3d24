//! Segments from a rig channel: the plateaus of a continuous log.
//!
//! A dividing head logs its encoder, a rate table its rate, a centrifuge
//! its speed, a chamber its temperature: a channel that moves between
//! positions and jitters at rest. `--segment-by COLUMN` finds the plateaus
//! of that column, drops the moves and the settling after each, and hands
//! the procedure the table it expects: every kept row carries its
//! plateau's nominal value in COLUMN, every dropped row is gone.
//!
//! # Rule
//! * **Runs.** Rows in file order; a run grows while a row's value lies
//!   within the tolerance of the run's mean: `|x − x̄| ≤ a + r·|x̄|` (`a`
//!   the absolute tolerance, `r` the relative one).
//! * **Plateaus.** A run that lasts at least the settle time plus the
//!   shortest plateau (`time_s` span) is a plateau; its first
//!   `settle_s` are dropped. Shorter runs are moves (dropped). Two
//!   plateaus in a row whose means agree within the tolerance are one (a
//!   glitch between them is dropped, the settle time is not applied again).
//! * **Values.** Each plateau's nominal value is the next of the plan's
//!   values (`--segment-values`) in order, or, without a list, the mean of
//!   its kept rows, pooled with every other plateau whose mean agrees
//!   within the tolerance (a position or speed visited again gets one
//!   value); a value within the tolerance of zero is zero (at rest; not
//!   for `temperature_c`). A plateau matches a planned value within half the
//!   smallest step between planned values (at least ten tolerances);
//!   a planned value with no plateau, or a plateau that matches no planned
//!   value, is refused naming its time.
//! * **Scatter.** Each plateau's standard deviation of COLUMN over its
//!   kept rows is reported ([`Segment::scatter`]), with the mean's offset
//!   from the nominal value.
//!
//! Defaults per column ([`defaults`]): `angle_deg` and `phi_deg` 0.01 deg,
//! settle 1 s; `rate_deg_s` 0.01 deg/s + 0.1 %, settle 2 s; `omega_rad_s`
//! 2e-4 rad/s + 0.1 %, settle 2 s; `temperature_c` 0.5 °C, settle 600 s;
//! the shortest plateau kept 1 s (60 s for `temperature_c`). Another
//! column needs its tolerance given.
//!
//! The procedure reads a text whose lines are the file's own: a dropped
//! row becomes a comment line, so every message still names the file's
//! line.

use crate::error::{clip, InputError, Result};
use crate::table::Table;
use crate::writer::csv_text;

/// How a log is cut into plateaus (module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SegmentSpec {
    /// The rig channel (incal's column name, after `--columns`).
    pub column: String,
    /// Absolute tolerance (the column's unit); `None`: the column's default.
    pub tolerance: Option<f64>,
    /// Time dropped at the start of each plateau (s); `None`: the default.
    pub settle_s: Option<f64>,
    /// Shortest plateau kept after the settle time (s); `None`: the default.
    pub min_s: Option<f64>,
    /// The plan's nominal values in the order the log visits them (empty:
    /// each plateau's mean).
    pub values: Vec<f64>,
}

impl SegmentSpec {
    /// A spec from the front ends' options (`--segment-by`,
    /// `--segment-tolerance`, `--segment-settle-s`, `--segment-min-s`,
    /// `--segment-values`); `None` when no column is given. Refused, with
    /// the option named: a setting without `--segment-by`, a tolerance that
    /// is not positive, a time that is negative, a value that is not finite.
    pub fn from_options(
        column: Option<&str>,
        tolerance: Option<f64>,
        settle_s: Option<f64>,
        min_s: Option<f64>,
        values: &[f64],
    ) -> std::result::Result<Option<SegmentSpec>, String> {
        let Some(column) = column else {
            let given = [
                ("--segment-tolerance", tolerance.is_some()),
                ("--segment-settle-s", settle_s.is_some()),
                ("--segment-min-s", min_s.is_some()),
                ("--segment-values", !values.is_empty()),
            ];
            return match given.iter().find(|g| g.1) {
                Some((name, _)) => Err(format!("{name}: needs --segment-by COLUMN")),
                None => Ok(None),
            };
        };
        if column.trim().is_empty() {
            return Err("--segment-by: give a column name".into());
        }
        if let Some(t) = tolerance {
            if !(t.is_finite() && t > 0.0 && t <= 1e12) {
                return Err(format!(
                    "--segment-tolerance: {t} is not a positive tolerance"
                ));
            }
        }
        if let Some(v) = settle_s {
            if !(v.is_finite() && (0.0..=1e7).contains(&v)) {
                return Err(format!(
                    "--segment-settle-s: {v} is not a time in s (0 to 1e7)"
                ));
            }
        }
        if let Some(v) = min_s {
            // Zero would make every moving row a plateau of its own.
            if !(v.is_finite() && v > 0.0 && v <= 1e7) {
                return Err(format!(
                    "--segment-min-s: {v} is not a time in s (above 0, at most 1e7)"
                ));
            }
        }
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && v.abs() <= 1e15)) {
            return Err(format!("--segment-values: {v} is not a finite value"));
        }
        Ok(Some(SegmentSpec {
            column: column.trim().to_string(),
            tolerance,
            settle_s,
            min_s,
            values: values.to_vec(),
        }))
    }
}

/// The default (absolute tolerance, relative tolerance, settle s, shortest
/// plateau s) for a column, if it has one.
pub fn defaults(column: &str) -> Option<(f64, f64, f64, f64)> {
    match column {
        "angle_deg" | "phi_deg" => Some((0.01, 0.0, 1.0, 1.0)),
        "rate_deg_s" => Some((0.01, 1e-3, 2.0, 1.0)),
        "omega_rad_s" => Some((2e-4, 1e-3, 2.0, 1.0)),
        "temperature_c" => Some((0.5, 0.0, 600.0, 60.0)),
        _ => None,
    }
}

/// One plateau found.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    /// File line of its first kept row and of its last row.
    pub lines: (usize, usize),
    /// `time_s` of its first row (s).
    pub start_s: f64,
    /// `time_s` of its first kept row (after the settle time).
    pub kept_from_s: f64,
    /// `time_s` of its last row.
    pub end_s: f64,
    /// Rows kept.
    pub rows_kept: usize,
    /// Rows dropped while settling (and glitches merged into it).
    pub rows_dropped: usize,
    /// Mean of COLUMN over the kept rows.
    pub mean: f64,
    /// Standard deviation of COLUMN over the kept rows (0 for one row).
    pub scatter: f64,
    /// The nominal value written in COLUMN (planned, or the mean).
    pub value: f64,
}

/// A log cut into plateaus.
#[derive(Debug, Clone)]
pub struct Segmented {
    /// What the procedure reads: the header and the kept rows on their
    /// own lines, COLUMN set to each plateau's value, every other line a
    /// comment; a header of incal's names.
    pub text: Vec<u8>,
    /// The plateaus, in time order.
    pub segments: Vec<Segment>,
    /// Rows of the moves between plateaus (dropped).
    pub moving_rows: usize,
    /// The columns `--columns` selected, in order, as incal names them
    /// (to select them again when the text is read).
    pub selected: Vec<String>,
}

struct Run {
    start: usize,
    end: usize,
    mean: f64,
}

/// The runs of `x` under tolerance `tol(mean)`.
fn runs(x: &[f64], tol: &dyn Fn(f64) -> f64) -> Vec<Run> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < x.len() {
        let (start, mut mean, mut n) = (i, x[i], 1.0);
        let mut j = i + 1;
        while j < x.len() && (x[j] - mean).abs() <= tol(mean) {
            n += 1.0;
            mean += (x[j] - mean) / n;
            j += 1;
        }
        out.push(Run {
            start,
            end: j,
            mean,
        });
        i = j;
    }
    out
}

/// A plateau's rows: its first and one past its last, its run's mean and
/// the rows kept.
struct Plateau {
    start: usize,
    end: usize,
    mean: f64,
    kept: Vec<usize>,
}

/// The tolerance (absolute, relative), settle time and shortest plateau
/// for `spec`, or why there is none.
fn settings(file: &str, spec: &SegmentSpec) -> Result<(f64, f64, f64, f64)> {
    let (abs, rel, settle, min_s) = match (defaults(&spec.column), spec.tolerance) {
        (Some((a, r, s, m)), None) => (a, r, s, m),
        (Some((_, _, s, m)), Some(a)) => (a, 0.0, s, m),
        (None, Some(a)) => (a, 0.0, 1.0, 1.0),
        (None, None) => {
            return Err(InputError::file(
                file,
                format!(
                "--segment-by {}: no default tolerance for this column; give --segment-tolerance",
                clip(&spec.column)
            ),
            ))
        }
    };
    Ok((
        abs,
        rel,
        spec.settle_s.unwrap_or(settle),
        spec.min_s.unwrap_or(min_s),
    ))
}

/// Cut `table` into plateaus of `spec.column` (module docs).
pub fn segment(table: &Table, spec: &SegmentSpec) -> Result<Segmented> {
    let file = table.file();
    let col = table.column(&spec.column)?;
    let tcol = table.opt_column("time_s").ok_or_else(|| {
        InputError::file(
            file,
            format!(
                "--segment-by {}: a log needs time_s (the settle time is in seconds)",
                clip(&spec.column)
            ),
        )
    })?;
    let (abs, rel, settle, min_s) = settings(file, spec)?;
    let x = table.column_f64(col)?;
    let t = table.column_f64(tcol)?;
    for k in 1..t.len() {
        if t[k] < t[k - 1] {
            return Err(table.error_at(
                k,
                format!("time_s {} is before the row above ({})", t[k], t[k - 1]),
            ));
        }
    }
    let tol = move |m: f64| abs + rel * m.abs();
    let mut plateaus: Vec<Plateau> = Vec::new();
    for r in runs(&x, &tol) {
        if let Some(p) = plateaus.last_mut() {
            let glitch = t[r.start] - t[p.end - 1] < settle;
            if glitch && (r.mean - p.mean).abs() <= tol(p.mean) {
                // A glitch split one plateau: the rows between are dropped,
                // the settle time is not applied again.
                p.kept.extend(r.start..r.end);
                p.end = r.end;
                continue;
            }
        }
        if t[r.end - 1] - t[r.start] + 1e-9 >= settle + min_s {
            let from = (r.start..r.end)
                .find(|&k| t[k] >= t[r.start] + settle - 1e-9)
                .unwrap_or(r.start);
            plateaus.push(Plateau {
                start: r.start,
                end: r.end,
                mean: r.mean,
                kept: (from..r.end).collect(),
            });
        }
    }
    build(table, spec, col, (&x, &t), &plateaus, &tol)
}

/// The segments, their values and the text (after the plateaus are found).
fn build(
    table: &Table,
    spec: &SegmentSpec,
    col: usize,
    (x, t): (&[f64], &[f64]),
    plateaus: &[Plateau],
    tol: &dyn Fn(f64) -> f64,
) -> Result<Segmented> {
    let file = table.file();
    let mut segments = Vec::with_capacity(plateaus.len());
    for p in plateaus {
        let n = p.kept.len() as f64;
        let mean = p.kept.iter().map(|&k| x[k]).sum::<f64>() / n;
        let var = if p.kept.len() > 1 {
            p.kept.iter().map(|&k| (x[k] - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        let first = p.kept[0];
        segments.push(Segment {
            lines: (table.line(first), table.line(p.end - 1)),
            start_s: t[p.start],
            kept_from_s: t[first],
            end_s: t[p.end - 1],
            rows_kept: p.kept.len(),
            rows_dropped: (p.end - p.start) - p.kept.len(),
            mean,
            scatter: var.sqrt(),
            value: mean,
        });
    }
    if segments.is_empty() {
        return Err(InputError::file(
            file,
            format!(
                "--segment-by {}: no plateau found (no stretch within the tolerance for the settle time and the shortest plateau)",
                clip(&spec.column)
            ),
        ));
    }
    if spec.values.is_empty() {
        pool(&mut segments, tol, spec.column != "temperature_c");
    } else {
        assign(file, &spec.values, &mut segments, tol)?;
    }
    let in_plateaus: usize = plateaus.iter().map(|p| p.end - p.start).sum();
    let text = rewrite(table, col, x.len(), plateaus, &segments);
    let selected = table
        .header()
        .selected()
        .iter()
        .map(|&k| table.header().names()[k].clone())
        .collect();
    Ok(Segmented {
        text,
        segments,
        moving_rows: x.len() - in_plateaus,
        selected,
    })
}

/// Without a plan: plateaus whose means agree within the tolerance (a
/// position visited again, a speed set again) share one value, the mean
/// of their rows; every other plateau keeps its own mean.
fn pool(segments: &mut [Segment], tol: &dyn Fn(f64) -> f64, rests_at_zero: bool) {
    let mut groups: Vec<(f64, f64, Vec<usize>)> = Vec::new(); // (sum, rows, members)
    for (k, s) in segments.iter().enumerate() {
        let n = s.rows_kept as f64;
        match groups
            .iter_mut()
            .find(|g| (s.mean - g.0 / g.1).abs() <= tol(g.0 / g.1))
        {
            Some(g) => {
                g.0 += s.mean * n;
                g.1 += n;
                g.2.push(k);
            }
            None => groups.push((s.mean * n, n, vec![k])),
        }
    }
    for (sum, rows, members) in groups {
        // At rest: a stopped table or centrifuge reads zero.
        let value = if rests_at_zero && (sum / rows).abs() <= tol(0.0) {
            0.0
        } else {
            sum / rows
        };
        for k in members {
            segments[k].value = value;
        }
    }
}

/// Give each plateau its planned value, in order; refuse a planned value
/// without a plateau and a plateau without a planned value, naming the time.
fn assign(
    file: &str,
    values: &[f64],
    segments: &mut [Segment],
    tol: &dyn Fn(f64) -> f64,
) -> Result<()> {
    let mut step = f64::INFINITY;
    for w in values.windows(2) {
        if w[0] != w[1] {
            step = step.min((w[1] - w[0]).abs());
        }
    }
    // One planned value (or one repeated): ten tolerances.
    let window = |v: f64| {
        if step.is_finite() {
            (step / 2.0).max(10.0 * tol(v))
        } else {
            10.0 * tol(v)
        }
    };
    let mut j = 0;
    for (k, s) in segments.iter_mut().enumerate() {
        let near = |v: f64| (s.mean - v).abs() < window(v);
        if j < values.len() && near(values[j]) {
            s.value = values[j];
            j += 1;
            continue;
        }
        let message = if j + 1 < values.len() && near(values[j + 1]) {
            format!(
                "the plan's plateau at {} is missing{}: the log goes on to the plateau at t = {} s (mean {})",
                values[j],
                if k == 0 { " at the start of the log" } else { "" },
                s.start_s,
                s.mean
            )
        } else {
            format!(
                "a plateau at t = {} s (mean {}) is not in the plan (next planned value {})",
                s.start_s,
                s.mean,
                values.get(j).map_or("none".to_string(), |v| v.to_string())
            )
        };
        return Err(InputError::at(file, s.lines.0, message));
    }
    if j < values.len() {
        let end = segments.last().map_or(0.0, |s| s.end_s);
        return Err(InputError::file(
            file,
            format!(
                "the plan's plateau at {} is missing: the log ends at t = {end} s after {j} of {} plateaus",
                values[j],
                values.len()
            ),
        ));
    }
    Ok(())
}

/// The text the procedure reads (see [`Segmented::text`]).
fn rewrite(
    table: &Table,
    col: usize,
    rows: usize,
    plateaus: &[Plateau],
    segments: &[Segment],
) -> Vec<u8> {
    let h = table.header();
    let mut value_of = vec![None; rows];
    for (p, s) in plateaus.iter().zip(segments) {
        for &k in &p.kept {
            value_of[k] = Some(s.value);
        }
    }
    let mut out: Vec<u8> = Vec::with_capacity(64 * rows);
    let mut line = 1;
    let pad = |out: &mut Vec<u8>, line: &mut usize, to: usize| {
        while *line < to {
            out.extend_from_slice(b"#\n");
            *line += 1;
        }
    };
    pad(&mut out, &mut line, h.line());
    let names: Vec<String> = h.names().iter().map(|n| csv_text(n).into_owned()).collect();
    let text = names.join(",");
    // A quoted cell may hold line breaks: the lines count on by them.
    line += 1 + text.matches('\n').count();
    out.extend_from_slice(text.as_bytes());
    out.push(b'\n');
    for (r, v) in value_of.iter().enumerate() {
        let Some(v) = v else { continue };
        pad(&mut out, &mut line, table.line(r));
        let cells: Vec<String> = (0..h.width())
            .map(|c| {
                if c == col {
                    format!("{v}")
                } else {
                    csv_text(&table.text(r, c)).into_owned()
                }
            })
            .collect();
        let text = cells.join(",");
        line += 1 + text.matches('\n').count();
        out.extend_from_slice(text.as_bytes());
        out.push(b'\n');
    }
    out
}
