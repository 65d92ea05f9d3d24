//! `incal gfimu calibrate`, `incal gfimu solve`, `incal simulate gfimu` and
//! the gyro-free section of `incal demo` (seed 004; methods.md §4).

use std::path::{Path, PathBuf};

use clap::ValueEnum;
use incal::document::InputFile;
use incal::models::gfimu::{ArrayAccelerometer, Geometry};
use incal::procedures::gfimu::solve::Solver;
use incal::procedures::gfimu::{
    calibrate, CalibrateOptions, CalibratedAccelerometer, SolveOptions, StaticSample,
};
use incal::sim::gfimu::{
    motion_samples, simulate_static, six_positions, F0Frame, GfimuTruth, MotionProfile,
};
use incal::units::STANDARD_GRAVITY_M_S2;
use nalgebra::Vector3;
use serde_json::{json, Value};

use crate::error::{core, in_file, usage, CliError, CliResult};
use crate::input::Table;
use crate::options::noise_option;
use crate::output::{input_file, json_text, write_text, ResultArgs};

/// Geometry choice shared by every gfimu command.
#[derive(clap::Args, Debug, Clone)]
pub struct GeometryArgs {
    /// Array geometry file (TOML, [[accelerometer]] tables with name, position_m, direction).
    #[arg(long, conflicts_with = "lever_arm_m")]
    pub geometry: Option<PathBuf>,
    /// Lever arm L (m) of the built-in layout.
    #[arg(long)]
    pub lever_arm_m: Option<f64>,
    /// Built-in layout: paper (six: a, b at ±L on x sensing z; c, d on y sensing x; e, f on z sensing y) or twelve (two across each of ±L on x, y, z: px_y, px_z, mx_y, …; solves the centripetal products directly).
    #[arg(long, value_enum, default_value = "paper", conflicts_with = "geometry")]
    pub layout: Layout,
}

/// Built-in gyro-free layouts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Layout {
    /// The paper's six accelerometers (seed 004).
    Paper,
    /// Twelve accelerometers, two across each lever arm.
    Twelve,
}

/// Default lever arm of the built-in layout (m).
pub const DEFAULT_LEVER_ARM_M: f64 = 0.1;

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct GeometryFile {
    accelerometer: Vec<AccelerometerEntry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct AccelerometerEntry {
    name: String,
    // Vec, then checked: serde's fixed-size arrays ignore extra elements.
    position_m: Vec<f64>,
    direction: Vec<f64>,
}

impl GeometryArgs {
    /// The geometry and a label for messages; refuses a geometry that
    /// cannot solve for f0 and ω̇ (naming the file).
    pub fn load(&self) -> CliResult<(Geometry, String)> {
        self.load_with_input().map(|(g, l, _)| (g, l))
    }

    /// As [`GeometryArgs::load`], with the geometry file's input record
    /// (`None` for the built-in layout).
    pub fn load_with_input(&self) -> CliResult<(Geometry, String, Option<InputFile>)> {
        let (g, label, input) = match &self.geometry {
            Some(p) => {
                let (name, bytes, sha) = crate::io::read_hashed(p)?;
                let text = String::from_utf8(bytes)
                    .map_err(|_| CliError::Input(format!("{name}: not valid UTF-8")))?;
                let input = input_file("geometry", &p.display().to_string(), sha, None);
                if text.trim().is_empty() {
                    return Err(CliError::Input(format!(
                        "{name}: empty file (expected [[accelerometer]] tables)"
                    )));
                }
                let parsed: GeometryFile = toml::from_str(&text).map_err(|e| {
                    let line = e
                        .span()
                        .map(|s| text[..s.start.min(text.len())].lines().count().max(1));
                    let msg = e.message().replace('\n', " ");
                    CliError::Input(match line {
                        Some(l) => format!("{name}:{l}: {msg}"),
                        None => format!("{name}: {msg}"),
                    })
                })?;
                let mut accs = Vec::with_capacity(parsed.accelerometer.len());
                for (k, a) in parsed.accelerometer.into_iter().enumerate() {
                    for (field, v) in [("position_m", &a.position_m), ("direction", &a.direction)] {
                        if v.len() != 3 {
                            return Err(CliError::Input(format!(
                                "{name}: accelerometer[{k}].{field}: expected 3 numbers, got {}",
                                v.len()
                            )));
                        }
                    }
                    accs.push(ArrayAccelerometer {
                        name: a.name,
                        position_m: Vector3::new(a.position_m[0], a.position_m[1], a.position_m[2]),
                        direction: Vector3::new(a.direction[0], a.direction[1], a.direction[2]),
                    });
                }
                (
                    Geometry::new(accs).map_err(|e| in_file(&name, e))?,
                    name,
                    Some(input),
                )
            }
            None => {
                let l = self.lever_arm_m.unwrap_or(DEFAULT_LEVER_ARM_M);
                // A lever arm is a dimension of a unit on a table: millimetres
                // to a few metres.
                if !(l.is_finite() && l > 0.0 && l <= 10.0) {
                    return Err(usage(format!(
                        "--lever-arm-m must be positive and at most 10 m, got {}",
                        crate::output::num(l)
                    )));
                }
                let (g, what) = match self.layout {
                    Layout::Paper => (Geometry::paper(l), "paper"),
                    Layout::Twelve => (Geometry::twelve(l), "twelve-accelerometer"),
                };
                (
                    g.map_err(|e| usage(format!("--lever-arm-m: {e}")))?,
                    format!("{what} layout, lever arm {l} m"),
                    None,
                )
            }
        };
        g.require_solvable()
            .map_err(|e| usage(format!("{label}: geometry cannot solve the motion: {e}")))?;
        Ok((g, label, input))
    }
}

/// Options of `incal gfimu calibrate`.
#[derive(clap::Args, Debug)]
pub struct CalibrateArgs {
    /// Calibration CSV: position (+x, -x, +y, -y, +z, -z) or fx_g, fy_g, fz_g, and one column per accelerometer.
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Known standard deviation of one output sample (output units); default: from the data.
    #[arg(long)]
    pub noise: Option<f64>,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// Options of `incal gfimu solve`.
#[derive(clap::Args, Debug)]
pub struct SolveArgs {
    /// Calibration JSON written by `incal gfimu calibrate --json`.
    #[arg(long)]
    pub calibration: PathBuf,
    /// Time series CSV: time_s and one column per accelerometer.
    #[arg(long)]
    pub input: PathBuf,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Angular rate at the first sample (rad/s), x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub omega0_rad_s: Vec<f64>,
    /// Local gravity that defines the g unit (m/s^2).
    #[arg(long, visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Predicted u of the integrated angular rate (rad/s) beyond which a warning is given.
    #[arg(long, default_value_t = 0.01)]
    pub omega_u_limit_rad_s: f64,
    /// Print one JSON object instead of CSV (streamed, like the CSV).
    #[arg(long, conflicts_with = "jsonl")]
    pub json: bool,
    /// Print JSON lines: one object per sample, then one summary object.
    #[arg(long)]
    pub jsonl: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// What `incal simulate gfimu` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SimKind {
    /// Six-position static test (input of `gfimu calibrate`).
    Static,
    /// Rate-table motion time series (input of `gfimu solve`).
    Motion,
}

/// Options of `incal simulate gfimu`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    /// static (six-position calibration test) or motion (time series).
    #[arg(long, value_enum, default_value = "static")]
    pub kind: SimKind,
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Nominal scale factor of every accelerometer (output/g); truth K0, Ks are built from it.
    #[arg(long, default_value_t = 1.0)]
    pub k1: f64,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 1e-4)]
    pub noise: f64,
    /// Samples per static position.
    #[arg(long, default_value_t = 10)]
    pub samples: usize,
    /// Motion: record length (s).
    #[arg(long, default_value_t = 2.0)]
    pub duration_s: f64,
    /// Motion: sample rate (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
    /// Motion: spin-up duration with constant angular acceleration (s).
    #[arg(long, default_value_t = 1.005)]
    pub spin_up_s: f64,
    /// Motion: angular acceleration during spin-up (rad/s^2).
    #[arg(long, default_value_t = 2.0, allow_hyphen_values = true)]
    pub angular_accel_rad_s2: f64,
    /// Motion: rotation axis x,y,z (unit frame).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,1"
    )]
    pub axis: Vec<f64>,
    /// Motion: angular rate at t = 0 (rad/s), x,y,z.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0,0,0"
    )]
    pub omega0_rad_s: Vec<f64>,
    /// Motion: specific force at the origin (g), x,y,z (gravity along +z plus a constant acceleration).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "0.05,0,1"
    )]
    pub f0_g: Vec<f64>,
    /// Motion: the frame --f0-g is fixed in: unit (does not turn) or table (given at t = 0, turns through the unit as it rotates).
    #[arg(long, value_enum, default_value = "unit")]
    pub f0_frame: F0FrameArg,
    /// Motion: amplitude of a sinusoidal rate oscillation about the axis (rad/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub oscillation_amplitude_rad_s: f64,
    /// Motion: frequency of the rate oscillation (Hz, below half the sample rate).
    #[arg(long, default_value_t = 0.0)]
    pub oscillation_hz: f64,
    /// Local gravity that defines the g unit (m/s^2).
    #[arg(long, visible_alias = "g-local", default_value_t = STANDARD_GRAVITY_M_S2)]
    pub gravity_m_s2: f64,
    /// Random seed (same seed, same file).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `--f0-frame`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum F0FrameArg {
    Unit,
    Table,
}

