//! Applying an IMU calibration to a raw series, row by row: the typed
//! calibration read from a result document of any of the three IMU
//! procedures, the columns of a raw recording and the calibration of one
//! row.
//!
//! # Model
//! Every calibration is brought to one form (the inverse of the sensor
//! model, applied to raw outputs):
//! `f = M_a (a − b_a)`, `ω = M_g (g − b_g − G f)`, with `a`, `g` the raw
//! accelerometer and gyro outputs, `f` the specific force and `ω` the
//! angular rate.
//!
//! * `imu-ferraris` (imucal's definitions, Ferraris, Grimaldi & Parvis,
//!   "Procedure for effortless in-field calibration of three-axial rate
//!   gyro and accelerometers", Sensors and Materials, 1995):
//!   `M_a = (K_a R_a)⁻¹`, `M_g = (K_g R_g)⁻¹`, `G = K_ga`; `f` in m/s²,
//!   `ω` in deg/s.
//! * `imu-autocal` (imu_tk's convention, Tedaldi, Pretto & Menegatti, "A
//!   robust and easy to implement method for IMU calibration without
//!   external equipments", ICRA 2014): `M = T K`, `G = 0`; `f` in the unit
//!   of the gravity given (m/s²), `ω` in rad/s.
//! * `imu-multipos`: `M_a = A_acc⁻¹`, `M_g = A_gyr⁻¹`, `G = G_gyr`; `f` in
//!   m/s², `ω` in deg/s. A calibration without a gyro scale (no rotations
//!   or Earth rate in its session) calibrates the accelerometers only.

use crate::document::{Procedure, ResultDocument};
use crate::error::{Error, Result};

use super::{M3, V3};

/// The gyro part of a calibration: `ω = m (g − b − g_sens f)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroCalibration {
    /// Inverse scale-and-misalignment matrix `M_g` (ω unit per output).
    pub m: M3,
    /// Bias `b_g` (output).
    pub b: V3,
    /// g-sensitivity `G` (output per unit of f).
    pub g_sensitivity: M3,
}

/// A calibration ready to apply (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuCalibration {
    /// Inverse scale-and-misalignment matrix `M_a` (f unit per output).
    pub m_a: M3,
    /// Accelerometer bias `b_a` (output).
    pub b_a: V3,
    /// The gyro part, when the calibration has one.
    pub gyro: Option<GyroCalibration>,
    /// Unit of the calibrated gyro columns in their names: `deg_s` or `rad_s`.
    pub gyr_unit: &'static str,
}

fn bad(path: &str, what: &str) -> Error {
    Error::Unsupported(format!("{path}: {what}"))
}

fn json_m3(v: Option<&serde_json::Value>, path: &str) -> Result<M3> {
    let v = v.ok_or_else(|| bad(path, "missing"))?;
    let rows = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| bad(path, "expected a list of 3 rows"))?;
    let mut m = M3::zeros();
    for (i, r) in rows.iter().enumerate() {
        let r = r
            .as_array()
            .filter(|r| r.len() == 3)
            .ok_or_else(|| bad(&format!("{path}[{i}]"), "expected 3 numbers"))?;
        for (j, x) in r.iter().enumerate() {
            m[(i, j)] = x
                .as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(&format!("{path}[{i}][{j}]"), "not a finite number"))?;
        }
    }
    Ok(m)
}

fn json_v3(v: Option<&serde_json::Value>, path: &str) -> Result<V3> {
    let v = v.ok_or_else(|| bad(path, "missing"))?;
    let r = v
        .as_array()
        .filter(|r| r.len() == 3)
        .ok_or_else(|| bad(path, "expected 3 numbers"))?;
    let mut out = V3::zeros();
    for (j, x) in r.iter().enumerate() {
        out[j] = x
            .as_f64()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(&format!("{path}[{j}]"), "not a finite number"))?;
    }
    Ok(out)
}

fn inverse(m: M3, what: &str) -> Result<M3> {
    m.try_inverse()
        .filter(|i| i.iter().all(|v| v.is_finite()))
        .ok_or_else(|| Error::Unsupported(format!("{what} is singular")))
}

