//! Noise and stability analysis: the Allan family of deviations with
//! confidence intervals, noise identification, the IEEE Std 952 noise
//! terms and bias stability.
//!
//! Data are handled as phase `x` (angle, or velocity increment, summed:
//! `x_{k+1} = x_k + y_k τ0` from rate samples `y`), so every deviation
//! follows NIST SP 1065 (Riley 2008) and Stable32 exactly. A deviation is in
//! the rate unit (x unit per second); TDEV is in the x unit.

// Before the modules, so that each of them can use it.
/// Call an `#[inline(always)]` kernel through a copy compiled for AVX2
/// when the CPU has it (the same operations in the same order, no FMA
/// contraction: the same bits, only wider registers).
macro_rules! avx2_or_not {
    ($f:ident($($a:expr),*)) => {{
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx2")]
            fn wide<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                unsafe { wide(|| $f($($a),*)) }
            } else {
                $f($($a),*)
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            $f($($a),*)
        }
    }};
}

/// `wide(args)`, a kernel written in AVX2 intrinsics (FMA where the
/// portable loop has a `mul_add`) with the portable loop's operations per
/// lane, when the CPU has AVX2 and FMA; `portable` otherwise (the same bits
/// either way).
macro_rules! avx2_kernel {
    ($wide:ident($($a:expr),*), $portable:expr) => {{
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
            {
                // SAFETY: the CPU supports AVX2 and FMA (checked just above).
                unsafe { $wide($($a),*) }
            } else {
                $portable
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            $portable
        }
    }};
}

/// `f(0), …, f(n − 1)` in order, on rayon's threads when `parallel` and
/// `n > 1`: the same values either way, the fixed partition by which
/// every kernel here gives a parallel run a serial run's bits.
pub(crate) fn ordered_map<T: Send>(
    n: usize,
    parallel: bool,
    f: impl Fn(usize) -> T + Sync + Send,
) -> Vec<T> {
    use rayon::prelude::*;
    if parallel && n > 1 {
        (0..n).into_par_iter().map(f).collect()
    } else {
        (0..n).map(f).collect()
    }
}

pub mod corr;
pub mod dev;
pub mod edf;
mod point;
use point::{point, push, Point};
pub mod id;
pub mod markov;
pub mod minimum;
pub mod other_stats;
pub mod terms;

/// The former path of [`other_stats`], kept for its callers.
pub use other_stats as more;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The averaging factors m (τ = m·τ0) to evaluate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TauGrid {
    /// m = 1, 2, 4, 8, … (Stable32 "octave").
    Octave,
    /// m = 1, 2, 4, 10, 20, 40, 100, … (Stable32 "decade").
    Decade,
    /// Every m = 1, 2, 3, ….
    All,
    /// `k` points per decade, m = round(10^(j/k)), duplicates dropped.
    PerDecade(u32),
}

impl TauGrid {
    /// Parse `octave|decade|all|N`.
    pub fn parse(s: &str) -> Option<TauGrid> {
        match s {
            "octave" => Some(TauGrid::Octave),
            "decade" => Some(TauGrid::Decade),
            "all" => Some(TauGrid::All),
            n => n
                .parse::<u32>()
                .ok()
                .filter(|&k| (1..=1000).contains(&k))
                .map(TauGrid::PerDecade),
        }
    }

    /// The averaging factors for `n_phase` phase points: every m with
    /// `m ≤ (n_phase − 1)/4` (Stable32's limit, so each deviation rests on
    /// at least a quarter of the record), in increasing order.
    pub fn factors(&self, n_phase: usize) -> Vec<usize> {
        let max = n_phase.saturating_sub(1) / 4;
        let mut out = Vec::new();
        match *self {
            TauGrid::Octave => {
                let mut m = 1;
                while m <= max {
                    out.push(m);
                    m *= 2;
                }
            }
            TauGrid::Decade => {
                let mut dec = 1;
                'o: loop {
                    for k in [1, 2, 4] {
                        let m = k * dec;
                        if m > max {
                            break 'o;
                        }
                        out.push(m);
                    }
                    dec *= 10;
                }
            }
            TauGrid::All => out.extend(1..=max),
            TauGrid::PerDecade(k) => {
                let mut j = 0;
                loop {
                    let m = 10f64.powf(j as f64 / k as f64).round() as usize;
                    if m > max {
                        break;
                    }
                    if out.last() != Some(&m) {
                        out.push(m);
                    }
                    j += 1;
                }
            }
        }
        out
    }
}

