//! Centrifuge round trips with honest uncertainty (docs/src/centrifuge.md, He & Yin 2017):
//! simulate from a known truth with an ECM offset, IA tilt and the Earth
//! rate, calibrate, and count how often the truth lies within the reported
//! uncertainty.

use incal::estimation::Noise;
use incal::models::{AccelerometerModel, Term};
use incal::procedures::centrifuge::radius::ValueU;
use incal::procedures::centrifuge::{calibrate, CentrifugeOptions, CENTRIFUGE_TERMS};
use incal::rigs::centrifuge::{Centrifuge, Plane, Position};
use incal::sim::centrifuge::{rates_for_levels, simulate, standard_positions, CentrifugeSim};
use incal::sim::monte_carlo;

const G: f64 = 9.8012;
const R0: f64 = 0.71;

fn truth() -> AccelerometerModel {
    AccelerometerModel {
        k0_g: 1.2e-4,
        k1_out_per_g: 1.3,
        k2: 3.9e-6,
        k3: 5.0e-9,
        delta_o_rad: 2e-4,
        delta_p_rad: -1e-4,
        k_ip: 7.0e-6,
        k_io: 2.0e-6,
        k_po: -1.0e-6,
        k_pp: 4.6e-7,
        k_oo: -3.0e-7,
        k_oq: 5.0e-7,
    }
}

fn rig() -> Centrifuge {
    Centrifuge {
        r_plus_m: 0.714775,
        r_minus_m: 0.705794,
        latitude_rad: 39.9f64.to_radians(),
        g_local_m_s2: G,
        opposite_sense: false,
        tilt_rad: 3e-4,
    }
}

fn levels() -> Vec<f64> {
    vec![0.0, 1.0, 2.0, 4.0, 7.0, 10.0, 14.0, 18.0, 22.0, 25.0]
}

fn sim(seed: u64, positions: Vec<Position>) -> CentrifugeSim {
    CentrifugeSim {
        truth: truth(),
        rig: rig(),
        positions,
        rates_rad_s: rates_for_levels(&levels(), R0, G),
        samples: 5,
        noise: 2e-6,
        seed,
    }
}

fn options(order: usize) -> CentrifugeOptions {
    let t = truth();
    CentrifugeOptions {
        from: None,
        k0: Some(t.k0_g),
        u_k0: Some(0.0),
        k1: Some(t.k1_out_per_g),
        u_k1: Some(0.0),
        cov_k0_k1: Some(0.0),
        radius_m: R0,
        latitude_deg: 39.9,
        gravity_m_s2: G,
        opposite_sense: false,
        order,
        alignment_tolerance_deg: 0.0,
        noise: Noise::Auto,
        terms: None,
        u_omega_ppm: 0.0,
    }
}

/// Every coefficient, both regression radii, the ECM offset and both
/// static radii: the truth lies within ±2u
/// in 90–99 % of 300 trials. The variances come from the pooled sample
/// scatter (4 degrees of freedom per point, > 200 per station), so the
/// normal ±2u rate (95.4 %) applies.
#[test]
fn every_coefficient_and_radius_within_2u_at_95_percent() {
    let t = truth();
    let r = rig();
    let trials = 300;
    let runs = monte_carlo(11, trials, |s| {
        let obs = simulate(&sim(s, standard_positions()));
        let res = calibrate(&obs, &options(3)).expect("calibrates");
        let mut hits: Vec<bool> = CENTRIFUGE_TERMS
            .iter()
            .map(|term| {
                let (v, u) = res.coefficients.get(term.name()).expect("coefficient");
                (v - t.get(*term)).abs() <= 2.0 * u
            })
            .collect();
        // The regression radius is the effective one: at ip,0 the 1 g on OA
        // turns K_io into a scale error (1 + K_io) that the radius absorbs.
        let eff = 1.0 + t.k_io;
        for (k, truth_r) in [r.r_plus_m * eff, r.r_minus_m * eff]
            .into_iter()
            .enumerate()
        {
            let f = res.regression[k].as_ref().expect("radius");
            hits.push((f.radius_m.value - truth_r).abs() <= 2.0 * f.radius_m.u);
        }
        let ecm = res.ecm_offset_m;
        hits.push((ecm.value - r.ecm_offset_m() * eff).abs() <= 2.0 * ecm.u);
        // The static radii (eq. 5–6, nonlinearity at 1 g removed) measure
        // the same effective radius.
        for (k, truth_r) in [r.r_plus_m * eff, r.r_minus_m * eff]
            .into_iter()
            .enumerate()
        {
            let st = res.static_radius[k].expect("static radius");
            hits.push((st.value - truth_r).abs() <= 2.0 * st.u);
        }
        hits
    });
    let mut names: Vec<String> = CENTRIFUGE_TERMS.iter().map(|t| t.to_string()).collect();
    names.extend([
        "R+".into(),
        "R-".into(),
        "r".into(),
        "static R+".into(),
        "static R-".into(),
    ]);
    for (k, name) in names.iter().enumerate() {
        let rate = runs.iter().filter(|h| h[k]).count() as f64 / trials as f64;
        assert!((0.90..=0.99).contains(&rate), "{name}: {rate}");
    }
}

