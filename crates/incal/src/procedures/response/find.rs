//! Dwells found from the reference, for a stepped-sine recording without
//! a `freq_hz` column (a rate table's or shaker's log of its encoder or
//! reference accelerometer only).
//!
//! The reference is cut into windows of `W = dwell_window_s` seconds
//! overlapping by half. In each, the mean is removed, a Hann window
//! applied, and the spectrum's peak (bins 2 and up) located with the
//! Gaussian interpolation of its three highest bins,
//! `δ = ½ (ln a₋ − ln a₊)/(ln a₋ − 2 ln a₀ + ln a₊)`, `f = (k + δ)/W`,
//! its amplitude `2|X_k|/Σw`. A window whose amplitude is below 10⁻³ of
//! the recording's largest is still (no dwell). Consecutive moving windows
//! whose frequency stays within a quarter bin (`1/(4W)` Hz) or 0.1 % of
//! the first window of their run form one run; a sweep therefore forms
//! no run. A boundary between two dwells lies in at most two windows of
//! a run, so a run's dwell is its windows but the two at each end:
//! `[s_{j+2}, s_{k−2} + W)`, at least `W` long, needing runs of five or
//! more windows (dwells of about `3W` and longer). A run of three or four
//! is left out with a warning. The dwell's start frequency is the median
//! of its windows'; the four-parameter fit ([`super::sine::fit_frequency`])
//! then estimates it from the whole dwell.
//!
//! Dwells must differ by more than a quarter bin; the reference must
//! oscillate (a drifting level is removed per window).

use realfft::RealFftPlanner;

use super::input::Dwell;
use crate::error::{Error, Result};
use crate::warning::{Warning, WarningCode};

/// A whole recording before it is cut into dwells.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    /// The file line of each sample.
    pub lines: Vec<usize>,
    /// Every sample as one dwell (its `freq_hz` unused).
    pub samples: Dwell,
}

/// One window's spectral peak.
#[derive(Debug, Clone, Copy)]
struct Peak {
    freq_hz: f64,
    amplitude: f64,
}

/// The frequency (Hz) of the spectral peak of `x` sampled at `rate_hz`
/// (module docs: mean removed, Hann window, Gaussian interpolation)
/// between `lo_hz` and `hi_hz`: the start of the four-parameter fit of a
/// dwell whose nominal frequency may be off by more than half a bin.
pub fn peak_freq_hz(x: &[f64], rate_hz: f64, lo_hz: f64, hi_hz: f64) -> Option<f64> {
    let bins = (x.len() as f64 / rate_hz * lo_hz).floor().max(2.0) as usize
        ..(x.len() as f64 / rate_hz * hi_hz).ceil() as usize + 1;
    peak(x, rate_hz, &mut RealFftPlanner::new(), bins).map(|p| p.freq_hz)
}

