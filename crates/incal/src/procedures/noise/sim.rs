//! Seeded rate-noise records with the IEEE Std 952 terms as truth, in the
//! input formats of [`crate::procedures::noise`].
//!
//! Rate samples `y_k` at spacing τ0 (rate unit u) as the sum of
//! * quantization Q (u·s): the first difference of a white phase error of
//!   standard deviation Q (uniform, like a quantizer) over τ0 —
//!   `σ² = 3Q²/τ²`;
//! * angle random walk N (u·√s): white rate of standard deviation N/√τ0 —
//!   `σ² = N²/τ`;
//! * bias instability B (u): flicker rate by Kasdin & Walter's power-law
//!   generator (N. J. Kasdin and T. Walter, "Discrete simulation of power
//!   law noise", 1992 IEEE FCS, eq. 7 ff.): white noise of standard
//!   deviation B filtered by `h_0 = 1`, `h_k = h_{k−1}(k − ½)/k`, so the
//!   one-sided PSD is `B²/(πf)` at low f and `σ² = (2 ln 2/π) B²`;
//! * rate random walk K (u/√s): `y_k = y_{k−1} + K√τ0 w_k` — `σ² ≈ K²τ/3`;
//! * rate ramp R (u/s): `R·t` — `σ² = R²τ²/2`;
//! * lines (tones, [`add_tones`]): `a√2 sin(2πft + φ)`, rms amplitude `a`;
//! * a first-order Gauss–Markov bias ([`add_gauss_markov`]).
//!
//! Each term draws from its own ChaCha8 stream, seeded from the channel's
//! seed, so adding a term does not change the others. [`NoiseSim`] takes
//! the terms in engineering units (gyro: deg/s samples; accelerometer: g
//! samples) and writes CSV ([`write_csv`]) or raw interleaved
//! little-endian floats ([`write_binary`]).

mod spectral;
pub use spectral::spectral_record;

use rand::RngExt;
use rayon::prelude::*;

use super::{Format, QuantityKind};
use crate::error::{Error, Result};
use crate::sim::{normal, rng, trial_seed};
use crate::units::STANDARD_GRAVITY_M_S2;
/// IEEE terms of one simulated channel (rate unit base: Q in u·s, N in
/// u·√s, B in u, K in u/√s, R in u/s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NoiseTruth {
    /// Quantization Q.
    pub q: f64,
    /// Angle (velocity) random walk N.
    pub n: f64,
    /// Bias instability B.
    pub b: f64,
    /// Rate random walk K.
    pub k: f64,
    /// Rate ramp R.
    pub r: f64,
}

/// Flicker (1/f) noise of `n` samples by Kasdin & Walter: white noise of
/// standard deviation `sigma` convolved with the α = 1 power-law filter
/// (linear convolution through zero-padded real FFTs, `realfft`).
pub fn flicker(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
    use realfft::num_complex::Complex64;
    use realfft::RealFftPlanner;
    if n == 0 || sigma <= 0.0 {
        return vec![0.0; n];
    }
    let len = (2 * n).next_power_of_two();
    // The forward plan (its twiddles are gigabytes at 10⁸ samples) is
    // dropped before the inverse is planned.
    let fwd = RealFftPlanner::<f64>::new().plan_fft_forward(len);
    // One real buffer and one scratch serve every transform (at 10⁸
    // samples each buffer is 2 GB): the filter's spectrum first, then the
    // same buffer holds the noise.
    let mut scratch = vec![Complex64::new(0.0, 0.0); fwd.get_scratch_len()];
    let mut w = vec![0.0; len];
    w[0] = 1.0;
    for k in 1..n {
        w[k] = w[k - 1] * (k as f64 - 0.5) / k as f64;
    }
    let mut hs = fwd.make_output_vec();
    fwd.process_with_scratch(&mut w, &mut hs, &mut scratch)
        .expect("sizes from the plan");
    let mut r = rng(seed);
    w.fill(0.0);
    for v in w.iter_mut().take(n) {
        *v = normal(&mut r, sigma);
    }
    let mut ws = fwd.make_output_vec();
    fwd.process_with_scratch(&mut w, &mut ws, &mut scratch)
        .expect("sizes from the plan");
    let scale = 1.0 / len as f64;
    for (a, b) in ws.iter_mut().zip(&hs) {
        *a *= b * scale;
    }
    drop((hs, fwd));
    let inv = RealFftPlanner::<f64>::new().plan_fft_inverse(len);
    scratch.resize(inv.get_scratch_len(), Complex64::new(0.0, 0.0));
    // Real signals: the spectrum is real at 0 and len/2 but for round-off.
    ws[0].im = 0.0;
    if let Some(last) = ws.last_mut() {
        last.im = 0.0;
    }
    inv.process_with_scratch(&mut ws, &mut w, &mut scratch)
        .expect("real spectrum");
    drop((ws, scratch));
    w.truncate(n);
    w.shrink_to_fit();
    w
}

