//! Reading and writing the files of a gyro-free unit: the array geometry
//! (TOML), the static calibration CSV, the calibration JSON that
//! `gfimu solve` reads back, and the motion time series (CSV). Pure: the
//! front end opens the files and hands over their bytes or a reader.
//!
//! # Geometry file (TOML)
//! ```toml
//! [[accelerometer]]
//! name = "a"                   # a CSV column name
//! position_m = [0.1, 0.0, 0.0] # r_j, unit frame (m)
//! direction = [0.0, 0.0, 1.0]  # nominal sensitive direction l_j
//! ```
//!
//! # Static CSV
//! Either a `position` column (`+x`, `-x`, `+y`, `-y`, `+z`, `-z`: the
//! unit axis pointing up, a specific force of 1 g along it) or the
//! specific force itself in columns `fx_g`, `fy_g`, `fz_g` (g, unit frame),
//! and one column per accelerometer named as in the geometry (output).
//!
//! # Motion CSV
//! `time_s` (s, not decreasing; the streaming time-stamp policy of [`crate::timebase::StampStream`]) and one column per accelerometer
//! (output); other columns are ignored.

use std::io::{Read, Write};

use incal_io::{clip, Cell, CsvWriter, InputError, MAX_ABS_VALUE};
use nalgebra::Vector3;
use serde_json::Value;

use super::{CalibratedAccelerometer, StaticSample};
use crate::document::InputFile;
use crate::error::{Error, Result};
use crate::models::gfimu::{ArrayAccelerometer, Geometry};

/// Built-in gyro-free layouts (`paper`, `twelve` at the edges).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// The six accelerometers of Fig. 1 of the technical note *Error
    /// coefficient calibration algorithm; error compensation algorithm*
    /// (authors and year not known): a, b at ±L on x
    /// sensing z; c, d at ±L on y sensing x; e, f at ±L on z sensing y.
    #[default]
    Paper,
    /// Twelve accelerometers, two across each of the six lever arms: the
    /// centripetal products are solved directly.
    Twelve,
}

/// Default lever arm L of the built-in layouts (m).
pub const DEFAULT_LEVER_ARM_M: f64 = 0.1;

/// Largest lever arm of a built-in layout (m): a unit on a table is
/// millimetres to a few metres across.
pub const MAX_LEVER_ARM_M: f64 = 10.0;

/// Smallest sensing-vector norm |Ks| a calibration may give (output/g).
pub const MIN_KS_NORM: f64 = 1e-12;

/// Smallest sample noise a calibration may give, in g (`noise_output /
/// |Ks|`): below any accelerometer's resolution, and far enough above zero
/// that the solve's weights 1/σ² stay finite.
pub const MIN_NOISE_G: f64 = 1e-15;

/// The array a command works on: its geometry, a label for messages and
/// documents (the file name, or the built-in layout and lever arm), and
/// the record of the geometry file when it came from one. Built only by
/// [`ArrayGeometry::builtin`] and [`ArrayGeometry::from_toml`], so it can
/// always solve for f0 and ω̇ ([`Geometry::require_solvable`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayGeometry {
    /// The accelerometers.
    pub geometry: Geometry,
    /// `paper layout, lever arm 0.1 m`, or the file name.
    pub label: String,
    /// The geometry file as an input of a result (role `geometry`).
    pub file: Option<InputFile>,
}

/// The label of a built-in layout with lever arm `l` (m), as documents
/// record it (`paper layout, lever arm 0.1 m`).
fn builtin_label(layout: Layout, l: f64) -> String {
    let what = match layout {
        Layout::Paper => "paper",
        Layout::Twelve => "twelve-accelerometer",
    };
    format!("{what} layout, lever arm {l} m")
}

