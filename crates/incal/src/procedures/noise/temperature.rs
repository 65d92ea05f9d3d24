//! Noise against temperature from one long record (`temperature_bin_c:
//! W`): the record's samples binned by its `temperature_c` column into
//! bins W °C wide (`[kW, (k+1)W)`), each bin's IEEE 952 terms fitted to
//! the Allan variance of its stretches, and each term as a polynomial in
//! temperature (the thermal fit's machinery, [`crate::procedures::thermal`]:
//! weighted least squares in `T − 25 °C`, the degree rule).
//!
//! A bin's stretches are the runs of consecutive samples whose
//! temperature falls in it, cut at the record's gaps and missing samples
//! (and missing temperatures); a run stays in its bin until the
//! temperature leaves it by more than [`HYSTERESIS`] of a bin, so a
//! sensor's jitter at an edge does not split it;
//! runs shorter than the noise analysis's minimum are left out, the
//! others (at least [`MIN_RUN`] samples) pooled as the gap-aware deviations pool the stretches between
//! gaps ([`crate::noise::stability_segments`]). Its temperature is the
//! mean over the samples used. A bin whose longest run is too short for
//! one averaging time is listed with its reason and not fitted.
//!
//! (Several results at their own temperatures, e.g. one record per
//! chamber plateau, go through `incal thermal fit` instead: every noise
//! coefficient of the documents as a polynomial.)
//!
//! In the document, per channel, `channels.NAME.temperature` holds
//! `bin_c`, `bins` (each `{t_c, t_low_c, t_high_c, samples, stretches,
//! terms: {TERM: {value, u, dof}}}` in the terms' units, or `{t_c, samples,
//! reason}` when not analysed) and `models` (per term name: `degree`,
//! `t_ref_c`, `t_min_c`, `t_max_c`, `unit`, `bins` used); the coefficients
//! `NAME.TERM.c0` … `NAME.TERM.cd` (the term's unit per °C^k) and the
//! tables `noise_temperature.NAME.TERM` (per bin: temperature, value, u,
//! polynomial, residual) and `noise_temperature_model.NAME.TERM` (the
//! polynomial with u and U95 at 11 temperatures over the range).

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use super::document::NoiseUnits;
use super::gaps::stretches;
use super::input::Channels;
use super::{Build, NoiseOptions};
use crate::document::{Cell, Coefficient, DecisionCode, DocumentBuilder, Table};
use crate::error::{Error, Result};
use crate::noise::terms::{fit_terms, TermFit, TERMS};
use crate::noise::StabilityOptions;
use crate::procedures::thermal::document::polynomial_table;
use crate::procedures::thermal::{fit_with_degree, power_unit, Degree, PolyFit, DEFAULT_T_REF_C};
use crate::units::Unit;

/// How far (in bins) the temperature may stray past a bin's edges before
/// a run leaves it.
pub const HYSTERESIS: f64 = 0.1;

/// The shortest run of samples a bin uses (a term fit needs a few octaves
/// of τ).
pub const MIN_RUN: usize = 64;

/// The temperature binning option (flattened into the noise options).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct TemperatureOptions {
    /// Bin a record with a `temperature_c` column into bins this wide
    /// (°C), fit the noise terms in each, and each term as a polynomial in
    /// temperature.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub temperature_bin_c: Option<f64>,
}

impl TemperatureOptions {
    /// Range check (names the key).
    pub fn validate(&self) -> Result<()> {
        if let Some(w) = self.temperature_bin_c {
            crate::options::check_range("temperature_bin_c", w, 0.01, 500.0, "degC")?;
        }
        Ok(())
    }
}

/// One bin of one channel.
#[derive(Debug, Clone)]
pub struct Bin {
    /// Mean temperature of the samples used, °C.
    pub t_c: f64,
    /// The bin's edges, °C.
    pub edges_c: (f64, f64),
    /// Samples used.
    pub samples: usize,
    /// Stretches pooled.
    pub stretches: usize,
    /// The term fit (internal unit), or why there is none.
    pub fit: std::result::Result<TermFit, String>,
}

/// A channel's bins.
#[derive(Debug, Clone)]
pub struct ChannelTemperature {
    /// Bin width, °C.
    pub bin_c: f64,
    /// The bins with samples, coldest first.
    pub bins: Vec<Bin>,
}