/// The peak of `x` (mean removed, Hann window) with the sampling rate
/// `rate_hz` among `bins` (from 2); `None` when it lies in bins 0 or 1 or
/// at the top, or `x` is shorter than 8.
fn peak(
    x: &[f64],
    rate_hz: f64,
    planner: &mut RealFftPlanner<f64>,
    bins: std::ops::Range<usize>,
) -> Option<Peak> {
    let n = x.len();
    if n < 8 {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let w: Vec<f64> = (0..n)
        .map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos())
        .collect();
    let sw: f64 = w.iter().sum();
    let mut input: Vec<f64> = x.iter().zip(&w).map(|(v, w)| (v - mean) * w).collect();
    let fft = planner.plan_fft_forward(n);
    let mut spec = fft.make_output_vec();
    fft.process(&mut input, &mut spec).ok()?;
    let mag: Vec<f64> = spec.iter().map(|c| c.norm()).collect();
    let (k, a0) = mag
        .iter()
        .enumerate()
        .take((mag.len() - 1).min(bins.end))
        .skip(bins.start.max(2))
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    let (am, ap) = (mag[k - 1], mag[k + 1]);
    let delta = if am > 0.0 && ap > 0.0 && *a0 > 0.0 {
        let (lm, l0, lp) = (am.ln(), a0.ln(), ap.ln());
        let den = lm - 2.0 * l0 + lp;
        if den < 0.0 {
            (0.5 * (lm - lp) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    } else {
        0.0
    };
    Some(Peak {
        freq_hz: (k as f64 + delta) * rate_hz / n as f64,
        amplitude: 2.0 * a0 / sw,
    })
}

/// The dwells of `rec` (module docs) and the warnings for runs left out.
pub fn find(rec: &Recording, window_s: f64) -> Result<(Vec<Dwell>, Vec<Warning>)> {
    let d = &rec.samples;
    let n = d.time_s.len();
    let span = match (d.time_s.first(), d.time_s.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    let rate = if n > 1 && span > 0.0 {
        (n - 1) as f64 / span
    } else {
        0.0
    };
    let w = (window_s * rate).round() as usize;
    if w < 16 || n < 3 * w {
        return Err(Error::Unsupported(format!(
            "no freq_hz column: finding dwells from the reference needs windows (dwell_window_s {window_s} s) of 16 samples or more and a recording of three windows; it has {n} samples at {rate:.6} Hz"
        )));
    }
    let hop = w / 2;
    let mut planner = RealFftPlanner::new();
    let starts: Vec<usize> = (0..).map(|j| j * hop).take_while(|s| s + w <= n).collect();
    let peaks: Vec<Option<Peak>> = starts
        .iter()
        .map(|&s| peak(&d.reference[s..s + w], rate, &mut planner, 2..w))
        .collect();
    let top = peaks
        .iter()
        .flatten()
        .map(|p| p.amplitude)
        .fold(0.0, f64::max);
    let moving = |p: &Option<Peak>| p.filter(|p| p.amplitude > 1e-3 * top);
    let tol = |f: f64| (0.25 * rate / w as f64).max(1e-3 * f);
    // Runs of windows at one frequency: (first, last, frequencies).
    let mut runs: Vec<(usize, usize, Vec<f64>)> = Vec::new();
    for (j, p) in peaks.iter().enumerate() {
        let Some(p) = moving(p) else { continue };
        match runs.last_mut() {
            Some((_, last, fs)) if *last + 1 == j && (p.freq_hz - fs[0]).abs() <= tol(fs[0]) => {
                *last = j;
                fs.push(p.freq_hz);
            }
            _ => runs.push((j, j, vec![p.freq_hz])),
        }
    }
    let mut dwells = Vec::new();
    let mut warnings = Vec::new();
    for (j, k, mut fs) in runs {
        fs.sort_by(f64::total_cmp);
        let f = fs[fs.len() / 2];
        if k < j + 4 {
            if k >= j + 2 {
                warnings.push(Warning::new(
                    WarningCode::ShortRecord,
                    format!(
                        "lines {}-{}: {:.6} Hz held for {} windows of {window_s} s: too short to be found as a dwell (five windows and more); left out (give freq_hz, or a shorter dwell_window_s)",
                        rec.lines[starts[j]],
                        rec.lines[starts[k] + w - 1],
                        f,
                        k - j + 1
                    ),
                ));
            }
            continue;
        }
        let (a, b) = (starts[j + 2], starts[k - 2] + w);
        dwells.push(Dwell {
            freq_hz: f,
            first_line: rec.lines[a],
            last_line: rec.lines[b - 1],
            time_s: d.time_s[a..b].to_vec(),
            time_ref_s: if d.time_ref_s.len() == n {
                d.time_ref_s[a..b].to_vec()
            } else {
                Vec::new()
            },
            reference: d.reference[a..b].to_vec(),
            output: d.output[a..b].to_vec(),
            found: true,
        });
    }
    if dwells.is_empty() {
        return Err(Error::Unsupported(format!(
            "no freq_hz column, and no dwell found in the reference: no frequency is held for five windows of {window_s} s (give freq_hz, or another dwell_window_s)"
        )));
    }
    Ok((dwells, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recording(plan: &[(f64, f64, f64)], rate: f64) -> Recording {
        let mut rec = Recording::default();
        let mut t0 = 0.0;
        let mut i = 0usize;
        for &(f, dur, amp) in plan {
            let m = (dur * rate) as usize;
            for q in 0..m {
                let t = t0 + q as f64 / rate;
                rec.lines.push(i + 2);
                rec.samples.time_s.push(i as f64 / rate);
                let r = amp * (std::f64::consts::TAU * f * t).sin() + 0.3;
                rec.samples.reference.push(r);
                rec.samples.output.push(0.9 * r);
                i += 1;
            }
            t0 += m as f64 / rate;
        }
        rec
    }

    #[test]
    fn dwells_held_long_enough_are_found_with_their_frequency_and_still_parts_are_not() {
        let rec = recording(
            &[
                (2.0, 8.0, 1.0),
                (0.0, 2.0, 0.0),
                (7.5, 6.0, 0.5),
                (30.0, 6.0, 0.05),
                (55.0, 1.5, 0.05),
            ],
            500.0,
        );
        let (dwells, warnings) = find(&rec, 1.0).unwrap();
        let fs: Vec<f64> = dwells.iter().map(|d| d.freq_hz).collect();
        assert_eq!(fs.len(), 3, "{fs:?}");
        for (f, truth) in fs.iter().zip([2.0, 7.5, 30.0]) {
            assert!((f - truth).abs() < 0.05, "{fs:?}");
        }
        // Each dwell lies inside its own stretch of the recording.
        assert!(dwells[0].time_s[0] >= 0.0 && *dwells[0].time_s.last().unwrap() < 8.0);
        assert!(dwells[1].time_s[0] >= 10.0 && *dwells[1].time_s.last().unwrap() < 16.0);
        assert!(dwells[2].time_s[0] >= 16.0 && *dwells[2].time_s.last().unwrap() < 22.0);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].message.contains("55"), "{warnings:?}");
    }

    #[test]
    fn a_sweep_or_a_short_recording_has_no_dwell() {
        let mut rec = Recording::default();
        for i in 0..10_000 {
            let t = i as f64 / 1000.0;
            rec.lines.push(i + 2);
            rec.samples.time_s.push(t);
            rec.samples
                .reference
                .push((std::f64::consts::TAU * (1.0 + 2.0 * t) * t).sin());
            rec.samples.output.push(0.0);
        }
        let e = find(&rec, 1.0).unwrap_err().to_string();
        assert!(e.contains("no dwell found"), "{e}");
        let e = find(&rec, 5.0).unwrap_err().to_string();
        assert!(e.contains("three windows"), "{e}");
    }
}
