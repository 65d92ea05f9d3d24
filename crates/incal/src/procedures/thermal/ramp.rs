//! Ramp calibration: a static recording with the sensor's temperature
//! (`temperature_c`) while the chamber heats and cools, into the bias
//! polynomial (1) of every channel, the hysteresis between the heating
//! and cooling branches, an optional `dT/dt` term, and the sensor's lag
//! behind the chamber (`incal thermal ramp`).
//!
//! # Columns
//! `temperature_c` (the sensor's own temperature, °C, required),
//! `chamber_c` (the chamber's, optional: gives the lag), `time_s`
//! (optional: else the row index over `--rate-hz`), and the channels:
//! every other column, or those `--columns` selects.
//!
//! # Reduction
//! The rows are averaged in blocks of `block_s` seconds as they are read
//! (memory grows with the blocks, not the rows). Each block gives its
//! mean temperature, `dT/dt` (central difference of the block means),
//! and per channel its mean `ȳ_i` with `u_i = s/√n_i`, `s²` the
//! within-block variance pooled over the blocks (white noise within a
//! block; any excess between blocks shows as lack of fit and scales u, see
//! [`crate::estimation::linear::Variance::AtLeast`]). A block belongs to
//! the heating branch when `dT/dt > θ`, to the cooling branch when
//! `dT/dt < −θ`, and otherwise stays on the branch it was on (a sensor
//! keeps its branch through a hold), `θ = 0.25 × the 90th percentile of
//! |dT/dt|`. The model of each channel is
//!
//! `ȳ_i = Σ c_k (T_i − T_ref)^k + h b_i + r Ṫ_i`
//!
//! with `b_i = +½` (heating), `−½` (cooling), 0 (before the first
//! movement), so `h` is the heating branch minus the cooling branch
//! (Niu et al. 2013); `h` is fitted when both branches cover a common
//! range; `r` (the `dT/dt` term) only with `rate_term`. The degree rule is
//! that of the module docs.
//!
//! # Lag
//! With `chamber_c`, the sensor follows the chamber as a first-order lag,
//! `dT_s/dt = (T_c − T_s)/τ`: the slope `1/τ` of the blocks' `Ṫ_s`
//! against `T_c − T_s` (least squares through the origin, variance from
//! the residuals) gives `τ` with `u(τ) = u(1/τ) τ²`.

use std::io::Read;

use nalgebra::{DMatrix, DVector};
use serde_json::{json, Value};

use super::document::{block_table, channel_entry};
pub use super::input::{read, Block, RampInput, NOT_CHANNELS};
use super::{fit_with_degree, Degree, ValueU, DEFAULT_T_REF_C};
use crate::document::{DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument};
use crate::error::{Error, Result};
use crate::estimation::linear::{fit, Design, FitOptions};
use crate::procedures::noise::QuantityKind;
use crate::procedures::{Procedure as ProcedureShape, Progress};
use crate::units::Unit;

/// Options of a ramp reduction. In the document: `rate_hz`, `quantity`,
/// `t_ref_c`, `degree` (`"auto"` or 0…3), `block_s`, `rate_term`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RampOptions {
    /// Sample rate, Hz (the time base when there is no `time_s`). `None`:
    /// the rate of the `time_s` stamps, the blocks then cut by time (a
    /// recording without `time_s` is refused); given with `time_s`, it
    /// must agree with the stamps.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// What the channels measure: their unit (deg/s, g, or 1).
    #[serde(default)]
    pub quantity: QuantityKind,
    /// Reference temperature `T_ref`, °C.
    #[serde(default = "default_t_ref_c")]
    pub t_ref_c: f64,
    /// Degree of every polynomial, or the degree rule.
    #[serde(default)]
    pub degree: Degree,
    /// Block length, s.
    #[serde(default = "default_block_s")]
    pub block_s: f64,
    /// Fit a `dT/dt` term too.
    #[serde(default)]
    pub rate_term: bool,
}

/// [`DEFAULT_T_REF_C`].
pub(crate) fn default_t_ref_c() -> f64 {
    DEFAULT_T_REF_C
}

/// Blocks of 10 s.
fn default_block_s() -> f64 {
    10.0
}

impl Default for RampOptions {
    fn default() -> Self {
        Self {
            rate_hz: Some(1.0),
            quantity: QuantityKind::Generic,
            t_ref_c: DEFAULT_T_REF_C,
            degree: Degree::Auto,
            block_s: default_block_s(),
            rate_term: false,
        }
    }
}

