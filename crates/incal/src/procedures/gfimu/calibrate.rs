//! Multi-position static calibration of a gyro-free unit (GFIMU note §"试验过程";
//! docs/src/gfimu.md).
//!
//! # Plan
//! The unit is set in static positions with a known specific force `f`
//! (g, unit frame): the six-position test puts each unit axis up and down
//! (`f = ±e_x, ±e_y, ±e_z`), any ≥ 6 known orientations work.
//!
//! # Sign convention
//! `+x` means a specific force of +1 g along the unit's x axis: the x axis
//! points **up** (the reading an accelerometer gives when its input axis
//! points up). The paper's "x axis along gravity" is ambiguous; this is the
//! convention of docs/src/gfimu.md.
//!
//! # Estimation
//! Per accelerometer, the position means `Ē_i` are fitted with
//! `Ē_i = K0 + Ks_x f_x,i + Ks_y f_y,i + Ks_z f_z,i` by
//! [`crate::estimation::fit_means`] (pooled-scatter weights, lack of fit
//! never hidden). For the six-position test with equal sample counts the
//! design is orthogonal and the fit equals the paper's closed forms
//! ([`six_position`]): `K0 = [(E1+E2)/2 + (E3+E4)/2 + (E5+E6)/2]/3`,
//! `Ks = [(E1−E2), (E3−E4), (E5−E6)]/2`.
//!
//! # Derived coefficients
//! With the nominal direction `l` and the cross axes `p, q` of
//! [`crate::models::gfimu::cross_axes`] (paper's cycle):
//! `k1 = Ksᵀl`, `k2 = Ksᵀp`, `k3 = Ksᵀq` (GFIMU note eq. 8–10, output/g),
//! scale factor `|Ks|`, small misalignments `α_p = atan2(k2, k1)`,
//! `α_q = atan2(k3, k1)` (rad) and the angle between Ks and l,
//! `θ = atan2(√(k2²+k3²), k1)` (rad), all with GUM propagation
//! ([`Estimates::map`], analytic Jacobians). θ ≥ 0 is biased upwards when
//! it is not much larger than its u.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, Vector3};

use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Estimates, Fit, Noise, PositionStats};
use crate::models::gfimu::{cross_axes, Geometry};

/// Names of the fitted linear parameters of each accelerometer.
pub const LINEAR_TERMS: [&str; 4] = ["K0", "Ks_x", "Ks_y", "Ks_z"];

/// Names of the derived coefficients of each accelerometer (module docs).
pub const DERIVED_TERMS: [&str; 7] = [
    "scale_factor",
    "k1",
    "k2",
    "k3",
    "misalignment_p_rad",
    "misalignment_q_rad",
    "misalignment_rad",
];

/// One static sample: the specific force applied and every accelerometer's
/// output, in geometry order.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticSample {
    /// Specific force at the unit, unit frame (g).
    pub specific_force_g: Vector3<f64>,
    /// Outputs `E_j` (output units), one per accelerometer of the geometry.
    pub outputs: Vec<f64>,
}

/// Options of [`calibrate`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CalibrateOptions {
    /// Noise policy of the position means ([`Noise`]).
    pub noise: Noise,
}

/// The three six-position estimates of K0 (x, y, z pairs) and their
/// agreement: the check of GFIMU note `K0 = (E1+E2)/2 = (E3+E4)/2 = (E5+E6)/2`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct K0Consistency {
    /// `(E1+E2)/2, (E3+E4)/2, (E5+E6)/2` (output).
    pub values: [f64; 3],
    /// Their standard uncertainties (output), from the fit's noise.
    pub u: [f64; 3],
    /// Largest `|K0_a − K0_b| / √(u_a² + u_b²)` over the three pairs.
    pub max_normalized_difference: f64,
}

/// Calibration of one accelerometer.
#[derive(Debug, Clone, PartialEq)]
pub struct AccelerometerCalibration {
    /// Name.
    pub name: String,
    /// Nominal sensitive direction (unit vector).
    pub nominal_direction: Vector3<f64>,
    /// K0 (output) and Ks_x, Ks_y, Ks_z (output/g) with covariance.
    pub linear: Estimates,
    /// Derived coefficients [`DERIVED_TERMS`] (output/g, rad).
    pub derived: Estimates,
    /// [`LINEAR_TERMS`] then [`DERIVED_TERMS`] with their joint covariance.
    pub joint: Estimates,
    /// The least-squares fit of the position means.
    pub fit: Fit,
    /// Standard deviation of one output sample from the pooled scatter
    /// within positions (output), `None` with one sample per position.
    pub noise_output: Option<f64>,
    /// The K0 check when the plan holds all six ±axis positions.
    pub k0_consistency: Option<K0Consistency>,
}

