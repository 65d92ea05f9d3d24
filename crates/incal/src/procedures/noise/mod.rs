//! Noise and stability of long static records (`"procedure": "noise"`):
//! the Allan family of deviations with confidence intervals, the IEEE
//! Std 952 noise terms and bias stability of every channel.
//!
//! # Model
//! Rate samples `y_k` (gyro rate, accelerometer specific force, any rate
//! unit `u`) at spacing `τ0 = 1/F` are analysed as phase
//! `x_0 = 0`, `x_{k+1} = x_k + (y_k − c) τ0` (NIST SP 1065, W. J. Riley,
//! "Handbook of Frequency Stability Analysis", 2008, §5.2; the constant
//! `c` of [`crate::noise::phase_reference`] only adds a line every
//! deviation is blind to); angle (velocity increment) sums are the phase
//! itself. On the phase, at every averaging time `τ = m τ0` of the grid:
//! OADEV, MDEV, OHDEV, TDEV and TOTDEV ([`crate::noise::stability`]), the
//! power-law noise identified per τ and χ² bounds at the requested
//! confidence from the Greenhall & Riley equivalent degrees of freedom
//! (C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances
//! based on finite differences", PTTI 2003).
//!
//! # Terms
//! The Allan variance model of IEEE Std 952-1997 Annex C (eq. C.15 ff.),
//! `σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π) B² + K²τ/3 + R²τ²/2`
//!
//! | symbol | term | gyro unit | accelerometer unit |
//! |---|---|---|---|
//! | Q | quantization | arcsec | m/s |
//! | N | angle (velocity) random walk | deg/√h | µg/√Hz |
//! | B | bias instability | deg/h | µg |
//! | K | rate (acceleration) random walk | deg/h/√h | µg/√s |
//! | R | rate (acceleration) ramp | deg/h² | µg/s |
//!
//! fitted to OADEV by weighted least squares with the EDF's weights
//! ([`crate::noise::terms::fit_terms`]), with the slope-line readings of
//! IEEE Std 952 Fig. C.2 beside them, and bias stability (the standard
//! deviation of τ-averages, GJB 2426A / IEEE Std 1431) at each requested τ.
//! Accelerometer units follow IEEE Std 1293-2018.
//!
//! # Inputs
//! A CSV record ([`input::read`]: one column per channel, an optional
//! `time_s`) through the input layer ([`Noise`] is a [`Procedure`]), or a
//! raw interleaved little-endian `f32`/`f64` record mapped in place
//! ([`reduce_mapped`] over an [`incal_io::binary::MappedRecord`]).
//!
//! # Speed
//! Channels are analysed in parallel (rayon; `parallel: false` gives the
//! same bits on one thread). A mapped record is read once: each window is
//! checked and, when the channels' arrays fit in the file's size, built
//! into the phase in the same pass, then its pages are released, while the
//! record's SHA-256 runs on a thread of its own (`input::read_mapped`).

pub mod davar;
pub mod document;
pub mod export;
mod gaps;
pub mod gauss_markov;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod preprocess;
pub mod sim;
pub mod spectrum;
pub mod stacks;
pub mod temperature;
use gaps::gapped;
pub(crate) use gaps::stretches;
pub use gaps::MAX_STRETCHES;

use rayon::prelude::*;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::document::ResultDocument;
use crate::error::{Error, Result};
use crate::noise::{
    phase_fill, phase_from_rate_with, stability_with_progress, terms, Deviation, Series, Stability,
    StabilityOptions, Statistic, TauGrid,
};
use crate::procedures::{options_map, Procedure, Progress};
use document::{ChannelResult, Quantity};
use input::{Channels, Samples};

/// What the channels measure, and so the units of the noise terms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum QuantityKind {
    /// Gyro: rate in deg/s, rad/s or deg/h.
    Gyro,
    /// Accelerometer: specific force in g, mg or m/s².
    Accel,
    /// Anything else: terms in the input unit.
    #[default]
    Generic,
}

impl QuantityKind {
    /// The unit of the samples when none is given: deg/s, g or 1.
    pub fn default_unit(self) -> &'static str {
        match self {
            QuantityKind::Gyro => "deg/s",
            QuantityKind::Accel => "g",
            QuantityKind::Generic => "1",
        }
    }
}

