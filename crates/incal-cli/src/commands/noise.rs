//! `incal noise`: Allan-family deviations with confidence intervals, IEEE
//! Std 952 noise terms and bias stability of every channel of a record;
//! `incal simulate noise`: seeded records with known terms. Arguments in,
//! the core's [`incal::procedures::noise`] does the rest.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;

use clap::ValueEnum;
use incal::procedures::noise::preprocess::{Detrend, Fill, PreprocessOptions};
use incal::procedures::noise::sim::{NoiseSim, SimTone};
use incal::procedures::noise::spectrum::SpectrumOptions;
use incal::procedures::noise::{
    reduce_mapped, DataKind, Format, Noise, NoiseOptions, QuantityKind,
};
use incal::procedures::Progress;
use incal_io::binary::{MappedRecord, Sample};

use crate::error::{core, usage, CliResult};
use crate::input::ReadArgs;
use crate::output::ResultArgs;

/// What the channels measure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum QuantityArg {
    /// Gyro (rate in deg/s, rad/s or deg/h).
    Gyro,
    /// Accelerometer (g, mg or m/s2).
    Accel,
    /// Anything else (terms in the input unit).
    Generic,
}

impl From<QuantityArg> for QuantityKind {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Gyro => QuantityKind::Gyro,
            QuantityArg::Accel => QuantityKind::Accel,
            QuantityArg::Generic => QuantityKind::Generic,
        }
    }
}

/// Rate samples or their running sum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DataArg {
    /// Rate ("frequency") samples in --unit.
    Rate,
    /// Angle or velocity-increment sums ("phase") in --unit times seconds.
    Angle,
}

/// File format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// Text with a header line, comma separated.
    Csv,
    /// Raw little-endian 32-bit floats, channels interleaved.
    F32le,
    /// Raw little-endian 64-bit floats, channels interleaved.
    F64le,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Csv => Format::Csv,
            FormatArg::F32le => Format::F32le,
            FormatArg::F64le => Format::F64le,
        }
    }
}

/// `incal noise`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Record: CSV with a header (optional time_s column; every other numeric column is a channel) or raw binary (--format).
    #[arg(long, value_name = "FILE")]
    pub input: PathBuf,
    /// Sample rate in Hz (τ0 = 1/F). Optional when the CSV has a time_s column (then the stamps' rate; when given, checked against them). Required for binary records.
    #[arg(long)]
    pub rate_hz: Option<f64>,
    /// What the channels measure: sets the units of the noise terms.
    #[arg(long, value_enum, default_value = "generic")]
    pub quantity: QuantityArg,
    /// Unit of the rate samples: deg/s, rad/s, deg/h (gyro); g, mg, m/s2 (accel); any text (generic). Default deg/s, g, 1.
    #[arg(long)]
    pub unit: Option<String>,
    /// rate: samples are rates; angle: samples are angle (velocity) sums in unit times s.
    #[arg(long, value_enum, default_value = "rate")]
    pub data: DataArg,
    /// Averaging times: octave, decade, all, or N points per decade.
    #[arg(long, default_value = "octave")]
    pub taus: String,
    /// Statistics reported, comma separated: oadev, mdev, ohdev, tdev, totdev, adev, hdev, mtotdev, htotdev, theo1, theoh, mtie, tierms; all = every one (mtie and tierms only with --data angle).
    #[arg(long, default_value = "oadev,mdev,ohdev,tdev,totdev")]
    pub deviations: String,
    /// Confidence of the deviation bounds (0 < P < 1).
    #[arg(long, default_value_t = 0.683)]
    pub confidence: f64,
    /// Averaging times (s) of the bias stability (std of the τ-averages), comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = vec![10.0, 100.0])]
    pub stability_tau_s: Vec<f64>,
    /// Input format.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: FormatArg,
    /// Interleaved channels of a binary input (named ch1, ch2, ... for --columns).
    #[arg(long)]
    pub channels: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Put CSV rows that are out of time order in order by time_s instead of refusing them (warning time-sorted counts the rows moved).
    #[arg(long)]
    pub sort_time: bool,
    /// Three instruments recorded together (exactly three channels, e.g. --columns a,b,c): each one's OADEV by the three-cornered hat, in three_cornered_hat.
    #[arg(long)]
    pub three_cornered_hat: bool,
    /// Dynamic Allan variance: the OADEV of every window WINDOW_S seconds long, one every STEP_S seconds (e.g. 600,60), in table davar.CHANNEL, with a non-stationary warning when the windows disagree beyond their bounds.
    #[arg(long, value_name = "WINDOW_S,STEP_S")]
    pub davar: Option<String>,
    /// Noise against temperature from one record with a temperature_c column: bins this wide (degC), the terms fitted in each, each term as a polynomial in temperature (coefficients CHANNEL.TERM.c0...).
    #[arg(long, value_name = "DEGC")]
    pub temperature_bin_c: Option<f64>,
    /// One thread (same numbers as the parallel default, bit for bit).
    #[arg(long)]
    pub sequential: bool,
    #[command(flatten)]
    pub psd: PsdArgs,
    #[command(flatten)]
    pub pre: PreprocessArgs,
    /// Channels to analyse (default: every column but time_s; of a binary record every channel).
    #[command(flatten)]
    pub read: ReadArgs,
    #[command(flatten)]
    pub result: ResultArgs,
}