/// He & Yin 2017 Table 2: a first-order regression on data with K2 ≠ 0 drifts
/// with the range (the quadratic term leaks into the scale), while orders 2
/// and 3 barely move, and order 3 (the truth has K3 ≠ 0) recovers the
/// effective radius within its u.
#[test]
fn first_order_radius_drifts_with_range() {
    let obs = simulate(&CentrifugeSim {
        positions: vec![
            Position::new(Plane::Ip, 0.0, 1).unwrap(),
            Position::new(Plane::Ip, 0.0, -1).unwrap(),
        ],
        ..sim(5, vec![])
    });
    let mut o = options(2);
    o.terms = Some(vec![Term::K2]);
    let res = calibrate(&obs, &o).unwrap();
    for pol in [1i8, -1] {
        let rows: Vec<_> = res
            .radius_table
            .iter()
            .filter(|r| r.polarity == pol)
            .collect();
        let radius = |order: usize| -> Vec<f64> {
            rows.iter()
                .filter(|r| r.order == order)
                .map(|r| r.radius.as_ref().unwrap().value)
                .collect()
        };
        let (r1, r2, r3) = (radius(1), radius(2), radius(3));
        assert_eq!(r1.len(), 3);
        let drift1 = r1[2] - r1[0];
        let drift2 = (r2[2] - r2[0]).abs();
        let drift3 = (r3[2] - r3[0]).abs();
        // K2 = 3.9e-6 over 8→25 g: order 1 moves the radius by tens of µm,
        // orders 2 and 3 by well under one (the noise of these fits).
        assert!(drift1.abs() > 2e-5, "order-1 drift {drift1}");
        assert!(drift2 < 0.05 * drift1.abs(), "order-2 drift {drift2}");
        assert!(drift3 < 0.05 * drift1.abs(), "order-3 drift {drift3}");
        let eff = 1.0 + truth().k_io;
        let truth_r = eff
            * if pol > 0 {
                rig().r_plus_m
            } else {
                rig().r_minus_m
            };
        let last = rows
            .iter()
            .find(|r| r.order == 3 && r.max_input_g > 20.0)
            .unwrap();
        let v = last.radius.as_ref().unwrap();
        assert!((v.value - truth_r).abs() < 4.0 * v.u, "{v:?}");
        // Order 1 is also refused by the lack-of-fit test.
        let p1 = rows
            .iter()
            .find(|r| r.order == 1 && r.max_input_g > 20.0)
            .unwrap();
        assert!(p1.chi2_p_value.unwrap() < 1e-6);
    }
}

