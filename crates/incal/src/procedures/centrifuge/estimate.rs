//! The estimate of a centrifuge calibration (steps 5–6 of the module docs
//! of [`super`]): one input vector (K1, K0, the raw means and regression
//! parameters behind the radii, each station's c2, q, c3 and the type-B
//! alignment Δc2), the physical coefficients as linear combinations of it
//! (He & Yin 2017 eq. 2–3), the radius quantities (`joint_radius`), one GUM
//! propagation of everything through [`Estimates::map`] (JCGM 100 §5.2) and
//! the budget of every coefficient.

use std::collections::BTreeMap;
use std::ops::Range;

use nalgebra::{DMatrix, DVector};

use crate::error::Result;
use crate::estimation::{numeric_jacobian, Estimates};
use crate::models::Term;
use crate::rigs::centrifuge::Plane;

use super::budget::{delta_c2, Budget, BudgetLine, UncertaintyType};
use super::joint_radius::{push_radius_inputs, RadiusInputs, RadiusMap};
use super::options::CentrifugeOptions;
use super::stations::{is_axis, is_key, plane_terms, station_label, Station};
use super::CENTRIFUGE_TERMS;

/// A physical coefficient as a linear combination of inputs.
type Combo = Vec<(usize, f64)>;

/// `a += f·b`, merging the terms of the same input.
fn add(a: &mut Combo, b: &Combo, f: f64) {
    for (k, c) in b {
        if let Some(e) = a.iter_mut().find(|(j, _)| j == k) {
            e.1 += f * c;
        } else {
            a.push((*k, f * c));
        }
    }
}

/// Each coefficient's combination of inputs and, for a cross coupling, the
/// index of its cross station.
type Combos = BTreeMap<Term, (Combo, Option<usize>)>;

/// What [`estimate`] gives [`calibrate`](super::calibrate).
pub(super) struct Estimated {
    /// The coefficients (leading block of `joint`, dof of their inputs).
    pub(super) coefficients: Estimates,
    /// Coefficients and radius quantities (`CentrifugeResult::joint`).
    pub(super) joint: Estimates,
    /// Budget of every coefficient.
    pub(super) budgets: Vec<Budget>,
    /// Coefficients the data cannot give, with the reason.
    pub(super) unsupported: Vec<(Term, String)>,
}

/// The joint input vector, built block by block.
#[derive(Default)]
pub(super) struct Inputs {
    /// Name of each input.
    pub(super) names: Vec<String>,
    /// Value of each input.
    pub(super) values: Vec<f64>,
    /// Covariance blocks: (first index, block).
    pub(super) blocks: Vec<(usize, DMatrix<f64>)>,
    /// Covariances between blocks: (j, k, C_jk).
    pub(super) cross: Vec<(usize, usize, f64)>,
    /// How each input's u was evaluated.
    pub(super) kind: Vec<UncertaintyType>,
    /// Degrees of freedom of each input.
    pub(super) dof: Vec<f64>,
    /// Station index of each input (None for K1).
    pub(super) station: Vec<Option<usize>>,
}

impl Inputs {
    /// Append the inputs `items` (name, value) with their covariance block
    /// `cov`, all of one `kind` and `dof`, for `station`; the index of the
    /// first.
    pub(super) fn push_block(
        &mut self,
        station: Option<usize>,
        kind: UncertaintyType,
        items: Vec<(String, f64)>,
        cov: DMatrix<f64>,
        dof: f64,
    ) -> usize {
        let first = self.names.len();
        for (n, v) in items {
            self.names.push(n);
            self.values.push(v);
            self.kind.push(kind);
            self.dof.push(dof);
            self.station.push(station);
        }
        self.blocks.push((first, cov));
        first
    }

