//! One module per subcommand family.

pub mod centrifuge;
pub mod compare;
pub mod demo;
pub mod tumble;
