//! Noise terms in the configuration files of four visual-inertial
//! estimators, beside Kalibr's and PX4's ([`super::export`]): each in the
//! stack's own keys, units and time convention, with a header comment
//! saying which, the inflation factor and where every number comes from.
//!
//! From the continuous-time density `σ_c` (IEEE Std 952's N in SI) and
//! random walk `σ_bc` (K in SI) of [`super::export::kalibr`], an IMU rate
//! `f` and an inflation factor `k` (1 unless asked, stated):
//!
//! | stack | keys | time | values |
//! |---|---|---|---|
//! | VINS-Mono / VINS-Fusion | `acc_n`, `gyr_n`, `acc_w`, `gyr_w` | discrete, per IMU sample | `k σ_c √(2f)`, `k σ_bc √f` |
//! | ORB-SLAM3 | `IMU.NoiseGyro`, `IMU.NoiseAcc`, `IMU.GyroWalk`, `IMU.AccWalk`, `IMU.Frequency` | continuous | `k σ_c`, `k σ_bc` |
//! | OpenVINS | `imu0: accelerometer_noise_density …, update_rate` | continuous | `k σ_c`, `k σ_bc` |
//! | Basalt | `accel_noise_std`, `gyro_noise_std`, `accel_bias_std`, `gyro_bias_std` (per axis), `imu_update_rate` | continuous | `k σ_c`, `k σ_bc` |
//!
//! VINS propagates its preintegration covariance per sample with the
//! mid-point rule: the white noise of the two samples of a step of length
//! `Δt = 1/f` enters the angle (velocity) increment with weight `Δt/2`
//! each, so `gyr_n² Δt²/2` per step, which equals the continuous-time
//! growth `σ_c² Δt` when `gyr_n = σ_c √(2f)`; the bias enters with weight
//! `Δt`, `gyr_w² Δt² = σ_bc² Δt` when `gyr_w = σ_bc √f`. ORB-SLAM3 reads
//! continuous-time values and multiplies (divides) them by `√f` itself;
//! OpenVINS reads Kalibr's model; Basalt's calibration holds
//! continuous-time values per axis (x, y, z: the result's three channels
//! in order, or the largest axis on all three when the result has not
//! three channels, said in its note).

use crate::document::ResultDocument;
use crate::error::{Error, Result};

use super::document::Quantity;
use super::export::{every_axis, kalibr, yaml_float, KalibrImu, KalibrTerm};

/// A visual-inertial estimator whose configuration incal writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stack {
    /// VINS-Mono and VINS-Fusion (`acc_n` …, discrete).
    Vins,
    /// ORB-SLAM3 (`IMU.NoiseGyro` …, continuous).
    Orbslam3,
    /// OpenVINS (`kalibr_imu_chain.yaml`, continuous).
    Openvins,
    /// Basalt (calibration JSON, per axis, continuous).
    Basalt,
}

/// How a stack's file is written.
#[derive(Debug, Clone, PartialEq)]
pub struct StackOptions {
    /// Every value times this (1 to 1000; stated in the file).
    pub inflate: f64,
    /// The IMU rate the estimator runs at, Hz (default the records').
    pub rate_hz: Option<f64>,
    /// OpenVINS's `rostopic` (default `/imu0`).
    pub topic: Option<String>,
}

impl Default for StackOptions {
    fn default() -> Self {
        StackOptions {
            inflate: 1.0,
            rate_hz: None,
            topic: None,
        }
    }
}

/// The four SI values of `imu` by key.
fn si(imu: &KalibrImu, key: &str) -> Result<KalibrTerm> {
    imu.terms
        .iter()
        .find(|t| t.key == key)
        .cloned()
        .ok_or_else(|| Error::Unsupported(format!("no {key}")))
}

/// `# KEY: value unit from … (axis …)` for a value `t.value · factor`.
fn origin(t: &KalibrTerm, what: &str) -> String {
    format!(
        "{} = {} {} (axis {}, u {})",
        t.from,
        yaml_float(t.value),
        t.unit,
        t.channel,
        yaml_float(t.u)
    ) + what
}

