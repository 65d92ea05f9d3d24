//! The per-sample uncertainty of the motion solution (the `solve` module
//! docs, "Uncertainty"): the sample-noise part, the calibration part
//! carried through the specific force at each accelerometer, and the
//! integrated-ω error through the centripetal gradient, with the
//! propagation of the ω error covariance from sample to sample. Only the
//! diagonal of the p × p covariance is formed, and nothing is allocated.

use nalgebra::{Matrix3, Vector3};

use super::{NoiseSource, Solver, MAX_P};

impl Solver {
    /// The factor of the per-sample noise covariance: 1 for a known σ,
    /// the residual variance of this sample's solve at the final ω, or 0.
    fn noise_scale(&mut self, e: &[f64], w: &Vector3<f64>, x: &[f64; MAX_P]) -> f64 {
        let (n, p) = (self.cal.len(), self.p);
        match self.noise {
            NoiseSource::Known => 1.0,
            NoiseSource::Residuals => {
                // Residuals of the last solve, at the final ω.
                self.reduce(e, w);
                let mut ss = 0.0;
                for (j, yj) in self.y.iter().enumerate() {
                    let row = &self.design[j * p..(j + 1) * p];
                    let fit: f64 = row.iter().zip(&x[..p]).map(|(a, b)| a * b).sum();
                    ss += (yj - fit) * (yj - fit);
                }
                ss / (n - p) as f64
            }
            NoiseSource::None => 0.0,
        }
    }

    /// The rows of `P G` at ω (feedback; zero in direct mode), `G_j` the
    /// centripetal gradient of accelerometer j; `Q` (their ω̇ rows) kept
    /// for `F = I − QΔt`.
    fn centripetal_gain(&mut self, w: &Vector3<f64>) -> [Vector3<f64>; MAX_P] {
        let (n, p) = (self.cal.len(), self.p);
        let mut pg = [Vector3::zeros(); MAX_P];
        if !matches!(self.mode, super::SolveMode::Feedback { .. }) {
            return pg;
        }
        for j in 0..n {
            let s = &self.cal[j].ks;
            let r = &self.r[j];
            self.grad[j] = (s * w.dot(r) + r * s.dot(w) - w * (2.0 * s.dot(r))) / self.g;
        }
        for (a, pga) in pg.iter_mut().enumerate().take(p) {
            let row = &self.pinv[a * n..(a + 1) * n];
            *pga = row
                .iter()
                .zip(&self.grad)
                .fold(Vector3::zeros(), |acc, (pj, gj)| acc + gj * *pj);
        }
        self.q_last =
            Matrix3::from_rows(&[pg[3].transpose(), pg[4].transpose(), pg[5].transpose()]);
        pg
    }

    /// The calibration's part: added to `diag`, and the covariance of the
    /// integrated ω it causes (returned).
    ///
    /// The sensitivity of x to every K0_j, Ks_j at the specific force f_j
    /// of each accelerometer is `∂x/∂K0_j = −P_:j`, `∂x/∂Ks_ja = −P_:j f_ja`.
    /// Every column for accelerometer j is a multiple of P_:j, so
    /// `D U Dᵀ = Σ_j v_j P_:j P_:jᵀ` with `v_j = u²(K0_j) + Σ_a f_ja² u²(Ks_ja)`.
    /// The ω sensitivity follows `J_k = F J_{k−1} + Δt ∂ω̇/∂cal`.
    fn calibration_u(
        &mut self,
        f0: &Vector3<f64>,
        wd: &Vector3<f64>,
        w: &Vector3<f64>,
        dt: f64,
        diag: &mut [f64; MAX_P],
    ) -> Matrix3<f64> {
        let mut sigma_cal = Matrix3::zeros();
        if !self.has_cal {
            return sigma_cal;
        }
        let (n, p) = (self.cal.len(), self.p);
        let feedback = matches!(self.mode, super::SolveMode::Feedback { .. });
        let fm = if feedback {
            Matrix3::identity() - self.q_last * dt
        } else {
            Matrix3::identity()
        };
        for j in 0..n {
            let r = &self.r[j];
            let fj = f0 + (wd.cross(r) + w.cross(&w.cross(r))) / self.g;
            let u2 = &self.u2_cal[4 * j..4 * j + 4];
            let vj = u2[0] + (0..3).map(|a| fj[a] * fj[a] * u2[1 + a]).sum::<f64>();
            for (a, d) in diag.iter_mut().enumerate().take(p) {
                let pa = self.pinv[a * n + j];
                *d += pa * vj * pa;
            }
            // J_k = F J_{k−1} + Δt ∂ω̇/∂cal (columns of accelerometer j).
            let pw = Vector3::new(
                self.pinv[3 * n + j],
                self.pinv[4 * n + j],
                self.pinv[5 * n + j],
            );
            if feedback {
                for c in 0..4 {
                    let col = 4 * j + c;
                    if dt > 0.0 {
                        let scale = if c == 0 { -1.0 } else { -fj[c - 1] };
                        self.j_cal[col] = fm * self.j_cal[col] + pw * (scale * dt);
                    }
                    let v = self.j_cal[col];
                    sigma_cal += v * v.transpose() * u2[c];
                }
            } else {
                // F = I: the columns are P_ω̇,j times running integrals,
                // and only the diagonal of Σ is used.
                let s = &mut self.cal_integrals[j];
                if dt > 0.0 {
                    s[0] -= dt;
                    for a in 0..3 {
                        s[1 + a] -= fj[a] * dt;
                    }
                }
                let w2: f64 = (0..4).map(|c| s[c] * s[c] * u2[c]).sum();
                for i in 0..3 {
                    sigma_cal[(i, i)] += pw[i] * pw[i] * w2;
                }
            }
        }
        sigma_cal
    }

    /// The variances of the unknowns (diagonal) and the predicted u of the
    /// integrated ω at this sample (module docs), the ω error covariance
    /// propagated by `Σ_k = F Σ_{k−1} Fᵀ + Δt² C_ω̇`.
    pub(super) fn uncertainty(
        &mut self,
        e: &[f64],
        x: &[f64; MAX_P],
        f0: &Vector3<f64>,
        wd: &Vector3<f64>,
        w: &Vector3<f64>,
        dt: f64,
    ) -> ([f64; MAX_P], Vector3<f64>) {
        let p = self.p;
        let noise_scale = self.noise_scale(e, w, x);
        let mut diag = [0.0; MAX_P];
        for (d, nd) in diag.iter_mut().zip(&self.noise_diag[..p]) {
            *d = nd * noise_scale;
        }
        let cwd_noise = self.noise_wd * noise_scale;
        // The centripetal gradient at this sample: Q = ω̇ rows of P G, and
        // F = I − QΔt carries both ω error parts below.
        let pg = self.centripetal_gain(w);
        let sigma_cal = self.calibration_u(f0, wd, w, dt, &mut diag);
        // ω error from the sample noise: a random walk through F.
        if dt > 0.0 {
            let f = Matrix3::identity() - self.q_last * dt;
            self.sigma_omega = f * self.sigma_omega * f.transpose() + cwd_noise * (dt * dt);
        }
        let sigma_total = self.sigma_omega + sigma_cal;
        if matches!(self.mode, super::SolveMode::Feedback { .. }) {
            for (a, d) in diag.iter_mut().enumerate().take(p) {
                *d += pg[a].dot(&(sigma_total * pg[a]));
            }
        }
        let u_omega = Vector3::from_fn(|i, _| sigma_total[(i, i)].max(0.0).sqrt());
        (diag, u_omega)
    }
}
