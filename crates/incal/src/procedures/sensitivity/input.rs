//! Reading a sensitivity session: one row per sample, the runs labelled.
//!
//! Columns: `run` (a label per run; the rows of one run are
//! consecutive), the output columns (option `output_columns`, default `output`,
//! in the unit of the option `unit`), `time_s` (s; or the option
//! `rate_hz`), optional `input` (the applied acceleration in g or rate
//! in °/s, constant within a run: the scale factor and its sensitivity
//! where it takes two levels or more) and the stimulus of the kind,
//! constant within a run:
//! - vibration: `vib_g` (level, g rms or g peak by the option `level`),
//!   optional `vib_freq_hz` and `vib_angle_deg` (the direction of the
//!   vibration in the input–pendulous plane, from the input axis toward
//!   the pendulous axis; default 0);
//! - magnetic: `field_x_mt`, `field_y_mt`, `field_z_mt` (the applied
//!   field in mT in the instrument's axes; any of them, a missing one is
//!   0);
//! - shock: `shock_g` (the peak of the last shock the unit took before
//!   the run, 0 for the runs before the first shock).
//!
//! A run without its stimulus label (an empty cell), a label that changes
//! within a run, or a run label used again after another run are refused
//! naming the line.

use std::io::Read;

use super::{Kind, SensitivityOptions};
use crate::error::{Error, Result};
use crate::options::invalid;

/// The vibration stimulus columns.
pub const VIB: [&str; 3] = ["vib_g", "vib_freq_hz", "vib_angle_deg"];
/// The magnetic stimulus columns.
pub const FIELD: [&str; 3] = ["field_x_mt", "field_y_mt", "field_z_mt"];
/// The shock stimulus column.
pub const SHOCK: &str = "shock_g";

/// The stimulus of one run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stimulus {
    /// Vibration level, g rms (a peak level converted, module docs).
    pub vib_g_rms: f64,
    /// Vibration frequency (Hz), if given.
    pub vib_freq_hz: Option<f64>,
    /// Vibration direction from the input axis toward the pendulous axis
    /// (degrees).
    pub vib_angle_deg: f64,
    /// Applied field per instrument axis (mT).
    pub field_mt: [f64; 3],
    /// Peak of the last shock before the run (g).
    pub shock_g: f64,
}

/// One run.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Its label.
    pub label: String,
    /// The file line of its first row.
    pub line: usize,
    /// Start of its kept samples (s, the file's clock).
    pub start_s: f64,
    /// Its kept length (s): samples × the sample interval.
    pub duration_s: f64,
    /// Rows dropped by `settle_s`.
    pub dropped: usize,
    /// The stimulus.
    pub stimulus: Stimulus,
    /// The applied input (g or °/s), if the file has `input`.
    pub input: Option<f64>,
    /// The kept samples of each output column (reporting units: µg or
    /// °/h).
    pub samples: Vec<Vec<f64>>,
}

/// A session.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The kind, resolved from the columns when `auto`.
    pub kind: Kind,
    /// The output columns.
    pub columns: Vec<String>,
    /// Which magnetic axes the file has.
    pub field_axes: [bool; 3],
    /// The sample interval (s).
    pub dt_s: f64,
    /// The runs, in the file's order.
    pub runs: Vec<Run>,
}

/// The kind the columns say (`auto`), or the given one.
fn resolve_kind(h: &incal_io::Header, kind: Kind) -> Result<Kind> {
    if kind != Kind::Auto {
        return Ok(kind);
    }
    let has = |n: &str| h.opt_column(n).is_some();
    let found: Vec<Kind> = [
        (has(VIB[0]), Kind::Vibration),
        (FIELD.iter().any(|c| has(c)), Kind::Magnetic),
        (has(SHOCK), Kind::Shock),
    ]
    .into_iter()
    .filter(|(h, _)| *h)
    .map(|(_, k)| k)
    .collect();
    match found.as_slice() {
        [k] => Ok(*k),
        [] => Err(h
            .error("no stimulus column (vib_g; field_x_mt, field_y_mt, field_z_mt; or shock_g): every run needs its stimulus label")
            .into()),
        _ => Err(h
            .error("stimulus columns of more than one kind: give the kind (vibration, magnetic or shock)")
            .into()),
    }
}

