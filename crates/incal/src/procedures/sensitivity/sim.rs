//! Sensitivity session simulator: runs of `run_s` seconds, `gap_s`
//! apart (the noise runs on through the gaps, which are not written), at
//! the levels of the stimulus, with the instrument's output
//!
//! `y = bias + effect(stimulus) + k (1 + δ) u + w + f + r`
//!
//! in reporting units (µg or °/h; the file in `unit`): `effect` the
//! vibration rectification `(vrc cos²θ + vibropendulous sin θ cos θ +
//! vrc_pendulous sin²θ) g² + vib_linear g`, the magnetic sensitivity
//! `M B` (one output, or three with the 3×3 matrix `magnetic`), or the
//! sum of the shifts of the shocks taken so far; `k` the scale factor
//! (1 output unit per input unit) and `δ` the shocks' scale-factor
//! shifts (ppm) when `inputs` are given; `w` white noise (`noise`, per
//! sample), `f` flicker with bias instability `flicker` (Kasdin's
//! filter, [`crate::procedures::noise::sim::flicker`]) and `r` a random
//! walk (`random_walk`, per √s). Runs in the order of the levels
//! (`interleave`: a run at zero between two levels). Deterministic for a
//! seed.

use super::input::{Record, Run, Stimulus};
use super::{Kind, SensitivityOptions, Sensor};
use crate::error::Result;
use crate::options::{check_range, invalid};
use crate::sim::{normal, rng, trial_seed};

/// Options of `incal simulate sensitivity` (the truth in the keys).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensitivitySimOptions {
    /// The stimulus (default vibration).
    #[serde(default = "vibration")]
    pub kind: Kind,
    /// The instrument (default accel).
    #[serde(default)]
    pub sensor: Sensor,
    /// Levels, comma-separated: vibration g rms (default 0,2,4,6,8),
    /// field mT on each axis in turn (default -1,0,1), shock peaks g
    /// (default 100,200).
    #[serde(default)]
    pub levels: Option<String>,
    /// Vibration directions, degrees from the input axis toward the
    /// pendulous axis, comma-separated (default 0; `0,45,-45` for the
    /// vibropendulous term).
    #[serde(default = "zero_text")]
    pub angles_deg: String,
    /// Vibration frequency (Hz; default 100).
    #[serde(default = "hundred")]
    pub freq_hz: f64,
    /// Field axes the coil turns to, comma-separated (default x,y,z).
    #[serde(default = "xyz")]
    pub field_axes: String,
    /// Magnetic outputs: 1 (`output`) or 3 (`output_x`, `output_y`,
    /// `output_z`; default 3).
    #[serde(default = "three")]
    pub outputs: usize,
    /// A run at zero between two levels (default false: ascending).
    #[serde(default)]
    pub interleave: bool,
    /// Runs per level (default 1).
    #[serde(default = "one")]
    pub repeats: usize,
    /// Applied inputs (g or °/s), comma-separated: every level is run at
    /// each (default none: no `input` column).
    #[serde(default)]
    pub inputs: Option<String>,
    /// Rectification along the input axis (reporting unit/g²; default 30).
    #[serde(default = "thirty")]
    pub vrc: f64,
    /// Vibropendulous coefficient (reporting unit/g²; default 10).
    #[serde(default = "ten")]
    pub vibropendulous: f64,
    /// Rectification along the pendulous axis (reporting unit/g²;
    /// default 5).
    #[serde(default = "five")]
    pub vrc_pendulous: f64,
    /// Linear term in g (reporting unit/g; default 0).
    #[serde(default)]
    pub vib_linear: f64,
    /// Magnetic sensitivity, output i per field j, row-major, nine
    /// comma-separated values (reporting unit/mT).
    #[serde(default = "matrix")]
    pub magnetic: String,
    /// Bias shift of each shock (reporting units), comma-separated
    /// (default 20,-35).
    #[serde(default = "shifts")]
    pub shifts: String,
    /// Scale-factor shift of each shock (ppm), comma-separated (default
    /// none: 0).
    #[serde(default)]
    pub sf_shifts_ppm: Option<String>,
    /// Bias (reporting units; default 100).
    #[serde(default = "hundred")]
    pub bias: f64,
    /// White noise per sample (reporting units; default 50 µg or 36 °/h).
    #[serde(default)]
    pub noise: Option<f64>,
    /// Flicker: bias instability (reporting units; default 2 µg or
    /// 0.5 °/h).
    #[serde(default)]
    pub flicker: Option<f64>,
    /// Random walk (reporting units/√s; default 0).
    #[serde(default)]
    pub random_walk: f64,
    /// Seconds per run (default 30).
    #[serde(default = "thirty")]
    pub run_s: f64,
    /// Seconds between runs (default 10).
    #[serde(default = "ten")]
    pub gap_s: f64,
    /// Sampling rate (Hz; default 100).
    #[serde(default = "hundred")]
    pub rate_hz: f64,
    /// The output file's unit (default g or deg_s).
    #[serde(default)]
    pub unit: Option<String>,
    /// Seed (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