/// `n` rate samples at spacing `tau0_s` with the terms of `truth` (module
/// docs), seeded with `seed`.
pub fn rate_record(truth: &NoiseTruth, tau0_s: f64, n: usize, seed: u64) -> Vec<f64> {
    let mut y = if truth.b > 0.0 {
        flicker(n, truth.b, trial_seed(seed, 2))
    } else {
        vec![0.0; n]
    };
    if truth.n > 0.0 {
        let mut r = rng(trial_seed(seed, 1));
        let s = truth.n / tau0_s.sqrt();
        for v in y.iter_mut() {
            *v += normal(&mut r, s);
        }
    }
    if truth.q > 0.0 {
        let mut r = rng(trial_seed(seed, 0));
        let half = truth.q * 3f64.sqrt();
        let mut prev = r.random_range(-half..half);
        for v in y.iter_mut() {
            let e = r.random_range(-half..half);
            *v += (e - prev) / tau0_s;
            prev = e;
        }
    }
    if truth.k > 0.0 {
        let mut r = rng(trial_seed(seed, 3));
        let s = truth.k * tau0_s.sqrt();
        let mut walk = 0.0;
        for v in y.iter_mut() {
            walk += normal(&mut r, s);
            *v += walk;
        }
    }
    if truth.r != 0.0 {
        for (i, v) in y.iter_mut().enumerate() {
            *v += truth.r * i as f64 * tau0_s;
        }
    }
    y
}

/// Most samples per channel a simulation writes (10⁹).
pub const MAX_NOISE_SAMPLES: f64 = 1e9;