impl AccelerometerCalibration {
    /// K0 (output).
    pub fn k0(&self) -> f64 {
        self.linear.values()[0]
    }
    /// Ks (output/g).
    pub fn ks(&self) -> Vector3<f64> {
        let v = self.linear.values();
        Vector3::new(v[1], v[2], v[3])
    }
}

/// Result of [`calibrate`].
#[derive(Debug, Clone, PartialEq)]
pub struct GfimuCalibration {
    /// Per accelerometer, geometry order.
    pub accelerometers: Vec<AccelerometerCalibration>,
    /// Distinct positions (specific force, g) and their sample counts.
    pub positions: Vec<(Vector3<f64>, usize)>,
    /// Warnings (weak plan, lack of fit, inconsistent K0).
    pub warnings: Vec<crate::Warning>,
}

impl GfimuCalibration {
    /// The calibrated K0, Ks and sample noise of every accelerometer, in
    /// geometry order: the input of [`super::solve::solve`].
    pub fn calibrated(&self) -> Vec<super::solve::CalibratedAccelerometer> {
        self.accelerometers
            .iter()
            .map(|a| super::solve::CalibratedAccelerometer {
                k0: a.k0(),
                ks: a.ks(),
                noise_output: a.noise_output,
                u_k0: a.linear.u_at(0),
                u_ks: Vector3::new(a.linear.u_at(1), a.linear.u_at(2), a.linear.u_at(3)),
            })
            .collect()
    }
}

/// Paper's closed forms for one accelerometer from the six-position means
/// `E = [E1..E6]` (+x, −x, +y, −y, +z, −z; GFIMU note, docs/src/gfimu.md).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SixPosition {
    /// `(E1+E2)/2, (E3+E4)/2, (E5+E6)/2` (output).
    pub k0_by_axis: [f64; 3],
    /// Their mean (output).
    pub k0: f64,
    /// `[(E1−E2), (E3−E4), (E5−E6)]/2` (output/g).
    pub ks: Vector3<f64>,
    /// Paper's `k0, k1, k2, k3` for sensing axis `s`: `k0 = (E₊+E₋)/2`,
    /// `k1 = (E₊−E₋)/2`, `k2 = (2E_{p+} − E₊ − E₋)/2`,
    /// `k3 = (2E_{q+} − E₊ − E₋)/2` (for a: `k_a2 = (2E1−E5−E6)/2g`).
    pub paper: [f64; 4],
    /// The same `k2, k3` from the opposite positions:
    /// `(E₊ + E₋ − 2E_{p−})/2`, `(E₊ + E₋ − 2E_{q−})/2`.
    pub paper_cross_opposite: [f64; 2],
}

/// Paper's six-position formulas; `sensing_axis` 0 = x, 1 = y, 2 = z and
/// the cross axes follow the paper's cycle (x → y, z; y → z, x; z → x, y).
pub fn six_position(e: [f64; 6], sensing_axis: usize) -> Result<SixPosition> {
    if sensing_axis > 2 {
        return Err(Error::Unsupported(format!(
            "sensing axis {sensing_axis} (use 0, 1, 2)"
        )));
    }
    let pair = |k: usize| (e[2 * k], e[2 * k + 1]);
    let k0_by_axis = [0, 1, 2].map(|k| (pair(k).0 + pair(k).1) / 2.0);
    let ks = Vector3::from_fn(|k, _| (pair(k).0 - pair(k).1) / 2.0);
    let (sp, sm) = pair(sensing_axis);
    let (pp, pm) = pair((sensing_axis + 1) % 3);
    let (qp, qm) = pair((sensing_axis + 2) % 3);
    Ok(SixPosition {
        k0_by_axis,
        k0: k0_by_axis.iter().sum::<f64>() / 3.0,
        ks,
        paper: [
            (sp + sm) / 2.0,
            (sp - sm) / 2.0,
            (2.0 * pp - sp - sm) / 2.0,
            (2.0 * qp - sp - sm) / 2.0,
        ],
        paper_cross_opposite: [(sp + sm - 2.0 * pm) / 2.0, (sp + sm - 2.0 * qm) / 2.0],
    })
}

/// Grouping key of a specific force (1e-9 g resolution).
pub(super) fn key(f: &Vector3<f64>) -> [i64; 3] {
    [0, 1, 2].map(|k| (f[k] * 1e9).round() as i64)
}