    /// The covariance of all the inputs: the blocks on the diagonal and
    /// the cross terms between blocks.
    pub(super) fn covariance(&self) -> DMatrix<f64> {
        let n = self.names.len();
        let mut c = DMatrix::zeros(n, n);
        for (first, b) in &self.blocks {
            c.view_mut((*first, *first), b.shape()).copy_from(b);
        }
        for &(j, k, v) in &self.cross {
            c[(j, k)] = v;
            c[(k, j)] = v;
        }
        c
    }
}

/// The IA-radial stations, in order of preference (plane, φ0 in deg).
const IA_KEYS: [(Plane, f64); 2] = [(Plane::Ip, 0.0), (Plane::Io, 0.0)];
/// The PA-radial stations.
const PA_KEYS: [(Plane, f64); 2] = [(Plane::Ip, 90.0), (Plane::Po, 0.0)];
/// The OA-radial stations.
const OA_KEYS: [(Plane, f64); 2] = [(Plane::Io, 90.0), (Plane::Po, 90.0)];

/// Coefficients, radius quantities and budgets from one propagation of one
/// input vector (module docs, [`CentrifugeResult::joint`]). Sets the
/// alignment Δc2 (eq. 8) and the type-B half-width of every station.
///
/// [`CentrifugeResult::joint`]: super::CentrifugeResult::joint
pub(super) fn estimate(
    stations: &mut [Station],
    station_errors: &[(String, String)],
    radii: &RadiusInputs,
    opts: &CentrifugeOptions,
) -> Result<Estimated> {
    // Inputs: K1, then per station c2 (with q, c3 at the IA station), dc2.
    let mut inp = Inputs::default();
    let k1_idx = inp.push_block(
        None,
        UncertaintyType::B,
        vec![("K1".into(), opts.k1_u().value)],
        DMatrix::from_element(1, 1, opts.k1_u().u.powi(2)),
        f64::INFINITY,
    );
    // Radius inputs: K0 and E0 (tilt, static radii), then per polarity E_a
    // and the regression parameters. They follow K1 so that a coefficient
    // budget (lines in input order, zero sensitivities left out) is as
    // before.
    let radius_map = push_radius_inputs(&mut inp, k1_idx, radii, opts)?;
    let radius_inputs = k1_idx + 1..inp.names.len();
    let at = push_station_inputs(&mut inp, stations, find_station(stations, &IA_KEYS))?;
    let (combos, unsupported) = coefficient_combos(stations, station_errors, &at);
    set_alignment_dc2(
        stations,
        &mut inp,
        &combos,
        &at.dc2,
        opts.alignment_tolerance_rad(),
    );

    // Requested subset, report order.
    let order: Vec<Term> = CENTRIFUGE_TERMS
        .iter()
        .copied()
        .filter(|t| combos.contains_key(t))
        .filter(|t| opts.terms.as_ref().is_none_or(|r| r.contains(t)))
        .collect();
    let coefficient_map = CoefficientMap {
        rows: order.iter().map(|t| combos[t].0.clone()).collect(),
        k1: k1_idx,
        k1_used: opts.k1_u().value,
        n_in: inp.names.len(),
    };
    let joint = propagate(
        &inp,
        &order,
        &combos,
        &coefficient_map,
        &radius_map,
        radius_inputs,
    )?;
    let budgets = coefficient_budgets(&order, &combos, &joint, &inp, stations);
    Ok(Estimated {
        coefficients: joint.coefficients,
        joint: joint.joint,
        budgets,
        unsupported,
    })
}

