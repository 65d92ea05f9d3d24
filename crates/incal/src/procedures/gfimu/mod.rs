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
mod montecarlo;
pub mod plan;
pub mod sim;
pub mod sim_options;
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
/// noise policy. Recorded as `{"geometry": label, "noise": σ | null}`
/// ([`input::ArrayChoice::label`]).
#[derive(
    Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct GfimuCalibrateOptions {
    /// The array whose accelerometers are calibrated.
    #[serde(flatten)]
    pub array: input::ArrayChoice,
    /// Noise policy of the position means ([`Noise`]).
    #[serde(default)]
    pub noise: Noise,
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

    fn example() -> GfimuCalibrateOptions {
        GfimuCalibrateOptions {
            array: input::ArrayChoice::default(),
            noise: crate::estimation::Noise::Auto,
        }
    }

    fn validate(o: &GfimuCalibrateOptions) -> Result<()> {
        o.noise.validate()?;
        o.array.load().map(|_| ())
    }

    fn read<R: std::io::Read>(
        rows: &mut incal_io::Reader<R>,
        o: &GfimuCalibrateOptions,
    ) -> Result<Vec<StaticSample>> {
        input::read_static(rows, &o.array.load()?.geometry)
    }

    fn reduce(
        samples: &Vec<StaticSample>,
        o: &GfimuCalibrateOptions,
        _: &dyn super::Progress,
    ) -> Result<crate::document::ResultDocument> {
        let array = o.array.load()?;
        let cal = calibrate(
            &array.geometry,
            samples,
            &CalibrateOptions { noise: o.noise },
        )?;
        let mut doc = cal.document(&array.label, o.noise.sigma().is_some())?;
        doc.inputs.extend(array.file);
        Ok(doc)
    }

    fn recorded(
        _: &Vec<StaticSample>,
        o: &GfimuCalibrateOptions,
    ) -> Result<std::collections::BTreeMap<String, serde_json::Value>> {
        let mut m = super::options_map(o)?;
        m.insert("geometry".into(), o.array.label().into());
        Ok(m)
    }

    fn synthesis(
        samples: &Vec<StaticSample>,
        o: &GfimuCalibrateOptions,
        _: &crate::document::ResultDocument,
    ) -> Result<Option<crate::montecarlo::Synthesis<Vec<StaticSample>>>> {
        montecarlo::synthesis(samples, o).map(Some)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::options::from_json;
    use crate::procedures::{Plan, Procedure};
    use serde_json::json;

    fn key_of(r: Result<impl std::fmt::Debug>) -> String {
        crate::options::refused_key(r)
    }

    #[test]
    fn options_round_trip_and_name_a_bad_key() {
        let o: GfimuCalibrateOptions = from_json(&json!({})).unwrap();
        assert_eq!(o, GfimuCalibrateOptions::default());
        let shown = serde_json::to_value(&o).unwrap();
        assert_eq!(shown, json!({"noise": null}));
        assert_eq!(from_json::<GfimuCalibrateOptions>(&shown).unwrap(), o);
        let o: GfimuCalibrateOptions =
            from_json(&json!({"layout": "twelve", "lever_arm_m": 0.2, "noise": 1e-3})).unwrap();
        assert_eq!(o.noise, Noise::Known { sigma: 1e-3 });
        assert_eq!(o.array.label(), o.array.load().unwrap().label);
        assert_eq!(
            o.array.label(),
            "twelve-accelerometer layout, lever arm 0.2 m"
        );
        let bad = |v| {
            key_of(
                from_json::<GfimuCalibrateOptions>(&v).and_then(|o| GfimuCalibrate::validate(&o)),
            )
        };
        assert_eq!(bad(json!({"lever_arm_m": 0.0})), "lever_arm_m");
        assert_eq!(bad(json!({"layout": "paper", "lever": 1.0})), "lever");

        let p: plan::GfimuPlanOptions = from_json(&json!({"noise": 1e-4})).unwrap();
        assert_eq!(
            from_json::<plan::GfimuPlanOptions>(&serde_json::to_value(&p).unwrap()).unwrap(),
            p
        );
        let d = GfimuCalibrate::plan(&p).unwrap();
        assert_eq!(d.options["geometry"], "paper layout, lever arm 0.1 m");
        assert_eq!(d.options["positions"].as_array().map(Vec::len), Some(6));
        assert_eq!(
            (d.options["samples"].clone(), d.options["k1"].clone()),
            (json!(1), json!(1.0))
        );
        let bad = plan::GfimuPlanOptions {
            samples: 0,
            ..p.clone()
        };
        assert_eq!(key_of(GfimuCalibrate::plan(&bad)), "samples");
        let bad = plan::GfimuPlanOptions { noise: -1.0, ..p };
        assert_eq!(key_of(GfimuCalibrate::plan(&bad)), "noise");
    }
}
