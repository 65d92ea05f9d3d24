//! The noise of the runs and the covariance of their means.
//!
//! # Noise model
//! The overlapping Allan variance of the output is pooled over the runs
//! (each run's own samples: its constant stimulus effect cancels) at
//! octave cluster sizes `m = 1, 2, 4, …` up to half the longest run
//! (the run length itself is where the u is read), and fitted by
//! weighted least squares (weights `ν_m / 2σ⁴(τ_m)`, `ν_m` the
//! equivalent degrees of freedom, re-weighted with the model) with
//! non-negative terms, a random walk kept only when it lowers χ² by more
//! than its [`TERM_PENALTY`]:
//!
//! `σ²(τ) = a/τ + b + c τ`
//!
//! white noise (`a`, unit²·s), flicker (`b = 2 ln 2 · h₋₁`, unit²: the
//! bias instability `B = √b / 0.664`) and random walk (`c = q/3`,
//! unit²/s) (IEEE Std 952-2020 Annex C; NIST SP 1065).
//!
//! # Covariance of the run means
//! A run's mean over `[s_r, e_r]` (length `T_r`) has the Allan variance
//! at its own length, `σ²(T_r)`, as its u: the variance of the
//! difference of two adjacent runs' means is `2σ²(T)` whatever the
//! noise, where `σ/√n` is right only for white noise. Runs further apart
//! drift apart more under flicker and random walk; the joint covariance
//! of the run means comes from the generalized covariance of each term
//! (Matheron's intrinsic random functions: only contrasts are defined,
//! and every fit here has an intercept):
//!
//! `K(τ) = a δ(τ) − h₋₁ ln|τ| − (q/2)|τ|`,
//! `Σ_rs = (1/(T_r T_s)) ∫_r∫_s K(t − t′) dt dt′`
//! (the white term gives `δ_rs a/T_r`),
//!
//! in closed form through `G(x) = x²/2 ln|x| − 3x²/4` (ln) and
//! `|x|³/6` (|·|). A constant added to every element (`c 11ᵀ`, which the
//! intercept absorbs: the estimates of every other term and their
//! covariance are unchanged) makes the matrix positive definite.

use nalgebra::DMatrix;

use crate::error::{Error, Result};

/// A run's time span: start (s) and length (s), and its samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// Start (s).
    pub start_s: f64,
    /// Length (s).
    pub length_s: f64,
}

/// One pooled Allan variance.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct AvarPoint {
    /// τ (s).
    pub tau_s: f64,
    /// Allan variance (unit²).
    pub avar: f64,
    /// Equivalent degrees of freedom.
    pub edf: f64,
}

/// The fitted noise model (module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct NoiseModel {
    /// White: `a` (unit²·s).
    pub white: f64,
    /// Flicker floor `b` (unit²).
    pub flicker: f64,
    /// Random walk `c` (unit²/s).
    pub walk: f64,
    /// Degrees of freedom of the sensitivities' u: at first the
    /// equivalent degrees of freedom of the pooled Allan variance at the
    /// longest τ; the reduction replaces it by Welch–Satterthwaite's.
    pub dof: f64,
    /// The pooled Allan variances fitted.
    pub points: Vec<AvarPoint>,
}

/// Pooled overlapping Allan variance of the runs' samples (module docs).
pub fn pooled_avar(runs: &[&[f64]], dt_s: f64) -> Vec<AvarPoint> {
    let longest = runs.iter().map(|r| r.len()).max().unwrap_or(0);
    let sums: Vec<Vec<f64>> = runs
        .iter()
        .map(|r| {
            let mean = r.iter().sum::<f64>() / r.len().max(1) as f64;
            let mut s = Vec::with_capacity(r.len() + 1);
            s.push(0.0);
            let mut acc = 0.0;
            for v in *r {
                acc += v - mean;
                s.push(acc);
            }
            s
        })
        .collect();
    let mut out = Vec::new();
    let mut m = 1usize;
    while 2 * m < longest {
        let (mut ss, mut terms, mut edf) = (0.0, 0usize, 0.0);
        for s in &sums {
            let n = s.len() - 1;
            if n < 2 * m + 1 {
                continue;
            }
            for k in 0..=n - 2 * m {
                let a = s[k + m] - s[k];
                let b = s[k + 2 * m] - s[k + m];
                let d = (b - a) / m as f64;
                ss += d * d;
            }
            terms += n - 2 * m + 1;
            edf += edf_white(n, m);
        }
        if terms > 0 {
            out.push(AvarPoint {
                tau_s: m as f64 * dt_s,
                avar: ss / (2.0 * terms as f64),
                edf,
            });
        }
        m *= 2;
    }
    out
}

