//! Precision-centrifuge simulator: a truth instrument, a true rig (R+, R−,
//! tilt, latitude, sense) and a plan give observations in the input format
//! of [`crate::procedures::centrifuge`].
//!
//! For every position (in plan order) and every rate (in plan order; 0 =
//! at rest), `samples` outputs `E = K1·(model at the specific force of
//! [`Centrifuge::specific_force`]) + n`, `n ~ N(0, σ_n²)`, are drawn. The
//! specific force includes the ECM radius and alignment error of each
//! position, the IA tilt and the Earth-rate term.

use crate::error::{Error, Result};
use crate::models::AccelerometerModel;
use crate::options::invalid;
use crate::procedures::centrifuge::Observation;
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};
use crate::sim::{normal, rng};
use crate::units::arcsec_to_rad;

/// Configuration of a simulated centrifuge test.
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeSim {
    /// True instrument.
    pub truth: AccelerometerModel,
    /// True rig and mounting.
    pub rig: Centrifuge,
    /// Positions, in test order.
    pub positions: Vec<Position>,
    /// Table rates (rad/s), in test order; include 0 for the at-rest rows.
    pub rates_rad_s: Vec<f64>,
    /// Samples per point (≥ 1).
    pub samples: usize,
    /// Output noise σ of one sample (output units).
    pub noise: f64,
    /// Random seed.
    pub seed: u64,
}

impl CentrifugeSim {
    /// Refuse a configuration that cannot be simulated: no samples, a
    /// negative or non-finite noise, a rate that is negative or not finite,
    /// more than [`crate::sim::MAX_SIM_ROWS`] rows, an invalid truth, or a
    /// truth and rig whose output is not finite at some point.
    pub fn validate(&self) -> Result<()> {
        if self.samples == 0 {
            return bad("samples (at least 1 per point)", "0".into());
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return bad("noise (a non-negative number)", self.noise.to_string());
        }
        if let Some(w) = self
            .rates_rad_s
            .iter()
            .find(|w| !(w.is_finite() && **w >= 0.0))
        {
            return bad("rate (rad/s, a non-negative number)", w.to_string());
        }
        crate::sim::check_rows(&[
            ("positions", self.positions.len() as f64),
            ("levels_g", self.rates_rad_s.len() as f64),
            ("samples", self.samples as f64),
        ])?;
        self.truth.validate()?;
        for pos in &self.positions {
            for &w in &self.rates_rad_s {
                let e = self.truth.output(&self.rig.specific_force(pos, w));
                if !e.is_finite() {
                    return bad(
                        "truth and rig (the output is not finite; choose physical values)",
                        format!(
                            "at {}:{} deg, polarity {}, {w} rad/s",
                            pos.plane.name(),
                            pos.phi_rad.to_degrees(),
                            pos.polarity
                        ),
                    );
                }
            }
        }
        Ok(())
    }
}

fn bad<T>(what: &str, value: String) -> Result<T> {
    Error::invalid(what, value)
}

/// The rig and the test plan of a simulated or planned centrifuge test as
/// a front end gives them (snake_case keys in a plan document's
/// `options`): the true ECM radii `r_plus_m`, `r_minus_m` (m) with IA
/// radial, the nominal radius `radius_m` (m) that turns the nominal
/// centripetal inputs `levels_g` (g) into rates `ω = sqrt(level·g_L/R)`,
/// the IA tilt `tilt_arcsec`, `latitude_deg` (north positive),
/// `gravity_m_s2` (g_L), the sense of rotation, the fixture `positions`
/// (`plane:phi_deg`, both polarities of each unless `single_polarity`),
/// `samples` per point and the output `noise` σ of one sample (output
/// units). Every key has the command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct RigPlan {
    /// True ECM radius with IA radial, polarity + (m).
    #[serde(default = "d_r_plus")]
    pub r_plus_m: f64,
    /// True ECM radius with IA radial, polarity − (m).
    #[serde(default = "d_r_minus")]
    pub r_minus_m: f64,
    /// Nominal radius used to turn `levels_g` into rates (m).
    #[serde(default = "d_radius")]
    pub radius_m: f64,
    /// IA tilt above the horizontal plane (arcsec).
    #[serde(default = "d_tilt")]
    pub tilt_arcsec: f64,
    /// Latitude (deg, north positive).
    #[serde(default = "d_latitude")]
    pub latitude_deg: f64,
    /// Local gravity g_L (m/s²).
    #[serde(default = "d_gravity")]
    pub gravity_m_s2: f64,
    /// The table spins opposite to Earth's sense.
    #[serde(default)]
    pub opposite_sense: bool,
    /// Positions as `plane:phi_deg` (e.g. `ip:45`), in test order.
    #[serde(default = "d_positions")]
    pub positions: Vec<String>,
    /// Only polarity +1 at each position.
    #[serde(default)]
    pub single_polarity: bool,
    /// Nominal centripetal inputs (g) at `radius_m`; 0 = at rest.
    #[serde(default = "d_levels")]
    pub levels_g: Vec<f64>,
    /// Samples per point (≥ 1).
    #[serde(default = "d_samples")]
    pub samples: usize,
    /// Output noise σ of one sample (output units, ≥ 0).
    #[serde(default = "d_noise")]
    pub noise: f64,
}

