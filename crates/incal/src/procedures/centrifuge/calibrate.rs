//! The centrifuge calibration as a composition of its steps (module docs
//! of [`super`], He & Yin 2017): check the input, measure the radius at the
//! IA-radial station ([`super::ia_station`]), place the ECM, fit every
//! station ([`super::stations`]), propagate everything at once
//! ([`super::estimate`]) and give every radius the u of that propagation.

use crate::error::{Error, Result};
use crate::estimation::{Estimates, Noise};
use crate::models::Term;
use crate::rigs::centrifuge::{Centrifuge, Plane, Position};
use crate::warning::{Warning, WarningCode};

use super::budget::{self, Budget};
use super::estimate::{estimate, Estimated};
use super::ia_station::{measure_radius, RadiusMeasurement, RadiusRangeRow};
use super::joint_radius::RadiusInputs;
use super::options::{check_options, CentrifugeOptions};
use super::radius::{RadiusContext, RadiusFit, ValueU};
use super::stations::{fit_station, group, noise_in_g, station_label, Point, Station};
use super::Observation;

/// Everything a centrifuge calibration produces.
#[derive(Debug, Clone, PartialEq)]
pub struct CentrifugeResult {
    /// Label of the IA-radial station used for the radius.
    pub ia_station: Option<String>,
    /// Static tilt λ (rad), eq. 4 (`tilt_rad` of [`CentrifugeResult::joint`]).
    pub tilt_rad: Option<ValueU>,
    /// Static back-calculated radius (m) for polarity + and −, eq. 5–6,
    /// with the nonlinearity at the 1 g speed removed as
    /// [`correct_static_radius`](super::correct_static_radius) does when the regression gives K2 (K3):
    /// `R_plus_static_m` / `R_minus_static_m` of [`CentrifugeResult::joint`].
    pub static_radius: [Option<ValueU>; 2],
    /// The same radius exactly as eq. 5–6 compute it (nonlinearity ignored).
    pub static_radius_uncorrected: [Option<ValueU>; 2],
    /// Rate used for each static radius (rad/s).
    pub static_rate_rad_s: [Option<f64>; 2],
    /// Regression–iteration radius fits, polarity + and −, eq. 7; the u of
    /// each `radius_m` is that of `R_plus_m` / `R_minus_m` in
    /// [`CentrifugeResult::joint`].
    pub regression: [Option<RadiusFit>; 2],
    /// Radius for model orders 1–3 over growing ranges (Table 2).
    pub radius_table: Vec<RadiusRangeRow>,
    /// Fixture-centre radius R = (R+ + R−)/2 (m), `R_centre_m` of
    /// [`CentrifugeResult::joint`] (shared K1 included); the nominal radius
    /// with u = NaN when no regression radius was measured.
    pub centre_radius_m: ValueU,
    /// Signed ECM offset r = (R+ − R−)/2 (m), `ecm_offset_m` of
    /// [`CentrifugeResult::joint`]; 0 with u = NaN unless both polarities
    /// were measured.
    pub ecm_offset_m: ValueU,
    /// Station fits.
    pub stations: Vec<Station>,
    /// Stations that could not be fitted, with the reason.
    pub station_errors: Vec<(String, String)>,
    /// Physical coefficients (g units), in the order of
    /// [`CENTRIFUGE_TERMS`](super::CENTRIFUGE_TERMS), those available and requested: the leading
    /// block of [`CentrifugeResult::joint`] (same values and covariance),
    /// with `dof` the minimum over the inputs of the coefficients only
    /// (K1, the station fits, the type-B Δc2). The coefficient map depends
    /// on the same inputs as before the joint propagation, K1 once, so
    /// values and u are those of the coefficient map alone; K1 shows only
    /// in the cross-covariance with the radii.
    pub coefficients: Estimates,
    /// Coefficients and radius quantities from one GUM propagation
    /// ([`Estimates::map`]) of one input vector, with the full covariance.
    ///
    /// Names, in order, those available: the coefficients (as in
    /// [`CentrifugeResult::coefficients`]: `K2`, `K3`, `K_oq`, `K_pp`,
    /// `K_oo`, `K_ip`, `K_io`, `K_po`; g units), then
    /// * `R_plus_m`, `R_minus_m`: regression–iteration radii (m, eq. 7,
    ///   [`radius::radius_from_scale`](super::radius::radius_from_scale));
    /// * `R_plus_static_m`, `R_minus_static_m`: static radii (m, eq. 5–6,
    ///   [`radius::eq6_radius`](super::radius::eq6_radius), divided by the nonlinearity factor
    ///   `1 ± K2 a_g + K3 a_g²` of [`correct_static_radius`](super::correct_static_radius) with that
    ///   polarity's regression K2, K3 when there is a regression);
    /// * `R_centre_m = (R+ + R−)/2` (m, He & Yin 2017 §2.2; the one regression
    ///   radius when only one polarity was measured);
    /// * `ecm_offset_m = (R+ − R−)/2` (m, signed; both polarities only);
    /// * `tilt_rad`: λ = E0/K1 − K0 (rad, eq. 4).
    ///
    /// Inputs: K1 and K0 (u from the options), the at-rest mean E0 and the
    /// static-speed means E_a± (raw output, u = s/√n), each polarity's
    /// regression parameters (`b`, `scale`, `K2`, `K3`, covariance block of
    /// that fit), each station's c2 (with `q`, `c3` at the IA-radial
    /// station; covariance block of the station fit) and the type-B Δc2.
    /// K1 is one input: the scale of every `E/K1`, it is fully correlated
    /// between R+ and R− (`u²(R±) ⊃ (R± u(K1)/K1)²`, which does not average
    /// down in `R_centre_m`), between the radii and the tilt, and
    /// anti-correlated between the radii and the coefficients (a larger K1
    /// shrinks the radius and grows c2 ∝ K1). Blocks from different fits are
    /// independent: the regression fits and the IA-radial station fit share
    /// data, and that cross-covariance is not modelled. `dof`: the minimum
    /// over the inputs used (the raw means count as ∞, as for the static
    /// radius of [`radius::static_radius`](super::radius::static_radius)).
    pub joint: Estimates,
    /// Uncertainty budget of every coefficient.
    pub budgets: Vec<Budget>,
    /// Coefficients the data cannot give, with the reason.
    pub unsupported: Vec<(Term, String)>,
    /// Warnings.
    pub warnings: Vec<Warning>,
}

