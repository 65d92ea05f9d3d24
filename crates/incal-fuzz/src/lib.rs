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
//! The targets are derived from the procedure registry: every target a
//! registry entry names ([`incal::procedures::registry::Entry::fuzz`]) is
//! reduced by the entry's typed reduction with its example options
//! ([`incal::procedures::Procedure::example`]); [`EXTRA`] adds the inputs
//! that are not one procedure's recording (geometry, calibration and
//! result documents, limits). Each target's valid seed is the file of its
//! name in `seeds/` (written by the simulators: `make-seeds.sh`).

use std::collections::BTreeMap;
use std::sync::OnceLock;

use incal::document::{Procedure as Id, ResultDocument};
use incal::estimation::Noise;
use incal::procedures::registry::{InputKind, REGISTRY};
use incal::procedures::{reduce_source, Silent};

/// Longest refusal message allowed (characters): one readable line.
pub const MAX_MESSAGE: usize = 400;

/// The targets that are not one procedure's recording: `(name, what the
/// fuzzed bytes are)`.
pub const EXTRA: &[(&str, &str)] = &[
    ("gfimu-geometry", "gyro-free unit geometry TOML"),
    ("gfimu-solve", "gyro-free unit motion CSV"),
    (
        "gfimu-calibration",
        "gyro-free unit calibration JSON (gfimu solve --calibration)",
    ),
    (
        "imu-calibration",
        "IMU calibration JSON (imu apply --calibration)",
    ),
    ("result", "result document JSON (compare)"),
    ("limits", "limits TOML (--limits)"),
    (
        "thermal-model",
        "thermal model JSON (thermal apply, export px4 and ardupilot)",
    ),
    ("lab-profile", "laboratory profile TOML (report --lab)"),
    ("record-import", "records export JSON lines (record import)"),
    ("ulog", "PX4 ULog (noise)"),
    ("ros-bag", "ROS 1 bag (noise)"),
    ("mcap", "MCAP (noise)"),
];

/// Every target: `(name, what the fuzzed bytes are)`: those of the
/// registry's entries, in registry order, then [`EXTRA`].
pub fn targets() -> Vec<(&'static str, String)> {
    let mut out: Vec<(&'static str, String)> = Vec::new();
    for e in REGISTRY {
        for t in e.fuzz {
            let what = match e.input {
                InputKind::Recording => format!("{} recording ({})", e.command_line(), t),
                InputKind::Results => format!("result document JSON ({})", e.command_line()),
            };
            out.push((t, what));
        }
    }
    out.extend(EXTRA.iter().map(|(t, w)| (*t, (*w).to_string())));
    out
}

/// The target names of [`targets`].
pub fn target_names() -> Vec<&'static str> {
    targets().into_iter().map(|(t, _)| t).collect()
}

/// Executions of every target in the test suite (`tests/fuzz_props.rs`,
/// [`campaign`]): a fixed number per target, so CI does the same work on
/// every run; fewer for the targets whose seed is large (a whole session
/// per valid input): 1.6e7 bytes over the seed's size, from 100 to 2000.
pub fn ci_executions(target: &str) -> u64 {
    (16_000_000 / seed(target).len().max(1)).clamp(100, 2000) as u64
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

/// A valid input of `target`: the file `seeds/<target>` (empty for an
/// unknown target). The seeds are read once, on first use.
pub fn seed(target: &str) -> &'static [u8] {
    static SEEDS: OnceLock<BTreeMap<String, &'static [u8]>> = OnceLock::new();
    let seeds = SEEDS.get_or_init(|| {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds");
        let mut m = BTreeMap::new();
        for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            if let (Some(name), Ok(bytes)) = (e.file_name().to_str(), std::fs::read(e.path())) {
                m.insert(name.to_string(), &*Box::leak(bytes.into_boxed_slice()));
            }
        }
        m
    });
    seeds.get(target).copied().unwrap_or(b"")
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

