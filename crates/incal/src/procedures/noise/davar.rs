//! The dynamic Allan variance (`davar: "WINDOW_S,STEP_S"`): the
//! overlapping Allan deviation of every window `WINDOW_S` long, one window
//! every `STEP_S`, and a test of whether the windows agree.
//!
//! A stationary noise has one Allan variance; a sensor whose noise changes
//! along the record (warm-up, a vibration that comes and goes, a loop that
//! loses lock) has one per stretch, and the whole-record curve is their
//! average. The dynamic Allan variance (Galleani & Tavella, "The dynamic
//! Allan variance", IEEE Trans. UFFC 56(3), 2009) shows the change as a
//! surface over time and τ.
//!
//! Per window, at the octave factors m with `4m ≤ W` (W samples per
//! window): σ̂²(τ) by [`crate::noise::dev::oavar_many`], its EDF ν by
//! Greenhall & Riley ([`crate::noise::edf::greenhall`], the noise exponent
//! α the whole record identified at the nearest τ) and χ² bounds at the
//! noise options' `confidence` ([`crate::noise::edf::chi2_bounds`]).
//!
//! The test reads each estimate with the least EDF over α and every
//! redder noise (α − 1, …, −2), and leaves out τ0: a long-τ identification
//! can be off by a step or more (a white FM read as white PM at τ = W/4
//! would have an EDF 350 times too large, which alone raised false alarms
//! to one record in five), and at m = 1 Greenhall's EDF of a white FM is
//! 18 % above the estimate's (3205 against 2722 measured over 4000
//! records of 4096 samples), while from m = 2 it is below.
//!
//! **Stationarity test.** Windows that do not overlap (every
//! `⌈W/S⌉`-th, from the first) give independent estimates `νᵢσ̂ᵢ²/σ² ~ χ²_νᵢ`
//! under a stationary noise. At each τ from 2τ0 where all K of them have ν ≥ 2,
//! Bartlett's statistic for the homogeneity of variances,
//! `M = N ln s̄² − Σ νᵢ ln σ̂ᵢ²` with `N = Σ νᵢ`, `s̄² = Σ νᵢσ̂ᵢ²/N`, divided by
//! `C = 1 + (Σ 1/νᵢ − 1/N)/(3(K − 1))`, is χ² with K − 1 degrees of freedom
//! (M. S. Bartlett, "Properties of sufficiency and statistical tests",
//! Proc. R. Soc. A 160, 1937). The τ are tested together at a family-wise
//! false-alarm rate of [`FALSE_ALARM`] per channel (Bonferroni: each at
//! `FALSE_ALARM / T` over T averaging times); a channel where any τ
//! rejects gets a `non-stationary` warning naming the τ, the spread of the
//! windows' ADEV and the p-value.
//!
//! In the document, per channel, `channels.NAME.davar` holds `window_s`,
//! `step_s`, `window_samples`, `step_samples`, `windows`, `start_s` (each
//! window's start from the first sample), `taus_s`, `adev` (windows × τ,
//! input unit, null where not defined), `unit`, `confidence` and `test`
//! (`false_alarm`, `windows_compared`, `taus` as `{tau_s, statistic, dof,
//! p_value}`, `p_threshold`, `non_stationary`; null with fewer than two
//! windows that do not overlap, and `reason`). The table `davar.NAME` has a
//! row per window and τ: `start_s`, `tau_s`, `adev`, `lo`, `hi`, `edf`.

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::document::{Cell, Table};
use crate::error::{Error, Result};
use crate::noise::Stability;
use crate::units::Unit;
use crate::warning::{Warning, WarningCode};

/// Family-wise false-alarm rate of the stationarity test, per channel.
pub const FALSE_ALARM: f64 = 0.01;

/// The most windows of a channel (the table holds a row per window and τ).
pub const MAX_WINDOWS: usize = 1000;

/// The most samples read over all windows of a channel (windows × window
/// length): beyond this a longer step is asked for.
pub const MAX_READ: usize = 1 << 31;

/// The dynamic Allan variance's option (flattened into the noise options).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct DavarOptions {
    /// Dynamic Allan variance: `WINDOW_S,STEP_S`, the OADEV of every
    /// window WINDOW_S seconds long, one window every STEP_S seconds
    /// (e.g. `600,60`), and a test of whether they agree.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub davar: Option<String>,
}

