//! The noise record's first-order Gauss–Markov bias (`gauss_markov:
//! true`): σ and the correlation time T fitted to each channel's Allan
//! variance ([`crate::noise::markov`] for the model and its u), with its
//! discrete-time form at a filter rate.
//!
//! In the document, per channel, `channels.NAME.gauss_markov` holds
//! `sigma` and `u_sigma` (input unit), `tau_c_s` and `u_tau_c_s`, `dof`,
//! `k95`, `white_n` (the white term fitted beside it, input unit·√s),
//! `supported` and `reason` (why not, when not; without a fit only these
//! and `filter_rate_hz`), `tau_range_s`,
//! `filter_rate_hz`, `phi` and `u_phi` (`e^{−1/(f T)}`), `q_d` and `u_q_d`
//! (the discrete driving noise `σ√(1 − φ²)`, input unit) and `q_c` and
//! `u_q_c` (the continuous driving density `σ√(2/T)`, input unit/√s).
//! When supported, the coefficients `NAME.gm_sigma` (input unit) and
//! `NAME.gm_tau_c_s` (s); when not, a `not-significant` warning says why.

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::error::Result;
use crate::noise::markov::GaussMarkov;

/// The Gauss–Markov options (flattened into the noise options).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, schemars::JsonSchema)]
pub struct MarkovOptions {
    /// Also fit a first-order Gauss–Markov bias (σ, correlation time) to
    /// every channel's Allan variance.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub gauss_markov: bool,
    /// The filter rate of its discrete-time form, Hz (default the record's
    /// sample rate).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gm_filter_rate_hz: Option<f64>,
}

impl MarkovOptions {
    /// Range checks (names the key).
    pub fn validate(&self) -> Result<()> {
        if let Some(f) = self.gm_filter_rate_hz {
            crate::options::check_range("gm_filter_rate_hz", f, 1e-3, 1e6, "Hz")?;
        }
        Ok(())
    }

    /// The fit of one channel's OADEV and the filter rate (`None` without
    /// `gauss_markov` or with too few averaging times).
    pub fn compute(&self, st: &crate::noise::Stability, tau0: f64) -> Option<(Fitted, f64)> {
        if !self.gauss_markov {
            return None;
        }
        Some((
            crate::noise::markov::fit_gauss_markov(&st.taus_s, &st.oadev, tau0),
            self.gm_filter_rate_hz.unwrap_or(1.0 / tau0),
        ))
    }
}

/// A fit, or why there is none.
pub type Fitted = std::result::Result<GaussMarkov, String>;

/// `channels.NAME.gauss_markov` (module docs): values times `f` into the
/// input unit, at the filter rate `rate_hz`; `{supported: false, reason}`
/// without a fit.
pub fn json(g: &Fitted, f: f64, rate_hz: f64) -> Value {
    let g = match g {
        Ok(g) => g,
        Err(why) => return json!({"supported": false, "reason": why, "filter_rate_hz": rate_hz}),
    };
    let (phi, u_phi, qd, u_qd) = g.discrete(rate_hz);
    let (qc, u_qc) = g.continuous();
    json!({
        "sigma": g.sigma * f,
        "u_sigma": g.u_sigma * f,
        "tau_c_s": g.tau_c_s,
        "u_tau_c_s": g.u_tau_c_s,
        "dof": g.dof,
        "k95": crate::estimation::coverage_factor(g.dof, 0.95),
        "white_n": g.n * f,
        "supported": g.unsupported.is_none(),
        "reason": g.unsupported,
        "tau_range_s": [g.tau_range_s.0, g.tau_range_s.1],
        "filter_rate_hz": rate_hz,
        "phi": phi,
        "u_phi": u_phi,
        "q_d": qd * f,
        "u_q_d": u_qd * f,
        "q_c": qc * f,
        "u_q_c": u_qc * f,
    })
}
