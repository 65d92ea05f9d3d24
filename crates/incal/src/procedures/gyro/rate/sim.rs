//! Rate-table simulator: a truth and a plan give observations in the
//! input format of [`crate::procedures::gyro::rate`].
//!
//! The kinematics are computed here from vectors (frame x north, y east,
//! z up; Earth rate `Ω_e (cos φ, 0, sin φ)`, the table turning about z,
//! IA along ±z), not from the closed form the reduction uses, so a round
//! trip checks the reduction's kinematics as well as its statistics.

use super::{InputAxis, RateObservation, MAX_RATE_DEG_S};
use crate::error::{Error, Result};
use crate::sim::{normal, rng};
use crate::units::EARTH_RATE_RAD_S;

/// Largest |K1| a simulator accepts (output/(deg/s)).
pub const MAX_SIM_K1: f64 = 1e9;

/// Largest output noise σ a simulator accepts (output units).
pub const MAX_SIM_NOISE: f64 = 1e9;

/// Truth and plan of a simulated rate-transfer test.
#[derive(Debug, Clone, PartialEq)]
pub struct GyroRateSim {
    /// Scale factor for positive input rates (output/(deg/s)).
    pub k1_pos: f64,
    /// Scale factor for negative input rates (output/(deg/s)).
    pub k1_neg: f64,
    /// Bias (deg/h).
    pub b_deg_h: f64,
    /// K2 (1/(deg/s)).
    pub k2: f64,
    /// K3 (1/(deg/s)²).
    pub k3: f64,
    /// Latitude (rad).
    pub latitude_rad: f64,
    /// Input axis up or down.
    pub ia: InputAxis,
    /// Table rates (deg/s), in test order.
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    pub samples: usize,
    /// Output noise per sample (output units).
    pub noise: f64,
    /// Number of runs (1: no run column).
    pub runs: usize,
    /// Run-to-run scatter of K1 (ppm, standard deviation), one draw per run.
    pub run_scatter_ppm: f64,
    /// The output clips at ±`clip` (output units; 0: never).
    pub clip: f64,
    /// Seed.
    pub seed: u64,
}

/// The scale factors for positive and negative input rates of a gyro with
/// mean scale factor `k1` and asymmetry `asymmetry_ppm = (K1⁺ − K1⁻)/K1 ·
/// 10⁶` (IEEE Std 952 §3): `K1± = K1 (1 ± asymmetry·10⁻⁶/2)`.
pub fn k1_pos_neg(k1: f64, asymmetry_ppm: f64) -> (f64, f64) {
    let half = 0.5 * asymmetry_ppm * 1e-6;
    (k1 * (1.0 + half), k1 * (1.0 - half))
}

