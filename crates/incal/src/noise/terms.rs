//! The IEEE Std 952-1997 Annex C noise terms from the Allan variance, and
//! bias stability as GJB 2426A / IEEE Std 1431 define it.
//!
//! Allan variance model (IEEE Std 952 eq. C.15 ff., rate unit `u`, τ in s):
//! `σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π) B² + K²τ/3 + R²τ²/2`
//! with Q quantization (u·s), N angle random walk (u·√s), B bias
//! instability (u), K rate random walk (u/√s), R rate ramp (u/s).

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::{fit, Design, Estimates, FitOptions, Variance};
use crate::warning::{Warning, WarningCode};

use super::DevSeries;

/// `2 ln 2 / π`: the flicker (bias-instability) level of the Allan
/// variance, IEEE Std 952 eq. C.20 (σ = 0.664 B at the flat floor).
pub const FLICKER: f64 = 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI;

/// The five terms, in the order of the fit.
pub const TERMS: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// Regressor of term `j` at τ (the factor multiplying its square).
pub fn regressor(j: usize, tau: f64) -> f64 {
    match j {
        0 => 3.0 / (tau * tau),
        1 => 1.0 / tau,
        2 => FLICKER,
        3 => tau / 3.0,
        _ => tau * tau / 2.0,
    }
}

/// One-sided PSD (u²/Hz) of term `j` of amplitude `a` at `f_hz` > 0, with
/// the sample period `tau0_s` for quantization: IEEE Std 952-1997 Annex C
/// gives the two-sided `S(f)` of each term (`(2πf)² Q² τ0`, `N²`,
/// `B²/(2πf)`, `(K/2π)²/f²`, `R²/(2πf)³`); the one-sided `G = 2S`, which
/// the Allan variance model [`regressor`] matches (`σ²_A = G/(2τ)` for
/// white rate noise, `2 ln 2 · B²/π` for flicker).
pub fn term_psd(j: usize, a: f64, f_hz: f64, tau0_s: f64) -> f64 {
    let w = std::f64::consts::TAU * f_hz;
    2.0 * a
        * a
        * match j {
            0 => w * w * tau0_s,
            1 => 1.0,
            2 => 1.0 / w,
            3 => 1.0 / (w * w),
            _ => 1.0 / (w * w * w),
        }
}

/// One identified term: amplitude and its standard uncertainty, in the
/// rate unit's base (Q in u·s, N in u·√s, B in u, K in u/√s, R in u/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Term {
    /// Amplitude (Q, N, B, K or R).
    pub value: f64,
    /// Standard uncertainty of the amplitude.
    pub u: f64,
    /// Degrees of freedom of u (∞ when the EDF weights held).
    pub dof: f64,
}

/// The weighted fit of the five terms.
#[derive(Debug, Clone, PartialEq)]
pub struct TermFit {
    /// Each term when identified (`None` = not identified), in [`TERMS`] order.
    pub terms: [Option<Term>; 5],
    /// The fitted squared amplitudes of the kept terms (θ = amplitude²)
    /// with covariance.
    pub squares: Option<Estimates>,
    /// Warnings (terms not identified, and why).
    pub warnings: Vec<Warning>,
    /// Residual χ² of the final fit and its degrees of freedom.
    pub chi2: Option<(f64, usize)>,
}

impl TermFit {
    /// The model Allan deviation at τ from the identified terms.
    pub fn model(&self, tau: f64) -> f64 {
        let mut v = 0.0;
        for (j, t) in self.terms.iter().enumerate() {
            if let Some(t) = t {
                v += t.value * t.value * regressor(j, tau);
            }
        }
        v.sqrt()
    }
}

/// Correlation of the OADEV variance estimates one octave apart, by the
/// noise exponent α (measured over 300 simulated records of each pure noise
/// type, 2^15 points, octave τ: white FM 0.53, flicker FM 0.69, random-walk
/// FM 0.89; white and flicker PM taken as white FM).
fn octave_correlation(alpha: Option<i32>) -> f64 {
    match alpha {
        Some(a) if a <= -2 => 0.89,
        Some(-1) => 0.69,
        _ => 0.53,
    }
}

