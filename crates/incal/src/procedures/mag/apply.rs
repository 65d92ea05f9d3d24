//! Applying a magnetometer calibration: `b̂ = S (m − h)` row by row
//! (`incal mag apply`), and the same calibration as flight-stack
//! parameters (`incal mag export`).
//!
//! # Flight stacks
//! Both correct in their own unit `u` with a dimensionless matrix: PX4
//! `b = S_u (m − o)` with `CAL_MAG0_{X,Y,Z}OFF` (gauss), the diagonal
//! `CAL_MAG0_{X,Y,Z}SCALE` and off-diagonals `CAL_MAG0_XODIAG` (xy),
//! `YODIAG` (xz), `ZODIAG` (yz) (PX4 `sensor_calibration::Magnetometer`);
//! ArduPilot `b = S_u (m + o)` with `COMPASS_OFS_{X,Y,Z}` (milligauss,
//! added), `COMPASS_DIA_{X,Y,Z}`, `COMPASS_ODI_X` (xy), `_Y` (xz), `_Z`
//! (yz) and `COMPASS_SCALE` 1 (ArduPilot `AP_Compass_Backend`). With the
//! raw unit worth `k_r` µT, the calibrated field's unit `k_o` µT and the
//! stack's `k_u` µT: `o = ±h k_r/k_u` and `S_u = S k_o/k_r`, so the stack
//! gives the calibrated field in its own unit, `b̂ k_o/k_u`.

use std::io::{Read, Write};

use super::fit::{sym, HARD, M3, PAIRS, SOFT, V3};
use super::{Axes, MagUnit};
use crate::document::{Procedure, ResultDocument};
use crate::error::{Error, Result};

/// A calibration read from a result document of `incal mag`.
#[derive(Debug, Clone, PartialEq)]
pub struct MagCalibration {
    /// Hard iron (raw units, the magnetometer's axes).
    pub hard_iron: V3,
    /// Soft iron (output units per raw unit).
    pub soft_iron: M3,
    /// The file's columns to the magnetometer's axes.
    pub axes: Axes,
    /// The raw unit.
    pub unit: MagUnit,
    /// µT per output unit, `None` when the output is in counts.
    pub output_ut: Option<f64>,
}

fn coefficient(doc: &ResultDocument, name: &str) -> Result<f64> {
    doc.coefficients
        .get(name)
        .map(|c| c.value)
        .ok_or_else(|| Error::Unsupported(format!("the calibration has no coefficient {name}")))
}

impl MagCalibration {
    /// The calibration of a document of `incal mag`.
    pub fn from_document(doc: &ResultDocument) -> Result<MagCalibration> {
        if doc.procedure != Procedure::Mag {
            return Err(Error::Unsupported(format!(
                "a {} result is not a magnetometer calibration (incal mag)",
                doc.procedure
            )));
        }
        let extra = doc.extra.get("mag");
        let text = |key: &str| {
            extra
                .and_then(|m| m.get(key))
                .and_then(|v| v.as_str())
                .ok_or_else(|| {
                    Error::Unsupported(format!(
                        "$.mag.{key}: missing: not a calibration of incal mag"
                    ))
                })
        };
        let unit = MagUnit::from_name(text("unit")?).ok_or_else(|| {
            Error::Unsupported("$.mag.unit: not uT, nT, gauss, mgauss or counts".into())
        })?;
        let axes = Axes::parse(text("axes")?)?;
        let output_ut = match text("output_unit")? {
            "uT" => Some(1.0),
            _ => unit.ut(),
        };
        let h = V3::new(
            coefficient(doc, HARD[0])?,
            coefficient(doc, HARD[1])?,
            coefficient(doc, HARD[2])?,
        );
        let c = SOFT
            .iter()
            .map(|n| coefficient(doc, n))
            .collect::<Result<Vec<f64>>>()?;
        Ok(MagCalibration {
            hard_iron: h,
            soft_iron: sym(&c),
            axes,
            unit,
            output_ut,
        })
    }

    /// The calibrated field of a row of the file's columns.
    pub fn apply(&self, raw: [f64; 3]) -> V3 {
        self.soft_iron * (V3::from(self.axes.map(raw)) - self.hard_iron)
    }
}

