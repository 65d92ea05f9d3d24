//! The plateaus of a threshold record, its levels (zero and the base
//! input), the steps between them grouped by size, and the noise of a
//! plateau mean measured on the record's own revisits of its levels.

use super::input::Record;
use crate::error::{Error, Result};

/// Which level a step is taken about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Group {
    /// About zero input: the threshold.
    Zero,
    /// About the base input: the resolution.
    Base,
}

impl Group {
    /// The coefficient's stem.
    pub fn name(self) -> &'static str {
        match self {
            Group::Zero => "threshold",
            Group::Base => "resolution",
        }
    }

    /// In words.
    pub fn about(self) -> &'static str {
        match self {
            Group::Zero => "at zero",
            Group::Base => "at the base input",
        }
    }
}

/// Consecutive rows at one commanded input.
#[derive(Debug, Clone, PartialEq)]
pub struct Plateau {
    /// The commanded input as written (deg/s or deg of tilt).
    pub command: f64,
    /// The input (deg/s or g).
    pub input: f64,
    /// First and last row (0-based) of the plateau.
    pub rows: (usize, usize),
    /// Samples kept after the settling time.
    pub n: usize,
    /// Their mean output.
    pub mean: f64,
    /// Their sum of squared deviations from the mean.
    pub ss: f64,
    /// The level it is at, if any.
    pub level: Option<Group>,
}

/// Cut a record into plateaus, leaving out the first `settle_s` of
/// each (time from `time_s`, else row / `rate_hz`). A plateau left with
/// fewer than 2 samples is refused naming its lines.
pub fn plateaus(rec: &Record, settle_s: f64, rate_hz: Option<f64>) -> Result<Vec<Plateau>> {
    let n = rec.output.len();
    let time = |k: usize| match (&rec.time_s, rate_hz) {
        (Some(t), _) => t[k],
        (None, Some(r)) => k as f64 / r,
        (None, None) => 0.0,
    };
    let mut out = Vec::new();
    let mut start = 0;
    for k in 1..=n {
        if k < n && rec.command[k] == rec.command[start] {
            continue;
        }
        let t0 = time(start);
        let kept: Vec<f64> = (start..k)
            .filter(|&j| time(j) - t0 >= settle_s)
            .map(|j| rec.output[j])
            .collect();
        if kept.len() < 2 {
            return Err(Error::Unsupported(format!(
                "the plateau at {} on lines {}-{} keeps {} samples after settle_s {settle_s} s: at least 2",
                rec.command[start],
                rec.lines[start],
                rec.lines[k - 1],
                kept.len()
            )));
        }
        let mean = kept.iter().sum::<f64>() / kept.len() as f64;
        let ss = kept.iter().map(|y| (y - mean).powi(2)).sum();
        out.push(Plateau {
            command: rec.command[start],
            input: rec.input(start),
            rows: (start, k - 1),
            n: kept.len(),
            mean,
            ss,
            level: None,
        });
        start = k;
    }
    Ok(out)
}

/// The base input (as written): `given`, which must be a plateau's
/// command; else the non-zero command held by most plateaus, when at
/// least 3 hold it and at least twice as many as any other non-zero
/// command; else none.
pub fn base_command(p: &[Plateau], given: Option<f64>) -> Result<Option<f64>> {
    if let Some(b) = given {
        if !p.iter().any(|q| q.command == b) {
            return crate::options::invalid(
                "base_input",
                format!("no plateau is at {b} (the input column's units)"),
            );
        }
        return Ok(Some(b));
    }
    // One pass, keyed by the value's bits (a record may hold many
    // distinct inputs).
    let mut by_bits: std::collections::HashMap<u64, (f64, usize)> = Default::default();
    for q in p.iter().filter(|q| q.command != 0.0) {
        by_bits
            .entry(q.command.to_bits())
            .or_insert((q.command, 0))
            .1 += 1;
    }
    let mut counts: Vec<(f64, usize)> = by_bits.into_values().collect();
    counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
    Ok(match counts.as_slice() {
        [(c, n), rest @ ..] if *n >= 3 && rest.first().is_none_or(|r| *n >= 2 * r.1) => Some(*c),
        _ => None,
    })
}