/// `T_ref` a temperature ([`crate::units::check_temperature_c`]: not
/// below absolute zero), or [`Error::InvalidOption`] naming `t_ref_c`.
/// A block of `block_s` must hold two samples at `rate_hz`.
pub(crate) fn check_block(block_s: f64, rate_hz: f64) -> Result<()> {
    if block_s * rate_hz < 2.0 {
        return crate::options::invalid(
            "block_s",
            format!(
                "{} s holds fewer than two samples at {} Hz",
                crate::error::short_number(&block_s.to_string()),
                crate::error::short_number(&rate_hz.to_string())
            ),
        );
    }
    Ok(())
}

pub(crate) fn check_t_ref_c(t_ref_c: f64) -> Result<()> {
    crate::units::check_temperature_c("t_ref_c", t_ref_c)
}

/// The ramp reduction as a [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy)]
pub struct Ramp;

impl ProcedureShape for Ramp {
    const ID: Procedure = Procedure::Thermal;
    type Options = RampOptions;
    type Input = RampInput;

    fn example() -> RampOptions {
        RampOptions::default()
    }

    fn validate(o: &RampOptions) -> Result<()> {
        use crate::options::{check_positive, invalid};
        if let Some(rate) = o.rate_hz {
            check_positive("rate_hz", rate)?;
            if rate > 1e7 {
                return invalid("rate_hz", format!("must be at most 1e7 Hz, got {rate}"));
            }
        }
        check_positive("block_s", o.block_s)?;
        if o.block_s > 86400.0 {
            return invalid(
                "block_s",
                format!("must be at most 86400 s, got {}", o.block_s),
            );
        }
        if let Some(rate) = o.rate_hz {
            check_block(o.block_s, rate)?;
        }
        check_t_ref_c(o.t_ref_c)
    }

    fn read<R: Read>(rows: &mut incal_io::Reader<R>, o: &RampOptions) -> Result<RampInput> {
        read(rows, o)
    }

    fn reduce(input: &RampInput, o: &RampOptions, _p: &dyn Progress) -> Result<ResultDocument> {
        reduce(input, o)
    }

    fn synthesis(
        input: &RampInput,
        o: &RampOptions,
        _: &ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<RampInput>>> {
        super::montecarlo::synthesis(input, o).map(Some)
    }
}

/// The blocks as the fit sees them, computed once for the reduction and
/// the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockDesign {
    /// Mean time of each block, s.
    pub time_s: Vec<f64>,
    /// Mean sensor temperature of each block, °C.
    pub temp_c: Vec<f64>,
    /// `dT/dt`, central difference of the block means, °C/s.
    pub rate_c_s: Vec<f64>,
    /// +1 heating, −1 cooling, 0 before the first movement ([`branches`]).
    pub branch: Vec<i8>,
    /// Rows in each block.
    pub rows: Vec<usize>,
}

/// The blocks' design (module docs); at least 4 blocks of `block_s`.
pub fn block_design(input: &RampInput, block_s: f64) -> Result<BlockDesign> {
    let blocks = &input.blocks;
    if blocks.len() < 4 {
        return Err(Error::TooFew {
            what: format!("blocks of {block_s} s (a longer recording, or a shorter `block_s`)"),
            needed: 4,
            got: blocks.len(),
        });
    }
    let time_s: Vec<f64> = blocks.iter().map(|b| b.time.mean).collect();
    let temp_c: Vec<f64> = blocks.iter().map(|b| b.temp.mean).collect();
    let rate_c_s = central_rate(&time_s, &temp_c);
    let branch = branches(&rate_c_s);
    let rows = blocks.iter().map(|b| b.temp.n).collect();
    Ok(BlockDesign {
        time_s,
        temp_c,
        rate_c_s,
        branch,
        rows,
    })
}

/// True when a heating and a cooling branch each have 3 blocks or more
/// and cover a common range (over a fifth of the whole): the hysteresis
/// can then be separated from the polynomial.
pub fn both_branches(temp: &[f64], branch: &[i8]) -> bool {
    let count = |s: i8| branch.iter().filter(|&&b| b == s).count();
    let range = |s: i8| {
        temp.iter()
            .zip(branch)
            .filter(|(_, b)| **b == s)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (t, _)| {
                (lo.min(*t), hi.max(*t))
            })
    };
    let (hl, hh) = range(1);
    let (cl, ch) = range(-1);
    let (lo, hi) = temp
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
            (a.min(*t), b.max(*t))
        });
    count(1) >= 3 && count(-1) >= 3 && hh.min(ch) - hl.max(cl) > 0.2 * (hi - lo)
}

