//! `incal response sine|broadband|step`, and their plans and simulators
//! (`incal plan|simulate response-sine|response-broadband|response-step`).

use std::path::PathBuf;

use clap::{Subcommand, ValueEnum};
use incal::procedures::response::model::Order;
use incal::procedures::response::plan::{DwellChoice, ModelGuess, ResponsePlanOptions};
use incal::procedures::response::sim::ResponseSimOptions;
use incal::procedures::response::broadband::plan::BroadbandPlanOptions;
use incal::procedures::response::broadband::sim::{BroadbandSimOptions, Excitation};
use incal::procedures::response::broadband::welch::Window;
use incal::procedures::response::broadband::{Align, BroadbandOptions, ResponseBroadband};
use incal::procedures::response::fit::{ModelOptions, Rig};
use incal::procedures::response::step::plan::StepPlanOptions;
use incal::procedures::response::step::sim::StepSimOptions;
use incal::procedures::response::step::{ResponseStep, StepOptions};
use incal::procedures::response::{
    BandwidthMethod, Drift, OrderChoice, ResponseOptions, ResponseSine,
};
use incal::procedures::{Plan, Silent};

use crate::error::{core, CliResult};
use crate::input::ReadArgs;
use crate::output::{PlanOut, ResultArgs};

/// `incal response …`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Stepped sine (dwells): gain and phase per dwell, a low-pass model with delay, bandwidth, latency and flatness.
    Sine(SineArgs),
    /// Broadband record (random, chirp, multisine): H1 and coherence by Welch averaging, the same model.
    Broadband(BroadbandArgs),
    /// Step (a rate or tilt step): the same model in the time domain, delay, rise time, overshoot, settling time.
    Step(StepArgs),
}

/// Model order of the reduction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum OrderArg {
    /// First order unless its fit fails the 5 % lack-of-fit test.
    Auto,
    /// First-order low-pass with delay.
    First,
    /// Second-order low-pass with delay.
    Second,
}

/// Model order of a plan or a simulation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FixedOrderArg {
    /// First-order low-pass with delay.
    First,
    /// Second-order low-pass with delay.
    Second,
}

impl From<FixedOrderArg> for Order {
    fn from(o: FixedOrderArg) -> Order {
        match o {
            FixedOrderArg::First => Order::First,
            FixedOrderArg::Second => Order::Second,
        }
    }
}

/// The slow terms of each dwell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DriftArg {
    /// An offset and a linear drift.
    Linear,
    /// An offset only.
    None,
}

/// Whether the output is aligned to the reference before the spectra.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AlignArg {
    /// Shifted by the whole samples of a first pass's latency.
    Latency,
    /// Not shifted: the plain H1.
    None,
}

/// The window of each Welch segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WindowArg {
    /// The periodic Hann window (random or chirp excitation).
    Hann,
    /// No window: for a periodic excitation whose period divides the segment.
    Rectangular,
}

impl From<WindowArg> for Window {
    fn from(w: WindowArg) -> Window {
        match w {
            WindowArg::Hann => Window::Hann,
            WindowArg::Rectangular => Window::Rectangular,
        }
    }
}

/// Which bandwidth is `bandwidth_hz`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BandwidthArg {
    /// The fitted model's half-power frequency.
    Model,
    /// Interpolated between the dwells that bracket -3.01 dB (refused when none do).
    Interpolated,
}

/// The rig of the test (its reference standard makes the result traceable).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum RigArg {
    /// A rate table in its angular-vibration mode.
    RateTable,
    /// A vibration exciter (shaker).
    Shaker,
}

/// The model's options, the same for every response method.
#[derive(clap::Args, Debug)]
pub struct ModelArgs {
    /// Model order.
    #[arg(long, value_enum, default_value = "auto")]
    pub order: OrderArg,
    /// Scale factor the gains are normalised to (output per reference unit); default the fitted k_dc.
    #[arg(long)]
    pub k1: Option<f64>,
    /// Standard uncertainty of --k1.
    #[arg(long)]
    pub u_k1: Option<f64>,
    /// The reference's relative amplitude uncertainty, % (type B).
    #[arg(long, default_value_t = 0.0)]
    pub u_reference_pct: f64,
    /// The reference's phase uncertainty, deg (type B).
    #[arg(long, default_value_t = 0.0)]
    pub u_reference_phase_deg: f64,
    /// Which bandwidth is `bandwidth_hz`.
    #[arg(long, value_enum, default_value = "model")]
    pub bandwidth: BandwidthArg,
    /// Upper end of the gain-flatness band, Hz: flatness_db is reported only with it.
    #[arg(long)]
    pub flatness_to_hz: Option<f64>,
    /// The rig whose reference standard the reference channel is (the certificate's traceability).
    #[arg(long, value_enum, default_value = "rate-table")]
    pub rig: RigArg,
}