fn vec3(opt: &str, v: &[f64]) -> CliResult<Vector3<f64>> {
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(usage(format!(
            "{opt}: expected three finite numbers x,y,z, got {v:?}"
        )));
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

fn parse_position(s: &str) -> Option<Vector3<f64>> {
    let (sign, axis) = match s.trim().as_bytes() {
        [b'+', a] => (1.0, *a),
        [b'-', a] => (-1.0, *a),
        _ => return None,
    };
    let k = match axis.to_ascii_lowercase() {
        b'x' => 0,
        b'y' => 1,
        b'z' => 2,
        _ => return None,
    };
    let mut f = Vector3::zeros();
    f[k] = sign;
    Some(f)
}

fn read_static(path: &Path, g: &Geometry) -> CliResult<(Table, Vec<StaticSample>)> {
    let t = Table::read(path)?;
    let pos_col = t.opt_column("position");
    if pos_col.is_some()
        && ["fx_g", "fy_g", "fz_g"]
            .iter()
            .any(|c| t.opt_column(c).is_some())
    {
        return Err(CliError::Input(format!(
            "{}: both a 'position' column and fx_g/fy_g/fz_g columns: give one description of the specific force",
            t.path
        )));
    }
    let force_cols = match pos_col {
        Some(_) => None,
        None => {
            if t.opt_column("fx_g").is_none() {
                return Err(CliError::Input(format!(
                    "{}: missing column 'position' (or columns fx_g, fy_g, fz_g)",
                    t.path
                )));
            }
            Some([t.column("fx_g")?, t.column("fy_g")?, t.column("fz_g")?])
        }
    };
    let acc_cols: Vec<usize> = g
        .names()
        .iter()
        .map(|n| t.column(n))
        .collect::<CliResult<_>>()?;
    let mut out = Vec::with_capacity(t.row_count());
    for row in 0..t.row_count() {
        let f = match (pos_col, force_cols) {
            (Some(c), _) => parse_position(t.text(row, c)).ok_or_else(|| {
                t.error_at(
                    row,
                    format!(
                        "column 'position': '{}' is not one of +x, -x, +y, -y, +z, -z",
                        crate::output::clip(t.text(row, c))
                    ),
                )
            })?,
            (None, Some(c)) => {
                Vector3::new(t.f64(row, c[0])?, t.f64(row, c[1])?, t.f64(row, c[2])?)
            }
            (None, None) => unreachable_columns()?,
        };
        let outputs = acc_cols
            .iter()
            .map(|&c| t.f64(row, c))
            .collect::<CliResult<_>>()?;
        out.push(StaticSample {
            specific_force_g: f,
            outputs,
        });
    }
    Ok((t, out))
}

/// Never reached (a position or force column was found above); an error
/// instead of a panic keeps input from ever aborting the process.
fn unreachable_columns() -> CliResult<Vector3<f64>> {
    Err(usage("no position columns"))
}

/// `incal gfimu calibrate`.
pub fn run_calibrate(a: &CalibrateArgs) -> CliResult<()> {
    let noise = noise_option(a.noise)?;
    let (g, label, geometry_input) = a.geometry.load_with_input()?;
    let (table, samples) = read_static(&a.input, &g)?;
    let cal = calibrate(&g, &samples, &CalibrateOptions { noise })
        .map_err(|e| in_file(&table.path, e))?;
    let mut doc = cal
        .document(&label, a.noise.is_some())
        .map_err(|e| in_file(&table.path, e))?;
    doc.inputs.push(table.input_file("input"));
    doc.inputs.extend(geometry_input);
    doc.options.insert("noise".into(), json!(a.noise));
    a.result.emit(doc)
}

fn read_calibration(
    path: &Path,
    g: &Geometry,
) -> CliResult<(String, Vec<CalibratedAccelerometer>)> {
    let (name, text) = crate::io::read_text(path)?;
    if text.trim().is_empty() {
        return Err(CliError::Input(format!(
            "{name}: empty file (expected the JSON of 'incal gfimu calibrate --json')"
        )));
    }
    let doc: Value = serde_json::from_str(&text)
        .map_err(|e| CliError::Input(format!("{name}:{}: not valid JSON: {e}", e.line())))?;
    let accs = doc
        .get("accelerometers")
        .and_then(Value::as_object)
        .ok_or_else(|| {
            CliError::Input(format!(
                "{name}: $.accelerometers: missing or not an object (expected the JSON of 'incal gfimu calibrate --json')"
            ))
        })?;
    let names = g.names();
    // An accelerometer the geometry does not have: a calibration of
    // another array.
    if let Some(extra) = accs.keys().find(|k| !names.contains(k)) {
        return Err(CliError::Input(format!(
            "{name}: $.accelerometers.{}: not an accelerometer of the geometry ({})",
            crate::output::clip(extra),
            names.join(", ")
        )));
    }
    const KNOWN: [&str; 5] = [
        "K0",
        "Ks",
        "k0_consistency",
        "noise_output",
        "nominal_direction",
    ];
    let mut out = Vec::new();
    for n in names {
        let a = accs.get(&n).ok_or_else(|| {
            CliError::Input(format!(
                "{name}: $.accelerometers.{n}: missing: accelerometer '{n}' of the geometry is not calibrated in this file"
            ))
        })?;
        let obj = a.as_object().ok_or_else(|| {
            CliError::Input(format!("{name}: $.accelerometers.{n}: not an object"))
        })?;
        if let Some(k) = obj.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(CliError::Input(format!(
                "{name}: $.accelerometers.{n}.{}: unknown field (expected {})",
                crate::output::clip(k),
                KNOWN.join(", ")
            )));
        }
        let bad = |path: &str, what: &str| {
            CliError::Input(format!("{name}: $.accelerometers.{n}.{path}: {what}"))
        };
        let k0 = a
            .pointer("/K0/value")
            .and_then(Value::as_f64)
            .ok_or_else(|| bad("K0.value", "missing or not a number"))?;
        let ks: Vec<f64> = a
            .pointer("/Ks/value")
            .and_then(Value::as_array)
            .filter(|v| v.len() == 3)
            .and_then(|v| v.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
            .ok_or_else(|| bad("Ks.value", "must be an array of exactly three numbers"))?;
        let noise_output = match a.get("noise_output") {
            None | Some(Value::Null) => None,
            Some(v) => Some(
                v.as_f64()
                    .filter(|s| s.is_finite() && *s > 0.0)
                    .ok_or_else(|| bad("noise_output", "must be a positive number or null"))?,
            ),
        };
        // The calibration's u (optional: a hand-made file may omit it).
        let u_k0 = match a.pointer("/K0/u") {
            None | Some(Value::Null) => 0.0,
            Some(v) => v
                .as_f64()
                .filter(|u| u.is_finite() && *u >= 0.0)
                .ok_or_else(|| bad("K0.u", "must be a non-negative number"))?,
        };
        let u_ks = match a.pointer("/Ks/u") {
            None | Some(Value::Null) => Vector3::zeros(),
            Some(v) => {
                let u = v
                    .as_array()
                    .filter(|v| v.len() == 3)
                    .and_then(|v| v.iter().map(Value::as_f64).collect::<Option<Vec<f64>>>())
                    .filter(|u| u.iter().all(|x| x.is_finite() && *x >= 0.0))
                    .ok_or_else(|| bad("Ks.u", "must be an array of three non-negative numbers"))?;
                Vector3::new(u[0], u[1], u[2])
            }
        };
        out.push(CalibratedAccelerometer {
            k0,
            ks: Vector3::new(ks[0], ks[1], ks[2]),
            noise_output,
            u_k0,
            u_ks,
        });
    }
    Ok((name, out))
}

/// `incal gfimu solve`.
pub fn run_solve(a: &SolveArgs) -> CliResult<()> {
    let omega0 = vec3("--omega0-rad-s", &a.omega0_rad_s)?;
    if !(a.gravity_m_s2.is_finite() && a.gravity_m_s2 > 0.0 && a.gravity_m_s2 <= 100.0) {
        return Err(usage(
            "--gravity-m-s2 must be a positive number (at most 100)",
        ));
    }
    if !(a.omega_u_limit_rad_s.is_finite() && a.omega_u_limit_rad_s > 0.0) {
        return Err(usage("--omega-u-limit-rad-s must be a positive number"));
    }
    let (g, _) = a.geometry.load()?;
    let (cal_file, cal) = read_calibration(&a.calibration, &g)?;
    let opts = SolveOptions {
        omega0_rad_s: omega0,
        gravity_m_s2: a.gravity_m_s2,
        omega_u_limit_rad_s: a.omega_u_limit_rad_s,
    };
    // Everything about the calibration is checked before the series is read.
    let solver = Solver::new(&g, &cal, &opts).map_err(|e| match e {
        incal::Error::Unseparable { .. } | incal::Error::IllConditioned { .. } => in_file(
            &cal_file,
            format!("calibrated geometry cannot solve the motion: {e}"),
        ),
        e => in_file(&cal_file, e),
    })?;
    let kind = if a.json {
        OutKind::Json
    } else if a.jsonl {
        OutKind::JsonLines
    } else {
        OutKind::Csv
    };
    stream_solve(a, &g, solver, kind)
}

/// Rows parsed per batch handed from the reader thread to the solver.
const BATCH_ROWS: usize = 4096;

/// One batch of parsed rows: line numbers and `[t, e_1 … e_N]` per row.
struct Batch {
    lines: Vec<u64>,
    values: Vec<f64>,
}

/// What the reader thread sends: a batch, or the error that stopped it
/// (after every good row before it).
enum Parsed {
    Rows(Batch),
    Failed(CliError),
}

/// Open the series input (a file or `-`, past a UTF-8 byte-order mark) as
/// a CSV reader of byte records.
fn series_reader(path: &Path) -> CliResult<csv::Reader<Box<dyn std::io::Read + Send>>> {
    let (_, reader) = crate::io::open_input(path)?;
    let boxed: Box<dyn std::io::Read + Send> = Box::new(reader);
    Ok(csv::ReaderBuilder::new()
        .has_headers(false)
        .comment(Some(b'#'))
        .flexible(true)
        // Fields are trimmed where they are read (a number, a header
        // name): csv's own trim copies every record.
        .from_reader(boxed))
}

/// The next record of the series, false at its end; a CSV error names
/// its line.
fn next_record(
    name: &str,
    csv: &mut csv::Reader<Box<dyn std::io::Read + Send>>,
    rec: &mut csv::ByteRecord,
) -> CliResult<bool> {
    csv.read_byte_record(rec).map_err(|e| {
        let line = e.position().map_or(0, |p| p.line());
        CliError::Input(format!("{name}:{line}: not valid CSV"))
    })
}

/// Read the header of the series: the column of `time_s` and of every
/// accelerometer (geometry order), and the header's width.
fn series_header(
    name: &str,
    csv: &mut csv::Reader<Box<dyn std::io::Read + Send>>,
    g: &Geometry,
) -> CliResult<(Vec<usize>, usize)> {
    let mut rec = csv::ByteRecord::new();
    loop {
        if !next_record(name, csv, &mut rec)? {
            return Err(CliError::Input(format!(
                "{name}: empty file (expected a header row)"
            )));
        }
        if rec.iter().all(|f| f.trim_ascii().is_empty()) {
            continue;
        }
        let headers: Vec<String> = rec
            .iter()
            .map(|h| String::from_utf8_lossy(h.trim_ascii()).to_string())
            .collect();
        let find = |n: &str| {
            headers.iter().position(|h| h == n).ok_or_else(|| {
                CliError::Input(format!(
                    "{name}: missing column '{n}' (columns: {})",
                    crate::output::clip(&headers.join(", "))
                ))
            })
        };
        let mut cols = vec![find("time_s")?];
        for n in g.names() {
            cols.push(find(&n)?);
        }
        return Ok((cols, headers.len()));
    }
}

/// The reader thread: parse every data row into batches of numbers, in
/// order; stop at the first bad row and send its error. A row is checked
/// here (width, numbers, increasing time) so the solver sees only clean
/// samples; the line numbers travel with the rows for the solver's errors.
fn parse_series(
    name: &str,
    mut csv: csv::Reader<Box<dyn std::io::Read + Send>>,
    cols: &[usize],
    names: &[String],
    width: usize,
    tx: &std::sync::mpsc::SyncSender<Parsed>,
    recycled: &std::sync::mpsc::Receiver<Batch>,
) {
    let mut rec = csv::ByteRecord::new();
    let mut prev_t: Option<f64> = None;
    let mut batch = Batch {
        lines: Vec::with_capacity(BATCH_ROWS),
        values: Vec::with_capacity(BATCH_ROWS * cols.len()),
    };
    let result = (|| -> CliResult<()> {
        loop {
            if !next_record(name, &mut csv, &mut rec)? {
                return Ok(());
            }
            let line = rec.position().map_or(0, |p| p.line());
            // A blank row (first field empty, then all) is skipped.
            if rec.get(0).is_none_or(|f| f.trim_ascii().is_empty())
                && rec.iter().all(|f| f.trim_ascii().is_empty())
            {
                continue;
            }
            if rec.len() != width {
                return Err(CliError::Input(format!(
                    "{name}:{line}: {} fields, but the header has {width}",
                    rec.len()
                )));
            }
            // One UTF-8 check per row; fields split at ASCII delimiters
            // are then valid on their own.
            let text = std::str::from_utf8(rec.as_slice()).ok();
            for (i, &k) in cols.iter().enumerate() {
                let field = text.and_then(|t| t.get(rec.range(k).unwrap_or(0..0)));
                let v = match field.map(|f| f.trim_ascii().parse::<f64>()) {
                    Some(Ok(v)) if v.is_finite() && v.abs() <= crate::input::MAX_ABS_VALUE => v,
                    _ => {
                        let what = if i == 0 { "time_s" } else { &names[i - 1] };
                        return Err(CliError::Input(format!(
                            "{name}:{line}: column '{what}': '{}' is not a finite number within 1e15",
                            crate::output::clip(&String::from_utf8_lossy(rec[k].trim_ascii()))
                        )));
                    }
                };
                if i == 0 {
                    if let Some(prev) = prev_t {
                        if v <= prev {
                            return Err(CliError::Input(format!(
                                "{name}:{line}: column 'time_s': {v} is not after the previous sample ({prev})"
                            )));
                        }
                    }
                    prev_t = Some(v);
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
                    Err(_) => Batch {
                        lines: Vec::with_capacity(BATCH_ROWS),
                        values: Vec::with_capacity(BATCH_ROWS * cols.len()),
                    },
                };
                let full = std::mem::replace(&mut batch, next);
                if tx.send(Parsed::Rows(full)).is_err() {
                    // The solver stopped (its own error): nothing to add.
                    return Ok(());
                }
            }
        }
    })();
    if !batch.lines.is_empty() {
        let _ = tx.send(Parsed::Rows(batch));
    }
    if let Err(e) = result {
        let _ = tx.send(Parsed::Failed(e));
    }
}

/// Output of `gfimu solve`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OutKind {
    Csv,
    Json,
    JsonLines,
}

