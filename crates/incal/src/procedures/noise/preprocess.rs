//! Preprocessing of a noise record before its statistics, as Stable32's
//! users do it (W. J. Riley, *Handbook of Frequency Stability Analysis*,
//! NIST Special Publication 1065, 2008, §8 "Data preprocessing": outlier
//! recognition by the median absolute deviation, gap filling, drift
//! removal), every step recorded in the document: nothing changes
//! silently.
//!
//! The steps run in this order, each on every channel:
//! 1. **outliers** (`mad:K`): a sample farther than `K·1.4826·MAD` from the
//!    channel's median (MAD, the median absolute deviation, times 1.4826
//!    is the standard deviation of normal noise) becomes a missing sample;
//! 2. **fill** (`gaps`): every missing sample (an empty or NaN cell, one
//!    removed as an outlier, or a period the `time_s` stamps skip) inside
//!    the record is replaced by the straight line between its neighbours;
//!    missing samples at either end cannot be interpolated and are left
//!    out (the record starts and ends with a sample);
//! 3. **detrend**: a drift model fitted by least squares to the samples
//!    (t in s from the first sample, on the record's grid) and subtracted:
//!    `linear` `c + b·t`, `quadratic` `c + b·t + a·t²`, or `log` Stable32's
//!    frequency drift `c + a·ln(1 + b·t)`, b found by a golden-section
//!    search of the least residual over ln b (from 10⁻³ to 10³ per record
//!    length).
//!
//! In the document, `preprocessing` is the list of steps, each with
//! `step`, its parameters and per channel what it did (`samples`: row
//! ranges `[first, last]`, 0-based indices of the record's samples in time
//! order, inclusive; for a stamp gap filled, the indices the inserted
//! samples take), and a `summary` line; the table `preprocessing` gives
//! one row per step and channel, and the certificate states the summary.
//! Removing a drift changes what the record says about rate random walk
//! and ramp (a linear detrend removes R): the document's terms describe
//! the preprocessed record. A binary record is read into memory whole for
//! it (`reduce_mapped`).

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::input::Channels;
use crate::document::{Cell, Table};
use crate::error::Result;
use crate::options::invalid;

/// A drift model removed from each channel (`detrend`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Detrend {
    /// `c + b·t`.
    Linear,
    /// `c + b·t + a·t²`.
    Quadratic,
    /// `c + a·ln(1 + b·t)` (Stable32's log frequency drift).
    Log,
}

/// What `fill` fills.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Fill {
    /// Missing samples and the periods the stamps skip.
    Gaps,
}

/// The preprocessing options (flattened into the noise options).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct PreprocessOptions {
    /// Remove a drift from every channel before the statistics: linear,
    /// quadratic or log.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detrend: Option<Detrend>,
    /// Remove outliers: `mad:K`, a sample farther than K times the
    /// MAD-based standard deviation from the median (K from 2 to 100;
    /// Stable32 uses 5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outliers: Option<String>,
    /// Fill the missing samples and the stamps' gaps by straight lines
    /// between their neighbours: `gaps`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fill: Option<Fill>,
}

impl PreprocessOptions {
    /// Whether any step is asked for.
    pub fn any(&self) -> bool {
        self.detrend.is_some() || self.outliers.is_some() || self.fill.is_some()
    }

    /// K of `mad:K` (names the key when malformed).
    pub fn mad_k(&self) -> Result<Option<f64>> {
        let Some(s) = &self.outliers else {
            return Ok(None);
        };
        let Some(k) = s.strip_prefix("mad:") else {
            return invalid(
                "outliers",
                format!("{s:?}: expected mad:K (K from 2 to 100, e.g. mad:5)"),
            );
        };
        let Ok(k) = k.trim().parse::<f64>() else {
            return invalid("outliers", format!("{s:?}: K is not a number (e.g. mad:5)"));
        };
        crate::options::check_range("outliers", k, 2.0, 100.0, "")?;
        Ok(Some(k))
    }

    /// Range checks (names the key).
    pub fn validate(&self) -> Result<()> {
        self.mad_k().map(|_| ())
    }
}

