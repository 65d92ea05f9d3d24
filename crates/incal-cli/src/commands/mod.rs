//! One module per subcommand family.
//!
//! The procedures' families are listed once, in [`procedure_families!`]:
//! each is its own file holding its arguments and three command enums,
//! `Reductions` (its commands at the top level), `Plans` (`incal plan …`)
//! and `Simulations` (`incal simulate …`), any of them empty, each with
//! its [`Run`]. The macro declares the modules and flattens their enums
//! into the command tree, so a new procedure's CLI is its file and its
//! name in the list.

pub mod batch;
pub mod compare;
pub mod convert;
pub mod demo;
pub mod export;
pub mod procedures;
pub mod record;
pub mod report;
pub mod schema;
pub mod serve;
pub mod units;
pub mod user;

use crate::error::CliResult;

/// A parsed command that runs itself.
pub trait Run {
    /// Run the command.
    fn run(&self) -> CliResult<()>;
}

/// Declare the procedure families and build, from their command enums, the
/// three parts of the command tree: [`Reductions`], [`Plans`] and
/// [`Simulations`] (in the order given: the order of `incal --help`).
macro_rules! procedure_families {
    ($($m:ident),* $(,)?) => {
        $(pub mod $m;)*

        /// The procedures' commands at the top level (`incal tumble`, `incal gyro …`).
        #[derive(clap::Subcommand, Debug)]
        #[allow(non_camel_case_types)]
        pub enum Reductions {
            $(#[command(flatten)] $m($m::Reductions),)*
        }

        /// `incal plan …`: every procedure's plan.
        #[derive(clap::Subcommand, Debug)]
        #[allow(non_camel_case_types)]
        pub enum Plans {
            $(#[command(flatten)] $m($m::Plans),)*
        }

        /// `incal simulate …`: every procedure's simulator.
        #[derive(clap::Subcommand, Debug)]
        #[allow(non_camel_case_types)]
        pub enum Simulations {
            $(#[command(flatten)] $m($m::Simulations),)*
        }

        impl Run for Reductions {
            fn run(&self) -> CliResult<()> {
                match self { $(Self::$m(c) => c.run(),)* }
            }
        }

        impl Run for Plans {
            fn run(&self) -> CliResult<()> {
                match self { $(Self::$m(c) => c.run(),)* }
            }
        }

        impl Run for Simulations {
            fn run(&self) -> CliResult<()> {
                match self { $(Self::$m(c) => c.run(),)* }
            }
        }
    };
}

procedure_families!(
    tumble,
    centrifuge,
    misalign,
    gfimu,
    gyro,
    noise,
    imu,
    thermal,
    response,
    warmup,
    repeatability,
    threshold,
    mag,
    sensitivity
);
