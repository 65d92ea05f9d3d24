//! The procedure registry: every procedure of incal, once.
//!
//! One [`Entry`] per procedure holds what the front ends and the documents
//! need to know about it: its id, the document id it writes, the command
//! that reduces it, its plan and simulator commands, its title, the rig
//! whose reference standards make it traceable, the method the certificate
//! states, the references it cites (keys of `docs/src/references.md`), its
//! chapter of the manual, its Python names, the fuzz targets that cover its
//! input, the run sheet of its plans, and its typed entry points (the
//! reduction, plan and simulator with options as JSON and their schemas).
//! Every other list of procedures is derived from [`REGISTRY`] (the
//! certificate's rig and method, the plan run sheet, `incal batch`, `incal
//! procedures`, Python's function tables, the fuzz targets) or checked
//! against it by a test that names what is missing where (the CLI's
//! subcommands, the fuzz seeds, Python's stubs, the README's table and the
//! manual's chapters).
//!
//! Adding a procedure: its folder `procedures/<name>/`, one entry here,
//! its CLI file, its chapter (CONTRIBUTING walks through it).

use crate::document::plan::PlanDocument;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The procedure that produced a document.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Procedure {
    /// Dividing-head tumble test (Wu et al. 2015; GJB 1037A).
    Tumble,
    /// Precision centrifuge (He & Yin 2017; IEEE Std 836).
    Centrifuge,
    /// Gyro misalignment on a rate table (Li et al. 2012).
    MisalignGyro,
    /// Accelerometer misalignment on a vertical face (Li et al. 2012).
    MisalignAccel,
    /// Gyro-free unit: K0 and Ks of every accelerometer (the GFIMU note).
    GfimuCalibrate,
    /// Gyro rate-transfer test on a rate table (IEEE Std 952 / 1431).
    GyroRate,
    /// Gyro multi-position test on a dividing head (IEEE Std 517 / 1431).
    GyroPositions,
    /// Noise and stability: Allan family, IEEE Std 952 terms, bias stability.
    Noise,
    /// IMU triad, Ferraris six-position + three-rotation method (imucal).
    ImuFerraris,
    /// IMU triad, least squares over known orientations.
    ImuMultipos,
    /// IMU triad, autocalibration without a fixture (Tedaldi et al. 2014).
    ImuAutocal,
    /// Thermal model: coefficients as polynomials in temperature, from
    /// soak plateaus or a chamber ramp (IEEE Std 1293 / 952; Niu et al.
    /// 2013).
    Thermal,
    /// Dynamic response by stepped sine: gain, phase, bandwidth and delay
    /// (IEEE Std 1431 §12.15, IEEE Std 1057 sine fits).
    ResponseSine,
    /// Dynamic response from a broadband record: H1 by Welch averaging,
    /// coherence (Bendat & Piersol).
    ResponseBroadband,
    /// Step response: the same model fitted in the time domain, rise time,
    /// overshoot, settling time and delay.
    ResponseStep,
    /// Turn-on time and warm-up from power-on at one temperature: the
    /// settled value, the warm-up curve, settling time and drift
    /// (IEEE Std 952 / 1431, GJB 2426A).
    Warmup,
    /// Repeatability turn-on to turn-on and day to day: variance
    /// components of one coefficient over runs (IEEE Std 952 / 1431, GJB
    /// 2426A, GJB 1037A).
    Repeatability,
    /// Threshold and resolution: the smallest input step answered at zero
    /// and at a base input (IEEE Std 952 / 1431, GJB 2426A, GJB 1037A).
    Threshold,
    /// Magnetometer calibration: hard iron, soft iron and the alignment to
    /// the accelerometer by a constrained ellipsoid fit (IEEE Std 1431
    /// §12.16 magnetic sensitivity; Kok & Schön 2014).
    Mag,
    /// Environmental sensitivities: vibration rectification and
    /// vibropendulous error, magnetic sensitivity, shift across a shock
    /// (IEEE Std 1293 / 952 / 1431).
    Sensitivity,
}

impl Procedure {
    /// Every document id, in registry order (each once).
    pub fn all() -> Vec<Procedure> {
        let mut out: Vec<Procedure> = Vec::new();
        for e in REGISTRY {
            if !out.contains(&e.document) {
                out.push(e.document);
            }
        }
        out
    }

    /// The procedure with document id `id`, if any.
    pub fn from_id(id: &str) -> Option<Procedure> {
        REGISTRY
            .iter()
            .map(|e| e.document)
            .find(|p| p.as_str() == id)
    }

    /// The procedure id as in the JSON (`tumble`, `misalign-gyro`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            Procedure::Tumble => "tumble",
            Procedure::Centrifuge => "centrifuge",
            Procedure::MisalignGyro => "misalign-gyro",
            Procedure::MisalignAccel => "misalign-accel",
            Procedure::GfimuCalibrate => "gfimu-calibrate",
            Procedure::GyroRate => "gyro-rate",
            Procedure::GyroPositions => "gyro-positions",
            Procedure::Noise => "noise",
            Procedure::ImuFerraris => "imu-ferraris",
            Procedure::ImuMultipos => "imu-multipos",
            Procedure::ImuAutocal => "imu-autocal",
            Procedure::Thermal => "thermal",
            Procedure::ResponseSine => "response-sine",
            Procedure::ResponseBroadband => "response-broadband",
            Procedure::ResponseStep => "response-step",
            Procedure::Warmup => "warmup",
            Procedure::Repeatability => "repeatability",
            Procedure::Threshold => "threshold",
            Procedure::Mag => "mag",
            Procedure::Sensitivity => "sensitivity",
        }
    }
}

