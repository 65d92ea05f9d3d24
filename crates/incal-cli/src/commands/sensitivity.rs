//! `incal sensitivity`, its plan and its simulator (`incal plan|simulate
//! sensitivity`).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::sensitivity::plan::SensitivityPlanOptions;
use incal::procedures::sensitivity::sim::SensitivitySimOptions;
use incal::procedures::sensitivity::{Kind, Level, Sensitivity, SensitivityOptions, Sensor};
use incal::procedures::{Plan, Silent};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// The stimulus.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum KindArg {
    /// From the file's stimulus columns.
    Auto,
    /// Vibration (`vib_g`): rectification and vibropendulous error.
    Vibration,
    /// Magnetic field (`field_x_mt`, `field_y_mt`, `field_z_mt`).
    Magnetic,
    /// Shock (`shock_g`): the shift across each shock.
    Shock,
}

impl From<KindArg> for Kind {
    fn from(k: KindArg) -> Kind {
        match k {
            KindArg::Auto => Kind::Auto,
            KindArg::Vibration => Kind::Vibration,
            KindArg::Magnetic => Kind::Magnetic,
            KindArg::Shock => Kind::Shock,
        }
    }
}

/// The instrument.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SensorArg {
    /// An accelerometer (sensitivities in µg per unit of the stimulus).
    Accel,
    /// A gyro (sensitivities in °/h per unit of the stimulus).
    Gyro,
}

impl From<SensorArg> for Sensor {
    fn from(s: SensorArg) -> Sensor {
        match s {
            SensorArg::Accel => Sensor::Accel,
            SensorArg::Gyro => Sensor::Gyro,
        }
    }
}

/// How `vib_g` states the level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LevelArg {
    /// g rms.
    Rms,
    /// g peak of a sine.
    Peak,
}