/// CSV header of the solution.
const SOLUTION_CSV_HEADER: &str = "time_s,f0_x_g,f0_y_g,f0_z_g,omega_dot_x_rad_s2,omega_dot_y_rad_s2,omega_dot_z_rad_s2,omega_x_rad_s,omega_y_rad_s,omega_z_rad_s,u_f0_x_g,u_f0_y_g,u_f0_z_g,u_omega_dot_x_rad_s2,u_omega_dot_y_rad_s2,u_omega_dot_z_rad_s2,u_omega_x_rad_s,u_omega_y_rad_s,u_omega_z_rad_s\n";

/// Units of the solution's quantities (JSON).
fn solution_units() -> Value {
    json!({"time_s": "s", "f0_g": "g", "omega_dot_rad_s2": "rad/s^2", "omega_rad_s": "rad/s",
        "u_f0_g": "g", "u_omega_dot_rad_s2": "rad/s^2", "u_omega_rad_s": "rad/s"})
}

/// The `geometry` object of the JSON outputs: rank and condition number
/// of the motion system (null when infinite).
fn geometry_json(d: &incal::estimation::Diagnostics) -> Value {
    json!({
        "rank": d.rank,
        "condition_number": d.condition.is_finite().then_some(d.condition),
    })
}

/// What comes before the first sample: the CSV header, or the JSON
/// object's opening up to its `samples` array.
fn solution_head(file: &str, kind: OutKind, d: &incal::estimation::Diagnostics) -> String {
    match kind {
        OutKind::Csv => SOLUTION_CSV_HEADER.to_string(),
        OutKind::JsonLines => String::new(),
        OutKind::Json => {
            format!(
                "{{\n  \"procedure\": \"gfimu-solve\",\n  \"input\": {},\n  \"units\": {},\n  \"geometry\": {},\n  \"samples\": [\n",
                json!(file),
                solution_units(),
                geometry_json(d)
            )
        }
    }
}

