//! The kinematics of the gyro fit, in imu_tk's conventions: the RK4
//! quaternion step of `q̇ = ½ Ω(ω) q`, the rotation of a quaternion, a
//! motion between two still intervals integrated with calibrated rates,
//! and the two directions normal to gravity that incal projects the gyro
//! residual on.

use nalgebra::{Matrix4, Vector4};

use super::super::{M3, V3};

/// imu_tk's `Ω(ω)` of the quaternion derivative `q̇ = ½ Ω(ω) q`, q = (w, x, y, z).
fn omega_skew(w: &V3) -> Matrix4<f64> {
    Matrix4::new(
        0.0, -w[0], -w[1], -w[2], //
        w[0], 0.0, w[2], -w[1], //
        w[1], -w[2], 0.0, w[0], //
        w[2], w[1], -w[0], 0.0,
    )
}

/// One RK4 quaternion step from rate `w0` to `w1` over `dt` (imu_tk's
/// `quatIntegrationStepRK4`), normalised.
pub fn rk4_step(q: &Vector4<f64>, w0: &V3, w1: &V3, dt: f64) -> Vector4<f64> {
    let w01 = (w0 + w1) * 0.5;
    let k1 = omega_skew(w0) * q * 0.5;
    let k2 = omega_skew(&w01) * (q + k1 * (0.5 * dt)) * 0.5;
    let k3 = omega_skew(&w01) * (q + k2 * (0.5 * dt)) * 0.5;
    let k4 = omega_skew(w1) * (q + k3 * dt) * 0.5;
    let r = q + (k1 / 6.0 + k2 / 3.0 + k3 / 3.0 + k4 / 6.0) * dt;
    r / r.norm()
}

/// Rotation matrix of a unit quaternion (w, x, y, z) (ceres'
/// `QuaternionToRotation`).
pub fn quat_to_rotation(q: &Vector4<f64>) -> M3 {
    let (a, b, c, d) = (q[0], q[1], q[2], q[3]);
    let s = 1.0 / (a * a + b * b + c * c + d * d);
    M3::new(
        a * a + b * b - c * c - d * d,
        2.0 * (b * c - a * d),
        2.0 * (a * c + b * d),
        2.0 * (a * d + b * c),
        a * a - b * b + c * c - d * d,
        2.0 * (c * d - a * b),
        2.0 * (b * d - a * c),
        2.0 * (a * b + c * d),
        a * a - b * b - c * c + d * d,
    ) * s
}

/// One motion between still intervals: the raw gyro samples (bias not yet
/// removed), their time steps, and the gravity directions before and after.
pub(super) struct Motion {
    /// Raw gyro samples, from the last sample of the first still interval
    /// to the one before the second.
    pub gyr: Vec<V3>,
    /// Time steps between them (s).
    pub dt: Vec<f64>,
    /// Gravity direction before.
    pub g0: V3,
    /// Gravity direction after.
    pub g1: V3,
    /// Two unit vectors normal to g1 (incal's projection).
    pub basis: [V3; 2],
    /// Index of the still interval it starts from.
    pub from: usize,
}

/// Integrate the calibrated rates of a motion: `R(q)` from the start.
pub(super) fn integrate(m: &Motion, tk: &M3, bias: &V3) -> M3 {
    let mut q = Vector4::new(1.0, 0.0, 0.0, 0.0);
    let mut w_prev = tk * (m.gyr[0] - bias);
    for i in 0..m.dt.len() {
        let w_next = tk * (m.gyr[i + 1] - bias);
        q = rk4_step(&q, &w_prev, &w_next, m.dt[i]);
        w_prev = w_next;
    }
    quat_to_rotation(&q)
}

/// Two unit vectors normal to the unit vector `g` (incal's projection
/// basis): the sensor axis least aligned with `g`, made normal to it,
/// and `g` × that.
pub(super) fn unit_basis(g: &V3) -> [V3; 2] {
    let k = (0..3)
        .min_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
        .unwrap_or(0);
    let mut e = V3::zeros();
    e[k] = 1.0;
    let u = (e - g * g.dot(&e)).normalize();
    [u, g.cross(&u)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rk4_integrates_a_constant_rate() {
        let w = V3::new(0.0, 0.0, 1.0);
        let mut q = Vector4::new(1.0, 0.0, 0.0, 0.0);
        for _ in 0..100 {
            q = rk4_step(&q, &w, &w, 0.01);
        }
        let r = quat_to_rotation(&q);
        // One radian about z: body x turns towards y.
        assert!(
            (r[(0, 0)] - 1f64.cos()).abs() < 1e-9,
            "{}",
            r[(0, 0)] - 1f64.cos()
        );
        assert!((r[(1, 0)] - 1f64.sin()).abs() < 1e-9);
    }
}
