//! The two test tiers of incal's own validation, and the one switch between
//! them: `INCAL_TESTS=full` in the environment.
//!
//! The default tier (a developer's `cargo test`) checks every behaviour and
//! refusal and runs each Monte Carlo at the smallest count that still fails
//! on a broken uncertainty; the statistical tier runs the hundreds of seeds,
//! kill -9 loops and long campaigns (`INCAL_TESTS=full cargo test
//! --workspace`; `.ci/run` runs both). A coverage check takes its count from
//! [`trials`] and its band from [`band`]: in the full tier the band asserted
//! is the one the test states; in the fast tier it is widened to three
//! binomial standard deviations of the smaller count, so that an honest U95
//! passes at any seed while a U95 too small by a factor of two (coverage
//! about 68 % for a normal error) still fails.

/// Whether the statistical tier runs (`INCAL_TESTS=full`).
pub fn full() -> bool {
    std::env::var("INCAL_TESTS").is_ok_and(|v| v == "full")
}

/// `fast` in the default tier, `full` in the statistical tier.
pub fn trials(fast: usize, full_count: usize) -> usize {
    if full() {
        full_count
    } else {
        fast
    }
}

/// The band `[lo, hi]` a rate over `n` trials is asserted in: as stated in
/// the statistical tier (or when `n` is at least the count the band was
/// written for), else widened to `p ± 3 sqrt(p (1 − p) / n)` around its
/// centre `p = (lo + hi) / 2`, clipped to `[0, 1]`.
pub fn band(n: usize, lo: f64, hi: f64) -> (f64, f64) {
    if full() || n == 0 {
        return (lo, hi);
    }
    let p = 0.5 * (lo + hi);
    let s = 3.0 * (p * (1.0 - p) / n as f64).sqrt();
    ((p - s).min(lo).max(0.0), (p + s).max(hi).min(1.0))
}

/// Three binomial standard deviations of a rate `p` over `n` trials in
/// the fast tier (0 in the statistical tier, where a bound is asserted as
/// written).
fn spread(n: usize, p: f64) -> f64 {
    if full() || n == 0 {
        0.0
    } else {
        3.0 * (p.clamp(0.0, 1.0) * (1.0 - p.clamp(0.0, 1.0)) / n as f64).sqrt()
    }
}

/// The largest rate asserted for something that should happen at most at
/// rate `p` (a false inclusion, a miss): `p` in the statistical tier, `p`
/// plus three binomial spreads of `n` trials in the fast tier.
pub fn at_most(n: usize, p: f64) -> f64 {
    (p + spread(n, p)).min(1.0)
}

/// The smallest rate asserted for something that should happen at least
/// at rate `p` (a coverage, a find): `p` in the statistical tier, `p` less
/// three binomial spreads of `n` trials in the fast tier.
pub fn at_least(n: usize, p: f64) -> f64 {
    (p - spread(n, p)).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_count_widens_the_band_but_still_refuses_a_halved_uncertainty() {
        if full() {
            return;
        }
        let (lo, hi) = band(40, 0.93, 0.97);
        assert!(lo < 0.93 && hi > 0.97);
        // U95 half the truth covers about 68 % of normal errors.
        assert!(lo > 0.75, "{lo}");
        assert_eq!(band(0, 0.93, 0.97), (0.93, 0.97));
    }
}
