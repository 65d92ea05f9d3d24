//! Seeded simulation utilities shared by every rig simulator.
//!
//! Every random stream is a ChaCha8 generator seeded from an explicit `u64`.
//! Monte Carlo trials draw from per-trial seeds derived by SplitMix64, so a
//! parallel run gives exactly the numbers of a serial one.

/// The centrifuge simulator (lives with its procedure).
pub use crate::procedures::centrifuge::sim as centrifuge;
pub mod demo;
pub mod tier;
/// The gyro simulators (live with their procedures).
pub mod gyro {
    pub use crate::procedures::gyro::positions::sim::{
        simulate_positions, DriftTruth, GyroPositionsSim,
    };
    pub use crate::procedures::gyro::rate::sim::{simulate_rate, GyroRateSim};
}
/// The gyro-free unit simulator (lives with its procedure).
pub use crate::procedures::gfimu::sim as gfimu;
/// The IMU triad simulator (lives with its procedures).
pub use crate::procedures::imu::sim as imu;
/// The misalignment simulators (live with their procedures).
pub use crate::procedures::misalign::sim as misalign;
/// The noise simulator (lives with its procedure).
pub use crate::procedures::noise::sim as noise;
/// The tumble simulator (lives with its procedure).
pub use crate::procedures::tumble::sim as tumble;

use rand::rngs::ChaCha8Rng;
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;

/// Largest number of rows (or samples) a simulator writes.
pub const MAX_SIM_ROWS: u64 = 10_000_000;

/// Refuse a simulation whose size (`factors`, named, multiplied) exceeds
/// [`MAX_SIM_ROWS`]; the message names the factors and the limit.
pub fn check_rows(factors: &[(&str, f64)]) -> crate::Result<()> {
    let total: f64 = factors.iter().map(|f| f.1.max(0.0)).product();
    if total.is_finite() && total <= MAX_SIM_ROWS as f64 {
        Ok(())
    } else {
        let names: Vec<&str> = factors.iter().map(|f| f.0).collect();
        Err(crate::Error::Unsupported(format!(
            "the simulation would write {total:.3e} rows ({}); the limit is {MAX_SIM_ROWS}",
            names.join(" x ")
        )))
    }
}

/// A seeded ChaCha8 stream.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Seed of trial `k` of a run seeded with `seed` (SplitMix64 of `seed + k·φ`),
/// independent of execution order.
pub fn trial_seed(seed: u64, k: u64) -> u64 {
    let mut z = seed.wrapping_add(k.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Run `trials` Monte Carlo trials of `f(trial_seed)` in parallel, results
/// in trial order (identical to a serial run).
pub fn monte_carlo<T: Send>(seed: u64, trials: usize, f: impl Fn(u64) -> T + Sync) -> Vec<T> {
    (0..trials as u64)
        .into_par_iter()
        .map(|k| f(trial_seed(seed, k)))
        .collect()
}

/// A zero-mean normal draw with standard deviation `sigma` (0 when `sigma`
/// is 0 or invalid, so a noiseless simulation needs no special case).
pub fn normal(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    if sigma > 0.0 && sigma.is_finite() {
        Normal::new(0.0, sigma).map_or(0.0, |n| n.sample(rng))
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallel_equals_serial() {
        let par = monte_carlo(7, 64, |s| normal(&mut rng(s), 1.0));
        let ser: Vec<f64> = (0..64)
            .map(|k| normal(&mut rng(trial_seed(7, k)), 1.0))
            .collect();
        assert_eq!(par, ser);
        assert_ne!(par[0], par[1]);
    }
}