impl GyroRateSim {
    /// Refuse a configuration that cannot be simulated: a scale factor
    /// `K1 = (K1⁺ + K1⁻)/2` that is zero or beyond 1e9, an asymmetry of
    /// 10⁶ ppm or more, B beyond 1e7 deg/h, K2 or K3 beyond 1, a latitude
    /// outside ±90°, no samples or runs, more than
    /// [`crate::sim::MAX_SIM_ROWS`] rows, a rate beyond 1e5 deg/s, a noise
    /// outside 0…1e9, a run scatter outside 0…1e5 ppm, or a truth whose
    /// output is not finite.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &str, v: f64| Error::invalid(what, v);
        let k1 = 0.5 * (self.k1_pos + self.k1_neg);
        if !(k1.is_finite() && k1 != 0.0 && k1.abs() <= MAX_SIM_K1) {
            return bad("k1 (non-zero, at most 1e9 in magnitude)", k1);
        }
        let asymmetry_ppm = (self.k1_pos - self.k1_neg) / k1 * 1e6;
        if !(asymmetry_ppm.is_finite() && asymmetry_ppm.abs() < 1e6) {
            return bad("asymmetry_ppm (below 1e6 in magnitude)", asymmetry_ppm);
        }
        if !(self.b_deg_h.is_finite() && self.b_deg_h.abs() <= 1e7) {
            return bad("b_deg_h (at most 1e7 in magnitude)", self.b_deg_h);
        }
        for (name, v) in [("k2", self.k2), ("k3", self.k3)] {
            if !(v.is_finite() && v.abs() <= 1.0) {
                return bad(&format!("{name} (at most 1 in magnitude)"), v);
            }
        }
        crate::options::check_latitude_deg(self.latitude_rad.to_degrees())?;
        if self.samples == 0 {
            return bad("samples (at least 1 per rate)", 0.0);
        }
        if self.runs == 0 {
            return bad("runs (at least 1)", 0.0);
        }
        if self.rates_deg_s.is_empty() {
            return Err(Error::TooFew {
                what: "rates_deg_s".into(),
                needed: 1,
                got: 0,
            });
        }
        crate::sim::check_rows(&[
            ("rates_deg_s", self.rates_deg_s.len() as f64),
            ("samples", self.samples as f64),
            ("runs", self.runs as f64),
        ])?;
        if let Some(r) = self
            .rates_deg_s
            .iter()
            .find(|r| !(r.is_finite() && r.abs() <= MAX_RATE_DEG_S))
        {
            return bad("rates_deg_s (a table rate, |rate| <= 1e5 deg/s)", *r);
        }
        if !(self.noise.is_finite() && (0.0..=MAX_SIM_NOISE).contains(&self.noise)) {
            return bad("noise (a non-negative number, at most 1e9)", self.noise);
        }
        if !(self.run_scatter_ppm.is_finite() && (0.0..1e5).contains(&self.run_scatter_ppm)) {
            return bad("run_scatter_ppm (within 0..1e5)", self.run_scatter_ppm);
        }
        if !(self.clip.is_finite() && self.clip >= 0.0) {
            return bad("clip (a non-negative output, 0 for none)", self.clip);
        }
        for &rate in &self.rates_deg_s {
            let (w_in, k1) = self.input_and_scale(rate);
            if !self.output(w_in, k1).is_finite() {
                return bad("truth (its output is not finite) at rate_deg_s", rate);
            }
        }
        Ok(())
    }

    /// Rate along IA (deg/s) at table rate `rate_deg_s`, and the scale
    /// factor of its sign.
    fn input_and_scale(&self, rate_deg_s: f64) -> (f64, f64) {
        let we = EARTH_RATE_RAD_S.to_degrees();
        let axis = [0.0, 0.0, self.ia.sign()];
        // Total rate (deg/s) in the local frame: Earth plus the table about z.
        let w = [
            we * self.latitude_rad.cos(),
            0.0,
            we * self.latitude_rad.sin() + rate_deg_s,
        ];
        let w_in: f64 = (0..3).map(|k| w[k] * axis[k]).sum();
        let k1 = if w_in >= 0.0 {
            self.k1_pos
        } else {
            self.k1_neg
        };
        (w_in, k1)
    }

    /// Noise-free output at input rate `w_in` with scale factor `k1`.
    fn output(&self, w_in: f64, k1: f64) -> f64 {
        k1 * (w_in + self.b_deg_h / 3600.0 + self.k2 * w_in * w_in + self.k3 * w_in.powi(3))
    }
}

/// Simulate a rate-transfer test: `E = K1± (ω_in + B + K2 ω_in² + K3 ω_in³) + n`
/// with `ω_in` the table rate plus the Earth rate projected on IA, clipped
/// at `±clip` when it is not 0 (a converter at full scale; deterministic
/// for a given seed).
pub fn simulate_rate(cfg: &GyroRateSim) -> Vec<RateObservation> {
    let mut r = rng(cfg.seed);
    let mut out = Vec::new();
    for run in 0..cfg.runs.max(1) {
        let scale = 1.0 + normal(&mut r, cfg.run_scatter_ppm * 1e-6);
        let label = (cfg.runs > 1).then(|| format!("run{}", run + 1));
        for &rate in &cfg.rates_deg_s {
            let (w_in, k1) = cfg.input_and_scale(rate);
            let e0 = cfg.output(w_in, k1 * scale);
            for _ in 0..cfg.samples.max(1) {
                let y = e0 + normal(&mut r, cfg.noise);
                out.push(RateObservation {
                    rate_deg_s: rate,
                    output: if cfg.clip > 0.0 {
                        y.clamp(-cfg.clip, cfg.clip)
                    } else {
                        y
                    },
                    run: label.clone(),
                });
            }
        }
    }
    out
}

