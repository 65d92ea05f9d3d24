//! The warm-up curve fitted to block means (module docs of
//! [`super`]): the blocks, the noise of a block mean (batch means of the
//! richest curve's residuals), the Gauss–Newton fit of one model shape
//! and the choice of the shape by the lack-of-fit rule at the batch
//! scale.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::estimation::gauss_newton::{
    gauss_newton, GaussNewtonOptions, NonlinearModel, StepControl,
};
use crate::estimation::linear::{FitOptions, Variance, VarianceSource, LACK_OF_FIT_ALPHA};
use crate::estimation::{Estimates, Fit};

/// The shape of the warm-up curve `B(t) = B∞ + Σ Aᵢ e^{−t/τᵢ} [+ D t]`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    /// One exponential.
    Exp1,
    /// One exponential and a linear drift.
    Exp1Drift,
    /// Two exponentials.
    Exp2,
    /// Two exponentials and a linear drift.
    Exp2Drift,
}

impl Shape {
    /// Every shape, simplest first (the order the rule tries them).
    pub const ALL: [Shape; 4] = [Shape::Exp1, Shape::Exp1Drift, Shape::Exp2, Shape::Exp2Drift];

    /// The shape's name (`exp1`, `exp1-drift`, …).
    pub fn name(self) -> &'static str {
        match self {
            Shape::Exp1 => "exp1",
            Shape::Exp1Drift => "exp1-drift",
            Shape::Exp2 => "exp2",
            Shape::Exp2Drift => "exp2-drift",
        }
    }

    /// Two exponentials.
    pub fn two(self) -> bool {
        matches!(self, Shape::Exp2 | Shape::Exp2Drift)
    }

    /// A linear drift term.
    pub fn drift(self) -> bool {
        matches!(self, Shape::Exp1Drift | Shape::Exp2Drift)
    }

    /// Parameter names, in the order of the parameter vector:
    /// `bias_settled, amplitude, tau_s[, amplitude_2, tau_2_s][, drift_per_s]`.
    pub fn names(self) -> Vec<String> {
        let mut v = vec!["bias_settled", "amplitude", "tau_s"];
        if self.two() {
            v.extend(["amplitude_2", "tau_2_s"]);
        }
        if self.drift() {
            v.push("drift_per_s");
        }
        v.into_iter().map(String::from).collect()
    }
}

/// The transient `Σ Aᵢ e^{−t/τᵢ}` at `t` (s from power-on).
pub fn transient(shape: Shape, p: &[f64], t: f64) -> f64 {
    let mut v = p[1] * (-t / p[2]).exp();
    if shape.two() {
        v += p[3] * (-t / p[4]).exp();
    }
    v
}

/// The whole curve `B(t)` at `t` (s from power-on).
pub fn curve(shape: Shape, p: &[f64], t: f64) -> f64 {
    let d = if shape.drift() {
        p[p.len() - 1] * t
    } else {
        0.0
    };
    p[0] + transient(shape, p, t) + d
}

/// Valid samples after turn-on in blocks of `block` rows.
#[derive(Debug, Clone)]
pub struct Blocks {
    /// Time of each valid sample (s from power-on).
    pub t: Vec<f64>,
    /// Its output.
    pub y: Vec<f64>,
    /// Each block: the range of samples in `t`/`y`.
    pub ranges: Vec<(usize, usize)>,
    /// Each block's mean output.
    pub mean: Vec<f64>,
    /// Rows per block.
    pub rows: usize,
    /// Each block: its samples evenly spaced (their exponentials by
    /// recurrence, [`exp_sums`]).
    pub even: Vec<bool>,
}

/// `(Σ e^{−t/τ}, Σ t e^{−t/τ})` over the times `ts`: when they are
/// evenly spaced (`even`), by the recurrence `e_{k+1} = e_k e^{−Δ/τ}`
/// (one exponential a block instead of one a sample; the products'
/// rounding stays near `k·ε` relative), else term by term.
pub fn exp_sums(ts: &[f64], tau: f64, even: bool) -> (f64, f64) {
    let (mut s0, mut s1) = (0.0, 0.0);
    if even && ts.len() > 1 {
        let r = (-(ts[1] - ts[0]) / tau).exp();
        let mut e = (-ts[0] / tau).exp();
        for &t in ts {
            s0 += e;
            s1 += t * e;
            e *= r;
        }
    } else {
        for &t in ts {
            let e = (-t / tau).exp();
            s0 += e;
            s1 += t * e;
        }
    }
    (s0, s1)
}

