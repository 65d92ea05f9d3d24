//! The sensitivity model of the run means, its order rule and the
//! generalized least-squares fit.
//!
//! # Terms (per output column; `g` the vibration level in g rms, `B_j`
//! the field along axis j in mT, `u` the applied input)
//! - every kind: `bias` (the intercept, not reported: its u depends on
//!   the noise's arbitrary constant, [`super::noise`]) and, where `input`
//!   takes two levels or more, `scale_factor` (`u`);
//! - vibration: `vrc` (`g²`) when every vibrated run has one direction;
//!   with several directions θ in the input–pendulous plane, `vrc`
//!   (`g² cos²θ`), `vibropendulous` (`g² sin θ cos θ`) and
//!   `vrc_pendulous` (`g² sin²θ`), each only where a run excites it (IEEE
//!   Std 1293-2018: the rectification `K_ii a_i² + K_ip a_i a_p + K_pp
//!   a_p²` averaged over the vibration). Several frequencies: one set per
//!   frequency (`vrc_100hz`, …). The order rule may add `vib_linear`
//!   (`g`) and then `vib_cubic` (`g³`);
//! - magnetic: `magnetic_j` (`B_j`) for every axis the runs vary; the
//!   order rule may add `magnetic_j_quad` (`B_j²`) where the axis has
//!   three levels or more;
//! - shock: `shock_shift_p` (the indicator of the runs after the p-th
//!   shock): the change of the bias across that shock, against the runs
//!   just before it;
//! - with a scale factor, each reported term `t` gets `t_sf` (`u` times
//!   its column), reported as `10⁶ t_sf / scale_factor` (ppm per unit of
//!   the stimulus; ppm for a shock).
//!
//! # Fit and order rule
//! Generalized least squares with the covariance of the run means
//! ([`super::noise`]), whitened by its Cholesky factor onto the one
//! solver ([`crate::estimation::linear`], variance
//! [`Variance::AtLeast`]: the noise's u unless the runs scatter more).
//! The order: the base terms first, then each richer candidate in turn;
//! the first whose lack-of-fit test passes
//! (`P(χ²_{n−p} ≥ χ²) ≥` [`LACK_OF_FIT_ALPHA`]) is taken, as the thermal
//! degree rule does; when none passes the richest is taken with u scaled
//! by the residuals (warning `lack-of-fit`).

use nalgebra::{DMatrix, DVector};

use super::input::{Record, Run};
use super::Kind;
use crate::error::{Error, Result};
use crate::estimation::linear::{fit, Design, Fit, FitOptions, Variance, LACK_OF_FIT_ALPHA};

/// One term of the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    /// Its name (before an output column's suffix).
    pub name: String,
    /// Its column over the runs.
    pub column: Vec<f64>,
    /// Reported as a coefficient.
    pub reported: bool,
    /// A scale-factor interaction (reported in ppm).
    pub sf: bool,
    /// Per what the coefficient is (`g^2`, `mT`, empty for a shock).
    pub per: String,
}

impl Term {
    fn new(name: impl Into<String>, column: Vec<f64>, per: &str) -> Term {
        Term {
            name: name.into(),
            column,
            reported: true,
            sf: false,
            per: per.into(),
        }
    }

    fn nuisance(name: &str, column: Vec<f64>) -> Term {
        Term {
            reported: false,
            ..Term::new(name, column, "")
        }
    }
}

/// The base terms and the richer candidates of the order rule.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    /// Always fitted.
    pub base: Vec<Term>,
    /// Candidate `k` adds `extras[..k]`.
    pub extras: Vec<Term>,
}

fn distinct(v: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for x in v {
        if !out
            .iter()
            .any(|y| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-12))
        {
            out.push(x);
        }
    }
    out.sort_by(f64::total_cmp);
    out
}

/// A frequency in a term's name (`100hz`, `12.5hz`).
fn hz(f: f64) -> String {
    format!("{}hz", crate::error::short_f64((f * 1e3).round() / 1e3))
}

