//! Noise terms in the form the robotics tools read: Kalibr's `imu.yaml`
//! (the IMU noise model of Kalibr, imu_utils, VINS and allan_variance_ros).
//!
//! Kalibr models each axis as white noise plus a random-walk bias in
//! continuous time, with the noise density `σ_c` and the random walk
//! `σ_bc` in SI units:
//!
//! | Kalibr key | incal term | conversion |
//! |---|---|---|
//! | `gyroscope_noise_density` (rad/s/√Hz) | ARW N (°/√h) | `N · (π/180) / 60` |
//! | `gyroscope_random_walk` (rad/s²/√Hz) | RRW K (°/h/√h) | `K · (π/180) / (3600 · 60)` |
//! | `accelerometer_noise_density` (m/s²/√Hz) | VRW N (µg/√Hz) | `N · 10⁻⁶ · g₀` |
//! | `accelerometer_random_walk` (m/s³/√Hz) | acceleration random walk K (µg/√s) | `K · 10⁻⁶ · g₀` |
//!
//! with g₀ = 9.80665 m/s². N is the continuous-time density of the white
//! rate noise (IEEE Std 952-2020 Annex C: σ²(τ) = N²/τ), so
//! `σ_c = N` in SI units, and a discrete sample at rate f has standard
//! deviation `σ_d = σ_c·√f`; likewise K (σ²(τ) = K²τ/3) is `σ_bc`, and
//! `σ_bd = σ_bc/√f`. Kalibr takes one value per sensor: the largest of
//! the three axes, as its documentation asks, and says which axis in a
//! comment. A term that was not identified on an axis is refused, naming
//! the axis and the term, never written as zero.

use std::f64::consts::PI;

use crate::document::{Procedure, ResultDocument};
use crate::error::{Error, Result};
use crate::units::STANDARD_GRAVITY_M_S2;

use super::document::Quantity;

/// One Kalibr value: the largest axis, its SI value and its standard
/// uncertainty.
#[derive(Debug, Clone, PartialEq)]
pub struct KalibrTerm {
    /// Kalibr's key (`gyroscope_noise_density`, …).
    pub key: &'static str,
    /// SI value of the largest axis.
    pub value: f64,
    /// Its standard uncertainty, same unit.
    pub u: f64,
    /// SI unit, for the comment.
    pub unit: &'static str,
    /// The axis (channel) it comes from.
    pub channel: String,
    /// The incal coefficient it was converted from (`ch1.ARW`).
    pub from: String,
}

/// Kalibr's `imu.yaml` from a gyro and an accelerometer noise result.
#[derive(Debug, Clone, PartialEq)]
pub struct KalibrImu {
    /// Noise densities and random walks, in Kalibr's order.
    pub terms: Vec<KalibrTerm>,
    /// `update_rate` (Hz), the records' sample rate.
    pub update_rate_hz: f64,
    /// Where the results came from (`--gyro`, `--accel` names).
    pub sources: [String; 2],
}

fn bad(what: String) -> Error {
    Error::Unsupported(what)
}

/// The channels of a noise result, in document order.
fn channels(doc: &ResultDocument) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in doc.coefficients.names() {
        if let Some((ch, _)) = n.rsplit_once('.') {
            if !out.iter().any(|c| c == ch) {
                out.push(ch.to_string());
            }
        }
    }
    if let Some(serde_json::Value::Object(m)) = doc.extra.get("channels") {
        for ch in m.keys() {
            if !out.iter().any(|c| c == ch) {
                out.push(ch.clone());
            }
        }
    }
    out
}

/// The largest axis of `term` (index into [`Quantity::units`]' terms) of
/// a noise result of `quantity`, converted to SI by `si` (from the
/// internal rate unit, deg/s or g, times seconds to a power).
fn largest(
    doc: &ResultDocument,
    name: &str,
    quantity: &Quantity,
    term: usize,
    key: &'static str,
    unit: &'static str,
    si: f64,
) -> Result<KalibrTerm> {
    let (tname, ..) = quantity.units().terms[term].clone();
    let mut best: Option<KalibrTerm> = None;
    for t in every_axis(doc, name, quantity, term, (key, unit, si))? {
        if best.as_ref().is_none_or(|b| t.value > b.value) {
            best = Some(t);
        }
    }
    best.ok_or_else(|| bad(format!("{name}: no {tname}")))
}

