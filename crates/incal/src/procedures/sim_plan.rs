//! Plans by simulation: for a procedure whose uncertainty has no closed
//! form before the test (the IMU sessions, the noise analysis), the
//! planned session is simulated from its truth, rig and noise, and reduced
//! by the procedure itself; the u the reduction reports is the predicted u.
//!
//! The prediction is the procedure's own uncertainty model evaluated on a
//! recording with the planned noise, so it is what the reduction of the
//! real recording will report if the sensor's noise is as planned. A few
//! seeds are run (`seeds`, default 5): the predicted u of a term is the root
//! mean square of its u over them, and the plan records the scatter of the
//! estimates over the seeds against it (`scatter_over_u`, about 1 when the
//! reported u is honest; with 5 seeds its own spread is about ±35 %).

use std::marker::PhantomData;

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use super::{reduce_source, Plan, Procedure, Silent, Simulate};
use crate::document::plan::PlanDocument;
use crate::error::{Error, Result};

/// The options of a plan by simulation: the session as the simulator
/// takes it (truth, rig, noise, seed), the reduction's options, and how
/// many seeds are simulated.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
pub struct SimPlanOptions<S, R> {
    /// The planned session: the simulator's options.
    pub session: S,
    /// The reduction's options; when absent, those that match the session
    /// (its rate, gravity, rotation, …; `Planned::reduce_options`).
    #[serde(default = "no_reduce::<R>", skip_serializing_if = "Option::is_none")]
    pub reduce: Option<R>,
    /// Sessions simulated (seeds `seed`, `seed + 1`, …), 1 to 50.
    #[serde(default = "default_seeds")]
    pub seeds: usize,
}

fn no_reduce<R>() -> Option<R> {
    None
}

fn default_seeds() -> usize {
    5
}

/// A procedure planned by simulating its session with `S`: the session
/// as the procedure takes it (its sequence) and the reduction's options
/// that match a session, so that a plan needs only the session.
pub trait Planned<S: Simulate>: Procedure {
    /// The session as this procedure records it (the IMU procedures fix
    /// the sequence; the default is the session as given).
    fn session(session: S::Options) -> S::Options {
        session
    }

    /// The reduction's options for a recording of `session` (rate,
    /// gravity, …; the rest the procedure's defaults).
    fn reduce_options(session: &S::Options) -> Self::Options;
}

/// The plan of procedure `P` by simulating its session with `S` (module
/// docs).
#[derive(Debug, Clone, Copy)]
pub struct BySimulation<P, S>(PhantomData<(P, S)>);

/// The session's options with its `seed` advanced by `k`.
fn with_seed<S: Serialize + serde::de::DeserializeOwned + JsonSchema>(
    session: &S,
    k: usize,
) -> Result<S> {
    let mut v = serde_json::to_value(session)
        .map_err(|e| Error::Unsupported(format!("session options: {e}")))?;
    let Some(seed) = v.get("seed").and_then(serde_json::Value::as_u64) else {
        return crate::options::invalid("session", "the simulator's options have no `seed`");
    };
    v["seed"] = seed.wrapping_add(k as u64).into();
    crate::options::from_json(&v)
}

impl<P: Planned<S>, S: Simulate> Plan for BySimulation<P, S>
where
    S::Options: Clone,
    P::Options: Clone,
{
    type Options = SimPlanOptions<S::Options, P::Options>;

    fn plan(o: &Self::Options) -> Result<PlanDocument> {
        if !(1..=50).contains(&o.seeds) {
            return crate::options::invalid("seeds", format!("1 to 50, got {}", o.seeds));
        }
        let session = P::session(o.session.clone());
        let reduce = o
            .reduce
            .clone()
            .unwrap_or_else(|| P::reduce_options(&session));
        S::validate(&session)?;
        P::validate(&reduce)?;
        // term → (unit, u² summed, values) over the seeds.
        let mut terms: Vec<(String, String, f64, Vec<f64>)> = Vec::new();
        let mut dof = f64::INFINITY;
        let mut title = String::new();
        for k in 0..o.seeds {
            let drawn = with_seed(&session, k)?;
            let mut bytes = Vec::new();
            S::simulate(&drawn, &mut bytes)?;
            let read = incal_io::ReadOptions::default();
            let doc =
                reduce_source::<P, _>("planned session", &bytes[..], &read, &reduce, &Silent)?;
            title.clone_from(&doc.title);
            for (name, c) in doc.coefficients.iter() {
                dof = dof.min(c.dof.unwrap_or(f64::INFINITY));
                match terms.iter_mut().find(|t| t.0 == name) {
                    Some(t) => {
                        t.2 += c.u * c.u;
                        t.3.push(c.value);
                    }
                    None => terms.push((
                        name.into(),
                        c.unit.as_str().into(),
                        c.u * c.u,
                        vec![c.value],
                    )),
                }
            }
        }
        let mut plan = PlanDocument::new(P::ID, format!("Plan by simulation: {title}"));
        let options = serde_json::json!({"session": session, "reduce": reduce, "seeds": o.seeds});
        plan.with_options(&options)?;
        let mut scatter = serde_json::Map::new();
        let mut fixed = Vec::new();
        let sometimes: Vec<String> = terms
            .iter()
            .filter(|t| t.3.len() < o.seeds)
            .map(|t| format!("{} ({} of {})", t.0, t.3.len(), o.seeds))
            .collect();
        for (name, unit, u2, values) in &terms {
            let u = (u2 / values.len() as f64).sqrt();
            if !(u.is_finite() && u > 0.0) {
                fixed.push(name.clone());
                continue;
            }
            plan.predict(name, u, unit)?;
            if values.len() > 1 {
                let n = values.len() as f64;
                let mean = values.iter().sum::<f64>() / n;
                let sd =
                    (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
                scatter.insert(name.clone(), ((sd / u * 100.0).round() / 100.0).into());
            }
        }
        plan.set_dof(dof.min(1e6));
        plan.set("seeds", o.seeds.into())?;
        if !scatter.is_empty() {
            plan.set("scatter_over_u", serde_json::Value::Object(scatter))?;
        }
        plan.note(format!(
            "predicted by simulating the planned session {} time(s) and reducing it: the u the reduction reports for a recording with this noise (root mean square over the seeds)",
            o.seeds
        ));
        if !sometimes.is_empty() {
            plan.note(format!(
                "reported by only some of the simulated reductions (a term the model selection keeps or drops by chance): {}",
                sometimes.join(", ")
            ));
        }
        if !fixed.is_empty() {
            plan.note(format!(
                "not predicted (u = 0 in the reduction): {}",
                fixed.join(", ")
            ));
        }
        Ok(plan)
    }
}
