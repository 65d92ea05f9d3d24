//! The plans of the three IMU sessions. Their u comes from the scatter
//! inside every position and, for the autocalibration, a non-linear fit,
//! so each plan is by simulation ([`crate::procedures::sim_plan`]): the
//! planned session simulated ([`super::sim::ImuSimulator`]) and reduced by
//! the procedure itself.

use super::sim::ImuSimulator;
use crate::procedures::sim_plan::BySimulation;

/// `incal plan imu-ferraris`.
pub type FerrarisPlan = BySimulation<super::ferraris::Ferraris, ImuSimulator>;

/// `incal plan imu-multipos`.
pub type MultiposPlan = BySimulation<super::multipos::Multipos, ImuSimulator>;

/// `incal plan imu-autocal`.
pub type AutocalPlan = BySimulation<super::autocal::Autocal, ImuSimulator>;