/// What the samples are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum DataKind {
    /// Rate ("frequency") samples in the unit.
    #[default]
    Rate,
    /// Angle or velocity-increment sums ("phase") in the unit times s.
    Angle,
}

/// How the record is stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// CSV with a header (through [`incal_io::Reader`]).
    #[default]
    Csv,
    /// Raw little-endian 32-bit floats, channels interleaved.
    F32le,
    /// Raw little-endian 64-bit floats, channels interleaved.
    F64le,
}

/// Options of a noise analysis. Serialised (the document's `options`,
/// [`NoiseOptions::settled`]) as `rate_hz`, `quantity`, `unit` (the unit
/// in use, the default filled in), `data`, `taus`, `deviations` (when not
/// the default), `stability_tau_s`, `confidence`, and `sort_time` and
/// `three_cornered_hat` when set; the storage (`format`, `channels`) and
/// `parallel` change no number and are not recorded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct NoiseOptions {
    /// Sample rate F (Hz); τ0 = 1/F. `None`: the rate of the record's
    /// `time_s` stamps (a record without stamps then is refused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
    /// What the channels measure.
    #[serde(default)]
    pub quantity: QuantityKind,
    /// Unit of the samples: deg/s, rad/s, deg/h (gyro); g, mg, m/s2
    /// (accel); any text (generic). `None`: [`QuantityKind::default_unit`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// Rate samples or their running sums.
    #[serde(default)]
    pub data: DataKind,
    /// Averaging times: `octave`, `decade`, `all` or N points per decade.
    #[serde(default = "default_taus")]
    pub taus: String,
    /// The statistics reported, comma separated ([`DEFAULT_DEVIATIONS`];
    /// `all` adds every [`Statistic`], MTIE and TIE rms only for angle
    /// data). OADEV and the noise identification are computed whatever
    /// the list (the term fit reads them).
    #[serde(
        default = "default_deviations",
        skip_serializing_if = "is_default_deviations"
    )]
    pub deviations: String,
    /// Confidence of the deviation bounds, 0 < P < 1 (Stable32: 0.683).
    #[serde(default = "default_confidence")]
    pub confidence: f64,
    /// Averaging times (s) of bias stability.
    #[serde(default = "default_stability_tau_s")]
    pub stability_tau_s: Vec<f64>,
    /// How the record is stored (not recorded).
    #[serde(default, skip_serializing)]
    pub format: Format,
    /// Interleaved channels of a binary record (binary formats only; not
    /// recorded).
    #[serde(default, skip_serializing)]
    pub channels: Option<usize>,
    /// Channels and sums on rayon's threads (the same bits either way;
    /// not recorded).
    #[serde(default = "default_parallel", skip_serializing)]
    pub parallel: bool,
    /// Put CSV rows that are out of time order in order by `time_s`
    /// instead of refusing them (warning `time-sorted`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub sort_time: bool,
    /// Three instruments recorded together (exactly three channels): each
    /// one's OADEV by the three-cornered hat
    /// ([`crate::noise::three_cornered_hat`]), in `three_cornered_hat`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub three_cornered_hat: bool,
    /// The power spectral density (`psd` and its settings).
    #[serde(flatten)]
    pub spectrum: spectrum::SpectrumOptions,
    /// The Gauss–Markov bias (`gauss_markov` and its filter rate).
    #[serde(flatten)]
    pub markov: gauss_markov::MarkovOptions,
    /// The dynamic Allan variance (`davar`).
    #[serde(flatten)]
    pub davar: davar::DavarOptions,
    /// Noise against temperature (`temperature_bin_c`).
    #[serde(flatten)]
    pub temperature: temperature::TemperatureOptions,
    /// Preprocessing before the statistics (`outliers`, `fill`,
    /// `detrend`), each step recorded in `preprocessing`.
    #[serde(flatten)]
    pub preprocess: preprocess::PreprocessOptions,
}

fn default_taus() -> String {
    "octave".into()
}

fn default_deviations() -> String {
    DEFAULT_DEVIATIONS.into()
}

fn default_confidence() -> f64 {
    0.683
}

fn default_stability_tau_s() -> Vec<f64> {
    vec![10.0, 100.0]
}

fn default_parallel() -> bool {
    true
}

