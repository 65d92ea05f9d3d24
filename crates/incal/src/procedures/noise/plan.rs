//! The plan of a noise analysis: how long to record, at what rate, for
//! the u of every noise term and bias stability. The Allan variance's
//! confidence depends on the noise types present at every τ and on the
//! model selection, so the plan is by simulation
//! ([`crate::procedures::sim_plan`]): the planned record simulated with its
//! terms ([`super::sim::NoiseSim`]) and analysed as `incal noise` would.

/// `incal plan noise` ([`crate::procedures::Plan`]).
pub type NoisePlan = crate::procedures::sim_plan::BySimulation<super::Noise, super::Noise>;