/// The preprocessing of `incal noise` (each step recorded in the document).
#[derive(clap::Args, Debug)]
pub struct PreprocessArgs {
    /// Remove a drift from every channel before the statistics (least squares; recorded in preprocessing).
    #[arg(long, value_enum)]
    pub detrend: Option<DetrendArg>,
    /// Remove outliers: mad:K, a sample farther than K MAD-based standard deviations from the median (K from 2 to 100; e.g. mad:5).
    #[arg(long, value_name = "mad:K")]
    pub outliers: Option<String>,
    /// Fill missing samples and the stamps' gaps by straight lines between their neighbours (recorded, row by row).
    #[arg(long, value_enum)]
    pub fill: Option<FillArg>,
}

/// `--detrend`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum DetrendArg {
    /// c + b t.
    Linear,
    /// c + b t + a t^2.
    Quadratic,
    /// c + a ln(1 + b t) (Stable32's log drift).
    Log,
}

/// `--fill`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum FillArg {
    /// Missing samples and the periods the stamps skip.
    Gaps,
}

impl PreprocessArgs {
    /// The core's options.
    fn options(&self) -> PreprocessOptions {
        PreprocessOptions {
            detrend: self.detrend.map(|d| match d {
                DetrendArg::Linear => Detrend::Linear,
                DetrendArg::Quadratic => Detrend::Quadratic,
                DetrendArg::Log => Detrend::Log,
            }),
            outliers: self.outliers.clone(),
            fill: self.fill.map(|_| Fill::Gaps),
        }
    }
}

/// The power spectral density of `incal noise`.
#[derive(clap::Args, Debug)]
pub struct PsdArgs {
    /// Also the power spectral density of every channel (Welch, chi-square bounds, the white level and its N beside the Allan fit's).
    #[arg(long)]
    pub psd: bool,
    /// Samples per PSD segment (default: the largest power of two with at least 8 segments, 16 to 65536).
    #[arg(long)]
    pub psd_segment_samples: Option<usize>,
    /// Overlap of the PSD segments, samples (default half a segment).
    #[arg(long)]
    pub psd_overlap_samples: Option<usize>,
    /// The window of each PSD segment.
    #[arg(long, value_enum, default_value = "hann")]
    pub psd_window: super::response::WindowArg,
    /// Confidence of the PSD's chi-square bounds (default 0.95).
    #[arg(long)]
    pub psd_confidence: Option<f64>,
    /// The band of the white level, Hz: LOW,HIGH (default 5 % to 25 % of the rate).
    #[arg(long, value_delimiter = ',', num_args = 2)]
    pub psd_white_band_hz: Option<Vec<f64>>,
    /// The tone search's false-alarm rate per spectrum (default 0.01).
    #[arg(long)]
    pub psd_false_alarm: Option<f64>,
    /// Also fit a first-order Gauss-Markov bias (sigma, correlation time, with u) to every channel's Allan variance, with its discrete-time form.
    #[arg(long)]
    pub gauss_markov: bool,
    /// The filter rate of the Gauss-Markov bias's discrete-time form, Hz (default the record's rate).
    #[arg(long)]
    pub gm_filter_rate_hz: Option<f64>,
}

