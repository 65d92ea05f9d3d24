//! The exports for Python, on the core directly: an IMU calibration as
//! imucal's JSON, noise terms as Kalibr's `imu.yaml`, PX4's EKF2
//! parameters or VINS's, ORB-SLAM3's, OpenVINS's and Basalt's settings, a thermal model as PX4's or ArduPilot's parameters.

use incal::document::ResultDocument;
use pyo3::prelude::*;

/// The options of an export (those its kind uses).
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct ExportOptions {
    ekf_rate_hz: Option<f64>,
    axes: Option<Vec<String>>,
    device_id: u32,
    with_offset: bool,
    imu: Option<u8>,
    inflate: Option<f64>,
    rate_hz: Option<f64>,
    topic: Option<String>,
    instance: Option<usize>,
}

/// `NAME: message` of an error of the document `name`.
fn in_file(name: &str) -> impl Fn(incal::Error) -> String + '_ {
    move |e| format!("{name}: {e}")
}

fn text(
    kind: &str,
    docs: &[(String, ResultDocument)],
    o: &ExportOptions,
) -> Result<String, String> {
    match (kind, docs) {
        ("imucal", [(name, doc)]) => {
            let cal = incal::procedures::imu::apply::to_imucal(doc).map_err(in_file(name))?;
            Ok(format!(
                "{}\n",
                serde_json::to_string_pretty(&cal).map_err(|e| e.to_string())?
            ))
        }
        ("kalibr", [(gname, gyro), (aname, accel)]) => {
            incal::procedures::noise::export::kalibr(gyro, gname, accel, aname)
                .map(|imu| imu.to_yaml())
                .map_err(|e| e.to_string())
        }
        ("vins" | "orbslam3" | "openvins" | "basalt", [(gname, gyro), (aname, accel)]) => {
            use incal::procedures::noise::stacks::{stack_text, Stack, StackOptions};
            let stack = match kind {
                "vins" => Stack::Vins,
                "orbslam3" => Stack::Orbslam3,
                "openvins" => Stack::Openvins,
                _ => Stack::Basalt,
            };
            if o.topic.is_some() && stack != Stack::Openvins {
                return Err(format!(
                    "topic: only export_openvins takes it, not export_{kind}"
                ));
            }
            let so = StackOptions {
                inflate: o.inflate.unwrap_or(1.0),
                rate_hz: o.rate_hz,
                topic: o.topic.clone(),
            };
            stack_text(stack, (gyro, gname), (accel, aname), &so).map_err(|e| e.to_string())
        }
        ("px4", [(gname, gyro), (aname, accel)]) => {
            let imu = incal::procedures::noise::export::kalibr(gyro, gname, accel, aname)
                .map_err(|e| e.to_string())?;
            incal::procedures::noise::export::px4(&imu, o.ekf_rate_hz.unwrap_or(100.0))
                .map(|p| p.to_params())
                .map_err(|e| e.to_string())
        }
        ("px4", [(name, doc)]) => {
            let model = incal::procedures::thermal::Model::of(doc).map_err(in_file(name))?;
            let params = incal::procedures::thermal::export::px4(
                &model,
                o.axes.as_deref(),
                o.device_id,
                o.with_offset,
            )
            .map_err(in_file(name))?;
            Ok(incal::procedures::thermal::export::px4_text(&params, name))
        }
        ("ardupilot", [(name, doc)]) => {
            let model = incal::procedures::thermal::Model::of(doc).map_err(in_file(name))?;
            let imu = o.imu.unwrap_or(1);
            if !(1..=3).contains(&imu) {
                return Err(format!("imu: {imu} is not 1, 2 or 3"));
            }
            let params =
                incal::procedures::thermal::export::ardupilot(&model, o.axes.as_deref(), imu)
                    .map_err(in_file(name))?;
            Ok(incal::procedures::thermal::export::ardupilot_text(
                &params, name,
            ))
        }
        ("mag-px4" | "mag-ardupilot", [(name, doc)]) => {
            use incal::procedures::mag::apply::{
                parameters, write_parameters, FlightStack, MagCalibration,
            };
            let stack = if kind == "mag-px4" {
                FlightStack::Px4
            } else {
                FlightStack::Ardupilot
            };
            let cal = MagCalibration::from_document(doc).map_err(in_file(name))?;
            let instance = o.instance.unwrap_or(0);
            if instance > 3 {
                return Err(format!("instance: {instance} is not 0 to 3"));
            }
            let params = parameters(&cal, stack, instance).map_err(in_file(name))?;
            let mut out = Vec::new();
            write_parameters(stack, &params, &mut out).map_err(|e| e.to_string())?;
            String::from_utf8(out).map_err(|e| e.to_string())
        }
        _ => Err(format!(
            "export {kind}: {} document(s) is not what it takes",
            docs.len()
        )),
    }
}

/// `_export(kind, documents, options) -> (code, text, error)`: `kind`
/// `imucal` (one IMU calibration), `kalibr`, `px4`, `vins`, `orbslam3`,
/// `openvins` or `basalt` (a gyro and an accelerometer noise result), `px4` or `ardupilot` (one thermal model),
/// `mag-px4` or `mag-ardupilot` (one magnetometer calibration, option `instance`);
/// `documents` a list of `(name, JSON text)`; `options` JSON
/// (`ekf_rate_hz`, `axes`, `device_id`, `with_offset`, `imu`, `inflate`,
/// `rate_hz`, `topic`).
#[pyfunction]
pub fn _export(
    kind: &str,
    documents: Vec<(String, String)>,
    options: &str,
) -> (u8, String, String) {
    let o: ExportOptions = match serde_json::from_str(options) {
        Ok(o) => o,
        Err(e) => return (2, String::new(), format!("export {kind}: {e}")),
    };
    let mut docs = Vec::new();
    for (name, t) in documents {
        match ResultDocument::from_json(&t) {
            Ok(d) => docs.push((name, d)),
            Err(e) => return (2, String::new(), format!("{name}: {e}")),
        }
    }
    match text(kind, &docs, &o) {
        Ok(t) => (0, t, String::new()),
        Err(e) => (2, String::new(), e),
    }
}
