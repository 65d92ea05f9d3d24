//! Single-axis rate table carrying a fixture and a gyro, and the vertical
//! reference face of the accelerometer test (Li et al. 2012 §2–3, docs/src/misalignment.md).
//!
//! # Conventions
//! Rotations are *passive* (they transform vector components into the
//! rotated frame), as in Li et al. 2012 eq. 3:
//! `Px(a) = [[1,0,0],[0,c,s],[0,−s,c]]`, `Py(a) = [[c,0,−s],[0,1,0],[s,0,c]]`,
//! `Pz(a) = [[c,s,0],[−s,c,0],[0,0,1]]`.
//!
//! Gyro chain (Li et al. 2012 eq. 3), reference frame z up along the table axis,
//! y north: `ω_body = P2 · Px(α) · P1 · Pz(β) · P0 · Pz(γ) · ω_ref`, with
//! `P0 = Px(Δθx0) Py(Δθy0)` (table face vs spin axis),
//! `P1 = Py(Δθy1) Pz(Δθz1)` (fixture face), `P2 = Py(Δθy2) Pz(Δθz2)` (gyro
//! input axis vs its mounting face), γ the table angle, β the fixture on the
//! table, α the gyro on the fixture, and
//! `ω_ref = [0, Ωe cos φ, ω + Ωe sin φ]`. The input axis is body x.
//! To first order in the small angles and Ωe (Li et al. 2012 after eq. 3):
//!
//! ```text
//! ω_I = Ωe cos φ sin(γ + β) − ω [Δθy0 cos β − Δθx0 sin β + Δθy1
//!                                 − Δθz2 sin α + Δθy2 cos α]
//! ```
//!
//! so whole-revolution means of `±ω` records cancel the Earth-rate term.

use crate::units::EARTH_RATE_RAD_S;

/// A 3×3 matrix, rows first.
pub type Mat3 = [[f64; 3]; 3];

/// `sin` and `cos` of an angle, exact (0, ±1) at whole multiples of 90°,
/// so that a plan at 0/90/180° gives exactly zero regressors and aliasing
/// is detected rather than hidden behind 1e-16 rounding.
pub fn sin_cos_exact(angle_rad: f64) -> (f64, f64) {
    let deg = angle_rad.to_degrees().rem_euclid(360.0);
    let q = (deg / 90.0).round();
    if (deg - 90.0 * q).abs() < 1e-9 {
        match (q as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        angle_rad.sin_cos()
    }
}

/// Passive rotation about x by `a` (rad).
pub fn px(a: f64) -> Mat3 {
    let (s, c) = sin_cos_exact(a);
    [[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]]
}
/// Passive rotation about y by `a` (rad).
pub fn py(a: f64) -> Mat3 {
    let (s, c) = sin_cos_exact(a);
    [[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]]
}
/// Passive rotation about z by `a` (rad).
pub fn pz(a: f64) -> Mat3 {
    let (s, c) = sin_cos_exact(a);
    [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Matrix product `a · b`.
pub fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// Matrix times vector.
pub fn apply(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2])
}

/// The small mounting angles of the gyro test (rad), Li et al. 2012 §2.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GyroMounting {
    /// Table face vs spin axis, about x (rad).
    pub dtheta_x0: f64,
    /// Table face vs spin axis, about y (rad).
    pub dtheta_y0: f64,
    /// Fixture face vs its base, about y (rad).
    pub dtheta_y1: f64,
    /// Fixture face vs its base, about z (rad); unobservable, second order.
    pub dtheta_z1: f64,
    /// Gyro input axis vs its mounting face, about y (rad).
    pub dtheta_y2: f64,
    /// Gyro input axis vs its mounting face, about z (rad).
    pub dtheta_z2: f64,
}

/// Angular rate along the gyro axes (deg/s), exact rotation chain of the
/// module docs: table angle `gamma_rad`, table rate `rate_deg_s` (signed,
/// relative to the Earth), fixture angle `beta_rad`, gyro angle `alpha_rad`,
/// latitude `latitude_rad`. Returns `[ω_I, ω_2, ω_3]`.
pub fn gyro_rates_deg_s(
    m: &GyroMounting,
    alpha_rad: f64,
    beta_rad: f64,
    gamma_rad: f64,
    rate_deg_s: f64,
    latitude_rad: f64,
) -> [f64; 3] {
    let we = EARTH_RATE_RAD_S.to_degrees();
    let (sl, cl) = latitude_rad.sin_cos();
    let w_ref = [0.0, we * cl, rate_deg_s + we * sl];
    let p0 = mul(&px(m.dtheta_x0), &py(m.dtheta_y0));
    let p1 = mul(&py(m.dtheta_y1), &pz(m.dtheta_z1));
    let p2 = mul(&py(m.dtheta_y2), &pz(m.dtheta_z2));
    let chain = [p2, px(alpha_rad), p1, pz(beta_rad), p0, pz(gamma_rad)];
    let total = chain.iter().skip(1).fold(chain[0], |acc, r| mul(&acc, r));
    apply(&total, w_ref)
}