/// The deviations computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Deviation {
    /// Overlapping Allan deviation.
    Oadev,
    /// Modified Allan deviation.
    Mdev,
    /// Overlapping Hadamard deviation.
    Ohdev,
    /// Time deviation (x unit).
    Tdev,
    /// Total deviation.
    Totdev,
}

impl Deviation {
    /// Every deviation, in the document's order.
    pub const ALL: [Deviation; 5] = [
        Deviation::Oadev,
        Deviation::Mdev,
        Deviation::Ohdev,
        Deviation::Tdev,
        Deviation::Totdev,
    ];
    /// Key in the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Deviation::Oadev => "oadev",
            Deviation::Mdev => "mdev",
            Deviation::Ohdev => "ohdev",
            Deviation::Tdev => "tdev",
            Deviation::Totdev => "totdev",
        }
    }
}

/// One deviation at every τ of a grid: value, χ² bounds, EDF and terms
/// (`None` where not defined or not available).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct DevSeries {
    /// The deviation.
    pub value: Vec<Option<f64>>,
    /// Lower bound at the confidence level.
    pub lo: Vec<Option<f64>>,
    /// Upper bound at the confidence level.
    pub hi: Vec<Option<f64>>,
    /// Equivalent degrees of freedom.
    pub edf: Vec<Option<f64>>,
    /// Number of terms summed.
    pub n: Vec<usize>,
}

/// Options of [`stability`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityOptions {
    /// Sample interval τ0 (s).
    pub tau0_s: f64,
    /// The τ grid.
    pub grid: TauGrid,
    /// Confidence of the bounds (Stable32's default 0.683).
    pub confidence: f64,
    /// Split each sum over rayon (results identical either way).
    pub parallel: bool,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        Self {
            tau0_s: 1.0,
            grid: TauGrid::Octave,
            confidence: 0.683,
            parallel: true,
        }
    }
}

/// The stability of one record at every τ of the grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stability {
    /// Averaging factors m.
    pub m: Vec<usize>,
    /// τ = m·τ0 (s).
    pub taus_s: Vec<f64>,
    /// Noise exponent α of S_y identified at each τ (Allan family), by
    /// the method in `id_method` ([`id`] module docs).
    pub alpha: Vec<Option<i32>>,
    /// Noise exponent with up to three differences (Hadamard; where the
    /// B1 ratio identified the noise, the Allan family's α).
    pub alpha_hadamard: Vec<Option<i32>>,
    /// How α was identified at each τ: lag-1 autocorrelation where the
    /// decimated record has at least [`id::MIN_POINTS`] points, the B1
    /// ratio (and R(n) for phase noise) where it has fewer.
    pub id_method: Vec<Option<id::IdMethod>>,
    /// Overlapping Allan deviation.
    pub oadev: DevSeries,
    /// Modified Allan deviation.
    pub mdev: DevSeries,
    /// Overlapping Hadamard deviation.
    pub ohdev: DevSeries,
    /// Time deviation.
    pub tdev: DevSeries,
    /// Total deviation.
    pub totdev: DevSeries,
}

impl Stability {
    /// A stability at factors `ms` (τ = m·τ0) with nothing filled in yet.
    fn empty(ms: &[usize], tau0_s: f64) -> Self {
        Stability {
            m: ms.to_vec(),
            taus_s: ms.iter().map(|&m| m as f64 * tau0_s).collect(),
            alpha: Vec::new(),
            alpha_hadamard: Vec::new(),
            id_method: Vec::new(),
            oadev: DevSeries::default(),
            mdev: DevSeries::default(),
            ohdev: DevSeries::default(),
            tdev: DevSeries::default(),
            totdev: DevSeries::default(),
        }
    }

    /// The series of deviation `d`.
    pub fn series(&self, d: Deviation) -> &DevSeries {
        match d {
            Deviation::Oadev => &self.oadev,
            Deviation::Mdev => &self.mdev,
            Deviation::Ohdev => &self.ohdev,
            Deviation::Tdev => &self.tdev,
            Deviation::Totdev => &self.totdev,
        }
    }

    fn series_mut(&mut self, d: Deviation) -> &mut DevSeries {
        match d {
            Deviation::Oadev => &mut self.oadev,
            Deviation::Mdev => &mut self.mdev,
            Deviation::Ohdev => &mut self.ohdev,
            Deviation::Tdev => &mut self.tdev,
            Deviation::Totdev => &mut self.totdev,
        }
    }
}

