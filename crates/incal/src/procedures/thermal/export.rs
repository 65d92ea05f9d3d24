//! A thermal model in the parameter forms flight stacks read
//! (`incal export px4|ardupilot MODEL.json`).
//!
//! Both stacks correct a three-axis sensor as `v ← v − offset(T)` with `T`
//! clamped to the calibrated range, in SI units (m/s², rad/s):
//!
//! * **PX4** (`TC_A0_*` accelerometer, `TC_G0_*` gyro, module
//!   `sensors/temperature_compensation`):
//!   `offset = X0 + X1 dT + X2 dT² + X3 dT³`, `dT = T − TREF`, `T` clamped
//!   to [`TMIN`, `TMAX`]; parameters `TC_x0_ID` (the sensor's device id),
//!   `TC_x0_TMIN`, `TC_x0_TMAX`, `TC_x0_TREF` (°C) and `TC_x0_Xk_i`
//!   (k = 0…3, axis i = 0, 1, 2 for X, Y, Z), plus `TC_A_ENABLE` /
//!   `TC_G_ENABLE` = 1. Written as a QGroundControl parameter file.
//! * **ArduPilot** (`INS_TCALn_*`, `AP_InertialSensor_tempcal`): the
//!   polynomial has no constant term and is in `(T − 35 °C)`, its
//!   coefficients scaled by 10⁶: `offset = 10⁻⁶ (ACC1 dT + ACC2 dT² + ACC3
//!   dT³)` with `dT = T − 35`; the correction applied is
//!   `offset(T) − offset(T_cal)` (`T_cal` the temperature of the regular
//!   calibration, INS_ACCn_CALTEMP). Parameters `INS_TCALn_ENABLE`,
//!   `_TMIN`, `_TMAX`, `_ACC1_X`…`_ACC3_Z` or `_GYR1_X`…`_GYR3_Z`, written
//!   as `NAME,VALUE` lines (a Mission Planner / MAVProxy parameter file).
//!
//! incal's polynomial in `(T − T_ref)` is re-expanded about the stack's
//! reference ([`super::shift_reference`]). Its constant term `c_0` is the
//! channel's value at `T_ref` (for a static ramp it includes gravity's
//! projection): PX4's `X0` is written as 0 unless `with_offset`, so both
//! exports, like `incal thermal apply`, correct the change from `T_ref`
//! and leave the offset to the sensor's regular calibration. Hysteresis
//! and `dT/dt` terms have no parameter in either stack and are left out.

use std::collections::BTreeMap;

use super::{poly, shift_reference, Model, ThermalEntry};
use crate::error::{Error, Result};

/// ArduPilot's fixed reference temperature, °C.
pub const ARDUPILOT_T_REF_C: f64 = 35.0;
/// ArduPilot's coefficient scale.
pub const ARDUPILOT_SCALE: f64 = 1e6;
/// Standard gravity for g → m/s², m/s².
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Which sensor the three channels are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sensor {
    /// Accelerometer (m/s² in the stacks).
    Accel,
    /// Gyro (rad/s in the stacks).
    Gyro,
}

/// Factor from a channel unit to the stack's SI unit, and the sensor it
/// implies.
pub fn si_factor(unit: &str) -> Option<(f64, Sensor)> {
    let d = std::f64::consts::PI / 180.0;
    Some(match unit {
        "g" => (STANDARD_GRAVITY, Sensor::Accel),
        "mg" => (STANDARD_GRAVITY * 1e-3, Sensor::Accel),
        "m/s^2" | "m/s2" => (1.0, Sensor::Accel),
        "deg/s" => (d, Sensor::Gyro),
        "rad/s" => (1.0, Sensor::Gyro),
        "deg/h" => (d / 3600.0, Sensor::Gyro),
        _ => return None,
    })
}