/// Penalty per term of the model-selection criterion `χ² + PENALTY·p`
/// ([`fit_terms`]): a term joins the model when it lowers the
/// generalized χ² by more than this.
///
/// Chosen by measurement, not from the χ² table: the χ² rests on a
/// modelled covariance of the σ̂² (EDF and a Markov correlation), and with
/// the table's 3.84 an absent term was reported in up to 15 % of simulated
/// records. With 10 (and the ramp at [`RAMP_FACTOR`] times it), over 200
/// seeded records of each of five mixes (`tests/noise_roundtrip.rs`, 2¹⁶–2¹⁸
/// samples) an absent term is reported in at most 1.5 % of records and a
/// term that dominates the top decade of τ is found in at least 96.5 %.
pub const PENALTY: f64 = 10.0;

/// The rate ramp R counts as this many terms in the criterion: it shows
/// only at the top one or two τ, where σ̂² rests on 3–6 degrees of freedom
/// with a skewed distribution, and a rate random walk's realization looks
/// like a ramp there (at 1× a random walk was read as a ramp, K missed and
/// R invented, in 10 % of records).
pub const RAMP_FACTOR: f64 = 3.0;

/// Two candidate models whose criteria differ by less than this are
/// reported as not separated (an evidence ratio `exp(Δ/2)` below e).
pub const NOT_SEPARATED: f64 = 2.0;

/// A fit of one set of terms: the estimates of their squares, the
/// generalized χ² and its dof.
struct Active {
    est: Estimates,
    chi2: f64,
    dof: usize,
    active: Vec<usize>,
}

impl Active {
    /// Every term of the set distinguishable from zero: its amplitude's
    /// U95 below the amplitude (`k·u(θ)/(2√θ) < √θ`, θ the fitted
    /// square, k the coverage factor at the fit's dof). A set with a term
    /// the record cannot tell from zero is not a model the document may
    /// report: its terms would be invented.
    fn distinguishable(&self) -> bool {
        let k = crate::estimation::coverage_factor(self.est.dof(), 0.95);
        (0..self.active.len()).all(|i| {
            let th = self.est.values()[i];
            th > 0.0 && k * self.est.u_at(i) < 2.0 * th
        })
    }

    /// `χ² + PENALTY·(terms)`, the ramp counting [`RAMP_FACTOR`] terms.
    fn score(&self) -> f64 {
        let weight: f64 = self
            .active
            .iter()
            .map(|&j| if j == 4 { RAMP_FACTOR } else { 1.0 })
            .sum();
        self.chi2 + PENALTY * weight
    }
}

/// The noise exponent α of S_y each term is (Q white PM, N white FM, B
/// flicker FM, K random-walk FM; the ramp, not a power law, taken as
/// random-walk FM).
const TERM_ALPHA: [i32; 5] = [2, 0, -1, -2, -2];

/// One observation of the fit: τ, σ̂, the EDF and α identified from the
/// data there, and the EDF each term's noise would give ([`TERM_ALPHA`]).
struct Obs {
    tau: f64,
    sigma: f64,
    edf: f64,
    alpha: Option<i32>,
    term_edf: [Option<f64>; 5],
}

/// The Markov correlation in log₂ τ of the observations' σ̂², from the
/// noise at each (`ρ_ij = Π_k ρ_k^{log₂(τ_{k+1}/τ_k)}`).
fn markov(obs: &[Obs], alpha: &[Option<i32>]) -> DMatrix<f64> {
    let n = obs.len();
    let mut corr = DMatrix::<f64>::identity(n, n);
    for i in 0..n {
        let mut r = 1.0;
        for j in i + 1..n {
            let rho = (octave_correlation(alpha[j - 1]) * octave_correlation(alpha[j])).sqrt();
            r *= rho.powf((obs[j].tau / obs[j - 1].tau).log2());
            corr[(i, j)] = r;
            corr[(j, i)] = r;
        }
    }
    corr
}

