//! Typed options of the misalignment simulators (`incal simulate misalign
//! gyro|accel`), in engineering units (angles in arcsec and degrees, the
//! conversion to rad in [`GyroSimOptions::config`] and
//! [`AccelSimOptions::config`] only), with the command line's defaults:
//! the instruments of Li et al. 2012.

use super::gyro::GyroConfig;
use super::sim::{simulate_accel, simulate_gyro, simulate_gyro_records, AccelSim, GyroSim};
use crate::error::Result;
use crate::rigs::rate_table::{FaceMounting, GyroMounting};
use crate::units::arcsec_to_rad;

/// Options of the gyro misalignment simulator; a key not given takes the
/// command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct GyroSimOptions {
    /// Scale factor kI (output per deg/s).
    pub scale_factor: f64,
    /// Bias V0 (output).
    pub bias: f64,
    /// σ of the bias shift per configuration (output).
    pub bias_shift: f64,
    /// True table-face angle about x (arcsec).
    pub dtheta_x0_arcsec: f64,
    /// True table-face angle about y (arcsec).
    pub dtheta_y0_arcsec: f64,
    /// True fixture-face angle about y (arcsec).
    pub dtheta_y1_arcsec: f64,
    /// True fixture-face angle about z (arcsec; second order, not estimable).
    pub dtheta_z1_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    pub dtheta_z2_arcsec: f64,
    /// Configurations `ALPHA:BETA` (deg), in test order.
    pub configs: Vec<GyroConfig>,
    /// Table rate magnitudes (deg/s); each is run forward then reverse.
    pub rates_deg_s: Vec<f64>,
    /// Records per configuration and signed rate.
    pub records: usize,
    /// Table revolutions per record (a non-whole number shows the Earth-rate error).
    pub turns: f64,
    /// Samples per revolution.
    pub samples_per_turn: usize,
    /// Output noise σ of one sample (output units).
    pub noise: f64,
    /// Latitude (deg), for the Earth rate.
    pub latitude_deg: f64,
    /// Write raw records (`time_s`, `table_angle_deg` per sample) instead of record means.
    pub time_series: bool,
    /// Random seed (same seed, same file).
    pub seed: u64,
}

impl Default for GyroSimOptions {
    fn default() -> Self {
        Self {
            scale_factor: -2.9222,
            bias: 0.002,
            bias_shift: 0.0,
            dtheta_x0_arcsec: 2.4,
            dtheta_y0_arcsec: -7.5,
            dtheta_y1_arcsec: -54.0,
            dtheta_z1_arcsec: 0.0,
            dtheta_y2_arcsec: -162.2,
            dtheta_z2_arcsec: 55.8,
            configs: GyroConfig::paper(),
            rates_deg_s: vec![20.0, 30.0, 40.0],
            records: 2,
            turns: 1.0,
            samples_per_turn: 36,
            noise: 1e-3,
            latitude_deg: 45.75,
            time_series: false,
            seed: 1,
        }
    }
}

impl GyroSimOptions {
    /// The simulator's configuration (angles in rad: the one conversion),
    /// refused as [`GyroSim::validate`] refuses.
    pub fn config(&self) -> Result<GyroSim> {
        crate::options::check_latitude_deg(self.latitude_deg)?;
        let cfg = GyroSim {
            mounting: GyroMounting {
                dtheta_x0: arcsec_to_rad(self.dtheta_x0_arcsec),
                dtheta_y0: arcsec_to_rad(self.dtheta_y0_arcsec),
                dtheta_y1: arcsec_to_rad(self.dtheta_y1_arcsec),
                dtheta_z1: arcsec_to_rad(self.dtheta_z1_arcsec),
                dtheta_y2: arcsec_to_rad(self.dtheta_y2_arcsec),
                dtheta_z2: arcsec_to_rad(self.dtheta_z2_arcsec),
            },
            scale_factor: self.scale_factor,
            bias: self.bias,
            bias_shift: self.bias_shift,
            configs: self.configs.clone(),
            rates_deg_s: self.rates_deg_s.clone(),
            records: self.records,
            turns: self.turns,
            samples_per_turn: self.samples_per_turn,
            noise: self.noise,
            latitude_rad: self.latitude_deg.to_radians(),
            seed: self.seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

impl crate::procedures::Simulate for super::MisalignGyro {
    type Options = GyroSimOptions;

    fn validate(o: &GyroSimOptions) -> Result<()> {
        o.config().map(|_| ())
    }

    /// Record means (the reduction's input), or with `time_series` the raw
    /// records the reduction averages itself.
    fn simulate(o: &GyroSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let cfg = o.config()?;
        if o.time_series {
            super::input::write_gyro_records(&simulate_gyro_records(&cfg), out)?;
        } else {
            super::input::write_gyro_means(&simulate_gyro(&cfg)?, out)?;
        }
        Ok(())
    }
}

/// Options of the accelerometer misalignment simulator; a key not given
/// takes the command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct AccelSimOptions {
    /// Scale factor kI (output per g).
    pub scale_factor: f64,
    /// Bias V0 (output).
    pub bias: f64,
    /// True verticality error of the face, about y (arcsec).
    pub dtheta_y0_arcsec: f64,
    /// True input-axis misalignment about y (arcsec).
    pub dtheta_y2_arcsec: f64,
    /// True input-axis misalignment about z (arcsec).
    pub dtheta_z2_arcsec: f64,
    /// Angles β (deg), in test order.
    pub betas_deg: Vec<f64>,
    /// Samples per angle.
    pub samples: usize,
    /// Output noise σ of one sample (output units).
    pub noise: f64,
    /// Random seed (same seed, same file).
    pub seed: u64,
}

impl Default for AccelSimOptions {
    fn default() -> Self {
        Self {
            scale_factor: 1.299,
            bias: -0.002,
            dtheta_y0_arcsec: 30.0,
            dtheta_y2_arcsec: -5.3,
            dtheta_z2_arcsec: 20.5,
            betas_deg: vec![0.0, 90.0, 180.0, 270.0],
            samples: 10,
            noise: 2e-5,
            seed: 1,
        }
    }
}

impl AccelSimOptions {
    /// The simulator's configuration (angles in rad: the one conversion),
    /// refused as [`AccelSim::validate`] refuses.
    pub fn config(&self) -> Result<AccelSim> {
        let cfg = AccelSim {
            mounting: FaceMounting {
                dtheta_y0: arcsec_to_rad(self.dtheta_y0_arcsec),
                dtheta_y1: 0.0,
                dtheta_y2: arcsec_to_rad(self.dtheta_y2_arcsec),
                dtheta_z2: arcsec_to_rad(self.dtheta_z2_arcsec),
            },
            scale_factor: self.scale_factor,
            bias: self.bias,
            betas_rad: self.betas_deg.iter().map(|b| b.to_radians()).collect(),
            samples: self.samples,
            noise: self.noise,
            seed: self.seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

impl crate::procedures::Simulate for super::MisalignAccel {
    type Options = AccelSimOptions;

    fn validate(o: &AccelSimOptions) -> Result<()> {
        o.config().map(|_| ())
    }

    fn simulate(o: &AccelSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        super::input::write_accel(&simulate_accel(&o.config()?), out)?;
        Ok(())
    }
}