/// A simulated noise record: the terms in engineering units of one
/// quantity (the other quantity's terms must be 0), the sample rate, the
/// length, the channels (independent, seeded from `seed`) and the format:
/// the options of `incal simulate noise` ([`crate::procedures::Simulate`]),
/// every term 0 unless given.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct NoiseSim {
    /// Gyro (deg/s samples) or accel (g samples); default gyro.
    #[serde(default = "gyro")]
    pub quantity: QuantityKind,
    /// Gyro: angle random walk N, deg/√h.
    #[serde(default)]
    pub arw_deg_rth: f64,
    /// Gyro: bias instability B, deg/h.
    #[serde(default)]
    pub bias_instability_deg_h: f64,
    /// Gyro: rate random walk K, deg/h/√h.
    #[serde(default)]
    pub rrw_deg_h_rth: f64,
    /// Gyro: angle quantization Q, arcsec.
    #[serde(default)]
    pub quantization_arcsec: f64,
    /// Gyro: rate ramp R, deg/h².
    #[serde(default)]
    pub rate_ramp_deg_h2: f64,
    /// Accelerometer: velocity random walk N, µg/√Hz.
    #[serde(default)]
    pub vrw_ug_rthz: f64,
    /// Accelerometer: bias instability B, µg.
    #[serde(default)]
    pub bias_instability_ug: f64,
    /// Accelerometer: acceleration random walk K, µg/√s.
    #[serde(default)]
    pub accel_rw_ug_rts: f64,
    /// Accelerometer: velocity quantization Q, m/s.
    #[serde(default)]
    pub quantization_m_s: f64,
    /// Accelerometer: acceleration ramp R, µg/s.
    #[serde(default)]
    pub accel_ramp_ug_s: f64,
    /// Sample rate, Hz.
    pub rate_hz: f64,
    /// Record length, s.
    pub duration_s: f64,
    /// Channels, 1 to 64.
    #[serde(default = "one")]
    pub channels: usize,
    /// Random seed (channel c draws from `trial_seed(seed, c)`).
    pub seed: u64,
    /// Lines added to every channel: `a√2 sin(2πft + φ)`, rms amplitude
    /// `a` in the sample unit (deg/s or g), phase `φ` drawn from the
    /// channel's seed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tones: Vec<SimTone>,
    /// A first-order Gauss–Markov bias added to every channel: its
    /// standard deviation in the sample unit (deg/s or g; 0 = none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub gm_sigma: f64,
    /// Its correlation time, s.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub gm_tau_s: f64,
    /// How the record is written: CSV (`time_s,ch1,…`) or raw
    /// interleaved little-endian floats.
    #[serde(default)]
    pub format: Format,
}

/// A simulated line.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields)]
pub struct SimTone {
    /// Frequency, Hz (below the Nyquist frequency).
    pub frequency_hz: f64,
    /// rms amplitude, deg/s (gyro) or g (accel).
    pub amplitude_rms: f64,
}