/// The three axes of a model: `axes` when given, else the entries whose
/// names end in x, y and z (one each), else the only three entries in
/// order.
pub fn axes<'a>(
    model: &'a Model,
    axes: Option<&[String]>,
) -> Result<[(&'a str, &'a ThermalEntry, &'a [f64]); 3]> {
    let pick = |name: &str| -> Result<(&'a str, &'a ThermalEntry, &'a [f64])> {
        model
            .entries
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(n, e, c)| (n.as_str(), e, c.as_slice()))
            .ok_or_else(|| Error::InvalidOption {
                key: "axes".into(),
                message: format!("the model has no channel {name} (it has {})", model.names()),
            })
    };
    if let Some(a) = axes {
        if a.len() != 3 {
            return Err(Error::InvalidOption {
                key: "axes".into(),
                message: format!("three channel names X,Y,Z, got {}", a.len()),
            });
        }
        if a[0] == a[1] || a[0] == a[2] || a[1] == a[2] {
            return Err(Error::InvalidOption {
                key: "axes".into(),
                message: format!(
                    "three different channels X,Y,Z, got {}",
                    a.iter()
                        .map(|s| incal_io::clip(s))
                        .collect::<Vec<_>>()
                        .join(",")
                ),
            });
        }
        return Ok([pick(&a[0])?, pick(&a[1])?, pick(&a[2])?]);
    }
    let by_suffix = |s: char| {
        let m: Vec<&str> = model
            .entries
            .iter()
            .map(|(n, _, _)| n.as_str())
            .filter(|n| n.to_ascii_lowercase().ends_with(s))
            .collect();
        (m.len() == 1).then(|| m[0])
    };
    if let (Some(x), Some(y), Some(z)) = (by_suffix('x'), by_suffix('y'), by_suffix('z')) {
        return Ok([pick(x)?, pick(y)?, pick(z)?]);
    }
    if model.entries.len() == 3 {
        let e = &model.entries;
        return Ok([
            (e[0].0.as_str(), &e[0].1, e[0].2.as_slice()),
            (e[1].0.as_str(), &e[1].1, e[1].2.as_slice()),
            (e[2].0.as_str(), &e[2].1, e[2].2.as_slice()),
        ]);
    }
    Err(Error::Unsupported(format!(
        "which channels are X, Y and Z? give --axes X,Y,Z (the model has {})",
        model.names()
    )))
}

/// The three axes in SI units: sensor, per axis the name, the polynomial
/// `c` (SI per °C^k) and `T_ref`, and the common valid range.
#[allow(clippy::type_complexity)]
fn si_axes(
    model: &Model,
    axes_given: Option<&[String]>,
) -> Result<(Sensor, Vec<(String, Vec<f64>, f64)>, f64, f64)> {
    let a = axes(model, axes_given)?;
    let mut sensor = None;
    let mut out = Vec::new();
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (name, e, c) in a {
        let (k, s) = si_factor(&e.unit).ok_or_else(|| {
            Error::Unsupported(format!(
                "{name}: unit {} has no flight-stack unit (give the ramp --quantity gyro or accel, units deg/s, rad/s, deg/h, g, mg or m/s^2)",
                e.unit
            ))
        })?;
        if sensor.is_some_and(|t| t != s) {
            return Err(Error::Unsupported(format!(
                "{name}: the three axes mix gyro and accelerometer units"
            )));
        }
        sensor = Some(s);
        out.push((
            name.to_string(),
            c.iter().map(|v| v * k).collect(),
            e.t_ref_c,
        ));
        lo = lo.max(e.t_min_c);
        hi = hi.min(e.t_max_c);
    }
    if lo > hi {
        return Err(Error::Unsupported(
            "the three axes have no common valid temperature range".into(),
        ));
    }
    Ok((sensor.unwrap_or(Sensor::Accel), out, lo, hi))
}

