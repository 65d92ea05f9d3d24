//! Repeatability simulator: runs of one coefficient over days and
//! turn-ons with known variance components.
//!
//! Day `d` draws `a_d ~ N(0, day_sd²)`, its turn-on `t` draws
//! `b_dt ~ N(0, turn_on_sd²)`, and the run reports
//! `x_dt = mean + a_d + b_dt + e_dt` with `e_dt ~ N(0, u_dt²)` and its own
//! `u_dt`: `within_u`, or, with `u_spread` s > 1, log-uniform within
//! `[within_u/√s, within_u·√s]`. With `within_dof` the reported u is
//! itself estimated: `u·√(χ²_ν/ν)`. Deterministic for a seed.

use rand::RngExt;

use super::input::write;
use super::Run;
use crate::error::Result;
use crate::options::{check_range, invalid};
use crate::sim::{normal, rng};

/// Options of `incal simulate repeatability`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RepeatSimOptions {
    /// Days (default 5).
    #[serde(default = "five")]
    pub days: usize,
    /// Turn-ons a day (default 3).
    #[serde(default = "three")]
    pub turn_ons_per_day: usize,
    /// The coefficient's mean (default 0.5).
    #[serde(default = "half")]
    pub mean: f64,
    /// Day-to-day standard deviation (default 0.02).
    #[serde(default = "day_sd")]
    pub day_sd: f64,
    /// Turn-on-to-turn-on standard deviation (default 0.01).
    #[serde(default = "turn_on_sd")]
    pub turn_on_sd: f64,
    /// Each run's own u (default 0.005).
    #[serde(default = "within_u")]
    pub within_u: f64,
    /// Spread of the runs' u (ratio of the largest to the smallest
    /// possible; default 1: all equal).
    #[serde(default = "one")]
    pub u_spread: f64,
    /// Degrees of freedom of each run's u (default none: exact).
    #[serde(default)]
    pub within_dof: Option<f64>,
    /// Random seed (default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

pub(super) fn five() -> usize {
    5
}
pub(super) fn three() -> usize {
    3
}
fn half() -> f64 {
    0.5
}
pub(super) fn day_sd() -> f64 {
    0.02
}
pub(super) fn turn_on_sd() -> f64 {
    0.01
}
pub(super) fn within_u() -> f64 {
    0.005
}
fn one() -> f64 {
    1.0
}
pub(super) fn seed_one() -> u64 {
    1
}

impl Default for RepeatSimOptions {
    fn default() -> Self {
        crate::options::from_json(&serde_json::json!({})).unwrap_or_else(|_| unreachable!())
    }
}

impl RepeatSimOptions {
    /// Every range check.
    pub fn validate(&self) -> Result<()> {
        if !(1..=10_000).contains(&self.days) {
            return invalid("days", format!("{}: 1 to 10000", self.days));
        }
        if !(1..=10_000).contains(&self.turn_ons_per_day) {
            return invalid(
                "turn_ons_per_day",
                format!("{}: 1 to 10000", self.turn_ons_per_day),
            );
        }
        check_range("mean", self.mean, -1e12, 1e12, "")?;
        check_range("day_sd", self.day_sd, 0.0, 1e12, "")?;
        check_range("turn_on_sd", self.turn_on_sd, 0.0, 1e12, "")?;
        check_range("within_u", self.within_u, 1e-300, 1e12, "")?;
        check_range("u_spread", self.u_spread, 1.0, 1e6, "")?;
        if let Some(v) = self.within_dof {
            check_range("within_dof", v, 1.0, 1e9, "")?;
        }
        Ok(())
    }

    /// The simulated runs.
    pub fn runs(&self) -> Result<Vec<Run>> {
        Ok(self.draw()?.0)
    }

    /// The runs and the mean of the true u² (the reported u differ from
    /// it with `within_dof`).
    fn draw(&self) -> Result<(Vec<Run>, f64)> {
        self.validate()?;
        let mut r = rng(self.seed);
        let mut out = Vec::new();
        let mut u2 = 0.0;
        for d in 0..self.days {
            let a = normal(&mut r, self.day_sd);
            for t in 0..self.turn_ons_per_day {
                let b = normal(&mut r, self.turn_on_sd);
                let u = self.within_u * self.u_spread.powf(r.random::<f64>() - 0.5);
                u2 += u * u;
                let e = normal(&mut r, u);
                let reported = match self.within_dof {
                    Some(nu) => {
                        let k = nu.round().max(1.0) as usize;
                        let chi2: f64 = (0..k).map(|_| normal(&mut r, 1.0).powi(2)).sum();
                        u * (chi2 / k as f64).sqrt()
                    }
                    None => u,
                };
                out.push(Run {
                    source: format!("day {} turn-on {}", d + 1, t + 1),
                    day: Some(format!("day-{}", d + 1)),
                    value: self.mean + a + b + e,
                    u: reported,
                    dof: self.within_dof.unwrap_or(f64::INFINITY),
                });
            }
        }
        let n = out.len() as f64;
        Ok((out, u2 / n))
    }

    /// The truth as JSON: the mean and the components as standard
    /// deviations (`within_run_sd` the root mean square of the true u).
    pub fn truth_json(&self) -> Result<serde_json::Value> {
        let u2 = self.draw()?.1;
        Ok(serde_json::json!({
            "mean": self.mean,
            "day_repeatability": self.day_sd,
            "turn_on_repeatability": self.turn_on_sd,
            "within_run_sd": u2.sqrt(),
        }))
    }
}

impl crate::procedures::Simulate for super::Repeatability {
    type Options = RepeatSimOptions;

    fn validate(o: &RepeatSimOptions) -> Result<()> {
        o.validate()
    }

    fn simulate(o: &RepeatSimOptions, out: &mut dyn std::io::Write) -> Result<()> {
        write(&o.runs()?, out)?;
        Ok(())
    }

    fn truth(o: &RepeatSimOptions) -> Result<Option<serde_json::Value>> {
        o.truth_json().map(Some)
    }
}