impl std::fmt::Display for Procedure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What a procedure reduces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum InputKind {
    /// One recording (CSV or binary samples): `--input FILE`; `incal
    /// batch` runs it over many recordings.
    Recording,
    /// Result documents of earlier reductions (`thermal fit`).
    Results,
}

/// The settings of a plan in the order they are run, for the operator:
/// the column names of the settings and one row per step (without the
/// `step` and `samples` columns that [`PlanDocument::run_sheet`] adds).
pub type RunSheet = (Vec<&'static str>, Vec<Vec<String>>);

/// One procedure in the registry (module docs).
#[derive(Debug, Clone, Copy)]
pub struct Entry {
    /// The registry id: kebab-case, unique; the document id unless one
    /// document id is written by several commands (`thermal-ramp` and
    /// `thermal-fit` both write `thermal`).
    pub id: &'static str,
    /// The procedure id the result documents carry.
    pub document: Procedure,
    /// The command words that reduce it (`["gyro", "rate"]`).
    pub command: &'static [&'static str],
    /// The command words of its plan (`["plan", "gyro-rate"]`), if any.
    pub plan: Option<&'static [&'static str]>,
    /// The command words of its simulator (`["simulate", "gyro-rate"]`).
    pub simulate: Option<&'static [&'static str]>,
    /// One line for people, as the certificate's heading and the README.
    pub title: &'static str,
    /// The rig whose reference standards make its results traceable (one
    /// of the certificate's rigs); `None` when no rig standard enters the
    /// result (the instrument's own record and time base).
    pub rig: Option<&'static str>,
    /// The method as the certificate states it: standards and papers by
    /// title, authors, venue and year.
    pub method: &'static str,
    /// The references it cites: anchors of `docs/src/references.md`.
    pub references: &'static [&'static str],
    /// Its chapter of the manual (`docs/src/<chapter>`).
    pub chapter: &'static str,
    /// What it reduces.
    pub input: InputKind,
    /// The fuzz targets that cover its input (`incal_fuzz::targets`: each
    /// reduced by the typed reduction with [`super::Procedure::example`]).
    pub fuzz: &'static [&'static str],
    /// The run sheet of its plan documents, if its plans list settings.
    pub run_sheet: Option<fn(&PlanDocument) -> RunSheet>,
    /// A small worked case: the simulator's options and the reduction's
    /// options (after `--input FILE`) that reduce what it writes. Every
    /// front end's test runs it (the document's schema and snapshots,
    /// Python equals the CLI); `None` for a procedure that reduces result
    /// documents.
    pub example: Option<Example>,
    /// The typed reduction: its options' JSON Schema and the reduction with
    /// options as JSON ([`super::reduce_json`]); `None` for a procedure
    /// that reduces result documents.
    pub reduction: Option<Typed>,
    /// The typed plan ([`super::Plan`]), if any.
    pub planner: Option<Typed<PlanFn>>,
    /// The typed simulator ([`super::Simulate`]), if any.
    pub simulator: Option<Typed<SimulateFn>>,
}

/// A reduction with options as JSON ([`super::reduce_json`]).
pub type ReduceFn = fn(
    &str,
    &mut dyn std::io::Read,
    &incal_io::ReadOptions,
    &serde_json::Value,
    &dyn super::Progress,
    Option<&crate::montecarlo::MonteCarloOptions>,
) -> crate::Result<crate::document::ResultDocument>;

/// A plan with options as JSON ([`super::plan_json`]).
pub type PlanFn = fn(&serde_json::Value) -> crate::Result<PlanDocument>;

/// A simulator with options as JSON ([`super::simulate_json`]): the
/// recording into the writer, its truth returned where the recording does
/// not carry it ([`super::Simulate::truth`]).
pub type SimulateFn =
    fn(&serde_json::Value, &mut dyn std::io::Write) -> crate::Result<Option<serde_json::Value>>;

/// One typed entry point of a procedure: the JSON Schema of its options
/// (the keys every front end spells its own way) and the function.
#[derive(Debug, Clone, Copy)]
pub struct Typed<F = ReduceFn> {
    /// The options' JSON Schema ([`crate::options::schema_of`]).
    pub schema: fn() -> serde_json::Value,
    /// The entry point.
    pub run: F,
    /// Options of a small worked case as JSON, valid against `schema`
    /// ([`super::Procedure::example`]); `None` where the entry point has
    /// no example of its own.
    pub example: Option<fn() -> serde_json::Value>,
}

/// The typed reduction of procedure `P`.
pub const fn reduction<P: super::Procedure>() -> Option<Typed> {
    Some(Typed {
        schema: crate::options::schema_of::<P::Options>,
        run: super::reduce_json::<P>,
        example: Some(P::example_json),
    })
}

/// The typed plan `T`.
pub const fn planner<T: super::Plan>() -> Option<Typed<PlanFn>> {
    Some(Typed {
        schema: crate::options::schema_of::<T::Options>,
        run: super::plan_json::<T>,
        example: None,
    })
}

/// The typed simulator `T`.
pub const fn simulator<T: super::Simulate>() -> Option<Typed<SimulateFn>> {
    Some(Typed {
        schema: crate::options::schema_of::<T::Options>,
        run: super::simulate_json::<T>,
        example: None,
    })
}

