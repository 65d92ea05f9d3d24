//! Pendulous accelerometer model equation (Wu et al. 2015 eq. 1; GJB 1037A;
//! IEEE Std 1293), extended with the terms a 1 g tumble or a centrifuge can
//! alias (docs/src/tumble.md, §2):
//!
//! ```text
//! E = K1 (K0 + a_i + K2 a_i² + K3 a_i³ + δo a_p + δp a_o
//!         + Kip a_i a_p + Kio a_i a_o + Kpo a_p a_o
//!         + Kpp a_p² + Koo a_o² + Koq a_i|a_i|)
//! ```
//!
//! | symbol | unit | meaning |
//! |---|---|---|
//! | `E` | output (V, mA, counts) | indicated output |
//! | `K1` | output/g | scale factor |
//! | `K0` | g | bias |
//! | `K2`, `K3` | g/g², g/g³ | input-axis nonlinearity |
//! | `δo`, `δp` | rad | input-axis misalignment about OA, PA |
//! | `Kip`, `Kio`, `Kpo` | g/g² | cross-coupling |
//! | `Kpp`, `Koo` | g/g² | cross-axis nonlinearity |
//! | `Koq` | g/g² | odd quadratic (IEEE Std 836) |
//! | `a_i, a_p, a_o` | g | specific force along IA, PA, OA |

use crate::error::{Error, Result};

/// Specific force along the instrument's input, pendulous and output axes, in g.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SpecificForce {
    /// Along the input axis IA (g).
    pub a_i: f64,
    /// Along the pendulous axis PA (g).
    pub a_p: f64,
    /// Along the output axis OA (g).
    pub a_o: f64,
}

/// One term of the model equation; its regressor is the function of the
/// specific force that multiplies it inside the parentheses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Term {
    /// Bias K0 (g); regressor 1.
    K0,
    /// Scale factor K1 (output/g); regressor `a_i` (K1 multiplies everything).
    K1,
    /// Second-order nonlinearity K2 (g/g²); regressor `a_i²`.
    K2,
    /// Third-order nonlinearity K3 (g/g³); regressor `a_i³`.
    K3,
    /// Misalignment δo about OA (rad); regressor `a_p`.
    DeltaO,
    /// Misalignment δp about PA (rad); regressor `a_o`.
    DeltaP,
    /// Cross-coupling Kip (g/g²); regressor `a_i a_p`.
    Kip,
    /// Cross-coupling Kio (g/g²); regressor `a_i a_o`.
    Kio,
    /// Cross-coupling Kpo (g/g²); regressor `a_p a_o`.
    Kpo,
    /// Cross-axis nonlinearity Kpp (g/g²); regressor `a_p²`.
    Kpp,
    /// Cross-axis nonlinearity Koo (g/g²); regressor `a_o²`.
    Koo,
    /// Odd quadratic Koq (g/g²); regressor `a_i |a_i|`.
    Koq,
}

impl Term {
    /// Every term, in the canonical order.
    pub const ALL: [Term; 12] = [
        Term::K0,
        Term::K1,
        Term::K2,
        Term::K3,
        Term::DeltaO,
        Term::DeltaP,
        Term::Kip,
        Term::Kio,
        Term::Kpo,
        Term::Kpp,
        Term::Koo,
        Term::Koq,
    ];

    /// Name used in files and JSON (`K0`, `delta_o`, `K_ip`, …).
    pub fn name(self) -> &'static str {
        match self {
            Term::K0 => "K0",
            Term::K1 => "K1",
            Term::K2 => "K2",
            Term::K3 => "K3",
            Term::DeltaO => "delta_o",
            Term::DeltaP => "delta_p",
            Term::Kip => "K_ip",
            Term::Kio => "K_io",
            Term::Kpo => "K_po",
            Term::Kpp => "K_pp",
            Term::Koo => "K_oo",
            Term::Koq => "K_oq",
        }
    }

    /// Unit of the coefficient (g-unit convention).
    pub fn unit(self) -> crate::units::Unit {
        use crate::units::Unit;
        match self {
            Term::K0 => Unit::G,
            Term::K1 => Unit::OutputPerG,
            Term::K3 => Unit::GPerG3,
            Term::DeltaO | Term::DeltaP => Unit::Rad,
            _ => Unit::GPerG2,
        }
    }

    /// Parse a name (as printed by [`Term::name`]; case-insensitive, `Kip`
    /// and `K_ip` both accepted).
    pub fn parse(s: &str) -> Result<Term> {
        let key = s.trim().to_ascii_lowercase().replace('_', "");
        Term::ALL
            .iter()
            .copied()
            .find(|t| t.name().to_ascii_lowercase().replace('_', "") == key)
            .ok_or_else(|| {
                Error::Unsupported(format!(
                    "unknown term '{s}' (known: {})",
                    Term::ALL.map(|t| t.name()).join(", ")
                ))
            })
    }

    /// The regressor of this term at specific force `a` (g).
    pub fn regressor(self, a: &SpecificForce) -> f64 {
        match self {
            Term::K0 => 1.0,
            Term::K1 => a.a_i,
            Term::K2 => a.a_i * a.a_i,
            Term::K3 => a.a_i.powi(3),
            Term::DeltaO => a.a_p,
            Term::DeltaP => a.a_o,
            Term::Kip => a.a_i * a.a_p,
            Term::Kio => a.a_i * a.a_o,
            Term::Kpo => a.a_p * a.a_o,
            Term::Kpp => a.a_p * a.a_p,
            Term::Koo => a.a_o * a.a_o,
            Term::Koq => a.a_i * a.a_i.abs(),
        }
    }
}