impl DavarOptions {
    /// The window and step (s), `None` without `davar`; an error names the
    /// key and says what is wrong.
    pub fn spec(&self) -> Result<Option<(f64, f64)>> {
        let Some(s) = &self.davar else {
            return Ok(None);
        };
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let nums: Vec<Option<f64>> = parts.iter().map(|p| p.parse::<f64>().ok()).collect();
        match nums.as_slice() {
            [Some(w), Some(st)] if w.is_finite() && st.is_finite() && *w > 0.0 && *st > 0.0 => {
                Ok(Some((*w, *st)))
            }
            _ => crate::options::invalid(
                "davar",
                format!(
                    "WINDOW_S,STEP_S: two positive numbers of seconds (e.g. 600,60), got '{s}'"
                ),
            ),
        }
    }

    /// Syntax check (names the key).
    pub fn validate(&self) -> Result<()> {
        self.spec().map(|_| ())
    }

    /// The dynamic Allan variance of the channel whose phase is `x`
    /// (sample period `tau0_s`, its whole-record stability `st` for α),
    /// bounds at `confidence`; `None` without `davar`. Refuses a window
    /// shorter than 8 samples or longer than the record, and more than
    /// [`MAX_WINDOWS`] windows or [`MAX_READ`] samples read.
    pub fn compute(
        &self,
        x: &[f64],
        tau0_s: f64,
        st: &Stability,
        confidence: f64,
        parallel: bool,
    ) -> Result<Option<Davar>> {
        let Some((window_s, step_s)) = self.spec()? else {
            return Ok(None);
        };
        let rows = x.len().saturating_sub(1);
        let w = (window_s / tau0_s).round() as usize;
        let s = ((step_s / tau0_s).round() as usize).max(1);
        let refuse = |m: String| Err(Error::Unsupported(format!("davar: {m}")));
        if w < 8 {
            return refuse(format!(
                "a window of {window_s} s holds {w} samples at {} Hz; at least 8 are needed",
                crate::error::short_f64(1.0 / tau0_s)
            ));
        }
        if w > rows {
            return refuse(format!(
                "the window ({window_s} s, {w} samples) is longer than the record ({rows} samples)"
            ));
        }
        let windows = (rows - w) / s + 1;
        if windows > MAX_WINDOWS {
            return refuse(format!(
                "{windows} windows of {window_s} s every {step_s} s; at most {MAX_WINDOWS}: take a longer step"
            ));
        }
        if windows.saturating_mul(w) > MAX_READ {
            return refuse(format!(
                "{windows} windows of {w} samples would read {} samples; at most {MAX_READ}: take a longer step or a shorter window",
                windows * w
            ));
        }
        let ms: Vec<usize> = std::iter::successors(Some(1usize), |m| Some(m * 2))
            .take_while(|m| 4 * m <= w)
            .collect();
        let alphas: Vec<i32> = ms
            .iter()
            .map(|&m| nearest_alpha(st, m as f64 * tau0_s))
            .collect();
        let one = |j: usize| -> Vec<Cellv> {
            let seg = &x[j * s..=j * s + w];
            crate::noise::dev::oavar_many(seg, &ms, tau0_s, false)
                .into_iter()
                .zip(ms.iter().zip(&alphas))
                .map(|(v, (&m, &a))| {
                    let v = v.filter(|v| v.var > 0.0 && v.var.is_finite());
                    let dev = v.map(|v| v.var.sqrt());
                    let g = |a: i32| crate::noise::edf::greenhall(a, 2, m, w + 1, true, false);
                    let edf = v.and_then(|_| g(a));
                    let b = dev
                        .zip(edf)
                        .and_then(|(d, e)| crate::noise::edf::chi2_bounds(d, e, confidence));
                    // The test's EDF (module docs): the least over α and
                    // every redder noise, from m = 2.
                    let test_edf = v
                        .filter(|_| m >= 2)
                        .and_then(|_| (-2..=a.max(-2)).filter_map(g).min_by(f64::total_cmp));
                    Cellv {
                        dev,
                        edf,
                        b,
                        test_edf,
                    }
                })
                .collect()
        };
        let values: Vec<Vec<Cellv>> = if parallel {
            (0..windows).into_par_iter().map(one).collect()
        } else {
            (0..windows).map(one).collect()
        };
        let q = w.div_ceil(s);
        let test = bartlett(&values, &ms, tau0_s, q);
        Ok(Some(Davar {
            window_s,
            step_s,
            window_samples: w,
            step_samples: s,
            starts_s: (0..windows).map(|j| (j * s) as f64 * tau0_s).collect(),
            taus_s: ms.iter().map(|&m| m as f64 * tau0_s).collect(),
            values,
            confidence,
            test,
            note: None,
        }))
    }
}