/// Rate samples whose mean is the constant [`phase_from_rate`] removes:
/// the first `PHASE_REF_SAMPLES` (or all, if fewer).
pub const PHASE_REF_SAMPLES: usize = 1 << 16;

/// A statistic beyond the default five ([`more`]), named as in the
/// document and `--deviations`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Statistic {
    /// Non-overlapping Allan deviation.
    Adev,
    /// Non-overlapping Hadamard deviation.
    Hdev,
    /// Modified total deviation.
    Mtotdev,
    /// Hadamard total deviation.
    Htotdev,
    /// Theo1 deviation (τ = 0.75·m·τ0, no bias correction).
    Theo1,
    /// TheoH: OADEV below a tenth of the record, bias-removed Theo1
    /// (TheoBR) from there on.
    Theoh,
    /// Maximum time interval error (phase unit; angle data).
    Mtie,
    /// Time interval error, rms (phase unit; angle data).
    Tierms,
}

impl Statistic {
    /// Every statistic, in the document's order.
    pub const ALL: [Statistic; 8] = [
        Statistic::Adev,
        Statistic::Hdev,
        Statistic::Mtotdev,
        Statistic::Htotdev,
        Statistic::Theo1,
        Statistic::Theoh,
        Statistic::Mtie,
        Statistic::Tierms,
    ];
    /// Key in the JSON and in `--deviations`.
    pub fn as_str(self) -> &'static str {
        match self {
            Statistic::Adev => "adev",
            Statistic::Hdev => "hdev",
            Statistic::Mtotdev => "mtotdev",
            Statistic::Htotdev => "htotdev",
            Statistic::Theo1 => "theo1",
            Statistic::Theoh => "theoh",
            Statistic::Mtie => "mtie",
            Statistic::Tierms => "tierms",
        }
    }
    /// The statistic named `s`.
    pub fn parse(s: &str) -> Option<Statistic> {
        Statistic::ALL.into_iter().find(|d| d.as_str() == s)
    }
    /// A time-interval error (of phase, not a frequency deviation).
    pub fn is_time_error(self) -> bool {
        matches!(self, Statistic::Mtie | Statistic::Tierms)
    }
}

/// One statistic on its own τ grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Averaging times (s).
    pub taus_s: Vec<f64>,
    /// Values, bounds, EDF and terms at each τ.
    pub dev: DevSeries,
    /// Averaging times of the grid left out: an O(N·m) statistic stops
    /// where its next τ would pass [`more::MAX_WORK`] operations.
    pub left_out: usize,
}