/// A flight stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FlightStack {
    /// PX4 (`CAL_MAG<n>_*`, gauss).
    Px4,
    /// ArduPilot (`COMPASS_*`, milligauss).
    Ardupilot,
}

impl FlightStack {
    /// µT per the stack's unit.
    pub fn unit_ut(self) -> f64 {
        match self {
            FlightStack::Px4 => 100.0,
            FlightStack::Ardupilot => 0.1,
        }
    }
}

/// The parameters of a calibration for a stack, compass `instance`
/// (PX4's `CAL_MAG<instance>`, ArduPilot's `COMPASS`, `COMPASS2`, …),
/// in the stack's order (module docs).
pub fn parameters(
    cal: &MagCalibration,
    stack: FlightStack,
    instance: usize,
) -> Result<Vec<(String, f64)>> {
    if cal.axes != Axes::parse("x,y,z")? {
        return Err(Error::Unsupported(
            "the calibration maps the file's axes (axes is not x,y,z): a flight stack applies its own rotation to the sensor's axes; calibrate with axes x,y,z to export".into(),
        ));
    }
    let (Some(kr), Some(ko)) = (cal.unit.ut(), cal.output_ut) else {
        return Err(Error::Unsupported(
            "the calibration is in counts: a flight stack needs the magnetometer's unit (calibrate with unit ut, nt, gauss or mgauss)".into(),
        ));
    };
    let ku = stack.unit_ut();
    let o = cal.hard_iron * (kr / ku);
    let s = cal.soft_iron * (ko / kr);
    let xyz = ["X", "Y", "Z"];
    let mut p = Vec::new();
    match stack {
        FlightStack::Px4 => {
            let pre = format!("CAL_MAG{instance}_");
            for a in 0..3 {
                p.push((format!("{pre}{}OFF", xyz[a]), o[a]));
            }
            for a in 0..3 {
                p.push((format!("{pre}{}SCALE", xyz[a]), s[(a, a)]));
            }
            for (k, (i, j)) in PAIRS[3..].iter().enumerate() {
                p.push((format!("{pre}{}ODIAG", xyz[k]), s[(*i, *j)]));
            }
        }
        FlightStack::Ardupilot => {
            let pre = match instance {
                0 => "COMPASS_".to_string(),
                n => format!("COMPASS{}_", n + 1),
            };
            for a in 0..3 {
                p.push((format!("{pre}OFS_{}", xyz[a]), -o[a]));
            }
            for a in 0..3 {
                p.push((format!("{pre}DIA_{}", xyz[a]), s[(a, a)]));
            }
            for (k, (i, j)) in PAIRS[3..].iter().enumerate() {
                p.push((format!("{pre}ODI_{}", xyz[k]), s[(*i, *j)]));
            }
            p.push((format!("{pre}SCALE"), 1.0));
        }
    }
    Ok(p)
}

/// Write the parameters as the stack's parameter file: PX4's
/// QGroundControl format (`vehicle component name value type`, tab
/// separated, type 9 for a float), ArduPilot's Mission Planner format
/// (`NAME,VALUE`); values in shortest round-trip form.
pub fn write_parameters(
    stack: FlightStack,
    params: &[(String, f64)],
    out: &mut dyn Write,
) -> Result<()> {
    let mut fmt = ryu::Buffer::new();
    match stack {
        FlightStack::Px4 => {
            writeln!(out, "# Onboard parameters for Vehicle 1 (incal mag export)")?;
            writeln!(out, "# Vehicle-Id Component-Id Name Value Type")?;
            for (n, v) in params {
                writeln!(out, "1\t1\t{n}\t{}\t9", fmt.format(*v))?;
            }
        }
        FlightStack::Ardupilot => {
            for (n, v) in params {
                writeln!(out, "{n},{}", fmt.format(*v))?;
            }
        }
    }
    Ok(())
}

