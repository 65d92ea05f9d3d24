//! Gyro tests (rate table and dividing head): round trips from a known
//! truth over many seeds, U95 coverage, plan-versus-Monte-Carlo agreement,
//! and the refusals of terms a plan cannot separate.

use incal::estimation::{coverage_factor, Noise};
use incal::procedures::gyro::positions::{self as gp, Axial, DriftTerm, GyroPositionsOptions};
use incal::procedures::gyro::rate::{self as gr, GyroRateOptions, InputAxis, RateTerm};
use incal::sim::gyro::{
    simulate_positions, simulate_rate, DriftTruth, GyroPositionsSim, GyroRateSim,
};
use incal::sim::{monte_carlo, normal, rng};

/// Trials of each Monte Carlo: 200 in the fast tier, 1000 in the
/// statistical tier (`incal::sim::tier`).
fn trials() -> usize {
    incal::sim::tier::trials(200, 1000)
}

fn rates() -> Vec<f64> {
    vec![
        -200.0, -100.0, -50.0, -10.0, -1.0, 0.0, 1.0, 10.0, 50.0, 100.0, 200.0,
    ]
}

fn rate_sim(seed: u64) -> GyroRateSim {
    GyroRateSim {
        k1_pos: 0.02,
        k1_neg: 0.02,
        b_deg_h: 5.0,
        k2: 2e-5,
        k3: -1e-7,
        latitude_rad: 45f64.to_radians(),
        ia: InputAxis::Up,
        rates_deg_s: rates(),
        samples: 20,
        noise: 2e-5,
        runs: 1,
        run_scatter_ppm: 0.0,
        clip: 0.0,
        seed,
    }
}

fn rate_opts(terms: &[RateTerm], noise: Noise) -> GyroRateOptions {
    GyroRateOptions {
        latitude_deg: 45.0,
        ia: InputAxis::Up,
        terms: terms.to_vec(),
        noise,
        rate_uncertainty_ppm: 0.0,
        linearity_ppm: None,
        output_limit: None,
    }
}

/// Fraction of trials whose U95 (k95 from each coefficient's dof) covers the truth.
fn covered(hits: &[Vec<bool>], k: usize) -> f64 {
    hits.iter().filter(|h| h[k]).count() as f64 / hits.len() as f64
}

#[test]
fn rate_test_u95_covers_truth() {
    let terms = [RateTerm::B, RateTerm::K1, RateTerm::K2, RateTerm::K3];
    let truth = [("B", 5.0), ("K1", 0.02), ("K2", 2e-5), ("K3", -1e-7)];
    for ia in [InputAxis::Up, InputAxis::Down] {
        let runs = monte_carlo(11, trials(), |s| {
            let mut cfg = rate_sim(s);
            cfg.ia = ia;
            let obs = simulate_rate(&cfg);
            let mut o = rate_opts(&terms, Noise::Auto);
            o.ia = ia;
            let r = gr::calibrate(&obs, &o).expect("rate test reduces");
            let mut hits: Vec<bool> = truth
                .iter()
                .map(|(n, t)| {
                    let (v, u) = r.coefficients.get(n).unwrap();
                    let dof = r.dof.iter().find(|d| d.0 == *n).unwrap().1;
                    (v - t).abs() <= coverage_factor(dof, 0.95) * u
                })
                .collect();
            let (v, u) = r.coefficients.get("asymmetry").expect("both signs");
            let dof = r.dof.iter().find(|d| d.0 == "asymmetry").unwrap().1;
            hits.push(v.abs() <= coverage_factor(dof, 0.95) * u);
            hits
        });
        for (k, name) in ["B", "K1", "K2", "K3", "asymmetry"].iter().enumerate() {
            let c = covered(&runs, k);
            eprintln!(
                "rate IA {} {name}: U95 coverage {:.1} %",
                ia.name(),
                100.0 * c
            );
            let (lo, hi) = incal::sim::tier::band(trials(), 0.92, 0.98);
            assert!(
                (lo..=hi).contains(&c),
                "IA {}: U95 of {name} covers the truth in {:.1} % of {} trials",
                ia.name(),
                100.0 * c,
                trials()
            );
        }
    }
}