impl Default for NoiseOptions {
    fn default() -> Self {
        Self {
            rate_hz: None,
            quantity: QuantityKind::Generic,
            unit: None,
            data: DataKind::Rate,
            taus: default_taus(),
            deviations: default_deviations(),
            confidence: default_confidence(),
            stability_tau_s: default_stability_tau_s(),
            format: Format::Csv,
            channels: None,
            parallel: true,
            sort_time: false,
            three_cornered_hat: false,
            spectrum: spectrum::SpectrumOptions::default(),
            markov: gauss_markov::MarkovOptions::default(),
            davar: davar::DavarOptions::default(),
            temperature: temperature::TemperatureOptions::default(),
            preprocess: preprocess::PreprocessOptions::default(),
        }
    }
}

/// The statistics reported by default.
pub const DEFAULT_DEVIATIONS: &str = "oadev,mdev,ohdev,tdev,totdev";

fn is_default_deviations(s: &str) -> bool {
    s == DEFAULT_DEVIATIONS
}

/// The statistics of a `deviations` list: the default five shown, and the
/// others ([`crate::noise::more`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// Of OADEV, MDEV, OHDEV, TDEV, TOTDEV, those shown.
    pub shown: Vec<Deviation>,
    /// The other statistics, in the document's order.
    pub more: Vec<Statistic>,
    /// TOTDEV was asked for by name (not by the default list).
    pub totdev_named: bool,
}

/// [`Error::InvalidOption`] for `key`.
fn invalid(key: &str, message: impl Into<String>) -> Error {
    Error::InvalidOption {
        key: key.into(),
        message: message.into(),
    }
}

impl NoiseOptions {
    /// The options as recorded in the document: the unit in use (the
    /// quantity's default filled in) and the sample rate used (`rate_hz`,
    /// from the stamps when none was given).
    pub fn settled(&self, rate_hz: Option<f64>) -> NoiseOptions {
        NoiseOptions {
            rate_hz: rate_hz.or(self.rate_hz),
            unit: Some(self.unit_text().to_string()),
            ..self.clone()
        }
    }

    /// The unit of the samples (the default of the quantity when none is given).
    pub fn unit_text(&self) -> &str {
        self.unit.as_deref().unwrap_or(self.quantity.default_unit())
    }

    /// The quantity with its term units, the unit text, and the factor
    /// from the input unit to the internal one (deg/s for gyros, g for
    /// accelerometers, the unit itself otherwise).
    pub fn units(&self) -> Result<(Quantity, String, f64)> {
        let u = self.unit_text();
        let bad = |ok: &str| invalid("unit", format!("'{}' is not a {ok}", incal_io::clip(u)));
        Ok(match self.quantity {
            QuantityKind::Gyro => {
                let f = match u {
                    "deg/s" => 1.0,
                    "rad/s" => 180.0 / std::f64::consts::PI,
                    "deg/h" => 1.0 / 3600.0,
                    _ => return Err(bad("gyro unit: deg/s, rad/s or deg/h")),
                };
                (Quantity::Gyro, u.to_string(), f)
            }
            QuantityKind::Accel => {
                let f = match u {
                    "g" => 1.0,
                    "mg" => 1e-3,
                    "m/s2" => 1.0 / crate::units::STANDARD_GRAVITY_M_S2,
                    _ => return Err(bad("accelerometer unit: g, mg or m/s2")),
                };
                (Quantity::Accel, u.to_string(), f)
            }
            QuantityKind::Generic => (Quantity::Generic(u.to_string()), u.to_string(), 1.0),
        })
    }

    /// The statistics of [`NoiseOptions::deviations`]: a comma-separated
    /// list of oadev, mdev, ohdev, tdev, totdev, adev, hdev, mtotdev,
    /// htotdev, theo1, theoh, mtie, tierms, or `all`.
    pub fn selection(&self) -> Result<Selection> {
        let mut shown = Vec::new();
        let mut more = Vec::new();
        for name in self.deviations.split(',').map(str::trim) {
            if name == "all" {
                shown.extend(Deviation::ALL);
                more.extend(
                    Statistic::ALL
                        .into_iter()
                        .filter(|s| !s.is_time_error() || self.data == DataKind::Angle),
                );
            } else if let Some(d) = Deviation::ALL.into_iter().find(|d| d.as_str() == name) {
                shown.push(d);
            } else if let Some(s) = Statistic::parse(name) {
                more.push(s);
            } else {
                return Err(invalid(
                    "deviations",
                    format!("'{}' is not one of oadev, mdev, ohdev, tdev, totdev, adev, hdev, mtotdev, htotdev, theo1, theoh, mtie, tierms, or all", incal_io::clip(name)),
                ));
            }
        }
        let shown: Vec<Deviation> = Deviation::ALL
            .into_iter()
            .filter(|d| shown.contains(d))
            .collect();
        let more: Vec<Statistic> = Statistic::ALL
            .into_iter()
            .filter(|s| more.contains(s))
            .collect();
        Ok(Selection {
            totdev_named: shown.contains(&Deviation::Totdev)
                && self.deviations != DEFAULT_DEVIATIONS,
            shown,
            more,
        })
    }