/// Read a parameter file of either format back (`#` lines skipped):
/// `name value` pairs in the file's order.
pub fn read_parameters(text: &str) -> Result<Vec<(String, f64)>> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line
            .split([',', '\t', ' '])
            .filter(|c| !c.is_empty())
            .collect();
        let (name, value) = match cells.len() {
            2 => (cells[0], cells[1]),
            5 => (cells[2], cells[3]),
            _ => {
                return Err(Error::Unsupported(format!(
                    "line {}: not a parameter line (NAME,VALUE or vehicle, component, name, value, type)",
                    k + 1
                )))
            }
        };
        let v: f64 = value.parse().map_err(|_| {
            Error::Unsupported(format!(
                "line {}: {name} = '{}' is not a number",
                k + 1,
                incal_io::clip(value)
            ))
        })?;
        out.push((name.to_string(), v));
    }
    Ok(out)
}

/// The field a stack computes from a raw reading (in the stack's unit)
/// with its parameters (module docs); `None` when one is missing.
pub fn stack_field(stack: FlightStack, params: &[(String, f64)], raw_u: V3) -> Option<V3> {
    let get = |suffix: &str| {
        params
            .iter()
            .find(|(n, _)| {
                n.ends_with(suffix) && (n.starts_with("CAL_MAG") || n.starts_with("COMPASS"))
            })
            .map(|p| p.1)
    };
    let v3 = |a: &str, b: &str, c: &str| Some(V3::new(get(a)?, get(b)?, get(c)?));
    match stack {
        FlightStack::Px4 => {
            let o = v3("_XOFF", "_YOFF", "_ZOFF")?;
            let d = v3("_XSCALE", "_YSCALE", "_ZSCALE")?;
            let f = v3("_XODIAG", "_YODIAG", "_ZODIAG")?;
            Some(sym(&[d.x, d.y, d.z, f.x, f.y, f.z]) * (raw_u - o))
        }
        FlightStack::Ardupilot => {
            let o = v3("OFS_X", "OFS_Y", "OFS_Z")?;
            let d = v3("DIA_X", "DIA_Y", "DIA_Z")?;
            let f = v3("ODI_X", "ODI_Y", "ODI_Z")?;
            let scale = get("_SCALE").unwrap_or(1.0);
            Some(sym(&[d.x, d.y, d.z, f.x, f.y, f.z]) * ((raw_u + o) * scale))
        }
    }
}

/// `incal mag apply` as a [`crate::procedures::stream::Stream`]: every
/// row's `mag_x, mag_y, mag_z` calibrated, `time_s` and every other
/// column copied as read.
#[derive(Debug, Clone, Copy)]
pub struct Apply;

impl crate::procedures::stream::Stream for Apply {
    type Model = MagCalibration;

    fn stream(
        cal: MagCalibration,
        name: &str,
        input: Box<dyn Read + Send + '_>,
        read: &incal_io::ReadOptions,
        out: &mut dyn Write,
    ) -> Result<crate::procedures::stream::Streamed> {
        let mut rows = incal_io::Reader::new(name, input, read)?;
        let h = rows.header();
        let cm = super::input::MAG
            .iter()
            .map(|c| h.column(c))
            .collect::<std::result::Result<Vec<usize>, _>>()?;
        let names: Vec<String> = h.names().to_vec();
        let header: Vec<String> = names
            .iter()
            .map(|n| incal_io::csv_text(n).into_owned())
            .collect();
        writeln!(out, "{}", header.join(","))?;
        let mut fmt = ryu::Buffer::new();
        let mut line = String::new();
        let mut written = 0u64;
        while let Some(row) = rows.next_row()? {
            let b = cal.apply([row.f64(cm[0])?, row.f64(cm[1])?, row.f64(cm[2])?]);
            line.clear();
            for k in 0..names.len() {
                if k > 0 {
                    line.push(',');
                }
                match cm.iter().position(|c| *c == k) {
                    Some(a) => line.push_str(fmt.format(b[a])),
                    None => line.push_str(&incal_io::csv_text(&row.text(k))),
                }
            }
            line.push('\n');
            out.write_all(line.as_bytes())?;
            written += 1;
        }
        rows.finish()?;
        out.flush()?;
        Ok(crate::procedures::stream::Streamed {
            rows: written,
            notes: vec![format!(
                "calibrated field in {}",
                match cal.output_ut {
                    Some(1.0) => "uT".to_string(),
                    _ => cal.unit.as_str().to_string(),
                }
            )],
            warnings: Vec::new(),
        })
    }
}
