//! Synthetic stepped-sine recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps every dwell's stamps (both clocks), lines and
//! frequency and draws both channels from the dwell's fitted sines, so
//! that the second, nonlinear stage — the low-pass model with its order
//! rule, the half-power bandwidth, the interpolated −3 dB point — is
//! propagated as it acts:
//! `x(t) = C + R cos(2π f (t − t₀) + φ) + σ* z` for each channel, with
//! * `C`, `R`, `φ` the dwell's fitted offset, amplitude and phase at the
//!   fitted (or estimated) frequency `f`, `t₀` the first fitted stamp
//!   (harmonics and drift, fitted beside the fundamental as nuisance
//!   terms, are left out);
//! * `σ*² = s² ν / χ²_ν`, `s` the channel's residual σ with its `n − p`;
//! * the reference's type-B terms, one draw per dwell as the reduction
//!   takes them: its amplitude off by a relative `N(0, (u_reference_pct /
//!   100)²)` and its phase by `N(0, u_reference_phase_deg²)` against the
//!   true input, so the output moves by both;
//! * a stated `k1` with its `u_k1` (one draw per trial): the output scaled
//!   by `k1* / k1`, the reduction normalising by the stated `k1`;
//! * the model-free bandwidth's interpolation error `|Δ|` of the result
//!   (a method error the GUM holds as a standard uncertainty): `N(0, Δ²)`
//!   added to each trial's interpolated bandwidth.

use crate::error::Result;
use crate::montecarlo::{scaled_variance, Drawn, MethodError, Synthesis};
use crate::sim::normal;

use super::input::{Dwell, Recorded};
use super::{calibrate, ResponseOptions};

/// One dwell's recipe: its template and both channels' fitted sines.
struct Recipe {
    dwell: Dwell,
    freq_hz: f64,
    origin_s: f64,
    /// (offset, amplitude, phase, residual variance, dof): output, reference.
    channels: [(f64, f64, f64, f64, f64); 2],
}

/// The recipe of synthetic stepped-sine recordings for `rec` reduced
/// with `o` (module docs).
pub(super) fn synthesis(rec: &Recorded, o: &ResponseOptions) -> Result<Synthesis<Recorded>> {
    let r = calibrate(&rec.dwells, o)?;
    let recipes: Vec<Recipe> = rec
        .dwells
        .iter()
        .zip(&r.dwells)
        .map(|(d, x)| {
            let start = d.time_s.first().copied().unwrap_or(0.0) + o.settle_s;
            let skip = d.time_s.partition_point(|t| *t < start);
            let ch = |c: &super::sine::ChannelFit| {
                (
                    c.offset,
                    c.amplitude,
                    c.phase_rad,
                    c.residual_sd * c.residual_sd,
                    c.dof as f64,
                )
            };
            Recipe {
                dwell: d.clone(),
                freq_hz: x.freq_hz,
                origin_s: d.time_s.get(skip).copied().unwrap_or(0.0),
                channels: [ch(&x.output), ch(&x.reference)],
            }
        })
        .collect();
    let mut drawn = vec![Drawn::new(
        "noise of each channel in each dwell",
        "normal, variance scaled inverse χ² (ν = the sine fit's n − p)",
        "σ = the dwell fit's residual σ".into(),
        "each dwell's sine fits",
    )];
    let TypeB {
        pct,
        phase,
        k1_rel,
        drawn: more,
        method,
    } = type_b(&o.model, &r.part, "at each dwell", "the dwells");
    drawn.extend(more);
    let warnings = rec.warnings.clone();
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Recorded> {
        let scale = 1.0 + normal(rng, k1_rel);
        let dwells = recipes
            .iter()
            .map(|q| {
                let (amp, ph) = (1.0 + normal(rng, pct), normal(rng, phase));
                let mut d = q.dwell.clone();
                let w = 2.0 * std::f64::consts::PI * q.freq_hz;
                let (c, a, p, s2, dof) = q.channels[0];
                let s = scaled_variance(rng, s2, dof).sqrt();
                for (y, t) in d.output.iter_mut().zip(&q.dwell.time_s) {
                    *y = c + scale * a * (w * (t - q.origin_s) + p + ph).cos() + normal(rng, s);
                }
                let (c, a, p, s2, dof) = q.channels[1];
                let s = scaled_variance(rng, s2, dof).sqrt();
                let stamps = if q.dwell.time_ref_s.len() == q.dwell.time_s.len() {
                    &q.dwell.time_ref_s
                } else {
                    &q.dwell.time_s
                };
                for (y, t) in d.reference.iter_mut().zip(stamps) {
                    *y = c + amp * a * (w * (t - q.origin_s) + p).cos() + normal(rng, s);
                }
                d
            })
            .collect();
        Ok(Recorded {
            dwells,
            warnings: warnings.clone(),
        })
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: None,
        method,
        factors: Vec::new(),
    })
}

/// The type-B inputs the stepped sine and the broadband record share: the
/// reference's relative amplitude and phase (radians) u, a stated `k1`'s
/// relative u, their rows of the table (`per`: how often the reference's
/// error is drawn; `around`: what the interpolation's curvature is read
/// from) and the model-free bandwidth's interpolation error as a method
/// error.
pub(super) struct TypeB {
    pub pct: f64,
    pub phase: f64,
    pub k1_rel: f64,
    pub drawn: Vec<Drawn>,
    pub method: Vec<MethodError>,
}

/// [`TypeB`] of the model options `m` and the model part `part`.
pub(super) fn type_b(
    m: &super::fit::ModelOptions,
    part: &super::fit::ModelPart,
    per: &str,
    around: &str,
) -> TypeB {
    let mut drawn = Vec::new();
    let (pct, phase) = (
        m.u_reference_pct / 100.0,
        m.u_reference_phase_deg.to_radians(),
    );
    if pct > 0.0 || phase > 0.0 {
        drawn.push(Drawn::new(
            &format!("reference amplitude and phase {per}"),
            "normal",
            format!(
                "u = {} %, {} deg",
                m.u_reference_pct, m.u_reference_phase_deg
            ),
            "u_reference_pct, u_reference_phase_deg",
        ));
    }
    let k1_rel = match (m.k1, m.u_k1) {
        (Some(k), Some(u)) if k != 0.0 && u > 0.0 => u / k.abs(),
        _ => 0.0,
    };
    if k1_rel > 0.0 {
        drawn.push(Drawn::new(
            "scale factor k1 (one per trial; the gains are normalised by the stated k1)",
            "normal",
            format!("u = {:.3e} relative", k1_rel),
            "u_k1",
        ));
    }
    let mut method = Vec::new();
    if part.interpolated.is_ok() && part.interpolation_u_hz > 0.0 {
        let name = match m.bandwidth {
            super::BandwidthMethod::Interpolated => "bandwidth_hz",
            super::BandwidthMethod::Model => "bandwidth_interp_hz",
        };
        method.push(MethodError {
            coefficient: name.into(),
            u: part.interpolation_u_hz,
        });
        drawn.push(Drawn::new(
            "the model-free bandwidth's interpolation error (one per trial, added to it)",
            "normal",
            format!("u = {:.3e} Hz", part.interpolation_u_hz),
            &format!("the curvature of {around} around −3 dB (the GUM's type B)"),
        ));
    }
    TypeB {
        pct,
        phase,
        k1_rel,
        drawn,
        method,
    }
}