/// True when `ts` are evenly spaced to a part in 10⁹ of the step.
fn evenly_spaced(ts: &[f64]) -> bool {
    if ts.len() < 3 {
        return true;
    }
    let d = ts[1] - ts[0];
    d > 0.0 && ts.windows(2).all(|w| ((w[1] - w[0]) - d).abs() <= 1e-9 * d)
}

impl Blocks {
    /// Group samples (`rows`: each sample's row after turn-on) by `rows`
    /// rows.
    pub fn new(t: &[f64], y: &[f64], row: &[usize], rows: usize) -> Self {
        let mut ranges = Vec::new();
        let mut start = 0;
        for k in 1..=t.len() {
            if k == t.len() || row[k] / rows != row[start] / rows {
                ranges.push((start, k));
                start = k;
            }
        }
        let mean = ranges
            .iter()
            .map(|&(a, b)| y[a..b].iter().sum::<f64>() / (b - a) as f64)
            .collect();
        let even = ranges
            .iter()
            .map(|&(a, b)| evenly_spaced(&t[a..b]))
            .collect();
        Blocks {
            t: t.to_vec(),
            y: y.to_vec(),
            even,
            ranges,
            mean,
            rows,
        }
    }

    /// The mean of the curve over each block's samples.
    pub fn model(&self, shape: Shape, p: &[f64]) -> Vec<f64> {
        self.ranges
            .iter()
            .zip(&self.even)
            .map(|(&(a, b), &even)| {
                let ts = &self.t[a..b];
                let mut v = p[1] * exp_sums(ts, p[2], even).0;
                if shape.two() {
                    v += p[3] * exp_sums(ts, p[4], even).0;
                }
                if shape.drift() {
                    v += p[p.len() - 1] * ts.iter().sum::<f64>();
                }
                p[0] + v / (b - a) as f64
            })
            .collect()
    }

    /// Each block's mean time (s from power-on).
    pub fn time(&self) -> Vec<f64> {
        self.ranges
            .iter()
            .map(|&(a, b)| self.t[a..b].iter().sum::<f64>() / (b - a) as f64)
            .collect()
    }
}

/// Block means against the curve, each over its standard deviation
/// `sqrt(σ²_LR / count)` (σ²_LR the long-run variance of one sample).
struct Residuals<'a> {
    shape: Shape,
    blocks: &'a Blocks,
    sd: Vec<f64>,
}

impl NonlinearModel for Residuals<'_> {
    fn names(&self) -> Vec<String> {
        self.shape.names()
    }

    fn predict(&self, p: &DVector<f64>) -> DVector<f64> {
        let m = self.blocks.model(self.shape, p.as_slice());
        DVector::from_iterator(
            m.len(),
            m.iter()
                .zip(&self.blocks.mean)
                .zip(&self.sd)
                .map(|((m, y), s)| (m - y) / s),
        )
    }

    /// Analytic: the block mean of `∂B/∂x` over its samples, over its σ.
    fn jacobian(&self, p: &DVector<f64>) -> DMatrix<f64> {
        let x = p.as_slice();
        let b = self.blocks;
        let mut j = DMatrix::zeros(b.ranges.len(), x.len());
        for (r, &(s, e)) in b.ranges.iter().enumerate() {
            let ts = &b.t[s..e];
            let mut row = vec![0.0; x.len()];
            row[0] = (e - s) as f64;
            let (s0, s1) = exp_sums(ts, x[2], b.even[r]);
            row[1] = s0;
            row[2] = x[1] * s1 / (x[2] * x[2]);
            if self.shape.two() {
                let (s0, s1) = exp_sums(ts, x[4], b.even[r]);
                row[3] = s0;
                row[4] = x[3] * s1 / (x[4] * x[4]);
            }
            if self.shape.drift() {
                row[x.len() - 1] = ts.iter().sum();
            }
            let w = 1.0 / ((e - s) as f64 * self.sd[r]);
            for (c, v) in row.iter().enumerate() {
                j[(r, c)] = v * w;
            }
        }
        j
    }
}

/// Gauss–Newton for the warm-up: damped by step halving, the prior
/// variance as known (the lack-of-fit test is [`lack_of_fit`]).
fn gn_options(dof: f64) -> GaussNewtonOptions {
    GaussNewtonOptions {
        fit: FitOptions {
            variance: Variance::Known { dof },
            ..FitOptions::default()
        },
        max_iter: 50,
        step: StepControl::Halving {
            halvings: 20,
            polish: 1e-3,
            polish_steps: 8,
        },
        ..GaussNewtonOptions::default()
    }
}