impl ImuCalibration {
    /// The calibration of a result document of `imu ferraris`,
    /// `imu multipos` or `imu autocal` (its top-level matrices, see the
    /// module docs). A missing or malformed matrix is refused naming its
    /// JSON path (`$.K_a`, `$.acc.b[2]`), a singular one naming the
    /// matrix, a document of another procedure naming `$.procedure`.
    pub fn from_document(doc: &ResultDocument) -> Result<ImuCalibration> {
        let x = &doc.extra;
        match doc.procedure {
            Procedure::ImuFerraris => {
                let k_a = json_m3(x.get("K_a"), "$.K_a")?;
                let r_a = json_m3(x.get("R_a"), "$.R_a")?;
                let k_g = json_m3(x.get("K_g"), "$.K_g")?;
                let r_g = json_m3(x.get("R_g"), "$.R_g")?;
                Ok(ImuCalibration {
                    m_a: inverse(k_a * r_a, "K_a R_a")?,
                    b_a: json_v3(x.get("b_a"), "$.b_a")?,
                    gyro: Some(GyroCalibration {
                        m: inverse(k_g * r_g, "K_g R_g")?,
                        b: json_v3(x.get("b_g"), "$.b_g")?,
                        g_sensitivity: json_m3(x.get("K_ga"), "$.K_ga")?,
                    }),
                    gyr_unit: "deg_s",
                })
            }
            Procedure::ImuAutocal => {
                let acc = x.get("acc").ok_or_else(|| bad("$.acc", "missing"))?;
                let tk = |v: &serde_json::Value, p: &str| -> Result<(M3, V3)> {
                    let t = json_m3(Some(&v["T"]), &format!("{p}.T"))?;
                    let k = json_m3(Some(&v["K"]), &format!("{p}.K"))?;
                    Ok((t * k, json_v3(Some(&v["b"]), &format!("{p}.b"))?))
                };
                let (m_a, b_a) = tk(acc, "$.acc")?;
                let gyro = match x.get("gyr") {
                    Some(g) => {
                        let (m, b) = tk(g, "$.gyr")?;
                        Some(GyroCalibration {
                            m,
                            b,
                            g_sensitivity: M3::zeros(),
                        })
                    }
                    None => None,
                };
                Ok(ImuCalibration {
                    m_a,
                    b_a,
                    gyro,
                    gyr_unit: "rad_s",
                })
            }
            Procedure::ImuMultipos => {
                let acc = x.get("acc").ok_or_else(|| bad("$.acc", "missing"))?;
                let m_a = inverse(json_m3(Some(&acc["A"]), "$.acc.A")?, "$.acc.A")?;
                let b_a = json_v3(Some(&acc["b"]), "$.acc.b")?;
                let gyro = match x.get("gyr") {
                    Some(g) if g.get("A").is_some() => Some(GyroCalibration {
                        m: inverse(json_m3(Some(&g["A"]), "$.gyr.A")?, "$.gyr.A")?,
                        b: json_v3(Some(&g["b"]), "$.gyr.b")?,
                        g_sensitivity: json_m3(Some(&g["G"]), "$.gyr.G")?,
                    }),
                    _ => None,
                };
                Ok(ImuCalibration {
                    m_a,
                    b_a,
                    gyro,
                    gyr_unit: "deg_s",
                })
            }
            other => Err(bad(
                "$.procedure",
                &format!(
                    "'{other}' is not an IMU calibration (imu-ferraris, imu-multipos or imu-autocal)"
                ),
            )),
        }
    }

    /// Calibrated specific force of a raw accelerometer sample:
    /// `f = M_a (a − b_a)`.
    pub fn acc(&self, raw: &V3) -> V3 {
        self.m_a * (raw - self.b_a)
    }

    /// Calibrated angular rate of a raw gyro sample, `f` the calibrated
    /// specific force of the same instant: `ω = M_g (g − b_g − G f)`;
    /// `None` when the calibration has no gyro part.
    pub fn gyr(&self, raw: &V3, f: &V3) -> Option<V3> {
        self.gyro
            .as_ref()
            .map(|g| g.m * (raw - g.b - g.g_sensitivity * f))
    }

