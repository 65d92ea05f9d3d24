//! IMU triad calibration: three accelerometers and three gyros in one
//! package.
//!
//! * [`ferraris`]: the six-position + three-rotation method of Ferraris et
//!   al. (1995) with imucal's conventions and JSON keys, plus the
//!   uncertainty of every matrix element.
//! * [`multipos`]: least squares over any set of known orientations.
//! * [`autocal`]: calibration without a fixture (Tedaldi et al., ICRA 2014),
//!   in imu_tk's exact steps (`tedaldi`) or incal's weighted form with
//!   covariance.
//! * [`detect`]: the moving-variance static detector.
//! * [`input`]: the sessions' columns, segmentation and checks, and the
//!   CSV of simulated sessions; [`sim`]: the session simulator and
//!   [`sim_options`] its typed options;
//!   [`document`]: the result documents; [`apply`]: a calibration applied
//!   to a raw series, row by row.
//!
//! The three reductions are [`super::Procedure`]s:
//! [`ferraris::Ferraris`], [`multipos::Multipos`] and
//! [`autocal::Autocal`].
//!
//! # Frames and units
//! The IMU frame is the frame the positions and rotations are given in;
//! `f` is the specific force (`+g` along the axis that points up), `ω` the
//! angular rate (right-handed: counter-clockwise seen from the tip of the
//! axis is positive). Raw outputs are in any unit (counts or physical).

pub mod apply;
pub mod autocal;
pub mod detect;
pub mod document;
pub mod ferraris;
pub mod input;
mod montecarlo;
pub mod multipos;
pub mod plan;
pub mod screen;
pub mod sim;
pub mod sim_options;

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};

/// A 3-vector (one triad sample, a mean, a direction).
pub type V3 = Vector3<f64>;
/// A 3×3 matrix.
pub type M3 = Matrix3<f64>;

/// Axis letters, in the order of vector components.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// Mean and sample covariance (n − 1) of a set of 6-vectors (accelerometer
/// x, y, z then gyro x, y, z; a missing triad is zero).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionStats {
    /// Samples.
    pub n: usize,
    /// Mean of each of the six channels.
    pub mean: [f64; 6],
    /// Sample covariance (n − 1 denominator), row-major 6×6.
    pub cov: [[f64; 6]; 6],
    /// Sum of each channel (for integrals).
    pub sum: [f64; 6],
}

impl SectionStats {
    /// Statistics of `samples` (two-pass: mean, then centred products).
    pub fn of(samples: &[[f64; 6]]) -> Result<SectionStats> {
        let n = samples.len();
        if n == 0 {
            return Err(Error::TooFew {
                what: "samples in a section".into(),
                needed: 1,
                got: 0,
            });
        }
        let mut sum = [0.0; 6];
        for s in samples {
            for k in 0..6 {
                sum[k] += s[k];
            }
        }
        let mut mean = [0.0; 6];
        for k in 0..6 {
            mean[k] = sum[k] / n as f64;
        }
        let mut cov = [[0.0; 6]; 6];
        if n > 1 {
            for s in samples {
                let d: [f64; 6] = std::array::from_fn(|k| s[k] - mean[k]);
                for (row, dj) in cov.iter_mut().zip(d) {
                    for (c, dk) in row.iter_mut().zip(d) {
                        *c += dj * dk;
                    }
                }
            }
            for row in cov.iter_mut() {
                for c in row.iter_mut() {
                    *c /= (n - 1) as f64;
                }
            }
        }
        Ok(SectionStats { n, mean, cov, sum })
    }

    /// Accelerometer mean.
    pub fn acc(&self) -> V3 {
        V3::new(self.mean[0], self.mean[1], self.mean[2])
    }

    /// Gyro mean.
    pub fn gyr(&self) -> V3 {
        V3::new(self.mean[3], self.mean[4], self.mean[5])
    }

    /// Standard deviation of channel `k`.
    pub fn std(&self, k: usize) -> f64 {
        self.cov[k][k].max(0.0).sqrt()
    }
}

/// Check a gravity magnitude (option `gravity_m_s2`): finite, positive,
/// at most 100 (m/s² or any unit a lab uses for 1 g). A negative value is
/// refused: imucal's opposite sign convention is an option of its own
/// (`convention`, [`ferraris::Convention::Imucal`]).
pub fn check_gravity_magnitude(g: f64) -> Result<()> {
    if (-100.0..0.0).contains(&g) {
        return crate::options::invalid(
            "gravity_m_s2",
            format!(
                "must be a positive magnitude, got {}; for imucal's convention (the positive axis reads -g) give {} with --convention imucal",
                crate::error::short_number(&g.to_string()),
                crate::error::short_number(&(-g).to_string())
            ),
        );
    }
    crate::options::check_positive("gravity_m_s2", g)?;
    crate::options::check_range("gravity_m_s2", g, 0.0, 100.0, "m/s^2")
}

/// Check a sample rate (option `rate_hz`): finite, positive, at most 1 MHz.
pub fn check_rate_hz(rate_hz: f64) -> Result<()> {
    crate::options::check_positive("rate_hz", rate_hz)?;
    crate::options::check_range("rate_hz", rate_hz, 0.0, 1e6, "Hz")
}

/// Check the angle of the rotation sections (option `rotation_deg`):
/// finite, non-zero, at most 100 turns.
pub fn check_rotation_deg(a: f64) -> Result<()> {
    crate::options::check_range("rotation_deg", a, -36000.0, 36000.0, "deg")?;
    if a == 0.0 {
        return crate::options::invalid(
            "rotation_deg",
            "must be non-zero (the angle of each rotation section)",
        );
    }
    Ok(())
}

/// Rows of a 3×3 matrix as nested vectors (the JSON "list of rows").
pub fn rows(m: &M3) -> Vec<Vec<f64>> {
    (0..3)
        .map(|i| (0..3).map(|j| m[(i, j)]).collect())
        .collect()
}

/// Name of matrix element `(i, j)`: `NAME.xy`.
pub fn element_name(name: &str, i: usize, j: usize) -> String {
    format!("{name}.{}{}", AXES[i], AXES[j])
}

/// Name of vector element `i`: `NAME.x`.
pub fn component_name(name: &str, i: usize) -> String {
    format!("{name}.{}", AXES[i])
}
