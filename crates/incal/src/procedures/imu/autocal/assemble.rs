//! The result assembled from the fits: the report of every still
//! interval used, the distinct orientations, the joint estimates of the
//! accelerometer and gyro parameters, and the warnings in their order
//! (channels, separation, fit quality, spikes, time gaps, orientations).

use nalgebra::DVector;

use super::super::detect::Interval;
use super::super::sim::TriadParams;
use super::super::{detect, screen, V3};
use super::accel::{acc_names, acc_params};
use super::gyro::{gyr_names, GyroFit};
use super::session::Session;
use super::threshold::Candidate;
use super::{AutocalResult, IntervalReport, ThresholdTrial};
use crate::error::{Error, Result};
use crate::estimation::{Estimates, Fit};
use crate::warning::{Warning, WarningCode};

/// Count gravity directions more than 10° apart (greedy clustering).
fn distinct_orientations(dirs: &[V3]) -> usize {
    let mut reps: Vec<V3> = Vec::new();
    for d in dirs {
        if !reps.iter().any(|r| r.dot(d) > 10f64.to_radians().cos()) {
            reps.push(*d);
        }
    }
    reps.len()
}

/// The report of every interval (raw mean and scatter of its used
/// samples) and the distinct orientations of their calibrated gravity
/// directions.
fn interval_reports(
    s: &Session,
    intervals: &[Interval],
    acc_p: &TriadParams,
) -> (Vec<IntervalReport>, usize) {
    let mut reports = Vec::new();
    let mut dirs = Vec::new();
    for iv in intervals {
        let u = s.used(iv).unwrap_or(*iv);
        let m = detect::mean(&s.acc, u);
        let v = detect::variance(&s.acc, u);
        dirs.push(acc_p.apply(&V3::from(m)).normalize());
        reports.push(IntervalReport {
            interval: *iv,
            start_s: s.time[iv.start],
            end_s: s.time[iv.end],
            used: u.len(),
            mean: m,
            std: v.map(|a| a.max(0.0).sqrt()),
        });
    }
    (reports, distinct_orientations(&dirs))
}

/// The joint estimates: `acc.*` and, with a gyro, `gyr.*` and its bias,
/// with their joint covariance; dof the smaller of the two fits'.
fn joint_estimates(
    x_acc: &DVector<f64>,
    acc_fit: &Fit,
    gyro: Option<&GyroFit>,
) -> Result<Estimates> {
    let mut names = acc_names();
    let mut values: Vec<f64> = x_acc.iter().copied().collect();
    let cov = match gyro {
        None => acc_fit.estimates.covariance().clone(),
        Some(gf) => {
            names.extend(gyr_names());
            names.extend(["gyr.b_x", "gyr.b_y", "gyr.b_z"].map(String::from));
            values.extend(gf.x.iter().copied());
            values.extend(gf.bias);
            gf.cov.clone()
        }
    };
    let dof = match gyro {
        Some(gf) => acc_fit.estimates.dof().min(gf.fit.estimates.dof()),
        None => acc_fit.estimates.dof(),
    };
    if cov.iter().any(|v| !v.is_finite()) || values.iter().any(|v| !v.is_finite()) {
        return Err(Error::Unsupported(
            "autocalibration gave a non-finite result".into(),
        ));
    }
    Estimates::new(names, DVector::from_vec(values), cov, dof)
}

/// The accelerometer samples the Hampel filter mended in the used part of
/// each interval (incal).
fn acc_spikes(s: &Session, intervals: &[Interval]) -> Vec<(String, usize)> {
    let mut spikes = Vec::new();
    if !s.spike_flags.is_empty() {
        for iv in intervals {
            let u = s.used(iv).unwrap_or(*iv);
            let n = s.spike_flags[u.start..=u.end]
                .iter()
                .filter(|f| **f)
                .count();
            spikes.push((
                format!("acc {:.2}-{:.2} s", s.time[u.start], s.time[u.end]),
                n,
            ));
        }
    }
    spikes
}