/// A worked case of a procedure ([`Entry::example`]): `incal
/// <simulate…> <simulate options> -o FILE`, then `incal <command…>
/// --input FILE <options>`.
#[derive(Debug, Clone, Copy)]
pub struct Example {
    /// Options of the simulator (after its command words).
    pub simulate: &'static [&'static str],
    /// Options of the reduction (besides `--input`).
    pub options: &'static [&'static str],
}

impl Entry {
    /// The entry as JSON, as `incal procedures --json` prints it (without
    /// the command line's argument tables) and Python builds its functions
    /// from it: `id`, `document`, `title`, `command`, `plan`, `simulate`
    /// (command words joined by spaces), `input`, `rig`, `method`,
    /// `references`, `chapter`, `run_sheet`, `fuzz`, `example`, `python`
    /// (`function`, `plan`, `simulate`) and `options` (the JSON Schemas of
    /// the typed `reduce`, `plan` and `simulate`).
    pub fn to_json(&self) -> serde_json::Value {
        let words = |w: Option<&[&str]>| w.map(|w| w.join(" "));
        serde_json::json!({
            "id": self.id,
            "document": self.document.as_str(),
            "title": self.title,
            "command": self.command_line(),
            "plan": words(self.plan),
            "simulate": words(self.simulate),
            "input": self.input,
            "rig": self.rig,
            "method": self.method,
            "references": self.references,
            "chapter": self.chapter,
            "run_sheet": self.run_sheet.is_some(),
            "fuzz": self.fuzz,
            "example": self.example.map(|x| serde_json::json!({"simulate": x.simulate, "options": x.options})),
            "python": {
                "function": self.python(),
                "plan": self.python_plan(),
                "simulate": self.python_simulate(),
            },
            "options": {
                "reduce": self.reduction.map(|t| (t.schema)()),
                "plan": self.planner.map(|t| (t.schema)()),
                "simulate": self.simulator.map(|t| (t.schema)()),
            },
        })
    }

    /// The Python function of the reduction (`incal.gyro_rate`): the
    /// command words joined by `_`, with `-` as `_`.
    pub fn python(&self) -> String {
        python_name(self.command)
    }

    /// The Python function of its plan (`incal.plan.gyro_rate`).
    pub fn python_plan(&self) -> Option<String> {
        self.plan.map(|w| python_name(&w[1..]))
    }

    /// The Python function of its simulator (`incal.simulate.misalign_gyro`).
    pub fn python_simulate(&self) -> Option<String> {
        self.simulate.map(|w| python_name(&w[1..]))
    }

    /// The command line words of the reduction, space-separated.
    pub fn command_line(&self) -> String {
        self.command.join(" ")
    }
}

/// Command words as a Python name (`["misalign", "gyro"]` → `misalign_gyro`).
fn python_name(words: &[&str]) -> String {
    words.join("_").replace('-', "_")
}

/// The entry of registry id `id` (`_` accepted for `-`), if any.
pub fn find(id: &str) -> Option<&'static Entry> {
    let id = id.replace('_', "-");
    REGISTRY.iter().find(|e| e.id == id)
}

/// The entries that write documents of `procedure`, in registry order.
pub fn of(procedure: Procedure) -> impl Iterator<Item = &'static Entry> {
    REGISTRY.iter().filter(move |e| e.document == procedure)
}

/// The first entry that writes documents of `procedure` (every document
/// id has one: a test checks it).
pub fn first_of(procedure: Procedure) -> Option<&'static Entry> {
    of(procedure).next()
}

/// The entry that `incal batch ID` runs: by registry id, or by document id
/// when exactly one entry reducing a recording writes it (`thermal` is
/// `thermal-ramp`). Only procedures that reduce one recording.
pub fn batch(id: &str) -> Option<&'static Entry> {
    let key = id.replace('_', "-");
    let by_id = find(&key).filter(|e| e.input == InputKind::Recording);
    by_id.or_else(|| {
        let p = Procedure::from_id(&key)?;
        let mut it = of(p).filter(|e| e.input == InputKind::Recording);
        let e = it.next()?;
        it.next().is_none().then_some(e)
    })
}

/// The ids of the procedures `incal batch` runs, in registry order.
pub fn batch_ids() -> Vec<&'static str> {
    REGISTRY
        .iter()
        .filter(|e| e.input == InputKind::Recording)
        .map(|e| e.id)
        .collect()
}

const DIVIDING_HEAD: Option<&str> = Some("dividing-head");
const RATE_TABLE: Option<&str> = Some("rate-table");

const LI2012: &str = "Misalignment separation on a rate table: Li W., Ren S., Zhao H., Error separating technology for misalignment angle measurement of inertial component, Journal of Harbin Institute of Technology, 2012, vol. 44, no. 1, pp. 43-46";
const THERMAL_METHOD: &str = "Coefficients as polynomials in temperature from soak plateaus or a chamber ramp: IEEE Std 1293-2018 and IEEE Std 952-1997 (temperature sensitivity of bias and scale factor); Niu X., Li Y., Zhang H., Wang Q., Ban Y., Fast thermal calibration of low-grade inertial sensors and inertial measurement units, Sensors, 2013, vol. 13, no. 9, pp. 12192-12217";