    /// The τ grid of [`NoiseOptions::taus`].
    pub fn grid(&self) -> Result<TauGrid> {
        TauGrid::parse(&self.taus).ok_or_else(|| {
            invalid(
                "taus",
                format!(
                    "'{}' is not octave, decade, all or a number of points per decade (1-1000)",
                    incal_io::clip(&self.taus)
                ),
            )
        })
    }

    /// The fewest samples one averaging time needs: 4 rate samples (5
    /// phase points), or 5 angle samples.
    pub fn min_samples(&self) -> usize {
        match self.data {
            DataKind::Rate => 4,
            DataKind::Angle => 5,
        }
    }

    /// The array each channel is analysed as, at sample rate `rate_hz`.
    fn build(&self, factor: f64, rate_hz: f64) -> Build {
        Build {
            factor,
            tau0: 1.0 / rate_hz,
            rate: self.data == DataKind::Rate,
        }
    }
}

/// The noise and stability analysis as a [`Procedure`] over CSV records
/// (binary records: [`reduce_mapped`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Noise;

impl Procedure for Noise {
    const ID: crate::document::Procedure = crate::document::Procedure::Noise;
    type Options = NoiseOptions;
    type Input = Channels;

    fn example() -> NoiseOptions {
        NoiseOptions {
            rate_hz: Some(100.0),
            // Sequential: the same numbers, and a fuzzer's process stays
            // on one thread.
            parallel: false,
            // The spectrum, its tone search and the Gauss–Markov fit too, so
            // the fuzz targets reach them.
            spectrum: spectrum::SpectrumOptions {
                psd: true,
                ..spectrum::SpectrumOptions::default()
            },
            markov: gauss_markov::MarkovOptions {
                gauss_markov: true,
                gm_filter_rate_hz: None,
            },
            ..NoiseOptions::default()
        }
    }

    /// The sample rate positive, the confidence in (0, 1), the τ grid
    /// known, every bias-stability τ positive, the unit one of the
    /// quantity's, and `channels` given with (and only with) a binary
    /// format, at least 1.
    fn validate(o: &NoiseOptions) -> Result<()> {
        if let Some(r) = o.rate_hz {
            crate::options::check_positive("rate_hz", r)?;
        }
        if !(o.confidence > 0.0 && o.confidence < 1.0) {
            return Err(invalid(
                "confidence",
                format!(
                    "must be between 0 and 1 (e.g. 0.683), got {}",
                    crate::error::short_f64(o.confidence)
                ),
            ));
        }
        o.grid()?;
        o.selection()?;
        if let Some(t) = o
            .stability_tau_s
            .iter()
            .find(|t| !(t.is_finite() && **t > 0.0))
        {
            return Err(invalid(
                "stability_tau_s",
                format!(
                    "every time must be a positive number of seconds, got {}",
                    crate::error::short_f64(*t)
                ),
            ));
        }
        o.units()?;
        o.spectrum.validate()?;
        o.davar.validate()?;
        o.temperature.validate()?;
        o.markov.validate()?;
        o.preprocess.validate()?;
        match (o.format, o.channels) {
            (Format::Csv, Some(_)) => Err(invalid(
                "channels",
                "goes with format f32le or f64le (a CSV record names its columns)",
            )),
            (Format::F32le | Format::F64le, None) => Err(invalid(
                "channels",
                "format f32le/f64le needs the number of interleaved channels",
            )),
            (_, Some(0)) => Err(invalid("channels", "at least 1, got 0")),
            _ => Ok(()),
        }
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &NoiseOptions,
    ) -> Result<Channels> {
        if o.format != Format::Csv {
            return Err(Error::Unsupported(
                "a binary record is read mapped (reduce_mapped), not as CSV".into(),
            ));
        }
        input::read(rows, o.rate_hz, o.sort_time)
    }