/// The bins of every channel (`None` each without `temperature_bin_c`);
/// refused without a `temperature_c` column, or when preprocessing changed
/// the rows (`fill`).
pub(super) fn compute(
    input: &Channels,
    o: &NoiseOptions,
    build: Build,
) -> Result<Vec<Option<ChannelTemperature>>> {
    let Some(w) = o.temperature.temperature_bin_c else {
        return Ok(vec![None; input.names.len()]);
    };
    let Some(temp) = &input.temperature_c else {
        return Err(Error::Unsupported(
            "temperature_bin_c: the record has no temperature_c column".into(),
        ));
    };
    if temp.len() != input.rows {
        return Err(Error::Unsupported(
            "temperature_bin_c: --fill gaps changes the rows; bin a record without filling (the bins are cut at gaps)".into(),
        ));
    }
    let opts = StabilityOptions {
        tau0_s: build.tau0,
        grid: crate::noise::TauGrid::Octave,
        confidence: o.confidence,
        parallel: false,
    };
    input
        .samples
        .iter()
        .map(|col| {
            channel(
                col,
                temp,
                &input.gaps,
                w,
                build,
                &opts,
                o.min_samples().max(MIN_RUN),
            )
            .map(Some)
        })
        .collect()
}

/// One channel's bins (module docs).
fn channel(
    col: &[f64],
    temp: &[f64],
    gaps: &[(usize, usize)],
    w: f64,
    build: Build,
    opts: &StabilityOptions,
    min: usize,
) -> Result<ChannelTemperature> {
    // Runs: stretches between gaps cut where the bin changes. A run stays
    // in its bin until the temperature leaves it by more than a tenth of
    // a bin (a sensor's jitter at an edge does not split it).
    let h = HYSTERESIS * w;
    let mut runs: std::collections::BTreeMap<i64, Vec<std::ops::Range<usize>>> = Default::default();
    for s in stretches(col, gaps).into_iter().filter(|s| !s.is_empty()) {
        let mut cur: Option<(i64, usize)> = None;
        // One step past the stretch (a NaN) closes its last run.
        let at = temp[s.clone()]
            .iter()
            .copied()
            .chain(std::iter::once(f64::NAN));
        for (i, t) in (s.start..).zip(at) {
            let stays =
                cur.is_some_and(|(b, _)| t >= b as f64 * w - h && t < (b + 1) as f64 * w + h);
            if stays {
                continue;
            }
            if let Some((b, start)) = cur.take() {
                runs.entry(b).or_default().push(start..i);
            }
            if t.is_finite() {
                cur = Some(((t / w).floor() as i64, i));
            }
        }
    }
    let mut bins = Vec::new();
    for (b, rs) in runs {
        let used: Vec<&std::ops::Range<usize>> = rs.iter().filter(|r| r.len() >= min).collect();
        let samples: usize = used.iter().map(|r| r.len()).sum();
        let t_sum: f64 = used.iter().flat_map(|r| temp[(*r).clone()].iter()).sum();
        let all: usize = rs.iter().map(|r| r.len()).sum();
        let t_c = if samples > 0 {
            t_sum / samples as f64
        } else {
            rs.iter().flat_map(|r| temp[r.clone()].iter()).sum::<f64>() / all as f64
        };
        let fit = if used.is_empty() {
            Err(format!(
                "its longest run of samples has {} samples; at least {min} are needed for a term fit",
                rs.iter().map(|r| r.len()).max().unwrap_or(0)
            ))
        } else {
            let xs: Vec<Vec<f64>> = used
                .iter()
                .map(|r| build.whole(r.len(), |i| col[r.start + i] * build.factor))
                .collect();
            let n_phase: usize = xs.iter().map(Vec::len).sum();
            crate::noise::stability_segments(&xs, opts, &|_| {})
                .and_then(|st| fit_terms(&st.taus_s, &st.oadev, &st.alpha, build.tau0, n_phase))
                .map_err(|e| e.to_string())
        };
        bins.push(Bin {
            t_c,
            edges_c: (b as f64 * w, (b + 1) as f64 * w),
            samples: if used.is_empty() { all } else { samples },
            stretches: used.len(),
            fit,
        });
    }
    Ok(ChannelTemperature { bin_c: w, bins })
}

/// A term's polynomial: the fit and the bins' points it was fitted to.
struct Model {
    fit: PolyFit,
    t: Vec<f64>,
    y: Vec<f64>,
    u: Vec<f64>,
}

