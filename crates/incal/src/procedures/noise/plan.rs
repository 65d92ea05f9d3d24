//! The plan of a noise analysis: how long to record, at what rate, for
//! the u of every noise term and bias stability. The Allan variance's
//! confidence depends on the noise types present at every τ and on the
//! model selection, so the plan is by simulation
//! ([`crate::procedures::sim_plan`]): the planned record simulated with its
//! terms ([`super::sim::NoiseSim`]) and analysed as `incal noise` would.

/// `incal plan noise` ([`crate::procedures::Plan`]).
pub type NoisePlan = crate::procedures::sim_plan::BySimulation<super::Noise, super::Noise>;

impl crate::procedures::sim_plan::Planned<super::Noise> for super::Noise {
    /// The record's rate and quantity; the rest `incal noise`'s defaults.
    fn reduce_options(s: &super::sim::NoiseSim) -> super::NoiseOptions {
        use crate::procedures::Procedure;
        super::NoiseOptions {
            rate_hz: Some(s.rate_hz),
            quantity: s.quantity,
            ..Self::example()
        }
    }
}