/// Statistic `s` of phase record `x` on the grid of `st` (the stability
/// of the same record; its α gives the EDF):
/// - ADEV and HDEV at every factor of `st`, EDF from Greenhall & Riley for
///   the non-overlapping estimators;
/// - MTOTDEV and HTOTDEV at the factors up to N/3, with the EDF of MVAR and
///   OHVAR respectively (a lower bound: the total estimators average
///   more; the bounds are conservative);
/// - Theo1 at even factors from 2 to N − 1 on the grid's spacing, τ =
///   0.75·m·τ0, EDF from [`edf::theo1`] with the α identified nearest in
///   τ;
/// - TheoH (Howe & Tasset 2006; SP 1065 §5.2.16): OADEV of `st` at the
///   factors below N/10, then TheoBR = k·Theo1 ([`more::theobr_bias`]) at
///   Theo1's factors with 0.75·m ≥ N/10, Theo1's EDF (the bias factor, a
///   mean of n + 1 ratios, is taken as exact); no TheoBR value below 120
///   points;
/// - MTIE and TIE rms at every factor of `st`, values and n only.
///
/// MTOTDEV, HTOTDEV, Theo1 and TheoH stop at the last τ within
/// [`more::MAX_WORK`] operations ([`Series::left_out`] counts the rest).
pub fn statistic(
    x: &[f64],
    s: Statistic,
    st: &Stability,
    opts: &StabilityOptions,
) -> Result<Series> {
    let n = x.len();
    let t0 = opts.tau0_s;
    let p = opts.confidence;
    let ms: Vec<usize> = match s {
        Statistic::Mtotdev | Statistic::Htotdev => {
            st.m.iter().copied().filter(|&m| 3 * m <= n).collect()
        }
        Statistic::Theo1 | Statistic::Theoh => {
            let mut v: Vec<usize> = opts
                .grid
                .factors(4 * n.saturating_sub(1) + 1)
                .into_iter()
                .map(|m| m.max(2).next_multiple_of(2))
                .filter(|&m| m < n)
                .collect();
            v.dedup();
            if s == Statistic::Theoh {
                // TheoBR from a tenth of the record on.
                v.retain(|&m| 0.75 * m as f64 >= (n / 10) as f64);
            }
            v
        }
        _ => st.m.clone(),
    };
    // TheoH's bias factor first (Theo1: 1), within half the budget (averaged in
    // blocks where the exact sum would pass it).
    let (bias, budget) = if s == Statistic::Theoh {
        let ba = more::theobr_block(n, more::MAX_WORK / 2.0);
        (
            more::theobr_bias(x, ba, opts.parallel),
            more::MAX_WORK - more::theobr_work(n / ba),
        )
    } else {
        (Some(1.0), more::MAX_WORK)
    };
    // The longest prefix of the grid within the budget (only MTOTDEV,
    // HTOTDEV, Theo1 and TheoH cost N·m per τ).
    let mut keep = ms.len();
    for k in 1..=ms.len() {
        if more::work(s.as_str(), n, &ms[..k]) > budget {
            keep = k - 1;
            break;
        }
    }
    let left_out = ms.len() - keep;
    let ms = &ms[..keep];
    let alpha_at = |m: usize, hadamard: bool| {
        st.m.iter().position(|&k| k == m).and_then(|k| {
            if hadamard {
                st.alpha_hadamard[k]
            } else {
                st.alpha[k]
            }
        })
    };
    // The α identified nearest (in log τ) to Theo1's τ = 0.75·m·τ0.
    let alpha_near = |m: usize| {
        let target = (0.75 * m as f64).ln();
        st.m.iter()
            .zip(&st.alpha)
            .filter_map(|(&k, a)| a.map(|a| (((k as f64).ln() - target).abs(), a)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, a)| a)
    };
    let mut out = Series {
        taus_s: Vec::new(),
        dev: DevSeries::default(),
        left_out,
    };
    if s == Statistic::Theoh {
        // OADEV, as computed for the main grid, below a tenth of the record.
        for (k, &m) in st.m.iter().enumerate() {
            if m >= n / 10 {
                break;
            }
            out.taus_s.push(st.taus_s[k]);
            out.dev.value.push(st.oadev.value[k]);
            out.dev.lo.push(st.oadev.lo[k]);
            out.dev.hi.push(st.oadev.hi[k]);
            out.dev.edf.push(st.oadev.edf[k]);
            out.dev.n.push(st.oadev.n[k]);
        }
    }
    for &m in ms {
        let tau = m as f64 * t0;
        let pair = |v: Option<dev::VarN>| v.map(|v| (v.var, v.n));
        let (v, edf, tau_s) = match s {
            Statistic::Adev => (
                pair(more::avar(x, m, t0)),
                alpha_at(m, false).and_then(|a| edf::greenhall(a, 2, m, n, false, false)),
                tau,
            ),
            Statistic::Hdev => (
                pair(more::hvar(x, m, t0)),
                alpha_at(m, true).and_then(|a| edf::greenhall(a, 3, m, n, false, false)),
                tau,
            ),
            Statistic::Mtotdev => (
                pair(more::mtotvar(x, m, t0, opts.parallel)),
                alpha_at(m, false).and_then(|a| edf::greenhall(a, 2, m, n, true, true)),
                tau,
            ),
            Statistic::Htotdev => (
                pair(more::htotvar(x, m, t0, opts.parallel)),
                alpha_at(m, true).and_then(|a| edf::greenhall(a, 3, m, n, true, false)),
                tau,
            ),
            // TheoH's TheoBR part is Theo1 times the bias factor (exactly
            // Theo1 for a factor of 1).
            Statistic::Theo1 | Statistic::Theoh => (
                bias.and_then(|b| {
                    more::theo1var(x, m, t0, opts.parallel).map(|v| (b * v.var, v.n))
                }),
                alpha_near(m).and_then(|a| edf::theo1(a, m, n)),
                0.75 * tau,
            ),
            Statistic::Mtie => (more::mtie(x, m).map(|(d, k)| (d * d, k)), None, tau),
            Statistic::Tierms => (more::tierms(x, m).map(|(d, k)| (d * d, k)), None, tau),
        };
        out.taus_s.push(tau_s);
        push(&mut out.dev, v, edf, p);
    }
    Ok(out)
}

