//! The plans of the three IMU sessions. Their u comes from the scatter
//! inside every position and, for the autocalibration, a non-linear fit,
//! so each plan is by simulation ([`crate::procedures::sim_plan`]): the
//! planned session simulated ([`super::sim::ImuSimulator`]) and reduced by
//! the procedure itself.

use super::sim::{ImuSimOptions, ImuSimulator, SequenceKind};
use crate::procedures::sim_plan::{BySimulation, Planned};
use crate::procedures::Procedure;

/// `incal plan imu-ferraris`.
pub type FerrarisPlan = BySimulation<super::ferraris::Ferraris, ImuSimulator>;

/// `incal plan imu-multipos`.
pub type MultiposPlan = BySimulation<super::multipos::Multipos, ImuSimulator>;

/// `incal plan imu-autocal`.
pub type AutocalPlan = BySimulation<super::autocal::Autocal, ImuSimulator>;

impl Planned<ImuSimulator> for super::ferraris::Ferraris {
    /// imucal's nine labelled sections.
    fn session(session: ImuSimOptions) -> ImuSimOptions {
        ImuSimOptions {
            sequence: SequenceKind::Ferraris,
            ..session
        }
    }

    fn reduce_options(s: &ImuSimOptions) -> super::ferraris::FerrarisOptions {
        super::ferraris::FerrarisOptions {
            rate_hz: Some(s.rate_hz),
            gravity_m_s2: s.gravity_m_s2,
            rotation_deg: s.rotation_deg,
            ..Self::example()
        }
    }
}

impl Planned<ImuSimulator> for super::multipos::Multipos {
    /// Static positions with their labels (and rotations).
    fn session(session: ImuSimOptions) -> ImuSimOptions {
        ImuSimOptions {
            sequence: SequenceKind::Positions,
            ..session
        }
    }

    fn reduce_options(s: &ImuSimOptions) -> super::multipos::MultiposSessionOptions {
        super::multipos::MultiposSessionOptions {
            rate_hz: Some(s.rate_hz),
            gravity_m_s2: s.gravity_m_s2,
            latitude_deg: s.latitude_deg,
            rotation_deg: s.rotation_deg,
            ..Self::example()
        }
    }
}

impl Planned<ImuSimulator> for super::autocal::Autocal {
    /// A still start, then random orientations.
    fn session(session: ImuSimOptions) -> ImuSimOptions {
        ImuSimOptions {
            sequence: SequenceKind::Random,
            ..session
        }
    }

    fn reduce_options(s: &ImuSimOptions) -> super::autocal::AutocalSessionOptions {
        super::autocal::AutocalSessionOptions {
            rate_hz: Some(s.rate_hz),
            gravity_m_s2: s.gravity_m_s2,
            init_static_s: s.init_static_s,
            ..Self::example()
        }
    }
}