/// What comes after the last sample: the CSV trailer comments, the JSON
/// object's mode and warnings, or the JSON-lines summary line; with
/// `error`, the reason the run stopped early (`# error:`, `"error"`).
fn solution_tail(kind: OutKind, solver: &Solver, error: Option<&str>) -> String {
    match kind {
        OutKind::Csv => {
            let mut t = format!("# mode: {}\n", solver.mode().name());
            for x in solver.warnings() {
                t.push_str(&format!("# warning: {x}\n"));
            }
            if let Some(e) = error {
                t.push_str(&format!("# error: {e}\n"));
            }
            t
        }
        OutKind::Json => {
            let mut t = format!(
                ",\n  \"mode\": {},\n  \"warnings\": {}",
                json!(solver.mode().name()),
                json!(solver.warnings())
            );
            if let Some(e) = error {
                t.push_str(&format!(",\n  \"error\": {}", json!(e)));
            }
            t.push_str("\n}\n");
            t
        }
        OutKind::JsonLines => {
            let mut summary = json!({
                "procedure": "gfimu-solve",
                "units": solution_units(),
                "geometry": geometry_json(solver.diagnostics()),
                "mode": solver.mode().name(),
                "warnings": solver.warnings(),
            });
            if let Some(e) = error {
                summary["error"] = json!(e);
            }
            format!("{}\n", json!({ "summary": summary }))
        }
    }
}