/// Starting values of the one-exponential curve: the settled level from
/// the last tenth of the blocks, the amplitude at power-on from the first
/// block, and τ from the time the curve falls to 1/e of its start.
pub fn start(b: &Blocks) -> (f64, f64, f64) {
    let n = b.mean.len();
    let tail = &b.mean[n - (n / 10).max(1)..];
    let settled = tail.iter().sum::<f64>() / tail.len() as f64;
    let time = b.time();
    let first = b.mean[0] - settled;
    let span = time[n - 1] - time[0];
    let tau = (1..n)
        .find(|&k| ((b.mean[k] - settled) / first) < (-1f64).exp())
        .map_or(span / 5.0, |k| (time[k] - time[0]).max(span / n as f64));
    let amp = first * (time[0] / tau).min(50.0).exp();
    (settled, amp, tau.max(1e-9))
}

/// Fit one shape from several starts (the best converged fit whose time
/// constants are positive; `tau_s` the longer): from the one-exponential
/// fit `base` when given (its `B∞, A, τ`), else from [`start`].
pub fn fit_shape(
    shape: Shape,
    b: &Blocks,
    var_lr: f64,
    dof: f64,
    base: Option<&[f64]>,
) -> Result<Fit> {
    let sd: Vec<f64> = b
        .ranges
        .iter()
        .map(|&(a, e)| (var_lr / (e - a) as f64).sqrt())
        .collect();
    let m = Residuals {
        shape,
        blocks: b,
        sd,
    };
    let opts = gn_options(dof);
    let y = DVector::zeros(b.mean.len());
    let mut best: Option<(f64, Fit)> = None;
    let mut last = None;
    for s in starts(shape, b, base) {
        match gauss_newton(&m, &y, DVector::from_vec(s), &opts) {
            Ok((f, _)) => {
                let v = f.estimates.values();
                let ok = v[2] > 0.0 && (!shape.two() || v[4] > 0.0);
                let cost = f.residuals.norm_squared();
                if ok && cost.is_finite() && best.as_ref().is_none_or(|x| cost < x.0) {
                    best = Some((cost, f));
                }
            }
            Err(e) => last = Some(e.to_string()),
        }
    }
    let f = best.map(|b| b.1).ok_or_else(|| {
        Error::Unsupported(format!(
            "the {} warm-up curve does not fit ({})",
            shape.name(),
            last.unwrap_or_else(|| "a time constant that is not positive".into())
        ))
    })?;
    order_taus(shape, f)
}

/// Starting points of a shape (see [`fit_shape`]): a second exponential
/// starts at a tenth and at a third of τ, of either sign, with the
/// first's amplitude shared; a drift at 0.
fn starts(shape: Shape, b: &Blocks, base: Option<&[f64]>) -> Vec<Vec<f64>> {
    let (s0, a0, tau0) = match base {
        Some(p) => (p[0], p[1], p[2]),
        None => start(b),
    };
    let scales: &[f64] = if base.is_some() {
        &[1.0]
    } else {
        &[1.0, 0.5, 2.0]
    };
    let mut out = Vec::new();
    for f in scales {
        let tau = tau0 * f;
        if shape.two() {
            for (share, ratio) in [(0.3, 0.1), (0.3, 0.3), (-0.3, 0.1), (-0.3, 0.3)] {
                let mut x = vec![s0, a0 * (1.0 - share), tau, a0 * share, tau * ratio];
                if shape.drift() {
                    x.push(0.0);
                }
                out.push(x);
            }
        } else {
            let mut x = vec![s0, a0, tau];
            if shape.drift() {
                x.push(0.0);
            }
            out.push(x);
        }
    }
    out
}

/// Name the longer time constant `tau_s` (swap the two exponentials'
/// parameters, values and covariance, when the fit found them the other
/// way round).
fn order_taus(shape: Shape, f: Fit) -> Result<Fit> {
    if !shape.two() || f.estimates.values()[2] >= f.estimates.values()[4] {
        return Ok(f);
    }
    let n = f.estimates.len();
    let perm: Vec<usize> = (0..n)
        .map(|k| match k {
            1 => 3,
            2 => 4,
            3 => 1,
            4 => 2,
            k => k,
        })
        .collect();
    let v = DVector::from_iterator(n, perm.iter().map(|&k| f.estimates.values()[k]));
    let c = DMatrix::from_fn(n, n, |i, j| f.estimates.covariance()[(perm[i], perm[j])]);
    let estimates =
        crate::estimation::Estimates::new(f.estimates.names().to_vec(), v, c, f.estimates.dof())?;
    Ok(Fit { estimates, ..f })
}