/// Fit the squares of the terms `active` (module docs of [`fit_terms`]);
/// `None` when the set has as many terms as observations, when a fitted
/// square comes out negative (the set is then not a non-negative model:
/// its subsets are fitted on their own), or when χ² is not finite.
fn fit_set(obs: &[Obs], active: Vec<usize>) -> Result<Option<Active>> {
    let nobs = obs.len();
    if active.is_empty() || active.len() >= nobs {
        return Ok(None);
    }
    let names: Vec<String> = active.iter().map(|&j| format!("{}2", TERMS[j])).collect();
    // Columns scaled to a largest entry of 1: over decades of τ the
    // regressors span many orders of magnitude (τ² against 1/τ²), which
    // would read as a zero column. θ_j = θ'_j / c_j afterwards.
    let raw = DMatrix::from_fn(nobs, active.len(), |i, k| regressor(active[k], obs[i].tau));
    let c: Vec<f64> = (0..active.len())
        .map(|k| raw.column(k).amax().max(f64::MIN_POSITIVE))
        .collect();
    let a = DMatrix::from_fn(nobs, active.len(), |i, k| raw[(i, k)] / c[k]);
    let y = DVector::from_iterator(nobs, obs.iter().map(|o| o.sigma * o.sigma));
    let mut pred: Vec<f64> = obs.iter().map(|o| o.sigma * o.sigma).collect();
    // The first pass weighs each σ̂² by the EDF of the noise identified
    // there; later ones by the noise the model says is there: on a few
    // tens of points the identification can call white FM flicker PM,
    // whose EDF is ten times larger, and one such point would carry the
    // fit (and invent a term to pass through it).
    let mut edf: Vec<f64> = obs.iter().map(|o| o.edf).collect();
    let mut alpha: Vec<Option<i32>> = obs.iter().map(|o| o.alpha).collect();
    let mut last = None;
    for _ in 0..6 {
        let w = DVector::from_iterator(nobs, edf.iter().zip(&pred).map(|(e, p)| e / (2.0 * p * p)));
        let design = Design::new(names.clone(), a.clone())?;
        let f = fit(
            &design,
            &y,
            &FitOptions {
                weights: Some(w.clone()),
                variance: Variance::Known { dof: f64::INFINITY },
                ..FitOptions::default()
            },
        )?;
        let m = &a * f.estimates.values();
        for (k, p) in pred.iter_mut().enumerate() {
            // Keep the weights of a poor early model sane.
            let s2 = obs[k].sigma * obs[k].sigma;
            *p = m[k].clamp(s2 / 4.0, s2 * 4.0);
        }
        // Each term's share of the model at each τ: the EDF of the mix
        // (`1/ν = Σ f_j²/ν_j`, the terms' estimates independent) and the
        // noise of the largest share.
        for (i, o) in obs.iter().enumerate() {
            let parts: Vec<(usize, f64)> = active
                .iter()
                .enumerate()
                .map(|(k, &j)| (j, (f.estimates.values()[k] * a[(i, k)]).max(0.0)))
                .collect();
            let total: f64 = parts.iter().map(|p| p.1).sum();
            if total.is_nan() || total <= 0.0 {
                continue;
            }
            let mut inv = 0.0;
            for &(j, v) in &parts {
                let share = v / total;
                inv += share * share / o.term_edf[j].unwrap_or(o.edf);
            }
            if inv > 0.0 {
                edf[i] = 1.0 / inv;
            }
            alpha[i] = parts
                .iter()
                .max_by(|p, q| p.1.total_cmp(&q.1))
                .map(|p| TERM_ALPHA[p.0]);
        }
        last = Some((f, w));
    }
    // The loop always runs; an error rather than a panic keeps input
    // from ever aborting the process.
    let (f, w) = last.ok_or_else(|| {
        crate::error::Error::Unsupported("noise-term fit: no iteration ran".into())
    })?;
    if f.estimates.values().iter().any(|&v| v < 0.0) {
        return Ok(None);
    }
    // Sandwich covariance of the weighted estimator under the
    // correlated covariance V of the σ̂²: C = B V Bᵀ, B = (AᵀWA)⁻¹AᵀW.
    let sd: Vec<f64> = edf
        .iter()
        .zip(&pred)
        .map(|(e, p)| p * (2.0 / e).sqrt())
        .collect();
    let corr = markov(obs, &alpha);
    let v = DMatrix::from_fn(nobs, nobs, |i, j| corr[(i, j)] * sd[i] * sd[j]);
    let bmat = f.estimates.covariance() * a.transpose() * DMatrix::from_diagonal(&w);
    let mut cov = &bmat * &v * bmat.transpose();
    // Generalized χ² of the residuals against V.
    let r = &y - &a * f.estimates.values();
    let dofr = nobs - active.len();
    let chi2 = v
        .clone()
        .cholesky()
        .map(|c| r.dot(&c.solve(&r)))
        .unwrap_or(f64::NAN);
    if !chi2.is_finite() {
        return Ok(None);
    }
    // Lack of fit: u grows by the Birge ratio √(χ²/ν) with ν = n − p
    // degrees of freedom whenever χ² exceeds its expectation ν. (Only at
    // the 5 % level, as the estimation core's lack-of-fit rule, B's
    // intervals covered 87–89 % of simulated truths: the modelled
    // covariance of the σ̂² is too small where flicker dominates.)
    let mut dof = f64::INFINITY;
    let birge = chi2 / dofr as f64;
    if birge > 1.0 {
        cov *= birge;
        dof = dofr as f64;
    }
    let p = active.len();
    let vals = DVector::from_fn(p, |k, _| f.estimates.values()[k] / c[k]);
    let cov = DMatrix::from_fn(p, p, |j, k| cov[(j, k)] / (c[j] * c[k]));
    let est = Estimates::new(names, vals, cov, dof)?;
    Ok(Some(Active {
        est,
        chi2,
        dof: dofr,
        active,
    }))
}