/// Calibrate from centrifuge observations (module docs); K0 and K1 as
/// [`CentrifugeOptions::resolve`] settles them (its warnings are the
/// procedure's, [`super::CentrifugeTest`]).
pub fn calibrate(obs: &[Observation], opts: &CentrifugeOptions) -> Result<CentrifugeResult> {
    let resolved = opts.resolve()?.options;
    let opts = &resolved;
    check_options(opts)?;
    check_observations(obs)?;
    let k1 = opts.k1_u().value;
    let noise = noise_in_g(opts.noise, k1);
    let ctx = radius_context(opts);
    let nominal = Centrifuge {
        r_plus_m: opts.radius_m,
        r_minus_m: opts.radius_m,
        latitude_rad: opts.latitude_rad(),
        g_local_m_s2: opts.gravity_m_s2,
        opposite_sense: opts.opposite_sense,
        tilt_rad: 0.0,
    };
    let mut warnings = Vec::new();
    let groups = super::stations::drop_clipped(group(obs), &mut warnings);

    // --- IA-radial station: tilt and radius -------------------------------
    let ia = [(Plane::Ip, 0i64), (Plane::Io, 0i64)]
        .iter()
        .find_map(|k| groups.iter().find(|g| g.0 == *k));
    let mut radius = match ia {
        Some((_, points)) => measure_radius(points, &nominal, opts, &ctx, noise, &mut warnings)?,
        None => {
            warnings.push(Warning::new(
                WarningCode::RadiusIncomplete,
                "no IA-radial station (ip,0 or io,0): radius not measured, nominal radius used",
            ));
            RadiusMeasurement::default()
        }
    };

    // --- ECM offset (values; u from the joint propagation below) ------------
    let (r_plus, r_minus) = ecm_radii(&radius.regression, opts.radius_m, &mut warnings);
    let (centre, offset) = budget::ecm_offset(r_plus, r_minus);
    let rig = Centrifuge {
        r_plus_m: r_plus,
        r_minus_m: r_minus,
        tilt_rad: 0.0,
        ..nominal
    };

    // --- stations ----------------------------------------------------------
    let (mut stations, station_errors) = fit_stations(&groups, &rig, opts.order, k1, noise);

    // --- coefficients and radii, one propagation ---------------------------
    let radius_inputs = RadiusInputs {
        e0: radius.e0,
        static_point: [0, 1].map(|k| radius.e_a[k].zip(radius.static_rate[k])),
        regression: [radius.regression[0].as_ref(), radius.regression[1].as_ref()],
    };
    let Estimated {
        coefficients,
        joint,
        budgets,
        unsupported,
    } = estimate(&mut stations, &station_errors, &radius_inputs, opts)?;
    check_coefficients(&coefficients, &unsupported, opts)?;
    station_warnings(&stations, &mut warnings);
    let (centre_radius_m, ecm_offset_m) =
        take_joint_radii(&joint, &mut radius, (centre, offset), opts.k1_u().value)?;
    Ok(CentrifugeResult {
        ia_station: ia.map(|g| station_label(g.0 .0, (g.0 .1 as f64 / 1e6).to_radians())),
        tilt_rad: radius.tilt,
        static_radius: radius.static_radius,
        static_radius_uncorrected: radius.static_uncorrected,
        static_rate_rad_s: radius.static_rate,
        regression: radius.regression,
        radius_table: radius.radius_table,
        centre_radius_m,
        ecm_offset_m,
        stations,
        station_errors,
        coefficients,
        joint,
        budgets,
        unsupported,
        warnings,
    })
}

