//! Gyro-free inertial unit: an array of N ≥ 6 single-axis accelerometers on
//! a rigid body (GFIMU note; docs/src/gfimu.md).
//!
//! # Conventions
//! The unit frame is right-handed with its origin at the reference point
//! whose specific force `f0` the unit reports. Accelerometer j sits at
//! `r_j` (m, unit frame) and nominally senses along the unit vector `l_j`.
//! A rigid body moving with angular rate `ω` (rad/s) and angular
//! acceleration `ω̇` (rad/s²) gives accelerometer j the specific force
//!
//! ```text
//! f_j = f0 + (ω̇ × r_j + ω × (ω × r_j)) / g        [g]
//! ```
//!
//! so the nominal array sees `l_jᵀ f0 + (r_j × l_j)ᵀ ω̇ / g` plus the
//! centripetal term. The N×6 matrix with rows `[l_jᵀ, (r_j × l_j)ᵀ/g]` must
//! have rank 6 for f0 and ω̇ to be solvable ([`Geometry::check`]).
//!
//! The paper's layout (GFIMU note Fig. 1), lever arm L: a, b at ±L on x sensing
//! z; c, d at ±L on y sensing x; e, f at ±L on z sensing y.

use nalgebra::{DVector, Vector3};

use crate::error::{Error, Result};
use crate::estimation::{Design, Diagnostics, Estimates, DEFAULT_COND_LIMIT, WARN_COND};
use crate::units::STANDARD_GRAVITY_M_S2;

/// One accelerometer of the array.
#[derive(Debug, Clone, PartialEq)]
pub struct ArrayAccelerometer {
    /// Name (column name in files).
    pub name: String,
    /// Position `r_j` in the unit frame (m).
    pub position_m: Vector3<f64>,
    /// Nominal sensitive direction `l_j` (unit vector, unit frame).
    pub direction: Vector3<f64>,
}

/// The array geometry: N ≥ 6 accelerometers with distinct names.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    accelerometers: Vec<ArrayAccelerometer>,
}

/// Names of the six motion unknowns, in solution order.
pub const MOTION_TERMS: [&str; 6] = [
    "f0_x",
    "f0_y",
    "f0_z",
    "omega_dot_x",
    "omega_dot_y",
    "omega_dot_z",
];

impl Geometry {
    /// Build from accelerometers: at least 6, distinct non-empty names,
    /// finite positions, non-zero finite directions (normalised here).
    pub fn new(accelerometers: Vec<ArrayAccelerometer>) -> Result<Self> {
        if accelerometers.len() < 6 {
            return Err(Error::TooFew {
                what:
                    "accelerometers in the array (f0 and the angular acceleration are 6 unknowns)"
                        .into(),
                needed: 6,
                got: accelerometers.len(),
            });
        }
        let mut out = Vec::with_capacity(accelerometers.len());
        for (k, a) in accelerometers.into_iter().enumerate() {
            if a.name.trim().is_empty() {
                return Err(Error::InvalidValue {
                    what: format!("name of accelerometer {}", k + 1),
                    value: "''".into(),
                });
            }
            // Names are CSV column names: no separators, quotes or comment
            // marks, and none of the columns the files already use.
            const RESERVED: [&str; 6] = ["time_s", "t", "position", "fx_g", "fy_g", "fz_g"];
            let ok_chars = a
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'));
            if !ok_chars || a.name.len() > 64 || RESERVED.contains(&a.name.as_str()) {
                return Err(Error::Unsupported(format!(
                    "accelerometer name '{}' cannot be a CSV column: use letters, digits, '_', '-', '.' (at most 64), not one of {}",
                    a.name.chars().take(40).collect::<String>(),
                    RESERVED.join(", ")
                )));
            }
            if out.iter().any(|b: &ArrayAccelerometer| b.name == a.name) {
                return Err(Error::Unsupported(format!(
                    "accelerometer '{}' listed twice",
                    a.name
                )));
            }
            if a.position_m.iter().any(|v| !v.is_finite()) {
                return Err(Error::InvalidValue {
                    what: format!("position of accelerometer '{}'", a.name),
                    value: format!("{:?}", a.position_m.as_slice()),
                });
            }
            let n = a.direction.norm();
            if !(n.is_finite() && n > 0.0) {
                return Err(Error::InvalidValue {
                    what: format!("direction of accelerometer '{}'", a.name),
                    value: format!("{:?}", a.direction.as_slice()),
                });
            }
            out.push(ArrayAccelerometer {
                direction: a.direction / n,
                ..a
            });
        }
        Ok(Self {
            accelerometers: out,
        })
    }

