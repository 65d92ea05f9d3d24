//! Threshold and resolution: the smallest input step the instrument
//! answers, at zero input (threshold) and at a base input (resolution),
//! from steps of increasing size on a rate table (a gyro; IEEE Std
//! 952-1997 and IEEE Std 1431-2004 threshold and resolution tests, GJB
//! 2426A-2004) or a dividing head (an accelerometer; GJB 1037A-2004,
//! IEEE Std 1293-2018) (docs/src/threshold.md).
//!
//! # Plateaus, levels and steps
//! Consecutive rows at one commanded input form a plateau (its first
//! `settle_s` left out). Zero and the base input are the levels; a step
//! is a transition between consecutive plateaus with one end at a level,
//! its size `|Δu|` (deg/s, or g: `sin(tilt)`); sizes within 2 % are one
//! size ([`levels::steps`]).
//!
//! # Response of a step size
//! `S = (1/T) Σ_t (ȳ_{k+1} − ȳ_k)/(u_{k+1} − u_k)` over its `T`
//! transitions (plateau means ȳ), and the response ratio `ρ = S/K1`:
//! the share of the output change the scale factor expects. K1 is given
//! (`scale_factor`, `scale_factor_u`), or measured as
//! `(ȳ_base − ȳ_zero)/u_base` over the plateaus at the two levels. Each
//! plateau mean has variance `s²/n` with `s²` measured on the record's
//! revisits of its levels ([`levels::noise`]: a two-sample variance at
//! the plateau's own length, so correlated noise and drift between
//! plateaus are in u); u(ρ) by linear propagation with the covariance
//! of the plateau means shared between S and K1.
//!
//! # Decision and the 50 % point
//! A step size passes when its output change is shown to be at least
//! `response_fraction` (default 50 %) of `K1·Δu`: the one-sided test
//! `t = (ρ − 0.5)/u(ρ) > t_{1−α, ν}` (`α = test_level`, 5 %). The
//! bracket: the smallest size from which every larger size passes, and
//! the size below it (which fails). Refused when the largest size fails
//! (no step passes: the threshold is above the steps) or the smallest
//! passes (every step passes: below them), naming the level and the
//! size. The threshold (resolution) is the input at which the response
//! reaches 50 %, interpolated between two adjacent sizes `a < b` linearly
//! in `1/Δu`: `x = x_a + (0.5 − ρ_a)(x_b − x_a)/(ρ_b − ρ_a)`, `Δ₅₀ = 1/x`
//! (exact for a dead band `D`, whose response `ρ = 1 − D/Δu` is linear
//! in `1/Δu` and reaches 50 % at `2D`). Its 95 % interval is Fieller's
//! for the ratio `(0.5 − ρ_a)/(ρ_b − ρ_a)` ([`fieller`]; E. C. Fieller,
//! "Some problems in interval estimation", J. R. Stat. Soc. B 16 (1954)
//! 175), carried through the monotone interpolation: exact for normal
//! ratios however curved the interpolation (a linearised u, taken where
//! the estimate lies, is too small on one side when a ratio's u is a
//! sizeable part of `ρ_b − ρ_a`). The
//! value reported is the interval's middle, U95 its half-width and
//! `u = U95/k95` (JCGM 101:2008 7.7: the interval, not the curve's point,
//! carries the coverage; the point itself is in the document). The two
//! sizes are those whose ratios straddle 50 %, the pair nearest the
//! bracket (the bracket itself jumps with the noise where a size's ratio
//! is near 50 %; the straddling pair moves continuously with the data),
//! else the bracket. Where the two ratios do not rise the value is their
//! middle with the rectangular u of their distance, and a warning.

pub mod document;
pub mod input;
pub mod levels;
mod montecarlo;
pub mod plan;
pub mod sim;

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::error::{Error, Result};
use crate::estimation::{coverage_factor, numeric_jacobian, propagate, Estimates};
use crate::warning::{Warning, WarningCode};
use input::{Record, Sensor};
use levels::{Group, Noise, Plateau, StepSize};

