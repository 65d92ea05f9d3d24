//! The result document of a stepped-sine response: the model's
//! coefficients (`k_dc`, `fc_hz` or `fn_hz` and `zeta`, `delay_s`,
//! `bandwidth_hz`, `phase_freq_hz`, `latency_s`), the model-free
//! bandwidth and the gain flatness, the `dwells` table and the Bode curve
//! of the model with its U95 band (`bode`).

use std::f64::consts::{LN_10, PI};

use nalgebra::DVector;
use serde_json::json;

use super::fit::ModelPart;
use super::model::response;
use super::sine::wrap_pi;
use super::{BandwidthMethod, ResponseResult};
use crate::document::{
    Cell, Coefficient, DecisionCode, DocumentBuilder, FitSummary, Procedure, ResultDocument, Table,
};
use crate::error::Result;
use crate::estimation::numeric_jacobian;
use crate::units::Unit;

/// The unit of a coefficient of this procedure.
pub fn unit_of(name: &str) -> Result<Unit> {
    Ok(Unit::Other(
        match name {
            "k_dc" => "output/reference",
            "zeta" => "1",
            n if n.ends_with("_hz") => "Hz",
            n if n.ends_with("_s") => "s",
            n if n.ends_with("_db") => "dB",
            _ => "1",
        }
        .into(),
    ))
}