/// Refuse no observation, a position off the fixture's planes and
/// polarities, and a rate or output that is not finite.
fn check_observations(obs: &[Observation]) -> Result<()> {
    if obs.is_empty() {
        return Err(Error::TooFew {
            what: "observations".into(),
            needed: 1,
            got: 0,
        });
    }
    for o in obs {
        Position::new(o.position.plane, o.position.phi_rad, o.position.polarity)?;
        crate::error::finite("rate omega", o.omega_rad_s)?;
        crate::error::finite("output", o.output)?;
    }
    Ok(())
}

/// What the radius formulas of [`radius`](super::radius) need from the options.
fn radius_context(opts: &CentrifugeOptions) -> RadiusContext {
    RadiusContext {
        k0_g: opts.k0_u(),
        k1: opts.k1_u(),
        latitude_rad: opts.latitude_rad(),
        g_local_m_s2: opts.gravity_m_s2,
        opposite_sense: opts.opposite_sense,
        u_omega_rel: opts.u_omega_ppm * 1e-6,
        known_sigma: match opts.noise {
            Noise::Known { sigma } => Some(sigma),
            Noise::Auto => None,
        },
    }
}

/// The ECM radii (R+, R−) (m) of the rig the stations are fitted with: the
/// regression radii; with one polarity measured, its radius for both (ECM
/// offset 0, with a warning); with none, the nominal radius `radius0_m`.
fn ecm_radii(
    regression: &[Option<RadiusFit>; 2],
    radius0_m: f64,
    warnings: &mut Vec<Warning>,
) -> (f64, f64) {
    match (&regression[0], &regression[1]) {
        (Some(p), Some(m)) => (p.radius_m.value, m.radius_m.value),
        (Some(p), None) => {
            warnings.push(Warning::new(
                WarningCode::RadiusIncomplete,
                "only polarity + measured: ECM offset taken as 0",
            ));
            (p.radius_m.value, p.radius_m.value)
        }
        (None, Some(m)) => {
            warnings.push(Warning::new(
                WarningCode::RadiusIncomplete,
                "only polarity - measured: ECM offset taken as 0",
            ));
            (m.radius_m.value, m.radius_m.value)
        }
        (None, None) => (radius0_m, radius0_m),
    }
}

/// Fit every station (eq. 9) on `rig`; the stations fitted, and the label
/// of each one that could not be with the reason.
fn fit_stations(
    groups: &[((Plane, i64), Vec<Point>)],
    rig: &Centrifuge,
    order: usize,
    k1: f64,
    noise: Noise,
) -> (Vec<Station>, Vec<(String, String)>) {
    let mut stations = Vec::new();
    let mut station_errors = Vec::new();
    for ((plane, key), points) in groups {
        let phi = (*key as f64 / 1e6).to_radians();
        match fit_station(*plane, phi, points, rig, order, k1, noise) {
            Ok(s) => stations.push(s),
            Err(e) => station_errors.push((station_label(*plane, phi), e.to_string())),
        }
    }
    (stations, station_errors)
}

