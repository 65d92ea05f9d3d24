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

/// Absolute zero, °C: no temperature is below it.
pub const ABSOLUTE_ZERO_C: f64 = -273.15;

/// The highest temperature a test of inertial instruments states, °C
/// (a chamber's, a plateau's, a model's range or reference).
pub const MAX_TEMPERATURE_C: f64 = 1000.0;

/// A temperature, °C: finite and within [`ABSOLUTE_ZERO_C`] ..
/// [`MAX_TEMPERATURE_C`], or [`crate::Error::InvalidOption`] naming `key`.
pub fn check_temperature_c(key: &str, t: f64) -> crate::Result<()> {
    crate::options::check_range(key, t, ABSOLUTE_ZERO_C, MAX_TEMPERATURE_C, "degC")
}

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

/// The unit of a number in a result document.
///
/// Values in the JSON are SI- or g-based (accelerations in local g,
/// angles in rad, lengths in m); [`Unit::engineering`] is the one place
/// that chooses how people read them (µg, ppm-style µg/g², arcsec, mm).
/// Serialized as its unit string (`"g/g^2"`); a string this version does
/// not know is kept as [`Unit::Other`], never dropped.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Unit {
    /// Local gravity units, `g` (bias K0, accelerations).
    G,
    /// Output units per g, `output/g` (scale factor K1, Ks).
    OutputPerG,
    /// `g/g^2` (K2, cross-axis and cross-coupling terms).
    GPerG2,
    /// `g/g^3` (K3).
    GPerG3,
    /// Radians, `rad` (misalignments, tilt, azimuth).
    Rad,
    /// Degrees, `deg` (plan and position angles).
    Deg,
    /// Metres, `m` (radii, lever arms).
    M,
    /// Instrument output units, `output`.
    Output,
    /// Output units per °/s, `output/(deg/s)` (gyro scale factor).
    OutputPerDegS,
    /// Degrees per second, `deg/s` (table rates).
    DegPerS,
    /// Radians per second, `rad/s`.
    RadPerS,
    /// Dimensionless, `1` (counts, ratios, standardized residuals).
    One,
    /// A unit string this version does not know (kept as given).
    Other(String),
}

impl Unit {
    /// The unit string of the JSON.
    pub fn as_str(&self) -> &str {
        match self {
            Unit::G => "g",
            Unit::OutputPerG => "output/g",
            Unit::GPerG2 => "g/g^2",
            Unit::GPerG3 => "g/g^3",
            Unit::Rad => "rad",
            Unit::Deg => "deg",
            Unit::M => "m",
            Unit::Output => "output",
            Unit::OutputPerDegS => "output/(deg/s)",
            Unit::DegPerS => "deg/s",
            Unit::RadPerS => "rad/s",
            Unit::One => "1",
            Unit::Other(s) => s,
        }
    }

    /// Parse a unit string (unknown strings become [`Unit::Other`]).
    pub fn parse(s: &str) -> Unit {
        match s {
            "g" => Unit::G,
            "output/g" => Unit::OutputPerG,
            "g/g^2" => Unit::GPerG2,
            "g/g^3" => Unit::GPerG3,
            "rad" => Unit::Rad,
            "deg" => Unit::Deg,
            "m" => Unit::M,
            "output" => Unit::Output,
            "output/(deg/s)" => Unit::OutputPerDegS,
            "deg/s" => Unit::DegPerS,
            "rad/s" => Unit::RadPerS,
            "1" => Unit::One,
            other => Unit::Other(other.to_string()),
        }
    }

    /// How people read a value of this unit: `(scale, label)` with
    /// `shown = value · scale`. µg for g, µg/g² and µg/g³ for the
    /// nonlinearity terms (ppm of g per g), arcsec for angles in rad, mm
    /// for metres; every other unit as it is.
    pub fn engineering(&self) -> (f64, &str) {
        match self {
            Unit::G => (1e6, "ug"),
            Unit::GPerG2 => (1e6, "ug/g^2"),
            Unit::GPerG3 => (1e6, "ug/g^3"),
            Unit::Rad => (ARCSEC_PER_RAD, "arcsec"),
            Unit::M => (1e3, "mm"),
            other => (1.0, other.as_str()),
        }
    }
}

impl Unit {
    /// As [`Unit::engineering`], for a value of magnitude `magnitude`: an
    /// angle of 0.1 rad (5.7°) or more, such as an azimuth, reads in
    /// degrees rather than arcseconds.
    pub fn engineering_for(&self, magnitude: f64) -> (f64, &str) {
        match self {
            Unit::Rad if magnitude.abs() >= 0.1 => (180.0 / std::f64::consts::PI, "deg"),
            other => other.engineering(),
        }
    }
}

impl std::fmt::Display for Unit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl serde::Serialize for Unit {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> serde::Deserialize<'de> for Unit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let s = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(d)?;
        Ok(Unit::parse(&s))
    }
}

impl schemars::JsonSchema for Unit {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "Unit".into()
    }
    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "type": "string",
            "description": "Unit string, e.g. g, output/g, g/g^2, g/g^3, rad, deg, m, output, output/(deg/s), deg/s, rad/s, 1"
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arcsec_per_rad_matches_methods_digest() {
        // 1 rad = 206264.806″
        assert!((ARCSEC_PER_RAD - 206_264.806).abs() < 1e-3);
        assert!((rad_to_arcsec(arcsec_to_rad(618.8)) - 618.8).abs() < 1e-9);
    }

    #[test]
    fn unit_strings_round_trip() {
        for u in [
            Unit::G,
            Unit::OutputPerG,
            Unit::GPerG2,
            Unit::GPerG3,
            Unit::Rad,
            Unit::Deg,
            Unit::M,
            Unit::Output,
            Unit::OutputPerDegS,
            Unit::DegPerS,
            Unit::RadPerS,
            Unit::One,
        ] {
            assert_eq!(Unit::parse(u.as_str()), u);
        }
        assert_eq!(Unit::parse("furlong"), Unit::Other("furlong".into()));
        assert_eq!(Unit::G.engineering(), (1e6, "ug"));
    }
}
