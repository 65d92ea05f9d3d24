//! One module per subcommand family.

pub mod compare;
pub mod demo;
pub mod misalign;
pub mod tumble;