/// Write one solved sample into `buf` (cleared first) in the output's
/// form, every number as its shortest round-trip decimal (ryu: formatting
/// dominated the run at 10⁶ rows). False when a number is not finite.
fn sample_line(
    buf: &mut String,
    fmt: &mut ryu::Buffer,
    m: &incal::procedures::gfimu::solve::MotionSample,
    kind: OutKind,
    first: bool,
) -> bool {
    let values = [m.f0_g, m.omega_dot_rad_s2, m.omega_rad_s];
    let us = [m.u_f0_g, m.u_omega_dot_rad_s2, m.u_omega_rad_s];
    let finite = m.time_s.is_finite()
        && values.iter().all(|v| v.iter().all(|x| x.is_finite()))
        && us.iter().flatten().all(|v| v.iter().all(|x| x.is_finite()));
    if !finite {
        return false;
    }
    buf.clear();
    match kind {
        OutKind::Csv => {
            buf.push_str(fmt.format(m.time_s));
            for v in values {
                for x in v.iter() {
                    buf.push(',');
                    buf.push_str(fmt.format(*x));
                }
            }
            for u in us {
                match u {
                    Some(v) => {
                        for x in v.iter() {
                            buf.push(',');
                            buf.push_str(fmt.format(*x));
                        }
                    }
                    None => buf.push_str(",,,"),
                }
            }
            buf.push('\n');
        }
        OutKind::Json | OutKind::JsonLines => {
            if kind == OutKind::Json {
                buf.push_str(if first { "    " } else { ",\n    " });
            }
            buf.push_str("{\"time_s\":");
            buf.push_str(fmt.format(m.time_s));
            let value_keys = ["f0_g", "omega_dot_rad_s2", "omega_rad_s"];
            for (key, v) in value_keys.iter().zip(values) {
                push_json_vec(buf, fmt, ',', key, Some(v));
            }
            // The JSON document keeps the contract's shape (u in its own
            // "uncertainty" array, written by `u_line`); JSON lines carry
            // u inside each sample.
            if kind == OutKind::JsonLines {
                for (key, v) in U_KEYS.iter().zip(us) {
                    push_json_vec(buf, fmt, ',', key, v);
                }
            }
            buf.push('}');
            if kind == OutKind::JsonLines {
                buf.push('\n');
            }
        }
    }
    true
}

