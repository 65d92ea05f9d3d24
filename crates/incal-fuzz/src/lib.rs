//! incal's fuzz targets, in process: each target feeds arbitrary bytes to
//! the input layer ([`incal_io`]) and a procedure of the core through the
//! same calls every front end makes ([`incal::procedures::reduce_source`],
//! the document, limits and calibration parsers). No temporary file, no
//! process, no command line: a target costs what its reduction costs.
//!
//! The contract checked by [`check`]: no panic; an input is either
//! accepted, with an output that is one valid JSON document (or, for `imu
//! apply`, rows of finite numbers), or refused with one line of at most
//! [`MAX_MESSAGE`] characters.
//!
//! The targets run under `cargo fuzz` (`fuzz/` at the repository root) and
//! as a property-based pass in the normal test suite (`tests/fuzz_props.rs`).
//! Each target's valid seed (`seeds/`, written by the simulators:
//! `make-seeds.sh`) is compiled in.

use incal::document::ResultDocument;
use incal::estimation::Noise;
use incal::procedures::{reduce_source, Procedure, Silent};

/// Longest refusal message allowed (characters): one readable line.
pub const MAX_MESSAGE: usize = 400;

/// Every target: `(name, what the fuzzed bytes are)`.
pub const TARGETS: &[(&str, &str)] = &[
    ("tumble", "tumble CSV"),
    ("centrifuge", "centrifuge CSV"),
    ("misalign-gyro", "misalignment gyro CSV (record means)"),
    ("misalign-gyro-raw", "misalignment gyro CSV (raw records)"),
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
    ("thermal-ramp", "thermal chamber ramp CSV"),
    (
        "thermal-fit",
        "result document JSON at one plateau (thermal fit, beside two others)",
    ),
    (
        "imu-calibration",
        "IMU calibration JSON (imu apply --calibration)",
    ),
    ("result", "result document JSON (compare)"),
    ("limits", "limits TOML (--limits)"),
];

/// Executions of every target in the test suite (`tests/fuzz_props.rs`,
/// [`campaign`]): a fixed number per target, so CI does the same work on
/// every run; fewer for the targets that reduce a whole session per valid
/// input (a few seconds each in the test profile).
pub fn ci_executions(target: &str) -> u64 {
    match target {
        "imu-autocal" => 100,
        "gfimu-solve" | "noise" | "imu-ferraris" | "imu-multipos" | "imu-calibration"
        | "gfimu-calibration" => 600,
        _ => 2000,
    }
}

/// The bytes that break readers, spliced in by [`mutate`].
pub const TOKENS: &[&[u8]] = &[
    b"nan", b"inf", b"1e308", b"1e16", b"", b",", b"\n", b"-1", b"0", b"abc", b"\"", b"#",
];

/// xorshift64*: a fixed stream from a seed, so a campaign is reproducible.
#[derive(Debug, Clone)]
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in `0..n` (0 when `n` is 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// `base` with one to three mutations: a bit flipped, the tail cut, or a
/// span replaced by one of [`TOKENS`].
pub fn mutate(base: &[u8], r: &mut Rng) -> Vec<u8> {
    let mut v = base.to_vec();
    for _ in 0..1 + r.below(3) {
        let n = v.len().max(1);
        match r.below(3) {
            0 if !v.is_empty() => {
                let at = r.below(n);
                v[at] ^= 1 << r.below(8);
            }
            1 => v.truncate(r.below(n + 1)),
            _ => {
                let at = r.below(n).min(v.len());
                let end = (at + r.below(8)).min(v.len());
                let t = TOKENS[r.below(TOKENS.len())];
                v.splice(at..end, t.iter().copied());
            }
        }
    }
    v
}

/// What a campaign did: executions and how many inputs were accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Campaign {
    /// Inputs run.
    pub executions: u64,
    /// Inputs accepted (the rest refused with one line).
    pub accepted: u64,
}