/// The α identified by the whole record at the τ nearest `tau` (log
/// distance) where one was; white FM (0) where none was.
fn nearest_alpha(st: &Stability, tau: f64) -> i32 {
    st.taus_s
        .iter()
        .zip(&st.alpha)
        .filter_map(|(t, a)| a.map(|a| ((t / tau).ln().abs(), a)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(0, |p| p.1)
}

/// One window's estimate at one τ (internal unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cellv {
    /// The deviation.
    pub dev: Option<f64>,
    /// Its EDF.
    pub edf: Option<f64>,
    /// Its χ² bounds.
    pub b: Option<(f64, f64)>,
    /// The EDF the stationarity test uses (module docs).
    pub test_edf: Option<f64>,
}

/// Bartlett's test at one τ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TauTest {
    /// τ (s).
    pub tau_s: f64,
    /// M/C.
    pub statistic: f64,
    /// K − 1.
    pub dof: usize,
    /// P(χ²_{K−1} ≥ M/C).
    pub p_value: f64,
    /// The least and the greatest window ADEV compared (internal unit).
    pub range: (f64, f64),
}

/// The stationarity test of a channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Test {
    /// Windows compared (that do not overlap).
    pub windows: usize,
    /// Each τ tested.
    pub taus: Vec<TauTest>,
}

impl Test {
    /// The per-τ threshold: [`FALSE_ALARM`] over the τ tested.
    pub fn threshold(&self) -> f64 {
        FALSE_ALARM / self.taus.len().max(1) as f64
    }

    /// The τ that reject stationarity, most significant first.
    pub fn rejected(&self) -> Vec<&TauTest> {
        let mut r: Vec<&TauTest> = self
            .taus
            .iter()
            .filter(|t| t.p_value < self.threshold())
            .collect();
        r.sort_by(|a, b| a.p_value.total_cmp(&b.p_value));
        r
    }
}

/// Bartlett's test (module docs) over the windows `0, q, 2q, …` at each τ;
/// `None` with fewer than two of them.
fn bartlett(values: &[Vec<Cellv>], ms: &[usize], tau0_s: f64, q: usize) -> Option<Test> {
    let picked: Vec<&Vec<Cellv>> = values.iter().step_by(q).collect();
    let k = picked.len();
    if k < 2 {
        return None;
    }
    let mut taus = Vec::new();
    for (i, &m) in ms.iter().enumerate() {
        let est: Option<Vec<(f64, f64)>> = picked
            .iter()
            .map(|w| {
                let c = w[i];
                Some((c.test_edf.filter(|e| *e >= 2.0)?, c.dev? * c.dev?))
            })
            .collect();
        let Some(est) = est else { continue };
        let n: f64 = est.iter().map(|e| e.0).sum();
        let pooled = est.iter().map(|e| e.0 * e.1).sum::<f64>() / n;
        let m_stat = n * pooled.ln() - est.iter().map(|e| e.0 * e.1.ln()).sum::<f64>();
        let c =
            1.0 + (est.iter().map(|e| 1.0 / e.0).sum::<f64>() - 1.0 / n) / (3.0 * (k - 1) as f64);
        let statistic = (m_stat / c).max(0.0);
        let Ok(chi) = ChiSquared::new((k - 1) as f64) else {
            continue;
        };
        let devs = est.iter().map(|e| e.1.sqrt());
        let range = devs.fold((f64::INFINITY, 0.0f64), |(a, b), d| (a.min(d), b.max(d)));
        taus.push(TauTest {
            tau_s: m as f64 * tau0_s,
            statistic,
            dof: k - 1,
            p_value: chi.sf(statistic),
            range,
        });
    }
    Some(Test { windows: k, taus })
}

/// One channel's dynamic Allan variance.
#[derive(Debug, Clone, PartialEq)]
pub struct Davar {
    /// Window and step asked for (s).
    pub window_s: f64,
    /// Step asked for (s).
    pub step_s: f64,
    /// Samples per window.
    pub window_samples: usize,
    /// Samples per step.
    pub step_samples: usize,
    /// Each window's start (s from the first sample).
    pub starts_s: Vec<f64>,
    /// τ (s).
    pub taus_s: Vec<f64>,
    /// Windows × τ.
    pub values: Vec<Vec<Cellv>>,
    /// Confidence of the bounds.
    pub confidence: f64,
    /// The stationarity test (`None`: fewer than two windows that do not
    /// overlap).
    pub test: Option<Test>,
    /// Where it comes from when not the whole record (gaps).
    pub note: Option<String>,
}