/// Options of the threshold reduction. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ThresholdOptions {
    /// The scale factor K1 (output units per deg/s, or per g), from a
    /// scale-factor test; default: measured from the plateaus at zero and
    /// at the base input.
    #[serde(default)]
    pub scale_factor: Option<f64>,
    /// Standard uncertainty of the given scale factor (same units;
    /// default 0).
    #[serde(default)]
    pub scale_factor_u: f64,
    /// The base input for the resolution, in the input column's units
    /// (deg/s, or deg of tilt); default: the non-zero input held by most
    /// plateaus (at least 3, twice any other).
    #[serde(default)]
    pub base_input: Option<f64>,
    /// Time left out at the start of each plateau (s; default 0): the
    /// table's or head's transient.
    #[serde(default)]
    pub settle_s: f64,
    /// Sampling rate (Hz) for `settle_s` when the file has no `time_s`.
    #[serde(default)]
    pub rate_hz: Option<f64>,
    /// The share of `K1·Δinput` a step's output change must reach
    /// (default 0.5, the standards' 50 %).
    #[serde(default = "half")]
    pub response_fraction: f64,
    /// Level of the one-sided test (default 0.05).
    #[serde(default = "five_percent")]
    pub test_level: f64,
}

fn half() -> f64 {
    0.5
}
fn five_percent() -> f64 {
    0.05
}

impl Default for ThresholdOptions {
    fn default() -> Self {
        Self {
            scale_factor: None,
            scale_factor_u: 0.0,
            base_input: None,
            settle_s: 0.0,
            rate_hz: None,
            response_fraction: 0.5,
            test_level: 0.05,
        }
    }
}

impl ThresholdOptions {
    /// Every range check of the reduction.
    pub fn validate(&self) -> Result<()> {
        use crate::options::{check_range, invalid};
        if let Some(k) = self.scale_factor {
            check_range("scale_factor", k, -1e15, 1e15, "output per input")?;
            if k.abs() < 1e-15 {
                return invalid("scale_factor", "a scale factor of zero answers no input");
            }
        }
        check_range("scale_factor_u", self.scale_factor_u, 0.0, 1e15, "")?;
        if self.scale_factor.is_none() && self.scale_factor_u != 0.0 {
            return invalid("scale_factor_u", "given without scale_factor");
        }
        if let Some(b) = self.base_input {
            check_range("base_input", b, -1e5, 1e5, "")?;
            if b == 0.0 {
                return invalid(
                    "base_input",
                    "zero is the threshold's level, not a base input",
                );
            }
        }
        check_range("settle_s", self.settle_s, 0.0, 1e7, "s")?;
        if let Some(r) = self.rate_hz {
            check_range("rate_hz", r, 1e-3, 1e7, "Hz")?;
        }
        check_range("response_fraction", self.response_fraction, 0.05, 0.95, "")?;
        check_range("test_level", self.test_level, 1e-4, 0.5, "")
    }
}

/// One step size's response.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// The steps.
    pub step: StepSize,
    /// `S`, the output change per unit input (output per deg/s or g).
    pub change_per_input: f64,
    /// The response ratio `ρ = S/K1` and its u.
    pub ratio: (f64, f64),
    /// Degrees of freedom of u(ρ).
    pub dof: f64,
    /// One-sided p-value of `ρ ≤ fraction`.
    pub p_value: f64,
    /// Shown to reach the fraction.
    pub passes: bool,
    /// S's weights over the plateau means (plateau, weight), each plateau
    /// once.
    coef: Vec<(usize, f64)>,
}