/// Inclusive index ranges `[first, last]` of the indices in `idx`
/// (sorted).
fn ranges(idx: &[usize]) -> Vec<[usize; 2]> {
    let mut out: Vec<[usize; 2]> = Vec::new();
    for &i in idx {
        match out.last_mut() {
            Some(r) if r[1] + 1 == i => r[1] = i,
            _ => out.push([i, i]),
        }
    }
    out
}

/// The median of finite `v` (`None` when there is none).
fn median(mut v: Vec<f64>) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    let hi = *m;
    if v.len() % 2 == 1 {
        return Some(hi);
    }
    let lo = v[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Some(0.5 * (lo + hi))
}

/// One step's record: its JSON entry and its table rows.
struct Step {
    json: Value,
    rows: Vec<Vec<Cell>>,
    summary: String,
}

/// Apply the steps of `o` to `input` (module docs): the preprocessed
/// record and the audit (`preprocessing` entry and table), or `None` —
/// and no copy of the record — when no step is asked for.
pub fn apply(input: &Channels, o: &PreprocessOptions) -> Result<Option<(Channels, Value, Table)>> {
    if !o.any() {
        return Ok(None);
    }
    let mut c = input.clone();
    let mut steps = Vec::new();
    if let Some(k) = o.mad_k()? {
        steps.push(outliers(&mut c, k));
    }
    if o.fill.is_some() {
        steps.push(fill(&mut c)?);
    }
    if let Some(d) = o.detrend {
        steps.push(detrend(&mut c, d)?);
    }
    let mut t = Table::new(
        "preprocessing",
        "Preprocessing: what each step did to each channel before the statistics",
        &[
            ("step", None),
            ("channel", None),
            ("samples_changed", None),
            ("detail", None),
        ],
    );
    let mut list = Vec::new();
    for s in steps {
        for r in s.rows {
            t.push(r)?;
        }
        let mut j = s.json;
        j["summary"] = json!(s.summary);
        list.push(j);
    }
    Ok(Some((c, Value::Array(list), t)))
}

/// Step 1: outliers beyond `k` MAD-based standard deviations become NaN.
fn outliers(c: &mut Channels, k: f64) -> Step {
    let mut per = serde_json::Map::new();
    let mut rows = Vec::new();
    let mut total = 0;
    for (name, col) in c.names.iter().zip(c.samples.iter_mut()) {
        let finite: Vec<f64> = col.iter().copied().filter(|v| v.is_finite()).collect();
        let med = median(finite.clone()).unwrap_or(0.0);
        let mad = median(finite.iter().map(|v| (v - med).abs()).collect()).unwrap_or(0.0);
        let sigma = 1.4826 * mad;
        let mut idx = Vec::new();
        if sigma > 0.0 {
            for (i, v) in col.iter_mut().enumerate() {
                if v.is_finite() && (*v - med).abs() > k * sigma {
                    *v = f64::NAN;
                    idx.push(i);
                }
            }
        }
        total += idx.len();
        let r = ranges(&idx);
        rows.push(vec![
            Cell::text("outliers"),
            Cell::text(name.clone()),
            Cell::num(idx.len() as f64),
            Cell::text(format!(
                "median {med:.4e}, MAD sigma {sigma:.4e}, limit {:.4e}; rows {}",
                k * sigma,
                show(&r)
            )),
        ]);
        per.insert(
            name.clone(),
            json!({"median": med, "sigma_mad": sigma, "removed": idx.len(), "samples": r}),
        );
    }
    Step {
        json: json!({"step": "outliers", "method": "mad", "k": k, "channels": per}),
        rows,
        summary: format!(
            "outliers farther than {k} MAD-based standard deviations from the median removed: {total} samples"
        ),
    }
}

/// Up to 20 ranges as `a-b, c, …` (the document holds them all).
fn show(r: &[[usize; 2]]) -> String {
    let mut v: Vec<String> = r
        .iter()
        .take(20)
        .map(|[a, b]| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}-{b}")
            }
        })
        .collect();
    if r.len() > 20 {
        v.push(format!("… ({} ranges in all)", r.len()));
    }
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

