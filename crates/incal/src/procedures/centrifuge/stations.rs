//! Stations of a centrifuge run: the samples grouped by fixture position
//! (plane, angle modulo 180°, polarity, rate) into points and stations,
//! and the fit of one station with the polarity model of eq. 9 (He & Yin
//! 2017; module docs of [`super`]), with the ECM radius and alignment
//! error of each polarity from [`crate::rigs::centrifuge`].

use std::collections::BTreeMap;

use crate::error::{Error, Result};
use crate::estimation::{fit_means, Design, Fit, Noise, PositionStats};
use crate::models::Term;
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};

use super::radius::ValueU;
use super::Observation;

/// ECM radius and alignment error of one polarity at a station.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// ±1.
    pub polarity: i8,
    /// Distance of the ECM from the spin axis (m).
    pub radius_m: f64,
    /// True minus nominal radial angle Δφ (rad).
    pub delta_phi_rad: f64,
    /// c2 change this Δφ alone would cause (eq. 8), g/g².
    pub delta_c2: f64,
}

/// One point of a station fit (one polarity and rate): the abscissa and
/// the mean that eq. 9 fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationPoint {
    /// ±1.
    pub polarity: i8,
    /// Table rate ω (rad/s).
    pub omega_rad_s: f64,
    /// Centripetal input `x = R±(φ0)·(ω² + 2ωΩe sinΦ)/g_L` (g).
    pub input_g: f64,
    /// Samples, mean and scatter of `E/K1` (g).
    pub stats: PositionStats,
}

/// Fit of one station (plane, φ0), eq. 9.
#[derive(Debug, Clone, PartialEq)]
pub struct Station {
    /// Plane.
    pub plane: Plane,
    /// Nominal angle φ0 in [0, π) (rad).
    pub phi_rad: f64,
    /// Polarities present.
    pub polarities: Vec<i8>,
    /// Number of points (plane, angle, polarity, rate).
    pub points: usize,
    /// Quadratic coefficient (g/g²).
    pub c2: ValueU,
    /// Odd quadratic (g/g²), with both polarities.
    pub q: Option<ValueU>,
    /// Cubic coefficient (g/g³), with order 3.
    pub c3: Option<ValueU>,
    /// ECM alignment per polarity.
    pub alignment: Vec<Alignment>,
    /// Half-width of the uniform type-B Δc2 (g/g²).
    pub delta_c2_half_width: f64,
    /// The linear fit.
    pub fit: Fit,
    /// The points fitted, in the order of `fit.residuals`.
    pub point_data: Vec<StationPoint>,
}

impl Station {
    /// `plane,phi_deg` label.
    pub fn label(&self) -> String {
        station_label(self.plane, self.phi_rad)
    }
}

/// `plane,phi_deg` label of a station (φ rounded to the µ°).
pub(super) fn station_label(plane: Plane, phi_rad: f64) -> String {
    let d = (phi_rad.to_degrees() * 1e6).round() / 1e6;
    format!("{},{}", plane.name(), d)
}

/// The samples of one point: one position (φ normalised to [0°, 180°))
/// at one table rate.
pub(super) struct Point {
    pub(super) position: Position,
    pub(super) omega: f64,
    pub(super) samples: Vec<f64>,
}

/// Normalise (φ, polarity) to φ in [0°, 180°) and give a µ° key.
fn normalise(pos: &Position) -> (i64, Position) {
    let mut key = (pos.phi_rad.to_degrees() * 1e6).round() as i64;
    key = key.rem_euclid(360_000_000);
    let mut pol = pos.polarity;
    if key >= 180_000_000 {
        key -= 180_000_000;
        pol = -pol;
    }
    (
        key,
        Position {
            plane: pos.plane,
            phi_rad: (key as f64 / 1e6).to_radians(),
            polarity: pol,
        },
    )
}