impl PsdArgs {
    /// The core's options.
    fn options(&self) -> SpectrumOptions {
        SpectrumOptions {
            psd: self.psd,
            psd_segment_samples: self.psd_segment_samples,
            psd_overlap_samples: self.psd_overlap_samples,
            psd_window: self.psd_window.into(),
            psd_confidence: self.psd_confidence,
            psd_white_band_hz: self.psd_white_band_hz.clone(),
            psd_false_alarm: self.psd_false_alarm,
        }
    }
}

/// Progress bars on stderr, one per stage of the core's [`Progress`],
/// when it is a terminal and not `--quiet` (nothing otherwise).
struct Bars {
    on: bool,
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    fn new(quiet: bool) -> Self {
        Self {
            on: !quiet && std::io::stderr().is_terminal(),
            bar: Mutex::new(None),
        }
    }
}

impl Progress for Bars {
    fn start(&self, what: &str, len: u64) {
        if !self.on {
            return;
        }
        let b = indicatif::ProgressBar::new(len);
        b.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{msg}} [{{bar:40}}] {{pos}}/{{len}} {what} {{elapsed}}"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        b.set_message("incal noise");
        if let Ok(mut g) = self.bar.lock() {
            if let Some(old) = g.replace(b) {
                old.finish_and_clear();
            }
        }
    }

    fn advance(&self, n: u64) {
        if !self.on {
            return;
        }
        if let Ok(g) = self.bar.lock() {
            if let Some(b) = g.as_ref() {
                b.inc(n);
            }
        }
    }

    fn finish(&self) {
        if !self.on {
            return;
        }
        if let Ok(mut g) = self.bar.lock() {
            if let Some(b) = g.take() {
                b.finish_and_clear();
            }
        }
    }
}

/// `incal noise`.
pub fn run(a: &Args) -> CliResult<()> {
    let options = NoiseOptions {
        rate_hz: a.rate_hz,
        quantity: a.quantity.into(),
        unit: a.unit.clone(),
        data: match a.data {
            DataArg::Rate => DataKind::Rate,
            DataArg::Angle => DataKind::Angle,
        },
        taus: a.taus.clone(),
        deviations: a.deviations.clone(),
        confidence: a.confidence,
        stability_tau_s: a.stability_tau_s.clone(),
        format: a.format.into(),
        channels: a.channels,
        parallel: !a.sequential,
        sort_time: a.sort_time,
        three_cornered_hat: a.three_cornered_hat,
        spectrum: a.psd.options(),
        markov: incal::procedures::noise::gauss_markov::MarkovOptions {
            gauss_markov: a.psd.gauss_markov,
            gm_filter_rate_hz: a.psd.gm_filter_rate_hz,
        },
        preprocess: a.pre.options(),
        davar: incal::procedures::noise::davar::DavarOptions {
            davar: a.davar.clone(),
        },
        temperature: incal::procedures::noise::temperature::TemperatureOptions {
            temperature_bin_c: a.temperature_bin_c,
        },
    };
    let bars = Bars::new(a.quiet);
    let sample = match a.format {
        FormatArg::Csv => {
            return crate::run::reduce::<Noise>(&a.input, &a.read, &options, &a.result, &bars)
        }
        FormatArg::F32le => Sample::F32le,
        FormatArg::F64le => Sample::F64le,
    };
    // Options first (a bad option is named before the file is opened).
    <Noise as incal::procedures::Procedure>::validate(&options).map_err(core)?;
    if a.result.monte_carlo.is_some() {
        return Err(core(incal::Error::InvalidOption {
            key: "monte_carlo".into(),
            message: "a binary record is analysed mapped, in place: the Monte Carlo draws from a CSV record (export the channels to CSV, or analyse a stretch of it)".into(),
        }));
    }
    let read = a.read.options()?;
    if read.segment.is_some() || read.header_line.is_some() {
        return Err(crate::error::CliError::Input(
            "--segment-by and --header-line read CSV text, not a binary record (--format)".into(),
        ));
    }
    let rec = MappedRecord::open(&a.input, a.channels.unwrap_or(0), sample)?;
    let doc = reduce_mapped(&rec, &read.columns, &options, &bars).map_err(core)?;
    a.result.emit(doc)
}

