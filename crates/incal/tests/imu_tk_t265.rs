//! A real recording with quantised time stamps, and imu_tk's own output for
//! it (fixture `fixtures/imu_tk_t265`, README and LICENSE there): a
//! RealSense T265 at about 200 Hz stamped to 10 ms, so about every other
//! stamp repeats the one before.
//!
//! - `--method tedaldi` reproduces imu_tk's published calibration: the
//!   accelerometer scales and biases and the gyro biases to imu_tk's 6
//!   printed digits (within one unit of the last), every misalignment and gyro scale within 1e-5 (at most
//!   0.3 % of its standard uncertainty; imu_tk's Ceres and incal's
//!   Gauss–Newton stop at different points of a flat minimum).
//! - `--method incal` should agree with it within its own stated U95; it
//!   does not yet (the ignored test below says by how much and what is
//!   known).
//! - The time-stamp policy reports the repeats (`time-repeats`).

use std::collections::BTreeMap;

use incal::procedures::imu::autocal::{Autocal, AutocalSessionOptions, Method};
use incal::procedures::{reduce_source, Silent};

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/imu_tk_t265/");

/// The two imu_tk files (`t x y z`) joined into incal's session CSV.
fn session() -> String {
    let read = |f: &str| std::fs::read_to_string(format!("{DIR}{f}")).unwrap();
    let (acc, gyr) = (read("t265_acc.mat"), read("t265_gyr.mat"));
    let mut csv = String::from("time_s,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n");
    let mut rows = 0;
    for (a, g) in acc.lines().zip(gyr.lines()) {
        let a: Vec<&str> = a.split_whitespace().collect();
        let g: Vec<&str> = g.split_whitespace().collect();
        if a.is_empty() {
            continue;
        }
        assert_eq!(a[0], g[0], "the two files share their time column");
        csv.push_str(&[a[0], a[1], a[2], a[3], g[1], g[2], g[3]].join(","));
        csv.push('\n');
        rows += 1;
    }
    assert_eq!(rows, 64_797);
    csv
}

/// imu_tk's `.calib` (T, K, b; `calibrated = T K (raw − b)`) as incal's
/// parameter names (`T = [[1, −m_yz, m_zy], [m_xz, 1, −m_zx], [−m_xy, m_yx, 1]]`).
fn calib(file: &str, triad: &str) -> BTreeMap<String, f64> {
    let text = std::fs::read_to_string(format!("{DIR}{file}")).unwrap();
    let x: Vec<f64> = text
        .split_whitespace()
        .map(|s| s.parse().unwrap())
        .collect();
    assert_eq!(x.len(), 21);
    let t = |r: usize, c: usize| x[3 * r + c];
    let mut m = BTreeMap::new();
    let mut put = |n: &str, v: f64| {
        m.insert(format!("{triad}.{n}"), v);
    };
    put("m_yz", -t(0, 1));
    put("m_zy", t(0, 2));
    put("m_zx", -t(1, 2));
    if triad == "gyr" {
        put("m_xz", t(1, 0));
        put("m_xy", -t(2, 0));
        put("m_yx", t(2, 1));
    }
    put("s_x", x[9]);
    put("s_y", x[13]);
    put("s_z", x[17]);
    put("b_x", x[18]);
    put("b_y", x[19]);
    put("b_z", x[20]);
    m
}

fn options(method: Method) -> AutocalSessionOptions {
    // The fork's apps/test_imu_calib.cpp settings.
    AutocalSessionOptions {
        rate_hz: 200.0,
        method,
        gravity_m_s2: 9.8016,
        init_static_s: 50.0,
        settle_s: 0.1,
    }
}

/// One unit of the 6th significant digit of `x` (imu_tk's streams print
/// 6 significant digits).
fn printed_unit(x: f64) -> f64 {
    10f64.powf(x.abs().log10().floor() - 5.0)
}

#[test]
fn tedaldi_reproduces_imu_tk_on_a_quantised_recording() {
    let csv = session();
    let read = incal_io::ReadOptions::default();
    let run = |method| {
        reduce_source::<Autocal, _>("t265.csv", csv.as_bytes(), &read, &options(method), &Silent)
            .unwrap()
    };
    let ted = run(Method::Tedaldi);
    assert!(ted.title.contains("41 still intervals"), "{}", ted.title);
    assert!(
        ted.warnings
            .iter()
            .any(|w| w.code == incal::WarningCode::TimeRepeats
                && w.message.starts_with("32368 time_s stamps repeat")),
        "{:?}",
        ted.warnings
    );
    let mut reference = calib("t265_test_imu_acc.calib", "acc");
    reference.extend(calib("t265_test_imu_gyro.calib", "gyr"));
    assert_eq!(reference.len(), 21);
    for (name, want) in &reference {
        let c = ted
            .coefficients
            .get(name)
            .unwrap_or_else(|| panic!("{name}"));
        let exact = name.starts_with("acc.s_") || name.contains(".b_");
        if exact {
            let d = (c.value - want).abs();
            assert!(
                d <= printed_unit(*want),
                "{name}: {} vs imu_tk {want}",
                c.value
            );
        } else {
            let d = (c.value - want).abs();
            assert!(
                d <= 1e-5 && d <= 0.003 * c.u,
                "{name}: {} vs imu_tk {want} (u {})",
                c.value,
                c.u
            );
        }
    }
}

/// `--method incal` should agree with imu_tk's within its own stated U95
/// (issue "Real recordings"). On this recording it does not yet: measured
/// (2026-11-25), 9 of 21 parameters differ by more than U95: acc.s_z 1.4,
/// gyr.s_x 1.7, gyr.s_z 5.7 and the six gyro misalignments 9–32 times U95
/// (differences 0.007–0.029 against a stated u of about 4e-4). The
/// recording has only 6 distinct orientations (`weak-conditioning`); the
/// two methods' accelerometer frames differ by 0.02–0.05 in their
/// misalignments (within incal's U95 there), and each method's gyro
/// misalignments are relative to its own accelerometer frame. Whether
/// incal's gyro u is too small or imu_tk's gyro fit is pulled by its frame
/// is not established yet: a simulation with this recording's six
/// orientations would say. Run with `--ignored` to see the table.
#[test]
#[ignore = "open: on the T265 recording 9 of 21 parameters differ from imu_tk by more than incal's U95 (cause not yet established)"]
fn incal_agrees_with_tedaldi_within_its_u95() {
    let csv = session();
    let read = incal_io::ReadOptions::default();
    let run = |method| {
        reduce_source::<Autocal, _>("t265.csv", csv.as_bytes(), &read, &options(method), &Silent)
            .unwrap()
    };
    let (ted, inc) = (run(Method::Tedaldi), run(Method::Incal));
    let mut beyond = Vec::new();
    for (name, a) in inc.coefficients.iter() {
        let b = ted.coefficients.get(name).unwrap();
        let r = (a.value - b.value).abs() / a.u95;
        eprintln!(
            "{name}: incal {} tedaldi {} |d|/U95 {r:.2}",
            a.value, b.value
        );
        if r > 1.0 {
            beyond.push(format!("{name} ({r:.2} U95)"));
        }
    }
    assert!(beyond.is_empty(), "{beyond:?}");
}
