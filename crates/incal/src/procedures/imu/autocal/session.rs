//! The record prepared for the autocalibration: the options and lengths
//! checked, the channels screened (incal: accelerometer spikes mended),
//! the initial still interval and its variance norm (the base of the
//! detector's thresholds), the moving-variance norms with the time-stamp
//! gaps, and the samples each still interval contributes.

use std::borrow::Cow;

use nalgebra::DVector;

use super::super::detect::{self, Interval};
use super::super::{check_gravity_magnitude, screen};
use super::{AutocalOptions, Method};
use crate::error::{Error, Result};
use crate::warning::Warning;

/// A record checked and screened, with what every step of the method
/// shares.
pub(super) struct Session<'a> {
    /// Time of each sample (s).
    pub time: &'a [f64],
    /// Accelerometer samples (incal: spikes mended).
    pub acc: Cow<'a, [[f64; 3]]>,
    /// Options.
    pub opts: &'a AutocalOptions,
    /// Gravity magnitude (m/s²).
    pub g: f64,
    /// The initial still interval.
    pub init: Interval,
    /// Warnings of the channel check.
    pub checked: Vec<Warning>,
    /// Accelerometer samples mended by the Hampel filter (incal; empty
    /// for tedaldi).
    pub spike_flags: Vec<bool>,
    /// Variance norm of the initial still interval (the threshold unit).
    pub norm_th: f64,
    /// Moving-variance norms, infinite beside a time gap.
    pub norms: Vec<Option<f64>>,
    /// Samples trimmed from both ends of each interval (incal).
    pub trim: usize,
    /// Time-stamp gaps (sample index after each gap; incal only).
    gaps: Vec<usize>,
}

/// Refuse options and a record the method cannot use: gravity, initial
/// duration, lengths, samples for the variance window and in the
/// initial still interval (which is returned).
fn check_record(
    time: &[f64],
    acc: &[[f64; 3]],
    gyr: Option<&[[f64; 3]]>,
    opts: &AutocalOptions,
) -> Result<Interval> {
    check_gravity_magnitude(opts.gravity)?;
    if !(opts.init_static_s.is_finite() && opts.init_static_s > 0.0) {
        return Err(Error::InvalidValue {
            what: "initial still duration (s, > 0)".into(),
            value: opts.init_static_s.to_string(),
        });
    }
    if time.len() != acc.len() || gyr.is_some_and(|v| v.len() != acc.len()) {
        return Err(Error::Unsupported(
            "time and triads differ in length".into(),
        ));
    }
    if acc.len() < opts.window.max(11) + 1 {
        return Err(Error::TooFew {
            what: format!("samples for a {}-sample variance window", opts.window),
            needed: opts.window.max(11) + 1,
            got: acc.len(),
        });
    }
    let init = detect::initial_interval(time, opts.init_static_s);
    if init.len() < 3 {
        return Err(Error::TooFew {
            what: "samples in the initial still interval (--init-static-s)".into(),
            needed: 3,
            got: init.len(),
        });
    }
    Ok(init)
}

/// The channel check of all six channels ([`screen::ChannelCheck`]): its
/// warnings, or the refusal of a dead or clipped channel.
fn check_channels(acc: &[[f64; 3]], gyr: Option<&[[f64; 3]]>) -> Result<Vec<Warning>> {
    let mut checked = Vec::new();
    let mut channels = screen::ChannelCheck::<6>::default();
    for (i, a) in acc.iter().enumerate() {
        let w = gyr.map_or([0.0; 3], |g| g[i]);
        channels.push(&[a[0], a[1], a[2], w[0], w[1], w[2]]);
    }
    channels.finish(&screen::session_channels(gyr.is_some()), &mut checked)?;
    Ok(checked)
}