/// `incal simulate noise`.
#[derive(clap::Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Output format: csv (time_s,ch1,...) or raw interleaved f32le / f64le.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: FormatArg,
    /// Output file (- = standard output, csv only).
    #[arg(long, short = 'o')]
    pub output: PathBuf,
}

/// The record of `incal simulate noise` and of `incal plan noise`: the
/// noise terms of one quantity, the rate, the length, the channels and the
/// seed.
#[derive(clap::Args, Debug)]
pub struct SessionArgs {
    /// What to simulate: gyro (rate in deg/s, the --arw-deg-rth ... options) or accel (in g, the --vrw-ug-rthz ... options).
    #[arg(long, value_enum, default_value = "gyro")]
    pub quantity: QuantityArg,
    /// Accelerometer: velocity random walk N, ug/sqrt(Hz).
    #[arg(long, default_value_t = 0.0)]
    pub vrw_ug_rthz: f64,
    /// Accelerometer: bias instability B, ug (flicker, Kasdin & Walter).
    #[arg(long, default_value_t = 0.0)]
    pub bias_instability_ug: f64,
    /// Accelerometer: acceleration random walk K, ug/sqrt(s).
    #[arg(long, default_value_t = 0.0)]
    pub accel_rw_ug_rts: f64,
    /// Accelerometer: velocity quantization Q, m/s.
    #[arg(long, default_value_t = 0.0)]
    pub quantization_m_s: f64,
    /// Accelerometer: acceleration ramp R, ug/s.
    #[arg(long, default_value_t = 0.0)]
    pub accel_ramp_ug_s: f64,
    /// Angle random walk N, deg/sqrt(h).
    #[arg(long, default_value_t = 0.0)]
    pub arw_deg_rth: f64,
    /// Bias instability B, deg/h (flicker rate, Kasdin & Walter).
    #[arg(long, default_value_t = 0.0)]
    pub bias_instability_deg_h: f64,
    /// Rate random walk K, deg/h/sqrt(h).
    #[arg(long, default_value_t = 0.0)]
    pub rrw_deg_h_rth: f64,
    /// Angle quantization Q, arcsec.
    #[arg(long, default_value_t = 0.0)]
    pub quantization_arcsec: f64,
    /// Rate ramp R, deg/h^2.
    #[arg(long, default_value_t = 0.0)]
    pub rate_ramp_deg_h2: f64,
    /// Sample rate, Hz.
    #[arg(long)]
    pub rate_hz: f64,
    /// Record length, s.
    #[arg(long)]
    pub duration_s: f64,
    /// Channels (independent, seeded from --seed).
    #[arg(long, default_value_t = 1)]
    pub channels: usize,
    /// Random seed.
    #[arg(long)]
    pub seed: u64,
    /// A line added to every channel: FREQ_HZ:RMS (rms amplitude in deg/s or g; repeatable).
    #[arg(long = "tone", value_name = "FREQ_HZ:RMS", value_parser = parse_tone)]
    pub tones: Vec<SimTone>,
    /// A first-order Gauss-Markov bias: its standard deviation in the sample unit (deg/s or g).
    #[arg(long, default_value_t = 0.0)]
    pub gm_sigma: f64,
    /// Its correlation time, s.
    #[arg(long, default_value_t = 0.0)]
    pub gm_tau_s: f64,
}

/// `FREQ_HZ:RMS` into a simulated line.
fn parse_tone(s: &str) -> Result<SimTone, String> {
    let (f, a) = s
        .split_once(':')
        .ok_or_else(|| format!("FREQ_HZ:RMS, got '{s}'"))?;
    let num = |v: &str| v.trim().parse::<f64>().map_err(|_| format!("FREQ_HZ:RMS, got '{s}'"));
    Ok(SimTone {
        frequency_hz: num(f)?,
        amplitude_rms: num(a)?,
    })
}