/// Group into stations (plane, angle key) → points, in order of appearance.
pub(super) fn group(obs: &[Observation]) -> Vec<((Plane, i64), Vec<Point>)> {
    let mut stations: Vec<((Plane, i64), Vec<Point>)> = Vec::new();
    let mut index: BTreeMap<(Plane, i64), usize> = BTreeMap::new();
    let mut pindex: BTreeMap<(Plane, i64, i8, i64), (usize, usize)> = BTreeMap::new();
    for o in obs {
        let (key, pos) = normalise(&o.position);
        let s = *index.entry((pos.plane, key)).or_insert_with(|| {
            stations.push(((pos.plane, key), Vec::new()));
            stations.len() - 1
        });
        let wkey = (o.omega_rad_s * 1e9).round() as i64;
        let (si, pi) = *pindex
            .entry((pos.plane, key, pos.polarity, wkey))
            .or_insert_with(|| {
                stations[s].1.push(Point {
                    position: pos,
                    omega: o.omega_rad_s,
                    samples: Vec::new(),
                });
                (s, stations[s].1.len() - 1)
            });
        stations[si].1[pi].samples.push(o.output);
    }
    stations
}

/// The points whose output sits at the record's rail
/// ([`crate::validity::at_rail`]: a converter at full scale) removed from
/// `groups` (a station left with none goes too), named in a `saturated`
/// warning: a clipped point is never fitted.
pub(super) fn drop_clipped(
    groups: Vec<((Plane, i64), Vec<Point>)>,
    warnings: &mut Vec<crate::warning::Warning>,
) -> Vec<((Plane, i64), Vec<Point>)> {
    let all = groups.iter().flat_map(|g| &g.1).flat_map(|p| &p.samples);
    let (lo, hi) = all.fold((f64::INFINITY, f64::NEG_INFINITY), |a, y| {
        (a.0.min(*y), a.1.max(*y))
    });
    let points: Vec<&Point> = groups.iter().flat_map(|g| &g.1).collect();
    let n: Vec<usize> = points.iter().map(|p| p.samples.len()).collect();
    let rail: Vec<usize> = points
        .iter()
        .map(|p| p.samples.iter().filter(|y| **y == lo || **y == hi).count())
        .collect();
    let scatter: Vec<bool> = points
        .iter()
        .map(|p| {
            PositionStats::of(&p.samples)
                .is_ok_and(|st| crate::validity::scatters(st.n, st.mean, st.std))
        })
        .collect();
    let clipped = crate::validity::at_rail(&n, &rail, &scatter);
    if !clipped.contains(&true) {
        return groups;
    }
    let mut named = Vec::new();
    let mut k = 0;
    let mut out = Vec::new();
    for (key, pts) in groups {
        let mut kept = Vec::new();
        for p in pts {
            if clipped[k] {
                named.push(format!(
                    "{} {:+} at {:.6} rad/s",
                    station_label(key.0, (key.1 as f64 / 1e6).to_radians()),
                    p.position.polarity,
                    p.omega
                ));
            } else {
                kept.push(p);
            }
            k += 1;
        }
        if !kept.is_empty() {
            out.push((key, kept));
        }
    }
    let shown: Vec<&str> = named.iter().take(8).map(String::as_str).collect();
    warnings.push(crate::warning::Warning::new(
        crate::warning::WarningCode::Saturated,
        format!(
            "the output clips (most samples at the record's extreme output) at {}{}: left out of the fit",
            shown.join("; "),
            if named.len() > 8 { format!(" and {} more", named.len() - 8) } else { String::new() }
        ),
    ));
    out
}

/// Samples, mean and scatter of `E/K1` (g) of raw outputs `samples`.
pub(super) fn e_over_k1(samples: &[f64], k1: f64) -> Result<PositionStats> {
    let y: Vec<f64> = samples.iter().map(|e| e / k1).collect();
    PositionStats::of(&y)
}

/// The noise policy in g: a known σ (output units) divided by |K1|.
pub(super) fn noise_in_g(noise: Noise, k1: f64) -> Noise {
    match noise {
        Noise::Known { sigma } => Noise::Known {
            sigma: sigma / k1.abs(),
        },
        Noise::Auto => Noise::Auto,
    }
}

/// Axes (first, second) of a plane as model terms of their squares and
/// product: (K_aa, K_bb, K_ab).
pub(super) fn plane_terms(plane: Plane) -> (Term, Term, Term) {
    match plane {
        Plane::Ip => (Term::K2, Term::Kpp, Term::Kip),
        Plane::Io => (Term::K2, Term::Koo, Term::Kio),
        Plane::Po => (Term::Kpp, Term::Koo, Term::Kpo),
    }
}