/// Run `executions` mutations of `target`'s seed from the stream `seed`,
/// checking the contract ([`check`]) on each: the first broken one is the
/// error, with the input's size and the failure.
pub fn campaign(target: &str, executions: u64, seed_value: u64) -> Result<Campaign, String> {
    let base = seed(target);
    let mut r = Rng(seed_value | 1);
    let mut accepted = 0;
    for k in 0..executions {
        let data = mutate(base, &mut r);
        let Ok(outcome) = std::panic::catch_unwind(|| run(target, &data)) else {
            return Err(format!(
                "{target}: execution {k}: panicked on a {}-byte input",
                data.len()
            ));
        };
        check_outcome(target, &outcome).map_err(|e| {
            format!(
                "{target}: execution {k}: contract broken on a {}-byte input: {e}",
                data.len()
            )
        })?;
        if matches!(outcome, Outcome::Accepted(_)) {
            accepted += 1;
        }
    }
    Ok(Campaign {
        executions,
        accepted,
    })
}

/// A valid input of `target` (empty for an unknown target).
pub fn seed(target: &str) -> &'static [u8] {
    match target {
        "tumble" => include_bytes!("../seeds/tumble"),
        "centrifuge" => include_bytes!("../seeds/centrifuge"),
        "misalign-gyro" => include_bytes!("../seeds/misalign-gyro"),
        "misalign-gyro-raw" => include_bytes!("../seeds/misalign-gyro-raw"),
        "misalign-accel" => include_bytes!("../seeds/misalign-accel"),
        "gfimu-calibrate" => include_bytes!("../seeds/gfimu-calibrate"),
        "gfimu-geometry" => include_bytes!("../seeds/gfimu-geometry"),
        "gfimu-solve" => include_bytes!("../seeds/gfimu-solve"),
        "gfimu-calibration" => include_bytes!("../seeds/gfimu-calibration"),
        "gyro-rate" => include_bytes!("../seeds/gyro-rate"),
        "gyro-positions" => include_bytes!("../seeds/gyro-positions"),
        "noise" => include_bytes!("../seeds/noise"),
        "imu-ferraris" => include_bytes!("../seeds/imu-ferraris"),
        "imu-multipos" => include_bytes!("../seeds/imu-multipos"),
        "imu-autocal" => include_bytes!("../seeds/imu-autocal"),
        "thermal-ramp" => include_bytes!("../seeds/thermal-ramp"),
        "thermal-fit" => include_bytes!("../seeds/thermal-fit"),
        "imu-calibration" => include_bytes!("../seeds/imu-calibration"),
        "result" => include_bytes!("../seeds/result"),
        "limits" => include_bytes!("../seeds/limits"),
        _ => b"",
    }
}

/// What a target made of its bytes.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Accepted: the output as a front end would write it.
    Accepted(String),
    /// Refused: the one-line message a front end would show.
    Refused(String),
}

/// The name the fuzzed bytes go by in messages.
const NAME: &str = "input";

fn reduce<P: Procedure>(data: &[u8], options: &P::Options) -> Outcome {
    let read = incal_io::ReadOptions::default();
    match reduce_source::<P, _>(NAME, data, &read, options, &Silent) {
        Ok(doc) => Outcome::Accepted(doc.to_json()),
        Err(e) => Outcome::Refused(e.to_string()),
    }
}

fn document(data: &[u8]) -> Result<ResultDocument, String> {
    let text = std::str::from_utf8(data).map_err(|_| format!("{NAME}: not UTF-8 text"))?;
    ResultDocument::from_json(text).map_err(|e| format!("{NAME}: {e}"))
}

fn tumble_options() -> incal::procedures::tumble::TumbleOptions {
    incal::procedures::tumble::TumbleOptions::new(incal::rigs::Mount::Pendulum)
}