impl<'a> Session<'a> {
    /// Check and screen a record (module docs).
    pub fn prepare(
        time: &'a [f64],
        acc: &'a [[f64; 3]],
        gyr: Option<&[[f64; 3]]>,
        opts: &'a AutocalOptions,
    ) -> Result<Self> {
        let init = check_record(time, acc, gyr, opts)?;
        let checked = check_channels(acc, gyr)?;
        // incal: accelerometer spikes mended by a Hampel filter scaled by the
        // still start's robust scatter before the detector and the means;
        // tedaldi: imu_tk's steps, as read.
        let (acc, spike_flags) = if opts.method == Method::Incal {
            let scale = screen::triad_scale(&acc[init.start..=init.end], 0);
            let (a, f) = screen::hampel(acc, scale);
            (Cow::Owned(a), f)
        } else {
            (Cow::Borrowed(acc), Vec::new())
        };
        let norm_th = detect::norm3(detect::variance(&acc, init));
        if norm_th.is_nan() || norm_th <= 0.0 {
            return Err(Error::Unsupported(
                "the initial still interval has zero accelerometer variance: the threshold k*||var|| is 0 and nothing is still (a noise-free or saturated record?)".into(),
            ));
        }
        // incal: the time-stamp policy's gaps (a still interval never spans
        // one; a motion across one is left out of the gyro fit). tedaldi:
        // imu_tk's steps, no gap handling.
        let gaps: Vec<usize> = if opts.method == Method::Incal {
            crate::timebase::gap_indices(time)
        } else {
            Vec::new()
        };
        let mut norms = detect::variance_norms(&acc, opts.window);
        for &g in &gaps {
            // Both samples beside a gap read as moving: intervals end there.
            norms[g - 1] = Some(f64::INFINITY);
            norms[g] = Some(f64::INFINITY);
        }
        let dt_mean = (time[time.len() - 1] - time[0]) / (time.len() - 1) as f64;
        let trim = if opts.method == Method::Incal {
            (opts.settle_s / dt_mean).round() as usize
        } else {
            0
        };
        Ok(Session {
            time,
            acc,
            opts,
            g: opts.gravity.abs(),
            init,
            checked,
            spike_flags,
            norm_th,
            norms,
            trim,
            gaps,
        })
    }

    /// The samples an interval contributes (tedaldi: its first
    /// `min_samples`; incal: all, trimmed by the settle time), or `None`
    /// when it is too short.
    pub fn used(&self, iv: &Interval) -> Option<Interval> {
        let opts = self.opts;
        if iv.len() < opts.min_samples {
            return None;
        }
        match opts.method {
            Method::Tedaldi => Some(Interval {
                start: iv.start,
                end: iv.start + opts.min_samples - 1,
            }),
            Method::Incal => (iv.len() >= opts.min_samples + 2 * self.trim).then_some(Interval {
                start: iv.start + self.trim,
                end: iv.end - self.trim,
            }),
        }
    }

    /// Whether the motion from sample `end` to sample `start` spans a
    /// time gap.
    pub fn spans_gap(&self, end: usize, start: usize) -> bool {
        self.gaps.iter().any(|&g| g > end && g <= start)
    }

    /// The accelerometer's fallback start: no misalignment, no bias, the
    /// scale g over the median magnitude of the interval means at the
    /// threshold `2‖var‖` (or of the initial interval's mean).
    pub fn acc_fallback(&self) -> DVector<f64> {
        let acc = &self.acc[..];
        let g_est = {
            // Starting scale: g over the typical magnitude of interval means.
            let iv = detect::intervals_from_norms(&self.norms, 2.0 * self.norm_th);
            let mut mags: Vec<f64> = iv
                .iter()
                .filter(|i| i.len() >= 3)
                .map(|i| detect::norm3(detect::mean(acc, *i)))
                .collect();
            mags.sort_by(f64::total_cmp);
            if mags.is_empty() {
                detect::norm3(detect::mean(acc, self.init))
            } else {
                mags[mags.len() / 2]
            }
        };
        let s0 = if g_est > 0.0 { self.g / g_est } else { 1.0 };
        DVector::from_vec(vec![0.0, 0.0, 0.0, s0, s0, s0, 0.0, 0.0, 0.0])
    }
}