/// `term` of every axis (channel, in document order) as [`largest`]
/// reads it, each refused when missing or not positive.
pub(crate) fn every_axis(
    doc: &ResultDocument,
    name: &str,
    quantity: &Quantity,
    term: usize,
    (key, unit, si): (&'static str, &'static str, f64),
) -> Result<Vec<KalibrTerm>> {
    let (tname, tunit, factor) = quantity.units().terms[term].clone();
    let mut all = Vec::new();
    let chans = channels(doc);
    if chans.is_empty() {
        return Err(bad(format!("{name}: the result has no channels")));
    }
    for ch in chans {
        let cname = format!("{ch}.{tname}");
        let Some(c) = doc.coefficients.get(&cname) else {
            return Err(bad(format!(
                "{name}: {ch}: {tname} was not identified (see the result's warnings): Kalibr's {key} is not written as zero"
            )));
        };
        if c.unit != tunit {
            return Err(bad(format!(
                "{name}: $.coefficients[\"{cname}\"].unit is '{}', not '{}'",
                c.unit, tunit
            )));
        }
        if !(c.value.is_finite() && c.value > 0.0) {
            return Err(bad(format!(
                "{name}: $.coefficients[\"{cname}\"].value is {}: a noise density or random walk is positive",
                c.value
            )));
        }
        let k = si / factor;
        all.push(KalibrTerm {
            key,
            value: c.value * k,
            u: c.u * k,
            unit,
            channel: ch.clone(),
            from: cname,
        });
    }
    Ok(all)
}

fn noise_of(doc: &ResultDocument, name: &str, want: &str) -> Result<(Quantity, f64)> {
    if doc.procedure != Procedure::Noise {
        return Err(bad(format!(
            "{name}: a {} result, not a noise result",
            doc.procedure.as_str()
        )));
    }
    let quantity = match doc.options.get("quantity").and_then(|v| v.as_str()) {
        Some("gyro") => Quantity::Gyro,
        Some("accel") => Quantity::Accel,
        other => {
            return Err(bad(format!(
                "{name}: $.options.quantity is {}, not \"{want}\" (run incal noise with --quantity {want})",
                other.map_or("missing".to_string(), |q| format!("\"{q}\""))
            )))
        }
    };
    let rate = doc
        .options
        .get("rate_hz")
        .and_then(|v| v.as_f64())
        .filter(|r| r.is_finite() && *r > 0.0)
        .ok_or_else(|| bad(format!("{name}: $.options.rate_hz: missing")))?;
    Ok((quantity, rate))
}

