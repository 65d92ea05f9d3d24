//! The options of `incal simulate gfimu` ([`GfimuSimOptions`]), typed once
//! for every front end: engineering units, the command line's defaults, one
//! conversion into the simulator's configuration ([`GfimuSim`]).

use nalgebra::Vector3;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::input::ArrayChoice;
use super::sim::{F0Frame, GfimuSim, MotionProfile, SimKind};
use crate::error::Result;

/// What a simulated gyro-free unit test records.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum GfimuSimKind {
    /// The six-position static test: the input of `gfimu calibrate`.
    #[default]
    Static,
    /// A rate-table motion: the input of `gfimu solve`.
    Motion,
}

/// The frame the specific force at the origin is fixed in
/// ([`F0Frame`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum F0FrameOption {
    /// Fixed in the unit frame (does not turn).
    #[default]
    Unit,
    /// Fixed in the table frame at t = 0 (turns through the unit).
    Table,
}

/// The options of a simulated gyro-free unit test: the array, a truth built
/// from a nominal scale factor, white output noise, a static test or a
/// rate-table motion ([`MotionProfile`]; its fields apply to `motion`
/// only), and the seed. Defaults are those of `incal simulate gfimu`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct GfimuSimOptions {
    /// Static (six-position calibration test) or motion (time series).
    #[serde(default)]
    pub kind: GfimuSimKind,
    /// The array: a geometry file or a built-in layout.
    #[serde(flatten)]
    pub array: ArrayChoice,
    /// Nominal scale factor of every accelerometer (output/g).
    #[serde(default = "d_k1")]
    pub k1: f64,
    /// Output noise σ of one sample (output units).
    #[serde(default = "d_noise")]
    pub noise: f64,
    /// Samples per static position.
    #[serde(default = "d_samples")]
    pub samples: usize,
    /// Motion: record length (s).
    #[serde(default = "d_duration")]
    pub duration_s: f64,
    /// Motion: sample rate (Hz).
    #[serde(default = "d_rate")]
    pub rate_hz: f64,
    /// Motion: spin-up duration with constant angular acceleration (s).
    #[serde(default = "d_spin_up")]
    pub spin_up_s: f64,
    /// Motion: angular acceleration during spin-up (rad/s²).
    #[serde(default = "d_alpha")]
    pub angular_accel_rad_s2: f64,
    /// Motion: rotation axis x, y, z (unit frame).
    #[serde(default = "d_axis")]
    pub axis: [f64; 3],
    /// Motion: angular rate at t = 0 (rad/s), x, y, z.
    #[serde(default)]
    pub omega0_rad_s: [f64; 3],
    /// Motion: specific force at the origin (g), x, y, z.
    #[serde(default = "d_f0")]
    pub f0_g: [f64; 3],
    /// Motion: the frame `f0_g` is fixed in.
    #[serde(default)]
    pub f0_frame: F0FrameOption,
    /// Motion: amplitude of a sinusoidal rate oscillation about the axis
    /// (rad/s).
    #[serde(default)]
    pub oscillation_amplitude_rad_s: f64,
    /// Motion: frequency of the rate oscillation (Hz, below half the
    /// sample rate).
    #[serde(default)]
    pub oscillation_hz: f64,
    /// Local gravity that defines the g unit (m/s²).
    #[serde(default = "d_gravity")]
    pub gravity_m_s2: f64,
    /// Random seed (same seed, same file).
    #[serde(default = "d_seed")]
    pub seed: u64,
}

fn d_k1() -> f64 {
    1.0
}
fn d_noise() -> f64 {
    1e-4
}
fn d_samples() -> usize {
    10
}
fn d_duration() -> f64 {
    MotionProfile::rate_table().duration_s
}
fn d_rate() -> f64 {
    MotionProfile::rate_table().rate_hz
}
fn d_spin_up() -> f64 {
    MotionProfile::rate_table().spin_up_s
}
fn d_alpha() -> f64 {
    MotionProfile::rate_table().angular_accel_rad_s2
}
fn d_axis() -> [f64; 3] {
    MotionProfile::rate_table().axis.into()
}
fn d_f0() -> [f64; 3] {
    MotionProfile::rate_table().f0_g.into()
}
fn d_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}
fn d_seed() -> u64 {
    1
}

impl GfimuSimOptions {
    /// The simulator's configuration: the array loaded
    /// ([`ArrayChoice::load`]), the motion profile in the core's vectors.
    pub fn config(&self) -> Result<GfimuSim> {
        let kind = match self.kind {
            GfimuSimKind::Static => SimKind::Static {
                samples: self.samples,
            },
            GfimuSimKind::Motion => SimKind::Motion(MotionProfile {
                axis: Vector3::from(self.axis),
                angular_accel_rad_s2: self.angular_accel_rad_s2,
                spin_up_s: self.spin_up_s,
                omega0_rad_s: Vector3::from(self.omega0_rad_s),
                f0_g: Vector3::from(self.f0_g),
                f0_frame: match self.f0_frame {
                    F0FrameOption::Unit => F0Frame::Unit,
                    F0FrameOption::Table => F0Frame::Table,
                },
                oscillation_amplitude_rad_s: self.oscillation_amplitude_rad_s,
                oscillation_hz: self.oscillation_hz,
                duration_s: self.duration_s,
                rate_hz: self.rate_hz,
                gravity_m_s2: self.gravity_m_s2,
            }),
        };
        Ok(GfimuSim {
            array: self.array.load()?,
            k1_out_per_g: self.k1,
            noise: self.noise,
            kind,
            seed: self.seed,
        })
    }
}

impl crate::procedures::Simulate for super::GfimuCalibrate {
    type Options = GfimuSimOptions;

    fn validate(o: &GfimuSimOptions) -> Result<()> {
        o.config()?.validate()
    }

    fn simulate(o: &GfimuSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        o.config()?.write(out)?;
        Ok(())
    }

    /// `{"notes": [...]}`: every accelerometer's K0 and Ks and how the
    /// run was simulated.
    fn truth(o: &GfimuSimOptions) -> Result<Option<serde_json::Value>> {
        let cfg = o.config()?;
        cfg.validate()?;
        Ok(Some(serde_json::json!({ "notes": cfg.notes() })))
    }
}