/// A level's threshold (or resolution).
#[derive(Debug, Clone, PartialEq)]
pub struct Crossing {
    /// The level.
    pub group: Group,
    /// The bracket: the largest failing size and the smallest passing
    /// one above which all pass.
    pub bracket: (f64, f64),
    /// The two sizes interpolated between.
    pub pair: (f64, f64),
    /// The value (the 95 % interval's middle) and its u (input units).
    pub value: (f64, f64),
    /// The interpolated 50 % point itself (input units).
    pub at_fraction: f64,
    /// The 95 % interval (Fieller's, module docs).
    pub interval: (f64, f64),
    /// Degrees of freedom.
    pub dof: f64,
    /// Interpolated (else the bracket's middle).
    pub interpolated: bool,
}

/// The scale factor used: value, u, coefficients over the plateau means
/// (measured) or none (given).
#[derive(Debug, Clone, PartialEq)]
pub struct ScaleFactor {
    /// K1 (output per input unit).
    pub value: f64,
    /// Its u from the given value (0 when measured: then from `coef`).
    pub u_given: f64,
    /// Coefficients over the plateau means, when measured.
    pub coef: Option<Vec<f64>>,
}

/// A threshold test reduced.
#[derive(Debug, Clone)]
pub struct ThresholdResult {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// The plateaus.
    pub plateaus: Vec<Plateau>,
    /// The base input as written, if any.
    pub base_command: Option<f64>,
    /// The noise at the plateau scale.
    pub noise: Noise,
    /// The scale factor.
    pub scale: ScaleFactor,
    /// Each step size's response, by level then size.
    pub responses: Vec<Response>,
    /// The threshold and the resolution found.
    pub crossings: Vec<Crossing>,
    /// Warnings.
    pub warnings: Vec<Warning>,
    /// The options.
    pub options: ThresholdOptions,
}

impl ThresholdResult {
    /// `u²` of `aᵀȳ` (plateau means independent, `var = s²/n`).
    fn var_of(&self, a: &[f64]) -> f64 {
        var_of(&self.plateaus, self.noise.var_long, a)
    }

    /// The u of the scale factor.
    pub fn scale_u(&self) -> f64 {
        match &self.scale.coef {
            Some(c) => self.var_of(c).sqrt(),
            None => self.scale.u_given,
        }
    }
}

fn var_of(p: &[Plateau], s2: f64, a: &[f64]) -> f64 {
    a.iter().zip(p).map(|(c, q)| c * c * s2 / q.n as f64).sum()
}

fn dot(a: &[f64], p: &[Plateau]) -> f64 {
    a.iter().zip(p).map(|(c, q)| c * q.mean).sum()
}

/// The reduction (module docs).
pub fn calibrate(rec: &Record, o: &ThresholdOptions) -> Result<ThresholdResult> {
    o.validate()?;
    if o.settle_s > 0.0 && rec.time_s.is_none() && o.rate_hz.is_none() {
        return crate::options::invalid("settle_s", "needs the time: a time_s column or rate_hz");
    }
    let mut p = levels::plateaus(rec, o.settle_s, o.rate_hz)?;
    let base = levels::base_command(&p, o.base_input)?;
    levels::mark(&mut p, base);
    let steps = levels::steps(&p);
    if steps.is_empty() {
        return Err(Error::Unsupported(format!(
            "no step: {} plateaus, none a step from zero{} and back; a threshold test steps from a level it returns to",
            p.len(),
            if base.is_some() { " or the base input" } else { " (and no base input is held by 3 plateaus or more: give base_input)" }
        )));
    }
    let noise = levels::noise(&p)?;
    let scale = scale_factor(&p, rec.sensor, o)?;
    let mut r = ThresholdResult {
        sensor: rec.sensor,
        plateaus: p,
        base_command: base,
        noise,
        scale,
        responses: Vec::new(),
        crossings: Vec::new(),
        warnings: Vec::new(),
        options: o.clone(),
    };
    r.responses = steps
        .into_iter()
        .map(|s| response(&r, s))
        .collect::<Result<_>>()?;
    for g in [Group::Zero, Group::Base] {
        let at: Vec<&Response> = r.responses.iter().filter(|x| x.step.group == g).collect();
        if !at.is_empty() {
            let c = crossing(&r, g, &at)?;
            r.crossings.push(c);
        }
    }
    warn(&mut r);
    Ok(r)
}