/// A plan that cannot separate a term is refused, naming it: one polarity
/// at the IA-radial station cannot tell K_oq from K2; no 45° position in
/// plane po cannot give K_po.
#[test]
fn unseparable_requests_are_refused_by_name() {
    let obs = simulate(&sim(
        3,
        vec![
            Position::new(Plane::Ip, 0.0, 1).unwrap(),
            Position::new(Plane::Ip, 90.0f64.to_radians(), 1).unwrap(),
        ],
    ));
    let mut o = options(3);
    o.terms = Some(vec![Term::K2, Term::Koq]);
    let e = calibrate(&obs, &o).unwrap_err().to_string();
    assert!(e.contains("K_oq") && e.contains("polarit"), "{e}");
    o.terms = Some(vec![Term::Kpo]);
    let e = calibrate(&obs, &o).unwrap_err().to_string();
    assert!(e.contains("K_po") && e.contains("po,45"), "{e}");
    // Without a request, what the data supports is reported, the rest listed.
    o.terms = None;
    let r = calibrate(&obs, &o).unwrap();
    assert!(r.coefficients.get("K2").is_some() && r.coefficients.get("K_pp").is_some());
    assert!(r.unsupported.iter().any(|(t, _)| *t == Term::Kip));
    // Two rates only: the station cannot separate its cubic from the rest.
    let few = simulate(&CentrifugeSim {
        rates_rad_s: rates_for_levels(&[0.0, 5.0], R0, G),
        ..sim(4, vec![Position::new(Plane::Ip, 0.0, 1).unwrap()])
    });
    o.terms = Some(vec![Term::K2]);
    let e = calibrate(&few, &o).unwrap_err().to_string();
    assert!(e.contains("K2") && e.contains("ip,0"), "{e}");
}

/// The Earth-rate term and the sense of rotation: on noiseless data from a
/// table spinning against Earth's sense, the regression radius is exact
/// (to 1e-9 relative) when the procedure is told so, and off by about
/// `2Ωe sinΦ/ω` (tens of ppm at low rates) when it is not. The static
/// radius, corrected for K2 and K3 at 1 g, is exact too, and the paper's
/// uncorrected eq. 6 value reads high by (K2 + K_oq)·a_g.
#[test]
fn earth_rate_and_sense_are_applied() {
    let mut cfg = sim(
        21,
        vec![
            Position::new(Plane::Ip, 0.0, 1).unwrap(),
            Position::new(Plane::Ip, 0.0, -1).unwrap(),
        ],
    );
    cfg.rig.opposite_sense = true;
    cfg.noise = 0.0;
    cfg.samples = 1;
    cfg.rates_rad_s = rates_for_levels(&[0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0], R0, G);
    let obs = simulate(&cfg);
    let mut o = options(3);
    o.terms = Some(vec![Term::K2]);
    o.opposite_sense = true;
    let good = calibrate(&obs, &o).unwrap();
    let eff = 1.0 + truth().k_io;
    let r = good.regression[0].as_ref().unwrap().radius_m.value;
    assert!((r / (rig().r_plus_m * eff) - 1.0).abs() < 1e-7, "{r}");
    // Noiseless: the corrected static radius is exact like the regression
    // one; the uncorrected eq. 6 value reads high by the quadratic that
    // polarity + sees, (K2 + K_oq)·a_g (4.4 ppm at 1 g).
    let st = good.static_radius[0].unwrap();
    assert!(
        (st.value / (rig().r_plus_m * eff) - 1.0).abs() < 1e-7,
        "{st:?}"
    );
    let raw = good.static_radius_uncorrected[0].unwrap();
    let excess = raw.value / st.value - 1.0;
    let quad = truth().k2 + truth().k_oq;
    assert!(
        (excess / quad - 1.0).abs() < 0.02,
        "eq. 6 excess {excess:e}"
    );
    o.opposite_sense = false;
    let wrong = calibrate(&obs, &o).unwrap();
    let rw = wrong.regression[0].as_ref().unwrap().radius_m.value;
    assert!((rw / r - 1.0).abs() > 1e-5, "{rw} vs {r}");
}

