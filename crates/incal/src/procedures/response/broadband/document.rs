//! The result document of a broadband response: the model part (as for
//! the stepped sine), the `spectrum` table and the Bode curve.

use std::f64::consts::{LN_10, PI};

use serde_json::json;

use super::BroadbandResult;
use crate::document::{Cell, DecisionCode, DocumentBuilder, Procedure, ResultDocument, Table};
use crate::error::Result;
use crate::procedures::response::model::response;
use crate::procedures::response::sine::wrap_pi;
use crate::units::Unit;

impl BroadbandResult {
    /// The `spectrum` table: every bin above 0 Hz.
    fn spectrum_table(&self) -> Result<Table> {
        let o = |s: &str| Some(Unit::Other(s.into()));
        let mut t = Table::new(
            "spectrum",
            "Spectrum: H1 = Pxy/Pxx, coherence and the model (fitted = 1)",
            &[
                ("freq_hz", o("Hz")),
                ("pxx", o("reference^2/Hz")),
                ("pyy", o("output^2/Hz")),
                ("coherence", Some(Unit::One)),
                ("gain", o("output/reference")),
                ("u_gain", o("output/reference")),
                ("gain_db", o("dB")),
                ("u_gain_db", o("dB")),
                ("phase_deg", Some(Unit::Deg)),
                ("u_phase_deg", Some(Unit::Deg)),
                ("fitted", Some(Unit::One)),
                ("model_gain_db", o("dB")),
                ("model_phase_deg", Some(Unit::Deg)),
            ],
        );
        let part = &self.part;
        let x = part.model.fit.estimates.values().as_slice().to_vec();
        let sign = if x[0] < 0.0 { PI } else { 0.0 };
        let c = 20.0 / LN_10;
        for (k, b) in self.bins.iter().enumerate() {
            let p = &b.point;
            let (_, ph) = response(part.model.order, &x, p.freq_hz);
            let (mdb, mdeg) = part.model_db_deg(&x, p.freq_hz);
            let usable = p.gain > 0.0;
            t.push(vec![
                Cell::num(p.freq_hz),
                Cell::num(self.spectra.pxx[k + 1]),
                Cell::num(self.spectra.pyy[k + 1]),
                Cell::num(b.coherence),
                Cell::num(p.gain),
                Cell::num(p.u_gain),
                Cell::opt(usable.then(|| 20.0 * (p.gain / part.scale.0.abs()).log10())),
                Cell::opt(usable.then(|| c * p.u_gain / p.gain)),
                Cell::num((ph - sign + wrap_pi(p.phase_rad - ph)).to_degrees()),
                Cell::num(p.u_phase_rad.to_degrees()),
                Cell::num(if b.fitted { 1.0 } else { 0.0 }),
                Cell::num(mdb),
                Cell::num(mdeg),
            ])?;
        }
        Ok(t)
    }

    /// The result document.
    pub fn document(&self) -> Result<ResultDocument> {
        let fitted = self.bins.iter().filter(|b| b.fitted).count();
        let mut b = DocumentBuilder::new(
            Procedure::ResponseBroadband,
            format!(
                "Dynamic response from a broadband record: {fitted} of {} bins fitted, {} order model with delay",
                self.bins.len(),
                self.part.model.order.name()
            ),
        );
        self.part.write(&mut b)?;
        b.decision(
            DecisionCode::VarianceSource,
            format!("covariance of the model's coefficients: {} (neighbouring bins of a windowed spectrum are not independent)", self.covariance),
        );
        b.extra(
            "welch",
            json!({
                "segment_samples": self.options.segment_samples,
                "overlap_samples": self.options.overlap(),
                "window": "hann",
                "segments": self.spectra.segments,
                "effective_averages": self.spectra.effective,
                "enbw_bins": self.spectra.enbw_bins,
                "resolution_hz": self.spectra.freq_hz.get(1).copied(),
                "aligned_samples": self.shift_samples,
            }),
        )?;
        b.warnings(self.warnings.iter().cloned());
        b.table(self.spectrum_table()?);
        b.extra("bode", self.part.bode())?;
        Ok(b.finish())
    }
}
