//! Repeatability plans: for the days, turn-ons a day and the expected
//! components, the predicted u of each standard deviation from the
//! expected mean squares (module docs of [`super`]: `u(s) = s/√(2ν)`,
//! ν by Satterthwaite with the expected mean squares). Refused with fewer
//! than 3 days or 3 turn-ons, naming the level.

use super::sim::{day_sd, five, seed_one, three, turn_on_sd, within_u};
use crate::document::plan::PlanDocument;
use crate::error::Result;
use crate::options::{check_range, invalid};

/// Options of `incal plan repeatability`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RepeatPlanOptions {
    /// Days (default 5).
    #[serde(default = "five")]
    pub days: usize,
    /// Turn-ons a day (default 3).
    #[serde(default = "three")]
    pub turn_ons_per_day: usize,
    /// Expected day-to-day standard deviation (default 0.02).
    #[serde(default = "day_sd")]
    pub day_sd: f64,
    /// Expected turn-on-to-turn-on standard deviation (default 0.01).
    #[serde(default = "turn_on_sd")]
    pub turn_on_sd: f64,
    /// Each run's u (default 0.005).
    #[serde(default = "within_u")]
    pub within_u: f64,
    /// Unused by the prediction (kept so a plan and a simulation share
    /// their keys; default 1).
    #[serde(default = "seed_one")]
    pub seed: u64,
}

impl crate::procedures::Plan for super::Repeatability {
    type Options = RepeatPlanOptions;

    fn plan(o: &RepeatPlanOptions) -> Result<PlanDocument> {
        plan_document(o)
    }
}

/// `u` of a standard deviation `s` with `ν` degrees of freedom.
fn u_sd(v: f64, nu: f64) -> f64 {
    if v <= 0.0 {
        0.0
    } else {
        v.sqrt() / (2.0 * nu).sqrt()
    }
}

/// The plan document (module docs).
pub fn plan_document(o: &RepeatPlanOptions) -> Result<PlanDocument> {
    if o.days < 3 {
        return invalid(
            "days",
            format!("day level: {} days; at least 3 are needed", o.days),
        );
    }
    if o.turn_ons_per_day < 1
        || o.days
            .checked_mul(o.turn_ons_per_day)
            .is_none_or(|n| n > 1_000_000)
    {
        return invalid("turn_ons_per_day", "1 to 1000000 runs in all");
    }
    check_range("day_sd", o.day_sd, 0.0, 1e12, "")?;
    check_range("turn_on_sd", o.turn_on_sd, 0.0, 1e12, "")?;
    check_range("within_u", o.within_u, 1e-300, 1e12, "")?;
    let (d, t) = (o.days as f64, o.turn_ons_per_day as f64);
    let n = d * t;
    let u2 = o.within_u * o.within_u;
    let ms_on = o.turn_on_sd * o.turn_on_sd + u2;
    let ms_day = ms_on + t * o.day_sd * o.day_sd;
    let mut doc = PlanDocument::new(
        crate::document::Procedure::Repeatability,
        format!(
            "Repeatability plan: {} days x {} turn-ons",
            o.days, o.turn_ons_per_day
        ),
    );
    doc.with_options(o)?;
    if o.turn_ons_per_day >= 2 {
        let v = o.turn_on_sd * o.turn_on_sd;
        let nu = v * v / (ms_on * ms_on / (n - d));
        doc.predict("turn_on_repeatability", u_sd(v, nu), "output")?;
    } else {
        doc.note("turn_on_repeatability: one turn-on a day cannot separate it from the day-to-day component");
    }
    let inner = if o.turn_ons_per_day >= 2 {
        ms_on * ms_on / (n - d)
    } else {
        0.0
    };
    // One turn-on a day: the day component holds the turn-on variance too.
    let v = if o.turn_ons_per_day >= 2 {
        o.day_sd * o.day_sd
    } else {
        o.day_sd * o.day_sd + o.turn_on_sd * o.turn_on_sd
    };
    let nu = (t * v).powi(2) / (ms_day * ms_day / (d - 1.0) + inner);
    doc.predict("day_repeatability", u_sd(v, nu), "output")?;
    doc.predict(
        "repeatability_simple",
        u_sd(
            o.day_sd.powi(2) + ms_on,
            super::simple_dof(
                &vec![vec![ms_on; o.turn_ons_per_day]; o.days],
                o.day_sd.powi(2),
            ),
        ),
        "output",
    )?;
    doc.note("predicted from the expected mean squares of the nested analysis of variance: u(s) = s/sqrt(2 nu), nu by Satterthwaite");
    Ok(doc)
}