/// The printed budget is the propagation: for every coefficient the
/// combined u of its lines equals the u of the reported coefficient, and a
/// fixture tolerance of 1° adds the eq. 8 Δc2 as a type-B line with
/// half-width `|dc2/dφ|·(|Δφ_net| + 1°)` (for K_ip at 45°:
/// `|Kpp − K2|·Δφ`, He & Yin 2017 Table 3).
#[test]
fn budget_lines_add_up_to_the_reported_u() {
    let obs = simulate(&sim(8, standard_positions()));
    let mut o = options(3);
    o.alignment_tolerance_deg = 1.0;
    let r = calibrate(&obs, &o).unwrap();
    for b in &r.budgets {
        let u = r.coefficients.u(&b.coefficient).unwrap();
        assert!((b.combined_u - u).abs() <= 1e-12 * u, "{}", b.coefficient);
    }
    let b = r.budgets.iter().find(|b| b.coefficient == "K_ip").unwrap();
    let line = b
        .lines
        .iter()
        .find(|l| l.component == "alignment dc2(ip,45)")
        .unwrap();
    assert_eq!(line.sensitivity, 2.0);
    let st = r.stations.iter().find(|s| s.label() == "ip,45").unwrap();
    let net = st.alignment.iter().map(|a| a.delta_phi_rad).sum::<f64>() / 2.0;
    let (k2, kpp) = (
        r.coefficients.value("K2").unwrap(),
        r.coefficients.value("K_pp").unwrap(),
    );
    let hw = (kpp - k2).abs() * (net.abs() + 1f64.to_radians());
    assert!(
        (line.u - hw / 3f64.sqrt()).abs() < 1e-3 * line.u,
        "{line:?}"
    );
    assert!(b.combined_u_paper_eq10.unwrap() < b.combined_u);
}

/// The fixture-centre radius `R_centre_m = (R+ + R−)/2` (He & Yin 2017 §2.2):
/// the effective truth lies within ±2u in 90–99 % of 300 trials, as for the
/// other radii (u(K1) = 0 here; the shared-K1 term is checked by
/// tests/centrifuge_mc.rs).
#[test]
fn centre_radius_within_2u_at_95_percent() {
    let eff = 1.0 + truth().k_io;
    let truth_r = rig().centre_radius_m() * eff;
    let trials = 300;
    let runs = monte_carlo(12, trials, |s| {
        let obs = simulate(&sim(s, standard_positions()));
        let res = calibrate(&obs, &options(3)).expect("calibrates");
        let (v, u) = res.joint.get("R_centre_m").expect("R_centre_m");
        assert_eq!((v, u), (res.centre_radius_m.value, res.centre_radius_m.u));
        (v - truth_r).abs() <= 2.0 * u
    });
    let rate = runs.iter().filter(|h| **h).count() as f64 / trials as f64;
    assert!((0.90..=0.99).contains(&rate), "R_centre_m: {rate}");
}

/// `joint` holds the coefficients (exactly `coefficients`) followed by the
/// radius quantities in the documented order; every radius field carries
/// the joint u; K1 is one input: cov(R+, R−) contains the full
/// `R+ R− (u(K1)/K1)²` and cov(K2, R+) = −K2 R+ (u(K1)/K1)² (K2 ∝ K1,
/// R ∝ 1/K1).
#[test]
fn joint_estimates_share_k1_and_match_the_fields() {
    let obs = simulate(&sim(8, standard_positions()));
    let mut o = options(3);
    let rel = 1e-5;
    o.u_k1 = o.k1.map(|k1| rel * k1);
    o.u_k0 = Some(2e-6);
    let r = calibrate(&obs, &o).unwrap();
    let j = &r.joint;
    let mut expect: Vec<String> = r.coefficients.names().to_vec();
    expect.extend(
        [
            "R_plus_m",
            "R_minus_m",
            "R_plus_static_m",
            "R_minus_static_m",
            "R_centre_m",
            "ecm_offset_m",
            "tilt_rad",
        ]
        .map(String::from),
    );
    assert_eq!(j.names(), &expect[..]);
    let names: Vec<&str> = r.coefficients.names().iter().map(|s| s.as_str()).collect();
    let head = j.select(&names).unwrap();
    assert_eq!(head.values(), r.coefficients.values());
    assert_eq!(head.covariance(), r.coefficients.covariance());
    assert!(j.dof() <= r.coefficients.dof());
    let vu = |n: &str| {
        let (value, u) = j.get(n).unwrap();
        ValueU { value, u }
    };
    assert_eq!(r.regression[0].as_ref().unwrap().radius_m, vu("R_plus_m"));
    assert_eq!(r.regression[1].as_ref().unwrap().radius_m, vu("R_minus_m"));
    assert_eq!(r.static_radius[0], Some(vu("R_plus_static_m")));
    assert_eq!(r.static_radius[1], Some(vu("R_minus_static_m")));
    assert_eq!(r.centre_radius_m, vu("R_centre_m"));
    assert_eq!(r.ecm_offset_m, vu("ecm_offset_m"));
    assert_eq!(r.tilt_rad, Some(vu("tilt_rad")));
    let c = j.covariance();
    let at = |n: &str| j.index(n).unwrap();
    let (rp, rm, k2) = (
        j.value("R_plus_m").unwrap(),
        j.value("R_minus_m").unwrap(),
        j.value("K2").unwrap(),
    );
    let cov_pm = c[(at("R_plus_m"), at("R_minus_m"))];
    assert!(
        (cov_pm / (rp * rm * rel * rel) - 1.0).abs() < 1e-6,
        "{cov_pm:e}"
    );
    let cov_k2 = c[(at("K2"), at("R_plus_m"))];
    assert!(
        (cov_k2 / (-k2 * rp * rel * rel) - 1.0).abs() < 1e-6,
        "{cov_k2:e}"
    );
    // R_centre_m: the K1 term does not average down.
    let u_c = vu("R_centre_m").u;
    assert!(u_c >= 0.5 * (rp + rm) * rel, "{u_c:e}");
}

