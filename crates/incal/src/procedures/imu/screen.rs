//! Spikes in still data, and channels that cannot be calibrated.
//!
//! # Spikes
//! A sample of a still section (a labelled static position, an
//! autocalibration still interval) is a spike when one of its channels lies
//! more than [`SPIKE_SIGMAS`] robust standard deviations from the median:
//! `|x − med| > 6 σ̂`, `σ̂ = 1.4826 MAD` (the MAD of a normal sample
//! times 1.4826 estimates σ; Rousseeuw & Croux, "Alternatives to the
//! median absolute deviation", JASA 88, 1993). A quantised channel whose
//! MAD is 0 takes its smallest non-zero deviation (one quantisation step)
//! as σ̂. At 6 σ̂ a normal sample is flagged with probability 2e-9 per
//! channel: a clean session of 10⁶ samples keeps all of them. Spikes are
//! left out of the section's mean and scatter and counted in a `spikes`
//! warning.
//!
//! # Channels
//! [`ChannelCheck`]: a channel with one value in every row (a dead
//! axis) is refused naming its column; a channel that sits at its extreme
//! value in many rows (a converter at full scale) gets a `saturated`
//! warning naming the column, the value and the count.
//!
//! # Clipped gyro samples in motion
//! [`GyroRails`]: a gyro axis two or more samples in a row at its own
//! extreme over the session, when that extreme is an integer converter's
//! end ([`incal_io::at_rail`]; the input layer's `clipped` rule). A
//! rotation holding such samples integrates to the wrong angle: it is left
//! out where the session has another (multipos, autocal) and refused where
//! it has none (Ferraris).

use crate::error::{Error, Result};
use crate::warning::{Warning, WarningCode};

/// Robust standard deviations beyond which a still sample is a spike.
pub const SPIKE_SIGMAS: f64 = 6.0;

/// Median and robust scale `σ̂` of `v` (reordered in place): `1.4826 MAD`,
/// or the smallest non-zero deviation when the MAD is 0; `σ̂ = 0` when
/// every value is the median.
pub fn robust(v: &mut [f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mid = v.len() / 2;
    let med = *v.select_nth_unstable_by(mid, f64::total_cmp).1;
    let mut dev: Vec<f64> = v.iter().map(|x| (x - med).abs()).collect();
    let mad = *dev.select_nth_unstable_by(mid, f64::total_cmp).1;
    if mad > 0.0 {
        return (med, 1.4826 * mad);
    }
    let step = dev
        .iter()
        .copied()
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    (med, if step.is_finite() { step } else { 0.0 })
}

/// Flags of the spikes of a still section of `N`-channel samples: `true`
/// where any channel lies more than [`SPIKE_SIGMAS`] σ̂ from its median.
pub fn spikes<const N: usize>(samples: &[[f64; N]]) -> Vec<bool> {
    let mut flags = vec![false; samples.len()];
    let mut col = Vec::with_capacity(samples.len());
    for k in 0..N {
        col.clear();
        col.extend(samples.iter().map(|s| s[k]));
        let (med, scale) = robust(&mut col);
        if scale == 0.0 {
            continue;
        }
        for (f, s) in flags.iter_mut().zip(samples) {
            if (s[k] - med).abs() > SPIKE_SIGMAS * scale {
                *f = true;
            }
        }
    }
    flags
}

/// The samples of a still section with its spikes left out, and how many
/// were left out. At least half the samples are always kept (the median's
/// side), so a section never empties.
pub fn without_spikes<const N: usize>(samples: &[[f64; N]]) -> (Vec<[f64; N]>, usize) {
    let flags = spikes(samples);
    let kept: Vec<[f64; N]> = samples
        .iter()
        .zip(&flags)
        .filter(|(_, f)| !**f)
        .map(|(s, _)| *s)
        .collect();
    let dropped = samples.len() - kept.len();
    (kept, dropped)
}

/// What was done with the spikes, for [`spikes_warning`].
pub const LEFT_OUT: &str =
    "from their still section's median were left out of its mean and scatter";
/// What the Hampel filter does with them.
pub const REPLACED: &str = "from the median of their 11 neighbours were replaced by the line between their nearest unflagged neighbours";
/// What is done with the samples that stand out in motion.
pub const NOT_CHANGED: &str = "from the median of their 11 neighbours were found in motion and not changed (a bad sample and a short real transient, a knock, look alike; each moves the rotation integral: check those rows)";

/// The `spikes` warning for `(section, count)` pairs (sections without
/// spikes are not listed) saying what was `done` ([`LEFT_OUT`],
/// [`REPLACED`], [`NOT_CHANGED`]), or `None` when there are none.
pub fn spikes_warning(counts: &[(String, usize)], done: &str) -> Option<Warning> {
    let hit: Vec<String> = counts
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(s, n)| format!("{s} {n}"))
        .collect();
    if hit.is_empty() {
        return None;
    }
    let total: usize = counts.iter().map(|(_, n)| n).sum();
    let shown = if hit.len() > 12 {
        format!("{}, … ({} sections)", hit[..12].join(", "), hit.len())
    } else {
        hit.join(", ")
    };
    Some(Warning::new(
        WarningCode::Spikes,
        format!(
            "{total} sample(s) more than {SPIKE_SIGMAS} robust standard deviations (1.4826 MAD of still data) {done}: {shown}"
        ),
    ))
}