impl NoiseModel {
    /// The candidate models of pooled Allan variances (module docs), each
    /// with its score (the Allan fit's `χ²` plus its terms' penalties);
    /// [`super::reduce`] adds the run means' own evidence and takes the
    /// best.
    pub fn candidates(points: &[AvarPoint]) -> Result<Vec<(NoiseModel, f64)>> {
        if points.is_empty() || points.iter().all(|p| p.avar <= 0.0) {
            return Err(Error::Unsupported(
                "the runs' output does not vary: no noise to weigh the runs by (a constant output, or a column of the wrong channel)".into(),
            ));
        }
        let dof = points.last().map_or(1.0, |p| p.edf.max(1.0));
        let out: Vec<(NoiseModel, f64)> = candidates(points)
            .into_iter()
            .map(|(p, score)| {
                (
                    NoiseModel {
                        white: p[0],
                        flicker: p[1],
                        walk: p[2],
                        dof,
                        points: points.to_vec(),
                    },
                    score,
                )
            })
            .collect();
        if out.is_empty() {
            return Err(Error::Unsupported(
                "no noise model fits the runs' Allan variance".into(),
            ));
        }
        Ok(out)
    }

    /// The model that best explains both the pooled Allan variances and
    /// the run means (module docs): for the random walk of each
    /// candidate (none, or the one fitted), the flicker floor `b ≥ 0`
    /// that minimises the Allan fit's `χ²` (white refitted for that `b`)
    /// plus `run_evidence` of the model (the run means' restricted
    /// `−2ℓ`), by golden-section search; `None` from `run_evidence` for
    /// a model the runs cannot use.
    pub fn profile(
        points: &[AvarPoint],
        run_evidence: impl Fn(&NoiseModel) -> Option<f64>,
    ) -> Result<NoiseModel> {
        let cands = Self::candidates(points)?;
        let base = cands
            .iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|c| c.0.clone())
            .expect("non-empty");
        let model_var: Vec<f64> = points.iter().map(|p| base.avar(p.tau_s)).collect();
        let w: Vec<f64> = points
            .iter()
            .zip(&model_var)
            .map(|(p, m)| p.edf / (2.0 * m.powi(2).max(f64::MIN_POSITIVE)))
            .collect();
        let top = points.iter().map(|p| p.avar).fold(0.0_f64, f64::max);
        let b_max = 4.0 * cands.iter().map(|c| c.0.flicker).fold(0.0_f64, f64::max)
            + points.last().map_or(top, |p| p.avar);
        // The walk: none, that of the first Allan candidate with one, or
        // one of a geometric grid up
        // to what would double the longest τ's variance (a walk too slow
        // to show within a run can still move runs far apart).
        let mut walks: Vec<f64> = vec![0.0];
        walks.extend(cands.iter().map(|c| c.0.walk).filter(|c| *c > 0.0).take(1));
        if let Some(last) = points.last() {
            let c_max = last.avar / last.tau_s;
            walks.extend(
                (0..WALK_GRID)
                    .map(|k| c_max * 10f64.powf(-4.0 * k as f64 / (WALK_GRID - 1) as f64)),
            );
        }
        let mut best: Option<(f64, NoiseModel)> = None;
        for c in walks {
            let score = |b: f64| -> Option<(f64, NoiseModel)> {
                // White for this b and c: one-term weighted least squares.
                let (mut num, mut den) = (0.0, 0.0);
                for (p, wi) in points.iter().zip(&w) {
                    let x = 1.0 / p.tau_s;
                    num += wi * x * (p.avar - b - c * p.tau_s);
                    den += wi * x * x;
                }
                let a = (num / den).max(0.0);
                let chi2: f64 = points
                    .iter()
                    .zip(&w)
                    .map(|(p, wi)| wi * (p.avar - eval(&[a, b, c], p.tau_s)).powi(2))
                    .sum();
                let m = NoiseModel {
                    white: a,
                    flicker: b,
                    walk: c,
                    dof: base.dof,
                    points: points.to_vec(),
                };
                let penalty = if c > 0.0 { TERM_PENALTY[2] } else { 0.0 }
                    + if b > 0.0 { TERM_PENALTY[1] } else { 0.0 };
                run_evidence(&m).map(|r| (chi2 + penalty + r, m))
            };
            let f = |b: f64| score(b).map_or(f64::INFINITY, |s| s.0);
            let (mut lo, mut hi) = (0.0, b_max.max(f64::MIN_POSITIVE));
            let g = (5f64.sqrt() - 1.0) / 2.0;
            let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
            let (mut f1, mut f2) = (f(x1), f(x2));
            for _ in 0..40 {
                if f1 <= f2 {
                    hi = x2;
                    (x2, f2) = (x1, f1);
                    x1 = hi - g * (hi - lo);
                    f1 = f(x1);
                } else {
                    lo = x1;
                    (x1, f1) = (x2, f2);
                    x2 = lo + g * (hi - lo);
                    f2 = f(x2);
                }
            }
            for b in [0.0, 0.5 * (lo + hi)] {
                if let Some((s, m)) = score(b) {
                    if best.as_ref().is_none_or(|x| s < x.0) {
                        best = Some((s, m));
                    }
                }
            }
        }
        best.map(|b| b.1).ok_or_else(|| {
            Error::Unsupported(
                "no noise model gives a positive-definite covariance of the run means".into(),
            )
        })
    }

    /// The covariance of the model's present terms (those above 0) from
    /// the weighted Allan fit, `(AᵀWA)⁻¹` with `W = ν/(2σ⁴)` of the
    /// model; 0 for an absent term (3×3: white, flicker, walk).
    pub fn terms_covariance(&self) -> DMatrix<f64> {
        let theta = [self.white, self.flicker, self.walk];
        let idx: Vec<usize> = (0..3).filter(|&k| theta[k] > 0.0).collect();
        let mut out = DMatrix::zeros(3, 3);
        if idx.is_empty() || self.points.is_empty() {
            return out;
        }
        let basis = |p: &AvarPoint| [1.0 / p.tau_s, 1.0, p.tau_s];
        let mut info = DMatrix::zeros(idx.len(), idx.len());
        for p in &self.points {
            let w = p.edf / (2.0 * self.avar(p.tau_s).powi(2).max(f64::MIN_POSITIVE));
            let b = basis(p);
            for (i, ki) in idx.iter().enumerate() {
                for (j, kj) in idx.iter().enumerate() {
                    info[(i, j)] += w * b[*ki] * b[*kj];
                }
            }
        }
        if let Some(c) = info.try_inverse() {
            for (i, ki) in idx.iter().enumerate() {
                for (j, kj) in idx.iter().enumerate() {
                    out[(*ki, *kj)] = c[(i, j)];
                }
            }
        }
        out
    }

    /// This model with term `k` (white, flicker, walk) times `1 + e`.
    pub fn scaled(&self, k: usize, e: f64) -> NoiseModel {
        let mut m = self.clone();
        match k {
            0 => m.white *= 1.0 + e,
            1 => m.flicker *= 1.0 + e,
            _ => m.walk *= 1.0 + e,
        }
        m
    }

    /// The best candidate on the Allan variances alone.
    pub fn fit(points: Vec<AvarPoint>) -> Result<NoiseModel> {
        let c = Self::candidates(&points)?;
        Ok(c.into_iter()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|x| x.0)
            .expect("non-empty"))
    }

    /// The model's Allan variance at τ (unit²).
    pub fn avar(&self, tau_s: f64) -> f64 {
        eval(&[self.white, self.flicker, self.walk], tau_s)
    }

    /// The bias instability `B = √b / 0.664` (unit).
    pub fn bias_instability(&self) -> f64 {
        self.flicker.sqrt() / 0.664
    }

    /// The covariance of the run means (module docs), positive definite.
    pub fn run_covariance(&self, spans: &[Span]) -> Result<DMatrix<f64>> {
        let r = spans.len();
        if r == 0 {
            return Err(Error::Unsupported("no runs".into()));
        }
        let scale = {
            let mut l: Vec<f64> = spans.iter().map(|s| s.length_s).collect();
            l.sort_by(f64::total_cmp);
            l[r / 2].max(f64::MIN_POSITIVE)
        };
        let h = self.flicker / (2.0 * 2f64.ln());
        let q = 3.0 * self.walk;
        let t0 = spans[0].start_s;
        let mut s = DMatrix::zeros(r, r);
        for i in 0..r {
            for j in 0..=i {
                let (a1, l1) = ((spans[i].start_s - t0) / scale, spans[i].length_s / scale);
                let (a2, l2) = ((spans[j].start_s - t0) / scale, spans[j].length_s / scale);
                let (b1, b2) = (a1 + l1, a2 + l2);
                let both =
                    |g: &dyn Fn(f64) -> f64| g(b1 - a2) - g(a1 - a2) - g(b1 - b2) + g(a1 - b2);
                let ln_part = both(&g_ln);
                let abs_part = both(&|x: f64| x.abs().powi(3) / 6.0);
                let mut v = (-h * ln_part - 0.5 * q * scale * abs_part) / (l1 * l2);
                if i == j {
                    v += self.white / spans[i].length_s;
                }
                s[(i, j)] = v;
                s[(j, i)] = v;
            }
        }
        let top = s.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut c = 4.0 * top + f64::MIN_POSITIVE;
        for _ in 0..40 {
            let shifted = s.add_scalar(c);
            if shifted.clone().cholesky().is_some() {
                return Ok(shifted);
            }
            c *= 4.0;
        }
        Err(Error::Unsupported(
            "the covariance of the run means is not positive definite (runs overlapping in time?)"
                .into(),
        ))
    }
}