/// Add `tones` to the rate samples `y` (spacing `tau0_s`), their phases
/// drawn from `seed`.
pub fn add_tones(y: &mut [f64], tones: &[SimTone], tau0_s: f64, seed: u64) {
    let mut r = rng(trial_seed(seed, 5));
    for t in tones {
        let phase = r.random_range(0.0..std::f64::consts::TAU);
        let (w, a) = (
            std::f64::consts::TAU * t.frequency_hz,
            t.amplitude_rms * 2f64.sqrt(),
        );
        for (i, v) in y.iter_mut().enumerate() {
            *v += a * (w * i as f64 * tau0_s + phase).sin();
        }
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// Add a stationary first-order Gauss–Markov bias of standard deviation
/// `sigma` and correlation time `tau_c_s` to `y` (spacing `tau0_s`):
/// `b₀ ~ N(0, σ²)`, `b_{k+1} = φ b_k + σ√(1 − φ²) w_k`, `φ = e^{−τ0/T}`,
/// drawn from `seed`'s own stream.
pub fn add_gauss_markov(y: &mut [f64], sigma: f64, tau_c_s: f64, tau0_s: f64, seed: u64) {
    if sigma <= 0.0 || tau_c_s <= 0.0 {
        return;
    }
    let mut r = rng(trial_seed(seed, 6));
    let phi = (-tau0_s / tau_c_s).exp();
    let q = sigma * (1.0 - phi * phi).sqrt();
    let mut b = normal(&mut r, sigma);
    for v in y.iter_mut() {
        *v += b;
        b = phi * b + normal(&mut r, q);
    }
}

fn gyro() -> QuantityKind {
    QuantityKind::Gyro
}

fn one() -> usize {
    1
}

impl crate::procedures::Simulate for super::Noise {
    type Options = NoiseSim;

    fn validate(o: &NoiseSim) -> Result<()> {
        o.validate()
    }

    fn simulate(o: &NoiseSim, out: &mut dyn std::io::Write) -> Result<()> {
        o.write(&o.simulate(), o.format, out)?;
        Ok(())
    }
}

impl NoiseSim {
    fn gyro_terms(&self) -> [(&'static str, f64); 5] {
        [
            ("arw_deg_rth", self.arw_deg_rth),
            ("bias_instability_deg_h", self.bias_instability_deg_h),
            ("rrw_deg_h_rth", self.rrw_deg_h_rth),
            ("quantization_arcsec", self.quantization_arcsec),
            ("rate_ramp_deg_h2", self.rate_ramp_deg_h2),
        ]
    }

    fn accel_terms(&self) -> [(&'static str, f64); 5] {
        [
            ("vrw_ug_rthz", self.vrw_ug_rthz),
            ("bias_instability_ug", self.bias_instability_ug),
            ("accel_rw_ug_rts", self.accel_rw_ug_rts),
            ("quantization_m_s", self.quantization_m_s),
            ("accel_ramp_ug_s", self.accel_ramp_ug_s),
        ]
    }

    /// Refuse what cannot be simulated: a generic quantity (no term
    /// units), a term of the other quantity, a negative or non-finite
    /// amplitude (the ramp may be negative), a rate that is not positive,
    /// fewer than 4 or more than [`MAX_NOISE_SAMPLES`] samples, and a
    /// channel count outside 1 to 64.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String, v: f64| Error::invalid(what, v);
        // One option, one meaning: a term of the other quantity is refused.
        let (mine, other, what) = match self.quantity {
            QuantityKind::Gyro => (self.gyro_terms(), self.accel_terms(), "gyro"),
            QuantityKind::Accel => (self.accel_terms(), self.gyro_terms(), "accel"),
            QuantityKind::Generic => {
                return crate::options::invalid(
                    "quantity",
                    "gyro or accel (a generic quantity has no term units to simulate)",
                )
            }
        };
        if let Some((n, _)) = other.iter().find(|(_, v)| *v != 0.0) {
            return crate::options::invalid(n, format!("not a term of quantity {what}"));
        }
        for (n, v) in mine.iter().take(4) {
            if !(v.is_finite() && *v >= 0.0) {
                return bad(format!("{n} (a non-negative number)"), *v);
            }
        }
        if !mine[4].1.is_finite() {
            return bad(format!("{} (a finite number)", mine[4].0), mine[4].1);
        }
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return bad("rate_hz (a positive number, Hz)".into(), self.rate_hz);
        }
        let n = self.duration_s * self.rate_hz;
        if !(n.is_finite() && (4.0..=MAX_NOISE_SAMPLES).contains(&n)) {
            return crate::options::invalid(
                "duration_s",
                format!("times `rate_hz` must give between 4 and 1e9 samples, got {n}"),
            );
        }
        for (i, t) in self.tones.iter().enumerate() {
            if !(t.frequency_hz > 0.0 && t.frequency_hz < 0.5 * self.rate_hz) {
                return crate::options::invalid(
                    &format!("tones[{i}].frequency_hz"),
                    format!(
                        "above 0 and below half the rate ({} Hz), got {}",
                        0.5 * self.rate_hz,
                        t.frequency_hz
                    ),
                );
            }
            if !(t.amplitude_rms.is_finite() && t.amplitude_rms >= 0.0) {
                return crate::options::invalid(
                    &format!("tones[{i}].amplitude_rms"),
                    format!("a non-negative number, got {}", t.amplitude_rms),
                );
            }
        }
        if !(self.gm_sigma.is_finite() && self.gm_sigma >= 0.0) {
            return bad("gm_sigma (a non-negative number)".into(), self.gm_sigma);
        }
        if self.gm_sigma > 0.0 && !(self.gm_tau_s.is_finite() && self.gm_tau_s > 0.0) {
            return bad(
                "gm_tau_s (a positive number of seconds with gm_sigma)".into(),
                self.gm_tau_s,
            );
        }
        if self.channels == 0 || self.channels > 64 {
            return bad("channels (1 to 64)".into(), self.channels as f64);
        }
        Ok(())
    }

    /// Samples per channel: `duration_s · rate_hz`, rounded.
    pub fn samples(&self) -> usize {
        (self.duration_s * self.rate_hz).round() as usize
    }

    /// Sample interval τ0 = 1/rate (s).
    pub fn tau0_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// The terms in the simulator's base: deg/s (gyro) or g (accel) with
    /// seconds.
    pub fn truth(&self) -> NoiseTruth {
        match self.quantity {
            // Gyro units to the deg/s base of the simulator.
            QuantityKind::Gyro => NoiseTruth {
                q: self.quantization_arcsec / 3600.0,
                n: self.arw_deg_rth / 60.0,
                b: self.bias_instability_deg_h / 3600.0,
                k: self.rrw_deg_h_rth / 216_000.0,
                r: self.rate_ramp_deg_h2 / (3600.0 * 3600.0),
            },
            // Accelerometer units to the g base (ug/sqrt(Hz) = 1e-6 g*sqrt(s)).
            _ => NoiseTruth {
                q: self.quantization_m_s / STANDARD_GRAVITY_M_S2,
                n: self.vrw_ug_rthz * 1e-6,
                b: self.bias_instability_ug * 1e-6,
                k: self.accel_rw_ug_rts * 1e-6,
                r: self.accel_ramp_ug_s * 1e-6,
            },
        }
    }

    /// The rate samples of every channel (channels on rayon's threads;
    /// deterministic for a given seed). Call [`NoiseSim::validate`] first.
    pub fn simulate(&self) -> Vec<Vec<f64>> {
        let truth = self.truth();
        let (tau0, n) = (self.tau0_s(), self.samples());
        (0..self.channels)
            .into_par_iter()
            .map(|c| {
                let seed = trial_seed(self.seed, c as u64);
                let mut y = rate_record(&truth, tau0, n, seed);
                add_tones(&mut y, &self.tones, tau0, seed);
                add_gauss_markov(&mut y, self.gm_sigma, self.gm_tau_s, tau0, seed);
                y
            })
            .collect()
    }

    /// Write simulated channels in `format` (CSV: [`write_csv`]; binary:
    /// [`write_binary`]).
    pub fn write<W: std::io::Write>(
        &self,
        chans: &[Vec<f64>],
        format: Format,
        out: W,
    ) -> std::io::Result<W> {
        match format {
            Format::Csv => write_csv(chans, self.tau0_s(), out),
            Format::F32le => write_binary(chans, false, out),
            Format::F64le => write_binary(chans, true, out),
        }
    }
}

/// Write channels as the CSV input of [`crate::procedures::noise`]:
/// `time_s,ch1,ch2,…`, `time_s = i·τ0`, every number in full (shortest
/// round trip).
pub fn write_csv<W: std::io::Write>(chans: &[Vec<f64>], tau0_s: f64, out: W) -> std::io::Result<W> {
    use incal_io::{Cell, CsvWriter};
    let names: Vec<String> = (1..=chans.len()).map(|c| format!("ch{c}")).collect();
    let mut header: Vec<&str> = vec!["time_s"];
    header.extend(names.iter().map(String::as_str));
    let mut w = CsvWriter::new(out, &header)?;
    let n = chans.first().map_or(0, Vec::len);
    for i in 0..n {
        w.cell(Cell::Num(i as f64 * tau0_s))?;
        for ch in chans {
            w.cell(Cell::Num(ch[i]))?;
        }
        w.end_row()?;
    }
    w.finish()
}

/// Write channels as raw interleaved little-endian floats (`f64` when
/// `f64le`, else `f32` rounded to nearest), one frame per sample.
pub fn write_binary<W: std::io::Write>(
    chans: &[Vec<f64>],
    f64le: bool,
    mut out: W,
) -> std::io::Result<W> {
    let n = chans.first().map_or(0, Vec::len);
    for i in 0..n {
        for ch in chans {
            if f64le {
                out.write_all(&ch[i].to_le_bytes())?;
            } else {
                out.write_all(&(ch[i] as f32).to_le_bytes())?;
            }
        }
    }
    out.flush()?;
    Ok(out)
}