/// Design of `[1, f_x, f_y, f_z]` at the positions.
pub fn design(positions: &[Vector3<f64>]) -> Result<Design> {
    let rows: Vec<Vec<f64>> = positions.iter().map(|f| vec![1.0, f.x, f.y, f.z]).collect();
    Design::from_rows(LINEAR_TERMS.iter().map(|s| s.to_string()).collect(), &rows)
}

/// `(K0, Ks)` with [`DERIVED_TERMS`] appended, analytic Jacobian (module
/// docs), joint covariance kept ([`Estimates::augment`]).
fn derive(linear: &Estimates, l: &Vector3<f64>) -> Result<Estimates> {
    let (p, q) = cross_axes(l);
    let ks_of = |x: &DVector<f64>| Vector3::new(x[1], x[2], x[3]);
    let f = |x: &DVector<f64>| {
        let s = ks_of(x);
        let (k1, k2, k3) = (s.dot(l), s.dot(&p), s.dot(&q));
        DVector::from_vec(vec![
            s.norm(),
            k1,
            k2,
            k3,
            k2.atan2(k1),
            k3.atan2(k1),
            k2.hypot(k3).atan2(k1),
        ])
    };
    let jac = |x: &DVector<f64>| {
        let s = ks_of(x);
        let (k1, k2, k3) = (s.dot(l), s.dot(&p), s.dot(&q));
        let n = s.norm();
        let r = k2.hypot(k3);
        let rows: [Vector3<f64>; 7] = [
            if n > 0.0 { s / n } else { Vector3::zeros() },
            *l,
            p,
            q,
            (p * k1 - l * k2) / (k1 * k1 + k2 * k2),
            (q * k1 - l * k3) / (k1 * k1 + k3 * k3),
            if r > 0.0 {
                ((p * k2 + q * k3) * (k1 / r) - l * r) / (k1 * k1 + r * r)
            } else {
                Vector3::zeros()
            },
        ];
        let mut j = DMatrix::zeros(7, 4);
        for (i, g) in rows.iter().enumerate() {
            for c in 0..3 {
                j[(i, c + 1)] = g[c];
            }
        }
        j
    };
    linear.augment(
        DERIVED_TERMS.iter().map(|s| s.to_string()).collect(),
        f,
        jac,
    )
}