/// Run `target` on `data` (module docs). Panics only for an unknown target.
pub fn run(target: &str, data: &[u8]) -> Outcome {
    use incal::procedures::{centrifuge, gfimu, gyro, imu, misalign, noise, tumble};
    match target {
        "tumble" => reduce::<tumble::Tumble>(data, &tumble_options()),
        "centrifuge" => reduce::<centrifuge::CentrifugeTest>(data, &centrifuge_options()),
        "misalign-gyro" | "misalign-gyro-raw" => {
            reduce::<misalign::MisalignGyro>(data, &misalign::gyro::GyroOptions::new(-2.9222))
        }
        "misalign-accel" => {
            reduce::<misalign::MisalignAccel>(data, &misalign::accel::AccelOptions::new(1.299))
        }
        "gfimu-calibrate" => reduce::<gfimu::GfimuCalibrate>(
            data,
            &gfimu::GfimuCalibrateOptions {
                array: gfimu::input::ArrayChoice::default(),
                noise: Noise::Auto,
            },
        ),
        "gfimu-geometry" => {
            match gfimu::input::ArrayGeometry::from_toml(NAME, NAME, data, String::new()) {
                Ok(_) => reduce::<gfimu::GfimuCalibrate>(
                    seed("gfimu-calibrate"),
                    &gfimu::GfimuCalibrateOptions {
                        array: gfimu::input::ArrayChoice {
                            geometry: Some(gfimu::input::GeometryFile {
                                name: NAME.into(),
                                path: None,
                                sha256: Some(String::new()),
                                toml: String::from_utf8_lossy(data).into_owned(),
                            }),
                            ..Default::default()
                        },
                        noise: Noise::Auto,
                    },
                ),
                Err(e) => Outcome::Refused(e.to_string()),
            }
        }
        "gfimu-solve" => solve(seed("gfimu-calibration"), data),
        "gfimu-calibration" => solve(data, seed("gfimu-solve")),
        "gyro-rate" => reduce::<gyro::rate::GyroRate>(
            data,
            &gyro::rate::GyroRateOptions {
                latitude_deg: 45.0,
                ia: gyro::rate::InputAxis::Up,
                terms: gyro::rate::default_terms(),
                noise: Noise::Auto,
                rate_uncertainty_ppm: 0.0,
            },
        ),
        "gyro-positions" => {
            let axial = gyro::positions::Axial::Sa;
            reduce::<gyro::positions::GyroPositions>(
                data,
                &gyro::positions::GyroPositionsOptions {
                    azimuth_deg: Some(90.0),
                    ..gyro::positions::GyroPositionsOptions::new(45.0, axial, 0.02, None)
                },
            )
        }
        "noise" => reduce::<noise::Noise>(
            data,
            &noise::NoiseOptions {
                rate_hz: Some(100.0),
                // Sequential: a fuzzer's process stays on one thread.
                parallel: false,
                ..noise::NoiseOptions::default()
            },
        ),
        "imu-ferraris" => reduce::<imu::ferraris::Ferraris>(data, &ferraris_options()),
        "imu-multipos" => reduce::<imu::multipos::Multipos>(
            data,
            &imu::multipos::MultiposSessionOptions {
                gravity_m_s2: 9.81,
                matrix: imu::multipos::MatrixForm::Full,
                rate_hz: 100.0,
                latitude_deg: None,
                rotation_deg: -360.0,
            },
        ),
        "imu-autocal" => reduce::<imu::autocal::Autocal>(
            data,
            &imu::autocal::AutocalSessionOptions {
                rate_hz: 100.0,
                method: imu::autocal::Method::Incal,
                gravity_m_s2: 9.81,
                init_static_s: 3.0,
                settle_s: 0.1,
                init: Default::default(),
                sort_time: false,
                window_samples: 101,
                min_samples: 100,
            },
        ),
        "imu-calibration" => apply_imu(data, seed("imu-ferraris")),
        "thermal-ramp" => reduce::<incal::procedures::thermal::ramp::Ramp>(
            data,
            &incal::procedures::thermal::ramp::RampOptions::default(),
        ),
        "thermal-fit" => thermal_fit(data),
        "result" => compare_result(data),
        "limits" => limits(data),
        other => panic!("unknown fuzz target {other}"),
    }
}

