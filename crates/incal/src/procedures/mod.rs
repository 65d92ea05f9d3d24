//! Calibration procedures: test plan + rig kinematics + linear(ised) model +
//! map to physical coefficients, all on [`crate::estimation`].
//!
//! # One shape
//! Every reducing procedure is one folder,
//! `procedures/<name>/{mod,input,plan,sim,document}.rs` (model and map,
//! columns/segmentation/checks, plan, simulator, result document), and
//! implements [`Procedure`]: options validated once, rows read through the
//! input layer ([`incal_io`]) into observations, observations reduced into
//! the one result document. [`reduce_source`] runs the whole chain for any
//! front end (the CLI, Python, fuzzing on bytes): a front end only turns
//! its arguments into the procedure's options and renders the document.

pub mod centrifuge;
pub mod gfimu;
pub mod gyro;
pub mod imu;
pub mod mag;
pub mod misalign;
pub mod noise;
pub mod registry;
pub mod repeatability;
pub mod response;
pub mod segmented;
pub mod sensitivity;
pub mod sim_plan;
pub mod stream;
pub mod thermal;
pub mod threshold;
pub mod tumble;
pub mod warmup;

use std::io::Read;

use crate::document::{InputFile, ResultDocument};
use crate::error::{Error, Result};

/// Progress of a long reduction, rendered by the front end (a terminal
/// bar, a notebook widget) or ignored ([`Silent`]). The core never draws.
pub trait Progress: Sync {
    /// A stage of `len` steps begins (`what` names it for people).
    fn start(&self, _what: &str, _len: u64) {}
    /// `n` more steps of the current stage are done.
    fn advance(&self, _n: u64) {}
    /// The current stage is over.
    fn finish(&self) {}
}

/// No progress shown.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {}

/// One calibration procedure behind one shape (see the module docs).
pub trait Procedure {
    /// The procedure's id in result documents.
    const ID: crate::document::Procedure;
    /// The options of the reduction, validated by [`Procedure::validate`]
    /// and serialised (snake_case keys) into the document's `options`;
    /// read from JSON and published as a JSON Schema (`crate::options`).
    type Options: serde::Serialize + serde::de::DeserializeOwned + schemars::JsonSchema + Sync;
    /// Observations as the input layer reads them from a recording.
    type Input;

    /// Check the options once, before anything is read; every range check
    /// of the procedure lives here, not in a front end.
    fn validate(options: &Self::Options) -> Result<()>;

    /// The options of a small worked case: those that reduce what the
    /// procedure's simulator writes with its defaults (the rig and truth
    /// of `incal simulate`). The fuzz targets reduce their seeds with them
    /// and the registry publishes them ([`registry::Typed::example`]), so a
    /// front end can start from a valid set.
    fn example() -> Self::Options;

    /// [`Procedure::example`] as JSON a caller gives
    /// ([`reduce_json`] reads it back into the same options): the
    /// serialised options, unless the document's form of the options
    /// leaves out keys a caller gives (then the procedure adds them).
    fn example_json() -> serde_json::Value {
        serde_json::to_value(Self::example()).unwrap_or_default()
    }

    /// Columns, segmentation and checks: the rows of one recording into
    /// observations. Pure: the rows come from any source.
    fn read<R: Read>(
        rows: &mut incal_io::Reader<R>,
        options: &Self::Options,
    ) -> Result<Self::Input>;

    /// The reduction: observations into the result document (its
    /// `inputs` and `options` are filled by [`reduce_source`]).
    fn reduce(
        input: &Self::Input,
        options: &Self::Options,
        progress: &dyn Progress,
    ) -> Result<ResultDocument>;

    /// The options as the document records them (`options`): as given,
    /// unless the procedure settles an option from the recording (the
    /// noise analysis' sample rate from `time_s`): then the value used.
    fn recorded(
        input: &Self::Input,
        options: &Self::Options,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        let _ = input;
        options_map(options)
    }

    /// The recipe of synthetic inputs for the Monte Carlo propagation
    /// (`--monte-carlo`, [`crate::montecarlo`]): the fitted model of the
    /// reduction `doc` of `input`, the sample noise as estimated and every
    /// type-B input with its distribution. `None` (the default) for a
    /// procedure that draws none yet: `--monte-carlo` is then refused.
    fn synthesis(
        input: &Self::Input,
        options: &Self::Options,
        doc: &ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Self::Input>>> {
        let _ = (input, options, doc);
        Ok(None)
    }
}

/// The test plan of a procedure: its options (engineering units, the keys
/// of the plan document's `options`) into an `incal.plan/1` document.
pub trait Plan {
    /// The plan's options.
    type Options: serde::Serialize + serde::de::DeserializeOwned + schemars::JsonSchema;

    /// Predict the plan: settings, run sheet and expected uncertainties.
    fn plan(options: &Self::Options) -> Result<crate::document::plan::PlanDocument>;
}

/// A rig simulator: its options (truth, rig, noise, seed; engineering
/// units) into a recording the procedure reads, written to `out`.
pub trait Simulate {
    /// The simulator's options.
    type Options: serde::Serialize + serde::de::DeserializeOwned + schemars::JsonSchema;