/// K1: given, or `(ȳ_base − ȳ_zero)/u_base` over the plateaus at the two
/// levels.
fn scale_factor(p: &[Plateau], sensor: Sensor, o: &ThresholdOptions) -> Result<ScaleFactor> {
    if let Some(k) = o.scale_factor {
        return Ok(ScaleFactor {
            value: k,
            u_given: o.scale_factor_u,
            coef: None,
        });
    }
    let nb = p.iter().filter(|q| q.level == Some(Group::Base)).count();
    let nz = p.iter().filter(|q| q.level == Some(Group::Zero)).count();
    if nb == 0 || nz == 0 {
        return crate::options::invalid(
            "scale_factor",
            "needed: the record has no plateau at both zero and a base input to measure K1 from (give the scale factor of a scale-factor test)",
        );
    }
    let ub = p
        .iter()
        .find(|q| q.level == Some(Group::Base))
        .map_or(1.0, |q| q.input);
    let coef: Vec<f64> = p
        .iter()
        .map(|q| match q.level {
            Some(Group::Base) => 1.0 / (nb as f64 * ub),
            Some(Group::Zero) => -1.0 / (nz as f64 * ub),
            None => 0.0,
        })
        .collect();
    let value = dot(&coef, p);
    if value == 0.0 || !value.is_finite() {
        return Err(Error::Unsupported(format!(
            "the output does not change between zero and the base input ({} {}): no scale factor",
            ub,
            sensor.unit()
        )));
    }
    Ok(ScaleFactor {
        value,
        u_given: 0.0,
        coef: Some(coef),
    })
}

/// The estimates `[K1, S_1, …]` with their joint covariance: the plateau
/// means' `s²/n` through the coefficient rows (sparse: plateau, weight),
/// and the given K1's u. `C_ij = Σ_k a_ik a_jk s²/n_k`, computed over the
/// rows' own plateaus (no dense plateau-by-plateau matrix).
fn estimates(r: &ThresholdResult, rows: &[&[(usize, f64)]]) -> Result<Estimates> {
    let k_coef: Vec<(usize, f64)> = r
        .scale
        .coef
        .as_ref()
        .map(|c| {
            c.iter()
                .copied()
                .enumerate()
                .filter(|(_, w)| *w != 0.0)
                .collect()
        })
        .unwrap_or_default();
    let mut all: Vec<&[(usize, f64)]> = vec![&k_coef];
    all.extend_from_slice(rows);
    let m = all.len();
    // Each row as a map plateau -> weight, for the products.
    let maps: Vec<std::collections::HashMap<usize, f64>> = all
        .iter()
        .map(|row| row.iter().copied().collect())
        .collect();
    let v = |k: usize| r.noise.var_long / r.plateaus[k].n as f64;
    let mut cov = DMatrix::zeros(m, m);
    for i in 0..m {
        for j in i..m {
            let c: f64 = all[i]
                .iter()
                .filter_map(|(k, a)| maps[j].get(k).map(|b| a * b * v(*k)))
                .sum();
            cov[(i, j)] = c;
            cov[(j, i)] = c;
        }
    }
    cov[(0, 0)] += r.scale.u_given.powi(2);
    let mut values = vec![r.scale.value];
    values.extend(rows.iter().map(|c| sparse_dot(c, &r.plateaus)));
    let mut names = vec!["K1".to_string()];
    names.extend((0..rows.len()).map(|i| format!("S{i}")));
    Estimates::new(names, DVector::from_vec(values), cov, r.noise.dof)
}

/// `Σ a_k ȳ_k` over a sparse row.
fn sparse_dot(a: &[(usize, f64)], p: &[Plateau]) -> f64 {
    a.iter().map(|(k, w)| w * p[*k].mean).sum()
}

