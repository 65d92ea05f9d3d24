//! Physical constants and unit conversions used at the edges.
//!
//! Inside the library angles are radians, accelerations are in units of the
//! local gravity `g` unless a name says otherwise (`_m_s2`), and times are
//! seconds. Degrees and arcseconds appear only in plan definitions and in
//! the command-line tool's output.

/// Arcseconds per radian: 180·3600/π = 206264.806…″.
pub const ARCSEC_PER_RAD: f64 = 180.0 * 3600.0 / std::f64::consts::PI;

/// Earth's sidereal rotation rate Ωe in rad/s (IERS / WGS-84 value).
pub const EARTH_RATE_RAD_S: f64 = 7.292_115_0e-5;

/// Standard gravity gn in m/s² (CGPM 1901), used only to convert user
/// inputs given in m/s²; the models themselves work in local-g units.
pub const STANDARD_GRAVITY_M_S2: f64 = 9.806_65;

/// Degrees to radians.
pub fn deg_to_rad(deg: f64) -> f64 {
    deg.to_radians()
}

/// Radians to degrees.
pub fn rad_to_deg(rad: f64) -> f64 {
    rad.to_degrees()
}

/// Radians to arcseconds.
pub fn rad_to_arcsec(rad: f64) -> f64 {
    rad * ARCSEC_PER_RAD
}

/// Arcseconds to radians.
pub fn arcsec_to_rad(arcsec: f64) -> f64 {
    arcsec / ARCSEC_PER_RAD
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arcsec_per_rad_matches_methods_digest() {
        // methods.md: 1 rad = 206264.806″
        assert!((ARCSEC_PER_RAD - 206_264.806).abs() < 1e-3);
        assert!((rad_to_arcsec(arcsec_to_rad(618.8)) - 618.8).abs() < 1e-9);
    }
}