/// A geometry file as the front end read it (the core opens no file):
/// its name as the user gave it (messages, and the document's
/// `geometry`), its path as the document's inputs record it (default: the
/// name), the SHA-256 of its bytes (default: of `toml`) and its text
/// (TOML, module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct GeometryFile {
    /// The file's name as given.
    pub name: String,
    /// Its path as recorded among a result's inputs (default: `name`).
    #[serde(default)]
    pub path: Option<String>,
    /// SHA-256 of its bytes, hex (default: of `toml`).
    #[serde(default)]
    pub sha256: Option<String>,
    /// Its text: `[[accelerometer]]` tables.
    pub toml: String,
}

/// Which array the options name: a geometry file, or a built-in layout
/// with its lever arm (default: the paper layout, 0.1 m). Not recorded as
/// given: a document records the array's label as `geometry`
/// ([`ArrayChoice::label`]).
#[derive(
    Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct ArrayChoice {
    /// The geometry file (instead of a built-in layout).
    #[serde(default, skip_serializing)]
    pub geometry: Option<GeometryFile>,
    /// Built-in layout.
    #[serde(default, skip_serializing)]
    pub layout: Layout,
    /// Lever arm L of the built-in layout (m; default [`DEFAULT_LEVER_ARM_M`]).
    #[serde(default, skip_serializing)]
    pub lever_arm_m: Option<f64>,
}

impl ArrayChoice {
    /// The array: the geometry file read ([`ArrayGeometry::from_toml`]) or
    /// the built-in layout ([`ArrayGeometry::builtin`]); a lever arm with
    /// a geometry file is refused naming `lever_arm_m`.
    pub fn load(&self) -> Result<ArrayGeometry> {
        match &self.geometry {
            Some(f) => {
                if self.lever_arm_m.is_some() {
                    return crate::options::invalid(
                        "lever_arm_m",
                        "goes with a built-in layout, not with a geometry file",
                    );
                }
                let sha = f
                    .sha256
                    .clone()
                    .unwrap_or_else(|| incal_io::sha256_hex(f.toml.as_bytes()));
                let path = f.path.as_deref().unwrap_or(&f.name);
                ArrayGeometry::from_toml(&f.name, path, f.toml.as_bytes(), sha)
            }
            None => {
                ArrayGeometry::builtin(self.layout, self.lever_arm_m.unwrap_or(DEFAULT_LEVER_ARM_M))
            }
        }
    }

    /// The array's label as documents record it (`geometry`): the file's
    /// name, or the built-in layout's label.
    pub fn label(&self) -> String {
        match &self.geometry {
            Some(f) => f.name.clone(),
            None => builtin_label(self.layout, self.lever_arm_m.unwrap_or(DEFAULT_LEVER_ARM_M)),
        }
    }
}

/// A number echoed in a message: as typed when short, else in scientific
/// notation (a huge value is not printed with hundreds of digits).
pub(crate) fn shown(x: f64) -> String {
    let s = format!("{x}");
    if s.len() > 24 {
        format!("{x:.6e}")
    } else {
        s
    }
}

impl ArrayGeometry {
    /// A built-in layout with lever arm `lever_arm_m` (m, positive and at
    /// most [`MAX_LEVER_ARM_M`]).
    pub fn builtin(layout: Layout, lever_arm_m: f64) -> Result<Self> {
        let l = lever_arm_m;
        if !(l.is_finite() && l > 0.0 && l <= MAX_LEVER_ARM_M) {
            return crate::options::invalid(
                "lever_arm_m",
                format!(
                    "must be positive and at most {MAX_LEVER_ARM_M} m, got {}",
                    shown(l)
                ),
            );
        }
        let g = match layout {
            Layout::Paper => Geometry::paper(l),
            Layout::Twelve => Geometry::twelve(l),
        };
        let g = g.or_else(|e| crate::options::invalid("lever_arm_m", e.to_string()))?;
        Self::solvable(g, builtin_label(layout, l), None)
    }