/// The three-cornered hat (SP 1065 §8.2; Gray & Allan, 1974): three
/// instruments recorded together, phase records `x` of equal length; from
/// the OADEV of the three pairwise differences,
/// `σ²_a = ½(σ²_ab + σ²_ac − σ²_bc)` and likewise for b and c, at every τ of
/// the grid. Bounds from the Satterthwaite EDF of that combination,
/// `ν = 2(Σ cᵢsᵢ)² / Σᵢⱼ cᵢcⱼ·2Cᵢⱼ²/√(νᵢνⱼ)`, sᵢ the pair variances with
/// EDF νᵢ (from each pair's identified noise) and Cᵢⱼ their covariance
/// (two pairs share one instrument, whose estimated variance it is):
/// approximate bounds, their coverage measured in the tests. A negative
/// estimate (an instrument quieter than the other two can resolve) has no
/// value (`None`).
pub fn three_cornered_hat(x: [&[f64]; 3], opts: &StabilityOptions) -> Result<[Series; 3]> {
    let n = x[0].len();
    if x.iter().any(|v| v.len() != n) {
        return Err(Error::Unsupported(
            "three-cornered hat: the three records differ in length".into(),
        ));
    }
    let diff = |a: usize, b: usize| -> Vec<f64> { (0..n).map(|i| x[a][i] - x[b][i]).collect() };
    let pairs = [diff(0, 1), diff(0, 2), diff(1, 2)];
    let st: Vec<Stability> = pairs
        .iter()
        .map(|p| stability(p, opts))
        .collect::<Result<_>>()?;
    // Coefficients of (ab, ac, bc) for a, b, c.
    let coef = [[0.5, 0.5, -0.5], [0.5, -0.5, 0.5], [-0.5, 0.5, 0.5]];
    let mut out: [Series; 3] = std::array::from_fn(|_| Series {
        taus_s: st[0].taus_s.clone(),
        dev: DevSeries::default(),
        left_out: 0,
    });
    for k in 0..st[0].m.len() {
        let pair: Option<Vec<(f64, f64, usize)>> = st
            .iter()
            .map(|p| {
                let v = p.oadev.value[k]?;
                Some((v * v, p.oadev.edf[k].filter(|e| *e > 0.0)?, p.oadev.n[k]))
            })
            .collect();
        let Some(pair) = pair else {
            for o in &mut out {
                push(&mut o.dev, None, None, opts.confidence);
            }
            continue;
        };
        let est: Vec<f64> = coef
            .iter()
            .map(|c| c.iter().zip(&pair).map(|(ci, p)| ci * p.0).sum())
            .collect();
        // Covariance of the pair differences: each pair's variance on the
        // diagonal; two pairs share one instrument, whose variance is their
        // covariance (its sign squares away).
        let cov = |i: usize, j: usize| -> f64 {
            match (i.min(j), i.max(j)) {
                (i, j) if i == j => pair[i].0,
                (0, 1) => est[0].max(0.0),
                (0, 2) => est[1].max(0.0),
                _ => est[2].max(0.0),
            }
        };
        for (x, c) in coef.iter().enumerate() {
            // Var(Σ cᵢ sᵢ) for Gaussian sᵢ: Σᵢⱼ cᵢcⱼ·2Cᵢⱼ²/√(νᵢνⱼ).
            let mut var_est = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    var_est +=
                        c[i] * c[j] * 2.0 * cov(i, j).powi(2) / (pair[i].1 * pair[j].1).sqrt();
                }
            }
            let edf = (var_est > 0.0 && est[x] > 0.0).then(|| 2.0 * est[x] * est[x] / var_est);
            push(
                &mut out[x].dev,
                Some((est[x], pair[0].2)),
                edf,
                opts.confidence,
            );
        }
    }
    Ok(out)
}

/// The constant `c` removed from every rate sample before the running sum:
/// the mean of the first [`PHASE_REF_SAMPLES`] samples `y(0), …`, summed in
/// order (0 for no samples).
///
/// Any constant only adds the linear phase `(ȳ − c)·t` to `x`, to which
/// every deviation here (second and third differences, TOTDEV's inverted
/// reflection), the noise identification (quadratic detrend) and bias
/// stability (standard deviation of τ-averages) are blind. A constant near
/// the mean keeps that line, and so the running sum's round-off, small;
/// taking it from the start of the record (not the whole-record mean) lets
/// the phase be built in the one pass that reads the record.
pub fn phase_reference(n: usize, y: impl Fn(usize) -> f64) -> f64 {
    let k = n.min(PHASE_REF_SAMPLES);
    if k == 0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..k {
        sum += y(i);
    }
    sum / k as f64
}