/// The terms of `set`, by name, joined with "and" (`B and K`).
fn names(set: &[usize]) -> String {
    let v: Vec<&str> = set.iter().map(|&j| TERMS[j]).collect();
    match v.len() {
        0 => "none".into(),
        1 => v[0].into(),
        n => format!("{} and {}", v[..n - 1].join(", "), v[n - 1]),
    }
}

/// Fit the IEEE 952 terms to an OADEV series and choose which terms the
/// record supports.
///
/// Observations are σ̂²(τ_i) at τ at least 1.9× apart (about one per
/// octave), τ below 4τ0 (where sampling distorts every term) left out,
/// each with variance `2σ⁴/ν_i` (χ² with ν_i EDF) at the model σ²
/// (iterated), weighted by its inverse. ν_i is first the EDF of the noise
/// identified at τ_i, then (iterated) that of the model's mix there:
/// `1/ν = Σ_j f_j²/ν_j`, f_j term j's share of the model σ² and ν_j the
/// Greenhall EDF of its noise type at m = τ/τ0 over `n_phase` points.
/// Overlapping estimates at neighbouring τ share data: their correlation
/// is modelled as a Markov chain in log₂ τ,
/// `ρ_ij = Π_k ρ_k^{log₂(τ_{k+1}/τ_k)}` with the octave correlation ρ_k
/// of the noise type the model says dominates there, the covariance of
/// the estimates is the sandwich `B V Bᵀ`, `B = (AᵀWA)⁻¹AᵀW`, and the
/// residuals' generalized χ² is `rᵀV⁻¹r`.
///
/// **Model choice**: every set of the five terms is fitted (31 sets; a set
/// whose fit gives a negative square is not a model, nor is one in which
/// a term's U95 reaches its value: a term the record cannot tell from
/// zero is never reported), and the set with the
/// least `χ² + PENALTY·p` ([`PENALTY`], p terms, the ramp counting
/// [`RAMP_FACTOR`]) is reported: every term in
/// it, with u from its full covariance (u of an amplitude A = √θ is
/// `u(θ)/(2A)`) and the correlation between the squares
/// ([`TermFit::squares`]). A term outside it is "not identified": the
/// record is explained as well without it. When another set of no more
/// terms scores within [`NOT_SEPARATED`], the terms in which the two differ
/// are not separated by the record (typically B and K over a short τ range)
/// and a warning says so. When the residuals exceed the modelled scatter
/// (χ² above its dof), u grows by the Birge ratio with n − p degrees of
/// freedom.
pub fn fit_terms(
    taus: &[f64],
    oadev: &DevSeries,
    alpha: &[Option<i32>],
    tau0: f64,
    n_phase: usize,
) -> Result<TermFit> {
    let obs = observations(taus, oadev, alpha, tau0, n_phase);
    let mut cands: Vec<Active> = Vec::new();
    for mask in 1u32..32 {
        let set: Vec<usize> = (0..5).filter(|&j| mask >> j & 1 == 1).collect();
        if let Some(a) = fit_set(&obs, set)? {
            if a.distinguishable() {
                cands.push(a);
            }
        }
    }
    // Least score; on a tie the fewer terms, then the lower χ².
    let order = |a: &Active, b: &Active| {
        a.score()
            .total_cmp(&b.score())
            .then(a.active.len().cmp(&b.active.len()))
            .then(a.chi2.total_cmp(&b.chi2))
    };
    let mut warnings = Vec::new();
    let Some(best) = cands.iter().min_by(|a, b| order(a, b)) else {
        for j in 0..5 {
            warnings.push(not_identified(j, "too few averaging times"));
        }
        return Ok(TermFit {
            terms: [None; 5],
            squares: None,
            warnings,
            chi2: None,
        });
    };
    // The closest rival of no more terms, if the record cannot tell them
    // apart.
    let rival = cands
        .iter()
        .filter(|c| c.active != best.active && c.active.len() <= best.active.len())
        .filter(|c| c.score() - best.score() < NOT_SEPARATED)
        .min_by(|a, b| order(a, b));
    // The terms of `from` that are (or are not) in `other`.
    let pick = |from: &[usize], other: &[usize], inside: bool| -> Vec<usize> {
        from.iter()
            .copied()
            .filter(|j| other.contains(j) == inside)
            .collect()
    };
    // An alias: a rival of as many terms explaining the curve with other
    // noises in their place (B for K, Q for N). Neither is chosen: the
    // terms the two share are reported, the swapped ones are not. (A ramp
    // is not a noise: its criterion already weighs it as RAMP_FACTOR
    // terms, and the set without it is reported.)
    let aliased: Vec<usize> = match rival {
        Some(r)
            if r.active.len() == best.active.len()
                && !r.active.contains(&4)
                && !best.active.contains(&4) =>
        {
            pick(&best.active, &r.active, false)
        }
        _ => Vec::new(),
    };
    let mut terms = [None; 5];
    for (k, &j) in best.active.iter().enumerate() {
        let th = best.est.values()[k];
        let u = best.est.u_at(k);
        if th > 0.0 && !aliased.contains(&j) {
            let a = th.sqrt();
            terms[j] = Some(Term {
                value: a,
                u: u / (2.0 * a),
                dof: best.est.dof(),
            });
        }
    }
    if let Some(r) = rival {
        let only_best = pick(&best.active, &r.active, false);
        let only_rival = pick(&r.active, &best.active, false);
        let common = pick(&best.active, &r.active, true);
        let beside = if common.is_empty() {
            String::new()
        } else {
            format!(" beside {}", names(&common))
        };
        let verdict = if aliased.is_empty() {
            format!(
                "{} reported, {} not",
                names(&best.active),
                names(&only_rival)
            )
        } else {
            "they alias one another: neither is reported (where the curve has a minimum, adev_min is what the record determines there)".to_string()
        };
        warnings.push(Warning::new(
            WarningCode::NoiseTermsNotSeparated,
            format!(
                "the Allan variance is explained about as well by {}{beside} as by {} (criterion {:.1} against {:.1}): the record does not separate them; {verdict}",
                names(&only_rival),
                names(&only_best),
                r.score(),
                best.score(),
            ),
        ));
    }
    for j in (0..5).filter(|j| terms[*j].is_none() && !aliased.contains(j)) {
        warnings.push(not_identified(
            j,
            "the Allan variance is explained as well without it",
        ));
    }
    Ok(TermFit {
        terms,
        squares: Some(best.est.clone()),
        warnings,
        chi2: Some((best.chi2, best.dof)),
    })
}

