//! One reader serves every reducing command: the same recording written
//! with a UTF-8 BOM, a `#` comment line, CRLF line ends and `;` delimiters
//! gives every command the same coefficients as the plain file.

use crate::common;
use common::*;

/// `(name, simulate args, reduce args)`; the reduce args get `--input`.
fn cases() -> Vec<(&'static str, Vec<&'static str>, Vec<&'static str>)> {
    vec![
        (
            "tumble",
            vec!["simulate", "tumble", "--samples", "3"],
            vec!["tumble", "--mount", "pendulum"],
        ),
        (
            "centrifuge",
            vec![
                "simulate",
                "centrifuge",
                "--levels-g",
                "0,1,4,9",
                "--samples",
                "3",
            ],
            vec![
                "centrifuge",
                "--k1",
                "1.3",
                "--k0",
                "1.2e-4",
                "--radius-m",
                "0.71",
                "--latitude-deg",
                "39.9",
            ],
        ),
        (
            "misalign-gyro",
            vec!["simulate", "misalign", "gyro"],
            vec!["misalign", "gyro", "--scale-factor", "-2.9222"],
        ),
        (
            "misalign-gyro-raw",
            vec![
                "simulate",
                "misalign",
                "gyro",
                "--time-series",
                "--records",
                "1",
            ],
            vec!["misalign", "gyro", "--scale-factor", "-2.9222"],
        ),
        (
            "misalign-accel",
            vec!["simulate", "misalign", "accel"],
            vec!["misalign", "accel", "--scale-factor", "1.299"],
        ),
        (
            "gyro-rate",
            vec!["simulate", "gyro-rate", "--samples", "4"],
            vec!["gyro", "rate", "--latitude-deg", "45"],
        ),
        (
            "gyro-positions",
            vec!["simulate", "gyro-positions", "--samples", "4"],
            vec![
                "gyro",
                "positions",
                "--latitude-deg",
                "45",
                "--azimuth-deg",
                "90",
                "--k1",
                "0.02",
                "--axial",
                "sa",
            ],
        ),
        (
            "imu-ferraris",
            vec![
                "simulate",
                "imu",
                "--sequence",
                "ferraris",
                "--static-s",
                "0.5",
                "--rotation-s",
                "1",
            ],
            vec!["imu", "ferraris", "--rate-hz", "100"],
        ),
        (
            "imu-multipos",
            vec![
                "simulate",
                "imu",
                "--sequence",
                "positions",
                "--static-s",
                "0.3",
            ],
            vec!["imu", "multipos", "--rate-hz", "100"],
        ),
        (
            "imu-autocal",
            vec![
                "simulate",
                "imu",
                "--sequence",
                "random",
                "--orientations",
                "12",
                "--init-static-s",
                "3",
                "--static-s",
                "2",
                "--move-s",
                "1.5",
            ],
            vec!["imu", "autocal", "--rate-hz", "100", "--init-static-s", "3"],
        ),
        (
            "gfimu-calibrate",
            vec!["simulate", "gfimu"],
            vec!["gfimu", "calibrate"],
        ),
        (
            "noise",
            vec![
                "simulate",
                "noise",
                "--duration-s",
                "20",
                "--rate-hz",
                "100",
            ],
            vec!["noise", "--rate-hz", "100", "--quiet"],
        ),
    ]
}

/// The file as another acquisition system writes it: BOM, a comment line,
/// CRLF, `;` between fields.
fn foreign(plain: &str) -> String {
    let mut s = String::from("\u{feff}# exported by a data-acquisition system\r\n");
    for line in plain.lines() {
        s.push_str(&line.replace(',', ";"));
        s.push_str("\r\n");
    }
    s
}

#[test]
fn every_reducing_command_reads_bom_comment_crlf_and_semicolons() {
    for (name, sim, reduce) in cases() {
        let plain = tmp(&format!("{name}.csv"));
        let mut s = sim.clone();
        s.extend_from_slice(&["--seed", "5", "-o", p(&plain)]);
        ok(&run(&s));
        let text = std::fs::read_to_string(&plain).unwrap();
        assert!(text.contains(','), "{name}: a CSV");
        let other = write(&format!("{name}-foreign.csv"), &foreign(&text));
        let result = |file: &std::path::Path| {
            let mut a = reduce.clone();
            a.extend_from_slice(&["--input", p(file), "--json"]);
            json_of(&run(&a))
        };
        let (a, b) = (result(&plain), result(&other));
        assert!(
            a["coefficients"].as_object().is_some_and(|c| !c.is_empty())
                || a["channels"].as_object().is_some_and(|c| !c.is_empty()),
            "{name}: {a}"
        );
        assert_eq!(a["coefficients"], b["coefficients"], "{name}");
        assert_eq!(a["channels"], b["channels"], "{name}");
        assert_eq!(a["inputs"][0]["rows"], b["inputs"][0]["rows"], "{name}");
        assert_ne!(a["inputs"][0]["sha256"], b["inputs"][0]["sha256"], "{name}");
    }
}