const U_KEYS: [&str; 3] = ["u_f0_g", "u_omega_dot_rad_s2", "u_omega_rad_s"];

/// `{sep}"key":[x,y,z]` (or `null`) appended to `buf`.
fn push_json_vec(
    buf: &mut String,
    fmt: &mut ryu::Buffer,
    sep: char,
    key: &str,
    v: Option<Vector3<f64>>,
) {
    buf.push(sep);
    buf.push('"');
    buf.push_str(key);
    buf.push_str("\":");
    match v {
        Some(v) => {
            for (i, x) in v.iter().enumerate() {
                buf.push(if i == 0 { '[' } else { ',' });
                buf.push_str(fmt.format(*x));
            }
            buf.push(']');
        }
        None => buf.push_str("null"),
    }
}

/// One element of the JSON document's `"uncertainty"` array, or false when
/// this sample has no u (the array is then `null`, as for a calibration
/// without noise).
fn u_line(
    buf: &mut String,
    fmt: &mut ryu::Buffer,
    m: &incal::procedures::gfimu::solve::MotionSample,
    first: bool,
) -> bool {
    let us = [m.u_f0_g, m.u_omega_dot_rad_s2, m.u_omega_rad_s];
    if us.iter().any(|u| u.is_none()) {
        return false;
    }
    buf.clear();
    buf.push_str(if first { "    " } else { ",\n    " });
    for (i, (key, v)) in U_KEYS.iter().zip(us).enumerate() {
        push_json_vec(buf, fmt, if i == 0 { '{' } else { ',' }, key, v);
    }
    buf.push('}');
    true
}

/// A temporary file holding the JSON document's `"uncertainty"` array
/// while the samples stream out (it follows them in the document), so a
/// long series needs no memory for it; removed when dropped.
struct Spill {
    path: std::path::PathBuf,
    w: Option<std::io::BufWriter<std::fs::File>>,
}

impl Spill {
    fn new() -> CliResult<Spill> {
        static COUNT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = COUNT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("incal-gfimu-u-{}-{n}.json", std::process::id()));
        let f = std::fs::File::create(&path).map_err(|e| {
            CliError::Failure(anyhow::anyhow!("{}: cannot write: {e}", path.display()))
        })?;
        Ok(Spill {
            path,
            w: Some(std::io::BufWriter::with_capacity(1 << 16, f)),
        })
    }
}

impl Drop for Spill {
    fn drop(&mut self) {
        self.w = None;
        let _ = std::fs::remove_file(&self.path);
    }
}