/// Step 2: stamp gaps become NaN samples, then every inner NaN is
/// interpolated and the missing ends are cut.
fn fill(c: &mut Channels) -> Result<Step> {
    let inserted: usize = c.gaps.iter().map(|g| g.1).sum();
    if inserted > 0 {
        for col in c.samples.iter_mut() {
            let mut out = Vec::with_capacity(col.len() + inserted);
            let mut g = c.gaps.iter().peekable();
            for (i, &v) in col.iter().enumerate() {
                if let Some(&&(at, n)) = g.peek() {
                    if at == i {
                        out.extend(std::iter::repeat_n(f64::NAN, n));
                        g.next();
                    }
                }
                out.push(v);
            }
            *col = out;
        }
        c.rows += inserted;
        c.gaps.clear();
    }
    // Missing ends, cut from every channel alike (the channels share
    // their rows): the record keeps the rows from the first to the last
    // where every channel has a sample.
    let full = |i: &usize| c.samples.iter().all(|col| col[*i].is_finite());
    let (Some(first), Some(last)) = ((0..c.rows).find(full), (0..c.rows).rfind(full)) else {
        return invalid("fill", "no row has a sample in every channel to fill from");
    };
    let last = last + 1;
    let cut = (first, c.rows - last);
    let mut per = serde_json::Map::new();
    let mut rows = Vec::new();
    let mut total = 0;
    for (name, col) in c.names.iter().zip(c.samples.iter_mut()) {
        col.truncate(last);
        col.drain(..first);
        let mut idx = Vec::new();
        let mut i = 0;
        while i < col.len() {
            if col[i].is_finite() {
                i += 1;
                continue;
            }
            // col[0] and the last sample are finite after the cut.
            let a = i - 1;
            let mut b = i;
            while !col[b].is_finite() {
                b += 1;
            }
            let (ya, yb) = (col[a], col[b]);
            for (j, v) in col.iter_mut().enumerate().take(b).skip(i) {
                *v = ya + (yb - ya) * (j - a) as f64 / (b - a) as f64;
                idx.push(j);
            }
            i = b;
        }
        total += idx.len();
        let r = ranges(&idx);
        rows.push(vec![
            Cell::text("fill"),
            Cell::text(name.clone()),
            Cell::num(idx.len() as f64),
            Cell::text(format!("rows {} filled by straight lines", show(&r))),
        ]);
        per.insert(name.clone(), json!({"filled": idx.len(), "samples": r}));
    }
    c.rows = last - first;
    Ok(Step {
        json: json!({
            "step": "fill", "method": "linear", "stamp_periods_inserted": inserted,
            "cut_start": cut.0, "cut_end": cut.1, "channels": per,
        }),
        rows,
        summary: format!(
            "{total} missing samples filled by straight lines between their neighbours ({inserted} of them periods the stamps skip); {} samples without a neighbour cut from the ends",
            cut.0 + cut.1
        ),
    })
}

/// The time of each sample (s from the first) on the record's grid: the
/// stamps' gaps advance it by the periods they skip.
fn times(c: &Channels) -> Vec<f64> {
    let tau0 = 1.0 / c.rate_hz;
    let mut t = Vec::with_capacity(c.rows);
    let mut skip = 0usize;
    let mut g = c.gaps.iter().peekable();
    for i in 0..c.rows {
        while let Some(&&(at, n)) = g.peek() {
            if at > i {
                break;
            }
            skip += n;
            g.next();
        }
        t.push((i + skip) as f64 * tau0);
    }
    t
}

/// Least squares of `y` (finite entries) on the basis functions `f(t)`:
/// the coefficients and the residual sum of squares.
fn lsq(t: &[f64], y: &[f64], f: &dyn Fn(f64) -> Vec<f64>, p: usize) -> Option<(Vec<f64>, f64)> {
    let mut ata = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut aty = nalgebra::DVector::<f64>::zeros(p);
    let mut yy = 0.0;
    for (&ti, &yi) in t.iter().zip(y) {
        if !yi.is_finite() {
            continue;
        }
        let row = f(ti);
        for a in 0..p {
            aty[a] += row[a] * yi;
            for b in 0..p {
                ata[(a, b)] += row[a] * row[b];
            }
        }
        yy += yi * yi;
    }
    let sol = ata.clone().cholesky()?.solve(&aty);
    let rss = yy - sol.dot(&aty);
    Some((sol.iter().copied().collect(), rss))
}

