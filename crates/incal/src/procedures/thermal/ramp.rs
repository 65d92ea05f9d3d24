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
use serde::Serialize;
use serde_json::{json, Value};

use super::{fit_with_degree, power_unit, Degree, ThermalEntry, ValueU, DEFAULT_T_REF_C};
use crate::document::{
    Cell, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::{Error, Result};
use crate::estimation::linear::{fit, Design, FitOptions};
use crate::estimation::Estimates;
use crate::procedures::noise::QuantityKind;
use crate::procedures::{Procedure as ProcedureShape, Progress};
use crate::units::Unit;

/// Columns that are never channels.
pub const NOT_CHANNELS: [&str; 4] = ["time_s", "temperature_c", "chamber_c", "humidity_pct"];

/// Options of a ramp reduction.
#[derive(Debug, Clone, Serialize)]
pub struct RampOptions {
    /// Sample rate, Hz (the time base when there is no `time_s`).
    pub rate_hz: f64,
    /// What the channels measure: their unit (deg/s, g, or 1).
    pub quantity: QuantityKind,
    /// Reference temperature `T_ref`, °C.
    pub t_ref_c: f64,
    /// Degree of every polynomial, or the degree rule.
    pub degree: Degree,
    /// Block length, s.
    pub block_s: f64,
    /// Fit a `dT/dt` term too.
    pub rate_term: bool,
}

impl Default for RampOptions {
    fn default() -> Self {
        Self {
            rate_hz: 1.0,
            quantity: QuantityKind::Generic,
            t_ref_c: DEFAULT_T_REF_C,
            degree: Degree::Auto,
            block_s: 10.0,
            rate_term: false,
        }
    }
}

/// Welford accumulator of one channel in one block.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Acc {
    n: usize,
    mean: f64,
    m2: f64,
}

impl Acc {
    fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }
}

/// One block of rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    time: Acc,
    temp: Acc,
    chamber: Acc,
    channels: Vec<Acc>,
}

/// A ramp recording as blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct RampInput {
    /// Channel names.
    pub names: Vec<String>,
    /// The blocks, in time order.
    pub blocks: Vec<Block>,
    /// True when the recording has `chamber_c`.
    pub has_chamber: bool,
}

/// Rows per block.
fn block_rows(o: &RampOptions) -> usize {
    ((o.block_s * o.rate_hz).round() as usize).max(2)
}

/// Read a ramp recording (module docs).
pub fn read<R: Read>(rows: &mut incal_io::Reader<R>, o: &RampOptions) -> Result<RampInput> {
    let h = rows.header();
    let temp = h.column("temperature_c")?;
    let chamber = h.opt_column("chamber_c");
    let time = h.opt_column("time_s");
    let pick: Vec<usize> = if h.selected().is_empty() {
        (0..h.width())
            .filter(|&k| !NOT_CHANNELS.contains(&h.names()[k].as_str()))
            .collect()
    } else {
        h.selected()
            .iter()
            .copied()
            .filter(|&k| !NOT_CHANNELS.contains(&h.names()[k].as_str()))
            .collect()
    };
    if pick.is_empty() {
        return Err(h
            .error("no channel column besides time_s, temperature_c and chamber_c")
            .into());
    }
    let names: Vec<String> = pick.iter().map(|&k| h.names()[k].clone()).collect();
    let per = block_rows(o);
    let mut blocks = Vec::new();
    let empty = Block {
        time: Acc::default(),
        temp: Acc::default(),
        chamber: Acc::default(),
        channels: vec![Acc::default(); pick.len()],
    };
    let mut cur = empty.clone();
    let mut index = 0usize;
    let mut in_block = 0usize;
    let mut last_t = f64::NEG_INFINITY;
    while let Some(row) = rows.next_row()? {
        let t = match time {
            Some(c) => {
                let t = row.f64(c)?;
                if t <= last_t {
                    return Err(row
                        .cell_error(c, format!("time_s {t} does not increase (after {last_t})"))
                        .into());
                }
                last_t = t;
                t
            }
            None => index as f64 / o.rate_hz,
        };
        index += 1;
        let tc = row.f64(temp)?;
        if !(-273.15..=1000.0).contains(&tc) {
            return Err(row
                .cell_error(temp, format!("{tc} is not a temperature in degC"))
                .into());
        }
        cur.time.push(t);
        cur.temp.push(tc);
        if let Some(c) = chamber {
            cur.chamber.push(row.f64(c)?);
        }
        for (a, &k) in cur.channels.iter_mut().zip(&pick) {
            if let Some(v) = row.f64_or_missing(k)? {
                a.push(v);
            }
        }
        in_block += 1;
        if in_block == per {
            blocks.push(std::mem::replace(&mut cur, empty.clone()));
            in_block = 0;
        }
    }
    if in_block * 2 >= per {
        blocks.push(cur);
    }
    Ok(RampInput {
        names,
        blocks,
        has_chamber: chamber.is_some(),
    })
}