/// `gfimu solve`, one row in, one row out (CSV, JSON or JSON lines):
/// constant memory. The input is parsed on a second thread, a few thousand
/// rows ahead of the solver; the output is the same bytes as a serial run.
fn stream_solve(a: &SolveArgs, g: &Geometry, mut solver: Solver, kind: OutKind) -> CliResult<()> {
    use std::io::Write;
    let name = crate::io::display_name(&a.input);
    let mut csv = series_reader(&a.input)?;
    let (cols, width) = series_header(&name, &mut csv, g)?;
    let mut w = crate::io::open_output(a.output.as_deref())?;
    let wfail =
        |e: std::io::Error| CliError::Failure(anyhow::anyhow!("cannot write the solution: {e}"));
    w.write_all(solution_head(&name, kind, solver.diagnostics()).as_bytes())
        .map_err(wfail)?;
    let names = g.names();
    let stride = cols.len();
    let mut rows = 0u64;
    let mut fmt = ryu::Buffer::new();
    let mut line_buf = String::with_capacity(512);
    let mut spill = match kind {
        OutKind::Json => Some(Spill::new()?),
        _ => None,
    };
    let outcome = std::thread::scope(|scope| -> CliResult<()> {
        let (tx, rx) = std::sync::mpsc::sync_channel::<Parsed>(8);
        let (back_tx, back_rx) = std::sync::mpsc::sync_channel::<Batch>(8);
        let (name_r, cols_r, names_r) = (&name, &cols, &names);
        scope.spawn(move || parse_series(name_r, csv, cols_r, names_r, width, &tx, &back_rx));
        for msg in rx.iter() {
            let batch = match msg {
                Parsed::Rows(b) => b,
                Parsed::Failed(e) => {
                    w.flush().map_err(wfail)?;
                    return Err(e);
                }
            };
            for (line, row) in batch.lines.iter().zip(batch.values.chunks_exact(stride)) {
                let m = match solver.step(row[0], &row[1..]) {
                    Ok(m) => m,
                    Err(err) => {
                        w.flush().map_err(wfail)?;
                        // Dropping the receiver stops the reader.
                        drop(rx);
                        return Err(CliError::Input(format!("{name}:{line}: {err}")));
                    }
                };
                rows += 1;
                if !sample_line(&mut line_buf, &mut fmt, &m, kind, rows == 1) {
                    w.flush().map_err(wfail)?;
                    drop(rx);
                    return Err(CliError::Input(format!(
                        "{name}:{line}: the solution is not finite at this sample (t = {} s)",
                        m.time_s
                    )));
                }
                w.write_all(line_buf.as_bytes()).map_err(wfail)?;
                if let Some(sp) = spill.as_mut() {
                    if u_line(&mut line_buf, &mut fmt, &m, rows == 1) {
                        if let Some(sw) = sp.w.as_mut() {
                            sw.write_all(line_buf.as_bytes()).map_err(wfail)?;
                        }
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
    let outcome = match outcome {
        Ok(()) if rows == 0 => Err(CliError::Input(format!(
            "{name}: no data rows after the header"
        ))),
        // A write failure: nothing more can be written.
        Err(CliError::Failure(e)) => return Err(CliError::Failure(e)),
        o => o,
    };
    // Stopped by the input (a bad row, a diverged solution): the rows
    // before it stay, and the output is closed with the reason, so a JSON
    // document stays valid; the exit code still says it failed.
    let error = match &outcome {
        Err(CliError::Input(msg)) => Some(msg.as_str()),
        _ => None,
    };
    if kind == OutKind::Json {
        w.write_all(b"\n  ],\n  \"uncertainty\": ").map_err(wfail)?;
        match spill.as_mut() {
            Some(sp) => {
                if let Some(mut sw) = sp.w.take() {
                    sw.flush().map_err(wfail)?;
                }
                w.write_all(b"[\n").map_err(wfail)?;
                let mut f = std::fs::File::open(&sp.path).map_err(wfail)?;
                std::io::copy(&mut f, &mut w).map_err(wfail)?;
                w.write_all(b"\n  ]").map_err(wfail)?;
            }
            None => w.write_all(b"null").map_err(wfail)?,
        }
    }
    w.write_all(solution_tail(kind, &solver, error).as_bytes())
        .map_err(wfail)?;
    w.flush().map_err(wfail)?;
    outcome
}

fn position_label(f: &Vector3<f64>) -> String {
    let k = f.iamax();
    format!(
        "{}{}",
        if f[k] > 0.0 { "+" } else { "-" },
        ["x", "y", "z"][k]
    )
}

/// `incal simulate gfimu`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    if !(a.k1.is_finite() && a.k1 != 0.0) {
        return Err(usage("--k1 must be a finite non-zero number"));
    }
    if !(a.noise.is_finite() && a.noise >= 0.0) {
        return Err(usage("--noise must be a non-negative number"));
    }
    let (g, label) = a.geometry.load()?;
    let truth = GfimuTruth::typical(&g, a.k1);
    let names = g.names();
    let mut text = format!("# simulated gyro-free unit ({label}), seed {}\n", a.seed);
    for (j, n) in names.iter().enumerate() {
        let ks = truth.ks[j];
        text.push_str(&format!(
            "# truth {n}: K0 = {} output, Ks = [{}, {}, {}] output/g\n",
            truth.k0[j], ks.x, ks.y, ks.z
        ));
    }
    match a.kind {
        SimKind::Static => {
            if a.samples == 0 {
                return Err(usage("--samples must be at least 1"));
            }
            let data = simulate_static(&g, &truth, &six_positions(), a.samples, a.noise, a.seed)
                .map_err(core)?;
            text.push_str(&format!("position,{}\n", names.join(",")));
            for s in &data {
                let v: Vec<String> = s.outputs.iter().map(|x| x.to_string()).collect();
                text.push_str(&format!(
                    "{},{}\n",
                    position_label(&s.specific_force_g),
                    v.join(",")
                ));
            }
        }
        SimKind::Motion => {
            let m = MotionProfile {
                axis: vec3("--axis", &a.axis)?,
                angular_accel_rad_s2: a.angular_accel_rad_s2,
                spin_up_s: a.spin_up_s,
                omega0_rad_s: vec3("--omega0-rad-s", &a.omega0_rad_s)?,
                f0_g: vec3("--f0-g", &a.f0_g)?,
                f0_frame: match a.f0_frame {
                    F0FrameArg::Unit => F0Frame::Unit,
                    F0FrameArg::Table => F0Frame::Table,
                },
                oscillation_amplitude_rad_s: a.oscillation_amplitude_rad_s,
                oscillation_hz: a.oscillation_hz,
                duration_s: a.duration_s,
                rate_hz: a.rate_hz,
                gravity_m_s2: a.gravity_m_s2,
            };
            if m.axis.norm() == 0.0 {
                return Err(usage("--axis must not be zero"));
            }
            if !(m.angular_accel_rad_s2.is_finite()
                && m.spin_up_s.is_finite()
                && m.spin_up_s >= 0.0)
            {
                return Err(usage(
                    "--angular-accel-rad-s2 and --spin-up-s must be finite (spin-up >= 0)",
                ));
            }
            if !(m.oscillation_hz.is_finite()
                && m.oscillation_hz >= 0.0
                && m.oscillation_hz < m.rate_hz / 2.0)
            {
                return Err(usage(format!(
                    "--oscillation-hz must be at least 0 and below half of --rate-hz ({} Hz), got {}",
                    m.rate_hz / 2.0,
                    m.oscillation_hz
                )));
            }
            if !m.oscillation_amplitude_rad_s.is_finite()
                || (m.oscillation_amplitude_rad_s != 0.0 && m.oscillation_hz == 0.0)
            {
                return Err(usage(
                    "--oscillation-amplitude-rad-s must be finite, with --oscillation-hz > 0 when it is not 0",
                ));
            }
            if m.f0_frame == F0Frame::Table && !m.omega0_along_axis() {
                return Err(usage(
                    "--f0-frame table: --omega0-rad-s must lie along --axis (the unit turns about that one axis)",
                ));
            }
            let series = motion_samples(&g, &truth, &m, a.noise, a.seed).map_err(core)?;
            text.push_str(&format!(
                "# motion: axis {:?}, {} rad/s^2 for {} s, f0 {:?} g, omega0 {:?} rad/s\n",
                a.axis, a.angular_accel_rad_s2, a.spin_up_s, a.f0_g, a.omega0_rad_s
            ));
            if m.f0_frame == F0Frame::Table || m.oscillation_amplitude_rad_s != 0.0 {
                text.push_str(&format!(
                    "# f0 frame: {}; rate oscillation {} rad/s at {} Hz\n",
                    if m.f0_frame == F0Frame::Table {
                        "table (turns with the rotation)"
                    } else {
                        "unit"
                    },
                    m.oscillation_amplitude_rad_s,
                    m.oscillation_hz
                ));
            }
            text.push_str(&format!("time_s,{}\n", names.join(",")));
            // Streamed row by row: 10⁶ samples need no memory for the file.
            use std::fmt::Write as _;
            use std::io::Write as _;
            let mut w = crate::io::open_output(a.output.as_deref())?;
            let fail = |e: std::io::Error| {
                CliError::Failure(anyhow::anyhow!("cannot write the series: {e}"))
            };
            w.write_all(text.as_bytes()).map_err(fail)?;
            let mut row = String::with_capacity(512);
            for (t, e) in series {
                row.clear();
                let _ = write!(row, "{t}");
                for x in &e {
                    let _ = write!(row, ",{x}");
                }
                row.push('\n');
                w.write_all(row.as_bytes()).map_err(fail)?;
            }
            return w.flush().map_err(fail);
        }
    }
    write_text(a.output.as_deref(), &text)
}

/// Options of `incal plan gfimu`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub geometry: GeometryArgs,
    /// Static positions, comma separated, from +x, -x, +y, -y, +z, -z (default: the six-position test).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub positions: Option<Vec<String>>,
    /// Samples per position.
    #[arg(long, default_value_t = 1)]
    pub samples: usize,
    /// Standard deviation of one output sample (output units).
    #[arg(long)]
    pub noise: f64,
    /// Nominal scale factor of every accelerometer (output/g).
    #[arg(long, default_value_t = 1.0)]
    pub k1: f64,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write to this file instead of standard output.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal plan gfimu`: predicted u of every K0 and Ks, and the geometry's
/// conditioning for the motion solution.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    if !(a.noise.is_finite() && a.noise > 0.0) {
        return Err(usage(format!(
            "--noise must be a positive number, got {}",
            crate::output::num(a.noise)
        )));
    }
    if a.samples == 0 || a.samples > 100_000_000 {
        return Err(usage("--samples must be within 1..100000000"));
    }
    if !(a.k1.is_finite() && a.k1 != 0.0 && a.k1.abs() <= 1e9) {
        return Err(usage("--k1 must be non-zero and at most 1e9 in magnitude"));
    }
    let (g, label) = a.geometry.load()?;
    let positions: Vec<Vector3<f64>> = match &a.positions {
        None => six_positions(),
        Some(list) => list
            .iter()
            .map(|p| {
                parse_position(p.trim()).ok_or_else(|| {
                    usage(format!(
                        "--positions: '{}' is not one of +x, -x, +y, -y, +z, -z",
                        crate::output::clip(p)
                    ))
                })
            })
            .collect::<CliResult<_>>()?,
    };
    let cal = incal::procedures::gfimu::calibrate::plan(&g, &positions, a.samples, a.noise, a.k1)
        .map_err(|e| usage(format!("{label}: {e}")))?;
    let d = g.check().map_err(core)?;
    let mode = incal::procedures::gfimu::solve::solve_mode(
        &g,
        &g.accelerometers()
            .iter()
            .map(|x| x.direction)
            .collect::<Vec<_>>(),
        STANDARD_GRAVITY_M_S2,
    )
    .map_err(core)?;
    let rows: Vec<(String, [f64; 4])> = cal
        .accelerometers
        .iter()
        .map(|acc| {
            let l = &acc.linear;
            (
                acc.name.clone(),
                [l.u_at(0), l.u_at(1), l.u_at(2), l.u_at(3)],
            )
        })
        .collect();
    if a.json {
        let mut u = serde_json::Map::new();
        for (n, v) in &rows {
            u.insert(n.clone(), json!({"K0": v[0], "Ks": [v[1], v[2], v[3]]}));
        }
        let doc = json!({
            "plan": "gfimu",
            "geometry": label,
            "positions": positions.iter().map(|f| [f.x, f.y, f.z]).collect::<Vec<_>>(),
            "samples": a.samples,
            "noise": a.noise,
            "k1": a.k1,
            "predicted_u": Value::Object(u),
            "units": {"K0": "output", "Ks": "output/g"},
            "motion": {
                "rank": d.rank,
                "condition_number": d.condition.is_finite().then_some(d.condition),
                "mode": mode.name(),
            },
            "warnings": cal.warnings,
        });
        return write_text(a.output.as_deref(), &json_text(&doc));
    }
    let mut s = format!(
        "Gyro-free unit calibration plan: {label}, {} positions x {} samples, noise {:e} per sample, K1 = {} output/g\n",
        positions.len(),
        a.samples,
        a.noise,
        a.k1
    );
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|(n, v)| {
            let mut r = vec![n.clone()];
            r.extend(v.iter().map(|x| crate::output::sig(*x, 3)));
            r
        })
        .collect();
    s.push_str(&crate::output::table(
        &[
            "accelerometer",
            "u_K0 (output)",
            "u_Ks_x (output/g)",
            "u_Ks_y (output/g)",
            "u_Ks_z (output/g)",
        ],
        &body,
    ));
    s.push_str(&format!(
        "motion solution: rank {} of 6, condition number {:.3}, mode {}\n",
        d.rank,
        d.condition,
        mode.name()
    ));
    for w in &cal.warnings {
        s.push_str(&format!("warning [{}]: {}\n", w.code, w.message));
    }
    write_text(a.output.as_deref(), &s)
}