    /// Refuse options no simulation can use (before any output is opened).
    fn validate(options: &Self::Options) -> Result<()>;

    /// Draw the recording (same options and seed, same bytes) into `out`.
    fn simulate(options: &Self::Options, out: &mut dyn std::io::Write) -> Result<()>;

    /// The truth of a simulation whose recording does not carry it (the
    /// CSV holds rows only: the gyro-free unit's, the thermal chamber's and
    /// the IMU session's), as JSON: what `--truth-out` writes and Python's
    /// simulators return beside the rows. `None` (the default) where the
    /// recording's comment lines carry the truth.
    fn truth(options: &Self::Options) -> Result<Option<serde_json::Value>> {
        let _ = options;
        Ok(None)
    }
}

/// [`reduce_source`] with the options as JSON (a Python keyword dict, a
/// fuzz input): unknown, missing and mistyped keys are
/// [`Error::InvalidOption`] naming the key.
pub fn reduce_json<P: Procedure>(
    name: &str,
    src: &mut dyn Read,
    read: &incal_io::ReadOptions,
    options: &serde_json::Value,
    progress: &dyn Progress,
    monte_carlo: Option<&crate::montecarlo::MonteCarloOptions>,
) -> Result<ResultDocument> {
    let options: P::Options = crate::options::from_json(options)?;
    reduce_source_with::<P, _>(name, src, read, &options, progress, monte_carlo)
}

/// [`Plan::plan`] with the options as JSON.
pub fn plan_json<T: Plan>(
    options: &serde_json::Value,
) -> Result<crate::document::plan::PlanDocument> {
    T::plan(&crate::options::from_json(options)?)
}

/// [`Simulate::simulate`] with the options as JSON, validated first; the
/// simulation's [`Simulate::truth`] returned.
pub fn simulate_json<T: Simulate>(
    options: &serde_json::Value,
    out: &mut dyn std::io::Write,
) -> Result<Option<serde_json::Value>> {
    let options = crate::options::from_json(options)?;
    T::validate(&options)?;
    T::simulate(&options, out)?;
    T::truth(&options)
}

/// Read one recording (`src`, named `name` in messages and in the
/// document's inputs; `<stdin>` is recorded as `-`) and reduce it: validate
/// the options, read through the input layer, reduce, record the input's
/// SHA-256 and row count and the options. Every error names the file (and
/// the line and column when it has them).
pub fn reduce_source<P: Procedure, R: Read>(
    name: &str,
    src: R,
    read: &incal_io::ReadOptions,
    options: &P::Options,
    progress: &dyn Progress,
) -> Result<ResultDocument> {
    reduce_source_with::<P, R>(name, src, read, options, progress, None)
}

/// [`reduce_source`], then with `monte_carlo` the Monte Carlo propagation
/// of distributions ([`crate::montecarlo::run`]) on what was reduced: the
/// document's `monte_carlo` section and its warnings.
pub fn reduce_source_with<P: Procedure, R: Read>(
    name: &str,
    src: R,
    read: &incal_io::ReadOptions,
    options: &P::Options,
    progress: &dyn Progress,
    monte_carlo: Option<&crate::montecarlo::MonteCarloOptions>,
) -> Result<ResultDocument> {
    if let Some(mc) = monte_carlo {
        mc.validate()?;
    }
    P::validate(options)?;
    if let Ok(v) = serde_json::to_value(options) {
        crate::options::check_magnitudes(&v)?;
    }
    let (mut rows, original) = segmented::open(name, src, read)?;
    let preamble = match &original {
        Some(o) => o.summary.preamble.clone(),
        None => rows.preamble().to_vec(),
    };
    let stated = stated_rate::<P>(name, &preamble, options)?;
    let options = stated.as_ref().unwrap_or(options);
    // The options as given (and as the preamble settled them) are recorded;
    // a plateau's u carried into a type-B input is in `segmentation`.
    let given = options;
    let carried = match &original {
        Some(o) => segmented::carry::<P>(options, o)?,
        None => None,
    };
    let options = carried.as_ref().map_or(options, |c| &c.0);
    let input = P::read(&mut rows, options).map_err(|e| e.in_file(name))?;
    let read_back = rows.finish()?;
    // A segmented log: the file's own hash, rows, environment and clipped
    // runs, not those of the plateaus' text.
    let summary = match &original {
        Some(o) => o.summary.clone(),
        None => read_back,
    };
    let mut doc = P::reduce(&input, options, progress).map_err(|e| e.in_file(name))?;
    if let Some(mc) = monte_carlo {
        let (section, warnings) = crate::montecarlo::run::<P>(&input, options, &doc, mc, progress)?;
        doc.monte_carlo = Some(section);
        doc.warnings.extend(warnings);
    }
    if let Some(o) = &original {
        segmented::record(&mut doc, o, carried.as_ref().map(|c| (c.1, c.2)))?;
    }
    let path = if name == incal_io::source::STDIN_NAME {
        "-"
    } else {
        name
    };
    doc.inputs.insert(
        0,
        InputFile {
            role: "input".into(),
            path: path.into(),
            sha256: summary.sha256,
            rows: Some(summary.rows as u64),
        },
    );
    doc.options = P::recorded(&input, given)?;
    // What the document echoes (some options are recorded apart from the
    // options' own form, such as a K1 and its source).
    for (key, value) in &doc.options {
        crate::options::check_magnitudes_at(value, key)?;
    }
    record_environment(&mut doc, &summary.conditions);
    record_preamble(&mut doc, &preamble);
    doc.warnings.extend(clipped_warnings(&summary.clipped));
    Ok(doc)
}

/// A sample rate the recording's preamble states
/// ([`incal_io::stated_rate_hz`], e.g. `Fs,100`) against the options'
/// `rate_hz`: refused naming the line when they differ by more than
/// [`crate::timebase::RATE_TOLERANCE`]; the options with `rate_hz` set to
/// it when the option was not given (`None` when nothing changes: no rate
/// stated, or no `rate_hz` option).
fn stated_rate<P: Procedure>(
    name: &str,
    preamble: &[incal_io::PreambleLine],
    options: &P::Options,
) -> Result<Option<P::Options>> {
    let Some((stated, line)) = incal_io::stated_rate_hz(preamble) else {
        return Ok(None);
    };
    let Ok(serde_json::Value::Object(m)) = serde_json::to_value(options) else {
        return Ok(None);
    };
    let settle = |mut m: serde_json::Map<String, serde_json::Value>| {
        m.insert("rate_hz".into(), serde_json::json!(stated));
        let settled: P::Options = crate::options::from_json(&serde_json::Value::Object(m))?;
        P::validate(&settled)?;
        Ok(Some(settled))
    };
    match m.get("rate_hz") {
        Some(serde_json::Value::Number(r)) => {
            let r = r.as_f64().unwrap_or(f64::NAN);
            if (r - stated).abs() <= crate::timebase::RATE_TOLERANCE * stated {
                return Ok(None);
            }
            Err(incal_io::InputError::at(
                name,
                line,
                format!(
                    "the preamble states a sample rate of {stated} Hz, but rate_hz is {r} Hz \
                     (they differ by more than {} %)",
                    crate::timebase::RATE_TOLERANCE * 100.0
                ),
            )
            .into())
        }
        Some(serde_json::Value::Null) => settle(m),
        None if crate::options::schema_of::<P::Options>()
            .pointer("/properties/rate_hz")
            .is_some() =>
        {
            settle(m)
        }
        _ => Ok(None),
    }
}
/// The `clipped` warnings of a recording's columns that sat at a
/// converter's rail ([`incal_io::Clipped`]), one per column and rail.
pub fn clipped_warnings(clipped: &[incal_io::Clipped]) -> Vec<crate::warning::Warning> {
    clipped
        .iter()
        .map(|c| {
            let lines: Vec<String> = c.lines.iter().map(|(a, b)| format!("{a}-{b}")).collect();
            let more = if c.runs > c.lines.len() { ", ..." } else { "" };
            crate::warning::Warning::new(
                crate::warning::WarningCode::Clipped,
                format!(
                    "{} sits at the rail {} in {} samples ({} run{}: lines {}{more}): clipped, they are not what the sensor sensed",
                    incal_io::clip(&c.column),
                    c.value,
                    c.samples,
                    c.runs,
                    if c.runs == 1 { "" } else { "s" },
                    lines.join(", ")
                ),
            )
        })
        .collect()
}

/// Record the lines before a recording's header (its logger's preamble,
/// [`incal_io::PreambleLine`]) as the document's `preamble`: `[{line, key,
/// value}]` in file order.
pub fn record_preamble(doc: &mut ResultDocument, preamble: &[incal_io::PreambleLine]) {
    if preamble.is_empty() {
        return;
    }
    let lines = preamble
        .iter()
        .map(|p| serde_json::json!({"line": p.line, "key": p.key, "value": p.value}))
        .collect();
    doc.extra
        .insert("preamble".into(), serde_json::Value::Array(lines));
}

/// Record the environmental columns a recording had (its `temperature_c`
/// and `humidity_pct`, summarised by the input layer) as the document's
/// `environment`: `{NAME: {mean, min, max, count}}`. The certificate states
/// them and the thermal fit takes each result's temperature from them.
pub fn record_environment(doc: &mut ResultDocument, conditions: &[incal_io::Condition]) {
    if conditions.is_empty() {
        return;
    }
    let m: serde_json::Map<String, serde_json::Value> = conditions
        .iter()
        .map(|c| {
            (
                c.name.clone(),
                serde_json::json!({"mean": c.mean, "min": c.min, "max": c.max, "count": c.count}),
            )
        })
        .collect();
    doc.extra
        .insert("environment".into(), serde_json::Value::Object(m));
}

/// The options as the document's `options` object.
pub fn options_map<T: serde::Serialize>(
    options: &T,
) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
    match serde_json::to_value(options) {
        Ok(serde_json::Value::Object(m)) => Ok(m.into_iter().collect()),
        Ok(_) | Err(_) => Err(Error::Unsupported(
            "options do not serialise to a JSON object".into(),
        )),
    }
}
