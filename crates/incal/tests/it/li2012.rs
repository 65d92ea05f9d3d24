//! Li et al. 2012 (misalignment separation) reproduced: Table 1 (gyro on a rate
//! table, three rates) and Table 2 (accelerometer on a vertical face, three
//! runs), by least squares on the linearised models of docs/src/misalignment.md.
//!
//! Tolerance: the paper prints 0.1″; every value must round to the printed
//! figure, |ours − printed| ≤ 0.05″ (half the printed resolution).

use incal::estimation::Noise;
use incal::procedures::misalign::accel::{self, AccelObservation, AccelOptions};
use incal::procedures::misalign::gyro::GyroConfig;
use incal::procedures::misalign::gyro::{self, observations_deg, GyroOptions};
use incal::procedures::misalign::plan::predict_gyro;
use incal::units::rad_to_arcsec;
use incal::Error;

/// Li et al. 2012 Table 1: V_n(+ω), V_n(−ω) for the five configurations
/// (α, β) = (0,0), (0,180°), (180°,180°), (90°,180°), (0,90°), kI = −2.9222
/// V/(°/s); then the printed Δθy0, Δθx0, Δθy1, Δθy2, Δθz2, γ (″).
/// One Table 1 row: rate (°/s), (V+, V−) per configuration, printed angles.
type Table1Row = (f64, [(f64, f64); 5], [f64; 6]);

const TABLE1: [Table1Row; 3] = [
    (
        20.0,
        [
            (-0.0614, 0.0654),
            (-0.0576, 0.0606),
            (0.0350, -0.0306),
            (-0.0290, 0.0287),
            (-0.0600, 0.0638),
        ],
        [-7.6, 2.3, -54.0, -162.2, 55.4, 171.4],
    ),
    (
        30.0,
        [
            (-0.0929, 0.0969),
            (-0.0869, 0.0903),
            (0.0517, -0.0468),
            (-0.0433, 0.0435),
            (-0.0908, 0.0947),
        ],
        [-7.4, 2.4, -53.7, -162.2, 55.8, 171.5],
    ),
    (
        40.0,
        [
            (-0.1246, 0.1284),
            (-0.1164, 0.1197),
            (0.0679, -0.0632),
            (-0.0580, 0.0583),
            (-0.1217, 0.1256),
        ],
        [-7.5, 2.4, -53.8, -162.0, 56.3, 171.5],
    ),
];

const CONFIGS: [(f64, f64); 5] = [
    (0.0, 0.0),
    (0.0, 180.0),
    (180.0, 180.0),
    (90.0, 180.0),
    (0.0, 90.0),
];
const KI_GYRO: f64 = -2.9222;
const NAMES: [&str; 6] = [
    "dtheta_y0",
    "dtheta_x0",
    "dtheta_y1",
    "dtheta_y2",
    "dtheta_z2",
    "gamma",
];

fn table1_rows(k: usize) -> Vec<(f64, f64, f64, f64)> {
    let (w, v, _) = TABLE1[k];
    CONFIGS
        .iter()
        .zip(v)
        .flat_map(|(&(a, b), (vp, vm))| [(a, b, w, vp), (a, b, -w, vm)])
        .collect()
}

/// Table 1, every rate, every angle and γ: least squares with a common bias
/// (the paper's model) rounds to the printed 0.1″.
#[test]
fn table1_gyro_all_rates() {
    for (k, row) in TABLE1.iter().enumerate() {
        let obs = observations_deg(&table1_rows(k));
        let r = gyro::calibrate(
            &obs,
            &GyroOptions {
                scale_factor: KI_GYRO,
                per_config_bias: false,
                noise: Noise::Auto,
                scale_factor_unit: Default::default(),
                average: Default::default(),
            },
        )
        .unwrap();
        for (name, printed) in NAMES.iter().zip(row.2) {
            let ours = rad_to_arcsec(r.angles.value(name).unwrap());
            assert!(
                (ours - printed).abs() <= 0.05 + 1e-9,
                "ω = {}: {name} = {ours:.3}″, Table 1 prints {printed}″",
                row.0
            );
            // 10 readings, 6 terms: u from 4 degrees of freedom, finite.
            assert!(r.angles.u(name).unwrap() > 0.0);
        }
        assert_eq!(r.fit.dof, 4);
    }
}