/// Welch–Satterthwaite ([`crate::procedures::gyro::welch_satterthwaite`]):
/// the part of `u²` from the plateau means with the noise's ν, the given
/// K1's part counted as known (ν = ∞).
fn effective_dof(u2: f64, given_part: f64, dof: f64) -> f64 {
    crate::procedures::gyro::welch_satterthwaite(&[
        ((u2 - given_part).max(0.0).sqrt(), dof),
        (given_part.max(0.0).sqrt(), f64::INFINITY),
    ])
}

/// One step size's response ratio and test.
fn response(r: &ThresholdResult, step: StepSize) -> Result<Response> {
    // S's weights over the plateau means: two per transition (a plateau
    // shared by two transitions appears twice; the products add up).
    let t = step.transitions.len() as f64;
    let mut coef: Vec<(usize, f64)> = Vec::with_capacity(2 * step.transitions.len());
    for &k in &step.transitions {
        let du = r.plateaus[k + 1].input - r.plateaus[k].input;
        coef.push((k, -1.0 / (t * du)));
        coef.push((k + 1, 1.0 / (t * du)));
    }
    coef.sort_by_key(|c| c.0);
    coef.dedup_by(|b, a| {
        let same = a.0 == b.0;
        if same {
            a.1 += b.1;
        }
        same
    });
    let e = estimates(r, &[&coef])?;
    let ratio = e.map_numeric(vec!["rho".into()], |x| DVector::from_vec(vec![x[1] / x[0]]))?;
    let (rho, u) = (ratio.values()[0], ratio.u_at(0));
    let k = r.scale.value;
    let given = (rho / k * r.scale.u_given).powi(2);
    let dof = effective_dof(u * u, given, r.noise.dof);
    let f = r.options.response_fraction;
    let p_value = if u > 0.0 {
        let z = (rho - f) / u;
        let tail = match StudentsT::new(0.0, 1.0, dof.min(1e6)) {
            Ok(t) => 1.0 - t.cdf(z),
            Err(_) => 0.5,
        };
        tail.clamp(0.0, 1.0)
    } else if rho > f {
        0.0
    } else {
        1.0
    };
    Ok(Response {
        change_per_input: e.values()[1],
        ratio: (rho, u),
        dof,
        p_value,
        passes: p_value < r.options.test_level,
        step,
        coef,
    })
}

