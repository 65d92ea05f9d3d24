use super::*;

fn chans(samples: Vec<Vec<f64>>, gaps: Vec<(usize, usize)>) -> Channels {
    Channels {
        names: (0..samples.len()).map(|k| format!("c{k}")).collect(),
        rows: samples[0].len(),
        samples,
        rate_hz: 10.0,
        timebase: None,
        gaps,
        duplicates: 0,
        sorted: 0,
        temperature_c: None,
    }
}

fn white(n: usize, seed: u64) -> Vec<f64> {
    let mut r = crate::sim::rng(seed);
    (0..n).map(|_| crate::sim::normal(&mut r, 1.0)).collect()
}

#[test]
fn outliers_beyond_k_mad_sigmas_are_removed_and_listed() {
    let mut y = white(2000, 1);
    for &(i, v) in &[(10, 40.0), (11, -35.0), (900, 25.0)] {
        y[i] = v;
    }
    let o = PreprocessOptions {
        outliers: Some("mad:6".into()),
        ..Default::default()
    };
    let (c, j, t) = apply(&chans(vec![y.clone()], vec![]), &o).unwrap().unwrap();
    let nan: Vec<usize> = (0..2000).filter(|&i| c.samples[0][i].is_nan()).collect();
    assert_eq!(nan, [10, 11, 900]);
    assert_eq!(
        j[0]["channels"]["c0"]["samples"],
        json!([[10, 11], [900, 900]])
    );
    assert_eq!(j[0]["channels"]["c0"]["removed"], 3);
    assert!(j[0]["summary"].as_str().unwrap().contains("3 samples"));
    assert_eq!(t.rows.len(), 1);
    // The rest untouched.
    assert!((0..2000)
        .filter(|i| ![10, 11, 900].contains(i))
        .all(|i| c.samples[0][i] == y[i]));
}

#[test]
fn fill_interpolates_cells_and_stamp_gaps_and_cuts_the_ends() {
    // A ramp 0, 1, 2, … with cells 3–4 empty, the stamps skipping 2
    // periods before sample 8, and the first and last cells empty.
    let mut y: Vec<f64> = (0..12).map(|i| i as f64).collect();
    // Sample 8 and after sit 2 periods later: values follow the grid.
    for v in y.iter_mut().skip(8) {
        *v += 2.0;
    }
    y[3] = f64::NAN;
    y[4] = f64::NAN;
    y[0] = f64::NAN;
    y[11] = f64::NAN;
    let o = PreprocessOptions {
        fill: Some(Fill::Gaps),
        ..Default::default()
    };
    let (c, j, _) = apply(&chans(vec![y], vec![(8, 2)]), &o).unwrap().unwrap();
    // Rows 1..=12 of the 14-sample grid remain: values 1 … 12.
    let want: Vec<f64> = (1..=12).map(|i| i as f64).collect();
    assert_eq!(c.rows, 12);
    assert!(c.gaps.is_empty());
    for (a, b) in c.samples[0].iter().zip(&want) {
        assert!((a - b).abs() < 1e-12, "{:?}", c.samples[0]);
    }
    assert_eq!(j[0]["stamp_periods_inserted"], 2);
    assert_eq!(
        (j[0]["cut_start"].clone(), j[0]["cut_end"].clone()),
        (json!(1), json!(1))
    );
    // Indices after the cut: cells 3–4 are 2–3; the inserted periods 7–8.
    assert_eq!(j[0]["channels"]["c0"]["samples"], json!([[2, 3], [7, 8]]));
}

#[test]
fn each_drift_model_is_recovered_and_removed() {
    let n = 4000;
    let noise = white(n, 3);
    let t: Vec<f64> = (0..n).map(|i| i as f64 / 10.0).collect();
    for (d, f, keys) in [
        (
            Detrend::Linear,
            Box::new(|t: f64| 5.0 + 0.02 * t) as Box<dyn Fn(f64) -> f64>,
            vec![("offset", 5.0), ("slope_per_s", 0.02)],
        ),
        (
            Detrend::Quadratic,
            Box::new(|t: f64| -1.0 + 0.01 * t + 3e-5 * t * t),
            vec![
                ("offset", -1.0),
                ("slope_per_s", 0.01),
                ("curvature_per_s2", 3e-5),
            ],
        ),
        (
            Detrend::Log,
            Box::new(|t: f64| 2.0 + 4.0 * (0.05 * t).ln_1p()),
            vec![("offset", 2.0), ("a", 4.0), ("b_per_s", 0.05)],
        ),
    ] {
        let y: Vec<f64> = t
            .iter()
            .zip(&noise)
            .map(|(&t, e)| f(t) + 0.01 * e)
            .collect();
        let o = PreprocessOptions {
            detrend: Some(d),
            ..Default::default()
        };
        let (c, j, _) = apply(&chans(vec![y], vec![]), &o).unwrap().unwrap();
        let coef = &j[0]["channels"]["c0"]["coefficients"];
        for (k, want) in keys {
            let got = coef[k].as_f64().unwrap();
            assert!(
                (got - want).abs() <= 0.02 * want.abs(),
                "{d:?} {k}: {got} vs {want}"
            );
        }
        // What remains is the noise (to the fit's own small error).
        let rms = (c.samples[0]
            .iter()
            .zip(&noise)
            .map(|(a, e)| (a - 0.01 * e).powi(2))
            .sum::<f64>()
            / n as f64)
            .sqrt();
        assert!(rms < 2e-3, "{d:?}: {rms}");
    }
}

#[test]
fn a_malformed_outlier_rule_is_named() {
    for bad in ["mad", "mad:x", "mad:1", "iqr:3", "mad:1e9"] {
        let o = PreprocessOptions {
            outliers: Some(bad.into()),
            ..Default::default()
        };
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains("outliers"), "{bad}: {e}");
    }
    assert!(PreprocessOptions::default().validate().is_ok());
}