fn vibration() -> Kind {
    Kind::Vibration
}
fn zero_text() -> String {
    "0".into()
}
pub(crate) fn hundred() -> f64 {
    100.0
}
pub(crate) fn xyz() -> String {
    "x,y,z".into()
}
pub(crate) fn three() -> usize {
    3
}
pub(crate) fn one() -> usize {
    1
}
pub(crate) fn thirty() -> f64 {
    30.0
}
pub(crate) fn ten() -> f64 {
    10.0
}
fn five() -> f64 {
    5.0
}
fn matrix() -> String {
    "5,0.5,-0.3,0.2,4,0.6,-0.4,0.1,6".into()
}
fn shifts() -> String {
    "20,-35".into()
}
pub(crate) fn seed_one() -> u64 {
    1
}

/// A comma-separated list of numbers.
pub fn numbers(key: &str, s: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|p| {
            let p = p.trim();
            p.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && v.abs() <= 1e9)
                .map_or_else(
                    || {
                        invalid(
                            key,
                            format!("'{}' is not a list of numbers", incal_io::clip(s)),
                        )
                    },
                    Ok,
                )
        })
        .collect()
}

/// A planned run: label, stimulus, input, start (s), samples.
#[derive(Debug, Clone, PartialEq)]
pub struct Planned {
    /// Label.
    pub label: String,
    /// Stimulus.
    pub stimulus: Stimulus,
    /// Input.
    pub input: Option<f64>,
    /// Start (s).
    pub start_s: f64,
    /// Samples.
    pub n: usize,
    /// Shocks taken before it.
    pub phase: usize,
}

impl SensitivitySimOptions {
    /// The kind (auto is vibration).
    pub fn kind(&self) -> Kind {
        if self.kind == Kind::Auto {
            Kind::Vibration
        } else {
            self.kind
        }
    }

    /// The levels.
    pub fn levels(&self) -> Result<Vec<f64>> {
        let default = match self.kind() {
            Kind::Magnetic => "-1,0,1",
            Kind::Shock => "100,200",
            _ => "0,2,4,6,8",
        };
        numbers("levels", self.levels.as_deref().unwrap_or(default))
    }

    /// White noise per sample and flicker (reporting units).
    pub fn noise_terms(&self) -> (f64, f64) {
        let (w, f) = match self.sensor {
            Sensor::Accel => (50.0, 2.0),
            Sensor::Gyro => (36.0, 0.5),
        };
        (self.noise.unwrap_or(w), self.flicker.unwrap_or(f))
    }

    /// The reduction's options for what this writes.
    pub fn reduction(&self) -> SensitivityOptions {
        SensitivityOptions {
            sensor: self.sensor,
            unit: self.unit.clone(),
            output_columns: self.column_names().join(","),
            ..SensitivityOptions::default()
        }
    }