    /// The options with the sample rate used (from the stamps when none
    /// was given).
    fn recorded(
        input: &Channels,
        o: &NoiseOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        options_map(&o.settled(Some(input.rate_hz)))
    }

    fn reduce(
        input: &Channels,
        o: &NoiseOptions,
        progress: &dyn Progress,
    ) -> Result<ResultDocument> {
        let (quantity, unit, factor) = o.units()?;
        // The record is copied only when a step changes it.
        let (pre, audit) = match preprocess::apply(input, &o.preprocess)? {
            Some((c, list, table)) => (std::borrow::Cow::Owned(c), Some((list, table))),
            None => (std::borrow::Cow::Borrowed(input), None),
        };
        let input: &Channels = &pre;
        let build = o.build(factor, input.rate_hz);
        let mut results = analyse(
            &Samples::Columns(&input.samples),
            &input.names,
            input.rows,
            None,
            &input.gaps,
            build,
            o,
            progress,
        )?;
        let temps = temperature::compute(input, o, build)?;
        for (r, t) in results.iter_mut().zip(temps) {
            r.temperature = t;
        }
        let mut doc = document::document(
            &o.selection()?.shown,
            &results,
            &quantity,
            &unit,
            o.confidence,
            o.grid()? != TauGrid::All,
        )?;
        doc.warnings
            .extend(unit_suspect(&input.names, &input.samples, o, factor));
        if input.sorted > 0 {
            doc.warnings
                .push(crate::timebase::sorted_warning(input.sorted, input.rows));
        }
        let gap_aware = format!(
            "the deviations leave out every term that spans a gap (n at each tau counts the terms kept; tau up to a quarter of the longest stretch){}",
            if o.selection()?.shown.contains(&Deviation::Totdev) {
                "; TOTDEV, defined by reflecting the whole record, is not reported"
            } else {
                ""
            }
        );
        if let Some(tb) = &input.timebase {
            let mut w = tb.warnings();
            for x in &mut w {
                if x.code == crate::WarningCode::TimeGaps {
                    x.message.push_str("; ");
                    x.message.push_str(if o.preprocess.fill.is_some() {
                        "filled by straight lines before the statistics (preprocessing)"
                    } else {
                        &gap_aware
                    });
                }
            }
            doc.warnings.extend(w);
        }
        if let Some((list, table)) = audit {
            doc.extra.insert("preprocessing".into(), list);
            doc.tables.push(table);
        }
        if o.three_cornered_hat {
            doc.extra
                .insert("three_cornered_hat".into(), hat(input, o, factor)?);
        }
        if input.duplicates > 0 {
            doc.warnings.push(crate::warning::Warning::new(
                crate::WarningCode::TimeRepeats,
                format!(
                    "{} rows equal to the row before in time_s and every channel were dropped as the logger's repeats (the stamps repeat off any regular grid, so they are not a coarse clock's)",
                    input.duplicates
                ),
            ));
        }
        for (name, col) in input.names.iter().zip(&input.samples) {
            let missing = col.iter().filter(|v| v.is_nan()).count();
            if missing > 0 {
                let runs = stretches(col, &[]).len().max(1);
                doc.warnings.push(crate::warning::Warning::new(
                    crate::WarningCode::TimeGaps,
                    format!(
                        "channel {name}: {missing} missing samples (empty or NaN cells), {runs} stretches between them; {gap_aware}"
                    ),
                ));
            }
        }
        Ok(doc)
    }