/// Phase from rate samples (NIST SP 1065 §5.2, frequency to phase):
/// `x_0 = 0`, `x_{k+1} = x_k + (y_k − c) τ0`, `c` from [`phase_reference`]
/// (n + 1 points, in the rate unit × s).
pub fn phase_from_rate(y: &[f64], tau0: f64) -> Vec<f64> {
    phase_from_rate_with(y.len(), tau0, |i| y[i])
}

/// As [`phase_from_rate`] with the rate samples `y(0), …, y(n−1)` read
/// through a function, once (and the first [`PHASE_REF_SAMPLES`] once
/// more for `c`), e.g. straight from a memory-mapped file.
pub fn phase_from_rate_with(n: usize, tau0: f64, y: impl Fn(usize) -> f64) -> Vec<f64> {
    let c = phase_reference(n, &y);
    let mut x = vec![0.0; n + 1];
    phase_fill(&mut x[1..], 0.0, c, tau0, y);
    x
}

/// The running sum of [`phase_from_rate`] over one stretch of the record:
/// `out[i] = acc + Σ_{j≤i} (y(j) − c) τ0` (`y(j)` the stretch's j-th
/// sample); returns the sum at its end, the `acc` of the next stretch.
/// Filled stretch by stretch, the phase has the same bits as in one pass.
pub fn phase_fill(
    out: &mut [f64],
    mut acc: f64,
    c: f64,
    tau0: f64,
    y: impl Fn(usize) -> f64,
) -> f64 {
    for (i, o) in out.iter_mut().enumerate() {
        acc += (y(i) - c) * tau0;
        *o = acc;
    }
    acc
}

/// Every deviation of phase record `x` at every τ of the grid, with the
/// noise identified per τ, Greenhall & Riley EDF and χ² bounds.
/// Fails on fewer than 5 points, a non-finite sample, τ0 ≤ 0 or a
/// confidence outside (0, 1).
pub fn stability(x: &[f64], opts: &StabilityOptions) -> Result<Stability> {
    stability_with_progress(x, opts, &|_| {})
}

/// As [`stability`], calling `tick(k)` after the k-th τ (for a progress
/// bar).
pub fn stability_with_progress(
    x: &[f64],
    opts: &StabilityOptions,
    tick: &(dyn Fn(usize) + Sync),
) -> Result<Stability> {
    check_record(x, opts)?;
    stability_run(x, opts.grid.factors(x.len()), opts, tick)
}

/// As [`stability`] at the averaging factors `ms` instead of the grid's
/// (e.g. another program's τ list; a factor too large for a deviation
/// gives `None` there). `opts.grid` is not used. Fails as [`stability`],
/// and on a factor of 0.
pub fn stability_at(x: &[f64], ms: &[usize], opts: &StabilityOptions) -> Result<Stability> {
    if ms.contains(&0) {
        return Err(Error::InvalidValue {
            what: "averaging factor".into(),
            value: "0".into(),
        });
    }
    check_record(x, opts)?;
    stability_run(x, ms.to_vec(), opts, &|_| {})
}