/// Kalibr's IMU noise model from a gyro noise result (`--quantity gyro`)
/// and an accelerometer noise result (`--quantity accel`) of the same
/// IMU at the same sample rate (module docs for the conversions).
pub fn kalibr(
    gyro: &ResultDocument,
    gyro_name: &str,
    accel: &ResultDocument,
    accel_name: &str,
) -> Result<KalibrImu> {
    let (qg, rate_g) = noise_of(gyro, gyro_name, "gyro")?;
    if qg != Quantity::Gyro {
        return Err(bad(format!(
            "{gyro_name}: $.options.quantity is \"accel\", not \"gyro\" (give the gyro result as --gyro)"
        )));
    }
    let (qa, rate_a) = noise_of(accel, accel_name, "accel")?;
    if qa != Quantity::Accel {
        return Err(bad(format!(
            "{accel_name}: $.options.quantity is \"gyro\", not \"accel\" (give the accelerometer result as --accel)"
        )));
    }
    if rate_g != rate_a {
        return Err(bad(format!(
            "{gyro_name} was recorded at {rate_g} Hz and {accel_name} at {rate_a} Hz: Kalibr's update_rate is one rate"
        )));
    }
    let rad = PI / 180.0;
    let g0 = STANDARD_GRAVITY_M_S2;
    // Internal units: deg/s and g; terms: N in (unit)·√s, K in (unit)/√s.
    let terms = vec![
        largest(
            accel,
            accel_name,
            &qa,
            1,
            "accelerometer_noise_density",
            "m/s^2/sqrt(Hz)",
            g0,
        )?,
        largest(
            accel,
            accel_name,
            &qa,
            3,
            "accelerometer_random_walk",
            "m/s^3/sqrt(Hz)",
            g0,
        )?,
        largest(
            gyro,
            gyro_name,
            &qg,
            1,
            "gyroscope_noise_density",
            "rad/s/sqrt(Hz)",
            rad,
        )?,
        largest(
            gyro,
            gyro_name,
            &qg,
            3,
            "gyroscope_random_walk",
            "rad/s^2/sqrt(Hz)",
            rad,
        )?,
    ];
    Ok(KalibrImu {
        terms,
        update_rate_hz: rate_g,
        sources: [gyro_name.to_string(), accel_name.to_string()],
    })
}

impl KalibrImu {
    /// The `imu.yaml` text: Kalibr's keys, each value in shortest
    /// round-trip form, with a comment naming the axis, the incal
    /// coefficient and its u.
    pub fn to_yaml(&self) -> String {
        let mut s = String::from(
            "# IMU noise model for Kalibr (continuous time, SI units), written by incal export kalibr\n",
        );
        s.push_str(&format!(
            "# gyro: {}\n# accelerometer: {}\n# per sensor the largest axis\n",
            self.sources[0], self.sources[1]
        ));
        for t in &self.terms {
            s.push_str(&format!(
                "{}: {}  # {}, {} (axis {}), u = {} {}\n",
                t.key,
                yaml_float(t.value),
                t.unit,
                t.from,
                t.channel,
                yaml_float(t.u),
                t.unit
            ));
        }
        s.push_str(&format!(
            "update_rate: {}  # Hz\n",
            yaml_float(self.update_rate_hz)
        ));
        s
    }
}

/// PX4's EKF2 IMU noise parameters from the same two results.
///
/// EKF2 adds, per prediction step of length dt = 1/f (f the filter's
/// prediction rate, `--ekf-rate-hz`), the variance `(EKF2_GYR_NOISE·dt)²` to
/// each delta angle and `(EKF2_GYR_B_NOISE·dt)²` to each gyro bias state
/// (likewise ACC for delta velocity and accelerometer bias). Over a time T
/// that is `T·σ²·dt`, which equals the continuous-time growth `σ_c²·T`
/// when `σ = σ_c·√f`:
///
/// | PX4 parameter | Kalibr value | conversion |
/// |---|---|---|
/// | `EKF2_GYR_NOISE` (rad/s) | `gyroscope_noise_density` | `·√f` |
/// | `EKF2_ACC_NOISE` (m/s²) | `accelerometer_noise_density` | `·√f` |
/// | `EKF2_GYR_B_NOISE` (rad/s²) | `gyroscope_random_walk` | `·√f` |
/// | `EKF2_ACC_B_NOISE` (m/s³) | `accelerometer_random_walk` | `·√f` |
///
/// These are the sensor's own figures at rest: a floor. PX4's defaults are
/// larger on purpose (vibration, temperature, model errors); raise them in
/// flight tuning, never below these.
#[derive(Debug, Clone, PartialEq)]
pub struct Px4Params {
    /// (parameter name, value, unit, the Kalibr term it comes from).
    pub params: Vec<(&'static str, f64, &'static str, KalibrTerm)>,
    /// The prediction rate f (Hz).
    pub ekf_rate_hz: f64,
    /// Where the results came from.
    pub sources: [String; 2],
}

