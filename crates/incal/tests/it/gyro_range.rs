//! The rate-transfer test's input range and saturation: clipped rates
//! named and never fitted, the input range against the one the noise-free
//! truth has, rates beyond it left out, and a noiseless record with no
//! rail.

use incal::estimation::Noise;
use incal::procedures::gyro::rate::{self as gr, GyroRateOptions, InputAxis, RateTerm};
use incal::sim::gyro::{simulate_rate, GyroRateSim};

fn rates() -> Vec<f64> {
    vec![
        -500.0, -400.0, -300.0, -200.0, -100.0, -50.0, -10.0, 10.0, 50.0, 100.0, 200.0, 300.0,
        400.0, 500.0,
    ]
}

/// K3 = 1e-8 (deg/s)^-2 bends the output by 1.25 % at 500 deg/s; the
/// converter clips at 9 output units (450 deg/s).
fn sim(seed: u64) -> GyroRateSim {
    GyroRateSim {
        k1_pos: 0.02,
        k1_neg: 0.02,
        b_deg_h: 5.0,
        k2: 0.0,
        k3: 1e-8,
        latitude_rad: 45f64.to_radians(),
        ia: InputAxis::Up,
        rates_deg_s: rates(),
        samples: 20,
        noise: 2e-4,
        runs: 1,
        run_scatter_ppm: 0.0,
        clip: 9.0,
        seed,
    }
}

fn opts(linearity_ppm: Option<f64>, output_limit: Option<f64>) -> GyroRateOptions {
    GyroRateOptions {
        latitude_deg: 45.0,
        ia: InputAxis::Up,
        terms: vec![RateTerm::B, RateTerm::K1],
        noise: Noise::Auto,
        rate_uncertainty_ppm: 0.0,
        linearity_ppm,
        output_limit,
    }
}

/// The largest deviation of the noise-free means from their straight line
/// (equal weights) over the rates up to `r`, in ppm of the full scale.
fn truth_ppm(r: f64) -> f64 {
    let s = sim(1);
    let lat = s.latitude_rad;
    let x: Vec<f64> = rates()
        .into_iter()
        .filter(|w| w.abs() <= r)
        .map(|w| gr::input_rate_deg_s(w, lat, InputAxis::Up))
        .collect();
    let y: Vec<f64> = x
        .iter()
        .map(|w| 0.02 * (w + 5.0 / 3600.0 + 1e-8 * w.powi(3)))
        .collect();
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let c1 = sxy / sxx;
    let fs = c1.abs() * x.iter().fold(0.0f64, |m, w| m.max(w.abs()));
    let worst = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (b - my - c1 * (a - mx)).abs())
        .fold(0.0, f64::max);
    worst / fs * 1e6
}

#[test]
fn clipped_rates_are_named_and_never_fitted() {
    let obs = simulate_rate(&sim(3));
    let r = gr::calibrate(&obs, &opts(None, None)).unwrap();
    assert_eq!(r.clipped_deg_s, vec![-500.0, 500.0]);
    assert!(r.positions.iter().all(|p| p.rate_deg_s.abs() < 500.0));
    assert!(r
        .warnings
        .iter()
        .any(|w| w.message.contains("clips at -500, 500 deg/s")));
    // The same fit as the record without them.
    let kept: Vec<_> = obs
        .iter()
        .filter(|o| o.rate_deg_s.abs() < 500.0)
        .cloned()
        .collect();
    let r2 = gr::calibrate(&kept, &opts(None, None)).unwrap();
    assert_eq!(r.coefficients.value("K1"), r2.coefficients.value("K1"));
    // A given limit finds them too, and 400 deg/s (8.0 output) with a
    // limit of 8.
    let r3 = gr::calibrate(&obs, &opts(None, Some(8.0))).unwrap();
    assert_eq!(r3.clipped_deg_s, vec![-500.0, -400.0, 400.0, 500.0]);
}

#[test]
fn a_noiseless_record_has_no_rail() {
    let obs = simulate_rate(&GyroRateSim {
        noise: 0.0,
        clip: 0.0,
        ..sim(3)
    });
    let r = gr::calibrate(&obs, &opts(None, None));
    if let Ok(r) = r {
        assert!(r.clipped_deg_s.is_empty());
    }
}

#[test]
fn the_input_range_is_the_truths() {
    // The noise-free truth's range for each limit, against the reduction's.
    for limit in [50.0, 150.0, 400.0, 1000.0] {
        let want = [400.0, 300.0, 200.0, 100.0, 50.0]
            .into_iter()
            .find(|r| truth_ppm(*r) <= limit);
        let r = gr::calibrate(&simulate_rate(&sim(4)), &opts(Some(limit), None)).unwrap();
        let got = r.range.as_ref().and_then(|x| x.range_deg_s);
        eprintln!("limit {limit} ppm: truth {want:?}, found {got:?}");
        assert_eq!(got, want, "limit {limit} ppm");
        let beyond: Vec<f64> = [
            -400.0f64, -300.0, -200.0, -100.0, 100.0, 200.0, 300.0, 400.0,
        ]
        .into_iter()
        .filter(|w| w.abs() > want.unwrap_or(f64::INFINITY))
        .collect();
        assert_eq!(r.beyond_deg_s, beyond, "limit {limit} ppm");
        let d = r.document(false, 0.0).unwrap();
        assert_eq!(
            d.coefficients.get("input_range_deg_s").map(|c| c.value),
            want
        );
    }
}

/// A record of more distinct rates than any rate test holds (a ramp) is
/// refused for the input range, naming the option, instead of refitting
/// the line once per rate.
#[test]
fn a_ramp_is_refused_for_the_input_range() {
    let ramp: Vec<f64> = (1..=1500).map(|k| k as f64 * 0.2).collect();
    let obs = simulate_rate(&GyroRateSim {
        rates_deg_s: ramp,
        samples: 2,
        clip: 0.0,
        ..sim(5)
    });
    let e = gr::calibrate(&obs, &opts(Some(300.0), None))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("linearity_ppm") && e.contains("1500 distinct"),
        "{e}"
    );
}