/// Batches of the noise estimate: long against the noise's correlation
/// (a Gauss–Markov bias correlated over a tenth of a batch is 90 % in),
/// with enough degrees of freedom left after the richest curve's six
/// parameters.
pub const BATCHES: usize = 20;

/// The noise scale `m_n` of a valid run of `n` samples: a twentieth of
/// it (refused below 60 samples).
pub fn noise_scale(n: usize) -> Result<usize> {
    if n < 60 {
        return Err(Error::Unsupported(format!(
            "the longest run of consecutive valid samples after turn-on holds {n}: the noise estimate needs at least 60"
        )));
    }
    Ok(n / BATCHES)
}

/// Every shape's fit on one set of blocks, each fitted once (weights
/// from a first variance `v0`) and rescaled to the noise found later
/// (the estimates do not depend on a common variance factor).
pub struct Fits<'a> {
    blocks: &'a Blocks,
    v0: f64,
    base: Option<Vec<f64>>,
    done: Vec<(Shape, std::result::Result<Fit, String>)>,
    /// The run (sample range), the batch length and the richest fit's
    /// batch sum of squares and parameter count ([`Fits::noise`]).
    pure: Option<((usize, usize), usize, f64, usize)>,
}

impl<'a> Fits<'a> {
    /// Start with the first variance from the Hadamard variance at the
    /// block length over the run `y` (refused when the output does not
    /// scatter).
    pub fn new(blocks: &'a Blocks, y: &[f64]) -> Result<Self> {
        let v0 = long_run_variance(y, blocks.rows.min(noise_scale(y.len())?))
            .map(|v| v.0)
            .filter(|v| *v > 0.0 && v.is_finite())
            .ok_or_else(flat)?;
        let mut f = Fits {
            blocks,
            v0,
            base: None,
            done: Vec::new(),
            pure: None,
        };
        if let Ok(e) = f.raw(Shape::Exp1) {
            f.base = Some(e.estimates.values().as_slice().to_vec());
        }
        Ok(f)
    }

    /// The fit at `v0` (cached).
    fn raw(&mut self, s: Shape) -> Result<Fit> {
        if let Some((_, r)) = self.done.iter().find(|(x, _)| *x == s) {
            return r.clone().map_err(Error::Unsupported);
        }
        let r = fit_shape(s, self.blocks, self.v0, 1e9, self.base.as_deref());
        self.done.push((s, r.clone().map_err(|e| e.to_string())));
        r
    }

    /// The fit of `s` with the noise `(σ²_LR, dof)` and its lack-of-fit
    /// test ([`Fits::lack_of_fit`]).
    pub fn get(&mut self, s: Shape, noise: (f64, f64)) -> Result<Fit> {
        let mut f = self.raw(s)?;
        let k = noise.0 / self.v0;
        let e = &f.estimates;
        f.estimates = Estimates::new(
            e.names().to_vec(),
            e.values().clone(),
            e.covariance() * k,
            noise.1,
        )?;
        f.residuals /= k.sqrt();
        f.weighted_rss /= k;
        f.sigma /= k.sqrt();
        self.lack_of_fit(s, f)
    }

    /// Shape `s`'s residuals (parameters `x`) over the samples `run`.
    fn residuals(&self, s: Shape, x: &[f64], run: (usize, usize)) -> Vec<f64> {
        let b = self.blocks;
        (run.0..run.1)
            .map(|k| b.y[k] - curve(s, x, b.t[k]))
            .collect()
    }