/// The stability of a record with gaps, given as its contiguous stretches
/// `segs` (phase records, each at least 5 points; a gap between any two):
/// every term that would straddle a gap is left out, which is the same as
/// pooling each stretch's sums.
///
/// At each τ of the grid (the factors of the longest stretch), for OADEV,
/// MDEV, TDEV and OHDEV: `σ² = Σₛ nₛ σₛ² / Σₛ nₛ` over the stretches that
/// hold a term (`n` = Σₛ nₛ, the terms kept), with the Satterthwaite EDF
/// of that weighted mean of independent χ² estimates,
/// `EDF = (Σₛ nₛ)² / Σₛ (nₛ² / EDFₛ)`, and χ² bounds from it. The noise
/// is identified on each stretch; α at a τ is that of the longest stretch
/// identified there. TOTDEV, which extends the record by reflection at its
/// ends, is not defined across a gap: left empty (`None`, n = 0).
pub fn stability_segments(
    segs: &[Vec<f64>],
    opts: &StabilityOptions,
    tick: &(dyn Fn(usize) + Sync),
) -> Result<Stability> {
    let longest = segs.iter().map(Vec::len).max().unwrap_or(0);
    if longest < 5 {
        return Err(Error::Unsupported(format!(
            "noise: the longest stretch between gaps has {longest} points; at least 5 are needed for one τ"
        )));
    }
    for s in segs {
        check_record(s, opts)?;
    }
    let ms = opts.grid.factors(longest);
    // Longest first: α is taken from the first stretch that has it.
    let mut order: Vec<usize> = (0..segs.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(segs[i].len()));
    let parts: Vec<Stability> = order
        .iter()
        .map(|&i| {
            let s = &segs[i];
            let fit: Vec<usize> = ms.iter().copied().filter(|&m| 2 * m < s.len()).collect();
            stability_run(s, fit, opts, &|_| {})
        })
        .collect::<Result<_>>()?;
    let p = opts.confidence;
    let mut st = Stability::empty(&ms, opts.tau0_s);
    for (k, _) in ms.iter().enumerate() {
        // Stretch parts hold a prefix of the factors: index k where present.
        let at = |s: &Stability| (k < s.m.len()).then_some(k);
        let first = parts
            .iter()
            .find_map(|s| at(s).and_then(|j| s.alpha[j].map(|_| (s, j))));
        st.alpha.push(first.and_then(|(s, j)| s.alpha[j]));
        st.alpha_hadamard
            .push(first.and_then(|(s, j)| s.alpha_hadamard[j]));
        st.id_method.push(first.and_then(|(s, j)| s.id_method[j]));
        for d in [
            Deviation::Oadev,
            Deviation::Mdev,
            Deviation::Ohdev,
            Deviation::Tdev,
        ] {
            let (mut n, mut sum, mut den, mut edf_ok) = (0usize, 0.0, 0.0, true);
            for s in &parts {
                let Some(j) = at(s) else { continue };
                let ser = s.series(d);
                let (Some(v), nj) = (ser.value[j], ser.n[j]) else {
                    continue;
                };
                if nj == 0 {
                    continue;
                }
                n += nj;
                sum += nj as f64 * v * v;
                match ser.edf[j] {
                    Some(e) if e > 0.0 => den += (nj * nj) as f64 / e,
                    _ => edf_ok = false,
                }
            }
            let pooled = (n > 0).then(|| (sum / n as f64, n));
            let edf = (n > 0 && edf_ok && den > 0.0).then(|| (n * n) as f64 / den);
            push(st.series_mut(d), pooled, edf, p);
        }
        push(&mut st.totdev, None, None, p);
        tick(k + 1);
    }
    Ok(st)
}

fn check_record(x: &[f64], opts: &StabilityOptions) -> Result<()> {
    if x.len() < 5 {
        return Err(Error::Unsupported(format!(
            "noise: {} samples; at least 5 are needed for one τ",
            x.len()
        )));
    }
    if !(opts.tau0_s > 0.0 && opts.tau0_s.is_finite()) {
        return Err(Error::InvalidValue {
            what: "sample interval tau0 (s)".into(),
            value: opts.tau0_s.to_string(),
        });
    }
    if !(opts.confidence > 0.0 && opts.confidence < 1.0) {
        return Err(Error::InvalidValue {
            what: "confidence".into(),
            value: opts.confidence.to_string(),
        });
    }
    if let Some(k) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::InvalidValue {
            what: format!("sample {}", k + 1),
            value: x[k].to_string(),
        });
    }
    Ok(())
}