/// The bracket and the 50 % point of one level (module docs).
fn crossing(r: &ThresholdResult, g: Group, at: &[&Response]) -> Result<Crossing> {
    let unit = r.sensor.unit();
    let name = g.name();
    if at.len() < 2 {
        return Err(Error::Unsupported(format!(
            "the steps {} have one size ({:.4e} {unit}): a {name} needs step sizes that bracket it, at least two",
            g.about(),
            at[0].step.size
        )));
    }
    let last = at[at.len() - 1];
    if !last.passes {
        return Err(Error::Unsupported(format!(
            "no step {} passes: the largest, {:.4e} {unit}, is not shown to reach {:.0} % of K1 times the step (ratio {:.3} +- {:.3}); the {name} is above the steps: add larger steps",
            g.about(),
            last.step.size,
            100.0 * r.options.response_fraction,
            last.ratio.0,
            last.ratio.1
        )));
    }
    let b = (0..at.len())
        .rev()
        .take_while(|&i| at[i].passes)
        .last()
        .unwrap_or(at.len() - 1);
    if b == 0 {
        return Err(Error::Unsupported(format!(
            "every step {} passes, the smallest {:.4e} {unit} included (ratio {:.3} +- {:.3}): the {name} is below the steps: add smaller steps",
            g.about(),
            at[0].step.size,
            at[0].ratio.0,
            at[0].ratio.1
        )));
    }
    // The pair interpolated: the adjacent sizes whose ratios straddle the
    // fraction, the one nearest the test's bracket (a choice continuous in
    // the data, where the test's bracket jumps with the noise at a size
    // whose ratio is near 50 %); else the test's bracket.
    let f = r.options.response_fraction;
    let pair = (0..at.len() - 1)
        .filter(|&i| at[i].ratio.0 < f && at[i + 1].ratio.0 >= f)
        .min_by_key(|&i| i.abs_diff(b - 1))
        .unwrap_or(b - 1);
    let (ra, rb) = (at[pair], at[pair + 1]);
    let (da, db) = (ra.step.size, rb.step.size);
    let bracket = (at[b - 1].step.size, at[b].step.size);
    let e = estimates(r, &[&ra.coef, &rb.coef])?;
    let point = move |x: &DVector<f64>| {
        let (pa, pb) = (x[1] / x[0], x[2] / x[0]);
        let (xa, xb) = (1.0 / da, 1.0 / db);
        1.0 / (xa + (f - pa) * (xb - xa) / (pb - pa))
    };
    let v = point(e.values());
    let rising = rb.ratio.0 > ra.ratio.0;
    if rising && v.is_finite() && v >= 0.5 * da && v <= db {
        let steps: Vec<f64> = (0..e.len())
            .map(|k| 1e-6 * e.values()[k].abs().max(e.u_at(k)).max(1e-300))
            .collect();
        let j = numeric_jacobian(&|x| DVector::from_vec(vec![point(x)]), e.values(), &steps);
        let c = propagate(e.covariance(), &j);
        let u2 = c[(0, 0)].max(0.0);
        let jk = j[(0, 0)] * r.scale.u_given;
        let dof = effective_dof(u2, jk * jk, r.noise.dof);
        let k = coverage_factor(dof, 0.95);
        let rho = e.map_numeric(vec!["rho_a".into(), "rho_b".into()], |x| {
            DVector::from_vec(vec![x[1] / x[0], x[2] / x[0]])
        })?;
        let Some((lo, hi)) = fieller(rho.values(), rho.covariance(), f, (da, db), k) else {
            // The noise puts the 50 % point anywhere: the pair's middle.
            return Ok(middle(g, bracket, (da, db)));
        };
        // The value is the interval's middle and U95 its half-width, so
        // value ± U95 is the interval.
        let u = if u2 > 0.0 { 0.5 * (hi - lo) / k } else { 0.0 };
        return Ok(Crossing {
            group: g,
            bracket,
            pair: (da, db),
            value: (if u2 > 0.0 { 0.5 * (lo + hi) } else { v }, u),
            at_fraction: v,
            interval: (lo, hi),
            dof,
            interpolated: true,
        });
    }
    Ok(middle(g, bracket, (da, db)))
}

/// The middle of the pair `(da, db)` with the rectangular u of their
/// distance: where the ratios do not locate the 50 % point.
fn middle(group: Group, bracket: (f64, f64), (da, db): (f64, f64)) -> Crossing {
    Crossing {
        group,
        bracket,
        pair: (da, db),
        value: (0.5 * (da + db), (db - da) / 12f64.sqrt()),
        at_fraction: 0.5 * (da + db),
        interval: (da, db),
        dof: f64::INFINITY,
        interpolated: false,
    }
}