/// The stimulus columns of a kind and their file columns.
struct Columns {
    stim: Vec<(usize, &'static str)>,
    input: Option<usize>,
    time: Option<usize>,
    run: usize,
    out: Vec<usize>,
}

fn columns(h: &incal_io::Header, kind: Kind, names: &[String]) -> Result<Columns> {
    let stim = match kind {
        Kind::Vibration => {
            let mut v = vec![(h.column(VIB[0])?, VIB[0])];
            v.extend(
                VIB[1..]
                    .iter()
                    .filter_map(|n| h.opt_column(n).map(|c| (c, *n))),
            );
            v
        }
        Kind::Magnetic => {
            let v: Vec<(usize, &str)> = FIELD
                .iter()
                .filter_map(|n| h.opt_column(n).map(|c| (c, *n)))
                .collect();
            if v.is_empty() {
                h.column(FIELD[0])?;
            }
            v
        }
        Kind::Shock | Kind::Auto => vec![(h.column(SHOCK)?, SHOCK)],
    };
    Ok(Columns {
        stim,
        input: h.opt_column("input"),
        time: h.opt_column("time_s"),
        run: h.column("run")?,
        out: names
            .iter()
            .map(|n| h.column(n))
            .collect::<std::result::Result<_, _>>()?,
    })
}

/// Read a session (module docs); samples in reporting units (`scale`
/// times the file's).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, o: &SensitivityOptions) -> Result<Record> {
    let h = rows.header();
    let kind = resolve_kind(h, o.kind)?;
    let names = o.column_names()?;
    let c = columns(h, kind, &names)?;
    if c.time.is_none() && o.rate_hz.is_none() {
        return Err(h
            .error("no column 'time_s': give the sampling rate (rate_hz) or the stamps")
            .into());
    }
    let scale = o.output_scale()?;
    let peak = o.level == super::Level::Peak;
    let mut field_axes = [false; 3];
    for (_, n) in &c.stim {
        if let Some(k) = FIELD.iter().position(|f| f == n) {
            field_axes[k] = true;
        }
    }
    let mut runs: Vec<(Run, Vec<f64>)> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    let mut k = 0usize;
    let mut last_t: Option<f64> = None;
    while let Some(row) = rows.next_row()? {
        let t = match (c.time, o.rate_hz) {
            (Some(ct), _) => row.f64(ct)?,
            (None, Some(r)) => k as f64 / r,
            (None, None) => unreachable!("checked above"),
        };
        if let (Some(ct), Some(l)) = (c.time, last_t) {
            if t <= l {
                return Err(row
                    .cell_error(ct, format!("time {t} s does not increase (previous {l} s)"))
                    .into());
            }
        }
        last_t = Some(t);
        k += 1;
        let label = row.label(c.run)?.to_string();
        if label.is_empty() {
            return Err(row.cell_error(c.run, "an empty run label").into());
        }
        let mut st = Stimulus::default();
        for (col, name) in &c.stim {
            let Some(v) = row.f64_or_missing(*col)? else {
                return Err(row
                    .cell_error(
                        *col,
                        format!(
                            "run '{}' without its stimulus label ({name} empty)",
                            incal_io::clip(&label)
                        ),
                    )
                    .into());
            };
            let bad = match *name {
                "vib_g" | "shock_g" => v < 0.0,
                "vib_freq_hz" => v <= 0.0,
                _ => false,
            };
            if bad {
                return Err(row
                    .cell_error(
                        *col,
                        format!("{name} = {v}: a level is not negative (a frequency positive)"),
                    )
                    .into());
            }
            set_stimulus(&mut st, name, v, peak);
        }
        let input = c.input.map(|ci| row.f64(ci)).transpose()?;
        let new_run = runs.last().is_none_or(|(r, _)| r.label != label);
        if new_run {
            if runs.len() >= super::MAX_RUNS {
                return Err(row
                    .cell_error(c.run, format!("more than {} runs: the run means' covariance grows with their square; reduce a part of the session at a time", super::MAX_RUNS))
                    .into());
            }
            if !seen.insert(label.clone()) {
                return Err(row
                    .cell_error(c.run, format!("run '{}' again after other runs: the rows of a run must be consecutive", incal_io::clip(&label)))
                    .into());
            }
            runs.push((
                Run {
                    label,
                    line: row.line(),
                    start_s: t,
                    duration_s: 0.0,
                    dropped: 0,
                    stimulus: st,
                    input,
                    samples: vec![Vec::new(); c.out.len()],
                },
                Vec::new(),
            ));
        }
        let (run, times) = runs.last_mut().expect("pushed above");
        if run.stimulus != st || run.input != input {
            // The first column whose value differs from the run's.
            let col = c
                .stim
                .iter()
                .find(|(_, name)| field(&st, name) != field(&run.stimulus, name))
                .map_or(c.input.unwrap_or(c.run), |(ci, _)| *ci);
            return Err(row
                .cell_error(col, format!("the stimulus or input changes within run '{}' (from line {}): give each level its own run label", incal_io::clip(&run.label), run.line))
                .into());
        }
        for (j, co) in c.out.iter().enumerate() {
            run.samples[j].push(row.f64(*co)? * scale);
        }
        times.push(t);
    }
    settle(kind, names, field_axes, runs, c.time.is_some(), o)
}

/// The stimulus's value of a column (its unit as stored).
fn field(st: &Stimulus, name: &str) -> Option<f64> {
    match name {
        "vib_g" => Some(st.vib_g_rms),
        "vib_freq_hz" => st.vib_freq_hz,
        "vib_angle_deg" => Some(st.vib_angle_deg),
        "shock_g" => Some(st.shock_g),
        _ => FIELD
            .iter()
            .position(|f| *f == name)
            .map(|k| st.field_mt[k]),
    }
}

