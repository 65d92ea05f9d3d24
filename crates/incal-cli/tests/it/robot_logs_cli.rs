//! Robot logs (PX4 ULog, ROS 1 bag, MCAP) as every reduction's input:
//! real vehicles' logs end to end, a chamber ramp written as a PX4
//! `sensor_gyro` log reduced as its CSV is, and the refusals. (Sample for
//! sample equality with the formats' reference readers is in the Python
//! tests, `test_robot_logs.py`.)

use std::path::PathBuf;

use crate::common::*;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../incal/tests/fixtures/robot_logs")
        .join(name)
}

/// A minimal PX4 ULog (format version 1): the header, one `F` format,
/// one `A` subscription (instance 0) and a `D` message per row.
fn ulog(format: &str, rows: &[Vec<u8>]) -> Vec<u8> {
    let mut out = b"ULog\x01\x12\x35\x01".to_vec();
    out.extend(0u64.to_le_bytes());
    let mut msg = |kind: u8, body: &[u8]| {
        out.extend((body.len() as u16).to_le_bytes());
        out.push(kind);
        out.extend(body);
    };
    msg(b'F', format.as_bytes());
    let name = format.split(':').next().unwrap();
    let mut add = vec![0u8];
    add.extend(7u16.to_le_bytes());
    add.extend(name.as_bytes());
    msg(b'A', &add);
    for r in rows {
        let mut d = 7u16.to_le_bytes().to_vec();
        d.extend(r);
        msg(b'D', &d);
    }
    out
}

/// PX4's `sensor_gyro` layout (rad/s, °C, µs).
const SENSOR_GYRO: &str = "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;uint8_t samples;uint8_t[4] _padding0;";

fn gyro_row(t_us: u64, w_rad_s: [f64; 3], temp_c: f64) -> Vec<u8> {
    let mut r = (t_us + 150).to_le_bytes().to_vec();
    r.extend(t_us.to_le_bytes());
    r.extend(7u32.to_le_bytes());
    for w in w_rad_s {
        r.extend((w as f32).to_le_bytes());
    }
    r.extend((temp_c as f32).to_le_bytes());
    r.extend([0u8; 4 + 3 + 1 + 4]);
    r
}

#[test]
fn a_real_flight_log_runs_noise_end_to_end() {
    let log = fixture("pyulog_sample_appended_multiple.ulg");
    let o = run(&[
        "noise",
        "--input",
        p(&log),
        "--topic",
        "sensor_combined",
        "--columns",
        "gyr_x,gyr_y,gyr_z",
        "--quantity",
        "gyro",
        "--json",
    ]);
    let doc = json_of(&o);
    let sha = incal_io::sha256_hex(&std::fs::read(&log).unwrap());
    assert_eq!(doc["inputs"][0]["sha256"], sha.as_str());
    assert_eq!(doc["inputs"][0]["rows"], 2373);
    // The stamps give the rate: 247 Hz from the vehicle's own clock.
    let rate = doc["options"]["rate_hz"].as_f64().unwrap();
    assert!((rate - 246.6).abs() < 1.0, "{rate}");
    let pre: Vec<String> = doc["preamble"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            format!(
                "{}={}",
                l["key"].as_str().unwrap(),
                l["value"].as_str().unwrap()
            )
        })
        .collect();
    assert!(pre.contains(&"format=PX4 ULog".to_string()), "{pre:?}");
    assert!(
        pre.iter()
            .any(|l| l.starts_with("units=gyro_rad: rad/s x 180/pi -> gyr deg/s")),
        "{pre:?}"
    );
    assert!(!coefficient_values(&doc).is_empty());
}

#[test]
fn a_bag_and_its_mcap_give_the_same_result() {
    let bag = fixture("husky_rl_test1.bag");
    let mcap = fixture("husky_rl_test1_imu_zstd.mcap");
    let args = |f: &PathBuf| {
        let o = run(&[
            "noise",
            "--input",
            p(f),
            "--columns",
            "gyr_z,acc_z",
            "--json",
        ]);
        coefficient_values(&json_of(&o))
    };
    let (a, b) = (args(&bag), args(&mcap));
    assert!(!a.is_empty());
    assert_eq!(a, b);
}

#[test]
fn a_chamber_ramp_logged_by_px4_reduces_as_its_csv() {
    let dir = workdir("robot_logs_thermal");
    let csv = dir.join("ramp.csv");
    ok(&run(&[
        "simulate",
        "thermal",
        "--seed",
        "5",
        "--hold-s",
        "600",
        "--output",
        p(&csv),
    ]));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| header.iter().position(|h| *h == n).unwrap();
    let (t, tc, gx, gy, gz) = (
        col("time_s"),
        col("temperature_c"),
        col("gx"),
        col("gy"),
        col("gz"),
    );
    let mut rows = Vec::new();
    let mut plain = String::from("time_s,gyr_x,gyr_y,gyr_z,temperature_c\n");
    for l in lines {
        let c: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
        let us = (c[t] * 1e6).round() as u64;
        // The log holds float32 rad/s: the CSV compared holds the same values.
        let w = [c[gx], c[gy], c[gz]].map(|d| (d.to_radians() as f32) as f64);
        let temp = (c[tc] as f32) as f64;
        rows.push(gyro_row(us, w, temp));
        plain.push_str(&format!(
            "{},{},{},{},{}\n",
            us as f64 / 1e6,
            w[0].to_degrees(),
            w[1].to_degrees(),
            w[2].to_degrees(),
            temp
        ));
    }
    let log = dir.join("thermal.ulg");
    std::fs::write(&log, ulog(SENSOR_GYRO, &rows)).unwrap();
    let flat = dir.join("thermal_f32.csv");
    std::fs::write(&flat, plain).unwrap();
    let reduce = |f: &PathBuf, topic: &[&str]| {
        let mut a = vec![
            "thermal",
            "ramp",
            "--input",
            p(f),
            "--quantity",
            "gyro",
            "--json",
        ];
        a.extend(topic);
        json_of(&run(&a))
    };
    let from_log = reduce(&log, &["--topic", "sensor_gyro"]);
    let from_csv = reduce(&flat, &[]);
    let (a, b) = (coefficient_values(&from_log), coefficient_values(&from_csv));
    assert!(a.len() >= 6, "{a:?}");
    for ((na, va, ua), (nb, vb, _)) in a.iter().zip(&b) {
        assert_eq!(na, nb);
        assert!(
            (va - vb).abs() <= 1e-9 * va.abs().max(*ua),
            "{na}: {va} vs {vb}"
        );
    }
    assert_eq!(
        from_log["environment"]["temperature_c"]["count"],
        from_csv["environment"]["temperature_c"]["count"]
    );
}

