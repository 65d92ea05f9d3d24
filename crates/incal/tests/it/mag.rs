//! Magnetometer calibration: round trips from known hard and soft iron,
//! alignment and inclination over many seeds (U95 coverage of every
//! element, with white and with Gauss–Markov noise), the refusals
//! (planar session, too few orientations, saturation), and the apply and
//! flight-stack exports agreeing to 1e-9.

use incal::procedures::mag::apply::{
    parameters, read_parameters, stack_field, write_parameters, FlightStack, MagCalibration,
};
use incal::procedures::mag::sim::{MagSimOptions, Motion};
use incal::procedures::mag::{calibrate, MagOptions, MagUnit};
use incal::sim::monte_carlo;
use incal::sim::tier::{band, trials};

const NAMES: [&str; 15] = [
    "hard_iron_x",
    "hard_iron_y",
    "hard_iron_z",
    "soft_iron_xx",
    "soft_iron_yy",
    "soft_iron_zz",
    "soft_iron_xy",
    "soft_iron_xz",
    "soft_iron_yz",
    "field_raw",
    "field_ut",
    "alignment_x_deg",
    "alignment_y_deg",
    "alignment_z_deg",
    "inclination_deg",
];

fn sim(seed: u64) -> MagSimOptions {
    MagSimOptions {
        seed,
        orientations: 24,
        dwell_s: 1.0,
        move_s: 0.5,
        rate_hz: 20.0,
        ..MagSimOptions::default()
    }
}

fn options(s: &MagSimOptions) -> MagOptions {
    MagOptions {
        field_ut: Some(s.field_ut),
        ..MagOptions::default()
    }
}

fn covered(s: &MagSimOptions) -> Vec<bool> {
    let truth = s.truth_json().unwrap();
    let r = calibrate(&s.record().unwrap(), &options(s)).expect("reduces");
    let e = &r.coefficients;
    let k95 = e.coverage_factor(0.95);
    NAMES
        .iter()
        .map(|name| {
            let t = truth[*name].as_f64().unwrap();
            let (v, u) = e.get(name).unwrap();
            (v - t).abs() <= k95 * u
        })
        .collect()
}

fn assert_band(label: &str, runs: &[Vec<bool>]) {
    let (lo, hi) = band(runs.len(), 0.93, 0.97);
    let mut outside = Vec::new();
    for (k, name) in NAMES.iter().enumerate() {
        let rate = runs.iter().filter(|r| r[k]).count() as f64 / runs.len() as f64;
        eprintln!("{label}, {name}: {rate:.3} of {}", runs.len());
        if !(lo..=hi).contains(&rate) {
            outside.push(format!("{name}: {rate:.3} (band {lo:.3}..{hi:.3})"));
        }
    }
    assert!(outside.is_empty(), "{label}: {}", outside.join("; "));
}

#[test]
fn mag_white_noise_u95_covers_the_truth() {
    let runs = monte_carlo(601, trials(40, 1000), |s| covered(&sim(s)));
    assert_band("mag, white noise", &runs);
}

/// Gauss–Markov noise as large as the white, correlated over 0.5 s (ten
/// samples): the residuals' inflation carries it.
#[test]
fn mag_correlated_noise_u95_covers_the_truth() {
    let runs = monte_carlo(602, trials(40, 1000), |s| {
        covered(&MagSimOptions {
            gm_ut: 0.3,
            gm_tau_s: 0.5,
            ..sim(s)
        })
    });
    assert_band("mag, Gauss-Markov noise", &runs);
}

#[test]
fn a_round_trip_recovers_the_truth_in_gauss() {
    let s = MagSimOptions {
        unit: MagUnit::Gauss,
        hard_iron_x: 0.12,
        hard_iron_y: -0.08,
        hard_iron_z: 0.25,
        ..sim(7)
    };
    let o = MagOptions {
        unit: MagUnit::Gauss,
        ..options(&s)
    };
    let r = calibrate(&s.record().unwrap(), &o).unwrap();
    let truth = s.truth_json().unwrap();
    for name in NAMES {
        let (v, u) = r.coefficients.get(name).unwrap();
        let t = truth[name].as_f64().unwrap();
        assert!((v - t).abs() <= 5.0 * u, "{name}: {v} against {t} (u {u})");
    }
    let doc = r.document().unwrap();
    assert_eq!(
        doc.coefficients.get("soft_iron_xx").unwrap().unit.as_str(),
        "uT/gauss"
    );
}

#[test]
fn without_the_local_field_the_soft_iron_has_determinant_one() {
    let s = sim(8);
    let r = calibrate(&s.record().unwrap(), &MagOptions::default()).unwrap();
    assert!((r.soft_iron().determinant() - 1.0).abs() < 1e-9);
    let truth = s.truth_json().unwrap();
    let (v, u) = r.coefficients.get("field_raw").unwrap();
    assert!((v - truth["field_raw"].as_f64().unwrap()).abs() < 5.0 * u);
}

