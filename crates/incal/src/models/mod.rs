//! Instrument error models.

pub mod accelerometer;

pub use accelerometer::{AccelerometerModel, SpecificForce, Term};