/// PX4 parameters: name → value, in the order written.
pub fn px4(
    model: &Model,
    axes_given: Option<&[String]>,
    device_id: u32,
    with_offset: bool,
) -> Result<Vec<(String, f64, u8)>> {
    let (sensor, ax, lo, hi) = si_axes(model, axes_given)?;
    let t_ref = ax[0].2;
    let p = match sensor {
        Sensor::Accel => "TC_A",
        Sensor::Gyro => "TC_G",
    };
    let mut out = vec![
        (format!("{p}_ENABLE"), 1.0, 6),
        (format!("{p}0_ID"), device_id as f64, 6),
        (format!("{p}0_TMIN"), lo, 9),
        (format!("{p}0_TMAX"), hi, 9),
        (format!("{p}0_TREF"), t_ref, 9),
    ];
    let shifted: Vec<Vec<f64>> = ax
        .iter()
        .map(|(_, c, tr)| shift_reference(c, *tr, t_ref))
        .collect();
    for k in 0..=3 {
        for (i, c) in shifted.iter().enumerate() {
            let v = if k == 0 && !with_offset {
                0.0
            } else {
                c.get(k).copied().unwrap_or(0.0)
            };
            out.push((format!("{p}0_X{k}_{i}"), v, 9));
        }
    }
    float32_all(out.iter().map(|(n, v, _)| (n.as_str(), *v)))?;
    Ok(out)
}

/// A flight stack's parameter `name` holds `value` as a float32: finite,
/// at most `f32::MAX` in magnitude and, when not 0, at least the smallest
/// normal float32 (1.2e-38; below it the parameter would read 0 or lose
/// its digits). Else [`Error::Unsupported`] naming the parameter.
pub fn float32_parameter(name: &str, value: f64) -> Result<()> {
    let a = value.abs();
    if value.is_finite()
        && a <= f64::from(f32::MAX)
        && (a == 0.0 || a >= f64::from(f32::MIN_POSITIVE))
    {
        return Ok(());
    }
    Err(Error::Unsupported(format!(
        "{name}: {value:e} does not fit the flight stack's float32 parameter (1.2e-38 to 3.4e38 in magnitude, or 0)"
    )))
}

/// Every parameter of `params` checked by [`float32_parameter`].
fn float32_all<'a>(params: impl IntoIterator<Item = (&'a str, f64)>) -> Result<()> {
    params
        .into_iter()
        .try_for_each(|(n, v)| float32_parameter(n, v))
}

/// The PX4 parameters as a QGroundControl parameter file.
pub fn px4_text(params: &[(String, f64, u8)], source: &str) -> String {
    let mut s =
        String::from("# PX4 thermal compensation parameters, written by incal export px4\n");
    s.push_str(&format!(
        "# from {source}: offset = X0 + X1 dT + X2 dT^2 + X3 dT^3, dT = T - TREF (degC), SI units; X0 is the offset at TREF\n"
    ));
    s.push_str("# Vehicle-Id\tComponent-Id\tName\tValue\tType\n");
    for (n, v, t) in params {
        let v = if *t == 6 {
            format!("{}", v.round() as i64)
        } else {
            format!("{v}")
        };
        s.push_str(&format!("1\t1\t{n}\t{v}\t{t}\n"));
    }
    s
}

/// ArduPilot parameters for IMU `imu` (1-based): name → value.
pub fn ardupilot(
    model: &Model,
    axes_given: Option<&[String]>,
    imu: u8,
) -> Result<Vec<(String, f64)>> {
    let (sensor, ax, lo, hi) = si_axes(model, axes_given)?;
    let kind = match sensor {
        Sensor::Accel => "ACC",
        Sensor::Gyro => "GYR",
    };
    let p = format!("INS_TCAL{imu}");
    let mut out = vec![
        (format!("{p}_ENABLE"), 1.0),
        (format!("{p}_TMIN"), lo),
        (format!("{p}_TMAX"), hi),
    ];
    let shifted: Vec<Vec<f64>> = ax
        .iter()
        .map(|(_, c, tr)| shift_reference(c, *tr, ARDUPILOT_T_REF_C))
        .collect();
    for k in 1..=3 {
        for (axis, c) in ["X", "Y", "Z"].iter().zip(&shifted) {
            let v = c.get(k).copied().unwrap_or(0.0) * ARDUPILOT_SCALE;
            out.push((format!("{p}_{kind}{k}_{axis}"), v));
        }
    }
    float32_all(out.iter().map(|(n, v)| (n.as_str(), *v)))?;
    Ok(out)
}