    fn synthesis(
        input: &Channels,
        o: &NoiseOptions,
        doc: &ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Channels>>> {
        montecarlo::synthesis(input, o, doc).map(Some)
    }
}

/// Reduce a mapped binary record: validate the options, select the
/// channels (`selection`: as [`incal_io::binary::MappedRecord::select`]),
/// read the record once (`input::read_mapped`), analyse every channel
/// and record the input (its SHA-256 and rows) and the options. Errors
/// name the file.
pub fn reduce_mapped(
    rec: &incal_io::binary::MappedRecord,
    selection: &incal_io::ColumnMap,
    o: &NoiseOptions,
    progress: &dyn Progress,
) -> Result<ResultDocument> {
    Noise::validate(o)?;
    let name = rec.name();
    if o.three_cornered_hat {
        return Err(Error::Unsupported(format!(
            "{name}: the three-cornered hat reads CSV records (give the three instruments as three columns)"
        )));
    }
    let rate_hz = o.rate_hz.ok_or_else(|| {
        Error::Unsupported(format!(
            "{name}: a binary record has no time_s: give the sample rate (`rate_hz`)"
        ))
    })?;
    let pick = rec.select(selection)?;
    let environment = pick
        .iter()
        .any(|p| incal_io::CONDITION_COLUMNS.contains(&p.1.as_str()));
    if o.preprocess.any() || environment || o.temperature.temperature_bin_c.is_some() {
        return preprocess::reduce_mapped(rec, pick, rate_hz, o, progress);
    }
    let (quantity, unit, factor) = o.units()?;
    let build = o.build(factor, rate_hz);
    // A record in memory is hashed on a thread of its own while it is
    // read and analysed (a file's hash thread reads the file itself).
    std::thread::scope(|s| {
        let memory_hash = rec
            .memory()
            .filter(|_| o.parallel)
            .map(|b| s.spawn(move || incal_io::sha256_hex(b)));
        let read = input::read_mapped(rec, &pick, build, o.parallel, progress)
            .map_err(|e| e.in_file(name))?;
        let index: Vec<usize> = pick.iter().map(|p| p.0).collect();
        let names: Vec<String> = pick.into_iter().map(|p| p.1).collect();
        let results = analyse(
            &Samples::Mapped { rec, index },
            &names,
            rec.rows(),
            read.built,
            &[],
            build,
            o,
            progress,
        )
        .map_err(|e| e.in_file(name))?;
        let tables = o.grid()? != TauGrid::All;
        let mut doc = document::document(
            &o.selection()?.shown,
            &results,
            &quantity,
            &unit,
            o.confidence,
            tables,
        )?;
        let path = if name == incal_io::source::STDIN_NAME {
            "-"
        } else {
            name
        };
        let sha256 = match (read.hash, memory_hash) {
            (incal_io::binary::RecordHash::Caller, Some(h)) => h.join().map_err(|_| {
                Error::Unsupported(format!("{name}: input hash: its thread failed"))
            })?,
            (hash, _) => hash.finish(name)?,
        };
        doc.inputs.push(crate::document::InputFile {
            role: "input".into(),
            path: path.into(),
            sha256,
            rows: Some(rec.rows() as u64),
        });
        doc.options = options_map(&o.settled(None))?;
        Ok(doc)
    })
}

/// The array each channel is analysed as: the phase of rate samples
/// ([`phase_from_rate_with`]) or the angle samples themselves, times
/// `factor` (input unit to internal unit).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Build {
    pub(crate) factor: f64,
    pub(crate) tau0: f64,
    pub(crate) rate: bool,
}

impl Build {
    /// Length of the array for `rows` samples.
    pub(crate) fn len(&self, rows: usize) -> usize {
        rows + usize::from(self.rate)
    }

    /// The whole array from samples `get(r)` (already × factor): the same
    /// bits as the windows of [`Build::window`].
    fn whole(&self, rows: usize, get: impl Fn(usize) -> f64) -> Vec<f64> {
        if self.rate {
            phase_from_rate_with(rows, self.tau0, get)
        } else {
            (0..rows).map(get).collect()
        }
    }

    /// Rows `r0..r0 + out.len()` of the array, `y(i)` the i-th of them
    /// (already × factor); `acc`: the phase before them, returned moved on
    /// (for angle data `acc + Σ 0·value`: 0 while every value is finite,
    /// NaN for good after one that is not).
    #[inline]
    pub(crate) fn window(
        &self,
        out: &mut [f64],
        acc: f64,
        c: f64,
        y: impl Fn(usize) -> f64,
    ) -> f64 {
        if self.rate {
            phase_fill(out, acc, c, self.tau0, y)
        } else {
            let mut s = acc;
            for (i, o) in out.iter_mut().enumerate() {
                *o = y(i);
                s += 0.0 * *o;
            }
            s
        }
    }
}