/// Half width of the Hampel window (11 samples).
pub const HAMPEL_HALF: usize = 5;

/// A Hampel filter for a record that moves between still intervals
/// (Hampel, "The influence curve and its role in robust estimation", JASA
/// 69, 1974; Pearson, "Outliers in process modeling and identification",
/// IEEE TCST 10, 2002), with a scale that follows the motion: sample `i`
/// is a spike when a channel lies more than [`SPIKE_SIGMAS`] `s_i` from
/// the median of its `2·HAMPEL_HALF + 1` neighbours, where
/// `s_i = max(scale[k], 1.4826 med|Δx| / √2)` over the window (`scale` the
/// robust σ̂ of a known still stretch; in still data both terms estimate
/// the noise σ, in a steep slope the second is the step per sample, so a
/// spike's neighbours, whose median it shifts by one rank, are not taken
/// for spikes). Each spike is replaced by the straight line between its
/// nearest unflagged neighbours (exact on a slope, the local level when
/// still), so the sample count and time steps stay as recorded. Returns
/// the record so mended, and the flags ([`hampel_flags`]).
pub fn hampel(x: &[[f64; 3]], scale: [f64; 3]) -> (Vec<[f64; 3]>, Vec<bool>) {
    let n = x.len();
    let hits = hampel_hits(x, scale);
    let mut out = x.to_vec();
    for (k, hit) in hits.iter().enumerate() {
        for i in (0..n).filter(|&i| hit[i]) {
            let l = (0..i).rev().find(|&j| !hit[j]);
            let r = (i + 1..n).find(|&j| !hit[j]);
            out[i][k] = match (l, r) {
                (Some(l), Some(r)) => {
                    x[l][k] + (x[r][k] - x[l][k]) * (i - l) as f64 / (r - l) as f64
                }
                (Some(j), None) | (None, Some(j)) => x[j][k],
                (None, None) => x[i][k],
            };
        }
    }
    (out, any_channel(&hits))
}

/// The samples [`hampel`] flags (any channel), without mending the record:
/// for data that is reported and left as recorded.
pub fn hampel_flags(x: &[[f64; 3]], scale: [f64; 3]) -> Vec<bool> {
    any_channel(&hampel_hits(x, scale))
}

/// Per sample: flagged on any channel.
fn any_channel(hits: &[Vec<bool>; 3]) -> Vec<bool> {
    (0..hits[0].len())
        .map(|i| hits.iter().any(|h| h[i]))
        .collect()
}

