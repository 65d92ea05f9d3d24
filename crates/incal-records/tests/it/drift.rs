//! History and drift on simulated drifting calibrations: K0 stepping
//! linearly over chosen (irregular) dates plus noise of each calibration's
//! own u. The store recovers the drift rate within its uncertainty, and
//! over many simulated histories the stated u covers the true rate as
//! often as it claims.

use crate::common;

use common::{temp_dir, tumble_doc, Rng};
use incal::estimation::VarianceSource;
use incal_records::history::{self, HistoryPoint};
use incal_records::{NewRecord, Store};

/// Truth: K0 = 2 mg on day 0, drifting 0.5 µg/day.
const K0: f64 = 2e-3;
const RATE: f64 = 0.5e-6;

/// Calibration days (irregular, about two years) and their u.
const DAYS: [i64; 7] = [0, 41, 97, 180, 260, 400, 731];
const U: [f64; 7] = [20e-6, 15e-6, 25e-6, 15e-6, 20e-6, 10e-6, 15e-6];

#[test]
fn store_recovers_the_drift_within_its_u() {
    let path = temp_dir("drift").join("incal.db");
    let mut s = Store::open(&path).unwrap();
    let mut rng = Rng::new(20250314);
    let start = incal_records::time::parse_utc("2023-05-02T08:30:00Z").unwrap();
    let mut values = Vec::new();
    for (d, u) in DAYS.iter().zip(U) {
        let value = K0 + RATE * *d as f64 + u * rng.normal();
        values.push(value);
        let doc = tumble_doc(Some("SN-D"), value, u, 40.0);
        let when = incal_records::time::format_utc(start + d * 86_400);
        s.add(&NewRecord {
            created_utc: Some(&when),
            ..NewRecord::new(&doc)
        })
        .unwrap();
    }
    // A record of another instrument between them changes nothing.
    s.add(&NewRecord::new(&tumble_doc(Some("SN-E"), 1.0, 0.1, 5.0)))
        .unwrap();
    let h = s.history("SN-D", "K0").unwrap();
    assert_eq!(h.points.len(), DAYS.len());
    assert_eq!(h.unit.as_str(), "g");
    let d = h.drift.clone().unwrap();
    assert_eq!(d.unit, "g/day");
    assert!(
        (d.value - RATE).abs() < 3.0 * d.u,
        "drift {} ± {} vs truth {RATE}",
        d.value,
        d.u
    );
    // The u of a slope over two years with ~17 µg per point: ~0.03 µg/day.
    assert!(d.u > 0.01e-6 && d.u < 0.1e-6, "{d:?}");
    assert_eq!(d.variance_source, VarianceSource::Prior);
    // Welch–Satterthwaite from 40 dof per calibration: between 40 and 7·40.
    let nu = d.dof.unwrap();
    assert!(nu > 40.0 && nu < 280.0, "{nu}");

    let r = h.repeatability.clone().unwrap();
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let sd = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 6.0).sqrt();
    assert!((r.value - sd).abs() < 1e-15);
    assert_eq!(r.dof, 6.0);
    let (a, b) = (&h.points[6], &h.points[5]);
    let en = (a.value - b.value) / (a.u95.powi(2) + b.u95.powi(2)).sqrt();
    assert!((h.en_latest.unwrap() - en).abs() < 1e-12);
}

fn simulated(rng: &mut Rng, rate: f64, extra_sd: f64) -> Vec<HistoryPoint> {
    DAYS.iter()
        .zip(U)
        .enumerate()
        .map(|(k, (d, u))| HistoryPoint {
            id: k as i64 + 1,
            created_utc: incal_records::time::format_utc(1_600_000_000 + d * 86_400),
            value: K0 + rate * *d as f64 + u * rng.normal() + extra_sd * rng.normal(),
            u,
            u95: 1.96 * u,
            dof: None,
            unit: incal::units::Unit::G,
            temperature_c: None,
        })
        .collect()
}

#[test]
fn the_stated_u_of_the_drift_covers_the_truth() {
    let mut rng = Rng::new(7);
    let trials = 2000;
    let mut covered = 0;
    for _ in 0..trials {
        let d = history::drift(&simulated(&mut rng, RATE, 0.0)).unwrap();
        if (d.value - RATE).abs() <= 1.96 * d.u {
            covered += 1;
        }
    }
    // 95 % coverage; binomial sd over 2000 trials is 0.5 %.
    let p = covered as f64 / trials as f64;
    assert!((0.93..=0.97).contains(&p), "coverage {p}");
}

#[test]
fn scatter_beyond_the_u_widens_the_drift_u() {
    // The instrument wanders 60 µg between calibrations whose u says 10–25:
    // the χ² test sees it and u(b) grows with the residual scatter.
    let mut rng = Rng::new(11);
    let mut from_residuals = 0;
    let mut covered = 0;
    let trials = 500;
    for _ in 0..trials {
        let d = history::drift(&simulated(&mut rng, RATE, 60e-6)).unwrap();
        if d.variance_source == VarianceSource::Residuals {
            from_residuals += 1;
            assert_eq!(d.dof, Some(5.0));
        }
        // Coverage with the t quantile of the stated dof (5 when scaled).
        let k = incal::estimation::coverage_factor(d.dof.unwrap_or(f64::INFINITY), 0.95);
        if (d.value - RATE).abs() <= k * d.u {
            covered += 1;
        }
    }
    assert!(
        from_residuals as f64 > 0.9 * trials as f64,
        "{from_residuals}"
    );
    let p = covered as f64 / trials as f64;
    assert!(p > 0.9, "coverage {p}");
}