fn d_r_plus() -> f64 {
    0.714775
}
fn d_r_minus() -> f64 {
    0.705794
}
fn d_radius() -> f64 {
    0.71
}
fn d_tilt() -> f64 {
    60.0
}
fn d_latitude() -> f64 {
    39.9
}
fn d_gravity() -> f64 {
    crate::units::STANDARD_GRAVITY_M_S2
}
fn d_positions() -> Vec<String> {
    DEFAULT_POSITIONS.iter().map(|p| p.to_string()).collect()
}
fn d_levels() -> Vec<f64> {
    DEFAULT_LEVELS_G.to_vec()
}
fn d_samples() -> usize {
    5
}
fn d_noise() -> f64 {
    2e-6
}

/// The default positions (He & Yin 2017's plan, [`standard_positions`]).
pub const DEFAULT_POSITIONS: [&str; 6] = ["ip:0", "ip:90", "io:90", "ip:45", "io:45", "po:45"];
/// The default nominal centripetal inputs (g).
pub const DEFAULT_LEVELS_G: [f64; 10] = [0.0, 1.0, 2.0, 4.0, 7.0, 10.0, 14.0, 18.0, 22.0, 25.0];

impl Default for RigPlan {
    /// The command line's defaults.
    fn default() -> Self {
        RigPlan {
            r_plus_m: d_r_plus(),
            r_minus_m: d_r_minus(),
            radius_m: d_radius(),
            tilt_arcsec: d_tilt(),
            latitude_deg: d_latitude(),
            gravity_m_s2: d_gravity(),
            opposite_sense: false,
            positions: d_positions(),
            single_polarity: false,
            levels_g: d_levels(),
            samples: d_samples(),
            noise: d_noise(),
        }
    }
}

/// The simulated instrument of a centrifuge test or plan, in engineering
/// units (g units; K1 in output/g; misalignments in arcsec), each with the
/// command line's default (the He & Yin 2017 instrument of the demo).
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
pub struct CentrifugeTruth {
    /// Bias K0 (g).
    #[serde(default = "t_k0")]
    pub k0: f64,
    /// Scale factor K1 (output/g).
    #[serde(default = "t_k1")]
    pub k1: f64,
    /// K2 (g/g²).
    #[serde(default = "t_k2")]
    pub k2: f64,
    /// K3 (g/g³).
    #[serde(default = "t_k3")]
    pub k3: f64,
    /// Misalignment δo (arcsec).
    #[serde(default = "t_delta_o")]
    pub delta_o_arcsec: f64,
    /// Misalignment δp (arcsec).
    #[serde(default = "t_delta_p")]
    pub delta_p_arcsec: f64,
    /// Cross-coupling K_ip (g/g²).
    #[serde(default = "t_k_ip")]
    pub k_ip: f64,
    /// Cross-coupling K_io (g/g²).
    #[serde(default = "t_k_io")]
    pub k_io: f64,
    /// Cross-coupling K_po (g/g²).
    #[serde(default = "t_k_po")]
    pub k_po: f64,
    /// Cross-axis nonlinearity K_pp (g/g²).
    #[serde(default = "t_k_pp")]
    pub k_pp: f64,
    /// Cross-axis nonlinearity K_oo (g/g²).
    #[serde(default = "t_k_oo")]
    pub k_oo: f64,
    /// Odd quadratic K_oq (g/g²).
    #[serde(default = "t_k_oq")]
    pub k_oq: f64,
}