fn stability_run(
    x: &[f64],
    ms: Vec<usize>,
    opts: &StabilityOptions,
    tick: &(dyn Fn(usize) + Sync),
) -> Result<Stability> {
    let n = x.len();
    let (t0, p, par) = (opts.tau0_s, opts.confidence, opts.parallel);
    let mut st = Stability::empty(&ms, t0);
    // The noise identification and the variances read the record
    // independently: side by side when parallel.
    let (ids, vars) = if par {
        rayon::join(
            || id::identify_many(x, &ms, par),
            || dev::stability_vars(x, &ms, t0, par),
        )
    } else {
        (
            id::identify_many(x, &ms, par),
            dev::stability_vars(x, &ms, t0, par),
        )
    };
    let dev::StabilityVars {
        oa: oas,
        oh: ohs,
        tot: tots,
        md: mvs,
    } = vars;
    // B1 and R(n) where the lag-1 method has too few points.
    let fall: Vec<usize> = (0..ms.len()).filter(|&k| ids[k].is_none()).collect();
    let fm: Vec<usize> = fall.iter().map(|&k| ms[k]).collect();
    let mut b1var = vec![None; ms.len()];
    for (&k, v) in fall.iter().zip(id::b1_overlapping_many(x, &fm, par)) {
        b1var[k] = v;
    }
    let mut last: Option<(id::NoiseId, id::IdMethod)> = None;
    for (k, &m) in ms.iter().enumerate() {
        let found = match ids[k] {
            Some(nid) => Some((nid, id::IdMethod::Lag1)),
            None => {
                let mt = m as f64 * t0;
                oas[k].filter(|o| o.var > 0.0).and_then(|o| {
                    let b1 = b1var[k]? / (mt * mt) / o.var;
                    let rn = mvs[k].map(|v| v.var / o.var);
                    id::b1_rn(b1, (n - 1) / m, rn, m).map(|(a, how)| {
                        let nid = id::NoiseId {
                            alpha_allan: a,
                            alpha_hadamard: a,
                        };
                        (nid, how)
                    })
                })
            }
        };
        // Where neither method applies (a τ without an Allan variance),
        // the last identified noise.
        let found = found.or(last);
        last = found;
        let nid = found.map(|f| f.0);
        st.alpha.push(nid.map(|n| n.alpha_allan));
        st.alpha_hadamard.push(nid.map(|n| n.alpha_hadamard));
        st.id_method.push(found.map(|f| f.1));
    }
    // The EDF and χ² bounds of every deviation at every τ: each τ on its
    // own (the same values serial or parallel, in τ order).
    let at = |k: usize| -> [Point; 5] {
        let m = ms[k];
        let (aa, ah) = (st.alpha[k], st.alpha_hadamard[k]);
        let pair = |v: Option<dev::VarN>| v.map(|v| (v.var, v.n));
        let mv = mvs[k];
        let medf = aa.and_then(|a| edf::greenhall(a, 2, m, n, true, true));
        let tau = m as f64 * t0;
        [
            point(
                pair(oas[k]),
                aa.and_then(|a| edf::greenhall(a, 2, m, n, true, false)),
                p,
            ),
            point(pair(mv), medf, p),
            point(mv.map(|v| (dev::tvar(v.var, tau), v.n)), medf, p),
            point(
                pair(ohs[k]),
                ah.and_then(|a| edf::greenhall(a, 3, m, n, true, false)),
                p,
            ),
            point(pair(tots[k]), aa.and_then(|a| edf::totdev(a, m, n)), p),
        ]
    };
    let points: Vec<[Point; 5]> = if par {
        use rayon::prelude::*;
        (0..ms.len()).into_par_iter().map(at).collect()
    } else {
        (0..ms.len()).map(at).collect()
    };
    for (k, [oa, md, td, oh, tot]) in points.into_iter().enumerate() {
        oa.push_to(&mut st.oadev);
        md.push_to(&mut st.mdev);
        td.push_to(&mut st.tdev);
        oh.push_to(&mut st.ohdev);
        tot.push_to(&mut st.totdev);
        tick(k + 1);
    }
    Ok(st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_phase_filled_stretch_by_stretch_has_the_one_pass_bits() {
        // Longer than the reference stretch, with a large offset and a drift,
        // so c is not the whole-record mean.
        let n = PHASE_REF_SAMPLES + 12_345;
        let y: Vec<f64> = (0..n)
            .map(|i| 1e3 + 1e-4 * i as f64 + ((i * 7919) % 101) as f64 / 50.0)
            .collect();
        let tau0 = 0.01;
        let x = phase_from_rate(&y, tau0);
        assert_eq!(x.len(), n + 1);
        assert_eq!(x[0], 0.0);
        let c = phase_reference(n, |i| y[i]);
        let first: f64 = y[..PHASE_REF_SAMPLES].iter().sum::<f64>() / PHASE_REF_SAMPLES as f64;
        assert_eq!(c, first);
        // Stretches of uneven lengths, as a reader's windows.
        let mut z = vec![0.0; n + 1];
        let (mut at, mut acc) = (0, 0.0);
        for len in [1, 999, 4096, 70_000].iter().cycle() {
            if at == n {
                break;
            }
            let b = (at + len).min(n);
            acc = phase_fill(&mut z[1 + at..1 + b], acc, c, tau0, |i| y[at + i]);
            at = b;
        }
        assert_eq!(x, z);
        // The definition, x_{k+1} = x_k + (y_k − c)τ0, written out.
        let mut s = 0.0;
        for k in 0..n {
            s += (y[k] - c) * tau0;
            assert_eq!(x[k + 1], s);
        }
        // A short record takes every sample's mean.
        assert_eq!(phase_reference(3, |i| [1.0, 2.0, 6.0][i]), 3.0);
        assert_eq!(phase_reference(0, |_| f64::NAN), 0.0);
    }
}