/// Per channel, the samples the test of [`hampel`] flags (a channel whose
/// `scale` is not positive flags none).
fn hampel_hits(x: &[[f64; 3]], scale: [f64; 3]) -> [Vec<bool>; 3] {
    let n = x.len();
    let mut w = Vec::with_capacity(2 * HAMPEL_HALF + 1);
    let mut d = Vec::with_capacity(2 * HAMPEL_HALF);
    std::array::from_fn(|k| {
        let mut hit = vec![false; n];
        if scale[k].is_nan() || scale[k] <= 0.0 {
            return hit;
        }
        // The first and last HAMPEL_HALF samples are not judged: their
        // window does not fit, and a truncated one mistakes a trend for a
        // spike.
        for i in HAMPEL_HALF..n.saturating_sub(HAMPEL_HALF) {
            let span = &x[i - HAMPEL_HALF..=i + HAMPEL_HALF];
            w.clear();
            w.extend(span.iter().map(|s| s[k]));
            let mid = w.len() / 2;
            let med = *w.select_nth_unstable_by(mid, f64::total_cmp).1;
            d.clear();
            d.extend(span.windows(2).map(|p| (p[1][k] - p[0][k]).abs()));
            let dmid = d.len() / 2;
            let step = *d.select_nth_unstable_by(dmid, f64::total_cmp).1;
            let s = scale[k].max(1.4826 * step / std::f64::consts::SQRT_2);
            hit[i] = (x[i][k] - med).abs() > SPIKE_SIGMAS * s;
        }
        hit
    })
}

/// The gyro's still scatter: per channel, the median over the still
/// sections of each section's robust σ̂ (the scale of [`hampel`] for the
/// rotations).
pub fn gyro_still_scale<'a>(statics: impl Iterator<Item = &'a [[f64; 6]]>) -> [f64; 3] {
    let per: Vec<[f64; 3]> = statics.map(|s| triad_scale(s, 3)).collect();
    median_scale(&per)
}

/// The robust σ̂ ([`robust`]) of channels `first..first + 3` of a still
/// stretch: the accelerometer (`first` 0) or gyro (3 of a session sample,
/// 0 of a gyro triad).
pub fn triad_scale<const N: usize>(s: &[[f64; N]], first: usize) -> [f64; 3] {
    std::array::from_fn(|k| {
        let mut c: Vec<f64> = s.iter().map(|x| x[first + k]).collect();
        robust(&mut c).1
    })
}

/// Per channel, the median of sections' scales.
pub fn median_scale(per: &[[f64; 3]]) -> [f64; 3] {
    std::array::from_fn(|k| {
        let mut c: Vec<f64> = per.iter().map(|p| p[k]).collect();
        robust(&mut c).0
    })
}

/// How many gyro samples of a rotation section [`hampel`] flags. They are
/// reported, not changed: at the sampling rates of these sessions a bad
/// sample and a short real transient (a knock during a hand rotation,
/// seen on all three axes at once in imucal's example session) look alike,
/// and the rotation integral must keep the real one.
pub fn rotation_spikes(section: &[[f64; 6]], scale: [f64; 3]) -> usize {
    let gyro: Vec<[f64; 3]> = section.iter().map(|s| [s[3], s[4], s[5]]).collect();
    hampel_flags(&gyro, scale).iter().filter(|f| **f).count()
}

/// Rows at the extreme value before a channel is called saturated: at
/// least this many, and at least 0.1 % of the rows.
pub const SATURATED_ROWS: usize = 20;

/// Checks of every channel of a session, one sample at a time (constant
/// memory): a channel with one value in every row is refused (a dead axis
/// cannot be calibrated: its scale would come out 0 or from noise
/// elsewhere); a channel whose largest or smallest value repeats in at
/// least [`SATURATED_ROWS`] rows and 0.1 % of them, and in more rows
/// than the next value does (clipping piles samples up at the extreme; the
/// tail of a quantised noisy channel thins out), gets a `saturated`
/// warning (a converter at full scale: the means of those rows are
/// clipped).
#[derive(Debug, Clone)]
pub struct ChannelCheck<const N: usize> {
    rows: usize,
    first: [f64; N],
    varies: [bool; N],
    /// The two largest distinct values and their counts.
    hi: [[(f64, usize); 2]; N],
    /// The two smallest (of the negated values).
    lo: [[(f64, usize); 2]; N],
}

/// Count `x` into the two largest distinct values `top`.
fn top2(top: &mut [(f64, usize); 2], x: f64) {
    if x > top[0].0 {
        top[1] = top[0];
        top[0] = (x, 1);
    } else if x == top[0].0 {
        top[0].1 += 1;
    } else if x > top[1].0 {
        top[1] = (x, 1);
    } else if x == top[1].0 {
        top[1].1 += 1;
    }
}