/// Fit one station with the polarity model of eq. 9 (module docs).
pub(super) fn fit_station(
    plane: Plane,
    phi_rad: f64,
    points: &[Point],
    rig: &Centrifuge,
    order: usize,
    k1: f64,
    noise: Noise,
) -> Result<Station> {
    let mut pols: Vec<i8> = points.iter().map(|p| p.position.polarity).collect();
    pols.sort_unstable_by(|a, b| b.cmp(a));
    pols.dedup();
    let both = pols.len() == 2;
    let names = parameter_names(&pols, order);
    let mut rows = Vec::new();
    let mut stats = Vec::new();
    let mut point_data = Vec::with_capacity(points.len());
    for p in points {
        let x = rig.centripetal_g(&p.position, p.omega);
        rows.push(design_row(plane, phi_rad, p, x, &pols, rig, order));
        let st = e_over_k1(&p.samples, k1)?;
        point_data.push(StationPoint {
            polarity: p.position.polarity,
            omega_rad_s: p.omega,
            input_g: x,
            stats: st,
        });
        stats.push(st);
    }
    let design = Design::from_rows(names, &rows)?;
    let (fit, _) = fit_means(&design, &stats, noise)?;
    let get = |n: &str| fit.estimates.get(n).map(|(value, u)| ValueU { value, u });
    let c2 = get("c2").ok_or_else(|| Error::Unsupported("station fit lost c2".into()))?;
    let alignment = pols
        .iter()
        .map(|&pol| {
            let g = rig.geometry(&Position {
                plane,
                phi_rad,
                polarity: pol,
            });
            Alignment {
                polarity: pol,
                radius_m: g.radius_m,
                delta_phi_rad: g.delta_phi_rad,
                delta_c2: 0.0,
            }
        })
        .collect();
    Ok(Station {
        plane,
        phi_rad,
        polarities: pols,
        points: points.len(),
        c2,
        q: if both { get("q") } else { None },
        c3: if order >= 3 { get("c3") } else { None },
        alignment,
        delta_c2_half_width: 0.0,
        fit,
        point_data,
    })
}

/// Parameters of the eq. 9 fit of a station with polarities `pols`
/// (+ first): `b±`, `s±` per polarity, `c2`, `q` with both polarities,
/// `c3` with model order 3.
fn parameter_names(pols: &[i8], order: usize) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for p in pols {
        let s = if *p > 0 { "+" } else { "-" };
        names.push(format!("b{s}"));
        names.push(format!("s{s}"));
    }
    names.push("c2".into());
    if pols.len() == 2 {
        names.push("q".into());
    }
    if order >= 3 {
        names.push("c3".into());
    }
    names
}

/// The design row of point `p` at centripetal input `x` (g), in the order
/// of [`parameter_names`].
fn design_row(
    plane: Plane,
    phi_rad: f64,
    p: &Point,
    x: f64,
    pols: &[i8],
    rig: &Centrifuge,
    order: usize,
) -> Vec<f64> {
    let s = p.position.sign();
    // Odd terms follow the input axis, whose angle to the radial
    // direction is off by the ECM alignment error Δφ±, opposite in the
    // two polarities: scale them by w = cos(φ0 + Δφ±)/cos φ0 so that
    // the polarity-dependent part of K_oq·a_i|a_i| and K3·a_i³ does not
    // leak into the common c2.
    let w = if plane.ia_horizontal() && phi_rad.cos().abs() > 1e-6 {
        let d = rig.geometry(&p.position).delta_phi_rad;
        (phi_rad + d).cos() / phi_rad.cos()
    } else {
        1.0
    };
    let mut row = Vec::with_capacity(2 * pols.len() + 3);
    for q in pols {
        let on = if *q == p.position.polarity { 1.0 } else { 0.0 };
        row.push(on);
        row.push(on * s * x);
    }
    row.push(x * x);
    if pols.len() == 2 {
        row.push(s * (w * x).powi(2));
    }
    if order >= 3 {
        row.push(s * (w * x).powi(3));
    }
    row
}

/// The station is at `plane,deg`.
pub(super) fn is_key(s: &Station, plane: Plane, deg: f64) -> bool {
    s.plane == plane && ((s.phi_rad.to_degrees() - deg).abs() < 1e-6)
}

/// The station is on an axis of its plane (φ0 = 0° or 90°).
pub(super) fn is_axis(s: &Station) -> bool {
    let d = s.phi_rad.to_degrees();
    d.abs() < 1e-6 || (d - 90.0).abs() < 1e-6
}