    /// The columns of a raw recording this calibration reads: `acc_x`,
    /// `acc_y`, `acc_z` (required), `gyr_x`, `gyr_y`, `gyr_z` (read when
    /// the file has `gyr_x` and the calibration a gyro part; then all three
    /// are required), `time_s` (optional, copied).
    pub fn columns(&self, h: &incal_io::Header) -> Result<ApplyColumns> {
        let acc = [h.column("acc_x")?, h.column("acc_y")?, h.column("acc_z")?];
        let gyr = match (h.opt_column("gyr_x"), self.gyro.is_some()) {
            (Some(_), true) => Some([h.column("gyr_x")?, h.column("gyr_y")?, h.column("gyr_z")?]),
            _ => None,
        };
        let time = h.opt_column("time_s");
        // Every other column (labels, temperature, a trigger, raw gyro
        // columns a gyro-less calibration does not use) is copied as read.
        let used: Vec<usize> = time
            .into_iter()
            .chain(acc)
            .chain(gyr.into_iter().flatten())
            .collect();
        let extra: Vec<usize> = (0..h.width()).filter(|k| !used.contains(k)).collect();
        let extra_names = extra.iter().map(|&k| h.names()[k].clone()).collect();
        Ok(ApplyColumns {
            time,
            acc,
            gyr,
            gyr_unit: self.gyr_unit,
            extra,
            extra_names,
        })
    }

    /// One raw row calibrated (the columns from [`ImuCalibration::columns`]).
    pub fn row(&self, cols: &ApplyColumns, row: &incal_io::Row<'_>) -> Result<CalibratedRow> {
        let time = match cols.time {
            Some(c) => Some(row.f64(c)?),
            None => None,
        };
        let [x, y, z] = cols.acc;
        let f = self.acc(&V3::new(row.f64(x)?, row.f64(y)?, row.f64(z)?));
        let gyr = match cols.gyr {
            Some([x, y, z]) => self.gyr(&V3::new(row.f64(x)?, row.f64(y)?, row.f64(z)?), &f),
            None => None,
        };
        let extra = cols
            .extra
            .iter()
            .map(|&k| row.text(k).to_string())
            .collect();
        Ok(CalibratedRow {
            time,
            acc: f,
            gyr,
            extra,
        })
    }
}

/// Where a raw recording holds what [`ImuCalibration`] reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ApplyColumns {
    /// `time_s`, when present.
    pub time: Option<usize>,
    /// `acc_x`, `acc_y`, `acc_z`.
    pub acc: [usize; 3],
    /// `gyr_x`, `gyr_y`, `gyr_z`, when read.
    pub gyr: Option<[usize; 3]>,
    gyr_unit: &'static str,
    /// Every other column, copied to the output after the calibrated ones.
    pub extra: Vec<usize>,
    /// Their names.
    pub extra_names: Vec<String>,
}

impl ApplyColumns {
    /// The header of the calibrated series: `time_s` (when copied),
    /// `acc_x_m_s2, acc_y_m_s2, acc_z_m_s2`, then `gyr_x_<unit>, …` when
    /// the gyro is calibrated (`deg_s` or `rad_s`).
    pub fn output_header(&self) -> Vec<String> {
        let mut h = Vec::with_capacity(7);
        if self.time.is_some() {
            h.push("time_s".to_string());
        }
        h.extend(["acc_x_m_s2", "acc_y_m_s2", "acc_z_m_s2"].map(String::from));
        if self.gyr.is_some() {
            let u = self.gyr_unit;
            h.extend(["x", "y", "z"].map(|a| format!("gyr_{a}_{u}")));
        }
        h.extend(self.extra_names.iter().cloned());
        h
    }
}

/// One calibrated row.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibratedRow {
    /// `time_s` as read, when the recording has it.
    pub time: Option<f64>,
    /// Specific force (m/s², or the unit of the autocalibration's gravity).
    pub acc: V3,
    /// Angular rate (deg/s, rad/s for an autocalibration), when calibrated.
    pub gyr: Option<V3>,
    /// The other columns of the row, as read.
    pub extra: Vec<String>,
}