/// The terms `set` (indices into [`TERMS`]) fitted to an OADEV series as
/// [`fit_terms`] fits each candidate set, without the choice among sets:
/// every term of the set with its u (a Monte Carlo trial keeps the terms
/// the record's own reduction chose). Refused when the set does not fit
/// (a square at or below zero, fewer averaging times than terms).
pub fn fit_terms_fixed(
    taus: &[f64],
    oadev: &DevSeries,
    alpha: &[Option<i32>],
    tau0: f64,
    n_phase: usize,
    set: &[usize],
) -> Result<TermFit> {
    let obs = observations(taus, oadev, alpha, tau0, n_phase);
    let Some(a) = fit_set(&obs, set.to_vec())? else {
        return Err(crate::error::Error::Unsupported(format!(
            "the terms {} do not fit the Allan variance ({} averaging times)",
            names(set),
            obs.len()
        )));
    };
    let mut terms = [None; 5];
    for (k, &j) in a.active.iter().enumerate() {
        let th = a.est.values()[k];
        if th > 0.0 {
            let v = th.sqrt();
            terms[j] = Some(Term {
                value: v,
                u: a.est.u_at(k) / (2.0 * v),
                dof: a.est.dof(),
            });
        }
    }
    Ok(TermFit {
        terms,
        squares: Some(a.est.clone()),
        warnings: Vec::new(),
        chi2: Some((a.chi2, a.dof)),
    })
}