#[test]
fn rate_test_recovers_asymmetry() {
    // K1+ = K1 (1 + 150 ppm), K1− = K1 (1 − 150 ppm): asymmetry 300 ppm.
    let runs = monte_carlo(12, trials(), |s| {
        let mut cfg = rate_sim(s);
        cfg.k1_pos = 0.02 * (1.0 + 150e-6);
        cfg.k1_neg = 0.02 * (1.0 - 150e-6);
        cfg.k3 = 0.0;
        let obs = simulate_rate(&cfg);
        let r = gr::calibrate(
            &obs,
            &rate_opts(&[RateTerm::B, RateTerm::K1, RateTerm::K2], Noise::Auto),
        )
        .unwrap();
        // With the asymmetry in the model, K2 and B stay unbiased.
        let (k2, uk2) = r.coefficients.get("K2").unwrap();
        assert!((k2 - 2e-5).abs() < 6.0 * uk2, "K2 {k2} ± {uk2}");
        let (v, u) = r.coefficients.get("asymmetry").unwrap();
        (
            v,
            (v - 300.0).abs() <= r.coefficients.coverage_factor(0.95) * u,
            u,
        )
    });
    let cov = runs.iter().filter(|r| r.1).count() as f64 / trials() as f64;
    let mean = runs.iter().map(|r| r.0).sum::<f64>() / trials() as f64;
    let u = runs[0].2;
    eprintln!(
        "asymmetry 300 ppm: mean {mean:.1} ppm, u {u:.1} ppm, coverage {:.1} %",
        100.0 * cov
    );
    let (lo, hi) = incal::sim::tier::band(trials(), 0.92, 0.98);
    assert!((lo..=hi).contains(&cov), "asymmetry coverage {cov}");
    assert!(
        (mean - 300.0).abs() < 3.0 * u / (trials() as f64).sqrt() + 1.0,
        "mean asymmetry {mean} ppm"
    );
    assert!(u < 30.0, "asymmetry u {u} ppm should resolve 300 ppm");
}

#[test]
fn rate_plan_predicts_monte_carlo_scatter() {
    let terms = [RateTerm::B, RateTerm::K1, RateTerm::K2, RateTerm::K3];
    let noise = 2e-5;
    let plan = gr::plan(&rates(), 20, noise, 0.02, &rate_opts(&terms, Noise::Auto)).unwrap();
    let runs = monte_carlo(13, trials(), |s| {
        let obs = simulate_rate(&rate_sim(s));
        let r = gr::calibrate(&obs, &rate_opts(&terms, Noise::Auto)).unwrap();
        ["B", "K1", "K2", "K3"].map(|n| r.coefficients.value(n).unwrap())
    });
    for (k, n) in ["B", "K1", "K2", "K3"].iter().enumerate() {
        let m = runs.iter().map(|r| r[k]).sum::<f64>() / trials() as f64;
        let sd =
            (runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (trials() as f64 - 1.0)).sqrt();
        let ratio = plan.coefficients.u(n).unwrap() / sd;
        eprintln!("rate plan {n}: plan u / MC sd = {ratio:.3}");
        assert!(
            (0.8..=1.2).contains(&ratio),
            "{n}: plan u / MC sd = {ratio}"
        );
    }
}

#[test]
fn rate_test_runs_give_repeatability() {
    let mut cfg = rate_sim(5);
    cfg.runs = 4;
    cfg.run_scatter_ppm = 100.0;
    let obs = simulate_rate(&cfg);
    let r = gr::calibrate(&obs, &rate_opts(&[RateTerm::B, RateTerm::K1], Noise::Auto)).unwrap();
    assert_eq!(r.runs.len(), 4);
    let (ppm, dof) = r.repeatability.unwrap();
    assert_eq!(dof, 3.0);
    // The spread of four draws of 100 ppm lies well within 10..300 ppm.
    assert!((10.0..300.0).contains(&ppm), "repeatability {ppm} ppm");
}

