//! One module per subcommand family.

pub mod batch;
pub mod centrifuge;
pub mod compare;
pub mod demo;
pub mod export;
pub mod gfimu;
pub mod gyro;
pub mod imu;
pub mod misalign;
pub mod noise;
pub mod procedures;
pub mod record;
pub mod report;
pub mod schema;
pub mod thermal;
pub mod tumble;