/// The model of a session (module docs); refused, naming the stimulus,
/// when it has a single level.
pub fn model(rec: &Record) -> Result<Model> {
    let runs = &rec.runs;
    let mut base = vec![Term::nuisance("bias", vec![1.0; runs.len()])];
    let mut extras = Vec::new();
    let stimulus = match rec.kind {
        Kind::Vibration => vibration(runs, &mut extras)?,
        Kind::Magnetic => magnetic(runs, rec.field_axes, &mut extras)?,
        Kind::Shock | Kind::Auto => shock(runs)?,
    };
    let inputs: Vec<f64> = runs.iter().map(|r| r.input.unwrap_or(0.0)).collect();
    let with_sf =
        runs.iter().all(|r| r.input.is_some()) && distinct(inputs.iter().copied()).len() >= 2;
    if with_sf {
        base.push(Term::nuisance("scale_factor", inputs.clone()));
    }
    let interactions: Vec<Term> = if with_sf {
        stimulus
            .iter()
            .map(|t| Term {
                name: format!("{}_sf", t.name),
                column: t.column.iter().zip(&inputs).map(|(a, b)| a * b).collect(),
                sf: true,
                ..t.clone()
            })
            .collect()
    } else {
        Vec::new()
    };
    if stimulus.is_empty() {
        return Err(Error::Unsupported(
            "no run excites a sensitivity: every stimulus is zero".into(),
        ));
    }
    base.extend(stimulus);
    base.extend(interactions);
    Ok(Model { base, extras })
}

/// True when the runs can separate every one of `terms`.
pub fn separable(terms: &[Term]) -> bool {
    terms_design(terms).is_ok_and(|d| {
        d.diagnose(None, crate::estimation::linear::DEFAULT_COND_LIMIT)
            .is_separable()
    })
}

/// The design matrix of `terms`: a row per run, a column per term.
pub fn design_matrix(terms: &[Term]) -> DMatrix<f64> {
    let n = terms.first().map_or(0, |t| t.column.len());
    DMatrix::from_fn(n, terms.len(), |i, j| terms[j].column[i])
}

fn terms_design(terms: &[Term]) -> Result<Design> {
    Design::new(
        terms.iter().map(|t| t.name.clone()).collect(),
        design_matrix(terms),
    )
}

/// The design and the run means whitened by the Cholesky factor `L` of
/// their covariance (`L⁻¹A`, `L⁻¹y`), with `L`; `None` when the
/// covariance is not positive definite.
fn whiten(
    terms: &[Term],
    y: &[f64],
    cov: &DMatrix<f64>,
) -> Option<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)> {
    let l = cov.clone().cholesky()?.l();
    let aw = l.solve_lower_triangular(&design_matrix(terms))?;
    let yw = l.solve_lower_triangular(&DVector::from_column_slice(y))?;
    Some((l, aw, yw))
}

/// Refuse, naming them, terms the runs cannot separate.
pub fn require_separable(terms: &[Term]) -> Result<()> {
    let d = terms_design(terms)?.diagnose(None, crate::estimation::linear::DEFAULT_COND_LIMIT);
    if d.is_separable() {
        return Ok(());
    }
    let names: Vec<String> = d.aliases.iter().map(|a| a.combination()).collect();
    Err(Error::Unsupported(format!(
        "these runs cannot separate {}: add runs at other levels or directions",
        names.join("; ")
    )))
}