#[test]
fn rate_test_nonlinearity_reads_the_quadratic() {
    // Noise-free, K2 only: the deviation from the straight line is the
    // parabola's, largest at the ends or the middle.
    let mut cfg = rate_sim(1);
    cfg.noise = 0.0;
    cfg.k3 = 0.0;
    cfg.b_deg_h = 0.0;
    cfg.latitude_rad = 0.0;
    cfg.rates_deg_s = (-10..=10).map(|k| 20.0 * k as f64).collect();
    let obs = simulate_rate(&cfg);
    let mut o = rate_opts(&[RateTerm::B, RateTerm::K1], Noise::Known { sigma: 1e-6 });
    o.latitude_deg = 0.0;
    let r = gr::calibrate(&obs, &o).unwrap();
    // LS line of K2 ω² over a symmetric grid is flat at K2·mean(ω²); the
    // largest deviation is K1·K2·max|ω² − mean(ω²)| (at the ends here), over
    // the full-scale output K1·200.
    let mean_w2 = cfg.rates_deg_s.iter().map(|w| w * w).sum::<f64>() / 21.0;
    let dev = cfg
        .rates_deg_s
        .iter()
        .map(|w| (w * w - mean_w2).abs())
        .fold(0.0, f64::max);
    let expect = 2e-5 * dev / 200.0 * 1e6;
    assert!(
        (r.nonlinearity_ppm_fs - expect).abs() < 1e-6 * expect,
        "{} vs {expect}",
        r.nonlinearity_ppm_fs
    );
}

fn drift() -> DriftTruth {
    DriftTruth {
        b: 3.0,
        d_i: 0.8,
        d_o: -0.5,
        d_s: 0.4,
        ..DriftTruth::default()
    }
}

fn angles() -> Vec<f64> {
    (0..12).map(|k| 30.0 * k as f64).collect()
}

fn pos_sim(lat: f64, azimuths: &[f64], axial: Axial, seed: u64) -> GyroPositionsSim {
    GyroPositionsSim {
        k1: 0.02,
        drift: drift(),
        latitude_rad: lat.to_radians(),
        azimuths_rad: azimuths.iter().map(|a| a.to_radians()).collect(),
        axial,
        angles_deg: angles(),
        samples: 10,
        noise: 2e-5,
        seed,
    }
}

#[test]
fn positions_u95_covers_truth_at_latitudes_and_azimuths() {
    let u_k1_rel = 2e-3;
    for (lat, az, axial) in [
        (0.0, 0.0, Axial::Sa),
        (45.0, 90.0, Axial::Sa),
        (-60.0, 30.0, Axial::Oa),
        (45.0, 200.0, Axial::Oa),
    ] {
        let terms = gp::default_terms(axial);
        let runs = monte_carlo(21, trials(), |s| {
            let obs = simulate_positions(&pos_sim(lat, &[az], axial, s));
            // The K1 handed over from a rate test is off by its own u.
            let mut r = rng(s ^ 0xA5A5);
            let k1 = 0.02 * (1.0 + normal(&mut r, u_k1_rel));
            let res = gp::calibrate(
                &obs,
                &GyroPositionsOptions {
                    terms: terms.clone(),
                    ..GyroPositionsOptions::new(lat, axial, k1, Some(0.02 * u_k1_rel))
                },
            )
            .expect("positions reduce");
            terms
                .iter()
                .map(|t| {
                    let (v, u) = res.coefficients.get(t.name()).unwrap();
                    let dof = res.dof.iter().find(|d| d.0 == t.name()).unwrap().1;
                    (v - drift_value(t.name())).abs() <= coverage_factor(dof, 0.95) * u
                })
                .collect::<Vec<bool>>()
        });
        for (k, t) in terms.iter().enumerate() {
            let c = covered(&runs, k);
            eprintln!(
                "positions lat {lat} az {az} {}: {} coverage {:.1} %",
                axial.name(),
                t.name(),
                100.0 * c
            );
            let (lo, hi) = incal::sim::tier::band(trials(), 0.92, 0.98);
            assert!(
                (lo..=hi).contains(&c),
                "lat {lat} az {az} {}: U95 of {} covers in {:.1} %",
                axial.name(),
                t.name(),
                100.0 * c
            );
        }
    }
}

fn drift_value(n: &str) -> f64 {
    drift().get(n)
}