impl From<OrderArg> for OrderChoice {
    fn from(o: OrderArg) -> OrderChoice {
        match o {
            OrderArg::Auto => OrderChoice::Auto,
            OrderArg::First => OrderChoice::First,
            OrderArg::Second => OrderChoice::Second,
        }
    }
}

impl ModelArgs {
    /// The core's model options.
    pub fn options(&self) -> ModelOptions {
        ModelOptions {
            order: self.order.into(),
            k1: self.k1,
            u_k1: self.u_k1,
            u_reference_pct: self.u_reference_pct,
            u_reference_phase_deg: self.u_reference_phase_deg,
            bandwidth: match self.bandwidth {
                BandwidthArg::Model => BandwidthMethod::Model,
                BandwidthArg::Interpolated => BandwidthMethod::Interpolated,
            },
            flatness_to_hz: self.flatness_to_hz,
            rig: match self.rig {
                RigArg::RateTable => Rig::RateTable,
                RigArg::Shaker => Rig::Shaker,
            },
        }
    }
}

/// `incal response sine`.
#[derive(clap::Args, Debug)]
pub struct SineArgs {
    /// Recording: `reference`, `output`, `time_s` (or --rate-hz) and `freq_hz` (without it the dwells are found from the reference).
    #[arg(long)]
    pub input: PathBuf,
    /// Sampling rate, Hz, when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Harmonic order fitted (1: the fundamental only); THD from 2 on.
    #[arg(long, default_value_t = 3)]
    pub harmonics: usize,
    /// The slow terms of each dwell: an offset and a linear drift, or an offset only.
    #[arg(long, value_enum, default_value = "linear")]
    pub drift: DriftArg,
    /// Seconds left out at the start of each dwell (the transient).
    #[arg(long, default_value_t = 0.0)]
    pub settle_s: f64,
    /// Estimate each dwell's frequency from the reference (four-parameter fit from freq_hz) instead of taking freq_hz as exact; always so without a freq_hz column.
    #[arg(long)]
    pub estimate_frequency: bool,
    /// Window of the dwell search without a freq_hz column, s: dwells must last about three windows.
    #[arg(long, default_value_t = 1.0)]
    pub dwell_window_s: f64,
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal response sine`.
pub fn run_sine(a: &SineArgs) -> CliResult<()> {
    let options = ResponseOptions {
        rate_hz: a.rate_hz,
        harmonics: a.harmonics,
        drift: match a.drift {
            DriftArg::Linear => Drift::Linear,
            DriftArg::None => Drift::None,
        },
        settle_s: a.settle_s,
        estimate_frequency: a.estimate_frequency,
        dwell_window_s: a.dwell_window_s,
        model: a.model.options(),
    };
    crate::run::reduce::<ResponseSine>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// The expected (or simulated) response.
#[derive(clap::Args, Debug, Clone)]
pub struct ModelGuessArgs {
    /// Model order.
    #[arg(long, value_enum, default_value = "second")]
    pub order: FixedOrderArg,
    /// Low-frequency gain k_dc (output per reference unit).
    #[arg(long, default_value_t = 1.0)]
    pub k_dc: f64,
    /// Corner f_c (first order) or natural frequency f_n (second order), Hz.
    #[arg(long, default_value_t = 80.0)]
    pub corner_hz: f64,
    /// Damping ratio of the second order.
    #[arg(long, default_value_t = 0.6)]
    pub zeta: f64,
    /// Pure delay, s.
    #[arg(long, default_value_t = 0.002)]
    pub delay_s: f64,
}

impl ModelGuessArgs {
    fn model(&self) -> ModelGuess {
        ModelGuess {
            order: self.order.into(),
            k_dc: self.k_dc,
            corner_hz: self.corner_hz,
            zeta: self.zeta,
            delay_s: self.delay_s,
        }
    }
}

/// The dwells of a plan or simulation.
#[derive(clap::Args, Debug, Clone)]
pub struct DwellArgs {
    /// Dwell frequencies, Hz, in test order (default: a log sweep from --f-min-hz to --f-max-hz).
    #[arg(long, value_delimiter = ',')]
    pub dwells_hz: Option<Vec<f64>>,
    /// Lowest dwell of the log sweep, Hz.
    #[arg(long, default_value_t = 1.0)]
    pub f_min_hz: f64,
    /// Highest dwell of the log sweep, Hz.
    #[arg(long, default_value_t = 200.0)]
    pub f_max_hz: f64,
    /// Dwells of the log sweep.
    #[arg(long, default_value_t = 12)]
    pub dwells: usize,
    /// Seconds per dwell (lengthened to --min-cycles).
    #[arg(long, default_value_t = 2.0)]
    pub seconds_per_dwell: f64,
    /// Fewest cycles per dwell (at least 2).
    #[arg(long, default_value_t = 10.0)]
    pub min_cycles: f64,
    #[command(flatten)]
    pub guess: ModelGuessArgs,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate_hz: f64,
    /// Reference amplitude (reference units).
    #[arg(long, default_value_t = 10.0)]
    pub amplitude: f64,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 0.02)]
    pub noise: f64,
    /// Reference noise of one sample (reference units).
    #[arg(long, default_value_t = 0.005)]
    pub reference_noise: f64,
}

impl DwellArgs {
    fn dwells(&self) -> DwellChoice {
        DwellChoice {
            dwells_hz: self.dwells_hz.clone(),
            f_min_hz: self.f_min_hz,
            f_max_hz: self.f_max_hz,
            dwells: self.dwells,
            seconds_per_dwell: self.seconds_per_dwell,
            min_cycles: self.min_cycles,
        }
    }

    fn model(&self) -> ModelGuess {
        self.guess.model()
    }
}

/// `incal plan response-sine`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub test: DwellArgs,
    /// The reference's relative amplitude uncertainty, % (type B).
    #[arg(long, default_value_t = 0.0)]
    pub u_reference_pct: f64,
    /// The reference's phase uncertainty, deg (type B).
    #[arg(long, default_value_t = 0.0)]
    pub u_reference_phase_deg: f64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan response-sine`.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    let t = &a.test;
    let options = ResponsePlanOptions {
        dwells: t.dwells(),
        model: t.model(),
        rate_hz: t.rate_hz,
        amplitude: t.amplitude,
        noise: t.noise,
        reference_noise: t.reference_noise,
        u_reference_pct: a.u_reference_pct,
        u_reference_phase_deg: a.u_reference_phase_deg,
    };
    a.out
        .emit(&<ResponseSine as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate response-sine`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub test: DwellArgs,
    /// Output bias (output units).
    #[arg(long, default_value_t = 0.0)]
    pub bias: f64,
    /// Second harmonic of the output, % of the fundamental.
    #[arg(long, default_value_t = 0.0)]
    pub distortion_pct: f64,
    /// Standard deviation of the reference's amplitude error, drawn once per dwell, %.
    #[arg(long, default_value_t = 0.0)]
    pub reference_error_pct: f64,
    /// The reference sampled on its own clock this much later than the output, s (writes a time_ref_s column).
    #[arg(long, default_value_t = 0.0)]
    pub reference_clock_offset_s: f64,
    /// The table's frequency error, %: it runs at freq_hz (1 + this/100).
    #[arg(long, default_value_t = 0.0)]
    pub frequency_error_pct: f64,
    /// Write no freq_hz column (the reduction then finds the dwells from the reference).
    #[arg(long)]
    pub no_freq_column: bool,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (model, bandwidth, latency, each dwell's gain and phase) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate response-sine`.
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    let t = &a.test;
    let options = ResponseSimOptions {
        dwells: t.dwells(),
        model: t.model(),
        rate_hz: t.rate_hz,
        amplitude: t.amplitude,
        noise: t.noise,
        reference_noise: t.reference_noise,
        bias: a.bias,
        distortion_pct: a.distortion_pct,
        reference_error_pct: a.reference_error_pct,
        reference_clock_offset_s: a.reference_clock_offset_s,
        frequency_error_pct: a.frequency_error_pct,
        no_freq_column: a.no_freq_column,
        seed: a.seed,
    };
    crate::run::simulate::<ResponseSine>(&options, a.output.as_deref())?;
    crate::run::write_truth::<ResponseSine>(&options, a.truth_out.as_deref())
}

/// `incal response broadband`.
#[derive(clap::Args, Debug)]
pub struct BroadbandArgs {
    /// Recording: `reference`, `output`, and `time_s` (or --rate-hz).
    #[arg(long)]
    pub input: PathBuf,
    /// Sampling rate, Hz, when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Samples per Welch segment (the resolution is rate / segment).
    #[arg(long, default_value_t = 1024)]
    pub segment_samples: usize,
    /// Overlap of the segments, samples (default: half a segment).
    #[arg(long)]
    pub overlap_samples: Option<usize>,
    /// Bins below this coherence are flagged, not fitted.
    #[arg(long, default_value_t = 0.9)]
    pub min_coherence: f64,
    /// Lowest frequency fitted, Hz.
    #[arg(long)]
    pub f_min_hz: Option<f64>,
    /// Highest frequency fitted, Hz.
    #[arg(long)]
    pub f_max_hz: Option<f64>,
    /// Align the output to the reference by the latency before the spectra (none: the plain H1, as scipy gives it).
    #[arg(long, value_enum, default_value = "latency")]
    pub align: AlignArg,
    /// The window of each segment (rectangular: for a multisine whose period divides the segment).
    #[arg(long, value_enum, default_value = "hann")]
    pub window: WindowArg,
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal response broadband`.
pub fn run_broadband(a: &BroadbandArgs) -> CliResult<()> {
    let options = BroadbandOptions {
        rate_hz: a.rate_hz,
        segment_samples: a.segment_samples,
        overlap_samples: a.overlap_samples,
        min_coherence: a.min_coherence,
        f_min_hz: a.f_min_hz,
        f_max_hz: a.f_max_hz,
        align: match a.align {
            AlignArg::Latency => Align::Latency,
            AlignArg::None => Align::None,
        },
        window: a.window.into(),
        model: a.model.options(),
    };
    crate::run::reduce::<ResponseBroadband>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// The expected response of a broadband plan or simulation.
#[derive(clap::Args, Debug, Clone)]
pub struct GuessArgs {
    #[command(flatten)]
    pub guess: ModelGuessArgs,
    /// Record length, s.
    #[arg(long, default_value_t = 60.0)]
    pub duration_s: f64,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate_hz: f64,
    /// RMS of the reference (reference units).
    #[arg(long, default_value_t = 10.0)]
    pub amplitude: f64,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 0.02)]
    pub noise: f64,
}

impl GuessArgs {
    fn model(&self) -> ModelGuess {
        self.guess.model()
    }
}

/// `incal plan response-broadband`.
#[derive(clap::Args, Debug)]
pub struct BroadbandPlanArgs {
    #[command(flatten)]
    pub test: GuessArgs,
    /// Samples per Welch segment.
    #[arg(long, default_value_t = 1024)]
    pub segment_samples: usize,
    /// Bins below this coherence are not fitted.
    #[arg(long, default_value_t = 0.9)]
    pub min_coherence: f64,
    /// Highest frequency fitted, Hz.
    #[arg(long)]
    pub f_max_hz: Option<f64>,
    /// Seed of the first of the simulated records the prediction reduces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan response-broadband`.
pub fn plan_broadband(a: &BroadbandPlanArgs) -> CliResult<()> {
    let t = &a.test;
    let options = BroadbandPlanOptions {
        model: t.model(),
        duration_s: t.duration_s,
        rate_hz: t.rate_hz,
        amplitude: t.amplitude,
        noise: t.noise,
        segment_samples: a.segment_samples,
        min_coherence: a.min_coherence,
        f_max_hz: a.f_max_hz,
        seed: a.seed,
    };
    a.out
        .emit(&<ResponseBroadband as Plan>::plan(&options).map_err(core)?)
}

/// The excitation of a simulated broadband test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ExcitationArg {
    /// White Gaussian noise.
    Random,
    /// A linear sweep from --f-low-hz to --f-high-hz over the record.
    Chirp,
    /// Equal sines at the bins of --period-samples in the band, Schroeder phases.
    Multisine,
}

/// `incal simulate response-broadband`.
#[derive(clap::Args, Debug)]
pub struct BroadbandSimArgs {
    #[command(flatten)]
    pub test: GuessArgs,
    /// Reference noise of one sample (it biases H1 low).
    #[arg(long, default_value_t = 0.0)]
    pub reference_noise: f64,
    /// Output bias (output units).
    #[arg(long, default_value_t = 0.0)]
    pub bias: f64,
    /// The excitation.
    #[arg(long, value_enum, default_value = "random")]
    pub excitation: ExcitationArg,
    /// Lowest frequency of a chirp or multisine, Hz.
    #[arg(long, default_value_t = 0.5)]
    pub f_low_hz: f64,
    /// Highest frequency of a chirp or multisine, Hz (default 0.4 of the sampling rate).
    #[arg(long)]
    pub f_high_hz: Option<f64>,
    /// Period of a multisine, samples (give the reduction the same --segment-samples).
    #[arg(long, default_value_t = 1024)]
    pub period_samples: usize,
    /// The reference sampled on its own clock this much later than the output, s (writes a time_ref_s column).
    #[arg(long, default_value_t = 0.0)]
    pub reference_clock_offset_s: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (model, bandwidth, latency) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate response-broadband`.
pub fn simulate_broadband(a: &BroadbandSimArgs) -> CliResult<()> {
    let t = &a.test;
    let options = BroadbandSimOptions {
        model: t.model(),
        duration_s: t.duration_s,
        rate_hz: t.rate_hz,
        amplitude: t.amplitude,
        noise: t.noise,
        reference_noise: a.reference_noise,
        bias: a.bias,
        excitation: match a.excitation {
            ExcitationArg::Random => Excitation::Random,
            ExcitationArg::Chirp => Excitation::Chirp,
            ExcitationArg::Multisine => Excitation::Multisine,
        },
        f_low_hz: a.f_low_hz,
        f_high_hz: a.f_high_hz,
        period_samples: a.period_samples,
        reference_clock_offset_s: a.reference_clock_offset_s,
        seed: a.seed,
    };
    crate::run::simulate::<ResponseBroadband>(&options, a.output.as_deref())?;
    crate::run::write_truth::<ResponseBroadband>(&options, a.truth_out.as_deref())
}

/// `incal response step`.
#[derive(clap::Args, Debug)]
pub struct StepArgs {
    /// Recording: `reference` (the step input), `output`, and `time_s` (or --rate-hz).
    #[arg(long)]
    pub input: PathBuf,
    /// Sampling rate, Hz, when the file has no `time_s`.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// Model order.
    #[arg(long, value_enum, default_value = "auto")]
    pub order: OrderArg,
    /// Half-width of the settling band, % of the step.
    #[arg(long, default_value_t = 2.0)]
    pub settling_band_pct: f64,
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// `incal response step`.
pub fn run_step(a: &StepArgs) -> CliResult<()> {
    let options = StepOptions {
        rate_hz: a.rate_hz,
        order: a.order.into(),
        settling_band_pct: a.settling_band_pct,
    };
    crate::run::reduce::<ResponseStep>(&a.input, &a.read, &options, &a.result, &Silent)
}

/// A step test: the expected response, the record and the step.
#[derive(clap::Args, Debug, Clone)]
pub struct StepTestArgs {
    #[command(flatten)]
    pub guess: ModelGuessArgs,
    /// Record length, s.
    #[arg(long, default_value_t = 1.0)]
    pub duration_s: f64,
    /// Sampling rate, Hz.
    #[arg(long, default_value_t = 1000.0)]
    pub rate_hz: f64,
    /// Time of the step, s.
    #[arg(long, default_value_t = 0.3)]
    pub step_s: f64,
    /// Step of the reference (reference units).
    #[arg(long, default_value_t = 10.0)]
    pub amplitude: f64,
    /// Output noise of one sample (output units).
    #[arg(long, default_value_t = 0.02)]
    pub noise: f64,
    /// Reference noise of one sample (reference units).
    #[arg(long, default_value_t = 0.005)]
    pub reference_noise: f64,
}

/// `incal plan response-step`.
#[derive(clap::Args, Debug)]
pub struct StepPlanArgs {
    #[command(flatten)]
    pub test: StepTestArgs,
    /// Seed of the first of the simulated records the prediction reduces.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub out: PlanOut,
}

/// `incal plan response-step`.
pub fn plan_step(a: &StepPlanArgs) -> CliResult<()> {
    let t = &a.test;
    let options = StepPlanOptions {
        model: t.guess.model(),
        duration_s: t.duration_s,
        rate_hz: t.rate_hz,
        step_s: t.step_s,
        amplitude: t.amplitude,
        noise: t.noise,
        reference_noise: t.reference_noise,
        seed: a.seed,
    };
    a.out
        .emit(&<ResponseStep as Plan>::plan(&options).map_err(core)?)
}

/// `incal simulate response-step`.
#[derive(clap::Args, Debug)]
pub struct StepSimArgs {
    #[command(flatten)]
    pub test: StepTestArgs,
    /// Output bias (output units).
    #[arg(long, default_value_t = 0.0)]
    pub bias: f64,
    /// The reference sampled on its own clock this much later than the output, s (writes a time_ref_s column).
    #[arg(long, default_value_t = 0.0)]
    pub reference_clock_offset_s: f64,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Write the truth (model, step metrics, the true step time) as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub truth_out: Option<PathBuf>,
    /// Output CSV (default: standard output).
    #[arg(long, short = 'o', value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// `incal simulate response-step`.
pub fn simulate_step(a: &StepSimArgs) -> CliResult<()> {
    let t = &a.test;
    let options = StepSimOptions {
        model: t.guess.model(),
        duration_s: t.duration_s,
        rate_hz: t.rate_hz,
        step_s: t.step_s,
        amplitude: t.amplitude,
        noise: t.noise,
        reference_noise: t.reference_noise,
        bias: a.bias,
        reference_clock_offset_s: a.reference_clock_offset_s,
        seed: a.seed,
    };
    crate::run::simulate::<ResponseStep>(&options, a.output.as_deref())?;
    crate::run::write_truth::<ResponseStep>(&options, a.truth_out.as_deref())
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(Subcommand, Debug)]
pub enum Reductions {
    /// Dynamic response: stepped sine (IEEE Std 1431 §12.15, IEEE Std 1057 sine fits, ISO 16063-21).
    #[command(subcommand)]
    Response(Command),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Response(Command::Sine(a)) => run_sine(a),
            Self::Response(Command::Broadband(a)) => run_broadband(a),
            Self::Response(Command::Step(a)) => run_step(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(Subcommand, Debug)]
#[allow(clippy::enum_variant_names)] // the command names: response-sine, …
pub enum Plans {
    /// Stepped-sine plan: predicted u of every dwell's gain and phase and of bandwidth, delay and latency.
    ResponseSine(PlanArgs),
    /// Broadband plan: predicted coherence and u of bandwidth, delay and latency for a record length and noise.
    ResponseBroadband(BroadbandPlanArgs),
    /// Step plan: predicted u of delay, rise time, overshoot, settling time and the model for a record and noise.
    ResponseStep(StepPlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::ResponseSine(a) => plan(a),
            Self::ResponseBroadband(a) => plan_broadband(a),
            Self::ResponseStep(a) => plan_step(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(Subcommand, Debug)]
#[allow(clippy::enum_variant_names)] // the command names: response-sine, …
pub enum Simulations {
    /// Stepped sine on a rate table or shaker; writes the input CSV of `incal response sine`.
    ResponseSine(SimArgs),
    /// White broadband excitation through a known low-pass with delay; writes the input CSV of `incal response broadband`.
    ResponseBroadband(BroadbandSimArgs),
    /// A reference step through a known low-pass with delay; writes the input CSV of `incal response step`.
    ResponseStep(StepSimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::ResponseSine(a) => simulate(a),
            Self::ResponseBroadband(a) => simulate_broadband(a),
            Self::ResponseStep(a) => simulate_step(a),
        }
    }
}
