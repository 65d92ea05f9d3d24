//! Six-accelerometer gyro-free inertial unit (seed 004; methods.md §4):
//! multi-position calibration of every accelerometer's equivalent bias K0
//! and equivalent sensitive-direction vector Ks ([`calibrate`]), and the
//! compensated angular-motion solution ([`solve`]).
//!
//! # Model (seed 004 eq. 8, methods.md §4)
//! Accelerometer j reads
//!
//! ```text
//! E_j = K0_j + Ks_jᵀ f_j
//! ```
//!
//! | symbol | unit | meaning |
//! |---|---|---|
//! | `E_j` | output (V, mA, counts) | indicated output |
//! | `K0_j` | output | equivalent bias `k1·k0` |
//! | `Ks_j` | output/g | equivalent sensitive-direction vector `k1 (l_i + d)` |
//! | `f_j` | g | specific force at the accelerometer, unit frame |
//!
//! `|Ks|` is the scale factor, `Ks/|Ks|` the true sensitive axis, and the
//! components of Ks across the nominal direction the cross-coupling.

pub mod calibrate;
pub mod solve;

pub use calibrate::{
    calibrate, six_position, AccelerometerCalibration, CalibrateOptions, GfimuCalibration,
    K0Consistency, SixPosition, StaticSample, DERIVED_TERMS, LINEAR_TERMS,
};
pub use solve::{solve, CalibratedAccelerometer, MotionSample, MotionSolution, SolveOptions};