/// The static radius in `joint` is the eq. 5–6 radius corrected for the
/// nonlinearity at ~1 g exactly as `correct_static_radius` does: the same
/// value; with u(K1) = 0 the shared K1 adds nothing, and the u agree to
/// 1e-4 (the joint map also lets `a_g = R·rate²/g` follow the eq. 6 radius,
/// which `correct_static_radius` takes as exact: a relative change of
/// ~K2·a_g, a few ppm).
#[test]
fn joint_static_radius_is_correct_static_radius() {
    use incal::procedures::centrifuge::correct_static_radius;
    use incal::rigs::centrifuge::centripetal_rate_squared;
    let obs = simulate(&sim(9, standard_positions()));
    let o = options(3);
    let r = calibrate(&obs, &o).unwrap();
    for (k, pol) in [(0usize, 1.0), (1, -1.0)] {
        let raw = r.static_radius_uncorrected[k].unwrap();
        let w = r.static_rate_rad_s[k].unwrap();
        let a_g = raw.value * centripetal_rate_squared(w, o.latitude_rad(), o.opposite_sense)
            / o.gravity_m_s2;
        let fit = &r.regression[k].as_ref().unwrap().fit.estimates;
        let c = correct_static_radius(raw, a_g, pol, fit).unwrap();
        let st = r.static_radius[k].unwrap();
        assert!((st.value / c.value - 1.0).abs() < 1e-14, "{st:?} {c:?}");
        assert!((st.u / c.u - 1.0).abs() < 1e-4, "{st:?} {c:?}");
    }
}

/// `plan` (the reduction on noise-free outputs with an exact scatter)
/// predicts the Monte Carlo standard deviation of every coefficient and of
/// the radii within 20 % (300 trials: the standard deviation itself is
/// known to ±4 %).
#[test]
fn plan_predicts_the_monte_carlo_scatter() {
    let p = incal::sim::centrifuge::plan(&sim(0, standard_positions()), &options(3)).unwrap();
    let trials = 300;
    let runs = monte_carlo(17, trials, |s| {
        let r = calibrate(&simulate(&sim(s, standard_positions())), &options(3)).unwrap();
        let mut v: Vec<f64> = r.coefficients.values().iter().copied().collect();
        v.extend(r.joint.values().iter().copied());
        v
    });
    let mut names: Vec<String> = p.coefficients.names().to_vec();
    names.extend(p.joint.names().iter().cloned());
    let mut predicted: Vec<f64> = (0..p.coefficients.len())
        .map(|k| p.coefficients.u_at(k))
        .collect();
    predicted.extend((0..p.joint.len()).map(|k| p.joint.u_at(k)));
    for (k, name) in names.iter().enumerate() {
        let m = runs.iter().map(|r| r[k]).sum::<f64>() / trials as f64;
        let sd =
            (runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (trials - 1) as f64).sqrt();
        let ratio = predicted[k] / sd;
        eprintln!(
            "{name}: plan u {:.3e}, Monte Carlo sd {sd:.3e}, ratio {ratio:.3}",
            predicted[k]
        );
        assert!(
            (0.8..1.25).contains(&ratio),
            "{name}: plan u / MC sd = {ratio}"
        );
    }
}