    /// The paper's six-accelerometer layout (GFIMU note Fig. 1) with lever
    /// arm `lever_arm_m` (> 0).
    pub fn paper(lever_arm_m: f64) -> Result<Self> {
        if !(lever_arm_m.is_finite() && lever_arm_m > 0.0) {
            return Err(Error::InvalidValue {
                what: "lever arm (m, > 0)".into(),
                value: lever_arm_m.to_string(),
            });
        }
        let l = lever_arm_m;
        let acc = |name: &str, r: [f64; 3], d: [f64; 3]| ArrayAccelerometer {
            name: name.into(),
            position_m: Vector3::from(r),
            direction: Vector3::from(d),
        };
        Self::new(vec![
            acc("a", [l, 0.0, 0.0], [0.0, 0.0, 1.0]),
            acc("b", [-l, 0.0, 0.0], [0.0, 0.0, 1.0]),
            acc("c", [0.0, l, 0.0], [1.0, 0.0, 0.0]),
            acc("d", [0.0, -l, 0.0], [1.0, 0.0, 0.0]),
            acc("e", [0.0, 0.0, l], [0.0, 1.0, 0.0]),
            acc("f", [0.0, 0.0, -l], [0.0, 1.0, 0.0]),
        ])
    }

    /// Twelve accelerometers that solve the centripetal products directly
    /// (no feedback of the integrated ω, unlike the six-accelerometer
    /// layout): two at each of ±L on x, y and z, each sensing one of the
    /// two directions across its lever arm. Named
    /// `{p|m}{axis}_{sensed axis}`: `px_y` sits at +L on x and senses y.
    ///
    /// With sensing across the lever arm, only the cross products
    /// `ω_xω_y, ω_xω_z, ω_yω_z` enter the outputs, and this layout separates
    /// them from f0 and ω̇ (`solve_mode` says `direct`).
    pub fn twelve(lever_arm_m: f64) -> Result<Self> {
        if !(lever_arm_m.is_finite() && lever_arm_m > 0.0) {
            return Err(Error::InvalidValue {
                what: "lever arm (m, > 0)".into(),
                value: lever_arm_m.to_string(),
            });
        }
        let axes = ["x", "y", "z"];
        let mut accs = Vec::with_capacity(12);
        for a in 0..3 {
            for (sign, tag) in [(1.0, "p"), (-1.0, "m")] {
                for b in (0..3).filter(|b| *b != a) {
                    let mut r = Vector3::zeros();
                    r[a] = sign * lever_arm_m;
                    let mut d = Vector3::zeros();
                    d[b] = 1.0;
                    accs.push(ArrayAccelerometer {
                        name: format!("{tag}{}_{}", axes[a], axes[b]),
                        position_m: r,
                        direction: d,
                    });
                }
            }
        }
        Self::new(accs)
    }

    /// The accelerometers, in order.
    pub fn accelerometers(&self) -> &[ArrayAccelerometer] {
        &self.accelerometers
    }

    /// Number of accelerometers.
    pub fn len(&self) -> usize {
        self.accelerometers.len()
    }

    /// Always false (a geometry has at least 6 accelerometers).
    pub fn is_empty(&self) -> bool {
        self.accelerometers.is_empty()
    }

    /// Names, in order.
    pub fn names(&self) -> Vec<String> {
        self.accelerometers.iter().map(|a| a.name.clone()).collect()
    }