#[test]
fn a_planar_session_is_refused_naming_the_terms() {
    let s = MagSimOptions {
        motion: Motion::Planar,
        ..sim(9)
    };
    let e = calibrate(&s.record().unwrap(), &options(&s))
        .err()
        .map(|e| e.to_string())
        .expect("refused");
    assert!(e.contains("cannot separate"), "{e}");
    assert!(
        e.contains("soft_iron_zz") || e.contains("hard_iron_z"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn too_few_orientations_are_refused() {
    let s = MagSimOptions {
        orientations: 6,
        move_s: 0.0,
        ..sim(10)
    };
    let e = calibrate(&s.record().unwrap(), &options(&s))
        .err()
        .map(|e| e.to_string())
        .expect("refused");
    assert!(e.contains("6 distinct orientations"), "{e}");
    assert!(e.contains("9 unknowns"), "{e}");
}

#[test]
fn a_saturated_column_is_refused_naming_it() {
    let s = sim(11);
    let mut rec = s.record().unwrap();
    for m in &mut rec.mag {
        m[1] = m[1].min(30.0);
    }
    let e = calibrate(&rec, &options(&s))
        .err()
        .map(|e| e.to_string())
        .expect("refused");
    assert!(e.contains("mag_y") && e.contains("saturated"), "{e}");
    let o = MagOptions {
        full_scale: Some(30.0),
        ..options(&s)
    };
    let e = calibrate(&rec, &o)
        .err()
        .map(|e| e.to_string())
        .expect("refused");
    assert!(e.contains("mag_y") && e.contains("full scale"), "{e}");
}

#[test]
fn exports_read_back_equal_apply() {
    for unit in [MagUnit::Ut, MagUnit::Gauss, MagUnit::Mgauss] {
        for field in [true, false] {
            let k = unit.ut().unwrap();
            let s = MagSimOptions {
                unit,
                hard_iron_x: 12.0 / k,
                hard_iron_y: -8.0 / k,
                hard_iron_z: 25.0 / k,
                ..sim(12)
            };
            let rec = s.record().unwrap();
            let o = MagOptions {
                unit,
                field_ut: field.then_some(50.0),
                ..MagOptions::default()
            };
            let doc = calibrate(&rec, &o).unwrap().document().unwrap();
            let cal = MagCalibration::from_document(&doc).unwrap();
            for stack in [FlightStack::Px4, FlightStack::Ardupilot] {
                let mut text = Vec::new();
                write_parameters(stack, &parameters(&cal, stack, 0).unwrap(), &mut text).unwrap();
                let back = read_parameters(std::str::from_utf8(&text).unwrap()).unwrap();
                let ku = stack.unit_ut();
                let ko = cal.output_ut.unwrap();
                for m in rec.mag.iter().step_by(37) {
                    let mine = cal.apply(*m) * (ko / ku);
                    let raw_u = nalgebra::Vector3::from(*m) * (k / ku);
                    let theirs = stack_field(stack, &back, raw_u).unwrap();
                    let d = (mine - theirs).norm() / mine.norm();
                    assert!(d < 1e-9, "{unit:?} {stack:?} field {field}: {d:e}");
                }
            }
        }
    }
}

#[test]
fn an_axes_map_or_counts_are_not_exported() {
    let s = sim(13);
    let rec = s.record().unwrap();
    let o = MagOptions {
        unit: MagUnit::Counts,
        ..MagOptions::default()
    };
    let cal =
        MagCalibration::from_document(&calibrate(&rec, &o).unwrap().document().unwrap()).unwrap();
    let e = parameters(&cal, FlightStack::Px4, 0)
        .err()
        .map(|e| e.to_string())
        .expect("refused");
    assert!(e.contains("counts"), "{e}");
}

/// A session turned continuously (no dwell: each orientation passed
/// through in 2 s of slerp), magnetometer only, with Gauss–Markov noise:
/// the jackknife's runs follow the motion.
#[test]
fn mag_continuous_turning_u95_covers_the_truth() {
    let runs = monte_carlo(603, trials(40, 1000), |seed| {
        let s = MagSimOptions {
            dwell_s: 0.05,
            move_s: 2.0,
            gm_ut: 0.3,
            gm_tau_s: 0.5,
            no_accelerometer: true,
            ..sim(seed)
        };
        let truth = s.truth_json().unwrap();
        let r = calibrate(&s.record().unwrap(), &options(&s)).expect("reduces");
        let e = &r.coefficients;
        let k95 = e.coverage_factor(0.95);
        NAMES[..11]
            .iter()
            .map(|name| {
                let (v, u) = e.get(name).unwrap();
                (v - truth[*name].as_f64().unwrap()).abs() <= k95 * u
            })
            .collect::<Vec<bool>>()
    });
    let (lo, hi) = band(runs.len(), 0.93, 0.97);
    for (k, name) in NAMES[..11].iter().enumerate() {
        let rate = runs.iter().filter(|r| r[k]).count() as f64 / runs.len() as f64;
        eprintln!("mag, continuous, {name}: {rate:.3} of {}", runs.len());
        assert!(
            (lo..=hi).contains(&rate),
            "{name}: {rate:.3} (band {lo:.3}..{hi:.3})"
        );
    }
}