    fn column_names(&self) -> Vec<String> {
        if self.kind() == Kind::Magnetic && self.outputs == 3 {
            ["output_x", "output_y", "output_z"]
                .map(String::from)
                .to_vec()
        } else {
            vec!["output".into()]
        }
    }

    fn field_axes(&self) -> Result<Vec<usize>> {
        let mut out = Vec::new();
        for p in self.field_axes.split(',').map(str::trim) {
            let k = match p {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                _ => {
                    return invalid(
                        "field_axes",
                        format!(
                            "'{}' is not a list of x, y, z",
                            incal_io::clip(&self.field_axes)
                        ),
                    )
                }
            };
            if out.contains(&k) {
                return invalid("field_axes", "an axis twice");
            }
            out.push(k);
        }
        Ok(out)
    }

    /// Which field axes the session's records carry (none unless
    /// magnetic).
    pub fn field_flags(&self) -> Result<[bool; 3]> {
        let mut flags = [false; 3];
        for j in self.field_axes()? {
            flags[j] = self.kind() == Kind::Magnetic;
        }
        Ok(flags)
    }

    /// Every range check; the planned runs.
    pub fn plan_runs(&self) -> Result<Vec<Planned>> {
        check_range("rate_hz", self.rate_hz, 1e-3, 1e6, "Hz")?;
        check_range("run_s", self.run_s, 0.0, 1e6, "s")?;
        check_range("gap_s", self.gap_s, 0.0, 1e6, "s")?;
        check_range("freq_hz", self.freq_hz, 0.0, 1e6, "Hz")?;
        check_range("random_walk", self.random_walk, 0.0, 1e9, "")?;
        let (w, f) = self.noise_terms();
        check_range("noise", w, 0.0, 1e12, "")?;
        check_range("flicker", f, 0.0, 1e12, "")?;
        if !(1..=100).contains(&self.repeats) {
            return invalid("repeats", "from 1 to 100");
        }
        if self.outputs != 1 && self.outputs != 3 {
            return invalid("outputs", "1 or 3");
        }
        self.reduction().validate()?;
        let n = (self.run_s * self.rate_hz).round() as usize;
        if n < super::MIN_RUN_SAMPLES {
            return invalid(
                "run_s",
                format!("{n} samples a run: at least {}", super::MIN_RUN_SAMPLES),
            );
        }
        let inputs: Vec<Option<f64>> = match &self.inputs {
            Some(s) => numbers("inputs", s)?.into_iter().map(Some).collect(),
            None => vec![None],
        };
        let levels = self.levels()?;
        let mut stims: Vec<(Stimulus, usize)> = Vec::new();
        match self.kind() {
            Kind::Magnetic => {
                for j in self.field_axes()? {
                    for &l in &levels {
                        let mut s = Stimulus::default();
                        s.field_mt[j] = l;
                        stims.push((s, 0));
                    }
                }
            }
            Kind::Shock => {
                stims.push((Stimulus::default(), 0));
                if levels.windows(2).any(|w| w[0] == w[1]) {
                    return invalid(
                        "levels",
                        "two shocks in a row at one level: the reduction tells shocks apart by shock_g changing",
                    );
                }
                for (p, &l) in levels.iter().enumerate() {
                    check_range("levels", l, 1e-9, 1e7, "g")?;
                    stims.push((
                        Stimulus {
                            shock_g: l,
                            ..Stimulus::default()
                        },
                        p + 1,
                    ));
                }
            }
            _ => {
                for a in numbers("angles_deg", &self.angles_deg)? {
                    for &l in &levels {
                        check_range("levels", l, 0.0, 1e4, "g")?;
                        stims.push((
                            Stimulus {
                                vib_g_rms: l,
                                vib_freq_hz: Some(self.freq_hz),
                                vib_angle_deg: a,
                                ..Stimulus::default()
                            },
                            0,
                        ));
                    }
                }
            }
        }
        if self.interleave && self.kind() != Kind::Shock {
            let zero = Stimulus {
                vib_freq_hz: stims[0].0.vib_freq_hz,
                ..Stimulus::default()
            };
            stims = stims
                .into_iter()
                .flat_map(|s| [(zero, 0), s])
                .chain([(zero, 0)])
                .collect();
        }
        let count = stims.len() * self.repeats * inputs.len();
        if count > super::MAX_RUNS || count as f64 * n as f64 > 5e7 {
            return invalid(
                "levels",
                format!(
                    "{count} runs of {n} samples: at most {} runs and 5e7 samples in all",
                    super::MAX_RUNS
                ),
            );
        }
        let step = self.gap_s + n as f64 / self.rate_hz;
        let mut out = Vec::new();
        for (s, phase) in stims {
            for _ in 0..self.repeats {
                for &input in &inputs {
                    let k = out.len();
                    out.push(Planned {
                        label: format!("r{}", k + 1),
                        stimulus: s,
                        input,
                        start_s: self.gap_s + k as f64 * step,
                        n,
                        phase,
                    });
                }
            }
        }
        Ok(out)
    }