impl<const N: usize> Default for ChannelCheck<N> {
    fn default() -> Self {
        Self {
            rows: 0,
            first: [0.0; N],
            varies: [false; N],
            hi: [[(f64::NEG_INFINITY, 0); 2]; N],
            lo: [[(f64::NEG_INFINITY, 0); 2]; N],
        }
    }
}

impl<const N: usize> ChannelCheck<N> {
    /// Take one sample.
    pub fn push(&mut self, s: &[f64; N]) {
        if self.rows == 0 {
            self.first = *s;
        }
        self.rows += 1;
        for (k, &x) in s.iter().enumerate() {
            self.varies[k] |= x != self.first[k];
            top2(&mut self.hi[k], x);
            top2(&mut self.lo[k], -x);
        }
    }

    /// The verdict for the channels named `names` (only those with a name:
    /// `None` for a channel the session does not have).
    pub fn finish(&self, names: &[Option<&str>; N], warnings: &mut Vec<Warning>) -> Result<()> {
        if self.rows < 2 {
            return Ok(());
        }
        let need = SATURATED_ROWS.max(self.rows / 1000);
        for (k, name) in names.iter().enumerate() {
            let Some(name) = name else { continue };
            if !self.varies[k] {
                return Err(Error::Unsupported(format!(
                    "column {name} is {} in every row: a dead channel cannot be calibrated (check the wiring or the column mapping)",
                    crate::error::short_f64(self.first[k])
                )));
            }
            for (end, top, sign) in [("largest", self.hi[k], 1.0), ("smallest", self.lo[k], -1.0)] {
                // Clipping piles the samples up at the extreme: more there
                // than at the next value (a natural tail thins out).
                let ((v, at), (_, next)) = (top[0], top[1]);
                let v = sign * v;
                if at >= need && at > next {
                    warnings.push(Warning::new(
                        WarningCode::Saturated,
                        format!(
                            "column {name} sits at its {end} value {} in {at} of {} rows: a converter at full scale clips the means there (reduce the range of motion or the gain, or leave those rows out)",
                            crate::error::short_f64(v),
                            self.rows
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The channel names of a session ([`super::input::CHANNELS`]; `None`
/// for the gyro's when the session has no gyro).
pub fn session_channels(gyro: bool) -> [Option<&'static str>; 6] {
    std::array::from_fn(|k| (k < 3 || gyro).then_some(super::input::CHANNELS[k]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, Normal};

    fn noisy(n: usize, seed: u64) -> Vec<[f64; 2]> {
        let mut rng = crate::sim::rng(seed);
        let normal = Normal::new(0.0, 1.0).unwrap();
        (0..n)
            .map(|_| {
                [
                    10.0 + normal.sample(&mut rng),
                    -3.0 + 0.1 * normal.sample(&mut rng),
                ]
            })
            .collect()
    }

    #[test]
    fn a_clean_normal_section_keeps_every_sample() {
        for seed in 0..20 {
            let s = noisy(50_000, seed);
            assert_eq!(without_spikes(&s).1, 0, "seed {seed}");
        }
    }

    #[test]
    fn spikes_are_found_in_either_channel() {
        let mut s = noisy(1000, 1);
        s[10][0] += 8.0;
        s[500][1] -= 0.8;
        s[700][0] += 5.0; // 5 sigma: kept
        let f = spikes(&s);
        assert!(f[10] && f[500] && !f[700]);
        assert_eq!(f.iter().filter(|x| **x).count(), 2);
    }

    #[test]
    fn a_quantised_channel_takes_its_step_as_scale() {
        // Mostly 100 with a few ±1 counts: MAD 0, step 1.
        let mut s: Vec<[f64; 1]> = (0..200)
            .map(|i| [100.0 + if i % 7 == 0 { 1.0 } else { 0.0 }])
            .collect();
        assert_eq!(without_spikes(&s).1, 0);
        s[3][0] = 107.0;
        assert_eq!(without_spikes(&s).1, 1);
        let mut c: Vec<f64> = vec![5.0; 10];
        assert_eq!(robust(&mut c), (5.0, 0.0));
    }

    fn check(s: &[[f64; 2]], names: [Option<&str>; 2], w: &mut Vec<Warning>) -> Result<()> {
        let mut c = ChannelCheck::default();
        s.iter().for_each(|x| c.push(x));
        c.finish(&names, w)
    }

    #[test]
    fn hampel_replaces_a_spike_by_the_local_level() {
        let mut x: Vec<[f64; 3]> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.05;
                [t.sin(), 1.0, if i % 2 == 0 { 0.01 } else { -0.01 }]
            })
            .collect();
        x[50][1] = 2.0;
        let (y, f) = hampel(&x, [0.01, 0.01, 0.01]);
        assert_eq!(f.iter().filter(|v| **v).count(), 1);
        assert!(f[50] && y[50][1] == 1.0);
        // The smooth sine moves less than 6 sigma from its local median.
        assert!((0..200).filter(|&i| i != 50).all(|i| y[i] == x[i]));
        // A spike on a steep slope is put back on the line, and its
        // neighbours are left alone.
        let mut ramp: Vec<[f64; 3]> = (0..100)
            .map(|i| {
                [
                    30.0 * i as f64 + if i % 2 == 0 { 1.0 } else { -1.0 },
                    0.0,
                    0.0,
                ]
            })
            .collect();
        ramp[40][0] += 500.0;
        let (y, f) = hampel(&ramp, [1.0, 0.0, 0.0]);
        assert_eq!(f.iter().filter(|v| **v).count(), 1);
        assert!(f[40] && (y[40][0] - 1200.0).abs() <= 1.0, "{}", y[40][0]);
    }

    #[test]
    fn dead_and_saturated_channels() {
        let mut w = Vec::new();
        let s: Vec<[f64; 2]> = (0..100).map(|i| [i as f64, 7.0]).collect();
        let e = check(&s, [Some("a"), Some("b")], &mut w).unwrap_err();
        assert!(e.to_string().contains("column b is 7 in every row"), "{e}");
        // A channel the session does not have is not judged.
        check(&s, [Some("a"), None], &mut w).unwrap();
        let s: Vec<[f64; 2]> = (0..100).map(|i| [(i as f64).min(60.0), i as f64]).collect();
        check(&s, [Some("a"), Some("b")], &mut w).unwrap();
        assert_eq!(w.len(), 1);
        assert!(w[0]
            .message
            .starts_with("column a sits at its largest value 60 in 40 of 100"));
        // A quantised channel whose tails thin out is not saturated, even
        // with 20 samples at each extreme.
        let mut s: Vec<[f64; 2]> = Vec::new();
        for v in 0..10usize {
            for _ in 0..20 + 20 * v.min(9 - v) {
                s.push([v as f64, s.len() as f64]);
            }
        }
        let mut w = Vec::new();
        check(&s, [Some("a"), Some("b")], &mut w).unwrap();
        assert!(w.is_empty(), "{w:?}");
    }
}

/// The rails of a session's gyro axes: per axis, its extremes over the
/// session that are integer converters' ends (module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GyroRails {
    rails: [Vec<f64>; 3],
}

impl GyroRails {
    /// The rails of the gyro samples `gy` (°/s or raw, any unit).
    pub fn of(gy: impl Iterator<Item = [f64; 3]> + Clone) -> Self {
        Self {
            rails: std::array::from_fn(|k| incal_io::extreme_rails(gy.clone().map(|g| g[k]))),
        }
    }

    /// The samples of `gy` at a rail in runs of two or more (one flag a
    /// sample), and the first (axis, rail) found.
    pub fn flags(&self, gy: &[[f64; 3]]) -> (Vec<bool>, Option<(usize, f64)>) {
        let mut out = vec![false; gy.len()];
        let mut first = None;
        for (k, rails) in self.rails.iter().enumerate() {
            let axis: Vec<f64> = gy.iter().map(|g| g[k]).collect();
            for &rail in rails {
                for (i, hit) in incal_io::rail_runs(&axis, &[rail]).into_iter().enumerate() {
                    if hit {
                        out[i] = true;
                        first.get_or_insert((k, rail));
                    }
                }
            }
        }
        (out, first)
    }

    /// The clipped samples of a section of six channels (gyro 3..6): their
    /// number and the first (axis, rail).
    pub fn count(&self, section: &[[f64; 6]]) -> (usize, Option<(usize, f64)>) {
        let gy: Vec<[f64; 3]> = section.iter().map(|s| [s[3], s[4], s[5]]).collect();
        let (flags, first) = self.flags(&gy);
        (flags.iter().filter(|&&f| f).count(), first)
    }
}