/// Every channel of a record: the deviations, the term fit, the
/// slope-line readings and bias stability (channels on rayon's threads
/// when `o.parallel`; the same bits either way). `built`: the channels'
/// arrays when the reading pass built them.
#[allow(clippy::too_many_arguments)]
fn analyse(
    d: &Samples<'_>,
    names: &[String],
    rows: usize,
    built: Option<Vec<Vec<f64>>>,
    gaps: &[(usize, usize)],
    build: Build,
    o: &NoiseOptions,
    progress: &dyn Progress,
) -> Result<Vec<ChannelResult>> {
    let min = o.min_samples();
    if rows < min {
        return Err(Error::Unsupported(format!(
            "{rows} samples; at least {min} are needed for one averaging time"
        )));
    }
    let grid = o.grid()?;
    let tau0 = build.tau0;
    if let Some(&t) = o.stability_tau_s.iter().find(|&&t| t < tau0 * (1.0 - 1e-9)) {
        return crate::options::invalid(
            "stability_tau_s",
            format!(
                "{} s is shorter than the sample period {} s: no averaging time below it is measured",
                crate::error::short_f64(t),
                // The period to the nanosecond (stamps carry round-off).
                (tau0 * 1e9).round() / 1e9
            ),
        );
    }
    let factor = build.factor;
    let opts = StabilityOptions {
        tau0_s: tau0,
        grid,
        confidence: o.confidence,
        parallel: o.parallel,
    };
    let sel = o.selection()?;
    let total = (grid.factors(rows + 1).len() * names.len()) as u64;
    progress.start("averaging times", total);
    let in_channel = |k: usize| {
        let name = &names[k];
        move |e: Error| Error::Unsupported(format!("channel {name}: {e}"))
    };
    let one = |k: usize| -> Result<ChannelResult> {
        if let Samples::Columns(c) = d {
            if !gaps.is_empty() || c[k].iter().any(|v| v.is_nan()) {
                if !sel.more.is_empty() || sel.totdev_named {
                    let names: Vec<&str> = sel
                        .more
                        .iter()
                        .map(|s| s.as_str())
                        .chain(sel.totdev_named.then_some("totdev"))
                        .collect();
                    return Err(in_channel(k)(Error::Unsupported(format!(
                        "{} not defined across gaps or missing samples (gap-aware here: oadev, mdev, ohdev, tdev); drop them from --deviations, or analyse the stretches between the gaps separately",
                        names.join(", ")
                    ))));
                }
                return gapped(&names[k], &c[k], gaps, build, &opts, o, &|_| {
                    progress.advance(1)
                })
                .map_err(in_channel(k));
            }
        }
        let win = d.window_rows();
        // Read in windows, each released once read: the phase is the only
        // resident copy of the channel.
        let get = |r: usize| d.get_streamed(k, r, win) * factor;
        let whole;
        let x: &[f64] = match &built {
            Some(b) => &b[k],
            None => {
                whole = build.whole(rows, get);
                d.release(0, rows);
                &whole
            }
        };
        let tick = |_: usize| progress.advance(1);
        let st = stability_with_progress(x, &opts, &tick).map_err(in_channel(k))?;
        let fit = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, tau0, x.len())
            .map_err(in_channel(k))?;
        let slope = terms::slope_readings(&st.taus_s, &st.oadev);
        let bias_stability = o
            .stability_tau_s
            .iter()
            .map(|&t| {
                let b = terms::bias_stability(x, tau0, t);
                (t, b.map(|b| terms::with_model_dof(b, &fit, tau0, t)))
            })
            .collect();
        let more = more_statistics(x, &sel.more, &st, &opts).map_err(in_channel(k))?;
        let spectrum = o.spectrum.compute(x, tau0).map_err(in_channel(k))?;
        let gauss_markov = o.markov.compute(&st, tau0);
        let davar = o
            .davar
            .compute(x, tau0, &st, o.confidence, o.parallel)
            .map_err(in_channel(k))?;
        Ok(ChannelResult {
            name: names[k].clone(),
            samples: rows,
            stability: st,
            fit,
            slope,
            bias_stability,
            more,
            to_input: 1.0 / factor,
            spectrum,
            gauss_markov,
            davar,
            temperature: None,
        })
    };
    let results = if o.parallel {
        (0..names.len())
            .into_par_iter()
            .map(one)
            .collect::<Result<Vec<_>>>()
    } else {
        (0..names.len()).map(one).collect::<Result<Vec<_>>>()
    };
    progress.finish();
    results
}