/// Where each station's inputs sit in the joint input vector.
struct StationInputs {
    /// Station index → index of its c2.
    c2: BTreeMap<usize, usize>,
    /// Station index → index of its alignment Δc2 (type B).
    dc2: BTreeMap<usize, usize>,
    /// (station index, `q` or `c3`) → index (IA-radial station only).
    extra: BTreeMap<(usize, &'static str), usize>,
}

impl StationInputs {
    /// A radial coefficient read directly at station `k`: `c2 + Δc2`.
    fn direct(&self, k: usize) -> Combo {
        vec![(self.c2[&k], 1.0), (self.dc2[&k], 1.0)]
    }
}

/// Push every station's c2 (with q and c3 at the IA-radial station `ia`;
/// the covariance block of its fit) and its alignment Δc2 (0 ± 0 until
/// [`set_alignment_dc2`]).
fn push_station_inputs(
    inp: &mut Inputs,
    stations: &[Station],
    ia: Option<usize>,
) -> Result<StationInputs> {
    let mut c2_idx: BTreeMap<usize, usize> = BTreeMap::new();
    let mut dc2_idx: BTreeMap<usize, usize> = BTreeMap::new();
    let mut extra: BTreeMap<(usize, &'static str), usize> = BTreeMap::new();
    for (k, s) in stations.iter().enumerate() {
        let mut items = vec![(format!("c2({})", s.label()), s.c2.value)];
        let mut which = vec!["c2"];
        if Some(k) == ia {
            if s.q.is_some() {
                items.push((format!("q({})", s.label()), s.q.map_or(0.0, |v| v.value)));
                which.push("q");
            }
            if s.c3.is_some() {
                items.push((format!("c3({})", s.label()), s.c3.map_or(0.0, |v| v.value)));
                which.push("c3");
            }
        }
        let sel: Vec<&str> = which.clone();
        let block = s.fit.estimates.select(&sel)?;
        let first = inp.push_block(
            Some(k),
            UncertaintyType::A,
            items,
            block.covariance().clone(),
            s.fit.estimates.dof(),
        );
        for (j, w) in which.iter().enumerate() {
            if *w == "c2" {
                c2_idx.insert(k, first + j);
            } else {
                extra.insert((k, w), first + j);
            }
        }
        let d = inp.push_block(
            Some(k),
            UncertaintyType::B,
            vec![(format!("alignment dc2({})", s.label()), 0.0)],
            DMatrix::zeros(1, 1),
            f64::INFINITY,
        );
        dc2_idx.insert(k, d);
    }
    Ok(StationInputs {
        c2: c2_idx,
        dc2: dc2_idx,
        extra,
    })
}

/// Index of the first station of `keys` (plane, φ0 in deg) that was
/// fitted.
fn find_station(stations: &[Station], keys: &[(Plane, f64)]) -> Option<usize> {
    keys.iter()
        .find_map(|(p, d)| stations.iter().position(|s| is_key(s, *p, *d)))
}

/// The station of `keys` for a `what` coefficient, or why there is none:
/// a station of `keys` that could not be fitted, or none recorded.
fn need_station(
    stations: &[Station],
    station_errors: &[(String, String)],
    keys: &[(Plane, f64)],
    what: &str,
) -> std::result::Result<usize, String> {
    find_station(stations, keys).ok_or_else(|| {
        failed_station(station_errors, keys).unwrap_or_else(|| {
            format!(
                "needs a {what} station ({})",
                keys.iter()
                    .map(|(p, d)| format!("{},{}", p.name(), d))
                    .collect::<Vec<_>>()
                    .join(" or ")
            )
        })
    })
}

/// Why the first station of `keys` that could not be fitted failed.
fn failed_station(station_errors: &[(String, String)], keys: &[(Plane, f64)]) -> Option<String> {
    keys.iter().find_map(|(p, d)| {
        let l = station_label(*p, d.to_radians());
        station_errors
            .iter()
            .find(|(s, _)| *s == l)
            .map(|(s, e)| format!("station {s} could not be fitted: {e}"))
    })
}

/// The cross station of `plane`: off the axes, nearest 45°.
fn cross_station(stations: &[Station], plane: Plane) -> Option<usize> {
    stations
        .iter()
        .enumerate()
        .filter(|(_, s)| s.plane == plane && !is_axis(s))
        .min_by(|a, b| {
            let da = (a.1.phi_rad.to_degrees() - 45.0).abs();
            let db = (b.1.phi_rad.to_degrees() - 45.0).abs();
            da.total_cmp(&db)
        })
        .map(|(k, _)| k)
}

/// Every coefficient the stations give as a combination of inputs, and
/// those they cannot give with the reason (module docs, step 5).
fn coefficient_combos(
    stations: &[Station],
    station_errors: &[(String, String)],
    at: &StationInputs,
) -> (Combos, Vec<(Term, String)>) {
    let mut combos = Combos::new();
    let mut unsupported: Vec<(Term, String)> = Vec::new();
    radial_combos(stations, station_errors, at, &mut combos, &mut unsupported);
    cross_combos(stations, at, &mut combos, &mut unsupported);
    (combos, unsupported)
}

/// The coefficients of the radial stations: K2, K3, K_oq (IA radial),
/// K_pp (PA radial), K_oo (OA radial).
fn radial_combos(
    stations: &[Station],
    station_errors: &[(String, String)],
    at: &StationInputs,
    combos: &mut Combos,
    unsupported: &mut Vec<(Term, String)>,
) {
    match need_station(stations, station_errors, &IA_KEYS, "IA-radial") {
        Ok(k) => {
            combos.insert(Term::K2, (at.direct(k), None));
            match at.extra.get(&(k, "c3")) {
                Some(&j) => {
                    combos.insert(Term::K3, (vec![(j, 1.0)], None));
                }
                None => unsupported.push((Term::K3, "needs model order 3".into())),
            }
            match at.extra.get(&(k, "q")) {
                Some(&j) => {
                    combos.insert(Term::Koq, (vec![(j, 1.0)], None));
                }
                None => unsupported.push((
                    Term::Koq,
                    "needs both polarities at the IA-radial station (the odd quadratic is separated from K2 only by the polarity reversal)".into(),
                )),
            }
        }
        Err(why) => {
            for t in [Term::K2, Term::K3, Term::Koq] {
                unsupported.push((t, why.clone()));
            }
        }
    }
    match need_station(stations, station_errors, &PA_KEYS, "PA-radial") {
        Ok(k) => {
            combos.insert(Term::Kpp, (at.direct(k), None));
        }
        Err(why) => unsupported.push((Term::Kpp, why)),
    }
    match need_station(stations, station_errors, &OA_KEYS, "OA-radial") {
        Ok(k) => {
            combos.insert(Term::Koo, (at.direct(k), None));
        }
        Err(why) => unsupported.push((Term::Koo, why)),
    }
}

/// The cross couplings K_ip, K_io, K_po from each plane's cross station
/// and the radial coefficients of its axes (eq. 2–3):
/// `K_ab = (c2 − K_aa cos²φ0 − K_bb sin²φ0) / (sinφ0 cosφ0)`.
fn cross_combos(
    stations: &[Station],
    at: &StationInputs,
    combos: &mut Combos,
    unsupported: &mut Vec<(Term, String)>,
) {
    for plane in [Plane::Ip, Plane::Io, Plane::Po] {
        let (ta, tb, tab) = plane_terms(plane);
        let Some(k) = cross_station(stations, plane) else {
            unsupported.push((
                tab,
                format!(
                    "needs a cross station in plane {} at an angle off the axes (e.g. {},45)",
                    plane.name(),
                    plane.name()
                ),
            ));
            continue;
        };
        let (Some((ca, _)), Some((cb, _))) = (combos.get(&ta).cloned(), combos.get(&tb).cloned())
        else {
            unsupported.push((
                tab,
                format!("needs {ta} and {tb} from their radial stations"),
            ));
            continue;
        };
        let (s, c) = stations[k].phi_rad.sin_cos();
        let mut combo = Vec::new();
        add(&mut combo, &at.direct(k), 1.0 / (s * c));
        add(&mut combo, &ca, -c * c / (s * c));
        add(&mut combo, &cb, -s * s / (s * c));
        combos.insert(tab, (combo, Some(k)));
    }
}

/// The alignment Δc2 of every station and polarity (eq. 8) at the point
/// values of the coefficients (Δc2 inputs 0), and the variance of each
/// station's type-B Δc2 input: uniform with half-width
/// `|dc2/dφ| (|Δφ_net| + tolerance)` (module docs), `Δφ_net` the mean Δφ
/// over the polarities, `tolerance` in rad.
fn set_alignment_dc2(
    stations: &mut [Station],
    inp: &mut Inputs,
    combos: &Combos,
    dc2_idx: &BTreeMap<usize, usize>,
    tolerance: f64,
) {
    // Point values (dc2 inputs are 0), then the type-B half-widths.
    let value_of = |combo: &Combo| combo.iter().map(|(j, c)| c * inp.values[*j]).sum::<f64>();
    let point: BTreeMap<Term, f64> = combos.iter().map(|(t, (c, _))| (*t, value_of(c))).collect();
    let mut dc2_var: Vec<(usize, f64)> = Vec::new();
    for (k, s) in stations.iter_mut().enumerate() {
        let (ta, tb, tab) = plane_terms(s.plane);
        let g = |t: Term| point.get(&t).copied().unwrap_or(0.0);
        let (kaa, kbb, kab) = (g(ta), g(tb), g(tab));
        for a in &mut s.alignment {
            a.delta_c2 = delta_c2(kaa, kbb, kab, s.phi_rad, a.delta_phi_rad);
        }
        let net = s.alignment.iter().map(|a| a.delta_phi_rad).sum::<f64>()
            / s.alignment.len().max(1) as f64;
        let hw = delta_c2(kaa, kbb, kab, s.phi_rad, net.abs() + tolerance).abs();
        s.delta_c2_half_width = hw;
        dc2_var.push((dc2_idx[&k], hw * hw / 3.0));
    }
    for (j, v) in dc2_var {
        if let Some(b) = inp.blocks.iter_mut().find(|(f, _)| *f == j) {
            b.1[(0, 0)] = v;
        }
    }
}

/// The requested coefficients as functions of the joint input vector:
/// each a linear combination of inputs times `K1/K1_used` (c2 ∝ K1).
struct CoefficientMap {
    /// One combination per coefficient, in report order.
    rows: Vec<Combo>,
    /// Index of K1.
    k1: usize,
    /// K1 the `E/K1` were computed with.
    k1_used: f64,
    /// Number of inputs.
    n_in: usize,
}

impl CoefficientMap {
    /// The coefficients at `x`.
    fn values(&self, x: &DVector<f64>) -> DVector<f64> {
        DVector::from_iterator(
            self.rows.len(),
            self.rows
                .iter()
                .map(|c| x[self.k1] / self.k1_used * c.iter().map(|(j, a)| a * x[*j]).sum::<f64>()),
        )
    }

    /// Their Jacobian at `x` (analytic).
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(self.rows.len(), self.n_in);
        for (r, c) in self.rows.iter().enumerate() {
            let sum: f64 = c.iter().map(|(j, a)| a * x[*j]).sum();
            for (j, a) in c {
                m[(r, *j)] += x[self.k1] / self.k1_used * a;
            }
            m[(r, self.k1)] += sum / self.k1_used;
        }
        m
    }
}

/// The outcome of the joint propagation.
struct Joint {
    /// The input vector with its covariance.
    inputs: Estimates,
    /// Jacobian of the coefficients at the inputs (rows in report order).
    jacobian: DMatrix<f64>,
    /// Coefficients then radius quantities (`CentrifugeResult::joint`).
    joint: Estimates,
    /// The coefficients alone, with the dof of their own inputs.
    coefficients: Estimates,
}

/// One GUM propagation ([`Estimates::map`]) of the inputs to the
/// coefficients of `order` and the radius quantities; `radius_inputs` are
/// the indices of the radius inputs (each used by some radius quantity).
fn propagate(
    inp: &Inputs,
    order: &[Term],
    combos: &Combos,
    coefficient_map: &CoefficientMap,
    radius_map: &RadiusMap,
    radius_inputs: Range<usize>,
) -> Result<Joint> {
    let n_in = inp.names.len();
    let used_dof = order
        .iter()
        .flat_map(|t| combos[t].0.iter().map(|(j, _)| inp.dof[*j]))
        .fold(f64::INFINITY, f64::min);
    // Every radius input is used by some radius quantity.
    let joint_dof = inp.dof[radius_inputs]
        .iter()
        .copied()
        .fold(used_dof, f64::min);
    let inputs = Estimates::new(
        inp.names.clone(),
        DVector::from_vec(inp.values.clone()),
        inp.covariance(),
        joint_dof,
    )?;
    let x = inputs.values().clone();
    let j = coefficient_map.jacobian(&x);
    // Coefficient rows: analytic (a linear combination times K1/K1_used);
    // radius rows: central differences with the steps of
    // `Estimates::map_numeric`.
    let steps: Vec<f64> = (0..n_in)
        .map(|k| 1e-6 * x[k].abs().max(inputs.u_at(k)).max(1e-12))
        .collect();
    let radius_f = |x: &DVector<f64>| radius_map.values(x);
    let mut names: Vec<String> = order.iter().map(|t| t.name().to_string()).collect();
    names.extend(radius_map.eval(&x).into_iter().map(|(n, _)| n.to_string()));
    let joint = inputs.map(
        names,
        |x| {
            let c = coefficient_map.values(x);
            let r = radius_f(x);
            DVector::from_iterator(c.len() + r.len(), c.iter().chain(r.iter()).copied())
        },
        |x| {
            let jc = coefficient_map.jacobian(x);
            let jr = numeric_jacobian(&radius_f, x, &steps);
            let mut m = DMatrix::zeros(jc.nrows() + jr.nrows(), n_in);
            m.rows_mut(0, jc.nrows()).copy_from(&jc);
            m.rows_mut(jc.nrows(), jr.nrows()).copy_from(&jr);
            m
        },
    )?;
    let coef_names: Vec<&str> = order.iter().map(|t| t.name()).collect();
    let head = joint.select(&coef_names)?;
    let coefficients = Estimates::new(
        head.names().to_vec(),
        head.values().clone(),
        head.covariance().clone(),
        used_dof,
    )?;
    Ok(Joint {
        inputs,
        jacobian: j,
        joint,
        coefficients,
    })
}

/// The budget of every coefficient of `order`: one line per input with a
/// non-zero sensitivity, in input order (module docs, step 5).
fn coefficient_budgets(
    order: &[Term],
    combos: &Combos,
    joint: &Joint,
    inp: &Inputs,
    stations: &[Station],
) -> Vec<Budget> {
    let n_in = inp.names.len();
    order
        .iter()
        .enumerate()
        .map(|(r, t)| {
            let cross_station = combos[t].1;
            let mut lines = Vec::new();
            let mut own = Vec::new();
            let mut dofs = Vec::new();
            for k in 0..n_in {
                let sens = joint.jacobian[(r, k)];
                if sens == 0.0 {
                    continue;
                }
                let u = joint.inputs.u_at(k);
                lines.push(BudgetLine {
                    component: inp.names[k].clone(),
                    kind: inp.kind[k],
                    u,
                    sensitivity: sens,
                    contribution: sens.abs() * u,
                });
                own.push(cross_station.is_some() && inp.station[k] == cross_station);
                dofs.push(inp.dof[k]);
            }
            let paper = cross_station
                .is_some_and(|k| (stations[k].phi_rad.to_degrees() - 45.0).abs() < 1e-6);
            Budget::from_lines(t.name().to_string(), lines, &own, &dofs, paper)
        })
        .collect()
}
