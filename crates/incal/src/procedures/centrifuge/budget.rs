//! Cross-coupling algebra and uncertainty budgets (He & Yin 2017 eq. 2, 3, 8, 10).
//!
//! In a plane with axes `a` (first) and `b` (second), the quadratic
//! coefficient of the output against the centripetal input at nominal
//! angle φ0 is (eq. 2)
//! `c2(φ0) = K_aa cos²φ0 + K_bb sin²φ0 + K_ab sinφ0 cosφ0`, so
//! `K_ab = (c2 − K_aa cos²φ0 − K_bb sin²φ0) / (sinφ0 cosφ0)`
//! (eq. 3 at 45°: `K_ab = 2c2 − K_aa − K_bb`). An angle error Δφ changes c2
//! by (eq. 8) `Δc2 = [(K_bb − K_aa) sin 2φ0 + K_ab cos 2φ0] Δφ`.
//!
//! # Budget convention
//! Every coefficient is a linear combination of independent inputs (the
//! `c2` of different stations come from different data; the type-B
//! alignment components are independent by construction), so the GUM
//! (JCGM 100 eq. 10) gives `u² = Σ (c_k u_k)²` with sensitivity
//! `c_k = ∂K/∂x_k`. For `K_ip` at 45° the sensitivity of `c2` and `Δc2` is
//! 2, i.e. `4(u²(c2) + u²(Δc2))`; the paper's eq. 10 writes
//! `2(u²(c2) + u²(Δc2))`. Both are reported; `u` is the GUM one.

/// Quadratic coefficient at angle φ0 (eq. 2).
pub fn c2_at(k_aa: f64, k_bb: f64, k_ab: f64, phi0_rad: f64) -> f64 {
    let (s, c) = phi0_rad.sin_cos();
    k_aa * c * c + k_bb * s * s + k_ab * s * c
}

/// Cross-coupling from a cross-position c2 (eq. 2 solved; eq. 3 at 45°).
/// Any consistent unit (g/g² or (m/s²)/(m/s²)²).
pub fn cross_coupling(c2: f64, k_aa: f64, k_bb: f64, phi0_rad: f64) -> f64 {
    let (s, c) = phi0_rad.sin_cos();
    (c2 - k_aa * c * c - k_bb * s * s) / (s * c)
}

/// Change of c2 for an angle error `dphi_rad` (eq. 8).
pub fn delta_c2(k_aa: f64, k_bb: f64, k_ab: f64, phi0_rad: f64, dphi_rad: f64) -> f64 {
    ((k_bb - k_aa) * (2.0 * phi0_rad).sin() + k_ab * (2.0 * phi0_rad).cos()) * dphi_rad
}

/// ECM offset and fixture-centre radius from the IA-radial radii
/// (He & Yin 2017 §2.2): `(R, r) = ((R+ + R−)/2, (R+ − R−)/2)`, r signed.
pub fn ecm_offset(r_plus_m: f64, r_minus_m: f64) -> (f64, f64) {
    (0.5 * (r_plus_m + r_minus_m), 0.5 * (r_plus_m - r_minus_m))
}

/// How a component's standard uncertainty was evaluated (JCGM 100 §4.2,
/// §4.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum UncertaintyType {
    /// Type A: statistical analysis of series of observations.
    A,
    /// Type B: other means (a stated bound, a given u).
    B,
}

impl UncertaintyType {
    /// `A` or `B`.
    pub fn as_str(self) -> &'static str {
        match self {
            UncertaintyType::A => "A",
            UncertaintyType::B => "B",
        }
    }
}

impl std::fmt::Display for UncertaintyType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One line of an uncertainty budget.
#[derive(Debug, Clone, PartialEq)]
pub struct BudgetLine {
    /// Component (e.g. `c2(ip,45)`, `alignment dc2(ip,45)`, `K2`, `K1`).
    pub component: String,
    /// `A` (statistical) or `B` (other means, e.g. uniform bound).
    pub kind: UncertaintyType,
    /// Standard uncertainty of the component (its own unit).
    pub u: f64,
    /// Sensitivity coefficient `∂K/∂x`.
    pub sensitivity: f64,
    /// Contribution `|c| u` (unit of the coefficient).
    pub contribution: f64,
}

/// The uncertainty budget of one coefficient.
#[derive(Debug, Clone, PartialEq)]
pub struct Budget {
    /// Coefficient name.
    pub coefficient: String,
    /// Lines, in input order.
    pub lines: Vec<BudgetLine>,
    /// Combined standard uncertainty (GUM), `sqrt(Σ contribution²)`.
    pub combined_u: f64,
    /// The paper's eq. 10 combination (cross positions at 45° only).
    pub combined_u_paper_eq10: Option<f64>,
    /// Welch–Satterthwaite effective degrees of freedom (type B: ∞).
    pub effective_dof: f64,
}

impl Budget {
    /// Build from lines; `own` marks the lines the paper weights by 2
    /// instead of 4 (c2 and Δc2 of the cross position), `dofs` the degrees
    /// of freedom of each line.
    pub fn from_lines(
        coefficient: String,
        lines: Vec<BudgetLine>,
        own: &[bool],
        dofs: &[f64],
        paper: bool,
    ) -> Budget {
        let combined_u = lines
            .iter()
            .map(|l| l.contribution.powi(2))
            .sum::<f64>()
            .sqrt();
        let combined_u_paper_eq10 = paper.then(|| {
            lines
                .iter()
                .zip(own)
                .map(|(l, o)| {
                    if *o {
                        2.0 * l.u * l.u
                    } else {
                        l.contribution.powi(2)
                    }
                })
                .sum::<f64>()
                .sqrt()
        });
        let denom: f64 = lines
            .iter()
            .zip(dofs)
            .filter(|(l, d)| d.is_finite() && **d > 0.0 && l.contribution > 0.0)
            .map(|(l, d)| l.contribution.powi(4) / d)
            .sum();
        let effective_dof = if denom > 0.0 {
            combined_u.powi(4) / denom
        } else {
            f64::INFINITY
        };
        Budget {
            coefficient,
            lines,
            combined_u,
            combined_u_paper_eq10,
            effective_dof,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq3_is_eq2_solved_at_45() {
        let phi = 45f64.to_radians();
        let (k2, kpp, kip) = (3.94e-7, 4.7e-8, 7.1e-7);
        let c2 = c2_at(k2, kpp, kip, phi);
        assert!((cross_coupling(c2, k2, kpp, phi) - kip).abs() < 1e-18);
        assert!((2.0 * c2 - (k2 + kpp) - kip).abs() < 1e-18);
    }

    #[test]
    fn eq8_is_the_derivative_of_eq2() {
        let (k2, kpp, kip) = (3.94e-7, 4.7e-8, 7.1e-7);
        for deg in [10.0f64, 45.0, 90.0, 120.0] {
            let phi = deg.to_radians();
            let h = 1e-6;
            let num = (c2_at(k2, kpp, kip, phi + h) - c2_at(k2, kpp, kip, phi - h)) / (2.0 * h);
            assert!((delta_c2(k2, kpp, kip, phi, 1.0) - num).abs() < 1e-15);
        }
    }
}