impl std::fmt::Display for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// All coefficients of the model equation (see module docs for units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelerometerModel {
    /// Bias K0 (g).
    pub k0_g: f64,
    /// Scale factor K1 (output/g).
    pub k1_out_per_g: f64,
    /// K2 (g/g²).
    pub k2: f64,
    /// K3 (g/g³).
    pub k3: f64,
    /// δo (rad).
    pub delta_o_rad: f64,
    /// δp (rad).
    pub delta_p_rad: f64,
    /// Kip (g/g²).
    pub k_ip: f64,
    /// Kio (g/g²).
    pub k_io: f64,
    /// Kpo (g/g²).
    pub k_po: f64,
    /// Kpp (g/g²).
    pub k_pp: f64,
    /// Koo (g/g²).
    pub k_oo: f64,
    /// Koq (g/g²).
    pub k_oq: f64,
}

impl Default for AccelerometerModel {
    /// An ideal instrument with K1 = 1 output/g.
    fn default() -> Self {
        Self {
            k0_g: 0.0,
            k1_out_per_g: 1.0,
            k2: 0.0,
            k3: 0.0,
            delta_o_rad: 0.0,
            delta_p_rad: 0.0,
            k_ip: 0.0,
            k_io: 0.0,
            k_po: 0.0,
            k_pp: 0.0,
            k_oo: 0.0,
            k_oq: 0.0,
        }
    }
}

impl AccelerometerModel {
    /// The instrument simulated in Wu et al. 2015 §2.1, with δo = 3×10⁻³ rad
    /// (docs/src/tumble.md: the printed 3×10⁻⁴ is a typo; Table 1 shows 618.8″).
    pub fn wu2015() -> Self {
        Self {
            k0_g: 8e-3,
            k1_out_per_g: 10.0,
            k2: 1e-6,
            k3: 5e-5,
            delta_o_rad: 3e-3,
            k_ip: 3e-7,
            ..Self::default()
        }
    }

    /// Refuse a model that cannot describe an instrument: a non-finite
    /// coefficient, or a zero scale factor (every output would be 0).
    pub fn validate(&self) -> Result<()> {
        for t in Term::ALL {
            crate::error::finite(&format!("coefficient {t}"), self.get(t))?;
        }
        if self.k1_out_per_g == 0.0 {
            return Err(Error::InvalidValue {
                what: "scale factor K1".into(),
                value: "0".into(),
            });
        }
        Ok(())
    }

    /// Coefficient of `term`.
    pub fn get(&self, term: Term) -> f64 {
        match term {
            Term::K0 => self.k0_g,
            Term::K1 => self.k1_out_per_g,
            Term::K2 => self.k2,
            Term::K3 => self.k3,
            Term::DeltaO => self.delta_o_rad,
            Term::DeltaP => self.delta_p_rad,
            Term::Kip => self.k_ip,
            Term::Kio => self.k_io,
            Term::Kpo => self.k_po,
            Term::Kpp => self.k_pp,
            Term::Koo => self.k_oo,
            Term::Koq => self.k_oq,
        }
    }

    /// Set the coefficient of `term`.
    pub fn set(&mut self, term: Term, value: f64) {
        let slot = match term {
            Term::K0 => &mut self.k0_g,
            Term::K1 => &mut self.k1_out_per_g,
            Term::K2 => &mut self.k2,
            Term::K3 => &mut self.k3,
            Term::DeltaO => &mut self.delta_o_rad,
            Term::DeltaP => &mut self.delta_p_rad,
            Term::Kip => &mut self.k_ip,
            Term::Kio => &mut self.k_io,
            Term::Kpo => &mut self.k_po,
            Term::Kpp => &mut self.k_pp,
            Term::Koo => &mut self.k_oo,
            Term::Koq => &mut self.k_oq,
        };
        *slot = value;
    }

    /// Indicated acceleration `E/K1` (g) at specific force `a`.
    pub fn indicated_g(&self, a: &SpecificForce) -> f64 {
        a.a_i
            + Term::ALL
                .iter()
                .filter(|t| **t != Term::K1)
                .map(|t| self.get(*t) * t.regressor(a))
                .sum::<f64>()
    }

    /// Output `E = K1 · indicated_g(a)` (output units).
    pub fn output(&self, a: &SpecificForce) -> f64 {
        self.k1_out_per_g * self.indicated_g(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for t in Term::ALL {
            assert_eq!(Term::parse(t.name()).unwrap(), t);
        }
        assert_eq!(Term::parse("Kip").unwrap(), Term::Kip);
        assert!(Term::parse("K9").is_err());
    }

    #[test]
    fn output_is_k1_times_bracket() {
        let m = AccelerometerModel::wu2015();
        let a = SpecificForce {
            a_i: 0.5,
            a_p: 0.8,
            a_o: 0.0,
        };
        let bracket = 8e-3 + 0.5 + 1e-6 * 0.25 + 5e-5 * 0.125 + 3e-3 * 0.8 + 3e-7 * 0.4;
        assert!((m.output(&a) - 10.0 * bracket).abs() < 1e-15);
    }
}

crate::named_enum!(Term, Term::ALL);