/// The three-cornered hat of a record's three channels, as the document's
/// `three_cornered_hat`: per channel `{taus_s, value, lo, hi, edf, n}` of
/// its OADEV (input unit).
fn hat(input: &Channels, o: &NoiseOptions, factor: f64) -> Result<serde_json::Value> {
    if input.names.len() != 3 {
        return Err(Error::Unsupported(format!(
            "the three-cornered hat needs exactly three channels (--columns a,b,c); the record has {}: {}",
            input.names.len(),
            input.names.join(", ")
        )));
    }
    if input.has_gaps() {
        return Err(Error::Unsupported(
            "the three-cornered hat is not defined across gaps or missing samples: analyse the stretches between them separately".into(),
        ));
    }
    let build = o.build(factor, input.rate_hz);
    let x: Vec<Vec<f64>> = input
        .samples
        .iter()
        .map(|c| build.whole(input.rows, |r| c[r] * factor))
        .collect();
    let opts = StabilityOptions {
        tau0_s: build.tau0,
        grid: o.grid()?,
        confidence: o.confidence,
        parallel: o.parallel,
    };
    let three = crate::noise::three_cornered_hat([&x[0], &x[1], &x[2]], &opts)?;
    let to_input = |v: &[Option<f64>]| -> Vec<Option<f64>> {
        v.iter().map(|x| x.map(|x| x / factor)).collect()
    };
    let mut out = serde_json::Map::new();
    for (name, s) in input.names.iter().zip(&three) {
        out.insert(
            name.clone(),
            serde_json::json!({
                "taus_s": s.taus_s,
                "value": to_input(&s.dev.value),
                "lo": to_input(&s.dev.lo),
                "hi": to_input(&s.dev.hi),
                "edf": s.dev.edf,
                "n": s.dev.n,
            }),
        );
    }
    Ok(serde_json::Value::Object(out))
}

/// The statistics beyond the default five of one channel's phase `x`
/// ([`crate::noise::statistic`]), on rayon's threads when `opts.parallel`
/// (the same bits either way).
fn more_statistics(
    x: &[f64],
    more: &[Statistic],
    st: &Stability,
    opts: &StabilityOptions,
) -> Result<Vec<(Statistic, Series)>> {
    let one = |&s: &Statistic| crate::noise::statistic(x, s, st, opts).map(|r| (s, r));
    if opts.parallel {
        more.par_iter().map(one).collect()
    } else {
        more.iter().map(one).collect()
    }
}

/// The unit check of an accelerometer record (every channel's mean in g,
/// `factor` from the input unit): a record at rest reads at most 1 g on
/// any axis, so a channel mean above 1.5 g says the samples are not in the
/// unit given (m/s² analysed as g); three channels whose means make a
/// vector of 0.08–0.12 g while the unit is m/s² say the reverse (a triad at
/// rest reads 1 g = 9.8 m/s²). Gyro units cannot be told apart this way.
fn unit_suspect(
    names: &[String],
    samples: &[Vec<f64>],
    o: &NoiseOptions,
    factor: f64,
) -> Option<crate::warning::Warning> {
    if o.quantity != QuantityKind::Accel || o.data != DataKind::Rate {
        return None;
    }
    let means: Vec<f64> = samples
        .iter()
        .map(|s| s.iter().sum::<f64>() / s.len().max(1) as f64 * factor)
        .collect();
    let unit = o.unit_text();
    if let Some((k, m)) = means.iter().enumerate().find(|(_, m)| m.abs() > 1.5) {
        return Some(crate::warning::Warning::new(
            crate::WarningCode::UnitSuspect,
            format!(
                "channel {} averages {} g (unit {unit}): an accelerometer at rest reads at most 1 g, so the samples are probably not in {unit} (m/s2? give --unit m/s2); every noise term scales with the unit",
                names[k],
                crate::error::short_f64(*m)
            ),
        ));
    }
    let norm = means.iter().map(|m| m * m).sum::<f64>().sqrt();
    if unit == "m/s2" && means.len() == 3 && (0.08..=0.12).contains(&norm) {
        return Some(crate::warning::Warning::new(
            crate::WarningCode::UnitSuspect,
            format!(
                "the three channels' means make a vector of {} m/s2: a triad at rest reads 9.8 m/s2, so the samples are probably in g (give --unit g); every noise term scales with the unit",
                crate::error::short_f64(norm / factor)
            ),
        ));
    }
    None
}

#[cfg(test)]
mod options_tests;