    fn matrix(&self) -> Result<Vec<f64>> {
        let m = numbers("magnetic", &self.magnetic)?;
        if m.len() != 9 {
            return invalid("magnetic", "nine values, row-major");
        }
        Ok(m)
    }

    fn shock_shifts(&self, shocks: usize) -> Result<(Vec<f64>, Vec<f64>)> {
        let b = numbers("shifts", &self.shifts)?;
        let s = match &self.sf_shifts_ppm {
            Some(t) => numbers("sf_shifts_ppm", t)?,
            None => vec![0.0; shocks],
        };
        if b.len() != shocks || s.len() != shocks {
            return invalid("shifts", format!("one shift per shock: {shocks} shocks"));
        }
        Ok((b, s))
    }

    /// The output's effect of a run's stimulus, per output column
    /// (reporting units), and the scale-factor multiplier.
    fn effect(&self, r: &Planned) -> Result<(Vec<f64>, f64)> {
        let s = &r.stimulus;
        Ok(match self.kind() {
            Kind::Magnetic => {
                let m = self.matrix()?;
                let rows = self.column_names().len();
                (
                    (0..rows)
                        .map(|i| (0..3).map(|j| m[3 * i + j] * s.field_mt[j]).sum())
                        .collect(),
                    1.0,
                )
            }
            Kind::Shock => {
                let shocks = self.levels()?.len();
                let (b, sf) = self.shock_shifts(shocks)?;
                let db: f64 = b[..r.phase].iter().sum();
                let ds: f64 = sf[..r.phase].iter().sum();
                (vec![db], 1.0 + 1e-6 * ds)
            }
            _ => {
                let (g, t) = (s.vib_g_rms, s.vib_angle_deg.to_radians());
                let k = self.vrc * t.cos().powi(2)
                    + self.vibropendulous * t.sin() * t.cos()
                    + self.vrc_pendulous * t.sin().powi(2);
                (vec![k * g * g + self.vib_linear * g], 1.0)
            }
        })
    }

