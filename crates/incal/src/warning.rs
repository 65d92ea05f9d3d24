//! Typed warnings: every warning a procedure gives carries a stable code
//! (for machines: records, limits, reports) and a message (for people).
//!
//! Codes are part of the result schema (`incal.result/1`): a code is never
//! renamed or reused; new situations get new codes.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// What a warning is about. Serialized in kebab-case (`weak-conditioning`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum WarningCode {
    /// The plan determines some combination of terms poorly (condition
    /// number above [`crate::estimation::WARN_COND`]).
    WeakConditioning,
    /// Residuals between positions exceed the sample scatter (χ² test);
    /// uncertainties were scaled up by the residual scatter.
    LackOfFit,
    /// A rate test without a forward/reverse pair: the bias is separated
    /// only through the rate dependence.
    NoReversal,
    /// The total misalignment γ is within 3 u of zero: its linear u and the
    /// azimuth are unreliable.
    SmallAngle,
    /// A raw record does not cover whole table turns, or was truncated.
    PartialTurns,
    /// Part of the data could not be reduced on its own (a pass, a station,
    /// a radius fit); the message says which and why.
    PartFailed,
    /// A centrifuge station has one polarity only: the odd quadratic is
    /// not separated there.
    OnePolarity,
    /// The centrifuge run lacks a piece the radius needs (at-rest rows, the
    /// IA-radial station, one polarity); a nominal value was used.
    RadiusIncomplete,
    /// An input estimate was given without its uncertainty: it is treated
    /// as exact, and every u derived from it is too small by its share.
    MissingUncertainty,
    /// The six-position bias estimates of one accelerometer disagree beyond
    /// their uncertainty.
    InconsistentBias,
    /// The array geometry or a calibrated quantity is outside the range in
    /// which the procedure's linear model holds.
    ModelRange,
    /// An IEEE noise term (quantization, random walk, bias instability,
    /// rate random walk, rate ramp) the record cannot support: not reported.
    NoiseTermNotIdentified,
    /// Two sets of IEEE noise terms explain the Allan variance about
    /// equally well: the record does not separate the terms in which they
    /// differ (e.g. bias instability and rate random walk over a short τ
    /// range); the chosen set is reported.
    NoiseTermsNotSeparated,
    /// The record, or a stretch of it, is too short for what is asked (an
    /// averaging time; a dwell found from the reference).
    ShortRecord,
    /// A statistic whose cost grows as N·m was computed up to an
    /// averaging time only (the longer ones would take too long).
    StatisticTruncated,
    /// A result whose signs say the data follow another convention than the
    /// options (e.g. a rotation in the opposite sense to `--rotation-deg`,
    /// or gravity of the other sign): the numbers are right for the options
    /// given, but probably not what was meant.
    SignConvention,
    /// Time stamps repeat (a clock coarser than the sampling): how many, and
    /// whether the time steps were taken from the sample index
    /// ([`crate::timebase`]).
    TimeRepeats,
    /// Gaps in the time stamps (steps above 1.5 periods): count, longest,
    /// total ([`crate::timebase`]).
    TimeGaps,
    /// Samples of a still section far from its median (robust scale) were
    /// left out of its mean ([`crate::procedures::imu::screen`]).
    Spikes,
    /// A channel sits at its extreme value in many rows (a converter at
    /// full scale).
    Saturated,
    /// Samples at a converter's rail (an integer converter's end or
    /// `--full-scale`) for two rows or more: named with their rows
    /// ([`incal_io::reader::rails`]).
    Clipped,
    /// Rows out of time order were put in order (`--sort-time`).
    TimeSorted,
    /// The data's magnitudes contradict the unit given (an accelerometer
    /// record in m/s² analysed as g, or the reverse).
    UnitSuspect,
    /// Empty or NaN cells of a channel were taken as missing samples and
    /// left out (how many, per channel).
    MissingSamples,
    /// A phase known only up to whole cycles: the fitted delay is longer
    /// than one period of the highest dwell, so it rests on the dwells
    /// below (the dynamic response).
    PhaseAmbiguous,
    /// A signal within 3 u of zero where one was expected (the output at a
    /// dwell of the dynamic response): its amplitude is biased up and its
    /// phase is noise.
    WeakSignal,
    /// Two estimates of one noise term disagree beyond the U95 of their
    /// difference (the PSD's white level against the Allan fit's N).
    NoiseInconsistent,
    /// A fitted term within its U95 of zero: the data do not distinguish
    /// it from zero (a term asked for, not chosen by the rule).
    NotSignificant,
    /// The temperature moved during a test meant to run at one
    /// temperature (the warm-up): its sensitivity mixes into the result.
    TemperatureNotConstant,
    /// Lines (tones) stand above the noise floor of a record's PSD: each
    /// raises the Allan deviation near τ ≈ 0.37/f, and an Allan fit there
    /// reads it as noise.
    Tones,
    /// The Allan deviation changes along the record beyond its bounds
    /// (the dynamic Allan variance's windows disagree): the whole-record
    /// statistics average over the change.
    NonStationary,
    /// A fitted property of the local field (the magnetometer's
    /// inclination) disagrees with the value given for the site beyond
    /// the U95 of their difference (En > 1).
    FieldMismatch,
    /// The GUM interval y ± U95 of a coefficient differs from the Monte
    /// Carlo coverage interval by more than the numerical tolerance
    /// (JCGM 101:2008 §8): the first-order uncertainty is not validated,
    /// the Monte Carlo interval is the one to use.
    GumNotValidated,
    /// More than 1 % of the Monte Carlo trials were refused by the
    /// reduction (the reason most of them failed is named).
    TrialsFailed,
}

