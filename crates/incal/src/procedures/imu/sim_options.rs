//! The options of the IMU session simulator as one typed set
//! ([`ImuSimOptions`], engineering units, the defaults of `incal simulate
//! imu`) and the simulator as one [`crate::procedures::Simulate`]
//! ([`ImuSimulator`]): the session of [`super::sim`] written as the CSV of
//! [`super::input::write`].

use super::sim::{simulate, ImuSim, ImuTruth, Layout, Sequence};
use crate::error::Result;

/// The session sequence of [`ImuSimOptions`] (`sequence`).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SequenceKind {
    /// imucal's nine labelled sections (input of `imu ferraris`).
    #[default]
    Ferraris,
    /// A still start, then random orientations joined by rotations (input
    /// of `imu autocal`).
    Random,
    /// As `random`, every turn 90° about a sensor axis (the six faces of a
    /// cube, hand-held).
    Faces,
    /// Static positions with their labels and up directions (input of
    /// `imu multipos`).
    Positions,
}

/// The default position labels: the six faces, then the twelve edges.
pub const DEFAULT_POSITIONS: [&str; 18] = [
    "x_p", "x_a", "y_p", "y_a", "z_p", "z_a", "x_p+y_p", "x_p+y_a", "x_a+y_p", "x_a+y_a",
    "x_p+z_p", "x_p+z_a", "x_a+z_p", "x_a+z_a", "y_p+z_p", "y_p+z_a", "y_a+z_p", "y_a+z_a",
];

/// Options of the IMU session simulator ([`ImuSimulator`], `incal simulate
/// imu`), in engineering units; the defaults are the command line's.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct ImuSimOptions {
    /// The session: ferraris, random, faces or positions.
    #[serde(default)]
    pub sequence: SequenceKind,
    /// Sample rate (Hz).
    #[serde(default = "default_rate_hz")]
    pub rate_hz: f64,
    /// Duration of every static position (s).
    #[serde(default = "default_static_s")]
    pub static_s: f64,
    /// Random, faces: orientations after the still start.
    #[serde(default = "default_orientations")]
    pub orientations: usize,
    /// Random, faces: duration of the still start (s).
    #[serde(default = "default_init_static_s")]
    pub init_static_s: f64,
    /// Random, faces: duration of each rotation between orientations (s).
    #[serde(default = "default_move_s")]
    pub move_s: f64,
    /// Positions: the labels (faces `x_p`…`z_a`, edges and corners as
    /// `x_p+y_a`, `x_p+y_p+z_a`).
    #[serde(default = "default_positions")]
    pub positions: Vec<String>,
    /// Positions: append the rotations `x_rot, y_rot, z_rot`.
    #[serde(default)]
    pub rotations: bool,
    /// Ferraris and positions: angle of each rotation (deg; −360 is
    /// clockwise seen from the tip).
    #[serde(default = "default_rotation_deg")]
    pub rotation_deg: f64,
    /// Ferraris and positions: duration of each rotation (s).
    #[serde(default = "default_rotation_s")]
    pub rotation_s: f64,
    /// Gravity magnitude (m/s²).
    #[serde(default = "default_gravity_m_s2")]
    pub gravity_m_s2: f64,
    /// Accelerometer white noise, one sample (output units).
    #[serde(default = "default_noise_acc")]
    pub noise_acc: f64,
    /// Gyro white noise, one sample (output units).
    #[serde(default = "default_noise_gyr")]
    pub noise_gyr: f64,
    /// Latitude φ (deg): adds the Earth rate (positions also get the
    /// north direction `nx, ny, nz`).
    #[serde(default)]
    pub latitude_deg: Option<f64>,
    /// The sensor: 0 a typical MEMS IMU in counts, any other number draws
    /// one around it with that seed ([`ImuTruth::of_seed`]).
    #[serde(default)]
    pub truth_seed: u64,
    /// No gyro g-sensitivity (`K_ga = 0`), as the autocalibration assumes.
    #[serde(default)]
    pub no_g_sensitivity: bool,
    /// Random seed of the noise and the orientations.
    #[serde(default = "default_seed")]
    pub seed: u64,
}

fn default_rate_hz() -> f64 {
    100.0
}
fn default_static_s() -> f64 {
    3.0
}
fn default_orientations() -> usize {
    30
}
fn default_init_static_s() -> f64 {
    50.0
}
fn default_move_s() -> f64 {
    1.5
}
fn default_positions() -> Vec<String> {
    DEFAULT_POSITIONS.iter().map(|s| s.to_string()).collect()
}
fn default_rotation_deg() -> f64 {
    -360.0
}
fn default_rotation_s() -> f64 {
    6.0
}
fn default_gravity_m_s2() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}
fn default_noise_acc() -> f64 {
    3.0
}
fn default_noise_gyr() -> f64 {
    2.0
}
fn default_seed() -> u64 {
    1
}

impl Default for ImuSimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({}))
            .expect("every simulator option has a default")
    }
}