/// The observations of [`fit_terms`]: σ̂²(τ) about an octave apart from
/// 4τ0 on, each with its EDF and the Greenhall EDF of every term's noise.
fn observations(
    taus: &[f64],
    oadev: &DevSeries,
    alpha: &[Option<i32>],
    tau0: f64,
    n_phase: usize,
) -> Vec<Obs> {
    let mut obs: Vec<Obs> = Vec::new();
    for (i, &t) in taus.iter().enumerate() {
        let (Some(s), Some(e)) = (oadev.value[i], oadev.edf[i]) else {
            continue;
        };
        // τ below 4τ0 is left out: sampling distorts the noise there (the
        // sampled flicker's Allan variance is 1.44× its continuous level at
        // τ0, 1.15× at 2τ0, 1.05× at 4τ0; anti-alias filters do the same).
        if t < 4.0 * tau0 - 1e-9 * tau0
            || !(s > 0.0 && e > 0.0)
            || obs.last().is_some_and(|o| t < 1.9 * o.tau)
        {
            continue;
        }
        let m = (t / tau0).round().max(1.0) as usize;
        obs.push(Obs {
            tau: t,
            sigma: s,
            edf: e,
            alpha: alpha.get(i).copied().flatten(),
            term_edf: TERM_ALPHA
                .map(|a| super::edf::greenhall(a, 2, m, n_phase, true, false).filter(|v| *v > 0.0)),
        });
    }
    obs
}

fn not_identified(j: usize, why: &str) -> Warning {
    let name = [
        "quantization Q",
        "random walk N",
        "bias instability B",
        "rate random walk K",
        "rate ramp R",
    ][j];
    Warning::new(
        WarningCode::NoiseTermNotIdentified,
        format!("{name} not identified: {why}; not reported"),
    )
}

