//! Precision centrifuge kinematics (He & Yin 2017 §1–2; IEEE Std 836;
//! docs/src/centrifuge.md).
//!
//! # Conventions
//! * The table spins at `ω` (rad/s) about the local vertical. The
//!   centripetal specific force at radius `R` (m) has magnitude
//!   `a_c = R (ω² + 2 s ω Ωe sin Φ)` (m/s², He & Yin 2017 eq. 6 denominator),
//!   `Ωe` = [`EARTH_RATE_RAD_S`], `Φ` latitude, `s = +1` when the table
//!   spins in Earth's sense (counter-clockwise seen from above in the
//!   northern hemisphere), `s = −1` for the opposite sense. It points from
//!   the instrument toward the spin axis: the "radial direction" below is
//!   this inward direction. In g units it is divided by `g_L`.
//! * A position is `(plane, φ0, polarity)`: the radial direction lies in the
//!   plane of the plane's first and second axes ([`Plane`]) at `φ0` from
//!   the first toward the second; the third axis points up and feels
//!   `+1 g` (`+g_L`). Polarity −1 is the fixture turned 180° about the
//!   vertical: every horizontal input changes sign.
//! * Tilt `λ` (rad): in planes `ip` and `io` the input axis is horizontal
//!   up to a small tilt that adds `sin λ` g and scales its horizontal
//!   input by `cos λ` (He & Yin 2017 eq. 4, 6). In plane `po` the input axis is
//!   the vertical one and the tilt is not modelled.
//! * Effective centre of mass (ECM, He & Yin 2017 §2.2): the fixture turns about
//!   its centre O′ at `R = (R+ + R−)/2` from the spin axis; the ECM sits at
//!   `r = (R+ − R−)/2` (signed) from O′, *against* the input axis (so that
//!   with IA radial, polarity + is at `R + r = R+` and polarity − at
//!   `R − r = R−`, docs/src/centrifuge.md sign fix). The offset turns with the
//!   fixture: at a horizontal-IA position `(φ0, ±)` the ECM is at
//!   `R± (φ0) = sqrt((R ± r cos φ0)² + (r sin φ0)²)` and the radial
//!   direction is off the nominal one by
//!   `Δφ± = ∓ atan(r sin φ0 / (R ± r cos φ0))` (He & Yin 2017 §2.2, signs from
//!   the geometry). In plane `po` the offset is vertical: `R± = R`,
//!   `Δφ = 0`.

use crate::error::{Error, Result};
use crate::models::SpecificForce;
use crate::units::EARTH_RATE_RAD_S;

/// The plane that contains the radial direction (contract column `plane`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Plane {
    /// IA → PA; OA up.
    Ip,
    /// IA → OA; PA up.
    Io,
    /// PA → OA; IA up.
    Po,
}

impl Plane {
    /// Parse `ip`, `io` or `po` (case-insensitive).
    pub fn parse(s: &str) -> Result<Plane> {
        match s.trim().to_ascii_lowercase().as_str() {
            "ip" => Ok(Plane::Ip),
            "io" => Ok(Plane::Io),
            "po" => Ok(Plane::Po),
            other => Err(Error::Unsupported(format!(
                "unknown plane '{other}' (use ip, io or po)"
            ))),
        }
    }

    /// Name (`ip`, `io`, `po`).
    pub fn name(self) -> &'static str {
        match self {
            Plane::Ip => "ip",
            Plane::Io => "io",
            Plane::Po => "po",
        }
    }

    /// True when the input axis is horizontal (planes `ip`, `io`).
    pub fn ia_horizontal(self) -> bool {
        !matches!(self, Plane::Po)
    }

    /// Specific force (g) for horizontal inputs `h1` (first axis), `h2`
    /// (second axis) and `v` on the vertical axis.
    fn compose(self, h1: f64, h2: f64, v: f64) -> SpecificForce {
        match self {
            Plane::Ip => SpecificForce {
                a_i: h1,
                a_p: h2,
                a_o: v,
            },
            Plane::Io => SpecificForce {
                a_i: h1,
                a_o: h2,
                a_p: v,
            },
            Plane::Po => SpecificForce {
                a_p: h1,
                a_o: h2,
                a_i: v,
            },
        }
    }
}

/// One fixture position on the centrifuge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Position {
    /// Plane of the radial direction.
    pub plane: Plane,
    /// Nominal angle φ0 from the first toward the second axis (rad).
    pub phi_rad: f64,
    /// +1 or −1.
    pub polarity: i8,
}

impl Position {
    /// Validate and build (polarity must be ±1, φ0 finite).
    pub fn new(plane: Plane, phi_rad: f64, polarity: i8) -> Result<Position> {
        if polarity != 1 && polarity != -1 {
            return Err(Error::InvalidValue {
                what: "polarity (must be +1 or -1)".into(),
                value: polarity.to_string(),
            });
        }
        crate::error::finite("angle phi", phi_rad)?;
        Ok(Position {
            plane,
            phi_rad,
            polarity,
        })
    }

    /// Polarity as ±1.0.
    pub fn sign(&self) -> f64 {
        f64::from(self.polarity)
    }
}

/// Centrifuge and mounting parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Centrifuge {
    /// Radius of the ECM with IA radial, polarity + (m).
    pub r_plus_m: f64,
    /// Radius of the ECM with IA radial, polarity − (m).
    pub r_minus_m: f64,
    /// Latitude Φ (rad).
    pub latitude_rad: f64,
    /// Local gravity g_L (m/s²): the g unit of every acceleration.
    pub g_local_m_s2: f64,
    /// True when the table spins opposite to Earth's sense.
    pub opposite_sense: bool,
    /// IA tilt λ above the horizontal plane (rad).
    pub tilt_rad: f64,
}