fn vibration(runs: &[Run], extras: &mut Vec<Term>) -> Result<Vec<Term>> {
    let g: Vec<f64> = runs.iter().map(|r| r.stimulus.vib_g_rms).collect();
    let levels = distinct(g.iter().copied());
    if levels.len() < 2 {
        return Err(Error::Unsupported(format!(
            "a single stimulus level: vib_g = {} g rms in every run; the rectification needs runs at two levels or more (0 included)",
            levels.first().copied().unwrap_or(0.0)
        )));
    }
    let shaken: Vec<&Run> = runs.iter().filter(|r| r.stimulus.vib_g_rms > 0.0).collect();
    let freqs = distinct(shaken.iter().map(|r| r.stimulus.vib_freq_hz.unwrap_or(0.0)));
    let mut terms = Vec::new();
    for f in &freqs {
        let suffix = if freqs.len() > 1 {
            format!("_{}", hz(*f))
        } else {
            String::new()
        };
        let in_group = |r: &Run| {
            r.stimulus.vib_g_rms > 0.0
                && (r.stimulus.vib_freq_hz.unwrap_or(0.0) - f).abs() <= 1e-9 * f.abs().max(1e-12)
        };
        let angles = distinct(
            runs.iter()
                .filter(|r| in_group(r))
                .map(|r| r.stimulus.vib_angle_deg),
        );
        let col = |k: &dyn Fn(f64) -> f64| -> Vec<f64> {
            runs.iter()
                .map(|r| {
                    // A direction's share below 1e-12 is zero (cos 90° is
                    // 6e-17 in floating point, not a term).
                    let share = k(r.stimulus.vib_angle_deg.to_radians());
                    if in_group(r) && share.abs() >= 1e-12 {
                        let g = r.stimulus.vib_g_rms;
                        g * g * share
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        if angles.len() == 1 {
            terms.push(Term::new(format!("vrc{suffix}"), col(&|_| 1.0), "g^2"));
        } else {
            for (name, k) in [
                ("vrc", (&|t: f64| t.cos().powi(2)) as &dyn Fn(f64) -> f64),
                ("vibropendulous", &|t: f64| t.sin() * t.cos()),
                ("vrc_pendulous", &|t: f64| t.sin().powi(2)),
            ] {
                let c = col(k);
                if c.iter().any(|v| *v != 0.0) {
                    terms.push(Term::new(format!("{name}{suffix}"), c, "g^2"));
                }
            }
        }
        let power = |p: i32| -> Vec<f64> {
            runs.iter()
                .map(|r| {
                    if in_group(r) {
                        r.stimulus.vib_g_rms.powi(p)
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        extras.push(Term::new(format!("vib_linear{suffix}"), power(1), "g"));
        extras.push(Term::new(format!("vib_cubic{suffix}"), power(3), "g^3"));
    }
    // Candidates in order: every linear term, then every cubic one.
    extras.sort_by_key(|t| t.name.starts_with("vib_cubic"));
    Ok(terms)
}

fn magnetic(runs: &[Run], axes: [bool; 3], extras: &mut Vec<Term>) -> Result<Vec<Term>> {
    let xyz = ["x", "y", "z"];
    let mut terms = Vec::new();
    for j in (0..3).filter(|&j| axes[j]) {
        let b: Vec<f64> = runs.iter().map(|r| r.stimulus.field_mt[j]).collect();
        let levels = distinct(b.iter().copied());
        if levels.len() < 2 {
            continue;
        }
        if levels.len() >= 3 {
            extras.push(Term::new(
                format!("magnetic_{}_quad", xyz[j]),
                b.iter().map(|v| v * v).collect(),
                "mT^2",
            ));
        }
        terms.push(Term::new(format!("magnetic_{}", xyz[j]), b, "mT"));
    }
    if terms.is_empty() {
        return Err(Error::Unsupported(
            "a single stimulus level: the field is the same in every run on every axis given; the magnetic sensitivity needs runs at two field levels or more".into(),
        ));
    }
    Ok(terms)
}

fn shock(runs: &[Run]) -> Result<Vec<Term>> {
    let first = &runs[0];
    if first.stimulus.shock_g != 0.0 {
        return Err(Error::Unsupported(format!(
            "line {}: the first run '{}' has shock_g = {}: the run before the first shock (shock_g 0) is missing",
            first.line,
            incal_io::clip(&first.label),
            first.stimulus.shock_g
        )));
    }
    let mut phase = vec![0usize; runs.len()];
    for k in 1..runs.len() {
        let (a, b) = (runs[k - 1].stimulus.shock_g, runs[k].stimulus.shock_g);
        phase[k] = phase[k - 1] + usize::from(a != b);
        if a != b && b == 0.0 {
            return Err(Error::Unsupported(format!(
                "line {}: run '{}' has shock_g = 0 after a shock: shock_g is the peak of the last shock the unit took",
                runs[k].line,
                incal_io::clip(&runs[k].label)
            )));
        }
    }
    let phases = phase.last().copied().unwrap_or(0);
    if phases == 0 {
        return Err(Error::Unsupported(
            "a single stimulus level: shock_g is 0 in every run (no shock between runs); the shift needs runs before and after a shock".into(),
        ));
    }
    Ok((1..=phases)
        .map(|p| {
            Term::new(
                format!("shock_shift_{p}"),
                phase.iter().map(|&q| f64::from(u8::from(q >= p))).collect(),
                "",
            )
        })
        .collect())
}

/// One step of the order rule.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Trial {
    /// The extra terms of this candidate.
    pub extras: Vec<String>,
    /// `χ²` of the whitened residuals.
    pub chi2: f64,
    /// `n − p`.
    pub dof: usize,
    /// Lack-of-fit p-value.
    pub p_value: Option<f64>,
}

/// The fit of one output column.
#[derive(Debug, Clone)]
pub struct OutputFit {
    /// The terms fitted.
    pub terms: Vec<Term>,
    /// The fit (whitened).
    pub fit: Fit,
    /// The run means (reporting units).
    pub y: Vec<f64>,
    /// The fitted run means.
    pub fitted: Vec<f64>,
    /// The order rule's steps.
    pub trials: Vec<Trial>,
}

/// Generalized least squares of `terms` to `y` with covariance `cov`
/// (module docs).
pub fn gls(terms: &[Term], y: &[f64], cov: &DMatrix<f64>, dof: f64) -> Result<Fit> {
    let n = y.len();
    let (_, aw, yw) = whiten(terms, y, cov).ok_or_else(|| {
        Error::Unsupported("the run means' covariance is not positive definite".into())
    })?;
    let design = Design::new(terms.iter().map(|t| t.name.clone()).collect(), aw)?;
    fit(
        &design,
        &yw,
        &FitOptions {
            weights: Some(DVector::from_element(n, 1.0)),
            variance: Variance::AtLeast { dof },
            ..FitOptions::default()
        },
    )
}

/// The restricted log-likelihood's `−2ℓ` of the run means `y` under
/// covariance `cov` with the terms `terms` (Patterson & Thompson):
/// `ln det Σ + ln det(AᵀΣ⁻¹A) + rᵀΣ⁻¹r`, up to a constant; the same for
/// `Σ + c11ᵀ` whenever the terms hold the intercept. The evidence of the
/// run means for a noise model.
pub fn reml(terms: &[Term], y: &[f64], cov: &DMatrix<f64>) -> Option<f64> {
    let (l, aw, yw) = whiten(terms, y, cov)?;
    let ata = aw.transpose() * &aw;
    let det_a = ata.clone().cholesky()?.l().diagonal().map(|v| v.ln()).sum() * 2.0;
    let x = ata.cholesky()?.solve(&(aw.transpose() * &yw));
    let r = &yw - &aw * x;
    let det_s = l.diagonal().map(|v| v.ln()).sum() * 2.0;
    Some(det_s + det_a + r.norm_squared())
}

/// Fit one output column with the order rule (module docs).
pub fn fit_output(m: &Model, y: &[f64], cov: &DMatrix<f64>, dof: f64) -> Result<OutputFit> {
    let n = y.len();
    let mut trials = Vec::new();
    let mut chosen: Option<(Vec<Term>, Fit)> = None;
    for k in 0..=m.extras.len() {
        let mut terms = m.base.clone();
        terms.extend(m.extras[..k].iter().cloned());
        if k > 0 && terms.len() >= n {
            break;
        }
        let f = match gls(&terms, y, cov, dof) {
            Ok(f) => f,
            Err(e) if k == 0 => return Err(refusal(e)),
            // A richer candidate the runs cannot separate ends the rule.
            Err(_) => break,
        };
        trials.push(Trial {
            extras: m.extras[..k].iter().map(|t| t.name.clone()).collect(),
            chi2: f.weighted_rss,
            dof: f.dof,
            p_value: f.chi2_p_value,
        });
        let passes = f.dof == 0 || f.chi2_p_value.is_some_and(|p| p >= LACK_OF_FIT_ALPHA);
        chosen = Some((terms, f));
        if passes {
            break;
        }
    }
    let (terms, fit) = chosen.ok_or_else(|| Error::Unsupported("no model fitted".into()))?;
    let x = fit.estimates.values();
    let fitted = (0..n)
        .map(|i| {
            terms
                .iter()
                .enumerate()
                .map(|(j, t)| t.column[i] * x[j])
                .sum()
        })
        .collect();
    Ok(OutputFit {
        terms,
        fit,
        y: y.to_vec(),
        fitted,
        trials,
    })
}

/// A design the runs cannot separate, said as a plan problem.
fn refusal(e: Error) -> Error {
    match e {
        Error::Unsupported(m) => Error::Unsupported(m),
        other => Error::Unsupported(format!(
            "the runs cannot separate the sensitivities: {other}; add runs at other levels or directions"
        )),
    }
}
