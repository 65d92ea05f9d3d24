//! Repeatability turn-on to turn-on and day to day: the variance
//! components of one coefficient over runs (each a turn-on, labelled by
//! its day), by a nested random-effects analysis of variance with each
//! run's own u as its within-run variance (docs/src/repeatability.md;
//! IEEE Std 952-1997 and IEEE Std 1431-2004 bias and scale-factor
//! repeatability, GJB 2426A-2004 and GJB 1037A-2004 turn-on to turn-on
//! repeatability).
//!
//! # Model
//! Run `t` of day `d` gives `x_dt` with its own `u_dt`:
//! `x_dt = μ + a_d + b_dt + e_dt`, `Var a = σ²_day`, `Var b = σ²_on`,
//! `Var e = u²_dt` (the run's own, known with `ν_dt` degrees of freedom).
//!
//! # Estimators
//! Runs whose u are within a factor of 3 of each other: the analysis of
//! variance (method of moments, unbalanced days by `T₀`):
//! `MS_on = Σ (x_dt − x̄_d)² / (N − D)`, `MS_day = Σ T_d (x̄_d − x̄)² /
//! (D − 1)`, `T₀ = (N − Σ T_d²/N)/(D − 1)`, `ū² = mean u²`;
//! `σ²_on = MS_on − ū²`, `σ²_day = (MS_day − MS_on)/T₀`. Runs whose u
//! differ more are weighted: Paule–Mandel at each level (within days
//! `Σ (x_dt − x̃_d)²/(u²_dt + σ²_on) = N − D` with `x̃_d` the weighted day
//! means; then over the day means with their variances), which equals the
//! analysis of variance for equal u and balanced days.
//!
//! Each component as a standard deviation with `u(s) = s/√(2ν)` and ν by
//! Satterthwaite (JCGM 100 G.4): `ν_on = σ⁴_on / (MS²_on/(N − D) +
//! ū⁴/ν_u)`, `ν_day = (T₀σ²_day)² / (MS²_day/(D − 1) + MS²_on/(N − D))`;
//! weighted, `ν_on = σ⁴_on Σ 1/(u² + σ²_on)² (N − D)/N` (the estimate's
//! information; equal u give the line above).
//! A component estimated at or below zero is reported as 0 and flagged.
//! Beside them the standards' simple formula over all runs,
//! `B_r = √(Σ (x − x̄)²/(N − 1))`, its degrees of freedom those of the
//! quadratic form under the fitted components ([`simple_dof`]: `N − 1`
//! for independent runs, fewer where runs share a day).

pub mod document;
pub mod input;
mod montecarlo;
pub mod plan;
pub mod sim;

use crate::error::{Error, Result};

/// One run: a turn-on's value of the coefficient and its own u.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Where it came from (a file, a record, a CSV line), for messages.
    pub source: String,
    /// Its day (`None` when the runs carry no day).
    pub day: Option<String>,
    /// The coefficient's value.
    pub value: f64,
    /// Its standard uncertainty (the within-run part).
    pub u: f64,
    /// The degrees of freedom of `u` (∞ when not given).
    pub dof: f64,
}

/// Options of the repeatability analysis. In the document: every key.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RepeatabilityOptions {
    /// The coefficient analysed (its name in the documents; a label for
    /// a table of runs). Default `value`.
    #[serde(default = "value")]
    pub coefficient: String,
    /// Its unit (default `output`; taken from the documents when they
    /// give one).
    #[serde(default = "output")]
    pub unit: String,
}

fn value() -> String {
    "value".into()
}
fn output() -> String {
    "output".into()
}

impl Default for RepeatabilityOptions {
    fn default() -> Self {
        Self {
            coefficient: value(),
            unit: output(),
        }
    }
}

impl RepeatabilityOptions {
    /// Every check of the options.
    pub fn validate(&self) -> Result<()> {
        if self.coefficient.trim().is_empty() {
            return crate::options::invalid("coefficient", "an empty coefficient name");
        }
        if self.unit.trim().is_empty() {
            return crate::options::invalid("unit", "an empty unit");
        }
        Ok(())
    }
}

/// How the components were estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The analysis of variance (u within a factor of 3).
    Anova,
    /// Paule–Mandel weighting at each level (u differ more).
    Weighted,
}