/// Heating (+1), cooling (−1) or neither yet (0) for each block, from
/// `dT/dt` (module docs).
pub fn branches(rate: &[f64]) -> Vec<i8> {
    let mut a: Vec<f64> = rate
        .iter()
        .map(|r| r.abs())
        .filter(|r| r.is_finite())
        .collect();
    a.sort_by(f64::total_cmp);
    let theta = if a.is_empty() {
        f64::INFINITY
    } else {
        0.25 * a[((a.len() - 1) as f64 * 0.9).round() as usize]
    };
    let mut state = 0i8;
    rate.iter()
        .map(|&r| {
            if r > theta {
                state = 1;
            } else if r < -theta {
                state = -1;
            }
            state
        })
        .collect()
}

fn central_rate(t: &[f64], y: &[f64]) -> Vec<f64> {
    let n = t.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            if b > a {
                (y[b] - y[a]) / (t[b] - t[a])
            } else {
                0.0
            }
        })
        .collect()
}

/// Reduce the blocks (module docs).
pub fn reduce(input: &RampInput, o: &RampOptions) -> Result<ResultDocument> {
    let blocks = &input.blocks;
    let BlockDesign {
        temp_c: temp,
        rate_c_s: rate,
        branch,
        ..
    } = block_design(input, o.block_s)?;
    let heating = branch.iter().filter(|&&b| b == 1).count();
    let cooling = branch.iter().filter(|&&b| b == -1).count();
    let both = both_branches(&temp, &branch);

    let mut b = DocumentBuilder::new(
        Procedure::Thermal,
        "Thermal model of the bias (chamber ramp)".to_string(),
    );
    let gone: Vec<String> = input
        .names
        .iter()
        .zip(&input.missing)
        .filter(|(_, &n)| n > 0)
        .map(|(name, n)| format!("{name} {n}"))
        .collect();
    if !gone.is_empty() {
        b.warnings([crate::warning::Warning::new(
            crate::warning::WarningCode::MissingSamples,
            format!(
                "empty or NaN cells taken as missing samples and left out of their blocks: {}",
                gone.join(", ")
            ),
        )]);
    }
    let mut extra: Vec<(String, Vec<f64>)> = Vec::new();
    if both {
        extra.push((
            "hysteresis".into(),
            branch.iter().map(|&s| 0.5 * s as f64).collect(),
        ));
    } else {
        b.decision(
            DecisionCode::NotDetermined,
            format!(
                "hysteresis: needs a heating and a cooling branch over a common range ({heating} heating and {cooling} cooling blocks)"
            ),
        );
    }
    if o.rate_term {
        extra.push(("rate_term".into(), rate.clone()));
    }
    let unit = Unit::parse(o.quantity.default_unit());
    let mut thermal = serde_json::Map::new();
    let mut selection = serde_json::Map::new();
    for (c, name) in input.names.iter().enumerate() {
        let d = ChannelBlocks::of(blocks, c, name, &temp, &extra)?;
        let (f, trials) = d.fit(name, o.t_ref_c, o.degree)?;
        b.decision(
            DecisionCode::ModelDegree,
            super::document::degree_reason(name, &f, o.degree, &trials),
        );
        b.warnings(
            f.fit
                .quality_warnings("the block means scatter about the model more than their white-noise u (bias instability, or a higher degree)")
                .into_iter()
                .map(|w| w.prefixed(name)),
        );
        b.fit(FitSummary::of(name, &f.fit, unit.clone()));
        let entry = channel_entry(&mut b, name, &f, o, &unit)?;
        thermal.insert(
            name.clone(),
            serde_json::to_value(&entry).unwrap_or(Value::Null),
        );
        selection.insert(name.clone(), json!(trials));
        b.table(block_table(name, &unit, &d, &branch, &f)?);
        b.table(super::document::compensated_table(name, &unit, &f)?);
    }
    if input.has_chamber {
        match lag(blocks, &rate) {
            Ok((tau, u_tau, dof)) => {
                b.extra("lag", json!(ValueU::new(tau, u_tau, "s", dof)))?;
            }
            Err(m) => {
                b.decision(DecisionCode::NotDetermined, format!("lag: {m}"));
            }
        }
    } else {
        b.decision(
            DecisionCode::NotDetermined,
            "lag: the recording has no chamber_c column",
        );
    }
    b.extra("thermal", Value::Object(thermal))?;
    b.extra("degree_selection", Value::Object(selection))?;
    b.extra(
        "branches",
        json!({"heating_blocks": heating, "cooling_blocks": cooling, "blocks": blocks.len()}),
    )?;
    Ok(b.finish())
}

