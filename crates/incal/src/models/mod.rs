//! Instrument error models.

pub mod accelerometer;
pub mod gfimu;

pub use accelerometer::{AccelerometerModel, SpecificForce, Term};