impl WarningCode {
    /// The stable code string (`weak-conditioning`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            WarningCode::WeakConditioning => "weak-conditioning",
            WarningCode::LackOfFit => "lack-of-fit",
            WarningCode::NoReversal => "no-reversal",
            WarningCode::SmallAngle => "small-angle",
            WarningCode::PartialTurns => "partial-turns",
            WarningCode::PartFailed => "part-failed",
            WarningCode::OnePolarity => "one-polarity",
            WarningCode::RadiusIncomplete => "radius-incomplete",
            WarningCode::MissingUncertainty => "missing-uncertainty",
            WarningCode::InconsistentBias => "inconsistent-bias",
            WarningCode::ModelRange => "model-range",
            WarningCode::NoiseTermNotIdentified => "noise-term-not-identified",
            WarningCode::NoiseTermsNotSeparated => "noise-terms-not-separated",
            WarningCode::ShortRecord => "short-record",
            WarningCode::StatisticTruncated => "statistic-truncated",
            WarningCode::SignConvention => "sign-convention",
            WarningCode::TimeRepeats => "time-repeats",
            WarningCode::TimeGaps => "time-gaps",
            WarningCode::Spikes => "spikes",
            WarningCode::Saturated => "saturated",
            WarningCode::Clipped => "clipped",
            WarningCode::TimeSorted => "time-sorted",
            WarningCode::UnitSuspect => "unit-suspect",
            WarningCode::MissingSamples => "missing-samples",
            WarningCode::PhaseAmbiguous => "phase-ambiguous",
            WarningCode::WeakSignal => "weak-signal",
            WarningCode::NoiseInconsistent => "noise-inconsistent",
            WarningCode::NotSignificant => "not-significant",
            WarningCode::TemperatureNotConstant => "temperature-not-constant",
            WarningCode::Tones => "tones",
            WarningCode::NonStationary => "non-stationary",
            WarningCode::FieldMismatch => "field-mismatch",
            WarningCode::GumNotValidated => "gum-not-validated",
            WarningCode::TrialsFailed => "trials-failed",
        }
    }
}

impl std::fmt::Display for WarningCode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A warning: a stable code and a one-line message.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Warning {
    /// Stable code.
    pub code: WarningCode,
    /// What happened and what it means for the numbers.
    pub message: String,
}

impl Warning {
    /// A warning with `code` and `message`.
    pub fn new(code: WarningCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }

    /// The same warning with `prefix: ` before its message (e.g. the
    /// station or line it concerns).
    pub fn prefixed(mut self, prefix: &str) -> Self {
        self.message = format!("{prefix}: {}", self.message);
        self
    }
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} [{}]", self.message, self.code)
    }
}