    /// incal's lack-of-fit rule at the batch scale, against the pure
    /// error of the richest fit (`S_r`, `p_r` parameters, `N` batches):
    /// for a simpler shape the extra-sum-of-squares test
    /// `F = ((S − S_r)/(p_r − p)) / (S_r/(N − p_r))` against
    /// `F(p_r − p, N − p_r)`; for another shape the mean squares' ratio
    /// against `F(N − p, N − p_r)`. Below
    /// [`LACK_OF_FIT_ALPHA`] the covariance is scaled by the ratio of the
    /// mean squares, with `N − p` degrees of freedom. The p-value is the
    /// fit's `chi2_p_value`.
    pub fn lack_of_fit(&self, s: Shape, mut f: Fit) -> Result<Fit> {
        use statrs::distribution::{ContinuousCDF, FisherSnedecor};
        let Some((run, m, s_r, p_r)) = self.pure else {
            return Ok(f);
        };
        let x = f.estimates.values().as_slice().to_vec();
        let p = x.len();
        let n = ((run.1 - run.0) / m) as f64;
        let ss = batch_ss(&self.residuals(s, &x, run), m);
        let (ms, ms_r) = (ss / (n - p as f64), s_r / (n - p_r as f64));
        let pv = if p < p_r {
            let fstat = ((ss - s_r).max(0.0) / (p_r - p) as f64) / ms_r;
            FisherSnedecor::new((p_r - p) as f64, n - p_r as f64).map(|d| 1.0 - d.cdf(fstat))
        } else {
            FisherSnedecor::new(n - p as f64, n - p_r as f64).map(|d| 1.0 - d.cdf(ms / ms_r))
        };
        let pv = pv.unwrap_or(1.0);
        f.chi2_p_value = Some(pv);
        let ratio = ms / ms_r;
        if pv < LACK_OF_FIT_ALPHA && ratio > 1.0 {
            let e = &f.estimates;
            f.estimates = Estimates::new(
                e.names().to_vec(),
                e.values().clone(),
                e.covariance() * ratio,
                n - p as f64,
            )?;
            f.variance_factor = ratio;
            f.variance_source = VarianceSource::Residuals;
        }
        Ok(f)
    }

    /// `σ²_LR` and its degrees of freedom (module docs of [`super`]):
    /// the residuals, over the longest valid run (`run`, a sample range),
    /// of the richest shape that fits (of least cost: two exponentials and
    /// a drift unless a simpler shape fits better) in `N` batches of `m` samples (batch means, the
    /// pure error every simpler shape is tested against):
    /// `σ²_LR = m Σ r̄ⱼ² / (N − p)` with `N − p` degrees of freedom
    /// (`N` = [`BATCHES`]).
    pub fn noise(&mut self, run: (usize, usize)) -> Result<(f64, f64)> {
        let b = self.blocks;
        let y = &b.y[run.0..run.1];
        let m_n = noise_scale(y.len())?;
        // The richest fit is the one of least cost (a richer shape stuck
        // in a worse minimum than a simpler one is not the pure error).
        let mut rich: Option<(Shape, Fit)> = None;
        for s in [Shape::Exp2Drift, Shape::Exp2, Shape::Exp1Drift, Shape::Exp1] {
            if let Ok(f) = self.raw(s) {
                if rich
                    .as_ref()
                    .is_none_or(|(_, r)| f.weighted_rss < r.weighted_rss)
                {
                    rich = Some((s, f));
                }
            }
        }
        let (r, p): (Vec<f64>, usize) = match &rich {
            Some((s, f)) => {
                let x = f.estimates.values().as_slice();
                (self.residuals(*s, x, run), x.len())
            }
            None => {
                let mean = y.iter().sum::<f64>() / y.len() as f64;
                (y.iter().map(|v| v - mean).collect(), 1)
            }
        };
        let sum = batch_ss(&r, m_n);
        let dof = (r.len() / m_n - p) as f64;
        let var = m_n as f64 * sum / dof;
        if rich.is_some() {
            self.pure = Some((run, m_n, sum, p));
        }
        if var > 0.0 && var.is_finite() {
            Ok((var, dof))
        } else {
            Err(flat())
        }
    }
}

/// The batch sum of squares `Σ r̄ⱼ²` of `r` in batches of `m` samples
/// (the remainder left out).
fn batch_ss(r: &[f64], m: usize) -> f64 {
    r.chunks_exact(m)
        .map(|c| (c.iter().sum::<f64>() / m as f64).powi(2))
        .sum()
}

fn flat() -> Error {
    Error::Unsupported(
        "the output does not scatter after turn-on: its noise, which weights the fit, is zero"
            .into(),
    )
}

/// The long-run variance of one sample and its degrees of freedom from
/// the overlapping Hadamard variance of the longest valid run at `m`
/// samples (NIST SP 1065 eq. 22; Greenhall & Riley EDF, white rate
/// noise): `σ²_LR = m·HVAR(m)`, the variance of an m-sample mean times
/// m. Second differences cancel the curve's level and slope, so a smooth
/// warm-up does not enter it while `m Δt ≪ τ`.
pub fn long_run_variance(run: &[f64], m: usize) -> Option<(f64, f64)> {
    let mut x = Vec::with_capacity(run.len() + 1);
    let mut s = 0.0;
    x.push(0.0);
    for v in run {
        s += v;
        x.push(s);
    }
    let h = crate::noise::dev::ohvar(&x, m, 1.0, false)?;
    let edf = crate::noise::edf::greenhall(0, 3, m, x.len(), true, false)?;
    Some((h.var * m as f64, edf.max(1.0)))
}