/// Calibrate every accelerometer of `geometry` from static samples
/// (module docs). Refuses fewer than 6 distinct positions and a plan whose
/// design cannot separate K0 and the three Ks components (naming them).
pub fn calibrate(
    geometry: &Geometry,
    samples: &[StaticSample],
    opts: &CalibrateOptions,
) -> Result<GfimuCalibration> {
    let n_acc = geometry.len();
    let mut index: BTreeMap<[i64; 3], usize> = BTreeMap::new();
    let mut groups: Vec<(Vector3<f64>, Vec<Vec<f64>>)> = Vec::new();
    for (k, s) in samples.iter().enumerate() {
        if s.outputs.len() != n_acc {
            return Err(Error::Unsupported(format!(
                "sample {}: {} outputs for {n_acc} accelerometers",
                k + 1,
                s.outputs.len()
            )));
        }
        if let Some(v) = s
            .specific_force_g
            .iter()
            .chain(s.outputs.iter())
            .find(|v| !v.is_finite())
        {
            return Err(Error::InvalidValue {
                what: format!("sample {}", k + 1),
                value: v.to_string(),
            });
        }
        let slot = *index.entry(key(&s.specific_force_g)).or_insert_with(|| {
            groups.push((s.specific_force_g, vec![Vec::new(); n_acc]));
            groups.len() - 1
        });
        for (j, e) in s.outputs.iter().enumerate() {
            groups[slot].1[j].push(*e);
        }
    }
    if groups.len() < 6 {
        return Err(Error::TooFew {
            what: "distinct static positions (orientations) for K0 and Ks".into(),
            needed: 6,
            got: groups.len(),
        });
    }
    let forces: Vec<Vector3<f64>> = groups.iter().map(|g| g.0).collect();
    let d = design(&forces)?;
    let mut warnings = Vec::new();
    let mut accelerometers = Vec::with_capacity(n_acc);
    // Indices of the six ±axis positions, if all present.
    let axis_pos: Option<[usize; 6]> = {
        let mut idx = [usize::MAX; 6];
        for (i, f) in forces.iter().enumerate() {
            for k in 0..3 {
                for (m, sign) in [1.0, -1.0].into_iter().enumerate() {
                    let mut e = Vector3::zeros();
                    e[k] = sign;
                    if key(f) == key(&e) {
                        idx[2 * k + m] = i;
                    }
                }
            }
        }
        idx.iter().all(|&i| i != usize::MAX).then_some(idx)
    };
    for (j, acc) in geometry.accelerometers().iter().enumerate() {
        let stats: Vec<PositionStats> = groups
            .iter()
            .map(|g| PositionStats::of(&g.1[j]))
            .collect::<Result<_>>()?;
        let (fit, weights) = fit_means(&d, &stats, opts.noise)?;
        let linear = fit.estimates.clone();
        let joint = derive(&linear, &acc.direction)?;
        let derived = joint.select(&DERIVED_TERMS)?;
        let (s2, dof) = crate::estimation::pooled_variance(&stats);
        let noise_output = (dof > 0).then(|| s2.sqrt());
        // The check tests lack of fit itself, so it uses the noise from the
        // sample scatter (or the known σ), not the residual-inflated factor;
        // with one sample per position only the residuals are available.
        let prior_noise = matches!(opts.noise, Noise::Known { .. }) || dof > 0;
        let factor = if prior_noise {
            1.0
        } else {
            fit.variance_factor
        };
        let k0_consistency = axis_pos.map(|idx| {
            let mean = |i: usize| stats[idx[i]].mean;
            let var = |i: usize| factor / weights[idx[i]];
            let values = [0, 1, 2].map(|k| (mean(2 * k) + mean(2 * k + 1)) / 2.0);
            let u = [0, 1, 2].map(|k| (var(2 * k) + var(2 * k + 1)).sqrt() / 2.0);
            let mut worst: f64 = 0.0;
            for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                let den = (u[a] * u[a] + u[b] * u[b]).sqrt();
                if den > 0.0 {
                    worst = worst.max((values[a] - values[b]).abs() / den);
                }
            }
            K0Consistency {
                values,
                u,
                max_normalized_difference: worst,
            }
        });
        if let Some(c) = &k0_consistency {
            if c.max_normalized_difference > 3.0 {
                warnings.push(crate::Warning::new(
                    crate::WarningCode::InconsistentBias,
                    format!(
                        "accelerometer '{}': the three six-position K0 estimates disagree by up to {:.1} u (an even-order error term or a mis-set position)",
                        acc.name, c.max_normalized_difference
                    ),
                ));
            }
        }
        for w in fit.quality_warnings("an unmodelled term, a mis-set position or drift") {
            // The design (and so its conditioning) is shared by every
            // accelerometer: say it once.
            let w = if w.code == crate::WarningCode::WeakConditioning {
                w
            } else {
                w.prefixed(&format!("accelerometer '{}'", acc.name))
            };
            if !warnings.contains(&w) {
                warnings.push(w);
            }
        }
        accelerometers.push(AccelerometerCalibration {
            name: acc.name.clone(),
            nominal_direction: acc.direction,
            linear,
            derived,
            joint,
            fit,
            noise_output,
            k0_consistency,
        });
    }
    let positions = groups.iter().map(|g| (g.0, g.1[0].len())).collect();
    Ok(GfimuCalibration {
        accelerometers,
        positions,
        warnings,
    })
}

/// Test design for the calibration: the standard uncertainty every
/// accelerometer's K0 and Ks *will* have for a plan of static positions
/// (specific force, g), `samples` per position and a known output noise
/// σ (output) per sample, at nominal sensitivity `k1_out_per_g` along each
/// nominal direction. It is [`calibrate`] itself run on noise-free samples
/// with the noise known, so the plan and the reduction cannot disagree;
/// a plan that cannot separate K0 and Ks is refused with the same message.
pub fn plan(
    geometry: &Geometry,
    positions: &[Vector3<f64>],
    samples: usize,
    noise: f64,
    k1_out_per_g: f64,
) -> Result<GfimuCalibration> {
    crate::validity::require_plan_inputs(samples, noise, k1_out_per_g, "nominal K1")?;
    let mut data = Vec::with_capacity(positions.len() * samples);
    for f in positions {
        let outputs: Vec<f64> = geometry
            .accelerometers()
            .iter()
            .map(|a| k1_out_per_g * a.direction.dot(f))
            .collect();
        for _ in 0..samples {
            data.push(StaticSample {
                specific_force_g: *f,
                outputs: outputs.clone(),
            });
        }
    }
    calibrate(
        geometry,
        &data,
        &CalibrateOptions {
            noise: Noise::Known { sigma: noise },
        },
    )
}