/// One channel's points of the fit: the blocks with at least two of its
/// samples, their means with `u_i = s/√n_i` (module docs), temperatures
/// and extra regressors.
pub(crate) struct ChannelBlocks {
    /// Indices of the blocks kept.
    pub(crate) keep: Vec<usize>,
    /// Block means.
    pub(crate) y: Vec<f64>,
    /// Their standard uncertainties.
    pub(crate) u: Vec<f64>,
    /// Their mean sensor temperatures, °C.
    pub(crate) t: Vec<f64>,
    /// The extra regressors at the blocks kept.
    pub(crate) extra: Vec<(String, Vec<f64>)>,
    /// Degrees of freedom of the pooled within-block variance.
    pub(crate) pooled_dof: usize,
    /// The within-block variance pooled over the blocks.
    pub(crate) variance: f64,
}

impl ChannelBlocks {
    /// The polynomial of `degree` (or the degree rule) through these
    /// points ([`fit_with_degree`], the pooled variance's dof as prior).
    pub(crate) fn fit(
        &self,
        name: &str,
        t_ref_c: f64,
        degree: Degree,
    ) -> Result<(super::PolyFit, Vec<super::DegreeTrial>)> {
        fit_with_degree(
            name,
            &self.t,
            &self.y,
            &self.u,
            &self.extra,
            t_ref_c,
            degree,
            self.pooled_dof as f64,
        )
    }

    /// Channel `c` (named `name`) of the blocks, with the blocks'
    /// temperatures `temp` and extra regressors `extra`; an error when
    /// the blocks show no scatter to weight the means.
    pub(crate) fn of(
        blocks: &[Block],
        c: usize,
        name: &str,
        temp: &[f64],
        extra: &[(String, Vec<f64>)],
    ) -> Result<Self> {
        let keep: Vec<usize> = (0..blocks.len())
            .filter(|&i| blocks[i].channels[c].n >= 2)
            .collect();
        let y: Vec<f64> = keep.iter().map(|&i| blocks[i].channels[c].mean).collect();
        // The within-block variance pooled over the blocks: a block's own
        // s² from a few samples would make the weights, and so χ², noisy.
        let (m2, pooled_dof) = keep.iter().fold((0.0, 0usize), |(m, d), &i| {
            let a = &blocks[i].channels[c];
            (m + a.m2, d + a.n - 1)
        });
        let var = m2 / pooled_dof.max(1) as f64;
        if !(var > 0.0 && var.is_finite()) {
            return Err(Error::Unsupported(format!(
                "channel {name}: no scatter within the blocks to weight the block means (a constant or missing channel)"
            )));
        }
        let u: Vec<f64> = keep
            .iter()
            .map(|&i| (var / blocks[i].channels[c].n as f64).sqrt())
            .collect();
        let t: Vec<f64> = keep.iter().map(|&i| temp[i]).collect();
        let extra: Vec<(String, Vec<f64>)> = extra
            .iter()
            .map(|(n, col)| (n.clone(), keep.iter().map(|&i| col[i]).collect()))
            .collect();
        Ok(ChannelBlocks {
            keep,
            y,
            u,
            t,
            extra,
            pooled_dof,
            variance: var,
        })
    }
}

/// The sensor's first-order lag τ behind the chamber (module docs):
/// `(τ, u(τ), dof)`.
fn lag(blocks: &[Block], rate: &[f64]) -> std::result::Result<(f64, f64, f64), String> {
    let x: Vec<f64> = blocks
        .iter()
        .map(|b| b.chamber.mean - b.temp.mean)
        .collect();
    let n = x.len();
    if x.iter().any(|v| !v.is_finite()) || n < 3 {
        return Err("chamber_c has no usable values".into());
    }
    let design = Design::new(
        vec!["inverse_lag".into()],
        DMatrix::from_column_slice(n, 1, &x),
    )
    .map_err(|e| e.to_string())?;
    let f = fit(
        &design,
        &DVector::from_column_slice(rate),
        &FitOptions::default(),
    )
    .map_err(|_| "the chamber and the sensor never differ: no lag to see".to_string())?;
    let (k, uk) = f.estimates.get("inverse_lag").ok_or("no slope")?;
    if k.is_nan() || k <= 0.0 || k < 3.0 * uk {
        return Err(format!(
            "the sensor does not follow the chamber measurably (1/tau = {k:.3e} +/- {uk:.1e} 1/s)"
        ));
    }
    Ok((1.0 / k, uk / (k * k), f.dof as f64))
}