/// Put a stimulus cell into the run's stimulus.
fn set_stimulus(st: &mut Stimulus, name: &str, v: f64, peak: bool) {
    match name {
        "vib_g" => st.vib_g_rms = if peak { v / 2f64.sqrt() } else { v },
        "vib_freq_hz" => st.vib_freq_hz = Some(v),
        "vib_angle_deg" => st.vib_angle_deg = v,
        "shock_g" => st.shock_g = v,
        _ => {
            if let Some(k) = FIELD.iter().position(|f| *f == name) {
                st.field_mt[k] = v;
            }
        }
    }
}

/// The sample interval, the settle time dropped, and the runs' spans.
fn settle(
    kind: Kind,
    columns: Vec<String>,
    field_axes: [bool; 3],
    runs: Vec<(Run, Vec<f64>)>,
    has_time: bool,
    o: &SensitivityOptions,
) -> Result<Record> {
    let mut steps: Vec<f64> = runs
        .iter()
        .flat_map(|(_, t)| t.windows(2).map(|w| w[1] - w[0]))
        .collect();
    if steps.is_empty() {
        return Err(Error::Unsupported(
            "no run has two samples: nothing to average".into(),
        ));
    }
    steps.sort_by(f64::total_cmp);
    let dt_s = steps[steps.len() / 2];
    if !(1e-7..=1e5).contains(&dt_s) {
        return Err(Error::Unsupported(format!(
            "the samples are {dt_s} s apart: time_s is not in seconds?"
        )));
    }
    if let (Some(r), true) = (o.rate_hz, has_time) {
        if ((dt_s * r) - 1.0).abs() > 0.01 {
            return invalid(
                "rate_hz",
                format!("{r} Hz disagrees with time_s, whose samples are {dt_s:.6} s apart"),
            );
        }
    }
    let mut out = Vec::with_capacity(runs.len());
    for (mut run, t) in runs {
        if t.len() > 2 {
            let mut own: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
            own.sort_by(f64::total_cmp);
            let step = own[own.len() / 2];
            if (step / dt_s - 1.0).abs() > 0.01 {
                return Err(Error::Unsupported(format!(
                    "line {}: run '{}' is sampled every {step} s, the session every {dt_s} s: one rate for every run",
                    run.line,
                    incal_io::clip(&run.label)
                )));
            }
        }
        let keep = t.iter().position(|&x| x - t[0] >= o.settle_s - 1e-9 * dt_s);
        let first = keep.unwrap_or(t.len());
        let n = t.len() - first;
        if n < super::MIN_RUN_SAMPLES {
            return Err(Error::Unsupported(format!(
                "line {}: run '{}' keeps {n} samples after the settle time ({} s): at least {} are needed to estimate its noise",
                run.line,
                incal_io::clip(&run.label),
                o.settle_s,
                super::MIN_RUN_SAMPLES
            )));
        }
        for s in &mut run.samples {
            s.drain(..first);
        }
        run.dropped = first;
        run.start_s = t[first];
        run.duration_s = n as f64 * dt_s;
        out.push(run);
    }
    Ok(Record {
        kind,
        columns,
        field_axes,
        dt_s,
        runs: out,
    })
}

/// Write a session as the reduction reads it (`time_s`, `run`, the
/// stimulus columns of `kind`, `input` when any run has one, the output
/// columns named `columns`); samples divided by `scale` (reporting units
/// per file unit, [`super::SensitivityOptions::output_scale`]).
pub fn write(rec: &Record, scale: f64, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    let mut head: Vec<&str> = vec!["time_s", "run"];
    match rec.kind {
        Kind::Vibration => head.extend(VIB),
        Kind::Magnetic => head.extend(FIELD),
        Kind::Shock | Kind::Auto => head.push(SHOCK),
    }
    let with_input = rec.runs.iter().any(|r| r.input.is_some());
    if with_input {
        head.push("input");
    }
    head.extend(rec.columns.iter().map(String::as_str));
    let mut w = incal_io::CsvWriter::new(out, &head)?;
    let num = incal_io::Cell::Num;
    for r in &rec.runs {
        let s = &r.stimulus;
        for k in 0..r.samples[0].len() {
            w.cell(num(r.start_s + k as f64 * rec.dt_s))?;
            w.cell(incal_io::Cell::Text(&r.label))?;
            match rec.kind {
                Kind::Vibration => {
                    for v in [s.vib_g_rms, s.vib_freq_hz.unwrap_or(0.0), s.vib_angle_deg] {
                        w.cell(num(v))?;
                    }
                }
                Kind::Magnetic => {
                    for v in s.field_mt {
                        w.cell(num(v))?;
                    }
                }
                Kind::Shock | Kind::Auto => w.cell(num(s.shock_g))?,
            }
            if with_input {
                w.cell(num(r.input.unwrap_or(0.0)))?;
            }
            for c in &r.samples {
                w.cell(num(c[k] / scale))?;
            }
            w.end_row()?;
        }
    }
    w.finish()?;
    Ok(())
}