/// The least-squares estimates equal the paper's closed forms
/// (docs/src/misalignment.md, corrected Δθz2 line) to rounding.
#[test]
fn table1_least_squares_equals_closed_forms() {
    for (k, &(w, v, _)) in TABLE1.iter().enumerate() {
        let d: Vec<f64> = v.iter().map(|(p, m)| p - m).collect();
        let den = 4.0 * KI_GYRO * w;
        let closed = [
            (d[1] - d[0]) / den,
            (2.0 * d[4] - d[1] - d[0]) / den,
            -(d[0] + d[2]) / den,
            (d[2] - d[1]) / den,
            (2.0 * d[3] - d[2] - d[1]) / den,
        ];
        let r = gyro::calibrate(
            &observations_deg(&table1_rows(k)),
            &GyroOptions {
                scale_factor: KI_GYRO,
                per_config_bias: false,
                noise: Noise::Auto,
                scale_factor_unit: Default::default(),
                average: Default::default(),
            },
        )
        .unwrap();
        for (name, c) in NAMES.iter().zip(closed) {
            let ours = r.angles.value(name).unwrap();
            assert!((ours - c).abs() < 1e-12, "{name}: {ours} vs {c}");
        }
    }
}

/// All three rates at once with one bias per configuration (the sums
/// V(+ω)+V(−ω) of Table 1 show a bias that shifts between mountings):
/// redundancy from the rates gives uncertainties, and the estimates agree
/// with the paper's rate-averaged values within their U95.
#[test]
fn table1_all_rates_per_config_bias() {
    let rows: Vec<_> = (0..3).flat_map(table1_rows).collect();
    let r = gyro::calibrate(
        &observations_deg(&rows),
        &GyroOptions {
            scale_factor: KI_GYRO,
            per_config_bias: true,
            noise: Noise::Auto,
            scale_factor_unit: Default::default(),
            average: Default::default(),
        },
    )
    .unwrap();
    assert_eq!(r.fit.dof, 20);
    assert_eq!(r.biases.len(), 5);
    let k95 = r.angles.coverage_factor(0.95);
    for (j, name) in NAMES.iter().enumerate() {
        let mean: f64 = (0..3).map(|k| TABLE1[k].2[j]).sum::<f64>() / 3.0;
        let (v, u) = r.angles.get(name).unwrap();
        let (v, u) = (rad_to_arcsec(v), rad_to_arcsec(u));
        assert!(u > 0.01 && u < 1.0, "{name}: u = {u}″");
        assert!(
            (v - mean).abs() <= k95 * u + 0.1,
            "{name}: {v} ± {u} vs {mean}"
        );
    }
}

/// Li et al. 2012 Table 2: V(0), V(π), V(π/2), V(3π/2) per run, kI = 1.299 V/g,
/// then the printed Δθy2, Δθz2, γ (″).
const TABLE2: [([f64; 4], [f64; 3]); 3] = [
    (
        [-0.001845, -0.001911, -0.001912, -0.002175],
        [-5.2, 20.9, 21.5],
    ),
    (
        [-0.001846, -0.001914, -0.001921, -0.002177],
        [-5.4, 20.3, 21.0],
    ),
    (
        [-0.001845, -0.001912, -0.001921, -0.002176],
        [-5.3, 20.2, 20.9],
    ),
];

/// Table 2, every run: Δθy2, Δθz2, γ round to the printed 0.1″.
#[test]
fn table2_accel_all_runs() {
    for (v, printed) in TABLE2 {
        let obs: Vec<AccelObservation> = [0.0f64, 180.0, 90.0, 270.0]
            .iter()
            .zip(v)
            .map(|(b, out)| AccelObservation {
                beta_rad: b.to_radians(),
                output: out,
            })
            .collect();
        let r = accel::calibrate(
            &obs,
            &AccelOptions {
                scale_factor: 1.299,
                noise: Noise::Auto,
                scale_factor_unit: Default::default(),
            },
        )
        .unwrap();
        for (name, p) in ["dtheta_y2", "dtheta_z2", "gamma"].iter().zip(printed) {
            let ours = rad_to_arcsec(r.angles.value(name).unwrap());
            assert!(
                (ours - p).abs() <= 0.05 + 1e-9,
                "{name} = {ours:.3}″, Table 2 prints {p}″"
            );
        }
        // Closed forms of Li et al. 2012 eq. 10–13.
        let y2 = (v[1] - v[0]) / (2.0 * 1.299);
        let z2 = (v[2] - v[3]) / (2.0 * 1.299);
        assert!((r.angles.value("dtheta_y2").unwrap() - y2).abs() < 1e-15);
        assert!((r.angles.value("dtheta_z2").unwrap() - z2).abs() < 1e-15);
        assert_eq!(r.fit.dof, 1);
    }
}