/// Every procedure, in the order of the CLI's help and the README.
pub static REGISTRY: &[Entry] = &[
    Entry {
        id: "tumble",
        document: Procedure::Tumble,
        command: &["tumble"],
        plan: Some(&["plan", "tumble"]),
        simulate: Some(&["simulate", "tumble"]),
        title: "Tumble test on a dividing head",
        rig: DIVIDING_HEAD,
        method: "Multi-point tumble test on a dividing head: GJB 1037A-2004, Test methods for single-axis pendulous servo linear accelerometers; IEEE Std 1293-2018; Wu W., Nian H., Liu B., Cui J., Jiang X., 12-point tumble test method in a small angle for pendulous accelerometer with narrow input range, Navigation Positioning and Timing, 2015, no. 4, pp. 77-82",
        references: &["wu2015", "gjb1037a", "ieee1293"],
        chapter: "tumble.md",
        input: InputKind::Recording,
        fuzz: &["tumble"],
        run_sheet: Some(super::tumble::plan::run_sheet),
        example: Some(Example {
            simulate: &["--seed", "11", "--passes", "2"],
            options: &["--mount", "pendulum"],
        }),
        reduction: reduction::<super::tumble::Tumble>(),
        planner: planner::<super::tumble::Tumble>(),
        simulator: simulator::<super::tumble::Tumble>(),
    },
    Entry {
        id: "centrifuge",
        document: Procedure::Centrifuge,
        command: &["centrifuge"],
        plan: Some(&["plan", "centrifuge"]),
        simulate: Some(&["simulate", "centrifuge"]),
        title: "Precision centrifuge: radius, K2/K3, cross-axis and cross-coupling",
        rig: Some("centrifuge"),
        method: "Precision centrifuge test: IEEE Std 836-2009, IEEE Recommended Practice for Precision Centrifuge Testing of Linear Accelerometers; He Y., Yin X., Calibration for the cross-coupling coefficients of linear accelerometers base on precision centrifuge, Metrology & Measurement Technology, 2017, vol. 37, no. 3, pp. 51-55",
        references: &["he2017", "ieee836"],
        chapter: "centrifuge.md",
        input: InputKind::Recording,
        fuzz: &["centrifuge"],
        run_sheet: Some(super::centrifuge::plan::run_sheet),
        example: Some(Example {
            simulate: &["--seed", "12"],
            options: &["--k0", "1.2e-4", "--u-k0", "2e-6", "--k1", "1.3", "--u-k1", "1.3e-6", "--radius-m", "0.71", "--latitude-deg", "39.9"],
        }),
        reduction: reduction::<super::centrifuge::CentrifugeTest>(),
        planner: planner::<super::centrifuge::CentrifugeTest>(),
        simulator: simulator::<super::centrifuge::CentrifugeTest>(),
    },
    Entry {
        id: "misalign-gyro",
        document: Procedure::MisalignGyro,
        command: &["misalign", "gyro"],
        plan: Some(&["plan", "misalign"]),
        simulate: Some(&["simulate", "misalign", "gyro"]),
        title: "Gyro misalignment on a rate table",
        rig: RATE_TABLE,
        method: LI2012,
        references: &["li2012"],
        chapter: "misalignment.md",
        input: InputKind::Recording,
        fuzz: &["misalign-gyro", "misalign-gyro-raw"],
        run_sheet: Some(super::misalign::plan::run_sheet_gyro),
        example: Some(Example {
            simulate: &["--seed", "13"],
            options: &["--scale-factor", "-2.9222"],
        }),
        reduction: reduction::<super::misalign::MisalignGyro>(),
        planner: planner::<super::misalign::MisalignGyro>(),
        simulator: simulator::<super::misalign::MisalignGyro>(),
    },
    Entry {
        id: "misalign-accel",
        document: Procedure::MisalignAccel,
        command: &["misalign", "accel"],
        plan: Some(&["plan", "misalign"]),
        simulate: Some(&["simulate", "misalign", "accel"]),
        title: "Accelerometer misalignment on a vertical face",
        rig: RATE_TABLE,
        method: LI2012,
        references: &["li2012"],
        chapter: "misalignment.md",
        input: InputKind::Recording,
        fuzz: &["misalign-accel"],
        run_sheet: Some(super::misalign::plan::run_sheet_accel),
        example: Some(Example {
            simulate: &["--seed", "14"],
            options: &["--scale-factor", "1.299"],
        }),
        reduction: reduction::<super::misalign::MisalignAccel>(),
        planner: planner::<super::misalign::MisalignAccel>(),
        simulator: simulator::<super::misalign::MisalignAccel>(),
    },
    Entry {
        id: "gyro-rate",
        document: Procedure::GyroRate,
        command: &["gyro", "rate"],
        plan: Some(&["plan", "gyro-rate"]),
        simulate: Some(&["simulate", "gyro-rate"]),
        title: "Gyro rate-transfer test on a rate table",
        rig: RATE_TABLE,
        method: "Rate-transfer test on a rate table: IEEE Std 952-1997 §12.3; IEEE Std 1431-2004 §10.3",
        references: &["ieee952", "ieee1431"],
        chapter: "gyro.md",
        input: InputKind::Recording,
        fuzz: &["gyro-rate"],
        run_sheet: Some(super::gyro::rate::plan::run_sheet),
        example: Some(Example {
            simulate: &["--samples", "4", "--seed", "16"],
            options: &["--latitude-deg", "45"],
        }),
        reduction: reduction::<super::gyro::rate::GyroRate>(),
        planner: planner::<super::gyro::rate::GyroRate>(),
        simulator: simulator::<super::gyro::rate::GyroRate>(),
    },
    Entry {
        id: "gyro-positions",
        document: Procedure::GyroPositions,
        command: &["gyro", "positions"],
        plan: Some(&["plan", "gyro-positions"]),
        simulate: Some(&["simulate", "gyro-positions"]),
        title: "Gyro multi-position test on a dividing head",
        rig: DIVIDING_HEAD,
        method: "Multi-position test on a dividing head: IEEE Std 517-1974; IEEE Std 1431-2004 §10.3",
        references: &["ieee517", "ieee1431"],
        chapter: "gyro.md",
        input: InputKind::Recording,
        fuzz: &["gyro-positions"],
        run_sheet: Some(super::gyro::positions::plan::run_sheet),
        example: Some(Example {
            simulate: &["--samples", "4", "--seed", "17"],
            options: &["--latitude-deg", "45", "--azimuth-deg", "90", "--k1", "0.02", "--axial", "sa"],
        }),
        reduction: reduction::<super::gyro::positions::GyroPositions>(),
        planner: planner::<super::gyro::positions::GyroPositions>(),
        simulator: simulator::<super::gyro::positions::GyroPositions>(),
    },
    Entry {
        id: "imu-ferraris",
        document: Procedure::ImuFerraris,
        command: &["imu", "ferraris"],
        plan: Some(&["plan", "imu-ferraris"]),
        simulate: Some(&["simulate", "imu"]),
        title: "IMU triad, Ferraris six positions and three rotations",
        rig: RATE_TABLE,
        method: "Six positions and three rotations: Ferraris F., Grimaldi U., Parvis M., Procedure for effortless in-field calibration of three-axis rate gyros and accelerometers, Sensors and Materials, 1995, vol. 7, no. 5, pp. 311-330",
        references: &["ferraris1995", "imucal"],
        chapter: "imu.md",
        input: InputKind::Recording,
        fuzz: &["imu-ferraris"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--sequence", "ferraris", "--static-s", "0.5", "--rotation-s", "1", "--seed", "18"],
            options: &["--rate-hz", "100"],
        }),
        reduction: reduction::<super::imu::ferraris::Ferraris>(),
        planner: planner::<super::imu::plan::FerrarisPlan>(),
        simulator: simulator::<super::imu::sim::ImuSimulator>(),
    },
    Entry {
        id: "imu-multipos",
        document: Procedure::ImuMultipos,
        command: &["imu", "multipos"],
        plan: Some(&["plan", "imu-multipos"]),
        simulate: Some(&["simulate", "imu"]),
        title: "IMU triad, least squares over known orientations",
        rig: DIVIDING_HEAD,
        method: "Least squares over known static orientations of the triad (model of IEEE Std 1293-2018 per axis)",
        references: &["ieee1293"],
        chapter: "imu.md",
        input: InputKind::Recording,
        fuzz: &["imu-multipos"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--sequence", "positions", "--static-s", "0.3", "--rotations", "--seed", "19"],
            options: &["--rate-hz", "100"],
        }),
        reduction: reduction::<super::imu::multipos::Multipos>(),
        planner: planner::<super::imu::plan::MultiposPlan>(),
        simulator: simulator::<super::imu::sim::ImuSimulator>(),
    },
    Entry {
        id: "imu-autocal",
        document: Procedure::ImuAutocal,
        command: &["imu", "autocal"],
        plan: Some(&["plan", "imu-autocal"]),
        simulate: Some(&["simulate", "imu"]),
        title: "IMU triad, autocalibration without a fixture",
        rig: None,
        method: "Calibration without a fixture: Tedaldi D., Pretto A., Menegatti E., A robust and easy to implement method for IMU calibration without external equipments, Proc. IEEE ICRA 2014, pp. 3042-3049",
        references: &["tedaldi2014", "imu-tk"],
        chapter: "imu.md",
        input: InputKind::Recording,
        fuzz: &["imu-autocal"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--sequence", "random", "--orientations", "12", "--init-static-s", "3", "--static-s", "2", "--move-s", "1.5", "--seed", "20"],
            options: &["--rate-hz", "100", "--init-static-s", "3"],
        }),
        reduction: reduction::<super::imu::autocal::Autocal>(),
        planner: planner::<super::imu::plan::AutocalPlan>(),
        simulator: simulator::<super::imu::sim::ImuSimulator>(),
    },
    Entry {
        id: "gfimu-calibrate",
        document: Procedure::GfimuCalibrate,
        command: &["gfimu", "calibrate"],
        plan: Some(&["plan", "gfimu"]),
        simulate: Some(&["simulate", "gfimu"]),
        title: "Gyro-free unit: K0 and Ks of every accelerometer",
        rig: DIVIDING_HEAD,
        method: "Six-position static test of a gyro-free inertial unit of six accelerometers (model of IEEE Std 1293-2018 per accelerometer)",
        references: &["gfimu-note", "ieee1293"],
        chapter: "gfimu.md",
        input: InputKind::Recording,
        fuzz: &["gfimu-calibrate"],
        run_sheet: Some(super::gfimu::plan::run_sheet),
        example: Some(Example {
            simulate: &["--seed", "15"],
            options: &[],
        }),
        reduction: reduction::<super::gfimu::GfimuCalibrate>(),
        planner: planner::<super::gfimu::GfimuCalibrate>(),
        simulator: simulator::<super::gfimu::GfimuCalibrate>(),
    },
    Entry {
        id: "noise",
        document: Procedure::Noise,
        command: &["noise"],
        plan: Some(&["plan", "noise"]),
        simulate: Some(&["simulate", "noise"]),
        title: "Noise and stability: Allan family, IEEE 952 terms, bias stability",
        rig: None,
        method: "Noise analysis of a static record: IEEE Std 952-1997 Annex C; W. J. Riley, Handbook of Frequency Stability Analysis, NIST Special Publication 1065, 2008",
        references: &["ieee952", "nist1065", "gjb2426a"],
        chapter: "noise.md",
        input: InputKind::Recording,
        fuzz: &["noise"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--duration-s", "600", "--rate-hz", "100", "--arw-deg-rth", "0.1", "--bias-instability-deg-h", "5", "--seed", "21", "--format", "csv"],
            options: &["--rate-hz", "100"],
        }),
        reduction: reduction::<super::noise::Noise>(),
        planner: planner::<super::noise::plan::NoisePlan>(),
        simulator: simulator::<super::noise::Noise>(),
    },
    Entry {
        id: "thermal-ramp",
        document: Procedure::Thermal,
        command: &["thermal", "ramp"],
        plan: Some(&["plan", "thermal"]),
        simulate: Some(&["simulate", "thermal"]),
        title: "Thermal model from a chamber ramp: bias polynomials, hysteresis, lag",
        rig: Some("thermal-chamber"),
        method: THERMAL_METHOD,
        references: &["niu2013", "ieee1293", "ieee952"],
        chapter: "thermal.md",
        input: InputKind::Recording,
        fuzz: &["thermal-ramp"],
        run_sheet: Some(super::thermal::plan::run_sheet),
        example: Some(Example {
            simulate: &["--seed", "22", "--rate-hz", "1", "--hold-s", "300", "--ramp-c-per-min", "4"],
            options: &["--rate-hz", "1", "--quantity", "gyro"],
        }),
        reduction: reduction::<super::thermal::ramp::Ramp>(),
        planner: planner::<super::thermal::Thermal>(),
        simulator: simulator::<super::thermal::ramp::Ramp>(),
    },
    Entry {
        id: "thermal-fit",
        document: Procedure::Thermal,
        command: &["thermal", "fit"],
        plan: Some(&["plan", "thermal"]),
        simulate: Some(&["simulate", "thermal"]),
        title: "Thermal model from soak plateaus: coefficients as polynomials in temperature",
        rig: Some("thermal-chamber"),
        method: THERMAL_METHOD,
        references: &["niu2013", "ieee1293", "ieee952"],
        chapter: "thermal.md",
        input: InputKind::Results,
        fuzz: &["thermal-fit"],
        run_sheet: Some(super::thermal::plan::run_sheet),
        example: None,
        reduction: None,
        planner: planner::<super::thermal::Thermal>(),
        simulator: simulator::<super::thermal::ramp::Ramp>(),
    },
    Entry {
        id: "response-sine",
        document: Procedure::ResponseSine,
        command: &["response", "sine"],
        plan: Some(&["plan", "response-sine"]),
        simulate: Some(&["simulate", "response-sine"]),
        title: "Dynamic response by stepped sine: gain, phase, bandwidth and delay",
        rig: RATE_TABLE,
        method: "Frequency response by stepped sine (dwells) against a reference motion: IEEE Std 1431-2004 §12.15 and IEEE Std 1293-2018 (frequency response), ISO 16063-21:2003 (comparison with a reference transducer); sine fits by IEEE Std 1057-2017 §4.1.3; first- and second-order low-pass models with a pure delay fitted to gain and phase",
        references: &["ieee1431", "ieee1057", "iso16063-21", "ieee1293"],
        chapter: "response.md",
        input: InputKind::Recording,
        fuzz: &["response-sine"],
        run_sheet: Some(super::response::plan::run_sheet),
        example: Some(Example {
            simulate: &["--seed", "21"],
            options: &[],
        }),
        reduction: reduction::<super::response::ResponseSine>(),
        planner: planner::<super::response::ResponseSine>(),
        simulator: simulator::<super::response::ResponseSine>(),
    },
    Entry {
        id: "response-broadband",
        document: Procedure::ResponseBroadband,
        command: &["response", "broadband"],
        plan: Some(&["plan", "response-broadband"]),
        simulate: Some(&["simulate", "response-broadband"]),
        title: "Dynamic response from a broadband record: H1, coherence, bandwidth and delay",
        rig: RATE_TABLE,
        method: "Frequency response from a broadband excitation by the H1 estimator with Welch averaging and its coherence-based random errors: Bendat J. S., Piersol A. G., Random Data: Analysis and Measurement Procedures, 4th ed., Wiley, 2010; Welch P. D., The use of fast Fourier transform for the estimation of power spectra, IEEE Transactions on Audio and Electroacoustics, 1967, vol. AU-15, no. 2, pp. 70-73; IEEE Std 1431-2004 §12.15; first- and second-order low-pass models with a pure delay fitted to gain and phase",
        references: &["bendat-piersol", "welch1967", "ieee1431"],
        chapter: "response.md",
        input: InputKind::Recording,
        fuzz: &["response-broadband"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "22", "--duration-s", "20"],
            options: &["--segment-samples", "256"],
        }),
        reduction: reduction::<super::response::broadband::ResponseBroadband>(),
        planner: planner::<super::response::broadband::ResponseBroadband>(),
        simulator: simulator::<super::response::broadband::ResponseBroadband>(),
    },
    Entry {
        id: "response-step",
        document: Procedure::ResponseStep,
        command: &["response", "step"],
        plan: Some(&["plan", "response-step"]),
        simulate: Some(&["simulate", "response-step"]),
        title: "Step response: delay, rise time, overshoot, settling time and the model",
        rig: RATE_TABLE,
        method: "Step response to a rate or tilt step against the reference: IEEE Std 1431-2004 and IEEE Std 1293-2018 (dynamic response); first- and second-order low-pass models with a pure delay fitted in the time domain, rise time (10-90 %), overshoot and settling time from the fitted model",
        references: &["ieee1431", "ieee1293"],
        chapter: "response.md",
        input: InputKind::Recording,
        fuzz: &["response-step"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "23"],
            options: &[],
        }),
        reduction: reduction::<super::response::step::ResponseStep>(),
        planner: planner::<super::response::step::ResponseStep>(),
        simulator: simulator::<super::response::step::ResponseStep>(),
    },
    Entry {
        id: "warmup",
        document: Procedure::Warmup,
        command: &["warmup"],
        plan: Some(&["plan", "warmup"]),
        simulate: Some(&["simulate", "warmup"]),
        title: "Turn-on time and warm-up: settled value, warm-up curve, settling time and drift",
        rig: Some("thermal-chamber"),
        method: "Turn-on time and warm-up from power-on at constant temperature: IEEE Std 952-1997 and IEEE Std 1431-2004 (turn-on time and warm-up tests), GJB 2426A-2004, Test methods for fiber optic gyroscopes (start-up time); the output fitted by one or two exponentials and a linear drift chosen by a lack-of-fit test, on block means weighted by the long-run noise variance from batch means of the residuals",
        references: &["ieee952", "ieee1431", "gjb2426a"],
        chapter: "warmup.md",
        input: InputKind::Recording,
        fuzz: &["warmup"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "24", "--duration-s", "1800", "--rate-hz", "2"],
            options: &[],
        }),
        reduction: reduction::<super::warmup::Warmup>(),
        planner: planner::<super::warmup::Warmup>(),
        simulator: simulator::<super::warmup::Warmup>(),
    },
    Entry {
        id: "repeatability",
        document: Procedure::Repeatability,
        command: &["repeatability"],
        plan: Some(&["plan", "repeatability"]),
        simulate: Some(&["simulate", "repeatability"]),
        title: "Repeatability turn-on to turn-on and day to day: variance components of a coefficient",
        rig: None,
        method: "Bias and scale-factor repeatability turn-on to turn-on and day to day: IEEE Std 952-1997 and IEEE Std 1431-2004, GJB 2426A-2004 and GJB 1037A-2004; the variance components by a nested random-effects analysis of variance with each run's own u as its within-run variance (Paule-Mandel weighting where the runs' u differ by more than a factor of 3), degrees of freedom by Satterthwaite (JCGM 100:2008 G.4)",
        references: &["ieee952", "ieee1431", "gjb2426a", "gjb1037a", "paule-mandel", "jcgm100"],
        chapter: "repeatability.md",
        input: InputKind::Recording,
        fuzz: &["repeatability"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "25"],
            options: &[],
        }),
        reduction: reduction::<super::repeatability::Repeatability>(),
        planner: planner::<super::repeatability::Repeatability>(),
        simulator: simulator::<super::repeatability::Repeatability>(),
    },
    Entry {
        id: "threshold",
        document: Procedure::Threshold,
        command: &["threshold"],
        plan: Some(&["plan", "threshold"]),
        simulate: Some(&["simulate", "threshold"]),
        title: "Threshold and resolution: the smallest input step answered at zero and at a base input",
        rig: RATE_TABLE,
        method: "Threshold and resolution from steps of increasing size about zero and about a base input, a gyro on a rate table or an accelerometer tilted on a dividing head: IEEE Std 952-1997 and IEEE Std 1431-2004, GJB 2426A-2004, GJB 1037A-2004; each step size's output change against K1 times the step, noise of the plateau means from the record's revisits of its levels, a one-sided test at 5 % for reaching 50 %, and the 50 % point interpolated in 1/step between the sizes that bracket it",
        references: &["ieee952", "ieee1431", "gjb2426a", "gjb1037a", "fieller"],
        chapter: "threshold.md",
        input: InputKind::Recording,
        fuzz: &["threshold"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "26"],
            options: &[],
        }),
        reduction: reduction::<super::threshold::Threshold>(),
        planner: planner::<super::threshold::Threshold>(),
        simulator: simulator::<super::threshold::Threshold>(),
    },
    Entry {
        id: "mag",
        document: Procedure::Mag,
        command: &["mag"],
        plan: Some(&["plan", "mag"]),
        simulate: Some(&["simulate", "mag"]),
        title: "Magnetometer calibration: hard iron, soft iron and the alignment to the accelerometer",
        rig: None,
        method: "Magnetometer calibration from a session turned through many orientations in a uniform field: a constrained ellipsoid fit (hard-iron offset, symmetric positive-definite soft-iron matrix) by Gauss-Newton least squares on the magnitude of the calibrated field, and with an accelerometer the constant angle between gravity and the field for the alignment and the inclination: Kok M., Schon T. B., Maximum likelihood calibration of a magnetometer using inertial sensors, IFAC Proceedings, 2014, vol. 47, no. 3, pp. 92-97; Vasconcelos J. F., Elkaim G., Silvestre C., Oliveira P., Cardeira B., Geometric approach to strapdown magnetometer calibration in sensor frame, IEEE Transactions on Aerospace and Electronic Systems, 2011, vol. 47, no. 2, pp. 1293-1306; uncertainty by JCGM 100:2008 with the residuals' autocorrelation",
        references: &["kok2014", "vasconcelos2011", "geyer1992", "ieee1431", "jcgm100"],
        chapter: "mag.md",
        input: InputKind::Recording,
        fuzz: &["mag"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "27"],
            options: &["--field-ut", "50", "--inclination-deg", "60"],
        }),
        reduction: reduction::<super::mag::Mag>(),
        planner: planner::<super::mag::Mag>(),
        simulator: simulator::<super::mag::Mag>(),
    },
    Entry {
        id: "sensitivity",
        document: Procedure::Sensitivity,
        command: &["sensitivity"],
        plan: Some(&["plan", "sensitivity"]),
        simulate: Some(&["simulate", "sensitivity"]),
        title: "Environmental sensitivities: vibration rectification and vibropendulous error, magnetic sensitivity, shift across a shock",
        rig: Some("shaker"),
        method: "Sensitivity of the bias (and the scale factor) to vibration, magnetic field and shock from runs at several levels of the stimulus: IEEE Std 1293-2018, IEEE Standard Specification Format Guide and Test Procedure for Linear Single-Axis, Nongyroscopic Accelerometers (vibration rectification and vibropendulous error); IEEE Std 952-2020 and IEEE Std 1431-2004 (magnetic sensitivity and vibration sensitivity of gyros); the run means weighted by their joint covariance from the output's white, flicker and random-walk noise (Allan variance, NIST SP 1065), generalized least squares with the lack-of-fit rule choosing the order; uncertainty by JCGM 100:2008 with Welch-Satterthwaite degrees of freedom",
        references: &["ieee1293", "ieee952", "ieee1431", "nist1065", "jcgm100"],
        chapter: "sensitivity.md",
        input: InputKind::Recording,
        fuzz: &["sensitivity"],
        run_sheet: None,
        example: Some(Example {
            simulate: &["--seed", "28", "--run-s", "10", "--rate-hz", "20"],
            options: &[],
        }),
        reduction: reduction::<super::sensitivity::Sensitivity>(),
        planner: planner::<super::sensitivity::Sensitivity>(),
        simulator: simulator::<super::sensitivity::Sensitivity>(),
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_kebab_case_and_every_document_id_has_an_entry() {
        let mut seen = std::collections::BTreeSet::new();
        for e in REGISTRY {
            assert!(seen.insert(e.id), "procedure {}: listed twice", e.id);
            assert!(
                e.id.chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'),
                "procedure {}: the id is not kebab-case",
                e.id
            );
            assert!(
                e.id == e.document.as_str() || e.id.starts_with(e.document.as_str()),
                "procedure {}: the id does not begin with its document id {}",
                e.id,
                e.document
            );
            assert!(e.method.len() > 40, "procedure {}: no method", e.id);
            assert!(!e.references.is_empty(), "procedure {}: no reference", e.id);
            assert!(!e.fuzz.is_empty(), "procedure {}: no fuzz target", e.id);
            assert_eq!(
                e.example.is_some(),
                e.input == InputKind::Recording && e.simulate.is_some(),
                "procedure {}: a procedure that reduces a simulated recording has a worked example",
                e.id
            );
        }
        for p in Procedure::all() {
            assert!(first_of(p).is_some(), "document id {p}: no registry entry");
        }
    }

    #[test]
    fn document_ids_are_the_serde_names() {
        let all = Procedure::all();
        for p in &all {
            assert_eq!(serde_json::to_value(p).unwrap(), p.as_str(), "{p:?}");
            assert_eq!(Procedure::from_id(p.as_str()), Some(*p));
        }
        let ids: std::collections::BTreeSet<&str> = all.iter().map(|p| p.as_str()).collect();
        assert_eq!(ids.len(), all.len(), "a document id twice");
    }

    #[test]
    fn batch_finds_by_id_and_by_a_document_id_with_one_recording_entry() {
        assert_eq!(batch("gyro_rate").map(|e| e.id), Some("gyro-rate"));
        assert_eq!(batch("thermal").map(|e| e.id), Some("thermal-ramp"));
        assert_eq!(batch("thermal-ramp").map(|e| e.id), Some("thermal-ramp"));
        assert!(batch("thermal-fit").is_none());
        assert!(batch("tumbel").is_none());
        assert!(batch_ids().contains(&"thermal-ramp"));
    }

    #[test]
    fn python_names_follow_the_commands() {
        let e = find("misalign-gyro").unwrap();
        assert_eq!(e.python(), "misalign_gyro");
        assert_eq!(e.python_plan().as_deref(), Some("misalign"));
        assert_eq!(e.python_simulate().as_deref(), Some("misalign_gyro"));
        assert_eq!(find("gyro-rate").unwrap().python(), "gyro_rate");
    }
}