/// One variance component as a standard deviation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Component {
    /// The variance estimate (may be negative before truncation).
    pub variance: f64,
    /// The standard deviation `max(0, variance)^½`.
    pub sd: f64,
    /// `u(sd)`.
    pub u: f64,
    /// Satterthwaite degrees of freedom.
    pub dof: f64,
}

impl Component {
    /// From a variance estimate, its degrees of freedom and the standard
    /// uncertainty of the variance estimate (`u_var`): a variance at or
    /// below zero is reported as 0 with `u = √u_var`, the size at which
    /// the component would show.
    fn of(variance: f64, dof: f64, u_var: f64) -> Component {
        let dof = if dof.is_nan() {
            1.0
        } else if dof.is_finite() {
            dof.max(1.0)
        } else {
            f64::INFINITY
        };
        if variance <= 0.0 {
            let u = if u_var.is_finite() {
                u_var.max(0.0).sqrt()
            } else {
                0.0
            };
            return Component {
                variance,
                sd: 0.0,
                u,
                dof,
            };
        }
        let sd = variance.sqrt();
        Component {
            variance,
            sd,
            u: sd / (2.0 * dof).sqrt(),
            dof,
        }
    }
}

/// The analysis of one coefficient's runs.
#[derive(Debug, Clone)]
pub struct RepeatResult {
    /// The runs.
    pub runs: Vec<Run>,
    /// The days in order of first appearance, with their runs' indices.
    pub days: Vec<(String, Vec<usize>)>,
    /// The grand mean and its u.
    pub mean: (f64, f64),
    /// Within-run: `√ū²` with the within-run degrees of freedom.
    pub within: Component,
    /// Turn-on to turn-on (`None` when every day has one run).
    pub turn_on: Option<Component>,
    /// Day to day (`None` when the runs carry no days).
    pub day: Option<Component>,
    /// The standards' simple formula over all runs.
    pub simple: Component,
    /// The estimator used.
    pub method: Method,
    /// The largest ratio of two runs' u.
    pub u_ratio: f64,
    /// Mean squares (turn-on, day) and `T₀`, for the document.
    pub anova: (f64, Option<f64>, f64),
    /// The options.
    pub options: RepeatabilityOptions,
}

/// Group runs by day (refused: some runs with a day and some without).
fn group(runs: &[Run]) -> Result<Vec<(String, Vec<usize>)>> {
    let with = runs.iter().filter(|r| r.day.is_some()).count();
    if with != 0 && with != runs.len() {
        let r = runs.iter().find(|r| r.day.is_none()).unwrap_or(&runs[0]);
        return Err(Error::Unsupported(format!(
            "{}: no day, while other runs have one: label every run's day or none",
            r.source
        )));
    }
    let mut days: Vec<(String, Vec<usize>)> = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        let d = r.day.clone().unwrap_or_default();
        match days.iter_mut().find(|(x, _)| *x == d) {
            Some((_, v)) => v.push(k),
            None => days.push((d, vec![k])),
        }
    }
    Ok(days)
}