    /// The session (samples in reporting units, as the reduction reads
    /// them).
    pub fn record(&self) -> Result<Record> {
        let planned = self.plan_runs()?;
        let k0 = self.sensor.unit_scale_factor();
        let dt = 1.0 / self.rate_hz;
        let cols = self.column_names();
        let last = planned.last().map_or(0.0, |p| p.start_s + p.n as f64 * dt);
        let total = (last * self.rate_hz).round() as usize + 1;
        let (w, fl) = self.noise_terms();
        let mut runs = Vec::with_capacity(planned.len());
        let mut series: Vec<Vec<f64>> = Vec::new();
        for c in 0..cols.len() {
            let seed = trial_seed(self.seed, c as u64);
            let mut y = crate::procedures::noise::sim::flicker(total, fl, trial_seed(seed, 1));
            let mut r = rng(trial_seed(seed, 2));
            let mut walk = 0.0;
            for v in y.iter_mut() {
                walk += normal(&mut r, self.random_walk * dt.sqrt());
                *v += normal(&mut r, w) + walk;
            }
            series.push(y);
        }
        for p in &planned {
            let (effect, sf) = self.effect(p)?;
            let at = (p.start_s * self.rate_hz).round() as usize;
            let samples = (0..cols.len())
                .map(|c| {
                    (0..p.n)
                        .map(|k| {
                            self.bias
                                + effect[c]
                                + sf * k0 * p.input.unwrap_or(0.0)
                                + series[c][at + k]
                        })
                        .collect()
                })
                .collect();
            runs.push(Run {
                label: p.label.clone(),
                line: 0,
                start_s: p.start_s,
                duration_s: p.n as f64 * dt,
                dropped: 0,
                stimulus: p.stimulus,
                input: p.input,
                samples,
            });
        }
        Ok(Record {
            kind: self.kind(),
            columns: cols,
            field_axes: self.field_flags()?,
            dt_s: dt,
            runs,
        })
    }

    /// The truth, named as the reduction reports it.
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        let planned = self.plan_runs()?;
        let mut t = serde_json::Map::new();
        let labels = self.reduction().labels()?;
        match self.kind() {
            Kind::Magnetic => {
                let m = self.matrix()?;
                let xyz = ["x", "y", "z"];
                for (i, l) in labels.iter().enumerate() {
                    for j in self.field_axes()? {
                        let name =
                            super::coefficient_name(&format!("magnetic_{}", xyz[j]), l.as_deref());
                        t.insert(name, m[3 * i + j].into());
                    }
                }
            }
            Kind::Shock => {
                let (b, s) = self.shock_shifts(self.levels()?.len())?;
                let with_sf = self.inputs.is_some();
                for (p, (db, ds)) in b.iter().zip(&s).enumerate() {
                    t.insert(format!("shock_shift_{}", p + 1), (*db).into());
                    if with_sf {
                        // ppm of the scale factor before the first shock.
                        t.insert(format!("shock_shift_{}_sf", p + 1), (*ds).into());
                    }
                }
            }
            _ => {
                let angles: Vec<f64> = {
                    let mut v: Vec<f64> = planned
                        .iter()
                        .filter(|p| p.stimulus.vib_g_rms > 0.0)
                        .map(|p| p.stimulus.vib_angle_deg)
                        .collect();
                    v.sort_by(f64::total_cmp);
                    v.dedup();
                    v
                };
                if angles.len() == 1 {
                    let th = angles[0].to_radians();
                    let k = self.vrc * th.cos().powi(2)
                        + self.vibropendulous * th.sin() * th.cos()
                        + self.vrc_pendulous * th.sin().powi(2);
                    t.insert("vrc".into(), k.into());
                } else {
                    t.insert("vrc".into(), self.vrc.into());
                    t.insert("vibropendulous".into(), self.vibropendulous.into());
                    t.insert("vrc_pendulous".into(), self.vrc_pendulous.into());
                }
            }
        }
        Ok(serde_json::Value::Object(t))
    }
}

impl Default for SensitivitySimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

impl crate::procedures::Simulate for super::Sensitivity {
    type Options = SensitivitySimOptions;

    fn validate(o: &SensitivitySimOptions) -> Result<()> {
        o.plan_runs()?;
        o.truth_json().map(|_| ())
    }

    fn simulate(o: &SensitivitySimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        super::input::write(&o.record()?, o.reduction().output_scale()?, out)?;
        Ok(())
    }

    fn truth(o: &SensitivitySimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