/// Equivalent degrees of freedom of the overlapping Allan variance of
/// `n` samples at cluster size `m` for white noise (NIST SP 1065 §5.3,
/// Table 5, with `N = n + 1` phase points), at least 1.
pub fn edf_white(n: usize, m: usize) -> f64 {
    let (big_n, m) = (n as f64 + 1.0, m as f64);
    let e = (3.0 * (big_n - 1.0) / (2.0 * m) - 2.0 * (big_n - 2.0) / big_n) * 4.0 * m * m
        / (4.0 * m * m + 5.0);
    e.max(1.0)
}

/// `G(x) = x²/2 ln|x| − 3x²/4`, `G(0) = 0`.
fn g_ln(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x * x * (0.5 * x.abs().ln() - 0.75)
    }
}

fn eval(p: &[f64; 3], tau: f64) -> f64 {
    p[0] / tau + p[1] + p[2] * tau
}

/// Walks tried by [`NoiseModel::profile`] besides none and the Allan
/// fit's.
pub const WALK_GRID: usize = 9;

/// Penalty of each noise term (white, flicker, random walk) in the model
/// choice: a random walk is kept only when it lowers χ² by more than
/// about the 5 % point of χ²₁ with margin for the correlation of
/// overlapping estimates (a spurious walk would let runs far apart
/// drift without bound); flicker, whose effect between runs grows only
/// with the logarithm of their distance, when it lowers the score by
/// more than 2 (Akaike's penalty: a short run shows it weakly, and
/// missing it understates u).
pub const TERM_PENALTY: [f64; 3] = [0.0, 2.0, 4.0];