/// The ArduPilot parameters as `NAME,VALUE` lines.
pub fn ardupilot_text(params: &[(String, f64)], source: &str) -> String {
    let mut s = String::from(
        "# ArduPilot IMU temperature calibration, written by incal export ardupilot\n",
    );
    s.push_str(&format!(
        "# from {source}: offset = 1e-6 (C1 dT + C2 dT^2 + C3 dT^3), dT = T - 35 degC, SI units\n"
    ));
    for (n, v) in params {
        if n.ends_with("_ENABLE") {
            s.push_str(&format!("{n},{}\n", v.round() as i64));
        } else {
            s.push_str(&format!("{n},{v}\n"));
        }
    }
    s
}

/// Read a parameter file of either form back: name → value (`#` lines
/// and blank lines skipped; tab-separated QGC rows or `NAME,VALUE`).
pub fn read_params(text: &str) -> std::result::Result<BTreeMap<String, f64>, String> {
    let mut m = BTreeMap::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let (name, value) = if l.contains('\t') {
            let f: Vec<&str> = l.split('\t').collect();
            if f.len() != 5 {
                return Err(format!(
                    "line {}: {} fields, a QGC row has 5",
                    i + 1,
                    f.len()
                ));
            }
            (f[2], f[3])
        } else {
            l.split_once(',')
                .ok_or_else(|| format!("line {}: not NAME,VALUE", i + 1))?
        };
        let v: f64 = value
            .trim()
            .parse()
            .map_err(|_| format!("line {}: value '{value}' is not a number", i + 1))?;
        if m.insert(name.trim().to_string(), v).is_some() {
            return Err(format!("line {}: {name} given twice", i + 1));
        }
    }
    Ok(m)
}

/// The correction PX4 applies at `t_c` on axis `i` from its parameters
/// (`prefix` = `TC_A0` or `TC_G0`).
pub fn px4_offset(p: &BTreeMap<String, f64>, prefix: &str, i: usize, t_c: f64) -> Option<f64> {
    let t = t_c.clamp(
        *p.get(&format!("{prefix}_TMIN"))?,
        *p.get(&format!("{prefix}_TMAX"))?,
    );
    let tref = *p.get(&format!("{prefix}_TREF"))?;
    let c: Option<Vec<f64>> = (0..=3)
        .map(|k| p.get(&format!("{prefix}_X{k}_{i}")).copied())
        .collect();
    Some(poly(&c?, tref, t))
}

/// The correction ArduPilot applies at `t_c` on `axis` (`X`, `Y`, `Z`)
/// for a regular calibration made at `t_cal_c` (`prefix` =
/// `INS_TCAL1`, `kind` = `ACC` or `GYR`).
pub fn ardupilot_offset(
    p: &BTreeMap<String, f64>,
    prefix: &str,
    kind: &str,
    axis: &str,
    t_c: f64,
    t_cal_c: f64,
) -> Option<f64> {
    let lo = *p.get(&format!("{prefix}_TMIN"))?;
    let hi = *p.get(&format!("{prefix}_TMAX"))?;
    let mut c = vec![0.0];
    for k in 1..=3 {
        c.push(p.get(&format!("{prefix}_{kind}{k}_{axis}"))? / ARDUPILOT_SCALE);
    }
    let f = |t: f64| poly(&c, ARDUPILOT_T_REF_C, t.clamp(lo, hi));
    Some(f(t_c) - f(t_cal_c))
}
