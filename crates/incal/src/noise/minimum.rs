//! The Allan deviation's minimum: what a record determines about its
//! flat floor whether or not the floor is bias instability (flicker),
//! the corner of white noise into a rate random walk, or both (IEEE Std
//! 952-1997 Annex C reads B at the floor, `σ_min = 0.664 B`, when flicker
//! makes it; a datasheet's "bias instability" is often this number).

use super::DevSeries;

/// The least overlapping Allan deviation over the τ grid and where the
/// curve stays on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AllanMinimum {
    /// τ of the least estimate (s).
    pub tau_s: f64,
    /// The least estimate σ̂_min (rate unit).
    pub adev: f64,
    /// Its standard uncertainty, `σ̂/√(2ν)` from the estimate's EDF ν
    /// (σ̂² is χ²-distributed with ν degrees of freedom).
    pub u_adev: f64,
    /// The EDF ν at the minimum (the uncertainty's dof).
    pub dof: f64,
    /// The floor's span: the contiguous τ around `tau_s` whose σ̂ lies
    /// below the minimum's 95 % upper bound `σ̂_min + 1.96·u` (s).
    pub tau_low_s: f64,
    /// Upper end of the span (s).
    pub tau_high_s: f64,
}

/// The minimum of `oadev` over `taus` when it lies inside the τ range
/// (not at its first or last estimate: a curve still falling, or rising
/// from the start, has no floor in the record), else `None`.
///
/// The least of many estimates sits low in its own scatter (by up to
/// about one u over a floor a decade wide); u is the estimate's own, as
/// Stable32 and the datasheets state it.
pub fn allan_minimum(taus: &[f64], oadev: &DevSeries) -> Option<AllanMinimum> {
    let pts: Vec<(f64, f64, f64)> = taus
        .iter()
        .enumerate()
        .filter_map(|(i, &t)| {
            let (s, e) = (oadev.value.get(i)?.as_ref()?, oadev.edf.get(i)?.as_ref()?);
            (s.is_finite() && *s > 0.0 && e.is_finite() && *e > 0.0).then_some((t, *s, *e))
        })
        .collect();
    let (k, &(tau_s, adev, dof)) = pts
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))?;
    if k == 0 || k + 1 == pts.len() {
        return None;
    }
    let u_adev = adev / (2.0 * dof).sqrt();
    let top = adev + 1.96 * u_adev;
    let low = pts[..k].iter().rev().take_while(|p| p.1 <= top).last();
    let high = pts[k + 1..].iter().take_while(|p| p.1 <= top).last();
    Some(AllanMinimum {
        tau_s,
        adev,
        u_adev,
        dof,
        tau_low_s: low.map_or(tau_s, |p| p.0),
        tau_high_s: high.map_or(tau_s, |p| p.0),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn series(v: &[f64]) -> DevSeries {
        let n = v.len();
        DevSeries {
            value: v.iter().map(|&x| Some(x)).collect(),
            lo: vec![None; n],
            hi: vec![None; n],
            edf: vec![Some(50.0); n],
            n: vec![1; n],
        }
    }

    #[test]
    fn the_floor_its_u_and_its_span() {
        let taus = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
        let m = allan_minimum(&taus, &series(&[5.0, 2.0, 1.05, 1.0, 1.2, 3.0])).unwrap();
        assert_eq!((m.tau_s, m.adev, m.dof), (8.0, 1.0, 50.0));
        assert!((m.u_adev - 0.1).abs() < 1e-12);
        // 1.05 is within 1 + 1.96·0.1; 1.2 is not.
        assert_eq!((m.tau_low_s, m.tau_high_s), (4.0, 8.0));
    }

    #[test]
    fn a_curve_falling_to_its_end_has_no_floor() {
        let taus = [1.0, 2.0, 4.0];
        assert!(allan_minimum(&taus, &series(&[3.0, 2.0, 1.0])).is_none());
        assert!(allan_minimum(&taus, &series(&[1.0, 2.0, 3.0])).is_none());
        assert!(allan_minimum(&[], &series(&[])).is_none());
    }
}
