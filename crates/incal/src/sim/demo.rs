//! The scenarios of `incal demo`, as data: every rig simulated from a known
//! truth with a seed, calibrated by its procedure into the one result
//! document, with the truth of every coefficient *as the plan observes it*.
//!
//! "As observed": a term the plan cannot separate from the fitted ones is
//! absorbed by them (e.g. with K_pp not modelled a 1 g tumble reports
//! `K0 + K_pp` and `K2 − K_pp`, [`crate::procedures::tumble::Absorption`]),
//! so the truth shown beside each estimate is the combination the estimate
//! really measures; the centrifuge's radii are the effective ones,
//! `R(1 + K_io)` (module docs of [`crate::procedures::centrifuge::radius`]).
//! A coefficient with no simple truth (a bias that shifts between
//! mountings) has none (`None`).

use std::collections::BTreeMap;

use nalgebra::Vector3;

use crate::document::{Cell, ResultDocument, Table};
use crate::error::Result;
use crate::estimation::Noise;
use crate::models::gfimu::Geometry;
use crate::models::{AccelerometerModel, Term};
use crate::procedures::tumble::plan::TumblePlan;
use crate::procedures::tumble::{calibrate as tumble_calibrate, TumbleOptions, TumbleResult};
use crate::rigs::Mount;
use crate::units::{arcsec_to_rad, rad_to_arcsec, Unit, STANDARD_GRAVITY_M_S2};

/// One calibrated scenario.
#[derive(Debug, Clone)]
pub struct DemoCase {
    /// What was simulated (plan, mount, …).
    pub heading: String,
    /// The calibration's result document.
    pub document: ResultDocument,
    /// Truth of each coefficient as the plan observes it (document units).
    pub truth: BTreeMap<String, f64>,
    /// Further tables (e.g. the motion recovered by the gyro-free unit).
    pub tables: Vec<Table>,
    /// Further findings, one line each.
    pub notes: Vec<String>,
}

/// One rig of the demo.
#[derive(Debug, Clone)]
pub struct DemoSection {
    /// Title (rig, source, standard).
    pub title: String,
    /// The virtual instrument and the plan, in a few lines.
    pub description: String,
    /// Its scenarios.
    pub cases: Vec<DemoCase>,
}

/// Every section of the demo for `seed` (same seed, same numbers).
pub fn sections(seed: u64) -> Result<Vec<DemoSection>> {
    Ok(vec![
        tumble(seed)?,
        gfimu(seed)?,
        misalign(seed)?,
        centrifuge(seed)?,
        gyro(seed)?,
        imu(seed)?,
        noise(seed)?,
    ])
}

/// Truth of a tumble's fitted terms as observed: each fitted coefficient
/// plus the absorbed terms it carries (`K_fitted + factor·K_absorbed`).
pub fn tumble_observed_truth(
    r: &TumbleResult,
    truth: &AccelerometerModel,
) -> BTreeMap<String, f64> {
    let mut out: BTreeMap<String, f64> = r
        .terms
        .iter()
        .map(|t| (t.name().to_string(), truth.get(*t)))
        .collect();
    for a in &r.absorbed {
        for (t, f) in &a.into {
            if let Some(v) = out.get_mut(t.name()) {
                *v += f * truth.get(a.term);
            }
        }
    }
    out
}