/// Options of the rate-transfer simulator (`incal simulate gyro-rate`), in
/// engineering units; a key not given takes the command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct GyroRateSimOptions {
    /// Scale factor K1 (output/(deg/s)), the mean of K1⁺ and K1⁻.
    pub k1: f64,
    /// Scale-factor asymmetry (K1⁺ − K1⁻)/K1 (ppm).
    pub asymmetry_ppm: f64,
    /// Bias B (deg/h).
    pub b_deg_h: f64,
    /// K2 (1/(deg/s)).
    pub k2: f64,
    /// K3 (1/(deg/s)²).
    pub k3: f64,
    /// Latitude (deg).
    pub latitude_deg: f64,
    /// Input axis up or down.
    pub ia: InputAxis,
    /// Table rates (deg/s), in test order.
    pub rates_deg_s: Vec<f64>,
    /// Samples per rate.
    pub samples: usize,
    /// Output noise of one sample (output units).
    pub noise: f64,
    /// Runs (2 or more add a `run` column).
    pub runs: usize,
    /// Run-to-run scatter of K1 (ppm, standard deviation).
    pub run_scatter_ppm: f64,
    /// The output clips at ±clip (output units; 0: never).
    pub clip: f64,
    /// Random seed (same seed, same file).
    pub seed: u64,
}

impl Default for GyroRateSimOptions {
    fn default() -> Self {
        Self {
            k1: 0.02,
            asymmetry_ppm: 0.0,
            b_deg_h: 5.0,
            k2: 0.0,
            k3: 0.0,
            latitude_deg: 45.0,
            ia: InputAxis::Up,
            rates_deg_s: vec![
                -200.0, -100.0, -50.0, -10.0, -1.0, 1.0, 10.0, 50.0, 100.0, 200.0,
            ],
            samples: 20,
            noise: 2e-5,
            runs: 1,
            run_scatter_ppm: 0.0,
            clip: 0.0,
            seed: 1,
        }
    }
}

impl GyroRateSimOptions {
    /// The simulator's configuration (K1⁺ and K1⁻ from K1 and the
    /// asymmetry, latitude in rad: the one conversion), refused as
    /// [`GyroRateSim::validate`] refuses.
    pub fn config(&self) -> Result<GyroRateSim> {
        crate::options::check_latitude_deg(self.latitude_deg)?;
        let (k1_pos, k1_neg) = k1_pos_neg(self.k1, self.asymmetry_ppm);
        let cfg = GyroRateSim {
            k1_pos,
            k1_neg,
            b_deg_h: self.b_deg_h,
            k2: self.k2,
            k3: self.k3,
            latitude_rad: self.latitude_deg.to_radians(),
            ia: self.ia,
            rates_deg_s: self.rates_deg_s.clone(),
            samples: self.samples,
            noise: self.noise,
            runs: self.runs,
            run_scatter_ppm: self.run_scatter_ppm,
            clip: self.clip,
            seed: self.seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

impl crate::procedures::Simulate for super::GyroRate {
    type Options = GyroRateSimOptions;

    fn validate(o: &GyroRateSimOptions) -> Result<()> {
        o.config().map(|_| ())
    }

    fn simulate(o: &GyroRateSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let obs = simulate_rate(&o.config()?);
        super::input::write(&obs, out)?;
        Ok(())
    }
}