/// `incal sensitivity`.
#[derive(clap::Args, Debug)]
pub struct SensitivityArgs {
    /// Recording of the runs: `run` (a label per run), the stimulus (`vib_g` [`vib_freq_hz`, `vib_angle_deg`]; `field_x_mt`, `field_y_mt`, `field_z_mt`; or `shock_g`), optional `input`, the output column(s) and `time_s`.
    #[arg(long)]
    pub input: PathBuf,
    /// The stimulus (default: from the file's columns).
    #[arg(long, value_enum, default_value = "auto")]
    pub kind: KindArg,
    /// The instrument.
    #[arg(long, value_enum, default_value = "accel")]
    pub sensor: SensorArg,
    /// The output columns, comma-separated; with several, every coefficient is named with the column's axis (`gyro_x` gives `_x`).
    #[arg(long, default_value = "output")]
    pub output_columns: String,
    /// The output columns' unit: accel g (default), mg, ug, m_s2; gyro deg_s (default), deg_h, rad_s.
    #[arg(long)]
    pub unit: Option<String>,
    /// How `vib_g` states the level.
    #[arg(long, value_enum, default_value = "rms")]
    pub level: LevelArg,
    /// Sampling rate, Hz, when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Seconds dropped at the start of each run (the transient after the stimulus is set).
    #[arg(long, default_value_t = 0.0)]
    pub settle_s: f64,
    /// The rig, for the certificate's traceability (default from the kind: shaker, helmholtz-coil, shock-machine).
    #[arg(long)]
    pub rig: Option<String>,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal sensitivity`.
pub fn run(a: &SensitivityArgs) -> CliResult<()> {
    let options = SensitivityOptions {
        kind: a.kind.into(),
        sensor: a.sensor.into(),
        output_columns: a.output_columns.clone(),
        unit: a.unit.clone(),
        level: match a.level {
            LevelArg::Rms => Level::Rms,
            LevelArg::Peak => Level::Peak,
        },
        rate_hz: a.rate_hz,
        settle_s: a.settle_s,
        rig: a.rig.clone(),
    };
    crate::run::reduce::<Sensitivity>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// A sensitivity session: the runs and the noise.
#[derive(clap::Args, Debug, Clone)]
pub struct SessionArgs {
    /// The stimulus.
    #[arg(long, value_enum, default_value = "vibration")]
    pub kind: KindArg,
    /// The instrument.
    #[arg(long, value_enum, default_value = "accel")]
    pub sensor: SensorArg,
    /// Levels, comma-separated: vibration g rms (default 0,2,4,6,8), field mT on each axis in turn (default -1,0,1), shock peaks g (default 100,200).
    #[arg(long, allow_hyphen_values = true)]
    pub levels: Option<String>,
    /// Vibration directions, degrees from the input axis toward the pendulous axis, comma-separated (0,45,-45 for the vibropendulous term).
    #[arg(long, default_value = "0", allow_hyphen_values = true)]
    pub angles_deg: String,
    /// Field axes the coil turns to, comma-separated.
    #[arg(long, default_value = "x,y,z")]
    pub field_axes: String,
    /// Magnetic outputs: 1 (`output`) or 3 (`output_x`, `output_y`, `output_z`).
    #[arg(long, default_value_t = 3)]
    pub outputs: usize,
    /// A run at zero between two levels (default: ascending).
    #[arg(long)]
    pub interleave: bool,
    /// Runs per level.
    #[arg(long, default_value_t = 1)]
    pub repeats: usize,
    /// Applied inputs (g or deg/s), comma-separated: every level is run at each (for the scale factor's sensitivity).
    #[arg(long, allow_hyphen_values = true)]
    pub inputs: Option<String>,
    /// White noise per sample, µg or deg/h (default 50 or 36).
    #[arg(long)]
    pub noise: Option<f64>,
    /// Flicker: bias instability, µg or deg/h (default 2 or 0.5).
    #[arg(long)]
    pub flicker: Option<f64>,
    /// Random walk, µg or deg/h per √s.
    #[arg(long, default_value_t = 0.0)]
    pub random_walk: f64,
    /// Seconds per run.
    #[arg(long, default_value_t = 30.0)]
    pub run_s: f64,
    /// Seconds between runs.
    #[arg(long, default_value_t = 10.0)]
    pub gap_s: f64,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub rate_hz: f64,
}

/// `incal plan sensitivity`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan sensitivity`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let s = &a.session;
    let options = SensitivityPlanOptions {
        kind: s.kind.into(),
        sensor: s.sensor.into(),
        levels: s.levels.clone(),
        angles_deg: s.angles_deg.clone(),
        field_axes: s.field_axes.clone(),
        outputs: s.outputs,
        interleave: s.interleave,
        repeats: s.repeats,
        inputs: s.inputs.clone(),
        noise: s.noise,
        flicker: s.flicker,
        random_walk: s.random_walk,
        run_s: s.run_s,
        gap_s: s.gap_s,
        rate_hz: s.rate_hz,
    };
    a.out.emit(&<Sensitivity as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate sensitivity`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Vibration frequency, Hz.
    #[arg(long, default_value_t = 100.0)]
    pub freq_hz: f64,
    /// Rectification along the input axis, µg/g² or deg/h/g².
    #[arg(long, default_value_t = 30.0, allow_negative_numbers = true)]
    pub vrc: f64,
    /// Vibropendulous coefficient, µg/g² or deg/h/g².
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub vibropendulous: f64,
    /// Rectification along the pendulous axis, µg/g² or deg/h/g².
    #[arg(long, default_value_t = 5.0, allow_negative_numbers = true)]
    pub vrc_pendulous: f64,
    /// A term linear in the vibration level, µg/g or deg/h/g.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub vib_linear: f64,
    /// Magnetic sensitivity, output i per field j, row-major, nine comma-separated values (µg/mT or deg/h/mT).
    #[arg(long, default_value = "5,0.5,-0.3,0.2,4,0.6,-0.4,0.1,6", allow_hyphen_values = true)]
    pub magnetic: String,
    /// Bias shift of each shock, µg or deg/h, comma-separated.
    #[arg(long, default_value = "20,-35", allow_hyphen_values = true)]
    pub shifts: String,
    /// Scale-factor shift of each shock, ppm, comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub sf_shifts_ppm: Option<String>,
    /// Bias, µg or deg/h.
    #[arg(long, default_value_t = 100.0, allow_negative_numbers = true)]
    pub bias: f64,
    /// The output file's unit (default g or deg_s).
    #[arg(long)]
    pub unit: Option<String>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (the sensitivities as the reduction names them) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate sensitivity`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let s = &a.session;
    let options = SensitivitySimOptions {
        kind: s.kind.into(),
        sensor: s.sensor.into(),
        levels: s.levels.clone(),
        angles_deg: s.angles_deg.clone(),
        freq_hz: a.freq_hz,
        field_axes: s.field_axes.clone(),
        outputs: s.outputs,
        interleave: s.interleave,
        repeats: s.repeats,
        inputs: s.inputs.clone(),
        vrc: a.vrc,
        vibropendulous: a.vibropendulous,
        vrc_pendulous: a.vrc_pendulous,
        vib_linear: a.vib_linear,
        magnetic: a.magnetic.clone(),
        shifts: a.shifts.clone(),
        sf_shifts_ppm: a.sf_shifts_ppm.clone(),
        bias: a.bias,
        noise: s.noise,
        flicker: s.flicker,
        random_walk: s.random_walk,
        run_s: s.run_s,
        gap_s: s.gap_s,
        rate_hz: s.rate_hz,
        unit: a.unit.clone(),
        seed: a.seed,
    };
    crate::run::simulate::<Sensitivity>(&options, a.output.as_deref())?;
    crate::run::write_truth::<Sensitivity>(&options, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Environmental sensitivities: vibration rectification and vibropendulous error, magnetic sensitivity, the shift across a shock, from runs at several levels (IEEE Std 1293 / 952 / 1431).
    Sensitivity(SensitivityArgs),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Sensitivity(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
pub enum Plans {
    /// Sensitivity plan: the predicted u of every sensitivity for the runs, levels and noise (the design and the noise's covariance); refuses runs that cannot separate a term, naming it.
    Sensitivity(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Sensitivity(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
pub enum Simulations {
    /// Runs on a shaker, in a Helmholtz coil or before and after shocks, with the effect, white, flicker and random-walk noise; writes the input CSV of `incal sensitivity`.
    Sensitivity(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Sensitivity(a) => simulate(a),
        }
    }
}