impl ImuSimOptions {
    /// The sensor the session is drawn from.
    pub fn truth(&self) -> ImuTruth {
        ImuTruth::of_seed(self.truth_seed, !self.no_g_sensitivity)
    }

    /// The simulator's model and the columns it is written with; a
    /// position label that is not one is refused naming it.
    pub fn model(&self) -> Result<(ImuSim, Layout)> {
        let (sequence, layout) = match self.sequence {
            SequenceKind::Ferraris => (
                Sequence::Ferraris {
                    rotation_deg: self.rotation_deg,
                    rotation_s: self.rotation_s,
                },
                Layout::Ferraris,
            ),
            SequenceKind::Random => (
                Sequence::Random {
                    positions: self.orientations,
                    init_s: self.init_static_s,
                    move_s: self.move_s,
                },
                Layout::Random,
            ),
            SequenceKind::Faces => (
                Sequence::Faces {
                    positions: self.orientations,
                    init_s: self.init_static_s,
                    move_s: self.move_s,
                },
                Layout::Random,
            ),
            SequenceKind::Positions => (
                Sequence::positions(
                    &self.positions,
                    self.rotations
                        .then_some((self.rotation_deg, self.rotation_s)),
                )?,
                Layout::Positions {
                    labels: self.positions.clone(),
                    north: self.latitude_deg.is_some(),
                },
            ),
        };
        let cfg = ImuSim {
            truth: self.truth(),
            sequence,
            rate_hz: self.rate_hz,
            static_s: self.static_s,
            gravity: self.gravity_m_s2,
            noise_acc: self.noise_acc,
            noise_gyr: self.noise_gyr,
            latitude_deg: self.latitude_deg,
            seed: self.seed,
        };
        Ok((cfg, layout))
    }

    /// Refuse options the simulator cannot use, naming the key
    /// ([`ImuSim::validate`]).
    pub fn validate(&self) -> Result<()> {
        self.model()?.0.validate()
    }

    /// The session's samples and the columns to write them with
    /// ([`super::input::write`]): options checked, then drawn.
    pub fn draw(&self) -> Result<(Vec<super::sim::ImuSample>, Layout)> {
        let (cfg, layout) = self.model()?;
        cfg.validate()?;
        Ok((simulate(&cfg)?, layout))
    }
}

/// `incal simulate imu` as one [`crate::procedures::Simulate`]: a session
/// for `imu ferraris`, `imu multipos` or `imu autocal`, written as CSV.
#[derive(Debug, Clone, Copy, Default)]
pub struct ImuSimulator;

impl crate::procedures::Simulate for ImuSimulator {
    type Options = ImuSimOptions;

    fn validate(o: &ImuSimOptions) -> Result<()> {
        o.validate()
    }

    fn simulate(o: &ImuSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let (samples, layout) = o.draw()?;
        super::input::write(&samples, &layout, out)?;
        Ok(())
    }

    /// The sensor's scales, biases, misalignments and g-sensitivity
    /// ([`ImuTruth::to_json`]).
    fn truth(o: &ImuSimOptions) -> Result<Option<serde_json::Value>> {
        Ok(Some(o.truth().to_json()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn simulator_options_round_trip_and_write_the_same_bytes() {
        use crate::procedures::Simulate;
        let o = ImuSimOptions {
            sequence: SequenceKind::Positions,
            static_s: 0.3,
            rotations: true,
            latitude_deg: Some(-33.9),
            ..ImuSimOptions::default()
        };
        assert_eq!(o.positions.len(), 18);
        let v = serde_json::to_value(&o).unwrap();
        assert_eq!(v["sequence"], "positions");
        assert_eq!(crate::options::from_json::<ImuSimOptions>(&v).unwrap(), o);
        let (mut a, mut b) = (Vec::new(), Vec::new());
        ImuSimulator::simulate(&o, &mut a).unwrap();
        crate::procedures::simulate_json::<ImuSimulator>(&v, &mut b).unwrap();
        assert_eq!(a, b);
        assert!(a.starts_with(b"time_s,position,fx,fy,fz,nx,ny,nz,acc_x"));
        let key = |e: crate::Error| crate::options::refused_key::<()>(Err(e));
        let bad = |v| key(crate::options::from_json::<ImuSimOptions>(&v).unwrap_err());
        assert_eq!(bad(serde_json::json!({"sequence": "cube"})), "sequence");
        assert_eq!(bad(serde_json::json!({"rate": 10})), "rate");
        let invalid = |o: ImuSimOptions| key(o.validate().unwrap_err());
        assert_eq!(
            invalid(ImuSimOptions {
                rate_hz: 0.0,
                ..o.clone()
            }),
            "rate_hz"
        );
        assert_eq!(
            invalid(ImuSimOptions {
                latitude_deg: Some(91.0),
                ..o.clone()
            }),
            "latitude_deg"
        );
        assert_eq!(
            invalid(ImuSimOptions {
                sequence: SequenceKind::Random,
                orientations: 0,
                ..o
            }),
            "orientations"
        );
    }
}