/// Radius of the ECM and angle of the true radial direction from the
/// nominal one at a position (module docs, He & Yin 2017 §2.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EcmGeometry {
    /// Distance of the ECM from the spin axis (m).
    pub radius_m: f64,
    /// True minus nominal angle of the radial direction, Δφ (rad).
    pub delta_phi_rad: f64,
}

/// ECM radius and alignment error for fixture centre `r_centre_m` = R,
/// signed ECM offset `offset_m` = r = (R+ − R−)/2, nominal angle φ0 and
/// polarity ±1 (module docs; He & Yin 2017 §2.2 with the sign fixed so that
/// φ0 → 0 gives R+ and R−).
pub fn ecm_geometry(r_centre_m: f64, offset_m: f64, phi_rad: f64, polarity: f64) -> EcmGeometry {
    let along = r_centre_m + polarity * offset_m * phi_rad.cos();
    let across = offset_m * phi_rad.sin();
    EcmGeometry {
        radius_m: along.hypot(across),
        delta_phi_rad: -polarity * across.atan2(along),
    }
}

impl Centrifuge {
    /// Fixture-centre radius R = (R+ + R−)/2 (m).
    pub fn centre_radius_m(&self) -> f64 {
        0.5 * (self.r_plus_m + self.r_minus_m)
    }

    /// Signed ECM offset r = (R+ − R−)/2 (m).
    pub fn ecm_offset_m(&self) -> f64 {
        0.5 * (self.r_plus_m - self.r_minus_m)
    }

    /// `ω² + 2 s ω Ωe sin Φ` (rad²/s², He & Yin 2017 eq. 6).
    pub fn rate_squared(&self, omega_rad_s: f64) -> f64 {
        centripetal_rate_squared(omega_rad_s, self.latitude_rad, self.opposite_sense)
    }

    /// ECM radius and alignment error at `pos`.
    pub fn geometry(&self, pos: &Position) -> EcmGeometry {
        if pos.plane.ia_horizontal() {
            ecm_geometry(
                self.centre_radius_m(),
                self.ecm_offset_m(),
                pos.phi_rad,
                pos.sign(),
            )
        } else {
            EcmGeometry {
                radius_m: self.centre_radius_m(),
                delta_phi_rad: 0.0,
            }
        }
    }

    /// Centripetal specific force magnitude (g) at `pos` and table rate ω.
    pub fn centripetal_g(&self, pos: &Position, omega_rad_s: f64) -> f64 {
        self.geometry(pos).radius_m * self.rate_squared(omega_rad_s) / self.g_local_m_s2
    }

    /// Specific force on the instrument axes (g) at `pos` and rate ω,
    /// including the ECM alignment error and the IA tilt (module docs).
    pub fn specific_force(&self, pos: &Position, omega_rad_s: f64) -> SpecificForce {
        let geo = self.geometry(pos);
        let ac = geo.radius_m * self.rate_squared(omega_rad_s) / self.g_local_m_s2;
        let phi = pos.phi_rad + geo.delta_phi_rad;
        let s = pos.sign();
        let (h1, h2) = (s * ac * phi.cos(), s * ac * phi.sin());
        let mut f = pos.plane.compose(h1, h2, 1.0);
        if pos.plane.ia_horizontal() {
            f.a_i = f.a_i * self.tilt_rad.cos() + self.tilt_rad.sin();
        }
        f
    }
}

/// `ω² + 2 s ω Ωe sin Φ` with `s = −1` for `opposite_sense` (rad²/s²):
/// the centripetal rate of a table spinning at ω relative to the Earth
/// (He & Yin 2017 eq. 6; the Ωe² term, below 1e-9 of ω² at 1 g, is dropped).
pub fn centripetal_rate_squared(omega_rad_s: f64, latitude_rad: f64, opposite_sense: bool) -> f64 {
    let s = if opposite_sense { -1.0 } else { 1.0 };
    omega_rad_s * omega_rad_s + 2.0 * s * omega_rad_s * EARTH_RATE_RAD_S * latitude_rad.sin()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rig() -> Centrifuge {
        Centrifuge {
            r_plus_m: 0.714775,
            r_minus_m: 0.705794,
            latitude_rad: 40f64.to_radians(),
            g_local_m_s2: 9.80,
            opposite_sense: false,
            tilt_rad: 0.0,
        }
    }

    #[test]
    fn ia_radial_radii_are_r_plus_and_r_minus() {
        let c = rig();
        for (pol, r) in [(1, c.r_plus_m), (-1, c.r_minus_m)] {
            let p = Position::new(Plane::Ip, 0.0, pol).unwrap();
            let g = c.geometry(&p);
            assert!((g.radius_m - r).abs() < 1e-12);
            assert!(g.delta_phi_rad.abs() < 1e-15);
            let f = c.specific_force(&p, 3.0);
            assert!((f.a_i - f64::from(pol) * r * c.rate_squared(3.0) / 9.8).abs() < 1e-12);
            assert_eq!(f.a_o, 1.0);
        }
    }

    #[test]
    fn transverse_radius_is_hypot() {
        // He & Yin 2017 §2.2.2: R3 = sqrt(R² + r²), Δφ = atan(r/R).
        let c = rig();
        let (rr, r) = (c.centre_radius_m(), c.ecm_offset_m());
        let g = c.geometry(&Position::new(Plane::Ip, 90f64.to_radians(), 1).unwrap());
        assert!((g.radius_m - rr.hypot(r)).abs() < 1e-12);
        assert!((g.delta_phi_rad.abs() - (r / rr).atan()).abs() < 1e-12);
    }
}