/// `thermal fit`: the fuzzed result document beside the seed's result
/// at two other plateaus (0 and 50 degC), as `thermal fit A B C` reads
/// three files.
fn thermal_fit(data: &[u8]) -> Outcome {
    use incal::procedures::thermal::soak;
    let doc = match document(data) {
        Ok(d) => d,
        Err(e) => return Outcome::Refused(e),
    };
    let mut inputs = vec![soak::SoakInput {
        name: NAME.into(),
        sha256: String::new(),
        doc,
    }];
    for t in ["0", "50"] {
        let Ok(mut other) = document(seed("thermal-fit")) else {
            return Outcome::Refused("seed: not a result document".into());
        };
        other
            .instrument
            .meta
            .insert("temperature_c".into(), t.into());
        inputs.push(soak::SoakInput {
            name: format!("plateau-{t}"),
            sha256: String::new(),
            doc: other,
        });
    }
    match soak::fit_documents(&inputs, &soak::SoakOptions::default()) {
        Ok(doc) => Outcome::Accepted(doc.to_json()),
        Err(e) => Outcome::Refused(e.to_string()),
    }
}

/// The centrifuge options of the seed's run (`incal simulate centrifuge`).
fn centrifuge_options() -> incal::procedures::centrifuge::CentrifugeOptions {
    use incal::procedures::centrifuge;
    centrifuge::CentrifugeOptions {
        from: None,
        k0: Some(1.2e-4),
        u_k0: None,
        k1: Some(1.3),
        u_k1: None,
        cov_k0_k1: None,
        radius_m: 0.71,
        latitude_deg: 39.9,
        gravity_m_s2: incal::units::STANDARD_GRAVITY_M_S2,
        opposite_sense: false,
        order: 3,
        alignment_tolerance_deg: 0.0,
        noise: Noise::Auto,
        terms: None,
        u_omega_ppm: 0.0,
    }
}

/// `compare`: the fuzzed document against itself.
fn compare_result(data: &[u8]) -> Outcome {
    match document(data) {
        Ok(d) => match incal::document::compare::compare_documents("a", &d, "b", &d) {
            Ok(c) => Outcome::Accepted(c.to_json().to_string()),
            Err(e) => Outcome::Refused(e.to_string()),
        },
        Err(e) => Outcome::Refused(e),
    }
}

/// `--limits`: the fuzzed limits applied to the tumble seed's result.
fn limits(data: &[u8]) -> Outcome {
    use incal::procedures::tumble;
    {
        let limits = match std::str::from_utf8(data) {
            Ok(text) => incal::document::limits::Limits::parse(text),
            Err(_) => Err("not UTF-8 text".into()),
        };
        match limits {
            Ok(limits) => {
                let read = incal_io::ReadOptions::default();
                let doc = reduce_source::<tumble::Tumble, _>(
                    "tumble.csv",
                    seed("tumble"),
                    &read,
                    &tumble_options(),
                    &Silent,
                );
                match doc {
                    Ok(mut doc) => match incal::document::limits::apply(&mut doc, &limits) {
                        Ok(()) => Outcome::Accepted(doc.to_json()),
                        Err(e) => Outcome::Refused(format!("{NAME}: {e}")),
                    },
                    Err(e) => Outcome::Refused(format!("seed: {e}")),
                }
            }
            Err(e) => Outcome::Refused(format!("{NAME}: {e}")),
        }
    }
}

fn ferraris_options() -> incal::procedures::imu::ferraris::FerrarisOptions {
    incal::procedures::imu::ferraris::FerrarisOptions {
        rate_hz: 100.0,
        gravity_m_s2: 9.81,
        convention: Default::default(),
        rotation_deg: -360.0,
        u_rotation_deg: 0.0,
    }
}

fn builtin_array() -> Result<incal::procedures::gfimu::input::ArrayGeometry, String> {
    use incal::procedures::gfimu::input::{ArrayGeometry, Layout, DEFAULT_LEVER_ARM_M};
    ArrayGeometry::builtin(Layout::Paper, DEFAULT_LEVER_ARM_M).map_err(|e| e.to_string())
}