/// Mark each plateau's level (zero, or the base command).
pub fn mark(p: &mut [Plateau], base: Option<f64>) {
    for q in p.iter_mut() {
        q.level = if q.command == 0.0 {
            Some(Group::Zero)
        } else if Some(q.command) == base {
            Some(Group::Base)
        } else {
            None
        };
    }
}

/// The steps of one size about one level: the transitions `k → k+1`
/// between consecutive plateaus with one end at the level.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSize {
    /// The level.
    pub group: Group,
    /// The step's size |Δinput| (deg/s or g; the mean over its
    /// transitions).
    pub size: f64,
    /// The transitions (index of the first plateau).
    pub transitions: Vec<usize>,
}

/// The steps grouped by level and size (sizes within 2 % are one size),
/// in order of level, then size. A transition between two levels (zero
/// to the base) or with no end at a level is not a step.
pub fn steps(p: &[Plateau]) -> Vec<StepSize> {
    let mut raw: Vec<(Group, f64, usize)> = Vec::new();
    for k in 0..p.len().saturating_sub(1) {
        let (a, b) = (&p[k], &p[k + 1]);
        let group = match (a.level, b.level) {
            (Some(g), None) | (None, Some(g)) => g,
            _ => continue,
        };
        raw.push((group, (b.input - a.input).abs(), k));
    }
    raw.sort_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
    let mut out: Vec<StepSize> = Vec::new();
    for (g, s, k) in raw {
        match out.last_mut() {
            Some(last) if last.group == g && s <= last.size * 1.02 => {
                let m = last.transitions.len() as f64;
                last.size = (last.size * m + s) / (m + 1.0);
                last.transitions.push(k);
            }
            _ => out.push(StepSize {
                group: g,
                size: s,
                transitions: vec![k],
            }),
        }
    }
    out
}

/// The noise of a plateau mean at the plateau's own length, measured on
/// the record's revisits of its levels: for each level, the differences
/// `d` of the means of its consecutive plateaus (a two-sample variance at
/// the plateau length, the drift between visits included). With
/// `var(ȳ_k) = s²/n_k`, `s² = Σ d² / Σ (1/n_k + 1/n_k')`; each level's
/// `m` successive differences give `2m²/(3m − 1)` degrees of freedom
/// (the mean square successive difference of white plateau means). Also
/// the within-plateau variance of one sample, pooled. Refused when no
/// level is visited twice.
pub fn noise(p: &[Plateau]) -> Result<Noise> {
    let (mut num, mut den, mut dof, mut pairs) = (0.0, 0.0, 0.0, 0usize);
    for g in [Group::Zero, Group::Base] {
        let at: Vec<&Plateau> = p.iter().filter(|q| q.level == Some(g)).collect();
        let m = at.len().saturating_sub(1);
        for w in at.windows(2) {
            num += (w[1].mean - w[0].mean).powi(2);
            den += 1.0 / w[0].n as f64 + 1.0 / w[1].n as f64;
        }
        if m > 0 {
            let m = m as f64;
            dof += 2.0 * m * m / (3.0 * m - 1.0);
        }
        pairs += m;
    }
    if pairs == 0 {
        return Err(Error::Unsupported(
            "no level is visited twice: the noise of a plateau mean is measured on the differences between visits of zero or the base input (a step and back); record the sequence level, level+step, level, level-step, level"
                .into(),
        ));
    }
    let (ss, nw): (f64, usize) = p.iter().fold((0.0, 0), |a, q| (a.0 + q.ss, a.1 + q.n - 1));
    Ok(Noise {
        var_long: num / den,
        dof,
        pairs,
        var_short: ss / nw.max(1) as f64,
    })
}

/// The noise of one sample at the plateau scale ([`noise`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// `s²`: a plateau mean of `n` samples has variance `s²/n` (output
    /// units squared).
    pub var_long: f64,
    /// Its degrees of freedom.
    pub dof: f64,
    /// How many revisit differences it rests on.
    pub pairs: usize,
    /// The pooled within-plateau variance of one sample.
    pub var_short: f64,
}