fn t_k0() -> f64 {
    1.2e-4
}
fn t_k1() -> f64 {
    1.3
}
fn t_k2() -> f64 {
    3.9e-6
}
fn t_k3() -> f64 {
    5e-9
}
fn t_delta_o() -> f64 {
    40.0
}
fn t_delta_p() -> f64 {
    -20.0
}
fn t_k_ip() -> f64 {
    7e-6
}
fn t_k_io() -> f64 {
    2e-6
}
fn t_k_po() -> f64 {
    -1e-6
}
fn t_k_pp() -> f64 {
    4.6e-7
}
fn t_k_oo() -> f64 {
    -3e-7
}
fn t_k_oq() -> f64 {
    5e-7
}

impl Default for CentrifugeTruth {
    /// The command line's defaults.
    fn default() -> Self {
        CentrifugeTruth {
            k0: t_k0(),
            k1: t_k1(),
            k2: t_k2(),
            k3: t_k3(),
            delta_o_arcsec: t_delta_o(),
            delta_p_arcsec: t_delta_p(),
            k_ip: t_k_ip(),
            k_io: t_k_io(),
            k_po: t_k_po(),
            k_pp: t_k_pp(),
            k_oo: t_k_oo(),
            k_oq: t_k_oq(),
        }
    }
}

impl CentrifugeTruth {
    /// The accelerometer model (misalignments from arcsec to rad); a value
    /// that is not finite, or K1 = 0, is [`Error::InvalidOption`] naming it.
    pub fn model(&self) -> Result<AccelerometerModel> {
        for (key, v) in [
            ("k0", self.k0),
            ("k1", self.k1),
            ("k2", self.k2),
            ("k3", self.k3),
            ("delta_o_arcsec", self.delta_o_arcsec),
            ("delta_p_arcsec", self.delta_p_arcsec),
            ("k_ip", self.k_ip),
            ("k_io", self.k_io),
            ("k_po", self.k_po),
            ("k_pp", self.k_pp),
            ("k_oo", self.k_oo),
            ("k_oq", self.k_oq),
        ] {
            if !v.is_finite() {
                return invalid(
                    key,
                    format!("truth model: must be a finite number, got {v}"),
                );
            }
        }
        if self.k1 == 0.0 {
            return invalid("k1", "truth model: the scale factor K1 must not be 0");
        }
        let m = AccelerometerModel {
            k0_g: self.k0,
            k1_out_per_g: self.k1,
            k2: self.k2,
            k3: self.k3,
            delta_o_rad: arcsec_to_rad(self.delta_o_arcsec),
            delta_p_rad: arcsec_to_rad(self.delta_p_arcsec),
            k_ip: self.k_ip,
            k_io: self.k_io,
            k_po: self.k_po,
            k_pp: self.k_pp,
            k_oo: self.k_oo,
            k_oq: self.k_oq,
        };
        m.validate()?;
        Ok(m)
    }
}

/// Options of the centrifuge simulator ([`crate::procedures::Simulate`]
/// for [`super::CentrifugeTest`]): the truth, the rig and plan, and the
/// seed (same seed, same file); every key has the command line's default.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
pub struct CentrifugeSimOptions {
    /// The simulated instrument.
    #[serde(flatten)]
    pub truth: CentrifugeTruth,
    /// The rig and the plan.
    #[serde(flatten)]
    pub rig: RigPlan,
    /// Random seed (default 1).
    #[serde(default = "d_seed")]
    pub seed: u64,
}

fn d_seed() -> u64 {
    1
}

impl Default for CentrifugeSimOptions {
    /// The command line's defaults (seed 1).
    fn default() -> Self {
        CentrifugeSimOptions {
            truth: CentrifugeTruth::default(),
            rig: RigPlan::default(),
            seed: d_seed(),
        }
    }
}

impl crate::procedures::Simulate for super::CentrifugeTest {
    type Options = CentrifugeSimOptions;

    fn validate(o: &CentrifugeSimOptions) -> Result<()> {
        o.rig.simulation(o.truth.model()?, o.seed).map(|_| ())
    }