/// The warnings of the fits: the misalignments hardly separated, and the
/// quality of the accelerometer fit and of the gyro fit.
fn fit_warnings(best: &Candidate, acc_fit: &Fit, gyro: Option<&GyroFit>) -> Vec<Warning> {
    let mut warnings = Vec::new();
    if let Some(e) = &best.separation {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!(
                "{}; the values and u of these terms rest on second-order effects and the gyro misalignments are relative to them",
                e.to_string().replacen("plan cannot separate", "this session hardly separates", 1)
            ),
        ));
    }
    warnings.extend(acc_fit.quality_warnings(
        "the sensor is not still in some intervals, or the model (scale, three misalignments, bias) does not hold",
    ));
    if let Some(gf) = gyro {
        warnings.extend(gf.fit.quality_warnings(
            "the sensor moves in the still intervals, rotates too fast for the sample rate, or the gyro model (scale, six misalignments, bias from the start) does not hold",
        ));
    }
    warnings
}

/// The warnings of the record: spikes mended, left out or reported, the
/// motions left out across time gaps or for clipped gyro samples, and too
/// few distinct orientations.
fn record_warnings(
    s: &Session,
    intervals: &[Interval],
    gyro: Option<&GyroFit>,
    orientations: usize,
) -> Vec<Warning> {
    let mut warnings = Vec::new();
    let (start_spikes, in_motion) = gyro.map_or((0, 0), |g| (g.start_spikes, g.in_motion));
    warnings.extend(screen::spikes_warning(
        &acc_spikes(s, intervals),
        screen::REPLACED,
    ));
    warnings.extend(screen::spikes_warning(
        &[("gyro still start".into(), start_spikes)],
        screen::LEFT_OUT,
    ));
    warnings.extend(screen::spikes_warning(
        &[("gyro between still intervals".into(), in_motion)],
        screen::NOT_CHANGED,
    ));
    let across = intervals
        .windows(2)
        .filter(|w| s.spans_gap(w[0].end, w[1].start))
        .count();
    if gyro.is_some() && across > 0 {
        warnings.push(Warning::new(
            WarningCode::TimeGaps,
            format!(
                "{across} of {} motions between still intervals span a time gap and are left out of the gyro fit (a rotation cannot be integrated across missing samples)",
                intervals.len() - 1
            ),
        ));
    }
    let clipped: &[usize] = gyro.map_or(&[], |g| &g.clipped);
    if !clipped.is_empty() {
        let at: Vec<String> = clipped
            .iter()
            .take(5)
            .map(|&k| {
                format!(
                    "{:.3}-{:.3} s",
                    s.time[intervals[k].end],
                    s.time[intervals[k + 1].start - 1]
                )
            })
            .collect();
        warnings.push(Warning::new(
            WarningCode::Clipped,
            format!(
                "{} of {} motions between still intervals hold gyro samples at a converter's rail ({}{}) and are left out of the gyro fit (a clipped rotation integrates to the wrong angle)",
                clipped.len(),
                intervals.len() - 1,
                at.join(", "),
                if clipped.len() > 5 { ", ..." } else { "" }
            ),
        ));
    }
    if orientations < 9 {
        warnings.push(Warning::new(
            WarningCode::WeakConditioning,
            format!(
                "only {orientations} distinct orientations (gravity directions more than 10 deg apart) among {} intervals: the scale and misalignment terms rest on few directions",
                intervals.len()
            ),
        ));
    }
    warnings
}

/// The result of [`super::autocal`] from the kept threshold `best`, the
/// final accelerometer fit and the gyro fit.
pub(super) fn assemble(
    s: Session,
    best: Candidate,
    trials: Vec<ThresholdTrial>,
    x_acc: DVector<f64>,
    acc_fit: Fit,
    gyro: Option<GyroFit>,
) -> Result<AutocalResult> {
    let acc_p = acc_params(&x_acc);
    let (reports, orientations) = interval_reports(&s, &best.intervals, &acc_p);
    let estimates = joint_estimates(&x_acc, &acc_fit, gyro.as_ref())?;
    let mut warnings = s.checked.clone();
    warnings.extend(fit_warnings(&best, &acc_fit, gyro.as_ref()));
    warnings.extend(record_warnings(
        &s,
        &best.intervals,
        gyro.as_ref(),
        orientations,
    ));
    let (gyr, gyr_fit) = match gyro {
        Some(g) => (Some(g.params), Some(g.fit)),
        None => (None, None),
    };
    Ok(AutocalResult {
        acc: acc_p,
        gyr,
        estimates,
        acc_fit,
        gyr_fit,
        intervals: reports,
        trials,
        k: best.k,
        threshold: best.k * s.norm_th,
        init: s.init,
        orientations,
        warnings,
        options: *s.opts,
    })
}