/// The file of `stack` from a gyro and an accelerometer noise result (the
/// module docs for the keys and conversions).
pub fn stack_text(
    stack: Stack,
    (gyro, gname): (&ResultDocument, &str),
    (accel, aname): (&ResultDocument, &str),
    o: &StackOptions,
) -> Result<String> {
    crate::options::check_range("inflate", o.inflate, 1.0, 1000.0, "")?;
    if let Some(r) = o.rate_hz {
        crate::options::check_range("rate_hz", r, 0.1, 1e6, "Hz")?;
    }
    let imu = kalibr(gyro, gname, accel, aname)?;
    let f = o.rate_hz.unwrap_or(imu.update_rate_hz);
    let k = o.inflate;
    let head = |name: &str, time: &str| -> String {
        format!(
            "# IMU noise for {name}, written by incal export\n# gyro: {gname}\n# accelerometer: {aname}\n# {time}\n# inflation factor {} (every noise value below is the sensor's at rest times {}); IMU rate {} Hz\n",
            yaml_float(k),
            yaml_float(k),
            yaml_float(f)
        )
    };
    let (gn, an) = (
        si(&imu, "gyroscope_noise_density")?,
        si(&imu, "accelerometer_noise_density")?,
    );
    let (gw, aw) = (
        si(&imu, "gyroscope_random_walk")?,
        si(&imu, "accelerometer_random_walk")?,
    );
    let line = |key: &str, t: &KalibrTerm, factor: f64, unit: &str, how: &str| {
        format!(
            "{key}: {}  # {unit}: {}\n",
            yaml_float(t.value * factor * k),
            origin(t, how)
        )
    };
    Ok(match stack {
        Stack::Vins => {
            let (w, b) = ((2.0 * f).sqrt(), f.sqrt());
            let mut s = String::from("%YAML:1.0\n");
            s += &head("VINS-Mono / VINS-Fusion (merge these keys into its config)", "discrete time per IMU sample, as VINS propagates its preintegration (mid-point rule): acc_n, gyr_n = sigma_c sqrt(2 f); acc_w, gyr_w = sigma_bc sqrt(f)");
            s += &line("acc_n", &an, w, "m/s^2", " x sqrt(2 f)");
            s += &line("gyr_n", &gn, w, "rad/s", " x sqrt(2 f)");
            s += &line("acc_w", &aw, b, "m/s^3", " x sqrt(f)");
            s += &line("gyr_w", &gw, b, "rad/s^2", " x sqrt(f)");
            s
        }
        Stack::Orbslam3 => {
            let mut s = String::from("%YAML:1.0\n");
            s += &head("ORB-SLAM3 (merge these keys into its settings)", "continuous time, SI units: ORB-SLAM3 multiplies the noise by sqrt(IMU.Frequency) and divides the walks by it itself");
            s += &line("IMU.NoiseGyro", &gn, 1.0, "rad/s/sqrt(Hz)", "");
            s += &line("IMU.NoiseAcc", &an, 1.0, "m/s^2/sqrt(Hz)", "");
            s += &line("IMU.GyroWalk", &gw, 1.0, "rad/s^2/sqrt(Hz)", "");
            s += &line("IMU.AccWalk", &aw, 1.0, "m/s^3/sqrt(Hz)", "");
            s += &format!("IMU.Frequency: {}  # Hz\n", yaml_float(f));
            s
        }
        Stack::Openvins => {
            let mut s = String::from("%YAML:1.0\n");
            s += &head(
                "OpenVINS (kalibr_imu_chain.yaml)",
                "continuous time, SI units (Kalibr's IMU noise model)",
            );
            s += "imu0:\n  T_i_b:\n    - [1.0, 0.0, 0.0, 0.0]\n    - [0.0, 1.0, 0.0, 0.0]\n    - [0.0, 0.0, 1.0, 0.0]\n    - [0.0, 0.0, 0.0, 1.0]\n";
            for (key, t) in [
                ("accelerometer_noise_density", &an),
                ("accelerometer_random_walk", &aw),
                ("gyroscope_noise_density", &gn),
                ("gyroscope_random_walk", &gw),
            ] {
                s += "  ";
                s += &line(key, t, 1.0, t.unit, "");
            }
            s += &format!(
                "  rostopic: {}\n  time_offset: 0.0\n  update_rate: {}  # Hz\n  model: \"kalibr\"\n",
                o.topic.as_deref().unwrap_or("/imu0"),
                yaml_float(f)
            );
            s
        }
        Stack::Basalt => basalt((gyro, gname), (accel, aname), &imu, f, k)?,
    })
}

/// Basalt's calibration keys (module docs), per axis.
fn basalt(
    (gyro, gname): (&ResultDocument, &str),
    (accel, aname): (&ResultDocument, &str),
    imu: &KalibrImu,
    f: f64,
    k: f64,
) -> Result<String> {
    // [`kalibr`] has checked each result's procedure and quantity.
    let (qg, qa) = (Quantity::Gyro, Quantity::Accel);
    let rad = std::f64::consts::PI / 180.0;
    let g0 = crate::units::STANDARD_GRAVITY_M_S2;
    let mut notes = Vec::new();
    let mut value = serde_json::Map::new();
    value.insert("imu_update_rate".into(), serde_json::json!(f));
    for (key, doc, name, q, term, si, from) in [
        (
            "accel_noise_std",
            accel,
            aname,
            &qa,
            1,
            g0,
            "accelerometer_noise_density",
        ),
        (
            "gyro_noise_std",
            gyro,
            gname,
            &qg,
            1,
            rad,
            "gyroscope_noise_density",
        ),
        (
            "accel_bias_std",
            accel,
            aname,
            &qa,
            3,
            g0,
            "accelerometer_random_walk",
        ),
        (
            "gyro_bias_std",
            gyro,
            gname,
            &qg,
            3,
            rad,
            "gyroscope_random_walk",
        ),
    ] {
        let axes = every_axis(doc, name, q, term, (from, "", si))?;
        let v: Vec<f64> = if axes.len() == 3 {
            axes.iter().map(|t| t.value * k).collect()
        } else {
            let big = imu
                .terms
                .iter()
                .find(|t| t.key == from)
                .map_or(0.0, |t| t.value);
            notes.push(format!(
                "{key}: {name} has {} channels, not 3: its largest axis on x, y and z",
                axes.len()
            ));
            vec![big * k; 3]
        };
        let chans: Vec<&str> = axes.iter().map(|t| t.channel.as_str()).collect();
        notes.push(format!(
            "{key} (x, y, z) from {name} channels {}",
            chans.join(", ")
        ));
        value.insert(key.into(), serde_json::json!(v));
    }
    let note = format!(
        "IMU noise for Basalt, written by incal export: merge value0's keys into the calibration. Continuous time, SI units (m/s^2/sqrt(Hz), rad/s/sqrt(Hz), m/s^3/sqrt(Hz), rad/s^2/sqrt(Hz)); inflation factor {k} (every noise value is the sensor's at rest times {k}); IMU rate {f} Hz. {}",
        notes.join("; ")
    );
    let doc = serde_json::json!({"incal_note": note, "value0": value});
    Ok(serde_json::to_string_pretty(&doc).map_err(|e| Error::Unsupported(e.to_string()))? + "\n")
}
