//! Synthetic centrifuge recordings for the Monte Carlo propagation
//! ([`crate::montecarlo`]).
//!
//! Each trial keeps the recording's points (position, table rate and
//! sample count; those the reduction dropped as clipped are left out) and
//! draws the outputs of a physical instrument on a physical rig, so that
//! every nonlinear step of the reduction — the regression–iteration radii,
//! the ECM geometry, the centripetal inputs computed with the measured
//! radii, the cross-coupling algebra — is propagated as it acts:
//! `E = K1* · (model at the specific force of
//! [`Centrifuge::specific_force`]) + σ* z`, with
//! * the instrument: the reported `K2`, `K3`, `K_oq`, `K_pp`, `K_oo`,
//!   `K_ip`, `K_io`, `K_po` (0 where not reported), the misalignments 0
//!   (every station fit absorbs them in its bias and scale);
//! * `(K0*, K1*) ~ N((K0, K1), Σ)` with Σ from `u_k0`, `u_k1`, `cov_k0_k1`
//!   (one draw per trial; the reduction divides by the stated K1);
//! * the rig: the measured regression radii `R+`, `R−` (the nominal
//!   radius where not measured) and the tilt whose at-rest output is the
//!   recorded one (the measured λ less the vertical axis's own terms,
//!   which λ = E0/K1 − K0 holds too), the stated latitude, gravity and
//!   sense, so the ECM alignment error of every position is the one the
//!   reduction inferred;
//! * the fixture angle of every station off by `U(−t, t)`, `t` =
//!   `alignment_tolerance_deg` (one draw per station and trial: the type-B
//!   Δc2 of the budget);
//! * the table rate of every point off by a relative `N(0, u_ω²)`,
//!   `u_ω` = `u_omega_ppm` · 10⁻⁶ (one draw per point: the rate's u at the
//!   static point of eq. 6), the recording keeping the nominal rate;
//! * the sample noise: the known σ (`noise`), else the points' pooled
//!   scatter with its `Σ(n − 1)` degrees of freedom, else (one sample per
//!   point) the IA-radial station fit's residual σ with its `n − p`, drawn
//!   as `σ*² = s² ν / χ²_ν`.

use rand::RngExt;

use crate::error::Result;
use crate::estimation::PositionStats;
use crate::models::AccelerometerModel;
use crate::montecarlo::{sample_noise, scaled_variance, Drawn, Synthesis};
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};
use crate::sim::normal;

use super::stations::{drop_clipped, group};
use super::{calibrate, CentrifugeOptions, Observation};

/// One point of the template: its station, position, nominal rate and
/// sample count.
struct Slot {
    station: usize,
    position: Position,
    omega_rad_s: f64,
    samples: usize,
}