#[test]
fn positions_plan_predicts_monte_carlo_scatter() {
    let axial = Axial::Sa;
    let terms = gp::default_terms(axial);
    let opts = GyroPositionsOptions {
        terms: terms.clone(),
        ..GyroPositionsOptions::new(45.0, axial, 0.02, Some(0.0))
    };
    let ang: Vec<f64> = angles().iter().map(|a| a.to_radians()).collect();
    let plan = gp::plan(&ang, &[90f64.to_radians()], 10, 2e-5, 0.02, &opts).unwrap();
    let runs = monte_carlo(22, trials(), |s| {
        let obs = simulate_positions(&pos_sim(45.0, &[90.0], axial, s));
        let r = gp::calibrate(&obs, &opts).unwrap();
        terms
            .iter()
            .map(|t| r.coefficients.value(t.name()).unwrap())
            .collect::<Vec<f64>>()
    });
    for (k, t) in terms.iter().enumerate() {
        let m = runs.iter().map(|r| r[k]).sum::<f64>() / trials() as f64;
        let sd =
            (runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (trials() as f64 - 1.0)).sqrt();
        let ratio = plan.coefficients.u(t.name()).unwrap() / sd;
        eprintln!("positions plan {}: plan u / MC sd = {ratio:.3}", t.name());
        assert!(
            (0.8..=1.2).contains(&ratio),
            "{}: plan u / MC sd = {ratio}",
            t.name()
        );
    }
}

#[test]
fn positions_fit_k1_from_earth_rate_needs_two_azimuths() {
    let axial = Axial::Sa;
    let opts = GyroPositionsOptions {
        k1: None,
        fit_k1: true,
        ..GyroPositionsOptions::new(45.0, axial, 0.02, None)
    };
    // One azimuth: the Earth-rate projection is a combination of sin θ and
    // cos θ, so K1 aliases with D_I and D_O; the refusal names them.
    let obs = simulate_positions(&pos_sim(45.0, &[90.0], axial, 3));
    let e = gp::calibrate(&obs, &opts).unwrap_err().to_string();
    assert!(
        e.contains("cannot separate") && e.contains("K1") && e.contains("D_I") && e.contains("D_O"),
        "{e}"
    );
    // Azimuths 90° and 270°: separable, K1 recovered within its U95.
    let mut cfg = pos_sim(45.0, &[90.0, 270.0], axial, 3);
    cfg.noise = 2e-6;
    cfg.samples = 50;
    let r = gp::calibrate(&simulate_positions(&cfg), &opts).unwrap();
    let (k1, u) = r.coefficients.get("K1").unwrap();
    assert!(
        (k1 - 0.02).abs() <= r.coefficients.coverage_factor(0.95) * u,
        "K1 {k1} ± {u}"
    );
    let (b, ub) = r.coefficients.get("B").unwrap();
    assert!(
        (b - 3.0).abs() <= r.coefficients.coverage_factor(0.95) * ub,
        "B {b} ± {ub}"
    );
}

#[test]
fn positions_refuse_bias_against_second_order_terms() {
    let axial = Axial::Sa;
    let obs = simulate_positions(&pos_sim(45.0, &[0.0], axial, 4));
    let opts = GyroPositionsOptions {
        terms: vec![
            DriftTerm::B,
            DriftTerm::DI,
            DriftTerm::DO,
            DriftTerm::DII,
            DriftTerm::DOO,
        ],
        ..GyroPositionsOptions::new(45.0, axial, 0.02, Some(0.0))
    };
    let e = gp::calibrate(&obs, &opts).unwrap_err().to_string();
    assert!(
        e.contains("cannot separate")
            && e.contains("B")
            && e.contains("D_II")
            && e.contains("D_OO"),
        "{e}"
    );
    // A term with no regressor in this mount is named too.
    let opts = GyroPositionsOptions {
        terms: vec![DriftTerm::B, DriftTerm::DS],
        ..opts
    };
    let e = gp::calibrate(&obs, &opts).unwrap_err().to_string();
    assert!(
        e.contains("D_S") && e.contains("zero at every position"),
        "{e}"
    );
}

#[test]
fn rate_test_refuses_one_rate_and_bad_latitude() {
    let mut cfg = rate_sim(1);
    cfg.rates_deg_s = vec![10.0];
    let obs = simulate_rate(&cfg);
    let e = gr::calibrate(&obs, &rate_opts(&[RateTerm::B, RateTerm::K1], Noise::Auto))
        .unwrap_err()
        .to_string();
    assert!(e.contains("distinct table rates"), "{e}");
    let mut o = rate_opts(&[RateTerm::B, RateTerm::K1], Noise::Auto);
    o.latitude_deg = 200.0;
    let e = gr::calibrate(&simulate_rate(&rate_sim(1)), &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("latitude"), "{e}");
}