/// The analysis (module docs). Refused: fewer than 3 runs, fewer than 3
/// days when the runs carry days, a u that is not positive.
pub fn analyse(runs: &[Run], o: &RepeatabilityOptions) -> Result<RepeatResult> {
    o.validate()?;
    if runs.len() < 3 {
        return Err(Error::Unsupported(format!(
            "turn-on level: {} runs; at least 3 turn-ons are needed",
            runs.len()
        )));
    }
    if let Some(r) = runs
        .iter()
        .find(|r| r.u.is_nan() || r.u <= 0.0 || r.u.is_infinite())
    {
        return Err(Error::Unsupported(format!(
            "{}: u = {} is not a positive number: the within-run variance is each run's own u",
            r.source, r.u
        )));
    }
    let days = group(runs)?;
    let dated = runs[0].day.is_some();
    if dated && days.len() < 3 {
        return Err(Error::Unsupported(format!(
            "day level: {} days ({}); at least 3 days are needed for the day-to-day component",
            days.len(),
            days.iter()
                .map(|d| d.0.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let n = runs.len() as f64;
    let (umin, umax) = runs
        .iter()
        .fold((f64::MAX, 0f64), |a, r| (a.0.min(r.u), a.1.max(r.u)));
    let u_ratio = umax / umin;
    let u2: Vec<f64> = runs.iter().map(|r| r.u * r.u).collect();
    let u2_mean = u2.iter().sum::<f64>() / n;
    // Satterthwaite over the runs' u (∞ when every u is exact).
    let nu_u = u2.iter().sum::<f64>().powi(2)
        / runs
            .iter()
            .map(|r| (r.u * r.u).powi(2) / r.dof)
            .sum::<f64>();
    let within = Component::of(u2_mean, nu_u, 0.0);
    let method = if u_ratio > 3.0 {
        Method::Weighted
    } else {
        Method::Anova
    };
    let x: Vec<f64> = runs.iter().map(|r| r.value).collect();
    let mean_all = x.iter().sum::<f64>() / n;
    let ss_all: f64 = x.iter().map(|v| (v - mean_all).powi(2)).sum();
    let (turn_on, day, anova, mean) = match method {
        Method::Anova => {
            // E[MS_on] = σ²_on + Σ (1 − 1/T_d) u²_dt / (N − D): a day's
            // single run adds nothing to MS_on.
            let df_on = n - days.len() as f64;
            let u2_on = if df_on > 0.0 {
                days.iter()
                    .map(|(_, ix)| {
                        let f = 1.0 - 1.0 / ix.len() as f64;
                        ix.iter().map(|&k| f * u2[k]).sum::<f64>()
                    })
                    .sum::<f64>()
                    / df_on
            } else {
                u2_mean
            };
            anova(&x, &days, (u2_on, u2_mean), nu_u, dated)
        }
        Method::Weighted => weighted(&x, &u2, &days, u2_mean, dated),
    };
    // The simple formula's ν from the fitted components: the runs of a
    // day share its effect, so they are not N independent values.
    let on2 = turn_on.map_or(0.0, |c| c.sd * c.sd);
    let day2 = day.map_or(0.0, |c| c.sd * c.sd);
    let groups: Vec<Vec<f64>> = days
        .iter()
        .map(|(_, ix)| ix.iter().map(|&k| on2 + u2[k]).collect())
        .collect();
    let simple = Component::of(ss_all / (n - 1.0), simple_dof(&groups, day2), 0.0);
    Ok(RepeatResult {
        runs: runs.to_vec(),
        days,
        mean,
        within,
        turn_on,
        day,
        simple,
        method,
        u_ratio,
        anova,
        options: o.clone(),
    })
}

/// The degrees of freedom of the simple formula's `s² = Σ (x − x̄)²/(N −
/// 1)` when the runs of a day share a day effect of variance `day_var`
/// and run `i` has its own variance `D_i` (`groups`: each day's `D_i`,
/// the turn-on component plus the run's u²): `s²` is the quadratic form
/// `xᵀAx/(N − 1)`, `A = I − 11ᵀ/N`, of normal runs with covariance
/// `Σ = diag(D) + day_var·B` (`B` ones within a day), so `ν = 2E²/Var =
/// tr(AΣ)²/tr((AΣ)²)` (Satterthwaite, JCGM 100 G.4, on the quadratic
/// form's exact mean and variance). Computed in O(N) from
/// `tr(AΣ) = tr Σ − 1ᵀΣ1/N` and
/// `tr((AΣ)²) = tr(Σ²) − 2|Σ1|²/N + (1ᵀΣ1)²/N²`. Independent runs of
/// equal variance give `N − 1`.
pub fn simple_dof(groups: &[Vec<f64>], day_var: f64) -> f64 {
    let n: f64 = groups.iter().map(|g| g.len() as f64).sum();
    let (mut tr, mut tr2, mut one, mut norm2) = (0.0, 0.0, 0.0, 0.0);
    for g in groups {
        let t = g.len() as f64;
        for &d in g {
            tr += d + day_var;
            tr2 += d * d + 2.0 * day_var * d;
            let s = d + day_var * t;
            norm2 += s * s;
            one += d;
        }
        tr2 += day_var * day_var * t * t;
        one += day_var * t * t;
    }
    let a = tr - one / n;
    let b = tr2 - 2.0 * norm2 / n + one * one / (n * n);
    if a > 0.0 && b > 0.0 {
        a * a / b
    } else {
        n - 1.0
    }
}

type Parts = (
    Option<Component>,
    Option<Component>,
    (f64, Option<f64>, f64),
    (f64, f64),
);

/// The analysis of variance (module docs).
fn anova(
    x: &[f64],
    days: &[(String, Vec<usize>)],
    (u2, u2_mean): (f64, f64),
    nu_u: f64,
    dated: bool,
) -> Parts {
    let n = x.len() as f64;
    let d = days.len() as f64;
    let means: Vec<f64> = days
        .iter()
        .map(|(_, ix)| ix.iter().map(|&k| x[k]).sum::<f64>() / ix.len() as f64)
        .collect();
    let grand = x.iter().sum::<f64>() / n;
    let ss_on: f64 = days
        .iter()
        .zip(&means)
        .map(|((_, ix), m)| ix.iter().map(|&k| (x[k] - m).powi(2)).sum::<f64>())
        .sum();
    let ss_day: f64 = days
        .iter()
        .zip(&means)
        .map(|((_, ix), m)| ix.len() as f64 * (m - grand).powi(2))
        .sum();
    let df_on = n - d;
    let ms_on = if df_on > 0.0 { ss_on / df_on } else { f64::NAN };
    let t0 = if d > 1.0 {
        (n - days
            .iter()
            .map(|(_, ix)| (ix.len() as f64).powi(2))
            .sum::<f64>()
            / n)
            / (d - 1.0)
    } else {
        n
    };
    let turn_on = (df_on > 0.0).then(|| {
        let v = ms_on - u2;
        let var_v = 2.0 * (ms_on * ms_on / df_on + u2 * u2 / nu_u);
        Component::of(v, 2.0 * v * v / var_v, var_v.sqrt())
    });
    let (day, ms_day) = if dated {
        let ms_day = ss_day / (d - 1.0);
        // With one run a day the turn-on and day components are one: the
        // day component holds both (against the within-run variance).
        let (inner, inner_var) = if df_on > 0.0 {
            (ms_on, ms_on * ms_on / df_on)
        } else {
            (u2_mean, u2_mean * u2_mean / nu_u)
        };
        let v = (ms_day - inner) / t0;
        let denom = ms_day * ms_day / (d - 1.0) + inner_var;
        let nu = (t0 * v).powi(2) / denom;
        (
            Some(Component::of(v, nu, (2.0 * denom).sqrt() / t0)),
            Some(ms_day),
        )
    } else {
        (None, None)
    };
    // The mean: of the day means (each day once), u from their spread;
    // without days, of the runs.
    let mean = if dated {
        let m = means.iter().sum::<f64>() / d;
        let u = (means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (d - 1.0) / d).sqrt();
        (m, u)
    } else {
        (grand, (ms_on / n).sqrt())
    };
    (turn_on, day, (ms_on, ms_day, t0), mean)
}

/// Paule–Mandel: the `τ² ≥ 0` with `Σ (x − x̃)²/(v + τ²) = dof` (`x̃` the
/// weighted mean with weights `1/(v + τ²)`, of each group), by bisection
/// on the monotone left side; 0 when it is below `dof` at `τ² = 0`.
fn paule_mandel(groups: &[Vec<(f64, f64)>], dof: f64) -> f64 {
    let stat = |t2: f64| -> f64 {
        groups
            .iter()
            .map(|g| {
                let w: Vec<f64> = g.iter().map(|(_, v)| 1.0 / (v + t2)).collect();
                let sw: f64 = w.iter().sum();
                let m = g.iter().zip(&w).map(|((x, _), w)| x * w).sum::<f64>() / sw;
                g.iter()
                    .zip(&w)
                    .map(|((x, _), w)| w * (x - m).powi(2))
                    .sum::<f64>()
            })
            .sum()
    };
    if stat(0.0) <= dof {
        return 0.0;
    }
    let scale = groups
        .iter()
        .flatten()
        .map(|(x, v)| x * x + v)
        .sum::<f64>()
        .max(f64::MIN_POSITIVE);
    let (mut lo, mut hi) = (0.0, scale);
    while stat(hi) > dof && hi < 1e300 {
        hi *= 4.0;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stat(mid) > dof {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Paule–Mandel at each level (module docs); the degrees of freedom as
/// for the analysis of variance with the weighted mean squares.
fn weighted(
    x: &[f64],
    u2: &[f64],
    days: &[(String, Vec<usize>)],
    u2_mean: f64,
    dated: bool,
) -> Parts {
    let n = x.len() as f64;
    let d = days.len() as f64;
    let groups: Vec<Vec<(f64, f64)>> = days
        .iter()
        .map(|(_, ix)| ix.iter().map(|&k| (x[k], u2[k])).collect())
        .collect();
    let df_on = n - d;
    let s2_on = if df_on > 0.0 {
        paule_mandel(&groups, df_on)
    } else {
        0.0
    };
    let day_means: Vec<(f64, f64)> = groups
        .iter()
        .map(|g| {
            let w: Vec<f64> = g.iter().map(|(_, v)| 1.0 / (v + s2_on)).collect();
            let sw: f64 = w.iter().sum();
            (
                g.iter().zip(&w).map(|((x, _), w)| x * w).sum::<f64>() / sw,
                1.0 / sw,
            )
        })
        .collect();
    // ν of the weighted estimate from its information,
    // `2/Var(σ̂²) = Σ 1/(u² + σ²)²`, times (N − D)/N for the day means
    // fitted (equal u: the analysis of variance's ν).
    let ms_on = s2_on + u2_mean;
    let turn_on = (df_on > 0.0).then(|| {
        let info: f64 = u2.iter().map(|v| (v + s2_on).powi(-2)).sum();
        let nu = s2_on * s2_on * info * df_on / n;
        Component::of(s2_on, nu, (2.0 * n / (info * df_on)).sqrt())
    });
    let all = vec![day_means.clone()];
    let (day, ms_day, grand) = if dated {
        let s2_day = paule_mandel(&all, d - 1.0);
        let v_mean = day_means.iter().map(|m| m.1).sum::<f64>() / d;
        let ms_day = s2_day + v_mean;
        // The day means' own variances are known as well as the u's and
        // the turn-on component behind them (N − D degrees of freedom).
        let inner = if df_on > 0.0 {
            v_mean * v_mean / df_on
        } else {
            0.0
        };
        let denom = ms_day * ms_day / (d - 1.0) + inner;
        let nu = s2_day * s2_day / denom;
        let w: Vec<f64> = day_means.iter().map(|m| 1.0 / (m.1 + s2_day)).collect();
        let sw: f64 = w.iter().sum();
        let g = day_means.iter().zip(&w).map(|(m, w)| m.0 * w).sum::<f64>() / sw;
        (
            Some(Component::of(s2_day, nu, (2.0 * denom).sqrt())),
            Some(ms_day),
            (g, sw.recip().sqrt()),
        )
    } else {
        let m = day_means[0];
        (None, None, (m.0, m.1.sqrt()))
    };
    (turn_on, day, (ms_on, ms_day, 1.0), grand)
}

/// Repeatability as one [`crate::procedures::Procedure`]: a table of runs
/// (`value`, `u`, optional `day` and `dof`) into the document; result
/// documents and the records store are read into the same runs by
/// [`input::runs_from_documents`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Repeatability;

impl crate::procedures::Procedure for Repeatability {
    const ID: crate::document::Procedure = crate::document::Procedure::Repeatability;
    type Options = RepeatabilityOptions;
    type Input = Vec<Run>;

    fn example() -> RepeatabilityOptions {
        RepeatabilityOptions::default()
    }

    fn validate(o: &RepeatabilityOptions) -> Result<()> {
        o.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        _: &RepeatabilityOptions,
    ) -> Result<Vec<Run>> {
        input::read(rows)
    }

    fn reduce(
        runs: &Vec<Run>,
        o: &RepeatabilityOptions,
        _: &dyn crate::procedures::Progress,
    ) -> Result<crate::document::ResultDocument> {
        analyse(runs, o)?.document()
    }

    fn synthesis(
        runs: &Vec<Run>,
        o: &RepeatabilityOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<Run>>>> {
        montecarlo::synthesis(runs, o).map(Some)
    }
}