/// The noise models over every subset of the three terms that holds
/// white noise, each fitted by weighted least squares with weights
/// `ν/(2σ⁴)` (σ² the data's, then the subset's own model), terms
/// non-negative, with its `χ²` plus the [`TERM_PENALTY`] of its terms.
fn candidates(points: &[AvarPoint]) -> Vec<([f64; 3], f64)> {
    let basis = |p: &AvarPoint| [1.0 / p.tau_s, 1.0, p.tau_s];
    let solve = |idx: &[usize], sigma2: &dyn Fn(usize) -> f64| -> Option<([f64; 3], f64)> {
        let w: Vec<f64> = (0..points.len())
            .map(|i| points[i].edf / (2.0 * sigma2(i).powi(2).max(f64::MIN_POSITIVE)))
            .collect();
        let a = DMatrix::from_fn(points.len(), idx.len(), |i, j| {
            basis(&points[i])[idx[j]] * w[i].sqrt()
        });
        let y = nalgebra::DVector::from_fn(points.len(), |i, _| points[i].avar * w[i].sqrt());
        let x = crate::estimation::bounded_svd(a.clone(), true, true)?
            .solve(&y, 1e-14)
            .ok()?;
        if x.iter().any(|v| *v < 0.0 || !v.is_finite()) {
            return None;
        }
        let mut p = [0.0; 3];
        for (j, k) in idx.iter().enumerate() {
            p[*k] = x[j];
        }
        Some((p, (&a * &x - &y).norm_squared()))
    };
    let mut out = Vec::new();
    for mask in 1u8..8 {
        let idx: Vec<usize> = (0..3).filter(|k| mask & (1 << k) != 0).collect();
        if idx.len() > points.len() {
            continue;
        }
        let Some((p0, _)) = solve(&idx, &|i| points[i].avar) else {
            continue;
        };
        if let Some((p, chi2)) = solve(&idx, &|i| eval(&p0, points[i].tau_s)) {
            out.push((p, chi2 + idx.iter().map(|k| TERM_PENALTY[*k]).sum::<f64>()));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacent_runs_differ_by_twice_the_allan_variance_for_every_term() {
        // Var(mean₂ − mean₁) of adjacent runs of length T is 2σ²(T).
        for (a, b, c) in [
            (2.0, 0.0, 0.0),
            (0.0, 3.0, 0.0),
            (0.0, 0.0, 0.5),
            (1.0, 1.0, 0.1),
        ] {
            let m = NoiseModel {
                white: a,
                flicker: b,
                walk: c,
                dof: 10.0,
                points: Vec::new(),
            };
            let t = 7.0;
            let spans = [
                Span {
                    start_s: 0.0,
                    length_s: t,
                },
                Span {
                    start_s: t,
                    length_s: t,
                },
            ];
            let s = m.run_covariance(&spans).unwrap();
            let var = s[(0, 0)] + s[(1, 1)] - 2.0 * s[(0, 1)];
            let want = 2.0 * m.avar(t);
            assert!(
                (var - want).abs() < 1e-9 * want.max(1.0),
                "{a} {b} {c}: {var} vs {want}"
            );
        }
    }

    #[test]
    fn white_noise_allan_variance_is_sigma_squared_over_m() {
        let mut r = crate::sim::rng(3);
        let x: Vec<f64> = (0..20000)
            .map(|_| crate::sim::normal(&mut r, 2.0))
            .collect();
        let p = pooled_avar(&[&x[..10000], &x[10000..]], 0.01);
        for q in &p[..6] {
            let m = q.tau_s / 0.01;
            let want = 4.0 / m;
            assert!((q.avar / want - 1.0).abs() < 4.0 / q.edf.sqrt(), "{q:?}");
        }
        let model = NoiseModel::fit(p).unwrap();
        assert!((model.white / (4.0 * 0.01) - 1.0).abs() < 0.1, "{model:?}");
    }
}