    /// The recording of `incal simulate centrifuge` (the input CSV of the
    /// reduction, [`super::input::write`]); a value the writer refuses (not
    /// finite) is an option beyond what the simulator can represent.
    fn simulate(o: &CentrifugeSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        let cfg = o.rig.simulation(o.truth.model()?, o.seed)?;
        super::input::write(&simulate(&cfg), out)?;
        Ok(())
    }
}

/// Largest radius or local gravity a rig may have (m, m/s²).
const MAX_RIG_VALUE: f64 = 100.0;
/// Largest IA tilt (arcsec, 10°).
const MAX_TILT_ARCSEC: f64 = 36000.0;
/// Largest nominal centripetal input (g).
const MAX_LEVEL_G: f64 = 1000.0;

impl RigPlan {
    /// Refuse a rig or plan no centrifuge has: no samples, a negative noise,
    /// a radius or gravity that is not positive or above 100, a tilt above
    /// 10°, a latitude beyond ±90°, a level that is negative or above
    /// 1000 g, a position that is not `plane:phi_deg`.
    pub fn validate(&self) -> Result<()> {
        if self.samples == 0 {
            return invalid("samples", "at least 1 per point, got 0");
        }
        if !(self.noise.is_finite() && self.noise >= 0.0) {
            return invalid(
                "noise",
                format!("must be a non-negative number, got {}", self.noise),
            );
        }
        for (name, v) in [
            ("r_plus_m", self.r_plus_m),
            ("r_minus_m", self.r_minus_m),
            ("radius_m", self.radius_m),
            ("gravity_m_s2", self.gravity_m_s2),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= MAX_RIG_VALUE) {
                return invalid(
                    name,
                    format!("must be a positive number at most {MAX_RIG_VALUE}, got {v}"),
                );
            }
        }
        if !(self.tilt_arcsec.is_finite() && self.tilt_arcsec.abs() <= MAX_TILT_ARCSEC) {
            return invalid(
                "tilt_arcsec",
                format!(
                    "must be at most 36000 (10 deg) in magnitude, got {}",
                    self.tilt_arcsec
                ),
            );
        }
        crate::options::check_latitude_deg(self.latitude_deg)?;
        if let Some(l) = self
            .levels_g
            .iter()
            .find(|l| !(l.is_finite() && (0.0..=MAX_LEVEL_G).contains(*l)))
        {
            return invalid(
                "levels_g",
                format!("a level must be non-negative and at most 1000 g (beyond any centrifuge), got {l}"),
            );
        }
        self.fixture_positions()?;
        Ok(())
    }

    /// The fixture positions of the plan: each `plane:phi_deg` in both
    /// polarities (+1 then −1), or +1 only with `single_polarity`.
    pub fn fixture_positions(&self) -> Result<Vec<Position>> {
        let mut out = Vec::new();
        for item in &self.positions {
            let bad = |why: &str| invalid("positions", format!("'{item}' {why}"));
            let Some((p, d)) = item.split_once(':') else {
                return bad("is not plane:phi_deg");
            };
            let plane = match Plane::parse(p) {
                Ok(plane) => plane,
                Err(e) => return invalid("positions", e.to_string()),
            };
            let Some(deg) = d.trim().parse().ok().filter(|x: &f64| x.is_finite()) else {
                return bad("needs an angle in deg after the plane");
            };
            // The same position twice adds rows but no information the
            // plan claims: a typo for another angle.
            let key = |x: f64| (x.rem_euclid(360.0) * 1e9).round() as i64;
            if out
                .iter()
                .any(|q: &Position| q.plane == plane && key(q.phi_rad.to_degrees()) == key(deg))
            {
                return bad("repeats a position (each plane:phi_deg once)");
            }
            let pols: &[i8] = if self.single_polarity { &[1] } else { &[1, -1] };
            for &polarity in pols {
                out.push(Position {
                    plane,
                    phi_rad: deg.to_radians(),
                    polarity,
                });
            }
        }
        Ok(out)
    }

    /// The simulated test of `truth` on this rig and plan, seeded with
    /// `seed`, checked ([`RigPlan::validate`], [`CentrifugeSim::validate`]).
    pub fn simulation(&self, truth: AccelerometerModel, seed: u64) -> Result<CentrifugeSim> {
        self.validate()?;
        let cfg = CentrifugeSim {
            truth,
            rig: Centrifuge {
                r_plus_m: self.r_plus_m,
                r_minus_m: self.r_minus_m,
                latitude_rad: self.latitude_deg.to_radians(),
                g_local_m_s2: self.gravity_m_s2,
                opposite_sense: self.opposite_sense,
                tilt_rad: arcsec_to_rad(self.tilt_arcsec),
            },
            positions: self.fixture_positions()?,
            rates_rad_s: rates_for_levels(&self.levels_g, self.radius_m, self.gravity_m_s2),
            samples: self.samples,
            noise: self.noise,
            seed,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

/// The standard plan of He & Yin 2017: IA radial (`ip,0`), PA radial (`ip,90`),
/// OA radial (`io,90`) and the 45° cross positions `ip,45`, `io,45`,
/// `po,45`, each in both polarities.
pub fn standard_positions() -> Vec<Position> {
    let list = [
        (Plane::Ip, 0.0),
        (Plane::Ip, 90.0),
        (Plane::Io, 90.0),
        (Plane::Ip, 45.0),
        (Plane::Io, 45.0),
        (Plane::Po, 45.0),
    ];
    let mut out = Vec::new();
    for (plane, deg) in list {
        for polarity in [1, -1] {
            out.push(Position {
                plane,
                phi_rad: f64::to_radians(deg),
                polarity,
            });
        }
    }
    out
}

/// Rates (rad/s) giving the nominal inputs `levels_g` (g) at radius `r_m`
/// with local gravity `g_m_s2`: `ω = sqrt(level·g/R)` (the Earth-rate term
/// is left to the procedure).
pub fn rates_for_levels(levels_g: &[f64], r_m: f64, g_m_s2: f64) -> Vec<f64> {
    levels_g
        .iter()
        .map(|l| (l.max(0.0) * g_m_s2 / r_m).sqrt())
        .collect()
}

/// Simulate the observations (deterministic for a given seed).
pub fn simulate(cfg: &CentrifugeSim) -> Vec<Observation> {
    let mut r = rng(cfg.seed);
    let mut out = Vec::with_capacity(cfg.positions.len() * cfg.rates_rad_s.len() * cfg.samples);
    for pos in &cfg.positions {
        for &w in &cfg.rates_rad_s {
            let e0 = cfg.truth.output(&cfg.rig.specific_force(pos, w));
            for _ in 0..cfg.samples.max(1) {
                out.push(Observation {
                    position: *pos,
                    omega_rad_s: w,
                    output: e0 + normal(&mut r, cfg.noise),
                });
            }
        }
    }
    out
}

/// The plan of a centrifuge test: the reduction itself run on noise-free
/// outputs with a deterministic scatter of exactly `cfg.noise` (sample
/// standard deviation) at every point, the output noise known to the fits.
/// The u it reports are the predicted standard uncertainties of the plan
/// (every fit's u scales with the noise; the static radius and tilt take
/// the scatter of the samples, which is exactly σ here). Needs at least 2
/// samples per point.
pub fn plan(
    cfg: &CentrifugeSim,
    opts: &crate::procedures::centrifuge::CentrifugeOptions,
) -> crate::error::Result<crate::procedures::centrifuge::CentrifugeResult> {
    let n = cfg.samples;
    if n < 2 || !(cfg.noise.is_finite() && cfg.noise > 0.0) {
        return Err(crate::error::Error::InvalidValue {
            what: "plan: samples per point (>= 2) and noise (> 0)".into(),
            value: format!("{n}, {}", cfg.noise),
        });
    }
    // z_i: zero mean, sample standard deviation exactly 1.
    let c = (n as f64 - 1.0) / 2.0;
    let ss: f64 = (0..n).map(|i| (i as f64 - c).powi(2)).sum();
    let scale = ((n as f64 - 1.0) / ss).sqrt();
    let mut quiet = cfg.clone();
    quiet.noise = 0.0;
    let mut obs = simulate(&quiet);
    for (k, o) in obs.iter_mut().enumerate() {
        o.output += cfg.noise * (k % n) as f64 * scale - cfg.noise * c * scale;
    }
    let mut o = opts.clone();
    o.noise = crate::estimation::Noise::Known { sigma: cfg.noise };
    crate::procedures::centrifuge::calibrate(&obs, &o)
}