/// Slope-line readings of IEEE Std 952 Annex C (Figure C.2): the
/// asymptote of each term touches the σ(τ) curve from below, so each
/// reading is the minimum over τ of σ(τ) divided by its slope line:
/// `Q = min σ τ/√3`, `N = min σ √τ` (the −½ line read at τ = 1 s),
/// `B = min σ / 0.664` (the flat floor), `K = min σ √(3/τ)` (the +½ line
/// read at τ = 3 s), `R = min σ √2/τ`. Upper bounds of each term.
pub fn slope_readings(taus: &[f64], oadev: &DevSeries) -> [Option<f64>; 5] {
    let pts: Vec<(f64, f64)> = taus
        .iter()
        .zip(&oadev.value)
        .filter_map(|(&t, v)| Some((t, (*v)?)))
        .collect();
    let min = |f: &dyn Fn(f64, f64) -> f64| pts.iter().map(|&(t, s)| f(t, s)).reduce(f64::min);
    [
        min(&|t, s| s * t / 3f64.sqrt()),
        min(&|t, s| s * t.sqrt()),
        min(&|_, s| s / FLICKER.sqrt()),
        min(&|t, s| s * (3.0 / t).sqrt()),
        min(&|t, s| s * 2f64.sqrt() / t),
    ]
}

/// Bias stability (GJB 2426A / IEEE Std 1431): the sample standard
/// deviation of the means of consecutive non-overlapping windows of `τ`
/// seconds, from phase `x` at spacing τ0 (window means are
/// `(x_{(j+1)k} − x_{jk})/(kτ0)`, k = round(τ/τ0)), with
/// `u = s/√(2(n−1))` and n − 1 degrees of freedom. `None` with fewer than
/// two windows, or when the differences overflow.
pub fn bias_stability(x: &[f64], tau0: f64, tau: f64) -> Option<Term> {
    bias_stability_segments(&[x], tau0, tau)
}

/// [`bias_stability`] of a record with gaps, given as its contiguous
/// stretches (phase records): the τ-averages of every stretch, none across
/// a gap, pooled about their common mean.
pub fn bias_stability_segments(segs: &[&[f64]], tau0: f64, tau: f64) -> Option<Term> {
    let k = (tau / tau0).round() as usize;
    if k == 0 {
        return None;
    }
    let kt = k as f64 * tau0;
    let means: Vec<f64> = segs
        .iter()
        .flat_map(|x| {
            let n = x.len().saturating_sub(1) / k;
            (0..n).map(move |j| (x[(j + 1) * k] - x[j * k]) / kt)
        })
        .collect();
    let n = means.len();
    if n < 2 {
        return None;
    }
    let mu = means.iter().sum::<f64>() / n as f64;
    let s = (means.iter().map(|m| (m - mu) * (m - mu)).sum::<f64>() / (n - 1) as f64).sqrt();
    // Samples near the f64 limit can overflow the differences: no number.
    s.is_finite().then_some(Term {
        value: s,
        u: s / (2.0 * (n - 1) as f64).sqrt(),
        dof: (n - 1) as f64,
    })
}