/// The recipe of synthetic centrifuge recordings for `obs` reduced with
/// `o` (module docs).
pub(super) fn synthesis(
    obs: &[Observation],
    o: &CentrifugeOptions,
) -> Result<Synthesis<Vec<Observation>>> {
    let o = o.resolve()?.options;
    let r = calibrate(obs, &o)?;
    let mut ignored = Vec::new();
    let groups = drop_clipped(group(obs), &mut ignored);
    let mut slots = Vec::new();
    let mut stats = Vec::new();
    for (s, (_, points)) in groups.iter().enumerate() {
        for p in points {
            slots.push(Slot {
                station: s,
                position: p.position,
                omega_rad_s: p.omega,
                samples: p.samples.len(),
            });
            stats.push(PositionStats::of(&p.samples)?);
        }
    }
    let (k0, k1) = (o.k0_u(), o.k1_u());
    let fit = r.stations.first().map(|s| &s.fit);
    let (fit_s, fit_dof) = fit.map_or((0.0, 0.0), |f| (f.sigma * k1.value.abs(), f.dof as f64));
    let (s2, dof, noise) = sample_noise(o.noise.sigma(), &stats, fit_s, fit_dof, "point");
    let mut drawn = vec![noise];
    let truth = instrument(&r.joint);
    let rig = Centrifuge {
        r_plus_m: r.joint.value("R_plus_m").unwrap_or(o.radius_m),
        r_minus_m: r
            .joint
            .value("R_minus_m")
            .or(r.joint.value("R_plus_m"))
            .unwrap_or(o.radius_m),
        latitude_rad: o.latitude_rad(),
        g_local_m_s2: o.gravity_m_s2,
        opposite_sense: o.opposite_sense,
        tilt_rad: 0.0,
    };
    let rig = Centrifuge {
        tilt_rad: true_tilt(&groups, &truth, &rig, r.joint.value("tilt_rad")),
        ..rig
    };
    // (K0, K1) by the Cholesky factor of their covariance.
    let (u0, u1, c) = (k0.u, k1.u, o.cov_k0_k1());
    let l11 = u0;
    let l21 = if u0 > 0.0 { c / u0 } else { 0.0 };
    let l22 = (u1 * u1 - l21 * l21).max(0.0).sqrt();
    if u0 > 0.0 || u1 > 0.0 {
        drawn.push(Drawn::new(
            "bias K0 and scale factor K1 (one per trial)",
            "normal, bivariate",
            format!("u(K0) = {u0:.3e} g, u(K1) = {u1:.3e} output/g, cov = {c:.3e}"),
            "u_k0, u_k1, cov_k0_k1 (or the chained tumble result)",
        ));
    }
    let tol = o.alignment_tolerance_rad();
    if tol > 0.0 {
        drawn.push(Drawn::new(
            "fixture angle error of each station (one per station)",
            "rectangular",
            format!("half-width {} deg", o.alignment_tolerance_deg),
            "alignment_tolerance_deg",
        ));
    }
    let u_w = o.u_omega_ppm * 1e-6;
    if u_w > 0.0 {
        drawn.push(Drawn::new(
            "relative error of the table rate at each point",
            "normal",
            format!("u = {} ppm", o.u_omega_ppm),
            "u_omega_ppm",
        ));
    }
    let stations = groups.len();
    let draw = move |rng: &mut rand::rngs::ChaCha8Rng| -> Result<Vec<Observation>> {
        let sigma = scaled_variance(rng, s2, dof).sqrt();
        let (z0, z1) = (normal(rng, 1.0), normal(rng, 1.0));
        let mut m = truth;
        m.k0_g = k0.value + l11 * z0;
        m.k1_out_per_g = k1.value + l21 * z0 + l22 * z1;
        let offsets: Vec<f64> = (0..stations)
            .map(|_| {
                if tol > 0.0 {
                    rng.random_range(-tol..tol)
                } else {
                    0.0
                }
            })
            .collect();
        let mut out = Vec::with_capacity(slots.iter().map(|s| s.samples).sum());
        for s in &slots {
            let set = Position {
                phi_rad: s.position.phi_rad + offsets[s.station],
                ..s.position
            };
            let w = s.omega_rad_s * (1.0 + normal(rng, u_w));
            let e = m.output(&rig.specific_force(&set, w));
            for _ in 0..s.samples {
                out.push(Observation {
                    position: s.position,
                    omega_rad_s: s.omega_rad_s,
                    output: e + normal(rng, sigma),
                });
            }
        }
        Ok(out)
    };
    Ok(Synthesis {
        draw: Box::new(draw),
        drawn,
        values: None,
        method: Vec::new(),
        factors: Vec::new(),
    })
}

/// The IA tilt of the trials' rig: the one whose at-rest output at the
/// IA-radial station is the recorded one. The reduction's λ = E0/K1 − K0
/// (eq. 4) holds everything the instrument gives at rest besides K0 — the
/// tilt and the vertical axis's own terms (`K_oo` or `K_pp` at 1 g) — so
/// the rig takes `asin(λ − those terms)`; 0 without a measured tilt.
fn true_tilt(
    groups: &[((Plane, i64), Vec<super::stations::Point>)],
    truth: &AccelerometerModel,
    rig: &Centrifuge,
    measured: Option<f64>,
) -> f64 {
    let Some(lambda) = measured else {
        return 0.0;
    };
    let Some(plane) = [Plane::Ip, Plane::Io]
        .into_iter()
        .find(|p| groups.iter().any(|g| g.0 == (*p, 0)))
    else {
        return 0.0;
    };
    let at_rest = Position {
        plane,
        phi_rad: 0.0,
        polarity: 1,
    };
    let m = AccelerometerModel {
        k0_g: 0.0,
        k1_out_per_g: 1.0,
        ..*truth
    };
    let rest = m.output(&rig.specific_force(&at_rest, 0.0));
    (lambda - rest).clamp(-1.0, 1.0).asin()
}

/// The instrument of the trials: the reported coefficients (0 where not
/// reported), no misalignment; K0 and K1 are set per trial.
fn instrument(joint: &crate::estimation::Estimates) -> AccelerometerModel {
    use crate::models::Term;
    let v = |t: Term| joint.value(t.name()).unwrap_or(0.0);
    AccelerometerModel {
        k0_g: 0.0,
        k1_out_per_g: 1.0,
        k2: v(Term::K2),
        k3: v(Term::K3),
        delta_o_rad: 0.0,
        delta_p_rad: 0.0,
        k_ip: v(Term::Kip),
        k_io: v(Term::Kio),
        k_po: v(Term::Kpo),
        k_pp: v(Term::Kpp),
        k_oo: v(Term::Koo),
        k_oq: v(Term::Koq),
    }
}