#[test]
fn convert_writes_what_the_reductions_read() {
    let log = fixture("pyulog_sample_log_small.ulg");
    let text = ok(&run(&[
        "convert",
        "--input",
        p(&log),
        "--topic",
        "sensor_gyro:2",
    ]));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "format,PX4 ULog");
    assert!(
        lines.contains(&"time_s,gyr_x,gyr_y,gyr_z,temperature_c"),
        "{text}"
    );
    let out = workdir("robot_logs_convert").join("gyro2.csv");
    ok(&run(&[
        "convert",
        "--input",
        p(&log),
        "--topic",
        "sensor_gyro:2",
        "-o",
        p(&out),
    ]));
    assert_eq!(std::fs::read_to_string(&out).unwrap(), text);
    // `:0` names the first instance, as the bare name does.
    assert_eq!(
        ok(&run(&[
            "convert",
            "--input",
            p(&log),
            "--topic",
            "sensor_accel:0"
        ])),
        ok(&run(&[
            "convert",
            "--input",
            p(&log),
            "--topic",
            "sensor_accel"
        ]))
    );
}

#[test]
fn robot_logs_are_refused_naming_the_problem() {
    // In the scratch directory: messages are measured without its path.
    let dir = workdir("robot_logs_refused");
    let small = dir.join("pyulog_sample_log_small.ulg");
    std::fs::copy(fixture("pyulog_sample_log_small.ulg"), &small).unwrap();
    // Several topics: the message lists them.
    refused(
        &run(&["noise", "--input", p(&small)]),
        &[
            "pyulog_sample_log_small.ulg: a PX4 ULog: give --topic",
            "sensor_accel (instances 0, 1, 2), sensor_combined, sensor_gyro (instances 0, 1, 2)",
        ],
    );
    refused(
        &run(&["noise", "--input", p(&small), "--topic", "sensor_baro"]),
        &["--topic 'sensor_baro': not in this PX4 ULog"],
    );
    refused(
        &run(&[
            "noise",
            "--input",
            p(&small),
            "--topic",
            "sensor_combined",
            "--header-line",
            "3",
        ]),
        &["--header-line 3: a PX4 ULog has no header line to name"],
    );
    refused(
        &run(&["convert", "--input", p(&small), "--stamps", "gps"]),
        &["--stamps: 'gps': expected header or log"],
    );
    let csv = dir.join("plain.csv");
    std::fs::write(&csv, "time_s,gyr_x\n0,1\n0.01,2\n").unwrap();
    refused(
        &run(&["noise", "--input", p(&csv), "--topic", "/imu"]),
        &["plain.csv: --topic '/imu': not a PX4 ULog, a ROS 1 bag or an MCAP file"],
    );
    refused(
        &run(&["convert", "--input", p(&csv)]),
        &["plain.csv: not a PX4 ULog"],
    );
    // A bag cut in the middle of a record.
    let bag = std::fs::read(fixture("husky_rl_test1.bag")).unwrap();
    let cut = dir.join("cut.bag");
    std::fs::write(&cut, &bag[..bag.len() / 2]).unwrap();
    refused(
        &run(&["noise", "--input", p(&cut)]),
        &["cut.bag: a ROS 1 bag: a broken record at byte"],
    );
    // A ULog cut mid-message ends there (as a logger's power cut leaves it).
    let rows: Vec<Vec<u8>> = (0..50)
        .map(|k| gyro_row(k * 10_000, [0.01, 0.02, 0.03], 30.0))
        .collect();
    let mut bytes = ulog(SENSOR_GYRO, &rows);
    bytes.truncate(bytes.len() - 5);
    let cut = dir.join("cut.ulg");
    std::fs::write(&cut, &bytes).unwrap();
    let text = ok(&run(&["convert", "--input", p(&cut)]));
    assert_eq!(
        text.lines()
            .filter(|l| l.starts_with(|c: char| c.is_ascii_digit()))
            .count(),
        49
    );
    // An MCAP cut in its header.
    let mcap = std::fs::read(fixture("husky_rl_test1_imu_zstd.mcap")).unwrap();
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &mcap[..20]).unwrap();
    refused(
        &run(&["noise", "--input", p(&cut)]),
        &["cut.mcap: an MCAP file:"],
    );
}