impl SessionArgs {
    /// The simulator's options, written as `format`.
    fn options(&self, format: Format) -> NoiseSim {
        NoiseSim {
            quantity: self.quantity.into(),
            arw_deg_rth: self.arw_deg_rth,
            bias_instability_deg_h: self.bias_instability_deg_h,
            rrw_deg_h_rth: self.rrw_deg_h_rth,
            quantization_arcsec: self.quantization_arcsec,
            rate_ramp_deg_h2: self.rate_ramp_deg_h2,
            vrw_ug_rthz: self.vrw_ug_rthz,
            bias_instability_ug: self.bias_instability_ug,
            accel_rw_ug_rts: self.accel_rw_ug_rts,
            quantization_m_s: self.quantization_m_s,
            accel_ramp_ug_s: self.accel_ramp_ug_s,
            rate_hz: self.rate_hz,
            duration_s: self.duration_s,
            channels: self.channels,
            seed: self.seed,
            format,
            tones: self.tones.clone(),
            gm_sigma: self.gm_sigma,
            gm_tau_s: self.gm_tau_s,
        }
    }
}

/// Options of `incal plan noise`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    #[command(flatten)]
    pub session: SessionArgs,
    /// Records simulated and analysed (seeds --seed, --seed + 1, …): the predicted u is the root mean square of their u.
    #[arg(long, default_value_t = 5)]
    pub seeds: usize,
    #[command(flatten)]
    pub out: crate::output::PlanOut,
}

/// `incal plan noise`: the record simulated with the planned terms and
/// length and analysed as `incal noise` would (a few seeds): the u of every
/// noise term it will identify.
pub fn plan(a: &PlanArgs) -> CliResult<()> {
    use incal::procedures::noise::plan::NoisePlan;
    use incal::procedures::sim_plan::SimPlanOptions;
    use incal::procedures::Plan;
    let o = SimPlanOptions {
        session: a.session.options(Format::Csv),
        reduce: None,
        seeds: a.seeds,
    };
    a.out
        .emit(&NoisePlan::plan(&o).map_err(core)?)
}

/// `incal simulate noise`: rate samples in deg/s (gyro) or g (accel).
pub fn simulate(a: &SimArgs) -> CliResult<()> {
    use incal::procedures::{noise::Noise, Simulate};
    let sim = a.session.options(a.format.into());
    if a.format == FormatArg::Csv {
        return crate::run::simulate::<Noise>(&sim, Some(&a.output));
    }
    Noise::validate(&sim).map_err(core)?;
    if incal_io::is_dash(&a.output) {
        return Err(usage(
            "--format f32le/f64le writes a file, not standard output",
        ));
    }
    // The output is opened before the (possibly long) simulation, so a
    // path that cannot be written fails at once.
    crate::io::write_binary_stream(Some(&a.output), |out| {
        Noise::simulate(&sim, out).map_err(|e| std::io::Error::other(e.to_string()))
    })
}

// The commands of this file in the command tree (`crate::commands`).

/// This file's commands at the top level (`incal …`).
#[derive(clap::Subcommand, Debug)]
pub enum Reductions {
    /// Noise and stability of long static records: OADEV, MDEV, OHDEV, TDEV, TOTDEV with confidence bounds, IEEE 952 noise terms, bias stability.
    Noise(Box<Args>),
}

impl crate::commands::Run for Reductions {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Noise(a) => run(a),
        }
    }
}

/// This file's plans (`incal plan …`).
#[derive(clap::Subcommand, Debug)]
pub enum Plans {
    /// Noise plan: the record simulated with the planned terms and length and analysed (a few seeds): the u of every noise term and bias stability it will report.
    Noise(PlanArgs),
}

impl crate::commands::Run for Plans {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Noise(a) => plan(a),
        }
    }
}

/// This file's simulators (`incal simulate …`).
#[derive(clap::Subcommand, Debug)]
pub enum Simulations {
    /// Rate-noise record (gyro) with IEEE 952 terms: quantization, white, flicker, random walk, ramp.
    Noise(SimArgs),
}

impl crate::commands::Run for Simulations {
    fn run(&self) -> CliResult<()> {
        match self {
            Self::Noise(a) => simulate(a),
        }
    }
}