/// Reduce `data` with the typed reduction of the registry entry whose
/// fuzz targets include `target`, with the entry's example options;
/// `None` when no entry with a typed reduction names it.
fn reduce(target: &str, data: &[u8]) -> Option<Outcome> {
    reduce_document(target, data).map(|r| match r {
        Ok(doc) => Outcome::Accepted(doc.to_json()),
        Err(e) => Outcome::Refused(e),
    })
}

/// [`reduce`]'s document itself (or its refusal), for the targets that
/// build on a reduced seed (`limits`).
fn reduce_document(target: &str, data: &[u8]) -> Option<Result<ResultDocument, String>> {
    let e = REGISTRY.iter().find(|e| e.fuzz.contains(&target))?;
    let typed = e.reduction?;
    let options = (typed.example?)();
    let read = incal_io::ReadOptions::default();
    let mut src = data;
    Some((typed.run)(NAME, &mut src, &read, &options, &Silent, None).map_err(|e| e.to_string()))
}

fn document(data: &[u8]) -> Result<ResultDocument, String> {
    let text = std::str::from_utf8(data).map_err(|_| format!("{NAME}: not UTF-8 text"))?;
    ResultDocument::from_json(text).map_err(|e| format!("{NAME}: {e}"))
}

/// Run `target` on `data` (module docs). Panics only for an unknown target.
pub fn run(target: &str, data: &[u8]) -> Outcome {
    use incal::procedures::gfimu;
    if let Some(outcome) = reduce(target, data) {
        return outcome;
    }
    match target {
        "gfimu-geometry" => {
            match gfimu::input::ArrayGeometry::from_toml(NAME, NAME, data, String::new()) {
                Ok(_) => {
                    let options = gfimu::GfimuCalibrateOptions {
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
                    };
                    let read = incal_io::ReadOptions::default();
                    let seed = seed(Id::GfimuCalibrate.as_str());
                    match reduce_source::<gfimu::GfimuCalibrate, _>(
                        NAME, seed, &read, &options, &Silent,
                    ) {
                        Ok(doc) => Outcome::Accepted(doc.to_json()),
                        Err(e) => Outcome::Refused(e.to_string()),
                    }
                }
                Err(e) => Outcome::Refused(e.to_string()),
            }
        }
        "gfimu-solve" => solve(seed("gfimu-calibration"), data),
        "gfimu-calibration" => solve(data, seed("gfimu-solve")),
        "imu-calibration" => apply_imu(data, seed(Id::ImuFerraris.as_str())),
        "result" => compare_result(data),
        "limits" => limits(data),
        "thermal-model" => thermal_model(data),
        "lab-profile" => lab_profile(data),
        "record-import" => record_import(data),
        // A robot log as a recording: the noise procedure reads it through
        // the input layer's decoding (incal_io::logs).
        "ulog" | "ros-bag" | "mcap" => reduce("noise", data).expect("noise is a registry target"),
        t if REGISTRY
            .iter()
            .any(|e| e.input == InputKind::Results && e.fuzz.contains(&t)) =>
        {
            thermal_fit(data, t)
        }
        other => panic!("unknown fuzz target {other}"),
    }
}