/// Fieller's interval for the 50 % point (module docs): with
/// `N = f − ρ_a`, `D = ρ_b − ρ_a` (jointly normal, covariance from that
/// of `ρ = (ρ_a, ρ_b)`), the ratios `R = N/D` with
/// `(N − R D)² ≤ k² var(N − R D)`, a quadratic in `R`; then
/// `x = x_a + (x_b − x_a) R` and `Δ = 1/x`, both monotone. `None` when
/// `D` is not distinguishable from zero at `k` (the set is unbounded) or
/// the interval reaches `x ≤ 0`.
pub fn fieller(
    rho: &DVector<f64>,
    c: &DMatrix<f64>,
    f: f64,
    (da, db): (f64, f64),
    k: f64,
) -> Option<(f64, f64)> {
    let (n, d) = (f - rho[0], rho[1] - rho[0]);
    let vn = c[(0, 0)];
    let vd = c[(0, 0)] + c[(1, 1)] - 2.0 * c[(0, 1)];
    let cnd = c[(0, 0)] - c[(0, 1)];
    let k2 = k * k;
    let a = d * d - k2 * vd;
    let b = -2.0 * (n * d - k2 * cnd);
    let cc = n * n - k2 * vn;
    if a <= 0.0 {
        return None;
    }
    let disc = b * b - 4.0 * a * cc;
    let root = disc.max(0.0).sqrt();
    let (r1, r2) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
    let (xa, xb) = (1.0 / da, 1.0 / db);
    let (x1, x2) = (xa + (xb - xa) * r1, xa + (xb - xa) * r2);
    if !(x1 > 0.0 && x2 > 0.0) {
        return None;
    }
    let (lo, hi) = (1.0 / x1.max(x2), 1.0 / x1.min(x2));
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// Warnings: a bracket not interpolated, a response ratio that does not
/// rise, noise between visits far above the within-plateau noise.
fn warn(r: &mut ThresholdResult) {
    let unit = r.sensor.unit();
    for c in &r.crossings {
        if !c.interpolated {
            r.warnings.push(Warning::new(
                WarningCode::ModelRange,
                format!(
                    "the {} lies between {:.4e} and {:.4e} {unit}, where the response ratio does not rise through 50 %: their middle is reported, with the rectangular u of their distance; add step sizes between them",
                    c.group.name(),
                    c.pair.0,
                    c.pair.1
                ),
            ));
        }
    }
    let ratio = r.noise.var_long / r.noise.var_short.max(f64::MIN_POSITIVE);
    if r.noise.var_short > 0.0 && ratio > 10.0 {
        r.warnings.push(Warning::new(
            WarningCode::NoiseInconsistent,
            format!(
                "plateau means scatter between visits {:.1} times more (in variance) than their samples within a plateau: drift, flicker or a table that does not return to the same input; u is from the visits",
                ratio
            ),
        ));
    }
}

/// Threshold and resolution as one [`crate::procedures::Procedure`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Threshold;

impl crate::procedures::Procedure for Threshold {
    const ID: crate::document::Procedure = crate::document::Procedure::Threshold;
    type Options = ThresholdOptions;
    type Input = Record;

    fn example() -> ThresholdOptions {
        ThresholdOptions::default()
    }

    fn validate(o: &ThresholdOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &ThresholdOptions,
    ) -> Result<Record> {
        input::read(rows)
    }

    fn reduce(
        rec: &Record,
        o: &ThresholdOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        calibrate(rec, o)?.document()
    }

    fn synthesis(
        rec: &Record,
        o: &ThresholdOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Record>>> {
        montecarlo::synthesis(rec, o).map(Some)
    }
}

impl ThresholdResult {
    /// The coefficients as estimates (the threshold, the resolution and
    /// K1 when measured; their u as in the document, uncorrelated).
    pub fn coefficients(&self) -> Result<Estimates> {
        let mut names = Vec::new();
        let (mut v, mut u, mut dof) = (Vec::new(), Vec::new(), f64::INFINITY);
        for c in &self.crossings {
            names.push(format!("{}_{}", c.group.name(), self.sensor.suffix()));
            v.push(c.value.0);
            u.push(c.value.1 * c.value.1);
            dof = dof.min(c.dof);
        }
        if self.scale.coef.is_some() {
            names.push("K1".into());
            v.push(self.scale.value);
            u.push(self.scale_u().powi(2));
        }
        Estimates::new(
            names,
            DVector::from_vec(v),
            DMatrix::from_diagonal(&DVector::from_vec(u)),
            dof,
        )
    }
}