/// A bias stability of [`bias_stability`] with the degrees of freedom its
/// windows have under the fitted noise model `fit` (τ in s, `tau0` the
/// sample period): window means of flicker or random-walk noise are
/// correlated, so their sample variance is known with fewer than `n − 1`
/// degrees of freedom. The means' covariance (generalized, for noises
/// whose variance grows without bound) is
/// `C(h) = [D((h+1)τ) + D(|h−1|τ) − 2D(hτ)]/(2τ²)` from the phase
/// structure function of the identified terms, `D(t) = 2Q² (t > 0) + N²t
/// − (B²/π) t² ln t − K²t³/6` (each term's `D` reproduces its Allan
/// variance `4D(τ) − D(2τ) = 2τ²σ²(τ)` of IEEE Std 952 C.15 ff.; the
/// ramp is deterministic and left out); `s² = yᵀAy/(n − 1)` with
/// `A = I − 11ᵀ/n` has `ν = tr(AC)²/tr((AC)²)` (Satterthwaite on the
/// quadratic form's exact moments, computed in O(n) on the Toeplitz `C`),
/// and `u = s/√(2ν)`. White noise alone gives `n − 1`. The term unchanged
/// when the model has no term or `ν` is not finite.
pub fn with_model_dof(t: Term, fit: &TermFit, tau0: f64, tau: f64) -> Term {
    let v = |j: usize| fit.terms[j].map_or(0.0, |t| t.value * t.value);
    let (q2, n2, b2, k2) = (v(0), v(1), v(2), v(3));
    if q2 + n2 + b2 + k2 <= 0.0 {
        return t;
    }
    let tau = (tau / tau0).round().max(1.0) * tau0;
    let d = |x: f64| -> f64 {
        if x <= 0.0 {
            return 0.0;
        }
        2.0 * q2 + n2 * x - b2 / std::f64::consts::PI * x * x * x.ln() - k2 * x.powi(3) / 6.0
    };
    let n = (t.dof + 1.0).round() as usize;
    if n < 2 {
        return t;
    }
    let g: Vec<f64> = (0..n)
        .map(|h| {
            let h = h as f64;
            (d((h + 1.0) * tau) + d((h - 1.0).abs() * tau) - 2.0 * d(h * tau)) / (2.0 * tau * tau)
        })
        .collect();
    let m = n as f64;
    // Prefix sums P(k) = Σ_{h ≤ k} C(h); row sums C1_i = P(i) + P(n−1−i) − C(0).
    let mut p = Vec::with_capacity(n);
    let mut acc = 0.0;
    for &x in &g {
        acc += x;
        p.push(acc);
    }
    let row = |i: usize| p[i] + p[n - 1 - i] - g[0];
    let (mut tr_cc, mut one) = (m * g[0] * g[0], m * g[0]);
    for (h, &x) in g.iter().enumerate().skip(1) {
        let w = 2.0 * (m - h as f64);
        tr_cc += w * x * x;
        one += w * x;
    }
    let norm2: f64 = (0..n).map(|i| row(i).powi(2)).sum();
    let tr_ac = m * g[0] - one / m;
    let tr_acac = tr_cc - 2.0 * norm2 / m + one * one / (m * m);
    let nu = tr_ac * tr_ac / tr_acac;
    if !(nu.is_finite() && nu > 0.0 && tr_ac > 0.0) {
        return t;
    }
    let nu = nu.min(t.dof);
    Term {
        value: t.value,
        u: t.value / (2.0 * nu).sqrt(),
        dof: nu,
    }
}

/// The Allan deviation of the fitted model minus the data, relative, at
/// each τ (for the report's fit lines); unused terms contribute nothing.
pub fn model_curve(fit: &TermFit, taus: &[f64]) -> Vec<f64> {
    taus.iter().map(|&t| fit.model(t)).collect()
}

#[cfg(test)]
mod psd_tests {
    use super::*;

    #[test]
    fn term_psds_are_the_one_sided_forms_of_the_allan_model() {
        // White rate: σ²_A = G/(2τ) = N²/τ.
        let (n, tau) = (0.3, 7.0);
        assert!((term_psd(1, n, 1.0, 0.01) / (2.0 * tau) - n * n / tau).abs() < 1e-15);
        // Flicker: G = h₋₁/f with σ²_A = 2 ln 2 h₋₁ = (2 ln 2/π) B².
        let (b, f) = (0.2, 0.5);
        let h = term_psd(2, b, f, 0.01) * f;
        assert!((2.0 * std::f64::consts::LN_2 * h - FLICKER * b * b).abs() < 1e-15);
        // Random walk: G = h₋₂/f², σ²_A = (2π²/3) h₋₂ τ = K² τ/3.
        let k = 0.05;
        let h2 = term_psd(3, k, f, 0.01) * f * f;
        let pi2 = std::f64::consts::PI.powi(2);
        assert!((2.0 * pi2 / 3.0 * h2 * tau - k * k * tau / 3.0).abs() < 1e-15);
    }
}