/// `thermal fit` (target `target`): the fuzzed result document beside the
/// seed's result at two other plateaus (0 and 50 degC), as `thermal fit A
/// B C` reads three files.
fn thermal_fit(data: &[u8], target: &str) -> Outcome {
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
        let Ok(mut other) = document(seed(target)) else {
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
    let limits = match std::str::from_utf8(data) {
        Ok(text) => incal::document::limits::Limits::parse(text),
        Err(_) => Err("not UTF-8 text".into()),
    };
    let limits = match limits {
        Ok(l) => l,
        Err(e) => return Outcome::Refused(format!("{NAME}: {e}")),
    };
    let tumble = Id::Tumble.as_str();
    let doc = reduce_document(tumble, seed(tumble))
        .unwrap_or_else(|| Err(format!("no typed reduction of {tumble}")));
    match doc {
        Ok(mut doc) => match incal::document::limits::apply(&mut doc, &limits) {
            Ok(()) => Outcome::Accepted(doc.to_json()),
            Err(e) => Outcome::Refused(format!("{NAME}: {e}")),
        },
        Err(e) => Outcome::Refused(format!("seed: {e}")),
    }
}

/// `thermal apply` of the fuzzed model to the thermal-ramp seed, and its
/// PX4 and ArduPilot exports: the outputs as one JSON document.
fn thermal_model(data: &[u8]) -> Outcome {
    use incal::procedures::thermal::{apply, export, Model};
    let run = || -> Result<String, String> {
        let doc = document(data)?;
        let model = Model::of(&doc).map_err(|e| format!("{NAME}: {e}"))?;
        let mut csv = Vec::new();
        let done = apply::apply(&model, "ramp", seed("thermal-ramp"), &mut csv)
            .map_err(|e| e.to_string())?;
        let px4 = export::px4(&model, None, 0, true).map_err(|e| e.to_string())?;
        let ap = export::ardupilot(&model, None, 1).map_err(|e| e.to_string())?;
        let values: Vec<f64> = px4
            .iter()
            .map(|p| p.1)
            .chain(ap.iter().map(|p| p.1))
            .collect();
        Ok(serde_json::json!({"rows": done.rows, "parameters": values}).to_string())
    };
    match run() {
        Ok(s) => Outcome::Accepted(s),
        Err(e) => Outcome::Refused(e),
    }
}

/// `report --lab`: the fuzzed profile's certificate of the result seed,
/// whose HTML must carry no element the profile's text could open.
fn lab_profile(data: &[u8]) -> Outcome {
    use incal_report::certificate::LabProfile;
    let run = || -> Result<String, String> {
        let text = std::str::from_utf8(data).map_err(|_| format!("{NAME}: not UTF-8 text"))?;
        let profile = LabProfile::parse(text).map_err(|e| format!("{NAME}: {e}"))?;
        let seed_text = std::str::from_utf8(seed("result")).map_err(|e| e.to_string())?;
        let doc = document(seed("result"))?;
        let cert = incal_report::stored::certificate(
            profile,
            seed_text,
            None,
            &incal_report::stored::Issue::default(),
        );
        let opts = incal_report::RenderOptions {
            date: Some("2026-01-01 00:00 UTC".into()),
            record: None,
            certificate: Some(cert),
        };
        let html = incal_report::render_html_with(&doc, &[], &opts).map_err(|e| e.to_string())?;
        // The page's own markup only: a profile opens no element.
        for tag in ["<script", "<img", "<iframe", "<object", "<embed", "<link"] {
            if html.contains(tag) {
                return Ok(format!("not JSON: the certificate holds {tag}"));
            }
        }
        if html.matches("</style>").count() != 1 {
            return Ok("not JSON: the profile closed the style element".into());
        }
        Ok(serde_json::json!({"html_bytes": html.len()}).to_string())
    };
    match run() {
        Ok(s) => Outcome::Accepted(s),
        Err(e) => Outcome::Refused(e),
    }
}

/// `record import` of the fuzzed lines into a new store (a file of its own
/// in the temporary directory, removed after): imported whole or refused
/// whole, with the store then verified.
fn record_import(data: &[u8]) -> Outcome {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    let path = std::env::temp_dir().join(format!(
        "incal-fuzz-import-{}-{}.db",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    ));
    let run = || -> Result<String, String> {
        let done = incal_records::Store::import_at(&path, data, NAME).map_err(|e| e.to_string())?;
        if done.added + done.present == 0 {
            // Nothing to import (the CLI says "imported 0 records").
            return Err(format!("{NAME}: no record to import"));
        }
        let store = incal_records::Store::open_existing(&path).map_err(|e| e.to_string())?;
        let v = store
            .verify()
            .map_err(|e| format!("imported, then verify failed: {e}"))?;
        if v.records != done.chain.records || v.head != done.chain.head {
            return Ok("not JSON: the chain verified is not the chain imported".into());
        }
        Ok(serde_json::json!({"added": done.added, "records": v.records}).to_string())
    };
    let out = run();
    incal_records::remove_sqlite_files(&path);
    match out {
        Ok(s) => Outcome::Accepted(s),
        Err(e) => Outcome::Refused(e),
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
