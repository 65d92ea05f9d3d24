//! Calibration procedures: test plan + rig kinematics + linear(ised) model +
//! map to physical coefficients, all on [`crate::estimation`].

pub mod centrifuge;
pub mod gfimu;
pub mod gyro;
pub mod imu;
pub mod misalign;
pub mod tumble;