impl Davar {
    /// `channels.NAME.davar` (module docs), values times `f` into the
    /// input `unit`.
    pub fn json(&self, f: f64, unit: &str) -> Value {
        let adev: Vec<Vec<Option<f64>>> = self
            .values
            .iter()
            .map(|w| w.iter().map(|c| c.dev.map(|d| d * f)).collect())
            .collect();
        let test = self.test.as_ref().map(|t| {
            json!({
                "false_alarm": FALSE_ALARM,
                "windows_compared": t.windows,
                "taus": t.taus.iter().map(|x| json!({
                    "tau_s": x.tau_s,
                    "statistic": x.statistic,
                    "dof": x.dof,
                    "p_value": x.p_value,
                })).collect::<Vec<_>>(),
                "p_threshold": t.threshold(),
                "non_stationary": !t.rejected().is_empty(),
            })
        });
        let mut o = json!({
            "window_s": self.window_s,
            "step_s": self.step_s,
            "window_samples": self.window_samples,
            "step_samples": self.step_samples,
            "windows": self.values.len(),
            "start_s": self.starts_s,
            "taus_s": self.taus_s,
            "adev": adev,
            "unit": unit,
            "confidence": self.confidence,
            "test": test,
        });
        if self.test.is_none() {
            o["reason"] = json!("fewer than two windows that do not overlap: the record is shorter than two windows");
        }
        if let Some(n) = &self.note {
            o["note"] = json!(n);
        }
        o
    }

    /// The table `davar.NAME` (module docs), values times `f` into `unit`.
    pub fn table(&self, name: &str, f: f64, unit: &str) -> Result<Table> {
        let u = Some(Unit::Other(unit.to_string()));
        let s = Some(Unit::Other("s".into()));
        let mut t = Table::new(
            &format!("davar.{name}"),
            &format!(
                "{name}: dynamic Allan deviation, windows of {} s every {} s",
                crate::error::short_f64(self.window_s),
                crate::error::short_f64(self.step_s)
            ),
            &[
                ("start_s", s.clone()),
                ("tau_s", s),
                ("adev", u.clone()),
                ("lo", u.clone()),
                ("hi", u),
                ("edf", None),
            ],
        );
        let opt = |v: Option<f64>| v.map_or(Cell::Null, Cell::num);
        for (start, w) in self.starts_s.iter().zip(&self.values) {
            for (tau, c) in self.taus_s.iter().zip(w) {
                t.push(vec![
                    Cell::num(*start),
                    Cell::num(*tau),
                    opt(c.dev.map(|d| d * f)),
                    opt(c.b.map(|b| b.0 * f)),
                    opt(c.b.map(|b| b.1 * f)),
                    opt(c.edf),
                ])?;
            }
        }
        Ok(t)
    }

    /// The `non-stationary` warning of channel `name` when the test
    /// rejects (values times `f` into `unit`).
    pub fn warning(&self, name: &str, f: f64, unit: &str) -> Option<Warning> {
        let t = self.test.as_ref()?;
        let r = t.rejected();
        let worst = r.first()?;
        // Four significant digits (the bounds of one window are a few %).
        let g = |v: f64| {
            let v = v * f;
            let e = v.abs().log10().floor() as i32;
            let d = 3i32.saturating_sub(e).clamp(0, 12) as usize;
            if (-3..5).contains(&e) {
                format!("{v:.d$}")
            } else {
                format!("{v:.3e}")
            }
        };
        let p = if worst.p_value < 1e-16 {
            "p < 1e-16".to_string()
        } else {
            format!("p = {:.1e}", worst.p_value)
        };
        Some(Warning::new(
            WarningCode::NonStationary,
            format!(
                "{name}: the noise changes along the record: over {} windows of {} s that do not overlap, the Allan deviation at tau = {} s runs from {} to {} {unit} (Bartlett's test {p}; {} of {} averaging times reject at a false-alarm rate of {FALSE_ALARM} per channel); the whole-record statistics average over the change (see davar.{name})",
                t.windows,
                crate::error::short_f64(self.window_s),
                crate::error::short_f64(worst.tau_s),
                g(worst.range.0),
                g(worst.range.1),
                r.len(),
                t.taus.len(),
            ),
        ))
    }
}