/// The ramp reduction as a [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy)]
pub struct Ramp;

impl ProcedureShape for Ramp {
    const ID: Procedure = Procedure::Thermal;
    type Options = RampOptions;
    type Input = RampInput;

    fn validate(o: &RampOptions) -> Result<()> {
        if !(o.rate_hz.is_finite() && o.rate_hz > 0.0 && o.rate_hz <= 1e7) {
            return Err(Error::InvalidValue {
                what: "rate_hz (Hz, above 0)".into(),
                value: o.rate_hz.to_string(),
            });
        }
        if !(o.block_s.is_finite() && o.block_s > 0.0 && o.block_s <= 86400.0) {
            return Err(Error::InvalidValue {
                what: "block_s (s, above 0)".into(),
                value: o.block_s.to_string(),
            });
        }
        if !(o.t_ref_c.is_finite() && o.t_ref_c.abs() <= 500.0) {
            return Err(Error::InvalidValue {
                what: "t_ref_c (degC)".into(),
                value: o.t_ref_c.to_string(),
            });
        }
        Ok(())
    }

    fn read<R: Read>(rows: &mut incal_io::Reader<R>, o: &RampOptions) -> Result<RampInput> {
        read(rows, o)
    }

    fn reduce(input: &RampInput, o: &RampOptions, _p: &dyn Progress) -> Result<ResultDocument> {
        reduce(input, o)
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
            what: format!("blocks of {block_s} s (a longer recording, or a shorter --block-s)"),
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
        let (f, trials) = fit_with_degree(
            name,
            &d.t,
            &d.y,
            &d.u,
            &d.extra,
            o.t_ref_c,
            o.degree,
            d.pooled_dof as f64,
        )?;
        b.decision(
            DecisionCode::ModelDegree,
            super::soak::degree_reason(name, &f, o.degree, &trials),
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
        b.table(super::soak::compensated_table(name, &unit, &f)?);
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
struct ChannelBlocks {
    /// Indices of the blocks kept.
    keep: Vec<usize>,
    /// Block means.
    y: Vec<f64>,
    /// Their standard uncertainties.
    u: Vec<f64>,
    /// Their mean sensor temperatures, °C.
    t: Vec<f64>,
    /// The extra regressors at the blocks kept.
    extra: Vec<(String, Vec<f64>)>,
    /// Degrees of freedom of the pooled within-block variance.
    pooled_dof: usize,
}

impl ChannelBlocks {
    /// Channel `c` (named `name`) of the blocks, with the blocks'
    /// temperatures `temp` and extra regressors `extra`; an error when
    /// the blocks show no scatter to weight the means.
    fn of(
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
        })
    }
}

/// A channel's polynomial coefficients `NAME.ck` into the document, and
/// its `thermal` entry (with the hysteresis and `dT/dt` terms when
/// fitted).
fn channel_entry(
    b: &mut DocumentBuilder,
    name: &str,
    f: &super::PolyFit,
    o: &RampOptions,
    unit: &Unit,
) -> Result<ThermalEntry> {
    let p = f.degree + 1;
    let dof = f.fit.estimates.dof();
    let e = Estimates::new(
        (0..p).map(|k| format!("c{k}")).collect(),
        f.values.rows(0, p).into_owned(),
        f.covariance.view((0, 0), (p, p)).into_owned(),
        dof,
    )?;
    b.estimates(&e, &format!("{name}."), |n| {
        let k: usize = n[1..].parse().map_err(|_| Error::Unsupported(n.into()))?;
        Ok(power_unit(unit, k))
    })?;
    let extra_u = |label: &str, unit_text: String| {
        f.names.iter().position(|n| n == label).map(|j| {
            ValueU::new(
                f.values[j],
                f.covariance[(j, j)].max(0.0).sqrt(),
                &unit_text,
                dof,
            )
        })
    };
    Ok(ThermalEntry {
        degree: f.degree,
        t_ref_c: o.t_ref_c,
        t_min_c: f.t_range_c.0,
        t_max_c: f.t_range_c.1,
        unit: unit.as_str().to_string(),
        hysteresis: extra_u("hysteresis", unit.as_str().to_string()),
        rate_term: extra_u("rate_term", format!("{}/(degC/s)", unit.as_str())),
    })
}

/// The table `ramp.NAME`: the block means against the sensor temperature
/// with the polynomial and the residual, at most about 60 rows
/// (consecutive blocks of one branch merged as weighted means, so a
/// report stays readable).
fn block_table(
    name: &str,
    unit: &Unit,
    d: &ChannelBlocks,
    branch: &[i8],
    f: &super::PolyFit,
) -> Result<Table> {
    let (keep, u, y, tk) = (&d.keep, &d.u, &d.y, &d.t);
    let mut tab = Table::new(
        &format!("ramp.{name}"),
        &format!("{name}: block means against the sensor temperature (consecutive blocks of a branch merged)"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("branch", None),
            ("mean", Some(unit.clone())),
            ("u", Some(unit.clone())),
            ("polynomial", Some(unit.clone())),
            ("residual", Some(unit.clone())),
        ],
    );
    let group = keep.len().div_ceil(60).max(1);
    let mut j = 0;
    while j < keep.len() {
        let br = branch[keep[j]];
        let mut end = j;
        while end < keep.len() && end - j < group && branch[keep[end]] == br {
            end += 1;
        }
        let (mut sw, mut st, mut sy, mut sr) = (0.0, 0.0, 0.0, 0.0);
        for q in j..end {
            let w = 1.0 / (u[q] * u[q]);
            let fitted: f64 = (0..f.values.len())
                .map(|k| f.values[k] * regressor(f, &d.extra, q, k, tk[q]))
                .sum();
            sw += w;
            st += w * tk[q];
            sy += w * y[q];
            sr += w * (y[q] - fitted);
        }
        let t_mean = st / sw;
        let (poly_only, _) = f.eval(t_mean);
        tab.push(vec![
            Cell::num(t_mean),
            Cell::text(match br {
                1 => "heating",
                -1 => "cooling",
                _ => "start",
            }),
            Cell::num(sy / sw),
            Cell::num(sw.sqrt().recip()),
            Cell::num(poly_only),
            Cell::num(sr / sw),
        ])?;
        j = end;
    }
    Ok(tab)
}

/// The value of regressor `k` of fit `f` at point `j`.
fn regressor(f: &super::PolyFit, extra: &[(String, Vec<f64>)], j: usize, k: usize, t: f64) -> f64 {
    if k <= f.degree {
        (t - f.t_ref_c).powi(k as i32)
    } else {
        extra[k - f.degree - 1].1[j]
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