/// A calibration in the JSON form imucal's `load_calibration_info` reads
/// (a `FerrarisCalibrationInfo`, format 2.0.0; Küderle et al., "imucal - A
/// Python library to calibrate 6 DOF IMUs", JOSS 2022): imucal applies
/// `a = R_a⁻¹ K_a⁻¹ (raw − b_a)` and
/// `ω = R_g⁻¹ K_g⁻¹ (raw − K_ga a − b_g)`, `a` in m/s², `ω` in deg/s.
///
/// An `imu ferraris` document is imucal's own definition: its matrices are
/// copied verbatim. For `imu multipos` and `imu autocal`, `K R = M⁻¹`
/// (the inverse of the applied matrix, `M_g` in deg/s per output) is split
/// into `K`, the diagonal of its row norms, and `R`, its rows normalised,
/// as imucal's Ferraris method defines them; `K_ga` is the g-sensitivity
/// (zero for autocal). A calibration without a gyro part is refused:
/// imucal's format has no accelerometer-only form.
pub fn to_imucal(doc: &ResultDocument) -> Result<serde_json::Value> {
    use serde_json::json;
    let rows = |m: &M3| -> Vec<Vec<f64>> {
        (0..3)
            .map(|i| (0..3).map(|j| m[(i, j)]).collect())
            .collect()
    };
    let v3 = |v: &V3| -> Vec<f64> { v.iter().copied().collect() };
    let cal = ImuCalibration::from_document(doc)?;
    let Some(g) = cal.gyro else {
        return Err(bad(
            "$.gyr",
            "this calibration has no gyro part: imucal's format needs one",
        ));
    };
    let split = |m: &M3, what: &str| -> Result<(M3, M3)> {
        let a = inverse(*m, what)?;
        let mut k = M3::zeros();
        let mut r = a;
        for i in 0..3 {
            let n = a.row(i).norm();
            k[(i, i)] = n;
            r.row_mut(i).scale_mut(1.0 / n);
        }
        Ok((k, r))
    };
    let x = &doc.extra;
    let (k_a, r_a, k_g, r_g) = if doc.procedure == Procedure::ImuFerraris {
        (
            json_m3(x.get("K_a"), "$.K_a")?,
            json_m3(x.get("R_a"), "$.R_a")?,
            json_m3(x.get("K_g"), "$.K_g")?,
            json_m3(x.get("R_g"), "$.R_g")?,
        )
    } else {
        let to_deg = if cal.gyr_unit == "rad_s" {
            std::f64::consts::PI / 180.0
        } else {
            1.0
        };
        let (k_a, r_a) = split(&cal.m_a, "M_a")?;
        // M_g in deg/s per output: ω_deg = M_g,rad · 180/π · (…).
        let (k_g, r_g) = split(&(g.m / to_deg), "M_g")?;
        (k_a, r_a, k_g, r_g)
    };
    let comment = format!(
        "exported by incal {} from an {} result",
        doc.incal_version, doc.procedure
    );
    Ok(json!({
        "acc_unit": "m/s^2",
        "gyr_unit": "deg/s",
        "from_acc_unit": "a.u.",
        "from_gyr_unit": "a.u.",
        "comment": comment,
        "K_a": rows(&k_a),
        "R_a": rows(&r_a),
        "b_a": v3(&cal.b_a),
        "K_g": rows(&k_g),
        "R_g": rows(&r_g),
        "K_ga": rows(&g.g_sensitivity),
        "b_g": v3(&g.b),
        "cal_type": "Ferraris",
        "_format_version": "2.0.0",
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_are_read_with_their_paths() {
        let v = serde_json::json!([[1, 0, 0], [0, 2, 0], [0, 0, 4]]);
        let m = json_m3(Some(&v), "$.A").unwrap();
        assert_eq!(m[(2, 2)], 4.0);
        let e = json_m3(
            Some(&serde_json::json!([[1, 0, 0], [0, 2], [0, 0, 1]])),
            "$.A",
        )
        .unwrap_err();
        assert!(e.to_string().contains("$.A[1]: expected 3 numbers"), "{e}");
        let e = json_v3(None, "$.b_g").unwrap_err();
        assert_eq!(e.to_string(), "$.b_g: missing");
        let e = inverse(M3::zeros(), "K_a R_a").unwrap_err();
        assert_eq!(e.to_string(), "K_a R_a is singular");
    }
}

/// `imu apply` as a [`crate::procedures::stream::Stream`]: a calibration
/// applied to a raw series row by row.
#[derive(Debug, Clone, Copy)]
pub struct Apply;

/// The model of [`Apply`]: the calibration and the time-stamp policy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApplyModel {
    /// The calibration ([`ImuCalibration::from_document`]).
    pub calibration: ImuCalibration,
    /// Hold the rows and write them in time order (`time_s` sorted, the
    /// rows moved reported) instead of refusing a decreasing stamp.
    pub sort_time: bool,
}

/// One calibrated row as CSV text: numbers in their shortest round-trip
/// form, other cells quoted as needed.
fn put_row(r: &CalibratedRow, line: &mut String, fmt: &mut ryu::Buffer) {
    line.clear();
    if let Some(t) = r.time {
        line.push_str(fmt.format(t));
        line.push(',');
    }
    for (k, x) in r.acc.iter().enumerate() {
        if k > 0 {
            line.push(',');
        }
        line.push_str(fmt.format(*x));
    }
    if let Some(g) = r.gyr {
        for x in g.iter() {
            line.push(',');
            line.push_str(fmt.format(*x));
        }
    }
    for cell in &r.extra {
        line.push(',');
        line.push_str(&incal_io::csv_text(cell));
    }
    line.push('\n');
}

impl crate::procedures::stream::Stream for Apply {
    type Model = ApplyModel;

    /// The time-stamp policy of a streaming reduction: stamps copied as
    /// read, a decreasing one refused at its line (or, with `sort_time`,
    /// the rows held and put in order), repeats and gaps reported.
    fn stream(
        model: ApplyModel,
        name: &str,
        input: Box<dyn std::io::Read + Send + '_>,
        read: &incal_io::ReadOptions,
        out: &mut dyn std::io::Write,
    ) -> Result<crate::procedures::stream::Streamed> {
        use crate::timebase::{permute, sorted_warning, time_order, StampStream};
        let cal = &model.calibration;
        let mut rows = incal_io::Reader::new(name, input, read)?;
        let cols = cal.columns(rows.header())?;
        let mut line = cols
            .output_header()
            .iter()
            .map(|h| incal_io::csv_text(h))
            .collect::<Vec<_>>()
            .join(",");
        line.push('\n');
        out.write_all(line.as_bytes())?;
        let mut fmt = ryu::Buffer::new();
        let mut stamps = StampStream::new(f64::INFINITY);
        let stamp_error = |(l, e): (usize, crate::timebase::TimeError)| {
            Error::from(incal_io::InputError::cell(name, l, "time_s", e.to_string()))
        };
        let mut held = Vec::new();
        let mut written = 0u64;
        while let Some(row) = rows.next_row()? {
            let r = cal.row(&cols, &row)?;
            if model.sort_time {
                held.push(r);
                continue;
            }
            if let Some(t) = r.time {
                stamps.push(t, row.line()).map_err(stamp_error)?;
            }
            put_row(&r, &mut line, &mut fmt);
            out.write_all(line.as_bytes())?;
            written += 1;
        }
        rows.finish()?;
        let mut warnings = Vec::new();
        if cols.time.is_some() && model.sort_time {
            let mut times: Vec<f64> = held.iter().map(|r| r.time.unwrap_or(0.0)).collect();
            if let Some((order, moved)) = time_order(&mut times) {
                permute(&mut held, &order);
                warnings.push(sorted_warning(moved, held.len()));
            }
            for (k, t) in times.iter().enumerate() {
                stamps.push(*t, k + 1).map_err(stamp_error)?;
            }
        }
        for r in &held {
            put_row(r, &mut line, &mut fmt);
            out.write_all(line.as_bytes())?;
            written += 1;
        }
        stamps.finish().map_err(stamp_error)?;
        warnings.extend(stamps.warnings());
        out.flush()?;
        Ok(crate::procedures::stream::Streamed {
            rows: written,
            notes: Vec::new(),
            warnings,
        })
    }
}