fn tumble(seed: u64) -> Result<DemoSection> {
    let truth = AccelerometerModel {
        delta_p_rad: arcsec_to_rad(-300.0),
        k_io: 5e-7,
        k_pp: 2e-6,
        ..AccelerometerModel::wu2015()
    };
    let cases = [
        (
            "pendulum mount, GJB 12-point",
            Mount::Pendulum,
            TumblePlan::gjb12(),
        ),
        ("gate mount, GJB 12-point", Mount::Gate, TumblePlan::gjb12()),
        (
            "pendulum mount, small-angle plan for a 0.5 g instrument",
            Mount::Pendulum,
            TumblePlan::for_range(0.5, 1.0)?,
        ),
    ];
    let mut out = Vec::new();
    for (k, (title, mount, plan)) in cases.into_iter().enumerate() {
        let obs = super::tumble::simulate(&super::tumble::TumbleSim {
            truth,
            mount,
            angles_deg: plan.angles_deg.clone(),
            samples: 10,
            noise: 1e-6,
            index_error_rad: arcsec_to_rad(1.0),
            passes: 1,
            seed: seed.wrapping_add(k as u64),
        });
        let r = tumble_calibrate(&obs, &TumbleOptions::new(mount))?;
        out.push(DemoCase {
            heading: format!(
                "{title}: angles {} deg",
                plan.angles_deg
                    .iter()
                    .map(|a| format!("{a}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            truth: tumble_observed_truth(&r, &truth),
            document: r.document(false)?,
            tables: Vec::new(),
            notes: Vec::new(),
        });
    }
    Ok(DemoSection {
        title: "Tumble test on a dividing head (Wu et al. 2015; GJB 1037A)".into(),
        description: "Virtual accelerometer: the instrument of Wu et al. 2015 (K1 = 10 output/g, K0 = 8 mg, ...) with K_pp = 2 ug/g^2,\n\
                      10 samples per position, output noise 1e-6, index-angle error 1 arcsec rms.\n\
                      A 1 g tumble cannot separate K_pp (pendulum) or K_oo (gate) from K0 and K2: the truth column shows\n\
                      what the plan observes (K0 + K_pp, K2 - K_pp)."
            .into(),
        cases: out,
    })
}

fn gfimu(seed: u64) -> Result<DemoSection> {
    use crate::procedures::gfimu::{calibrate, solve, CalibrateOptions, SolveOptions};
    use crate::sim::gfimu::{
        motion_truth, simulate_motion, simulate_static, six_positions, GfimuTruth, MotionProfile,
    };
    let g = Geometry::paper(0.1)?;
    let truth = GfimuTruth::typical(&g, 1.0);
    let noise = 1e-4;
    let data = simulate_static(&g, &truth, &six_positions(), 20, noise, seed)?;
    let cal = calibrate(&g, &data, &CalibrateOptions::default())?;
    let mut t = BTreeMap::new();
    for (j, a) in cal.accelerometers.iter().enumerate() {
        t.insert(format!("{}.K0", a.name), truth.k0[j]);
        t.insert(format!("{}.Ks_x", a.name), truth.ks[j].x);
        t.insert(format!("{}.Ks_y", a.name), truth.ks[j].y);
        t.insert(format!("{}.Ks_z", a.name), truth.ks[j].z);
        t.insert(format!("{}.scale_factor", a.name), truth.ks[j].norm());
    }
    let m = MotionProfile {
        axis: Vector3::new(0.2, -0.1, 1.0),
        angular_accel_rad_s2: 2.0,
        spin_up_s: 1.005,
        omega0_rad_s: Vector3::zeros(),
        f0_g: Vector3::new(0.05, 0.0, 1.0),
        duration_s: 3.0,
        rate_hz: 100.0,
        gravity_m_s2: STANDARD_GRAVITY_M_S2,
        ..MotionProfile::rate_table()
    };
    let series = simulate_motion(&g, &truth, &m, noise, seed.wrapping_add(1))?;
    let sol = solve(&g, &cal.calibrated(), &series, &SolveOptions::default())?;
    let mut motion = Table::new(
        "motion",
        "Motion recovered from the calibrated unit: spin-up about (0.2, -0.1, 1) at 2 rad/s^2 for 1.005 s, then constant rate; 100 Hz, 3 s",
        &[
            ("t_s", None),
            ("f0_z", None),
            ("truth_f0_z", None),
            ("max_f0_error_g", None),
            ("omega_dot_z", Some(Unit::Other("rad/s^2".into()))),
            ("truth_omega_dot_z", Some(Unit::Other("rad/s^2".into()))),
            ("u_omega_dot_z", Some(Unit::Other("rad/s^2".into()))),
            ("omega_z", Some(Unit::RadPerS)),
            ("truth_omega_z", Some(Unit::RadPerS)),
            ("max_omega_drift", Some(Unit::RadPerS)),
        ],
    );
    for s in sol.samples.iter().step_by(50) {
        let (f0, wd, w) = motion_truth(&m, s.time_s);
        let err = |a: &Vector3<f64>, b: &Vector3<f64>| (a - b).amax();
        motion.push(vec![
            Cell::num(s.time_s),
            Cell::num(s.f0_g.z),
            Cell::num(f0.z),
            Cell::num(err(&s.f0_g, &f0)),
            Cell::num(s.omega_dot_rad_s2.z),
            Cell::num(wd.z),
            Cell::opt(s.u_omega_dot_rad_s2.map(|u| u.z)),
            Cell::num(s.omega_rad_s.z),
            Cell::num(w.z),
            Cell::num(err(&s.omega_rad_s, &w)),
        ])?;
    }
    Ok(DemoSection {
        title: "Gyro-free inertial unit: six accelerometers (the GFIMU note)".into(),
        description: "Paper layout, lever arm 0.1 m, K1 = 1 output/g, mrad misalignments;\n\
                      six-position test with 20 samples per position, output noise 1e-4."
            .into(),
        cases: vec![DemoCase {
            heading: "six-position calibration, then a rate-table motion".into(),
            document: cal.document("paper layout, lever arm 0.1 m", false)?,
            truth: t,
            tables: vec![motion],
            notes: vec![
                "omega is integrated from the solved angular acceleration (no gyro to reset it): the noise alone gives a random walk,".into(),
                "calibration errors bias omega_dot into a linear drift, and the centripetal term feeds omega errors back, so the drift grows faster than sqrt(t).".into(),
            ],
        }],
    })
}

fn misalign(seed: u64) -> Result<DemoSection> {
    use crate::procedures::misalign::accel::{self, AccelOptions};
    use crate::procedures::misalign::gyro::{self, GyroConfig, GyroOptions, GYRO_ANGLES};
    use crate::rigs::rate_table::{FaceMounting, GyroMounting};
    use crate::sim::misalign::{simulate_accel, simulate_gyro, AccelSim, GyroSim};
    let cfg = GyroSim {
        mounting: GyroMounting {
            dtheta_x0: arcsec_to_rad(2.4),
            dtheta_y0: arcsec_to_rad(-7.5),
            dtheta_y1: arcsec_to_rad(-54.0),
            dtheta_z1: arcsec_to_rad(20.0),
            dtheta_y2: arcsec_to_rad(-162.2),
            dtheta_z2: arcsec_to_rad(55.8),
        },
        scale_factor: -2.9222,
        bias: 0.002,
        bias_shift: 2e-3,
        configs: GyroConfig::paper(),
        rates_deg_s: vec![20.0, 30.0, 40.0],
        records: 2,
        turns: 1.0,
        samples_per_turn: 36,
        noise: 1e-3,
        latitude_rad: 45.75f64.to_radians(),
        seed,
    };
    let m = cfg.mounting;
    let angle_truth = |y2: f64, z2: f64| -> BTreeMap<String, f64> {
        let mut t = BTreeMap::new();
        t.insert("dtheta_y2".to_string(), y2);
        t.insert("dtheta_z2".to_string(), z2);
        t.insert("gamma".to_string(), y2.hypot(z2));
        t.insert(
            "azimuth".to_string(),
            (-y2).atan2(z2).rem_euclid(std::f64::consts::TAU),
        );
        t
    };
    let mut gt = angle_truth(m.dtheta_y2, m.dtheta_z2);
    gt.insert("dtheta_y0".into(), m.dtheta_y0);
    gt.insert("dtheta_x0".into(), m.dtheta_x0);
    gt.insert("dtheta_y1".into(), m.dtheta_y1);
    let gopts = GyroOptions {
        scale_factor: cfg.scale_factor,
        per_config_bias: true,
        noise: Noise::Auto,
        scale_factor_unit: Default::default(),
        average: Default::default(),
    };
    let r = gyro::calibrate(&simulate_gyro(&cfg)?, &gopts)?;
    // The same test, noiseless, with 2.5-turn records averaged as recorded.
    let mut partial = cfg.clone();
    partial.turns = 2.5;
    partial.noise = 0.0;
    partial.bias_shift = 0.0;
    let rp = gyro::calibrate(
        &simulate_gyro(&partial)?,
        &GyroOptions {
            scale_factor: cfg.scale_factor,
            per_config_bias: false,
            noise: Noise::Known { sigma: 1e-9 },
            scale_factor_unit: Default::default(),
            average: Default::default(),
        },
    )?;
    let worst = GYRO_ANGLES
        .iter()
        .map(|n| {
            let t = gt.get(*n).copied().unwrap_or(f64::NAN);
            rad_to_arcsec((rp.angles.value(n).unwrap_or(f64::NAN) - t).abs())
        })
        .fold(0.0, f64::max);
    let acfg = AccelSim {
        mounting: FaceMounting {
            dtheta_y0: arcsec_to_rad(30.0),
            dtheta_y1: 0.0,
            dtheta_y2: arcsec_to_rad(-5.3),
            dtheta_z2: arcsec_to_rad(20.5),
        },
        scale_factor: 1.299,
        bias: -0.002,
        betas_rad: [0.0f64, 90.0, 180.0, 270.0]
            .iter()
            .map(|b| b.to_radians())
            .collect(),
        samples: 10,
        noise: 2e-5,
        seed: seed.wrapping_add(1),
    };
    let aopts = AccelOptions {
        scale_factor: acfg.scale_factor,
        noise: Noise::Auto,
        scale_factor_unit: Default::default(),
    };
    let ra = accel::calibrate(&simulate_accel(&acfg), &aopts)?;
    Ok(DemoSection {
        title: "Misalignment separation (Li et al. 2012)".into(),
        description: "Virtual gyro on a rate table: kI = -2.9222 V/(deg/s), the paper's five configurations,\n\
                      +-20/30/40 deg/s, 2 one-turn records each, Earth rate at 45.75 deg N, noise 1 mV per sample,\n\
                      bias shifting 2 mV rms between mountings (fitted per configuration).\n\
                      Virtual accelerometer on a vertical face: kI = 1.299 V/g, beta = 0/90/180/270 deg, 10 samples each, noise 20 uV."
            .into(),
        cases: vec![
            DemoCase {
                heading: "gyro on a rate table".into(),
                document: r.document(&gopts, &[])?,
                truth: gt,
                tables: Vec::new(),
                notes: vec![format!(
                    "noiseless records of 2.5 turns averaged as recorded: largest angle error {worst:.2} arcsec (Earth rate); `incal misalign gyro --average whole` removes it"
                )],
            },
            DemoCase {
                heading: "accelerometer on a vertical face".into(),
                document: ra.document(&aopts)?,
                truth: angle_truth(acfg.mounting.dtheta_y2, acfg.mounting.dtheta_z2),
                tables: Vec::new(),
                notes: Vec::new(),
            },
        ],
    })
}

/// The centrifuge scenario's truth instrument (g units).
pub fn centrifuge_truth() -> AccelerometerModel {
    AccelerometerModel {
        k0_g: 1.2e-4,
        k1_out_per_g: 1.3,
        k2: 3.9e-6,
        k3: 5e-9,
        delta_o_rad: arcsec_to_rad(40.0),
        delta_p_rad: arcsec_to_rad(-20.0),
        k_ip: 7e-6,
        k_io: 2e-6,
        k_po: -1e-6,
        k_pp: 4.6e-7,
        k_oo: -3e-7,
        k_oq: 5e-7,
    }
}

/// The centrifuge scenario's rig: He & Yin 2017's radii (ECM offset 4.49 mm),
/// IA tilt 60″, latitude 39.9° N, standard gravity.
pub fn centrifuge_rig() -> crate::rigs::centrifuge::Centrifuge {
    crate::rigs::centrifuge::Centrifuge {
        r_plus_m: 0.714775,
        r_minus_m: 0.705794,
        latitude_rad: 39.9f64.to_radians(),
        g_local_m_s2: STANDARD_GRAVITY_M_S2,
        opposite_sense: false,
        tilt_rad: arcsec_to_rad(60.0),
    }
}

fn centrifuge(seed: u64) -> Result<DemoSection> {
    use crate::procedures::centrifuge::{calibrate, CentrifugeOptions, CENTRIFUGE_TERMS};
    use crate::sim::centrifuge::{rates_for_levels, simulate, standard_positions, CentrifugeSim};
    let truth = centrifuge_truth();
    let rig = centrifuge_rig();
    let obs = simulate(&CentrifugeSim {
        truth,
        rig,
        positions: standard_positions(),
        rates_rad_s: rates_for_levels(
            &[0.0, 1.0, 2.0, 4.0, 7.0, 10.0, 14.0, 18.0, 22.0, 25.0],
            0.71,
            STANDARD_GRAVITY_M_S2,
        ),
        samples: 5,
        noise: 2e-6,
        seed,
    });
    let opts = CentrifugeOptions {
        from: None,
        k0: Some(truth.k0_g),
        u_k0: Some(2e-6),
        k1: Some(truth.k1_out_per_g),
        u_k1: Some(1.3e-6),
        cov_k0_k1: Some(0.0),
        radius_m: 0.71,
        latitude_deg: 39.9,
        gravity_m_s2: rig.g_local_m_s2,
        opposite_sense: false,
        order: 3,
        alignment_tolerance_deg: 0.0,
        noise: Noise::Auto,
        terms: None,
        u_omega_ppm: 0.0,
    };
    let r = calibrate(&obs, &opts)?;
    let mut t: BTreeMap<String, f64> = CENTRIFUGE_TERMS
        .iter()
        .map(|term: &Term| (term.name().to_string(), truth.get(*term)))
        .collect();
    // Radii measured at ip,0 are effective: R(1 + K_io).
    let eff = 1.0 + truth.k_io;
    for (name, v) in [
        ("R_plus_m", rig.r_plus_m),
        ("R_minus_m", rig.r_minus_m),
        ("R_plus_static_m", rig.r_plus_m),
        ("R_minus_static_m", rig.r_minus_m),
        ("R_centre_m", 0.5 * (rig.r_plus_m + rig.r_minus_m)),
        ("ecm_offset_m", rig.ecm_offset_m()),
    ] {
        t.insert(name.to_string(), v * eff);
    }
    Ok(DemoSection {
        title: "Precision centrifuge: radius, nonlinearity, cross-coupling (He & Yin 2017; IEEE Std 836)".into(),
        description: "Virtual accelerometer (K1 = 1.3 output/g), R+ = 0.714775 m, R- = 0.705794 m (ECM offset 4.49 mm),\n\
                      IA tilt 60 arcsec, latitude 39.9 deg, 0..25 g at ip,0 ip,90 io,90 ip,45 io,45 po,45, both polarities,\n\
                      5 samples per point, output noise 2e-6; K0 and K1 known to 2 ug and 1 ppm.\n\
                      Radii are effective radii R(1 + K_io), as the paper measures them."
            .into(),
        cases: vec![DemoCase {
            heading: "full position set, model order 3".into(),
            document: r.document(&opts)?,
            truth: t,
            tables: Vec::new(),
            notes: Vec::new(),
        }],
    })
}

fn gyro(seed: u64) -> Result<DemoSection> {
    use crate::procedures::gyro::positions::{self as gp, Axial, GyroPositionsOptions, K1Source};
    use crate::procedures::gyro::rate::{self as gr, GyroRateOptions, InputAxis, RateTerm};
    use crate::sim::gyro::{
        simulate_positions, simulate_rate, DriftTruth, GyroPositionsSim, GyroRateSim,
    };
    let latitude_rad = 45.75f64.to_radians();
    let k1 = 0.02;
    let rcfg = GyroRateSim {
        k1_pos: k1 * (1.0 + 100e-6),
        k1_neg: k1 * (1.0 - 100e-6),
        b_deg_h: 5.0,
        k2: 2e-5,
        k3: 0.0,
        latitude_rad,
        ia: InputAxis::Up,
        rates_deg_s: vec![
            -200.0, -100.0, -50.0, -10.0, -1.0, 1.0, 10.0, 50.0, 100.0, 200.0,
        ],
        samples: 20,
        noise: 2e-5,
        runs: 1,
        run_scatter_ppm: 0.0,
        clip: 0.0,
        seed: seed.wrapping_add(40),
    };
    let ropts = GyroRateOptions {
        latitude_deg: 45.75,
        ia: InputAxis::Up,
        terms: vec![RateTerm::K1, RateTerm::B, RateTerm::K2],
        noise: Noise::Auto,
        rate_uncertainty_ppm: 0.0,
        linearity_ppm: None,
        output_limit: None,
    };
    let rr = gr::calibrate(&simulate_rate(&rcfg), &ropts)?;
    // K1 seen by the main fit: the mean of K1+ and K1- (the asymmetry is
    // reported separately); K2 as observed is K1±K2/K1.
    let mut rt = BTreeMap::new();
    rt.insert("K1".to_string(), k1);
    rt.insert("B".to_string(), 5.0);
    rt.insert("K2".to_string(), 2e-5);
    rt.insert("K1_pos".to_string(), rcfg.k1_pos);
    rt.insert("K1_neg".to_string(), rcfg.k1_neg);
    rt.insert("asymmetry".to_string(), 200.0);
    let drift = DriftTruth {
        b: 3.0,
        d_i: 0.8,
        d_o: -0.5,
        ..DriftTruth::default()
    };
    let pcfg = GyroPositionsSim {
        k1,
        drift,
        latitude_rad,
        azimuths_rad: vec![90f64.to_radians()],
        axial: Axial::Sa,
        angles_deg: (0..12).map(|k| 30.0 * k as f64).collect(),
        samples: 10,
        noise: 2e-5,
        seed: seed.wrapping_add(41),
    };
    let (k1_fit, u_k1) = rr.coefficients.get("K1").unwrap_or((k1, 0.0));
    // K1 with its u and dof handed over from the rate test.
    let from = K1Source::Result {
        k1: k1_fit,
        u: u_k1,
        dof: rr.coefficients.dof(),
        input: crate::document::InputFile {
            role: "from".into(),
            path: "gyro rate (demo)".into(),
            sha256: String::new(),
            rows: None,
        },
    };
    let sf = from.scale_factor();
    let popts = GyroPositionsOptions {
        k1: None,
        u_k1: None,
        k1_from: Some(from),
        ..GyroPositionsOptions::new(45.75, Axial::Sa, k1_fit, None)
    };
    let pr = gp::calibrate(&simulate_positions(&pcfg), &popts)?;
    let pt: BTreeMap<String, f64> = ["B", "D_I", "D_O"]
        .iter()
        .map(|n| (n.to_string(), drift.get(n)))
        .collect();
    Ok(DemoSection {
        title: "Gyro tests: rate table and dividing head (IEEE Std 952 / 1431 / 517)".into(),
        description: "Virtual gyro: K1 = 0.02 output/(deg/s) with 200 ppm asymmetry, B = 5 deg/h, K2 = 2e-5 /(deg/s),\n\
                      D_I = 0.8, D_O = -0.5 deg/h/g; noise 2e-5 per sample; latitude 45.75 deg N.\n\
                      Rate table: +-1/10/50/100/200 deg/s, 20 samples each. Dividing head: 12 angles, axis east (azimuth 90 deg),\n\
                      spin axis along the head axis, 10 samples each, K1 and its u handed over from the rate test."
            .into(),
        cases: vec![
            DemoCase {
                heading: "rate-transfer test (IA up)".into(),
                document: rr.document(false, 0.0)?,
                truth: rt,
                tables: Vec::new(),
                notes: vec![format!(
                    "nonlinearity {:.0} ppm of full scale (the K2 term, read off the straight line)",
                    rr.nonlinearity_ppm_fs
                )],
            },
            DemoCase {
                heading: "multi-position test (Earth rate as the known input)".into(),
                document: pr.document(false, sf, "sa")?,
                truth: pt,
                tables: Vec::new(),
                notes: Vec::new(),
            },
        ],
    })
}

fn imu(seed: u64) -> Result<DemoSection> {
    use crate::procedures::imu::autocal::{autocal, AutocalOptions, Method};
    use crate::procedures::imu::ferraris::{element_names, ferraris, FerrarisOptions, SECTIONS};
    use crate::sim::imu::{simulate, ImuSim, ImuTruth, Sequence};
    let truth = ImuTruth::mems_counts();
    let fs = simulate(&ImuSim {
        truth: truth.clone(),
        sequence: Sequence::Ferraris {
            rotation_deg: -360.0,
            rotation_s: 6.0,
        },
        rate_hz: 100.0,
        static_s: 3.0,
        gravity: 9.81,
        noise_acc: 3.0,
        noise_gyr: 2.0,
        latitude_deg: None,
        seed: seed.wrapping_add(50),
    })?;
    let mut secs: [Vec<[f64; 6]>; 9] = Default::default();
    for x in &fs {
        if let Some(k) = SECTIONS.iter().position(|l| *l == x.part) {
            secs[k].push([x.acc[0], x.acc[1], x.acc[2], x.gyr[0], x.gyr[1], x.gyr[2]]);
        }
    }
    let fr = ferraris(&secs, &FerrarisOptions::imucal(100.0))?;
    let ft: BTreeMap<String, f64> = element_names()
        .into_iter()
        .zip(truth.ferraris().to_vec())
        .filter(|(n, _)| {
            !n.starts_with("K_a.") && !n.starts_with("K_g.")
                || n.ends_with("xx")
                || n.ends_with("yy")
                || n.ends_with("zz")
        })
        .collect();
    // Autocalibration: the gyro's g-sensitivity is outside its model.
    let mut t2 = truth.clone();
    t2.gyr_k_ga = nalgebra::Matrix3::zeros();
    let rs = simulate(&ImuSim {
        truth: t2.clone(),
        sequence: Sequence::Random {
            positions: 24,
            init_s: 10.0,
            move_s: 1.5,
        },
        rate_hz: 100.0,
        static_s: 2.5,
        gravity: 9.81,
        noise_acc: 3.0,
        noise_gyr: 2.0,
        latitude_deg: None,
        seed: seed.wrapping_add(51),
    })?;
    let time: Vec<f64> = rs.iter().map(|x| x.time_s).collect();
    let acc: Vec<[f64; 3]> = rs.iter().map(|x| [x.acc[0], x.acc[1], x.acc[2]]).collect();
    let gyr: Vec<[f64; 3]> = rs.iter().map(|x| [x.gyr[0], x.gyr[1], x.gyr[2]]).collect();
    let ar = autocal(
        &time,
        &acc,
        Some(&gyr),
        &AutocalOptions::new(Method::Incal, 9.81, 10.0),
    )?;
    let mut at = BTreeMap::new();
    if let Some((a, g)) = t2.imu_tk() {
        let names = ["m_yz", "m_zy", "m_zx", "m_xz", "m_xy", "m_yx"];
        for (k, n) in names.iter().enumerate() {
            if k < 3 {
                at.insert(format!("acc.{n}"), a.mis[k]);
            }
            at.insert(format!("gyr.{n}"), g.mis[k]);
        }
        for (k, ax) in ["x", "y", "z"].iter().enumerate() {
            at.insert(format!("acc.s_{ax}"), a.scale[k]);
            at.insert(format!("acc.b_{ax}"), a.bias[k]);
            at.insert(format!("gyr.s_{ax}"), g.scale[k].to_degrees()); // (deg/s)/output
            at.insert(format!("gyr.b_{ax}"), g.bias[k]);
        }
    }
    Ok(DemoSection {
        title: "IMU triad: Ferraris six positions + three rotations (imucal), autocalibration (Tedaldi 2014)".into(),
        description: "Virtual MEMS IMU in raw counts: about 2040 counts/g and 16.4 counts/(deg/s), biases of tens of counts,\n\
                      misalignments of 2-4 mrad, gyro g-sensitivity up to 0.018 counts/(m/s^2); white noise 3 and 2 counts per sample, 100 Hz.\n\
                      Ferraris: 3 s in each of the six positions, one -360 deg turn of 6 s about each axis.\n\
                      Autocalibration: 10 s still, then 24 random orientations (2.5 s still, 1.5 s turns), no fixture; the truth has no g-sensitivity."
            .into(),
        cases: vec![
            DemoCase {
                heading: "Ferraris (imucal's definitions)".into(),
                document: fr.document()?,
                truth: ft,
                tables: Vec::new(),
                notes: Vec::new(),
            },
            DemoCase {
                heading: "autocalibration, method incal (imu_tk's T, K, b)".into(),
                document: ar.document()?,
                truth: at,
                tables: Vec::new(),
                notes: vec![format!(
                    "{} still intervals found at k = {} ({} distinct orientations)",
                    ar.intervals.len(),
                    ar.k,
                    ar.orientations
                )],
            },
        ],
    })
}

fn noise(seed: u64) -> Result<DemoSection> {
    use crate::document::noise::{document, ChannelResult, Quantity};
    use crate::noise::{phase_from_rate, stability, terms, StabilityOptions, TauGrid};
    use crate::sim::noise::{rate_record, NoiseTruth};
    // Gyro in deg/s: ARW 0.06 deg/sqrt(h), bias instability 0.36 deg/h,
    // RRW 1.08 deg/h/sqrt(h) (the simulator's base: deg/s with seconds).
    let truth = NoiseTruth {
        q: 0.0,
        n: 0.06 / 60.0,
        b: 0.36 / 3600.0,
        k: 1.08 / 216_000.0,
        r: 0.0,
    };
    let tau0 = 0.1;
    let n = 1 << 20;
    let y = rate_record(&truth, tau0, n, seed.wrapping_add(60));
    let x = phase_from_rate(&y, tau0);
    let st = stability(
        &x,
        &StabilityOptions {
            tau0_s: tau0,
            grid: TauGrid::Octave,
            confidence: 0.683,
            parallel: true,
        },
    )?;
    let fit = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, tau0, x.len())?;
    let slope = terms::slope_readings(&st.taus_s, &st.oadev);
    let bias_stability = [10.0, 100.0]
        .iter()
        .map(|&t| (t, terms::bias_stability(&x, tau0, t)))
        .collect();
    let c = ChannelResult {
        name: "gx".into(),
        samples: n,
        stability: st,
        fit,
        slope,
        bias_stability,
        more: Vec::new(),
        to_input: 1.0,
        spectrum: None,
        gauss_markov: None,
        davar: None,
        temperature: None,
    };
    let doc = document(
        &crate::noise::Deviation::ALL,
        &[c],
        &Quantity::Gyro,
        "deg/s",
        0.683,
        false,
    )?;
    let mut t = BTreeMap::new();
    t.insert("gx.ARW".to_string(), 0.06);
    t.insert("gx.bias_instability".to_string(), 0.36);
    t.insert("gx.RRW".to_string(), 1.08);
    Ok(DemoSection {
        title: "Noise and stability: Allan family, IEEE Std 952 terms (incal noise)".into(),
        description: "Virtual gyro rate record, 10 Hz for 29 h (2^20 samples): ARW 0.06 deg/sqrt(h) (white),\n\
                      bias instability 0.36 deg/h (flicker, Kasdin-Walter), RRW 1.08 deg/h/sqrt(h) (random walk).\n\
                      The IEEE 952 model fitted to OADEV at octave taus, weights from the Greenhall-Riley EDF; bias stability (GJB) has no simple truth."
            .into(),
        cases: vec![DemoCase {
            heading: "one channel, octave taus".into(),
            document: doc,
            truth: t,
            tables: Vec::new(),
            notes: Vec::new(),
        }],
    })
}
