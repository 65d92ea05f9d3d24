//! Reading a step recording: columns `reference` (the step input: a rate
//! or an angle) and `output`, and `time_s` (s) or the option `rate_hz`,
//! evenly spaced, exactly as a broadband record
//! ([`crate::procedures::response::broadband::input`]): one record with
//! one step.

pub use crate::procedures::response::broadband::input::{read, write, Record};
