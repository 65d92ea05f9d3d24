//! Dividing head (indexing head) with a horizontal axis, Wu et al. 2015 §1.1–1.3.
//!
//! # Conventions
//! The head angle θ is read on the head; θ = 0 puts IA horizontal, θ = 90°
//! puts IA up (+1 g on IA). Looking at the head's face, the reading grows
//! clockwise (Wu et al. 2015 Fig. 1).
//!
//! * pendulum mount (OA ∥ head axis): `a_i = sin θ, a_p = cos θ, a_o = 0`
//! * gate mount (PA ∥ head axis): `a_i = sin θ, a_o = cos θ, a_p = 0`

use crate::error::{Error, Result};
use crate::models::SpecificForce;

/// How the accelerometer sits on the dividing head.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Mount {
    /// Output axis parallel to the head axis (pendulous axis down at θ = 0).
    Pendulum,
    /// Pendulous axis parallel to the head axis (output axis down at θ = 0).
    Gate,
}

impl Mount {
    /// Parse `pendulum` or `gate`.
    pub fn parse(s: &str) -> Result<Mount> {
        match s.trim().to_ascii_lowercase().as_str() {
            "pendulum" => Ok(Mount::Pendulum),
            "gate" => Ok(Mount::Gate),
            other => Err(Error::Unsupported(format!(
                "unknown mount '{other}' (use pendulum or gate)"
            ))),
        }
    }

    /// Name (`pendulum` / `gate`).
    pub fn name(self) -> &'static str {
        match self {
            Mount::Pendulum => "pendulum",
            Mount::Gate => "gate",
        }
    }

    /// Specific force on the instrument axes in a 1 g field at head angle
    /// `theta_rad` (Wu et al. 2015 §1.3).
    pub fn specific_force(self, theta_rad: f64) -> SpecificForce {
        let (s, c) = theta_rad.sin_cos();
        match self {
            Mount::Pendulum => SpecificForce {
                a_i: s,
                a_p: c,
                a_o: 0.0,
            },
            Mount::Gate => SpecificForce {
                a_i: s,
                a_p: 0.0,
                a_o: c,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ninety_degrees_is_ia_up() {
        for m in [Mount::Pendulum, Mount::Gate] {
            let a = m.specific_force(90f64.to_radians());
            assert!((a.a_i - 1.0).abs() < 1e-15);
            assert!(a.a_p.abs() < 1e-15 && a.a_o.abs() < 1e-15);
        }
        assert!((Mount::Pendulum.specific_force(0.0).a_p - 1.0).abs() < 1e-15);
        assert!((Mount::Gate.specific_force(0.0).a_o - 1.0).abs() < 1e-15);
    }
}

crate::named_enum!(Mount, [Mount::Pendulum, Mount::Gate]);