/// A configuration set without β = 90° cannot see Δθx0; without α = 90°
/// it cannot see Δθz2: refused, naming the angle.
#[test]
fn unseparable_gyro_plans_are_refused_by_name() {
    let no_b90 = [
        GyroConfig::deg(0.0, 0.0),
        GyroConfig::deg(0.0, 180.0),
        GyroConfig::deg(180.0, 180.0),
        GyroConfig::deg(90.0, 180.0),
    ];
    let e = predict_gyro(&no_b90, &[20.0], 1, KI_GYRO, 1e-4, false).unwrap_err();
    assert!(matches!(e, Error::Unseparable { .. }), "{e:?}");
    assert!(e.to_string().contains("dtheta_x0"), "{e}");
    let no_a90 = [
        GyroConfig::deg(0.0, 0.0),
        GyroConfig::deg(0.0, 180.0),
        GyroConfig::deg(180.0, 180.0),
        GyroConfig::deg(0.0, 90.0),
    ];
    let e = predict_gyro(&no_a90, &[20.0], 1, KI_GYRO, 1e-4, false).unwrap_err();
    assert!(e.to_string().contains("dtheta_z2"), "{e}");
    assert!(!e.to_string().contains("dtheta_x0"), "{e}");
    // Data from the paper without configuration 5 (β = 90°): refused too.
    let rows: Vec<_> = table1_rows(0).into_iter().take(8).collect();
    let e = gyro::calibrate(
        &observations_deg(&rows),
        &GyroOptions {
            scale_factor: KI_GYRO,
            per_config_bias: false,
            noise: Noise::Auto,
            scale_factor_unit: Default::default(),
            average: Default::default(),
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("dtheta_x0"), "{e}");
    // The paper's set without (180°,180°): α is always 0 or 90° at β = 180°,
    // so the fixture and gyro y-angles alias.
    let no_a180 = [
        GyroConfig::deg(0.0, 0.0),
        GyroConfig::deg(0.0, 180.0),
        GyroConfig::deg(90.0, 180.0),
        GyroConfig::deg(0.0, 90.0),
    ];
    let e = predict_gyro(&no_a180, &[20.0], 1, KI_GYRO, 1e-4, false).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("dtheta_y1") && msg.contains("dtheta_y2"),
        "{msg}"
    );
}

/// Accelerometer at 0° and 180° only (360° and −180° are the same angles):
/// two distinct angles for three terms are refused; 0/90/180 is the
/// smallest separable plan (no redundancy, so a known noise is needed).
#[test]
fn unseparable_accel_plans_are_refused() {
    let obs = |betas: &[f64]| -> Vec<AccelObservation> {
        betas
            .iter()
            .map(|b| AccelObservation {
                beta_rad: b.to_radians(),
                output: 0.0,
            })
            .collect()
    };
    let opts = AccelOptions {
        scale_factor: 1.299,
        noise: Noise::Known { sigma: 1e-6 },
        scale_factor_unit: Default::default(),
    };
    let e = accel::calibrate(&obs(&[0.0, 180.0, 360.0, 0.0]), &opts).unwrap_err();
    assert!(matches!(e, Error::TooFew { got: 2, .. }), "{e:?}");
    // β = 0, 180, −180: still only 0 and 180 → refused.
    let e = accel::calibrate(&obs(&[0.0, 180.0, -180.0]), &opts).unwrap_err();
    assert!(matches!(e, Error::TooFew { .. }), "{e:?}");
    let r = accel::calibrate(&obs(&[0.0, 90.0, 180.0]), &opts).unwrap();
    assert_eq!(r.fit.dof, 0);
}
