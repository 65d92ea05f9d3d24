//! Fuzz targets: every reader of the tool, run through the whole parse +
//! reduce path of the real command line ([`crate::main_from`]) on arbitrary
//! bytes. The contract checked by [`check`]: no panic, an exit code of 0 or
//! 2 (1 is only for failing to write an output, which does not happen
//! here), and on success an output that is one valid JSON document (so no
//! NaN or infinity can hide in it).
//!
//! The same targets run under `cargo fuzz` (`fuzz/` at the repository
//! root, README "Development") and as a quick property-based pass in the
//! normal test suite (`crates/incal-cli/tests/fuzz_props.rs`).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::OnceLock;

/// Silences the one-line messages on stderr while fuzzing.
pub static QUIET: AtomicBool = AtomicBool::new(false);

/// Every target: `(name, what the fuzzed bytes are)`.
pub const TARGETS: &[(&str, &str)] = &[
    ("tumble", "tumble CSV"),
    ("centrifuge", "centrifuge CSV"),
    ("misalign-gyro", "misalignment gyro CSV"),
    ("misalign-accel", "misalignment accelerometer CSV"),
    ("gfimu-calibrate", "gyro-free unit static CSV"),
    ("gfimu-geometry", "gyro-free unit geometry TOML"),
    ("gfimu-solve", "gyro-free unit motion CSV"),
    (
        "gfimu-calibration",
        "gyro-free unit calibration JSON (gfimu solve --calibration)",
    ),
    ("gyro-rate", "gyro rate-transfer CSV"),
    ("gyro-positions", "gyro multi-position CSV"),
    ("noise", "noise CSV"),
    ("imu-ferraris", "IMU Ferraris session CSV"),
    ("imu-multipos", "IMU multi-position CSV"),
    ("imu-autocal", "IMU autocalibration CSV"),
    (
        "imu-calibration",
        "IMU calibration JSON (imu apply --calibration)",
    ),
    ("result", "result document JSON (compare)"),
    ("limits", "limits TOML (--limits)"),
];

fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("incal-fuzz-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&d);
        d
    })
}

fn unique(name: &str) -> PathBuf {
    static N: AtomicU64 = AtomicU64::new(0);
    let k = N.fetch_add(1, Ordering::Relaxed);
    scratch().join(format!("{k}-{name}"))
}

fn os(args: &[&str]) -> Vec<OsString> {
    std::iter::once("incal")
        .chain(args.iter().copied())
        .map(OsString::from)
        .collect()
}

/// A valid input of each kind, from the simulators (made once).
pub fn seed(target: &str) -> Vec<u8> {
    static SEEDS: OnceLock<Vec<(String, Vec<u8>)>> = OnceLock::new();
    let seeds = SEEDS.get_or_init(make_seeds);
    seeds
        .iter()
        .find(|(n, _)| n == target)
        .map(|(_, b)| b.clone())
        .unwrap_or_default()
}

fn sim(args: &[&str], name: &str) -> Vec<u8> {
    let out = unique(name);
    let mut a: Vec<&str> = args.to_vec();
    let o = out.to_string_lossy().to_string();
    a.extend_from_slice(&["-o", &o]);
    crate::main_from(&os(&a));
    std::fs::read(&out).unwrap_or_default()
}

fn file(name: &str, bytes: &[u8]) -> String {
    let p = unique(name);
    let _ = std::fs::write(&p, bytes);
    p.to_string_lossy().to_string()
}