impl ChannelTemperature {
    /// Add the coefficients `NAME.TERM.ck`, the tables and the decisions
    /// of channel `name` to `b`; the `channels.NAME.temperature` object.
    pub fn render(&self, name: &str, units: &NoiseUnits, b: &mut DocumentBuilder) -> Result<Value> {
        let mut models = serde_json::Map::new();
        for j in 0..TERMS.len() {
            let (term, unit, k) = &units.terms[j];
            let pts: Vec<(f64, f64, f64, f64)> = self
                .bins
                .iter()
                .filter_map(|bin| {
                    let t = bin.fit.as_ref().ok()?.terms[j]?;
                    Some((bin.t_c, t.value * k, t.u * k, t.dof))
                })
                .collect();
            if pts.is_empty() {
                continue;
            }
            let full = format!("{name}.{term}");
            let t: Vec<f64> = pts.iter().map(|p| p.0).collect();
            let y: Vec<f64> = pts.iter().map(|p| p.1).collect();
            let u: Vec<f64> = pts.iter().map(|p| p.2).collect();
            // Welch–Satterthwaite for the weighted mean (JCGM 100 G.4):
            // ν = (Σ u⁻²)² / Σ (u⁻⁴/ν_i), the bins' dof pooled as their
            // weights pool them (infinite when every bin's is).
            let w: f64 = pts.iter().map(|p| p.2.powi(-2)).sum();
            let d: f64 = pts.iter().map(|p| p.2.powi(-4) / p.3).sum();
            let dof = if d > 0.0 { w * w / d } else { f64::INFINITY };
            let (fit, _) =
                match fit_with_degree(&full, &t, &y, &u, &[], DEFAULT_T_REF_C, Degree::Auto, dof) {
                    Ok(f) => f,
                    Err(e) => {
                        b.decision(
                            DecisionCode::NotDetermined,
                            format!(
                            "{full}: identified in {} bin(s): no polynomial in temperature ({e})",
                            pts.len()
                        ),
                        );
                        continue;
                    }
                };
            let m = Model { fit, t, y, u };
            add_coefficients(b, &full, unit, &m.fit)?;
            b.table(model_table(&full, unit, &m)?);
            b.table(polynomial_table(
                &format!("noise_temperature_model.{full}"),
                &format!("{full} from its polynomial over the bins' range, with its uncertainty"),
                unit,
                &m.fit,
            )?);
            models.insert(term.clone(), model_json(unit, &m));
        }
        let bins: Vec<Value> = self
            .bins
            .iter()
            .map(|bin| match &bin.fit {
                Ok(f) => {
                    let mut terms = serde_json::Map::new();
                    for (j, t) in f.terms.iter().enumerate() {
                        if let Some(t) = t {
                            let (term, _, k) = &units.terms[j];
                            terms.insert(
                                term.clone(),
                                json!({"value": t.value * k, "u": t.u * k, "dof": t.dof}),
                            );
                        }
                    }
                    json!({"t_c": bin.t_c, "t_low_c": bin.edges_c.0, "t_high_c": bin.edges_c.1,
                           "samples": bin.samples, "stretches": bin.stretches, "terms": terms})
                }
                Err(why) => {
                    json!({"t_c": bin.t_c, "t_low_c": bin.edges_c.0, "t_high_c": bin.edges_c.1,
                                   "samples": bin.samples, "reason": why})
                }
            })
            .collect();
        Ok(json!({"bin_c": self.bin_c, "bins": bins, "models": models}))
    }
}

/// `NAME.TERM.c0` … `cd` with their covariance and the fit's dof.
fn add_coefficients(b: &mut DocumentBuilder, full: &str, unit: &Unit, f: &PolyFit) -> Result<()> {
    let dof = f.fit.estimates.dof();
    for k in 0..=f.degree {
        let n = format!("{full}.c{k}");
        let u = f.covariance[(k, k)].max(0.0).sqrt();
        b.coefficient(
            &n,
            Coefficient::new(&n, f.values[k], u, power_unit(unit, k), dof)?,
        )?;
    }
    Ok(())
}

/// The model's JSON entry (module docs).
fn model_json(unit: &Unit, m: &Model) -> Value {
    let f = &m.fit;
    let (lo, hi) = f.t_range_c;
    json!({
        "degree": f.degree,
        "t_ref_c": f.t_ref_c,
        "t_min_c": lo,
        "t_max_c": hi,
        "unit": unit.as_str(),
        "bins": m.t.len(),
    })
}

/// The table `noise_temperature.NAME.TERM` (module docs).
fn model_table(full: &str, unit: &Unit, m: &Model) -> Result<Table> {
    let u = Some(unit.clone());
    let mut tab = Table::new(
        &format!("noise_temperature.{full}"),
        &format!("{full} in each temperature bin: value, polynomial and residual"),
        &[
            ("temperature_c", Some(Unit::Other("degC".into()))),
            ("value", u.clone()),
            ("u", u.clone()),
            ("polynomial", u.clone()),
            ("residual", u),
        ],
    );
    for ((t, y), s) in m.t.iter().zip(&m.y).zip(&m.u) {
        let (p, _) = m.fit.eval(*t);
        tab.push(vec![
            Cell::num(*t),
            Cell::num(*y),
            Cell::num(*s),
            Cell::num(p),
            Cell::num(y - p),
        ])?;
    }
    Ok(tab)
}
