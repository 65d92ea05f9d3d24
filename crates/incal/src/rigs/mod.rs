//! Rig kinematics: what specific force each test position puts on the
//! instrument's axes.

pub mod centrifuge;
pub mod dividing_head;
pub mod rate_table;

pub use dividing_head::Mount;
