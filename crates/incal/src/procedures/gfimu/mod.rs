//! Six-accelerometer gyro-free inertial unit (GFIMU note; docs/src/gfimu.md):
//! multi-position calibration of every accelerometer's equivalent bias K0
//! and equivalent sensitive-direction vector Ks ([`calibrate`](mod@calibrate)), and the
//! compensated angular-motion solution ([`solve`](mod@solve)).
//!
//! # Model (GFIMU note eq. 8, docs/src/gfimu.md)
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

//!
//! # Files
//! [`input`] reads the geometry (TOML), the static CSV, the calibration
//! JSON and the motion series; [`GfimuCalibrate`] is the calibration as
//! one [`super::Procedure`]; [`plan`] predicts its uncertainty;
//! [`sim`] simulates both tests; [`stream`] runs the motion solution row
//! by row (a streaming tool, not a reduction).

pub mod calibrate;
pub mod document;
pub mod input;
pub mod plan;
pub mod sim;
pub mod solve;
pub mod stream;

pub use calibrate::{
    calibrate, six_position, AccelerometerCalibration, CalibrateOptions, GfimuCalibration,
    K0Consistency, SixPosition, StaticSample, DERIVED_TERMS, LINEAR_TERMS,
};
pub use solve::{solve, CalibratedAccelerometer, MotionSample, MotionSolution, SolveOptions};

use crate::error::Result;
use crate::estimation::Noise;

/// Options of the calibration ([`GfimuCalibrate`]): the array and the
/// noise policy. Serialised as `{"geometry": label, "noise": σ | null}`.
#[derive(Debug, Clone, PartialEq)]
pub struct GfimuCalibrateOptions {
    /// The array whose accelerometers are calibrated.
    pub array: input::ArrayGeometry,
    /// Noise policy of the position means ([`Noise`]).
    pub noise: Noise,
}

impl serde::Serialize for GfimuCalibrateOptions {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(2))?;
        m.serialize_entry("geometry", &self.array.label)?;
        m.serialize_entry("noise", &self.noise.sigma())?;
        m.end()
    }
}

/// The multi-position static calibration of a gyro-free unit as one
/// [`super::Procedure`]: the static CSV ([`input::read_static`]) into
/// K0 and Ks of every accelerometer ([`calibrate()`]) and the result
/// document ([`GfimuCalibration::document`]), with the geometry file (if
/// any) among its inputs.
#[derive(Debug, Clone, Copy, Default)]
pub struct GfimuCalibrate;

impl super::Procedure for GfimuCalibrate {
    const ID: crate::document::Procedure = crate::document::Procedure::GfimuCalibrate;
    type Options = GfimuCalibrateOptions;
    type Input = Vec<StaticSample>;

    fn validate(o: &GfimuCalibrateOptions) -> Result<()> {
        o.noise.validate()
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &GfimuCalibrateOptions,
    ) -> Result<Vec<StaticSample>> {
        input::read_static(rows, &o.array.geometry)
    }

    fn reduce(
        samples: &Vec<StaticSample>,
        o: &GfimuCalibrateOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let cal = calibrate(
            &o.array.geometry,
            samples,
            &CalibrateOptions { noise: o.noise },
        )?;
        let mut doc = cal.document(&o.array.label, o.noise.sigma().is_some())?;
        doc.inputs.extend(o.array.file.clone());
        Ok(doc)
    }
}