/// The log model's b (1/s) by golden section over ln b.
fn log_b(t: &[f64], y: &[f64], span: f64) -> Option<f64> {
    let rss = |lb: f64| {
        let b = lb.exp();
        lsq(t, y, &|ti| vec![1.0, (b * ti).ln_1p()], 2).map_or(f64::INFINITY, |r| r.1)
    };
    let (mut lo, mut hi) = ((1e-3 / span).ln(), (1e3 / span).ln());
    // A coarse scan first: the residual need not be unimodal in ln b.
    let grid: Vec<f64> = (0..=24).map(|i| lo + (hi - lo) * i as f64 / 24.0).collect();
    let best = grid
        .iter()
        .copied()
        .min_by(|a, b| rss(*a).total_cmp(&rss(*b)))?;
    let step = (hi - lo) / 24.0;
    (lo, hi) = (best - step, best + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..60 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if rss(a) < rss(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    Some((0.5 * (lo + hi)).exp())
}

/// Step 3: the drift model fitted to each channel and subtracted.
fn detrend(c: &mut Channels, d: Detrend) -> Result<Step> {
    let t = times(c);
    let span = t.last().copied().unwrap_or(0.0).max(1.0 / c.rate_hz);
    let mut per = serde_json::Map::new();
    let mut rows = Vec::new();
    let name_of = match d {
        Detrend::Linear => "linear",
        Detrend::Quadratic => "quadratic",
        Detrend::Log => "log",
    };
    for (name, col) in c.names.iter().zip(c.samples.iter_mut()) {
        let fail = || {
            crate::error::Error::Unsupported(format!(
                "channel {name}: the {name_of} drift cannot be fitted (too few samples, or all equal)"
            ))
        };
        let (model, coef): (Box<dyn Fn(f64) -> f64>, Value) = match d {
            Detrend::Linear | Detrend::Quadratic => {
                let p = if d == Detrend::Linear { 2 } else { 3 };
                // Centred and scaled time keeps the normal equations sane.
                let (m, s) = (0.5 * span, 0.5 * span);
                let basis = move |ti: f64| {
                    let x = (ti - m) / s;
                    (0..p).map(|k| x.powi(k as i32)).collect::<Vec<_>>()
                };
                let (w, _) = lsq(&t, col, &basis, p).ok_or_else(fail)?;
                // Back to powers of t: c + b t + a t².
                let (c0, c1, c2) = match p {
                    2 => (w[0] - w[1] * m / s, w[1] / s, 0.0),
                    _ => (
                        w[0] - w[1] * m / s + w[2] * m * m / (s * s),
                        w[1] / s - 2.0 * w[2] * m / (s * s),
                        w[2] / (s * s),
                    ),
                };
                let mut j = json!({"offset": c0, "slope_per_s": c1});
                if p == 3 {
                    j["curvature_per_s2"] = json!(c2);
                }
                (Box::new(move |ti| c0 + c1 * ti + c2 * ti * ti), j)
            }
            Detrend::Log => {
                let b = log_b(&t, col, span).ok_or_else(fail)?;
                let (w, _) = lsq(&t, col, &|ti| vec![1.0, (b * ti).ln_1p()], 2).ok_or_else(fail)?;
                let (c0, a) = (w[0], w[1]);
                (
                    Box::new(move |ti| c0 + a * (b * ti).ln_1p()),
                    json!({"offset": c0, "a": a, "b_per_s": b}),
                )
            }
        };
        if coef
            .as_object()
            .is_some_and(|o| o.values().any(|v| !v.as_f64().is_some_and(f64::is_finite)))
        {
            return Err(fail());
        }
        for (v, &ti) in col.iter_mut().zip(&t) {
            if v.is_finite() {
                *v -= model(ti);
            }
        }
        let change = model(span) - model(0.0);
        rows.push(vec![
            Cell::text("detrend"),
            Cell::text(name.clone()),
            Cell::num(col.iter().filter(|v| v.is_finite()).count() as f64),
            Cell::text(format!(
                "{name_of} drift removed: {}; change over the record {change:.4e}",
                coef.as_object()
                    .map(|o| o
                        .iter()
                        .map(|(k, v)| format!("{k} {:.4e}", v.as_f64().unwrap_or(f64::NAN)))
                        .collect::<Vec<_>>()
                        .join(", "))
                    .unwrap_or_default()
            )),
        ]);
        per.insert(
            name.clone(),
            json!({"coefficients": coef, "change_over_record": change}),
        );
    }
    Ok(Step {
        json: json!({"step": "detrend", "model": name_of, "channels": per}),
        rows,
        summary: format!(
            "a {name_of} drift fitted by least squares and removed from every channel"
        ),
    })
}

/// A binary record preprocessed, binned by temperature, or with a channel
/// named as an environmental column (`temperature_c`, `humidity_pct`, e.g.
/// a Python keyword array): read into memory as [`Channels`] (a NaN
/// sample is a missing one, as an empty CSV cell; an infinite one is
/// refused naming its row and channel) and reduced as a CSV record is,
/// the environmental channels summarised in `environment` as a CSV
/// record's columns are (`temperature_c` kept for the bins); the caller
/// has checked the options and the rate (`rate_hz`) and selected the
/// channels (`pick`: index and name, as
/// [`incal_io::binary::MappedRecord::select`] gives them).
pub(super) fn reduce_mapped(
    rec: &incal_io::binary::MappedRecord,
    pick: Vec<(usize, String)>,
    rate_hz: f64,
    o: &super::NoiseOptions,
    progress: &dyn super::Progress,
) -> Result<crate::document::ResultDocument> {
    use crate::procedures::Procedure;
    let name = rec.name();
    let rows = rec.rows();
    let mut samples = Vec::with_capacity(pick.len());
    for (c, ch) in &pick {
        let col: Vec<f64> = (0..rows).map(|r| rec.get(*c, r)).collect();
        if let Some(r) = col.iter().position(|v| v.is_infinite()) {
            return Err(crate::error::Error::Unsupported(format!(
                "{name}: row {}, channel {ch}: an infinite sample",
                r + 1
            )));
        }
        samples.push(col);
    }
    let mut names: Vec<String> = pick.into_iter().map(|p| p.1).collect();
    let mut conditions = Vec::new();
    let mut temperature_c = None;
    for env in incal_io::CONDITION_COLUMNS {
        if let Some(k) = names.iter().position(|n| n == env) {
            names.remove(k);
            let col = samples.remove(k);
            let ok: Vec<f64> = col.iter().copied().filter(|v| v.is_finite()).collect();
            if !ok.is_empty() {
                conditions.push(incal_io::Condition {
                    name: env.to_string(),
                    count: ok.len(),
                    mean: ok.iter().sum::<f64>() / ok.len() as f64,
                    min: ok.iter().copied().fold(f64::INFINITY, f64::min),
                    max: ok.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                });
            }
            if env == "temperature_c" {
                temperature_c = Some(col);
            }
        }
    }
    if names.is_empty() {
        return Err(crate::error::Error::Unsupported(format!(
            "{name}: no channel besides the environment's (temperature_c, humidity_pct)"
        )));
    }
    let input = Channels {
        names,
        samples,
        rows,
        rate_hz,
        timebase: None,
        gaps: Vec::new(),
        duplicates: 0,
        sorted: 0,
        temperature_c,
    };
    let mut doc = super::Noise::reduce(&input, o, progress).map_err(|e| e.in_file(name))?;
    crate::procedures::record_environment(&mut doc, &conditions);
    let mut h = rec.hash(false);
    h.update(rec.bytes(0, rows));
    doc.inputs.insert(
        0,
        crate::document::InputFile {
            role: "input".into(),
            path: if name == incal_io::source::STDIN_NAME {
                "-"
            } else {
                name
            }
            .into(),
            sha256: h.finish(name)?,
            rows: Some(rows as u64),
        },
    );
    doc.options = super::options_map(&o.settled(None))?;
    Ok(doc)
}

#[cfg(test)]
#[path = "preprocess_tests.rs"]
mod tests;
