//! # incal — inertial-instrument calibration core
//!
//! Pure library: instrument error models, rig kinematics, one least-squares
//! estimation core, calibration procedures, test-plan prediction and rig
//! simulators. It reads no files and prints nothing; the `incal` binary
//! (crate `incal-cli`) does that.
//!
//! Every procedure follows docs/src/result-document.md: a test plan and the rig's
//! kinematics give the inputs of each observation, the error model is linear
//! in a parameter vector (design matrix), [`estimation::fit`] solves it with
//! covariance and rank/condition diagnostics, and a map with its Jacobian
//! gives the physical coefficients ([`estimation::Estimates::map`]).
//!
//! # Conventions
//! * Angles are radians inside; degrees and arcseconds only in plans and at
//!   the command-line edge ([`units`]).
//! * Accelerations are in units of local gravity `g` unless a name says
//!   otherwise; accelerometer coefficients are in g units (K0 in g, K2 in
//!   g/g², …), the scale factor K1 in output units per g.
//! * Every random thing takes an explicit `u64` seed ([`sim::rng`]).

#![warn(missing_docs)]

pub mod document;
pub mod error;
pub mod estimation;
pub mod units;
pub mod validity;
pub mod warning;

pub use error::{Alias, Error, Result};
pub use warning::{Warning, WarningCode};
pub mod models;
pub mod montecarlo;
pub mod noise;
pub mod options;
pub mod procedures;
pub mod rigs;
pub mod sim;
pub mod spectral;
pub mod timebase;