fn make_seeds() -> Vec<(String, Vec<u8>)> {
    let was = QUIET.swap(true, Ordering::Relaxed);
    let tumble = sim(&["simulate", "tumble", "--seed", "3"], "tumble.csv");
    let gfimu_static = sim(&["simulate", "gfimu", "--seed", "3"], "gfimu.csv");
    let gfimu_motion = sim(
        &[
            "simulate",
            "gfimu",
            "--kind",
            "motion",
            "--duration-s",
            "0.2",
            "--seed",
            "3",
        ],
        "motion.csv",
    );
    let gfimu_cal = {
        let p = file("gfimu_static.csv", &gfimu_static);
        sim(
            &["gfimu", "calibrate", "--input", &p, "--json"],
            "gfimu_cal.json",
        )
    };
    let ferraris = sim(
        &[
            "simulate",
            "imu",
            "--sequence",
            "ferraris",
            "--static-s",
            "0.5",
            "--rotation-s",
            "1",
        ],
        "ferraris.csv",
    );
    let imu_cal = {
        let p = file("ferraris_in.csv", &ferraris);
        sim(
            &[
                "imu",
                "ferraris",
                "--input",
                &p,
                "--rate-hz",
                "100",
                "--json",
            ],
            "imu_cal.json",
        )
    };
    let result = {
        let p = file("tumble_in.csv", &tumble);
        sim(
            &["tumble", "--mount", "pendulum", "--input", &p, "--json"],
            "result.json",
        )
    };
    let seeds = vec![
        ("tumble".to_string(), tumble),
        ("centrifuge".into(), sim(&["simulate", "centrifuge", "--levels-g", "0,1,4,9", "--samples", "3"], "cf.csv")),
        ("misalign-gyro".into(), sim(&["simulate", "misalign", "gyro"], "mg.csv")),
        ("misalign-accel".into(), sim(&["simulate", "misalign", "accel"], "ma.csv")),
        ("gfimu-calibrate".into(), gfimu_static),
        (
            "gfimu-geometry".into(),
            concat!(
                "[[accelerometer]]\nname = \"a\"\nposition_m = [0.1, 0.0, 0.0]\ndirection = [0.0, 0.0, 1.0]\n",
                "[[accelerometer]]\nname = \"b\"\nposition_m = [-0.1, 0.0, 0.0]\ndirection = [0.0, 0.0, 1.0]\n",
                "[[accelerometer]]\nname = \"c\"\nposition_m = [0.0, 0.1, 0.0]\ndirection = [1.0, 0.0, 0.0]\n",
                "[[accelerometer]]\nname = \"d\"\nposition_m = [0.0, -0.1, 0.0]\ndirection = [1.0, 0.0, 0.0]\n",
                "[[accelerometer]]\nname = \"e\"\nposition_m = [0.0, 0.0, 0.1]\ndirection = [0.0, 1.0, 0.0]\n",
                "[[accelerometer]]\nname = \"f\"\nposition_m = [0.0, 0.0, -0.1]\ndirection = [0.0, 1.0, 0.0]\n",
            )
            .as_bytes()
            .to_vec(),
        ),
        ("gfimu-solve".into(), gfimu_motion),
        ("gfimu-calibration".into(), gfimu_cal),
        ("gyro-rate".into(), sim(&["simulate", "gyro-rate", "--samples", "4"], "gr.csv")),
        ("gyro-positions".into(), sim(&["simulate", "gyro-positions", "--samples", "4"], "gp.csv")),
        ("noise".into(), sim(&["simulate", "noise", "--duration-s", "20", "--rate-hz", "100", "--seed", "3"], "noise.csv")),
        ("imu-ferraris".into(), ferraris),
        (
            "imu-multipos".into(),
            sim(&["simulate", "imu", "--sequence", "positions", "--static-s", "0.3"], "mp.csv"),
        ),
        (
            "imu-autocal".into(),
            sim(
                &[
                    "simulate", "imu", "--sequence", "random", "--orientations", "12",
                    "--init-static-s", "3", "--static-s", "2", "--move-s", "1.5",
                ],
                "ac.csv",
            ),
        ),
        ("imu-calibration".into(), imu_cal),
        ("result".into(), result),
        (
            "limits".into(),
            b"rule = \"guard-band\"\n[tumble]\nK0 = { min = -10000, max = 10000, unit = \"ug\" }\nK1 = { min = 9.99, max = 10.01 }\n".to_vec(),
        ),
    ];
    QUIET.store(was, Ordering::Relaxed);
    seeds
}

