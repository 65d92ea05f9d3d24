//! `incal export vins|orbslam3|openvins|basalt` from outside: each file
//! read back and checked against the two noise documents (the largest
//! axis in SI continuous time, times the stack's own conversion and the
//! stated inflation), Basalt's per axis; bad settings exit 2 naming them.

use crate::common;
use common::*;

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde_json::Value;

/// `key: value` lines (comments and the `%YAML` directive skipped, keys
/// trimmed of their indentation).
fn yaml_values(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.starts_with('%'))
        .filter_map(|l| {
            let (k, v) = l.split_once(':')?;
            let v = v.split('#').next()?.trim();
            (!v.is_empty()).then(|| (k.trim().to_string(), v.to_string()))
        })
        .collect()
}

/// Each axis's SI continuous-time value of `term`.
fn axes(d: &Value, term: &str, si: f64) -> Vec<f64> {
    ["ch1", "ch2", "ch3"]
        .iter()
        .map(|c| {
            d["coefficients"][format!("{c}.{term}")]["value"]
                .as_f64()
                .unwrap()
                * si
        })
        .collect()
}

fn max(v: &[f64]) -> f64 {
    v.iter().copied().fold(f64::MIN, f64::max)
}

fn close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() <= 1e-12 * want.abs(),
        "{what}: {got} vs {want}"
    );
}

#[test]
fn every_stack_file_reads_back_as_the_documents_say() {
    let dir = workdir("stacks");
    let (gj, aj) = noise_pair(&dir, "");
    let doc = |f: &PathBuf| -> Value {
        serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap()
    };
    let (gd, ad) = (doc(&gj), doc(&aj));
    let rad = std::f64::consts::PI / 180.0;
    let g0 = 9.80665;
    let gn = axes(&gd, "ARW", rad / 60.0);
    let gw = axes(&gd, "RRW", rad / 216_000.0);
    let an = axes(&ad, "VRW", 1e-6 * g0);
    let aw = axes(&ad, "acceleration_random_walk", 1e-6 * g0);
    let (k, f) = (3.0, 200.0_f64);
    let export = |stack: &str, extra: &[&str]| -> String {
        let mut a = vec![
            "export",
            stack,
            "--gyro",
            p(&gj),
            "--accel",
            p(&aj),
            "--inflate",
            "3",
            "--rate-hz",
            "200",
        ];
        a.extend_from_slice(extra);
        ok(&run(&a))
    };
    let num = |m: &BTreeMap<String, String>, key: &str| -> f64 {
        m.get(key)
            .unwrap_or_else(|| panic!("{key} in {m:?}"))
            .parse()
            .unwrap()
    };

    let vins = export("vins", &[]);
    assert!(
        vins.starts_with("%YAML:1.0\n")
            && vins.contains("discrete time")
            && vins.contains("inflation factor 3.0")
    );
    let v = yaml_values(&vins);
    close(num(&v, "acc_n"), max(&an) * k * (2.0 * f).sqrt(), "acc_n");
    close(num(&v, "gyr_n"), max(&gn) * k * (2.0 * f).sqrt(), "gyr_n");
    close(num(&v, "acc_w"), max(&aw) * k * f.sqrt(), "acc_w");
    close(num(&v, "gyr_w"), max(&gw) * k * f.sqrt(), "gyr_w");

    let orb = export("orbslam3", &[]);
    assert!(orb.contains("continuous time"));
    let v = yaml_values(&orb);
    close(num(&v, "IMU.NoiseGyro"), max(&gn) * k, "NoiseGyro");
    close(num(&v, "IMU.NoiseAcc"), max(&an) * k, "NoiseAcc");
    close(num(&v, "IMU.GyroWalk"), max(&gw) * k, "GyroWalk");
    close(num(&v, "IMU.AccWalk"), max(&aw) * k, "AccWalk");
    close(num(&v, "IMU.Frequency"), f, "Frequency");

    let ov = export("openvins", &["--topic", "/mti/imu"]);
    let v = yaml_values(&ov);
    close(
        num(&v, "gyroscope_noise_density"),
        max(&gn) * k,
        "gyro density",
    );
    close(num(&v, "gyroscope_random_walk"), max(&gw) * k, "gyro walk");
    close(
        num(&v, "accelerometer_noise_density"),
        max(&an) * k,
        "accel density",
    );
    close(
        num(&v, "accelerometer_random_walk"),
        max(&aw) * k,
        "accel walk",
    );
    close(num(&v, "update_rate"), f, "update_rate");
    assert_eq!(v["rostopic"], "/mti/imu");
    assert!(ov.contains("\nimu0:\n"));

    let b: Value = serde_json::from_str(&export("basalt", &[])).unwrap();
    let b = &b["value0"];
    for (key, want) in [
        ("gyro_noise_std", &gn),
        ("gyro_bias_std", &gw),
        ("accel_noise_std", &an),
        ("accel_bias_std", &aw),
    ] {
        let got: Vec<f64> = b[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(got.len(), 3);
        for (g, w) in got.iter().zip(want.iter()) {
            close(*g, w * k, key);
        }
    }
    close(b["imu_update_rate"].as_f64().unwrap(), f, "imu_update_rate");

    // Bad settings and documents are refused, named.
    refused(
        &run(&[
            "export",
            "vins",
            "--gyro",
            p(&gj),
            "--accel",
            p(&aj),
            "--inflate",
            "0.5",
        ]),
        &["--inflate"],
    );
    refused(
        &run(&["export", "orbslam3", "--gyro", p(&aj), "--accel", p(&aj)]),
        &["gyro"],
    );
    let e = run(&[
        "export",
        "basalt",
        "--gyro",
        p(&gj),
        "--accel",
        p(&aj),
        "--topic",
        "/x",
    ]);
    assert_eq!(e.status.code(), Some(2));
}