impl ResponseResult {
    /// The `dwells` table.
    fn dwell_table(&self) -> Result<Table> {
        let o = |s: &str| Some(Unit::Other(s.into()));
        let mut t = Table::new(
            "dwells",
            "Dwells: sine fits, gain and phase against the model",
            &[
                ("freq_hz", o("Hz")),
                ("u_freq_hz", o("Hz")),
                ("samples", Some(Unit::One)),
                ("cycles", Some(Unit::One)),
                ("ref_amplitude", o("reference")),
                ("u_ref_amplitude", o("reference")),
                ("ref_phase_deg", Some(Unit::Deg)),
                ("out_amplitude", Some(Unit::Output)),
                ("u_out_amplitude", Some(Unit::Output)),
                ("out_phase_deg", Some(Unit::Deg)),
                ("gain", o("output/reference")),
                ("u_gain", o("output/reference")),
                ("gain_db", o("dB")),
                ("u_gain_db", o("dB")),
                ("phase_deg", Some(Unit::Deg)),
                ("u_phase_deg", Some(Unit::Deg)),
                ("thd_ref_pct", o("%")),
                ("thd_out_pct", o("%")),
                ("model_gain_db", o("dB")),
                ("model_phase_deg", Some(Unit::Deg)),
                ("residual_gain", Some(Unit::One)),
                ("residual_phase", Some(Unit::One)),
            ],
        );
        let x = self.part.model.fit.estimates.values().as_slice().to_vec();
        let sign = if x[0] < 0.0 { PI } else { 0.0 };
        let c = 20.0 / LN_10;
        for d in &self.dwells {
            let p = &d.point;
            let (m, ph) = response(self.part.model.order, &x, p.freq_hz);
            let dphi = wrap_pi(p.phase_rad - ph);
            let (mdb, mdeg) = self.part.model_db_deg(&x, p.freq_hz);
            t.push(vec![
                Cell::num(d.freq_hz),
                Cell::opt(d.u_freq_hz),
                Cell::num(d.samples as f64),
                Cell::num(d.cycles),
                Cell::num(d.reference.amplitude),
                Cell::num(d.reference.u_amplitude),
                Cell::num(d.reference.phase_rad.to_degrees()),
                Cell::num(d.output.amplitude),
                Cell::num(d.output.u_amplitude),
                Cell::num(d.output.phase_rad.to_degrees()),
                Cell::num(p.gain),
                Cell::num(p.u_gain),
                Cell::num(20.0 * (p.gain / self.part.scale.0.abs()).log10()),
                Cell::num(c * p.u_gain / p.gain),
                Cell::num((ph - sign + dphi).to_degrees()),
                Cell::num(p.u_phase_rad.to_degrees()),
                Cell::opt(d.reference.thd.map(|v| 100.0 * v)),
                Cell::opt(d.output.thd.map(|v| 100.0 * v)),
                Cell::num(mdb),
                Cell::num(mdeg),
                Cell::num((p.gain - m) / p.u_gain),
                Cell::num(dphi / p.u_phase_rad),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let mut b = DocumentBuilder::new(
            Procedure::ResponseSine,
            format!(
                "Dynamic response by stepped sine: {} dwells, {} order model with delay",
                self.dwells.len(),
                self.part.model.order.name()
            ),
        );
        self.part.write(&mut b)?;
        b.warnings(self.warnings.iter().cloned());
        b.table(self.dwell_table()?);
        b.extra("bode", self.part.bode())?;
        Ok(b.finish())
    }
}

impl ModelPart {
    /// The model's coefficients, fit, decisions and the `scale`, `model`
    /// and `flatness` keys into a document (the caller adds its warnings,
    /// its tables and `bode`).
    pub fn write(&self, b: &mut DocumentBuilder) -> Result<()> {
        let f = &self.model.fit;
        let order = self.model.order;
        let interp_headline = self.bandwidth == BandwidthMethod::Interpolated;
        let mut e = self.coefficients.clone();
        if interp_headline {
            let names: Vec<String> = e
                .names()
                .iter()
                .map(|n| {
                    if n == "bandwidth_hz" {
                        "bandwidth_model_hz".into()
                    } else {
                        n.clone()
                    }
                })
                .collect();
            e = e.map(
                names,
                |x| x.clone(),
                |x| nalgebra::DMatrix::identity(x.len(), x.len()),
            )?;
        }
        b.estimates(&e, "", unit_of)?;
        match &self.interpolated {
            Ok((v, u)) => {
                let name = if interp_headline {
                    "bandwidth_hz"
                } else {
                    "bandwidth_interp_hz"
                };
                b.coefficient(
                    name,
                    Coefficient::new(name, *v, *u, unit_of(name)?, f.estimates.dof())?,
                )?;
            }
            Err(gap) => {
                b.decision(
                    DecisionCode::NotDetermined,
                    format!("no model-free bandwidth: {gap}"),
                );
            }
        }
        if let Some((v, u, at, band)) = self.flatness {
            b.coefficient(
                "flatness_db",
                Coefficient::new("flatness_db", v, u, unit_of("flatness_db")?, f64::INFINITY)?,
            )?;
            b.extra("flatness", json!({"band_hz": band, "worst_at_hz": at}))?;
        }
        b.fit(FitSummary::of("model", f, Unit::One));
        b.decision(
            DecisionCode::ModelDegree,
            format!("model order: {}", self.order_reason),
        );
        b.decision(
            DecisionCode::VarianceSource,
            match f.variance_source {
                crate::estimation::VarianceSource::Prior => "variance from each point's own u (a dwell's sine fits, or a bin's coherence and averages): the model's residuals agree with it",
                crate::estimation::VarianceSource::Residuals => "variance from the model's residuals: they exceed the points' own u (lack of fit)",
            },
        );
        if let Some((tau, u)) = self.coefficients.get("delay_s") {
            if tau.abs() <= self.coefficients.coverage_factor(0.95) * u {
                b.decision(
                    DecisionCode::NotDetermined,
                    format!("delay_s ({tau:.3e} s) is within its U95 ({:.3e} s) of zero: no delay is resolved", self.coefficients.coverage_factor(0.95) * u),
                );
            }
        }
        b.extra(
            "scale",
            json!({"value": self.scale.0, "u": self.scale.1, "source": self.scale.2, "unit": "output/reference"}),
        )?;
        b.extra(
            "model",
            json!({"order": order.name(), "phase_lag_deg": order.phase_lag_rad().to_degrees()}),
        )?;
        Ok(())
    }

    /// The model's gain (dB against the scale) and phase lag relative to
    /// the sign of `k_dc` (deg, continuous) at `f_hz`.
    pub fn model_db_deg(&self, x: &[f64], f_hz: f64) -> (f64, f64) {
        let (m, p) = response(self.model.order, x, f_hz);
        let sign = if x[0] < 0.0 { PI } else { 0.0 };
        (
            20.0 * (m / self.scale.0.abs()).log10(),
            (p - sign).to_degrees(),
        )
    }

    /// The Bode curve of the model on a log grid over the points (half an
    /// octave either side, 80 points) with `U95` from the model's
    /// covariance (JCGM 100 §5.1.2).
    pub fn bode(&self) -> serde_json::Value {
        let e = &self.model.fit.estimates;
        let x = e.values().clone();
        let k95 = e.coverage_factor(0.95);
        let (lo, hi) = (self.range_hz.0 / 2f64.sqrt(), self.range_hz.1 * 2f64.sqrt());
        let n = 80;
        let mut out = (vec![], vec![], vec![], vec![], vec![]);
        for k in 0..n {
            let f = (lo.ln() + (hi.ln() - lo.ln()) * k as f64 / (n - 1) as f64).exp();
            let g = |z: &DVector<f64>| {
                let (a, b) = self.model_db_deg(z.as_slice(), f);
                DVector::from_vec(vec![a, b])
            };
            let steps: Vec<f64> = (0..x.len())
                .map(|j| 1e-6 * x[j].abs().max(e.u_at(j)).max(1e-12))
                .collect();
            let j = numeric_jacobian(&g, &x, &steps);
            let c = crate::estimation::propagate(e.covariance(), &j);
            let (db, deg) = self.model_db_deg(x.as_slice(), f);
            out.0.push(f);
            out.1.push(db);
            out.2.push(deg);
            out.3.push(k95 * c[(0, 0)].max(0.0).sqrt());
            out.4.push(k95 * c[(1, 1)].max(0.0).sqrt());
        }
        json!({"freq_hz": out.0, "gain_db": out.1, "phase_deg": out.2, "u95_gain_db": out.3, "u95_phase_deg": out.4})
    }
}