/// Run `target` on `data`: the exit code and the output (when written).
pub fn run(target: &str, data: &[u8]) -> (u8, Option<Vec<u8>>) {
    QUIET.store(true, Ordering::Relaxed);
    let input = file("input", data);
    let out = unique("out");
    let o = out.to_string_lossy().to_string();
    let fixed = |t: &str, name: &str| file(name, &seed(t));
    let args: Vec<String> = match target {
        "tumble" => vec!["tumble", "--mount", "pendulum", "--input", &input, "--json"]
            .into_iter()
            .map(String::from)
            .collect(),
        "centrifuge" => [
            "centrifuge",
            "--input",
            &input,
            "--k1",
            "1.3",
            "--k0",
            "1.2e-4",
            "--radius-m",
            "0.71",
            "--latitude-deg",
            "39.9",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "misalign-gyro" => [
            "misalign",
            "gyro",
            "--input",
            &input,
            "--scale-factor",
            "-2.9222",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "misalign-accel" => [
            "misalign",
            "accel",
            "--input",
            &input,
            "--scale-factor",
            "1.299",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "gfimu-calibrate" => ["gfimu", "calibrate", "--input", &input, "--json"]
            .map(String::from)
            .to_vec(),
        "gfimu-geometry" => {
            let csv = fixed("gfimu-calibrate", "static.csv");
            [
                "gfimu",
                "calibrate",
                "--geometry",
                &input,
                "--input",
                &csv,
                "--json",
            ]
            .map(String::from)
            .to_vec()
        }
        "gfimu-solve" => {
            let cal = fixed("gfimu-calibration", "cal.json");
            [
                "gfimu",
                "solve",
                "--calibration",
                &cal,
                "--input",
                &input,
                "--json",
            ]
            .map(String::from)
            .to_vec()
        }
        "gfimu-calibration" => {
            let motion = fixed("gfimu-solve", "motion.csv");
            [
                "gfimu",
                "solve",
                "--calibration",
                &input,
                "--input",
                &motion,
                "--json",
            ]
            .map(String::from)
            .to_vec()
        }
        "gyro-rate" => [
            "gyro",
            "rate",
            "--input",
            &input,
            "--latitude-deg",
            "45",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "gyro-positions" => [
            "gyro",
            "positions",
            "--input",
            &input,
            "--latitude-deg",
            "45",
            "--azimuth-deg",
            "90",
            "--k1",
            "0.02",
            "--axial",
            "sa",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "noise" => [
            "noise",
            "--input",
            &input,
            "--rate-hz",
            "100",
            "--quiet",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "imu-ferraris" => [
            "imu",
            "ferraris",
            "--input",
            &input,
            "--rate-hz",
            "100",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "imu-multipos" => [
            "imu",
            "multipos",
            "--input",
            &input,
            "--rate-hz",
            "100",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "imu-autocal" => [
            "imu",
            "autocal",
            "--input",
            &input,
            "--rate-hz",
            "100",
            "--init-static-s",
            "3",
            "--json",
        ]
        .map(String::from)
        .to_vec(),
        "imu-calibration" => {
            let raw = fixed("imu-ferraris", "raw.csv");
            ["imu", "apply", "--calibration", &input, "--input", &raw]
                .map(String::from)
                .to_vec()
        }
        "result" => ["compare", &input, &input, "--json"]
            .map(String::from)
            .to_vec(),
        "limits" => {
            let csv = fixed("tumble", "t.csv");
            [
                "tumble", "--mount", "pendulum", "--input", &csv, "--limits", &input, "--json",
            ]
            .map(String::from)
            .to_vec()
        }
        other => panic!("unknown fuzz target {other}"),
    };
    let mut a: Vec<&str> = args.iter().map(String::as_str).collect();
    a.extend_from_slice(&["-o", &o]);
    let code = crate::main_from(&os(&a));
    let written = std::fs::read(&out).ok();
    let _ = std::fs::remove_file(&input);
    let _ = std::fs::remove_file(&out);
    (code, written)
}

/// [`run`] and the contract (module docs); `Err` says what broke it.
pub fn check(target: &str, data: &[u8]) -> Result<(), String> {
    let (code, out) = run(target, data);
    match code {
        0 => {
            let Some(out) = out else {
                return Err("exit 0 without an output".into());
            };
            if target == "imu-calibration" {
                // A CSV: every field a finite number.
                let text = String::from_utf8_lossy(&out);
                for (i, line) in text.lines().enumerate().skip(1) {
                    for f in line.split(',') {
                        match f.parse::<f64>() {
                            Ok(v) if v.is_finite() => {}
                            _ => return Err(format!("output line {}: '{f}'", i + 1)),
                        }
                    }
                }
                return Ok(());
            }
            serde_json::from_slice::<serde_json::Value>(&out)
                .map(|_| ())
                .map_err(|e| format!("exit 0 with an output that is not JSON: {e}"))
        }
        2 => Ok(()),
        c => Err(format!("exit code {c}")),
    }
}

/// Remove the scratch directory (end of a test run).
pub fn cleanup() {
    let _ = std::fs::remove_dir_all(scratch());
}

/// The scratch directory of this process.
pub fn scratch_dir() -> &'static Path {
    scratch()
}