/// `gfimu solve`: a calibration document and a motion series, the
/// solution streamed as one JSON document into memory.
fn solve(calibration: &[u8], series: &[u8]) -> Outcome {
    use incal::procedures::gfimu::input::read_calibration;
    use incal::procedures::gfimu::solve::Solver;
    use incal::procedures::gfimu::stream::{solve_stream, MotionSeries, SolutionFormat};
    use incal::procedures::gfimu::SolveOptions;
    let array = match builtin_array() {
        Ok(a) => a,
        Err(e) => return Outcome::Refused(e),
    };
    let g = &array.geometry;
    let run = || -> Result<String, String> {
        let cal = read_calibration("calibration", calibration, g).map_err(|e| e.to_string())?;
        let solver = Solver::for_calibration("calibration", g, &cal, &SolveOptions::default())
            .map_err(|e| e.to_string())?;
        let series = MotionSeries::open("series", series, &incal_io::ReadOptions::default(), g)
            .map_err(|e| e.to_string())?;
        let mut out = Vec::new();
        solve_stream(series, solver, SolutionFormat::Json, &mut out, None)
            .map_err(|e| e.to_string())?;
        String::from_utf8(out).map_err(|_| "the solution is not UTF-8".to_string())
    };
    match run() {
        Ok(s) => Outcome::Accepted(s),
        Err(e) => Outcome::Refused(e),
    }
}

/// `imu apply`: a calibration document applied to a raw series, row by row
/// (the output: one line of numbers per row).
fn apply_imu(calibration: &[u8], raw: &[u8]) -> Outcome {
    use incal::procedures::imu::apply::ImuCalibration;
    let run = || -> Result<String, String> {
        let doc = document(calibration)?;
        let cal = ImuCalibration::from_document(&doc).map_err(|e| format!("{NAME}: {e}"))?;
        let read = incal_io::ReadOptions {
            hash: false,
            ..incal_io::ReadOptions::default()
        };
        let mut rows = incal_io::Reader::new("raw", raw, &read).map_err(|e| e.to_string())?;
        let cols = cal.columns(rows.header()).map_err(|e| e.to_string())?;
        let mut out = String::new();
        while let Some(row) = rows.next_row().map_err(|e| e.to_string())? {
            let r = cal.row(&cols, &row).map_err(|e| e.to_string())?;
            let mut line: Vec<f64> = r.time.into_iter().collect();
            line.extend(r.acc.iter());
            if let Some(g) = r.gyr {
                line.extend(g.iter());
            }
            let cells: Vec<String> = line.iter().map(|x| x.to_string()).collect();
            out.push_str(&cells.join(","));
            out.push('\n');
        }
        Ok(out)
    };
    match run() {
        Ok(s) => Outcome::Accepted(s),
        Err(e) => Outcome::Refused(e),
    }
}

/// [`run`] and the contract (module docs); `Err` says what broke it.
pub fn check(target: &str, data: &[u8]) -> Result<(), String> {
    check_outcome(target, &run(target, data))
}

/// The contract of [`check`] on an outcome already run.
pub fn check_outcome(target: &str, outcome: &Outcome) -> Result<(), String> {
    match outcome {
        Outcome::Accepted(out) if target == "imu-calibration" => {
            for (i, line) in out.lines().enumerate() {
                for f in line.split(',') {
                    match f.parse::<f64>() {
                        Ok(v) if v.is_finite() => {}
                        _ => return Err(format!("output row {}: '{f}'", i + 1)),
                    }
                }
            }
            Ok(())
        }
        Outcome::Accepted(out) => serde_json::from_str::<serde_json::Value>(out)
            .map(|_| ())
            .map_err(|e| format!("accepted with an output that is not JSON: {e}")),
        Outcome::Refused(m) => {
            if m.trim().is_empty() {
                Err("refused without a message".into())
            } else if m.contains('\n') {
                Err(format!("a message of several lines: {m:?}"))
            } else if m.chars().count() > MAX_MESSAGE {
                Err(format!(
                    "a message of {} characters: {}…",
                    m.chars().count(),
                    m.chars().take(120).collect::<String>()
                ))
            } else {
                Ok(())
            }
        }
    }
}