/// [`Px4Params`] at prediction rate `ekf_rate_hz` (PX4's default 100 Hz,
/// `EKF2_PREDICT_US` = 10 000).
pub fn px4(imu: &KalibrImu, ekf_rate_hz: f64) -> Result<Px4Params> {
    crate::options::check_range("ekf_rate_hz", ekf_rate_hz, 1.0, 1e4, "Hz")?;
    let k = ekf_rate_hz.sqrt();
    let name = |key: &str| match key {
        "gyroscope_noise_density" => Some(("EKF2_GYR_NOISE", "rad/s")),
        "accelerometer_noise_density" => Some(("EKF2_ACC_NOISE", "m/s^2")),
        "gyroscope_random_walk" => Some(("EKF2_GYR_B_NOISE", "rad/s^2")),
        "accelerometer_random_walk" => Some(("EKF2_ACC_B_NOISE", "m/s^3")),
        _ => None,
    };
    let params = imu
        .terms
        .iter()
        .filter_map(|t| name(t.key).map(|(n, u)| (n, t.value * k, u, t.clone())))
        .collect();
    let params: Vec<(&'static str, f64, &'static str, KalibrTerm)> = params;
    for (n, v, _, _) in &params {
        crate::procedures::thermal::export::float32_parameter(n, *v)?;
    }
    Ok(Px4Params {
        params,
        ekf_rate_hz,
        sources: imu.sources.clone(),
    })
}

impl Px4Params {
    /// A QGroundControl parameter file (`Vehicle-Id Component-Id Name
    /// Value Type`, tab separated, type 9 = float), loaded by QGC's
    /// "Load from file" or `param load` in the PX4 shell; `#` lines are
    /// comments naming the source of each value.
    pub fn to_params(&self) -> String {
        let mut s = String::from("# PX4 EKF2 IMU noise parameters, written by incal export px4\n");
        s.push_str(&format!(
            "# gyro: {}\n# accelerometer: {}\n# per sensor the largest axis; EKF prediction rate {} Hz (value = continuous-time density x sqrt(rate))\n",
            self.sources[0],
            self.sources[1],
            yaml_float(self.ekf_rate_hz)
        ));
        s.push_str("# Vehicle-Id\tComponent-Id\tName\tValue\tType\n");
        for (n, v, u, t) in &self.params {
            s.push_str(&format!(
                "# {n}: {} {u} from {} = {} {} (axis {})\n",
                yaml_float(*v),
                t.from,
                yaml_float(t.value),
                t.unit,
                t.channel
            ));
            s.push_str(&format!("1\t1\t{n}\t{}\t9\n", yaml_float(*v)));
        }
        s
    }
}

/// A float as YAML 1.1 (PyYAML, which Kalibr reads with) takes it back
/// exactly: shortest round-trip digits, always with a `.`, and an
/// exponent with its sign (`1.5e-05` would be a string to PyYAML without
/// the `.`; `1.5e-5` is read as a float).
pub(crate) fn yaml_float(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || (1e-4..1e15).contains(&a) {
        let t = format!("{v:?}");
        return if t.contains('.') { t } else { format!("{t}.0") };
    }
    let t = format!("{v:e}");
    let (m, e) = t.split_once('e').unwrap_or((&t, "0"));
    let m = if m.contains('.') {
        m.to_string()
    } else {
        format!("{m}.0")
    };
    let e = if e.starts_with('-') {
        e.to_string()
    } else {
        format!("+{e}")
    };
    format!("{m}e{e}")
}

#[cfg(test)]
mod tests {
    use super::yaml_float;

    #[test]
    fn floats_are_written_as_yaml_reads_them_back() {
        for (v, want) in [
            (0.0, "0.0"),
            (9.81, "9.81"),
            (100.0, "100.0"),
            (1.5e-5, "1.5e-5"),
            (2e-7, "2.0e-7"),
            (3.0e20, "3.0e+20"),
        ] {
            assert_eq!(yaml_float(v), want);
            assert_eq!(yaml_float(v).parse::<f64>().unwrap(), v);
        }
    }
}
