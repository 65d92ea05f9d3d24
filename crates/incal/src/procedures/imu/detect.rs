//! The moving-variance static detector (Tedaldi et al. 2014, as imu_tk
//! implements it).
//!
//! A sample `i` is still when the norm of the per-axis variance (n − 1
//! denominator) of the accelerometer over the centred window
//! `[i − h, i + h]` (`2h + 1` samples, at least 11, odd) is below a
//! threshold; a still interval runs from the first still sample to the last
//! one before the next moving sample. Samples within `h` of either end of
//! the record are never classified (the window does not fit). The
//! threshold is `k · ‖var(initial still interval)‖`.

/// An interval of sample indices, both ends included.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interval {
    /// First sample.
    pub start: usize,
    /// Last sample (included).
    pub end: usize,
}

impl Interval {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.end + 1 - self.start
    }
    /// Never empty (kept for clippy's `len` rule).
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Mean of samples `start..=end`.
pub fn mean(x: &[[f64; 3]], iv: Interval) -> [f64; 3] {
    let mut m = [0.0; 3];
    for s in &x[iv.start..=iv.end] {
        for k in 0..3 {
            m[k] += s[k];
        }
    }
    let n = iv.len() as f64;
    m.map(|v| v / n)
}

/// Per-axis variance (n − 1 denominator) of samples `start..=end`, two-pass.
pub fn variance(x: &[[f64; 3]], iv: Interval) -> [f64; 3] {
    let m = mean(x, iv);
    let mut v = [0.0; 3];
    for s in &x[iv.start..=iv.end] {
        for k in 0..3 {
            let d = s[k] - m[k];
            v[k] += d * d;
        }
    }
    let n = iv.len() as f64;
    v.map(|a| a / (n - 1.0))
}

/// Euclidean norm of a 3-vector.
pub fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The windowed-variance norm of every sample (`None` within `h` of the
/// ends), window `2h + 1` as described in the module docs.
pub fn variance_norms(x: &[[f64; 3]], window: usize) -> Vec<Option<f64>> {
    let w = if window < 11 { 11 } else { window | 1 };
    let h = w / 2;
    let n = x.len();
    let mut out = vec![None; n];
    if w >= n {
        return out;
    }
    for (i, o) in out.iter_mut().enumerate().take(n - h).skip(h) {
        *o = Some(norm3(variance(
            x,
            Interval {
                start: i - h,
                end: i + h,
            },
        )));
    }
    out
}

/// Still intervals for a threshold, from precomputed [`variance_norms`].
pub fn intervals_from_norms(norms: &[Option<f64>], threshold: f64) -> Vec<Interval> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    let mut last_classified = None;
    for (i, v) in norms.iter().enumerate() {
        let Some(v) = v else { continue };
        last_classified = Some(i);
        match start {
            None if *v < threshold => start = Some(i),
            Some(s) if *v >= threshold => {
                out.push(Interval {
                    start: s,
                    end: i - 1,
                });
                start = None;
            }
            _ => {}
        }
    }
    if let (Some(s), Some(e)) = (start, last_classified) {
        out.push(Interval { start: s, end: e });
    }
    out
}

/// Index of the sample nearest to time `t` (imu_tk's `timeToIndex`: a tie
/// goes to the later sample).
pub fn time_to_index(time: &[f64], t: f64) -> usize {
    let (mut i0, mut i1) = (0usize, time.len() - 1);
    while i1 - i0 > 1 {
        let m = (i0 + i1) / 2;
        if t > time[m] {
            i0 = m;
        } else {
            i1 = m;
        }
    }
    if t - time[i0] < time[i1] - t {
        i0
    } else {
        i1
    }
}

/// The initial still interval: samples from the first to the one nearest
/// `time[0] + duration` (the whole record if it is shorter).
pub fn initial_interval(time: &[f64], duration: f64) -> Interval {
    let end_t = time[0] + duration;
    let end = if end_t >= time[time.len() - 1] {
        time.len() - 1
    } else {
        time_to_index(time, end_t)
    };
    Interval { start: 0, end }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_still_stretches() {
        let mut x = vec![[0.0, 0.0, 1.0]; 300];
        for (i, s) in x.iter_mut().enumerate().take(200).skip(150) {
            s[0] = (i as f64).sin();
        }
        let norms = variance_norms(&x, 21);
        let iv = intervals_from_norms(&norms, 1e-6);
        assert_eq!(iv.len(), 2);
        assert_eq!(
            iv[0],
            Interval {
                start: 10,
                end: 139
            }
        );
        assert_eq!(iv[1].start, 210);
        assert_eq!(iv[1].end, 289);
    }

    #[test]
    fn nearest_time_index() {
        let t: Vec<f64> = (0..10).map(|i| i as f64).collect();
        assert_eq!(time_to_index(&t, 3.4), 3);
        assert_eq!(time_to_index(&t, 3.5), 4);
        assert_eq!(initial_interval(&t, 50.0).end, 9);
    }
}
