//! One τ of a deviation series: the deviation, its χ² bounds at the
//! confidence asked, its EDF and the number of terms summed.

use super::{edf, DevSeries};

/// One τ of a [`DevSeries`]: the deviation, its χ² bounds, EDF and terms.
pub(super) struct Point {
    value: Option<f64>,
    bounds: Option<(f64, f64)>,
    edf: Option<f64>,
    n: usize,
}

impl Point {
    pub(super) fn push_to(self, s: &mut DevSeries) {
        s.value.push(self.value);
        s.lo.push(self.bounds.map(|b| b.0));
        s.hi.push(self.bounds.map(|b| b.1));
        s.edf.push(self.edf);
        s.n.push(self.n);
    }
}

/// The point of variance `v` (and its terms) with EDF `edf`: the
/// deviation √v and its bounds at confidence `p`.
pub(super) fn point(v: Option<(f64, usize)>, edf: Option<f64>, p: f64) -> Point {
    let (value, n) = match v {
        Some((var, n)) if var.is_finite() && var >= 0.0 => (Some(var.sqrt()), n),
        Some((_, n)) => (None, n),
        None => (None, 0),
    };
    let bounds = match (value, edf) {
        (Some(d), Some(e)) => edf::chi2_bounds(d, e, p),
        _ => None,
    };
    Point {
        value,
        bounds,
        edf: edf.filter(|e| e.is_finite()),
        n,
    }
}

pub(super) fn push(s: &mut DevSeries, v: Option<(f64, usize)>, edf: Option<f64>, p: f64) {
    point(v, edf, p).push_to(s);
}