    /// The geometry file `name` (as the user named it; `path` as recorded
    /// in a result, `sha256` of its bytes): UTF-8 TOML of
    /// `[[accelerometer]]` tables (module docs). Every problem names the
    /// file, and the line for a TOML syntax error.
    pub fn from_toml(name: &str, path: &str, bytes: &[u8], sha256: String) -> Result<Self> {
        let text =
            std::str::from_utf8(bytes).map_err(|_| InputError::file(name, "not valid UTF-8"))?;
        if text.trim().is_empty() {
            return Err(
                InputError::file(name, "empty file (expected [[accelerometer]] tables)").into(),
            );
        }
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
        let parsed: GeometryFile = toml::from_str(text).map_err(|e| {
            let msg = e.message().replace('\n', " ");
            match e.span() {
                Some(s) => {
                    let line = 1 + text[..s.start.min(text.len())].matches('\n').count();
                    InputError::at(name, line, msg)
                }
                None => InputError::file(name, msg),
            }
        })?;
        let mut accs = Vec::with_capacity(parsed.accelerometer.len());
        for (k, a) in parsed.accelerometer.into_iter().enumerate() {
            let mut v3 = [Vector3::zeros(); 2];
            for (slot, (field, v)) in v3
                .iter_mut()
                .zip([("position_m", &a.position_m), ("direction", &a.direction)])
            {
                let [x, y, z] = v.as_slice() else {
                    return Err(InputError::file(
                        name,
                        format!(
                            "accelerometer[{k}].{field}: expected 3 numbers, got {}",
                            v.len()
                        ),
                    )
                    .into());
                };
                *slot = Vector3::new(*x, *y, *z);
            }
            // An accelerometer further than a lever arm can reach from the
            // unit's origin is a typo (or millimetres given as metres).
            let r = v3[0].norm();
            if r.is_nan() || r > MAX_LEVER_ARM_M {
                return Err(InputError::file(
                    name,
                    format!(
                        "accelerometer[{k}].position_m: {} m from the origin, beyond {MAX_LEVER_ARM_M} m",
                        shown(r)
                    ),
                )
                .into());
            }
            accs.push(ArrayAccelerometer {
                name: a.name,
                position_m: v3[0],
                direction: v3[1],
            });
        }
        let g = Geometry::new(accs).map_err(|e| e.in_file(name))?;
        let file = InputFile {
            role: "geometry".into(),
            path: path.into(),
            sha256,
            rows: None,
        };
        Self::solvable(g, name.to_string(), Some(file))
    }

    fn solvable(geometry: Geometry, label: String, file: Option<InputFile>) -> Result<Self> {
        geometry.require_solvable().map_err(|e| {
            Error::Unsupported(format!("{label}: geometry cannot solve the motion: {e}"))
        })?;
        Ok(Self {
            geometry,
            label,
            file,
        })
    }
}