/// Factors of the five separable angles in the linearised input rate
/// `ω_I = ω · Σ f_k θ_k` (Li et al. 2012 eq. 4; docs/src/misalignment.md), in the order
/// `Δθy0, Δθx0, Δθy1, Δθy2, Δθz2`:
/// `f = [−cos β, sin β, −1, −cos α, sin α]`.
pub fn gyro_factors(alpha_rad: f64, beta_rad: f64) -> [f64; 5] {
    let (sa, ca) = sin_cos_exact(alpha_rad);
    let (sb, cb) = sin_cos_exact(beta_rad);
    [-cb, sb, -1.0, -ca, sa]
}

/// The small angles of the accelerometer test on a vertical face (rad),
/// Li et al. 2012 §3.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaceMounting {
    /// Verticality error of the reference face, about y (rad).
    pub dtheta_y0: f64,
    /// Fixture error, about y (rad).
    pub dtheta_y1: f64,
    /// Input axis vs mounting face, about y (rad).
    pub dtheta_y2: f64,
    /// Input axis vs mounting face, about z (rad).
    pub dtheta_z2: f64,
}

/// Specific force along the accelerometer's axes (g) with the instrument
/// turned by `beta_rad` about the horizontal normal (body x = IA) of the
/// vertical face: `a = Py(Δθy2) Pz(Δθz2) · Px(β) · Py(Δθy1) Py(Δθy0) · [0,0,1]`
/// (passive, Li et al. 2012 §3), to first order
/// `a_I = −Δθy0 − Δθy1 + Δθz2 sin β − Δθy2 cos β`.
pub fn face_specific_force_g(m: &FaceMounting, beta_rad: f64) -> [f64; 3] {
    let p2 = mul(&py(m.dtheta_y2), &pz(m.dtheta_z2));
    let pf = mul(&py(m.dtheta_y1), &py(m.dtheta_y0));
    let total = mul(&mul(&p2, &px(beta_rad)), &pf);
    apply(&total, [0.0, 0.0, 1.0])
}

/// Factors of `Δθy2, Δθz2` in the linearised `a_I`: `[−cos β, sin β]`.
pub fn face_factors(beta_rad: f64) -> [f64; 2] {
    let (s, c) = sin_cos_exact(beta_rad);
    [-c, s]
}

#[cfg(test)]
mod tests {
    use super::*;

    const AS: f64 = 1.0 / 206_264.806;

    #[test]
    fn exact_chain_matches_linearised_rate() {
        let m = GyroMounting {
            dtheta_x0: 2.3 * AS,
            dtheta_y0: -7.6 * AS,
            dtheta_y1: -54.0 * AS,
            dtheta_z1: 30.0 * AS,
            dtheta_y2: -162.2 * AS,
            dtheta_z2: 55.4 * AS,
        };
        for (a, b) in [(0.0f64, 0.0f64), (90.0, 180.0), (37.0, 123.0)] {
            let (a, b) = (a.to_radians(), b.to_radians());
            let w = 20.0;
            // latitude 90°: Earth rate along the table axis only, γ = 0.
            let exact = gyro_rates_deg_s(&m, a, b, 0.0, w, 0.0)[0];
            let f = gyro_factors(a, b);
            let th = [
                m.dtheta_y0,
                m.dtheta_x0,
                m.dtheta_y1,
                m.dtheta_y2,
                m.dtheta_z2,
            ];
            let lin: f64 = w * f.iter().zip(th).map(|(f, t)| f * t).sum::<f64>();
            let we = EARTH_RATE_RAD_S.to_degrees();
            let lin = lin + we * b.sin();
            // second-order terms: (1e-3 rad)² · 20 deg/s
            assert!((exact - lin).abs() < 5e-6, "{exact} vs {lin}");
        }
    }

    #[test]
    fn face_chain_matches_linearised_input() {
        let m = FaceMounting {
            dtheta_y0: 10.0 * AS,
            dtheta_y1: -4.0 * AS,
            dtheta_y2: -5.3 * AS,
            dtheta_z2: 20.5 * AS,
        };
        for b in [0.0f64, 90.0, 180.0, 270.0, 33.0] {
            let b = b.to_radians();
            let a = face_specific_force_g(&m, b)[0];
            let f = face_factors(b);
            let lin = -m.dtheta_y0 - m.dtheta_y1 + f[0] * m.dtheta_y2 + f[1] * m.dtheta_z2;
            assert!((a - lin).abs() < 1e-8, "{a} {lin}");
        }
    }

    #[test]
    fn quadrant_trig_is_exact() {
        assert_eq!(sin_cos_exact(std::f64::consts::PI), (0.0, -1.0));
        assert_eq!(sin_cos_exact(-std::f64::consts::FRAC_PI_2), (-1.0, 0.0));
    }
}