/// Refuse a requested coefficient the stations cannot give, and a position
/// set that gives no coefficient at all (one reason per distinct cause).
fn check_coefficients(
    coefficients: &Estimates,
    unsupported: &[(Term, String)],
    opts: &CentrifugeOptions,
) -> Result<()> {
    if let Some(req) = &opts.terms {
        for t in req {
            if let Some((_, why)) = unsupported.iter().find(|(u, _)| u == t) {
                return Err(Error::Unsupported(format!(
                    "this position set cannot give {t}: {why}"
                )));
            }
        }
    }
    if coefficients.is_empty() {
        // One reason per distinct cause (terms sharing it listed together),
        // so the line stays readable; `incal plan centrifuge` says the rest.
        let mut why: Vec<(Vec<String>, &str)> = Vec::new();
        for (t, w) in unsupported {
            match why.iter_mut().find(|(_, r)| *r == w.as_str()) {
                Some((terms, _)) => terms.push(t.to_string()),
                None => why.push((vec![t.to_string()], w.as_str())),
            }
        }
        let shown: Vec<String> = why
            .iter()
            .take(2)
            .map(|(t, w)| format!("{}: {w}", t.join(", ")))
            .collect();
        let more = why.len().saturating_sub(2);
        return Err(Error::Unsupported(format!(
            "this position set gives no coefficient ({}{})",
            shown.join("; "),
            if more > 0 {
                format!("; and {more} more: see incal plan centrifuge")
            } else {
                String::new()
            }
        )));
    }
    Ok(())
}

/// Warnings about the station fits: one polarity only at a station whose
/// c2 then includes the odd quadratic, and each fit's quality warnings.
fn station_warnings(stations: &[Station], warnings: &mut Vec<Warning>) {
    for s in stations {
        let c = s.phi_rad.cos();
        if let ([pol], true) = (&s.polarities[..], s.plane.ia_horizontal() && c.abs() > 1e-6) {
            let sign = if *pol > 0 { "+" } else { "-" };
            warnings.push(Warning::new(
                WarningCode::OnePolarity,
                format!(
                    "one polarity only at {}: the odd quadratic cannot be separated there, its c2 includes {sign}{:.3}*K_oq",
                    s.label(),
                    c * c
                ),
            ));
        }
    }
    for s in stations {
        for w in s
            .fit
            .quality_warnings("a model order too low for the speed range, drift, or rig vibration")
        {
            warnings.push(w.prefixed(&format!("station {}", s.label())));
        }
    }
}

/// Give every radius field of `radius` the value and u of the joint
/// propagation (`joint`), and return the centre radius and the ECM offset
/// (m) from it (`centre_offset`, with u = NaN, when it has none). Refuses
/// a radius that is not positive: the sign of K1 (`k1`) or K0 does not
/// match the output, and every coefficient would be sign-flipped nonsense.
fn take_joint_radii(
    joint: &Estimates,
    radius: &mut RadiusMeasurement,
    (centre, offset): (f64, f64),
    k1: f64,
) -> Result<(ValueU, ValueU)> {
    // Every radius field carries the u of the joint propagation.
    let ju = |name: &str| joint.get(name).map(|(value, u)| ValueU { value, u });
    for (k, name) in [(0usize, "R_plus_m"), (1, "R_minus_m")] {
        if let (Some(f), Some(v)) = (radius.regression[k].as_mut(), ju(name)) {
            f.radius_m.u = v.u;
        }
    }
    for (k, name) in [(0usize, "R_plus_static_m"), (1, "R_minus_static_m")] {
        if let Some(v) = ju(name) {
            radius.static_radius[k] = Some(v);
        }
    }
    let centre_radius_m = ju("R_centre_m").unwrap_or(ValueU {
        value: centre,
        u: f64::NAN,
    });
    // A radius is a length: a negative one means the scale factor's sign
    // (or K0) does not match the output, and every coefficient would be
    // sign-flipped nonsense.
    for (name, v) in [
        ("R_centre_m", Some(centre_radius_m)),
        ("R_plus_m", ju("R_plus_m")),
        ("R_minus_m", ju("R_minus_m")),
        ("R_plus_static_m", radius.static_radius[0]),
        ("R_minus_static_m", radius.static_radius[1]),
    ] {
        if let Some(v) = v {
            if !(v.value.is_finite() && v.value > 0.0) {
                return Err(Error::Unsupported(format!(
                    "the fitted radius {name} = {:.6} m is not positive: the sign of K1 ({}) does not match the output's response to the rate (check --k1 and the polarity)",
                    v.value, k1
                )));
            }
        }
    }
    let ecm_offset_m = ju("ecm_offset_m").unwrap_or(ValueU {
        value: offset,
        u: f64::NAN,
    });
    if let Some(v) = ju("tilt_rad") {
        radius.tilt = Some(v);
    }
    Ok((centre_radius_m, ecm_offset_m))
}