    /// Design of the motion unknowns `(f0 [g], ω̇ [rad/s²])` for sensitive
    /// vectors `s_j` (nominal `l_j`, or calibrated `Ks_j` in output/g):
    /// row j = `[s_jᵀ, (r_j × s_j)ᵀ / g]` (docs/src/gfimu.md), `gravity_m_s2` = g.
    pub fn motion_design(&self, sensitive: &[Vector3<f64>], gravity_m_s2: f64) -> Result<Design> {
        if sensitive.len() != self.len() {
            return Err(Error::Unsupported(format!(
                "{} sensitive vectors for {} accelerometers",
                sensitive.len(),
                self.len()
            )));
        }
        let rows: Vec<Vec<f64>> = self
            .accelerometers
            .iter()
            .zip(sensitive)
            .map(|(a, s)| {
                let m = a.position_m.cross(s) / gravity_m_s2;
                vec![s.x, s.y, s.z, m.x, m.y, m.z]
            })
            .collect();
        Design::from_rows(MOTION_TERMS.iter().map(|s| s.to_string()).collect(), &rows)
    }

    /// Rank and condition number of the nominal N×6 motion system
    /// (column-equilibrated, so independent of the lever-arm unit).
    pub fn check(&self) -> Result<Diagnostics> {
        let nominal: Vec<Vector3<f64>> = self.accelerometers.iter().map(|a| a.direction).collect();
        Ok(self
            .motion_design(&nominal, STANDARD_GRAVITY_M_S2)?
            .diagnose(None, DEFAULT_COND_LIMIT))
    }

    /// Refuse a geometry that cannot solve for f0 and ω̇, naming the
    /// unobservable combination ([`Error::Unseparable`]) or the weakest one
    /// when the condition number exceeds [`DEFAULT_COND_LIMIT`].
    /// Returns the diagnostics and a warning when the condition number
    /// exceeds [`WARN_COND`].
    pub fn require_solvable(&self) -> Result<(Diagnostics, Option<String>)> {
        let d = self.check()?;
        if !d.aliases.is_empty() {
            return Err(Error::Unseparable { aliases: d.aliases });
        }
        if d.rank < 6 {
            return Err(Error::IllConditioned {
                terms: d.weakest.terms.join(", "),
                condition: d.condition,
                limit: DEFAULT_COND_LIMIT,
            });
        }
        // Exercise the prediction path too: a unit-noise covariance exists.
        let nominal: Vec<Vector3<f64>> = self.accelerometers.iter().map(|a| a.direction).collect();
        let _: Estimates = self
            .motion_design(&nominal, STANDARD_GRAVITY_M_S2)?
            .predict(&DVector::from_element(self.len(), 1.0))?;
        let warning = (d.condition > WARN_COND).then(|| {
            format!(
                "weak array geometry (condition number {:.2e}): {} is poorly determined",
                d.condition,
                d.weakest.combination()
            )
        });
        Ok((d, warning))
    }
}

/// Two unit vectors `p, q` completing the nominal direction `l` to an
/// orthonormal frame in the paper's axis cycle (GFIMU note eq. 8–10): for
/// `l` along x the cross axes are y then z; along y: z then x; along z:
/// x then y. For an oblique `l` the dominant axis decides the cycle and
/// the next two unit axes are Gram–Schmidt orthogonalised against `l`.
pub fn cross_axes(l: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let k = l.iamax();
    let e = |i: usize| {
        let mut v = Vector3::zeros();
        v[i % 3] = 1.0;
        v
    };
    let ln = l.normalize();
    let p0 = e(k + 1);
    let p = (p0 - ln * ln.dot(&p0)).normalize();
    let q0 = e(k + 2);
    let q = (q0 - ln * ln.dot(&q0) - p * p.dot(&q0)).normalize();
    (p, q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_layout_is_well_conditioned() {
        let g = Geometry::paper(0.1).unwrap();
        let (d, w) = g.require_solvable().unwrap();
        assert_eq!(d.rank, 6);
        assert!(d.condition < 10.0, "{}", d.condition);
        assert!(w.is_none());
    }

    #[test]
    fn cross_axes_follow_the_paper_cycle() {
        let (p, q) = cross_axes(&Vector3::new(0.0, 0.0, 1.0));
        assert_eq!((p, q), (Vector3::x(), Vector3::y()));
        let (p, q) = cross_axes(&Vector3::new(1.0, 0.0, 0.0));
        assert_eq!((p, q), (Vector3::y(), Vector3::z()));
        let (p, q) = cross_axes(&Vector3::new(0.0, 1.0, 0.0));
        assert_eq!((p, q), (Vector3::z(), Vector3::x()));
    }
}