/// The specific force (g) of a static position `+x`, `-x`, `+y`, `-y`,
/// `+z`, `-z` (the axis pointing up: +1 g along it), or `None`.
pub fn parse_position(s: &str) -> Option<Vector3<f64>> {
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

/// The position label (`+x` … `-z`) of the axis a specific force lies
/// closest to.
pub fn position_label(f: &Vector3<f64>) -> String {
    let k = f.iamax();
    format!(
        "{}{}",
        if f[k] > 0.0 { "+" } else { "-" },
        ["x", "y", "z"][k]
    )
}

/// The static samples of a calibration CSV (module docs), accelerometers
/// in geometry order.
pub fn read_static<R: Read>(
    rows: &mut incal_io::Reader<R>,
    geometry: &Geometry,
) -> Result<Vec<StaticSample>> {
    let h = rows.header();
    let pos_col = h.opt_column("position");
    if pos_col.is_some()
        && ["fx_g", "fy_g", "fz_g"]
            .iter()
            .any(|c| h.opt_column(c).is_some())
    {
        return Err(InputError::file(
            h.file(),
            "both a 'position' column and fx_g/fy_g/fz_g columns: give one description of the specific force",
        )
        .into());
    }
    let force_cols = match pos_col {
        Some(_) => None,
        None => {
            if h.opt_column("fx_g").is_none() {
                return Err(InputError::file(
                    h.file(),
                    "missing column 'position' (or columns fx_g, fy_g, fz_g)",
                )
                .into());
            }
            Some([h.column("fx_g")?, h.column("fy_g")?, h.column("fz_g")?])
        }
    };
    let acc_cols: Vec<usize> = geometry
        .accelerometers()
        .iter()
        .map(|a| h.column(&a.name))
        .collect::<incal_io::Result<_>>()?;
    let mut out = Vec::new();
    while let Some(row) = rows.next_row()? {
        let f = match (pos_col, force_cols) {
            (Some(c), _) => parse_position(&row.text(c)).ok_or_else(|| {
                row.cell_error(
                    c,
                    format!(
                        "'{}' is not one of +x, -x, +y, -y, +z, -z",
                        clip(&row.text(c))
                    ),
                )
            })?,
            (None, Some([x, y, z])) => Vector3::new(row.f64(x)?, row.f64(y)?, row.f64(z)?),
            (None, None) => return Err(row.error("no position columns").into()),
        };
        let outputs = acc_cols
            .iter()
            .map(|&c| row.f64(c))
            .collect::<incal_io::Result<_>>()?;
        out.push(StaticSample {
            specific_force_g: f,
            outputs,
        });
    }
    Ok(out)
}

/// Write static samples in the static CSV format (a `position` column,
/// then one column per accelerometer; numbers in shortest round-trip
/// form), after `#` comment lines `notes`.
pub fn write_static<W: Write>(
    samples: &[StaticSample],
    geometry: &Geometry,
    notes: &[String],
    mut out: W,
) -> std::io::Result<W> {
    write_notes(&mut out, notes)?;
    let names = geometry.names();
    let mut header = vec!["position"];
    header.extend(names.iter().map(String::as_str));
    let mut w = CsvWriter::new(out, &header)?;
    for s in samples {
        w.cell(Cell::Text(&position_label(&s.specific_force_g)))?;
        for e in &s.outputs {
            w.cell(Cell::Num(*e))?;
        }
        w.end_row()?;
    }
    w.finish()
}

/// Write a motion record `(t, outputs)` in the motion CSV format
/// (`time_s`, then one column per accelerometer), after `#` comment lines
/// `notes`; row by row, so a long record needs no memory.
pub fn write_motion<W: Write>(
    series: impl IntoIterator<Item = (f64, Vec<f64>)>,
    geometry: &Geometry,
    notes: &[String],
    mut out: W,
) -> std::io::Result<W> {
    write_notes(&mut out, notes)?;
    let names = geometry.names();
    let mut header = vec!["time_s"];
    header.extend(names.iter().map(String::as_str));
    let mut w = CsvWriter::new(out, &header)?;
    for (t, e) in series {
        w.cell(Cell::Num(t))?;
        for x in &e {
            w.cell(Cell::Num(*x))?;
        }
        w.end_row()?;
    }
    w.finish()
}

fn write_notes<W: Write>(out: &mut W, notes: &[String]) -> std::io::Result<()> {
    for n in notes {
        out.write_all(b"# ")?;
        out.write_all(n.as_bytes())?;
        out.write_all(b"\n")?;
    }
    Ok(())
}

/// The columns of a motion series: `time_s`, then every accelerometer of
/// the geometry, in that order (indexes into the row).
pub fn series_columns(header: &incal_io::Header, geometry: &Geometry) -> Result<Vec<usize>> {
    let mut cols = vec![header.column("time_s")?];
    for a in geometry.accelerometers() {
        cols.push(header.column(&a.name)?);
    }
    Ok(cols)
}

/// The calibration JSON written by `gfimu calibrate --json` (its
/// `accelerometers` object: per accelerometer `K0.value`, `K0.u`,
/// `Ks.value`, `Ks.u`, `noise_output`), read strictly for `geometry`: an
/// unknown field, an accelerometer the geometry lacks or lacks in the
/// file, or a value of the wrong type is refused at its JSON path
/// (`NAME: $.accelerometers.a.Ks.value: …`). `u` may be absent (0).
pub fn read_calibration(
    name: &str,
    bytes: &[u8],
    geometry: &Geometry,
) -> Result<Vec<CalibratedAccelerometer>> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let good = &bytes[..e.valid_up_to()];
        let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
        InputError::at(name, line, "not valid UTF-8")
    })?;
    let fail = |msg: String| -> Error { InputError::file(name, msg).into() };
    if text.trim().is_empty() {
        return Err(fail(
            "empty file (expected the JSON of 'incal gfimu calibrate --json')".into(),
        ));
    }
    let doc: Value = serde_json::from_str(text)
        .map_err(|e| InputError::at(name, e.line(), format!("not valid JSON: {e}")))?;
    let accs = doc
        .get("accelerometers")
        .and_then(Value::as_object)
        .ok_or_else(|| {
            fail("$.accelerometers: missing or not an object (expected the JSON of 'incal gfimu calibrate --json')".into())
        })?;
    let names = geometry.names();
    // An accelerometer the geometry does not have: a calibration of
    // another array.
    if let Some(extra) = accs.keys().find(|k| !names.contains(k)) {
        return Err(fail(format!(
            "$.accelerometers.{}: not an accelerometer of the geometry ({})",
            clip(extra),
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
    let mut out = Vec::with_capacity(names.len());
    for n in &names {
        let a = accs.get(n).ok_or_else(|| {
            fail(format!(
                "$.accelerometers.{n}: missing: accelerometer '{n}' of the geometry is not calibrated in this file"
            ))
        })?;
        let obj = a
            .as_object()
            .ok_or_else(|| fail(format!("$.accelerometers.{n}: not an object")))?;
        if let Some(k) = obj.keys().find(|k| !KNOWN.contains(&k.as_str())) {
            return Err(fail(format!(
                "$.accelerometers.{n}.{}: unknown field (expected {})",
                clip(k),
                KNOWN.join(", ")
            )));
        }
        let bad = |path: &str, what: &str| fail(format!("$.accelerometers.{n}.{path}: {what}"));
        let three = |v: &Value| -> Option<Vector3<f64>> {
            match v.as_array()?.as_slice() {
                [x, y, z] => Some(Vector3::new(x.as_f64()?, y.as_f64()?, z.as_f64()?)),
                _ => None,
            }
        };
        let k0 = a
            .pointer("/K0/value")
            .and_then(Value::as_f64)
            .ok_or_else(|| bad("K0.value", "missing or not a number"))?;
        let ks = a
            .pointer("/Ks/value")
            .and_then(three)
            .ok_or_else(|| bad("Ks.value", "must be an array of exactly three numbers"))?;
        let noise_output = match a.get("noise_output") {
            None | Some(Value::Null) => None,
            Some(v) => Some(
                v.as_f64()
                    .filter(|s| s.is_finite() && *s > 0.0)
                    .ok_or_else(|| bad("noise_output", "must be a positive number or null"))?,
            ),
        };
        // Values a calibration of these outputs can hold: K0 within the
        // outputs' readable range, a sensing vector of at least 1e-12
        // output/g, and a sample noise of at least 1e-15 g (finer than any
        // accelerometer resolves) so the weights 1/σ² stay finite.
        if k0.abs() > MAX_ABS_VALUE {
            return Err(bad(
                "K0.value",
                &format!(
                    "{} is beyond ±1e15, the range of the outputs it corrects",
                    shown(k0)
                ),
            ));
        }
        let ks_norm = ks.norm();
        if ks.iter().any(|v| v.abs() > MAX_ABS_VALUE) || ks_norm.is_nan() || ks_norm < MIN_KS_NORM {
            return Err(bad(
                "Ks.value",
                &format!(
                    "|Ks| = {} must be at least {MIN_KS_NORM:e} output/g with every component within ±1e15",
                    shown(ks_norm)
                ),
            ));
        }
        if let Some(s) = noise_output {
            if s < MIN_NOISE_G * ks_norm || s > MAX_ABS_VALUE {
                return Err(bad(
                    "noise_output",
                    &format!(
                        "{} is not a sample noise of this accelerometer (at least {MIN_NOISE_G:e} g = {} output, at most 1e15)",
                        shown(s),
                        shown(MIN_NOISE_G * ks_norm)
                    ),
                ));
            }
        }
        // The calibration's u (optional: a hand-made file may omit it).
        let u_k0 = match a.pointer("/K0/u") {
            None | Some(Value::Null) => 0.0,
            Some(v) => v
                .as_f64()
                .filter(|u| (0.0..=MAX_ABS_VALUE).contains(u))
                .ok_or_else(|| bad("K0.u", "must be a non-negative number within 1e15"))?,
        };
        let u_ks = match a.pointer("/Ks/u") {
            None | Some(Value::Null) => Vector3::zeros(),
            Some(v) => three(v)
                .filter(|u| u.iter().all(|x| (0.0..=MAX_ABS_VALUE).contains(x)))
                .ok_or_else(|| {
                    bad(
                        "Ks.u",
                        "must be an array of three non-negative numbers within 1e15",
                    )
                })?,
        };
        out.push(CalibratedAccelerometer {
            k0,
            ks,
            noise_output,
            u_k0,
            u_ks,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::procedures::gfimu::sim::{simulate_static, six_positions, GfimuTruth};
    use crate::procedures::gfimu::{GfimuCalibrate, GfimuCalibrateOptions};
    use crate::procedures::{reduce_source, Silent};

    /// The static CSV as written by the simulator reads back, through the
    /// one input layer, whatever its delimiter, line ends, BOM or comments.
    #[test]
    fn static_csv_round_trips_in_any_dialect() {
        let array = ArrayGeometry::builtin(Layout::Paper, 0.1).unwrap();
        let g = &array.geometry;
        let truth = GfimuTruth::typical(g, 1.0);
        let data = simulate_static(g, &truth, &six_positions(), 3, 1e-4, 1).unwrap();
        let csv =
            String::from_utf8(write_static(&data, g, &["n".into()], Vec::new()).unwrap()).unwrap();
        let dialect = format!(
            "\u{feff}# c\r\n{}",
            csv.replace(',', ";").replace('\n', "\r\n")
        );
        let o = GfimuCalibrateOptions {
            array: ArrayChoice::default(),
            noise: crate::estimation::Noise::Auto,
        };
        let a = reduce_source::<GfimuCalibrate, _>(
            "a.csv",
            csv.as_bytes(),
            &Default::default(),
            &o,
            &Silent,
        )
        .unwrap();
        let b = reduce_source::<GfimuCalibrate, _>(
            "a.csv",
            dialect.as_bytes(),
            &Default::default(),
            &o,
            &Silent,
        )
        .unwrap();
        assert_eq!(a.coefficients, b.coefficients);
        assert_eq!(a.inputs[0].rows, Some(18));
        assert_eq!(a.options["geometry"], "paper layout, lever arm 0.1 m");
    }

    #[test]
    fn geometry_and_calibration_files_are_read_strictly() {
        let toml = b"[[accelerometer]]\nname = \"a\"\nposition_m = [0.1, x]\n";
        let e = ArrayGeometry::from_toml("g.toml", "g.toml", toml, String::new()).unwrap_err();
        assert!(e.to_string().starts_with("g.toml:3: "), "{e}");
        let g = Geometry::paper(0.1).unwrap();
        let e = read_calibration("c.json", b"{\"accelerometers\": {}}", &g).unwrap_err();
        assert!(e.to_string().contains("$.accelerometers.a: missing"), "{e}");
        let e = read_calibration("c.json", b"{\n\xff", &g).unwrap_err();
        assert_eq!(e.to_string(), "c.json:2: not valid UTF-8");
        let e = ArrayGeometry::builtin(Layout::Paper, 1e300).unwrap_err();
        assert!(e.to_string().contains("lever_arm_m"), "{e}");
        assert!(e.to_string().contains("1.000000e300"), "{e}");
    }
}
