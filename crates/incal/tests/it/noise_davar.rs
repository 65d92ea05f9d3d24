//! The dynamic Allan variance (`davar`), round trip: the windows' bounds
//! cover a stationary truth, the stationarity test keeps its false-alarm
//! rate on stationary records from both generators, and finds a noise that
//! changes half-way; the document carries the table, the surface and the
//! warning.
//!
//! The rates are printed (`-- --nocapture`) and quoted in the noise
//! chapter.

use incal::noise::{phase_from_rate, stability, StabilityOptions};
use incal::procedures::noise::davar::{Davar, DavarOptions};
use incal::procedures::noise::{Noise, NoiseOptions};
use incal::procedures::{reduce_source, Silent};
use incal::sim::noise::{rate_record, spectral_record, NoiseTruth};
use incal::sim::tier::{at_least, at_most, band, trials};
use incal::sim::{monte_carlo, trial_seed};

/// The dynamic Allan variance of rate samples `y` at τ0 = 1 s, window and
/// step `spec`, bounds at 95 %.
fn davar_of(y: &[f64], spec: &str) -> Davar {
    let x = phase_from_rate(y, 1.0);
    let opts = StabilityOptions {
        parallel: false,
        ..Default::default()
    };
    let st = stability(&x, &opts).unwrap();
    DavarOptions {
        davar: Some(spec.into()),
    }
    .compute(&x, 1.0, &st, 0.95, false)
    .unwrap()
    .unwrap()
}

fn rejects(d: &Davar) -> bool {
    d.test.as_ref().is_some_and(|t| !t.rejected().is_empty())
}

#[test]
fn window_bounds_cover_a_stationary_white_truth() {
    let truth = NoiseTruth {
        n: 0.01,
        ..Default::default()
    };
    let n = trials(8, 100);
    let res = monte_carlo(71, n, |s| {
        let d = davar_of(&rate_record(&truth, 1.0, 1 << 15, s), "4096,4096");
        let mut cells = (0usize, 0usize);
        for w in &d.values {
            for (tau, c) in d.taus_s.iter().zip(w) {
                let want = truth.n / tau.sqrt();
                cells.0 += 1;
                cells.1 += usize::from(c.b.is_some_and(|(lo, hi)| lo <= want && want <= hi));
            }
        }
        cells
    });
    let (all, cover) = res.iter().fold((0, 0), |a, c| (a.0 + c.0, a.1 + c.1));
    let rate = cover as f64 / all as f64;
    eprintln!("davar white: 95 % bounds cover the truth in {cover}/{all} window cells");
    // Cells of one record are correlated across τ: the band counts records.
    let (lo, hi) = band(n, 0.93, 0.97);
    assert!(
        (lo..=hi).contains(&rate),
        "coverage {rate:.3} outside [{lo:.3}, {hi:.3}]"
    );
}

/// A seeded record generator: truth, τ0 (s), samples, seed.
type Generator = fn(&NoiseTruth, f64, usize, u64) -> Vec<f64>;

const GENERATORS: [(&str, Generator); 2] = [
    ("time-domain", rate_record),
    ("frequency-domain", spectral_record),
];

#[test]
fn stationary_records_keep_the_false_alarm_rate() {
    let mixes = [
        (
            "white",
            NoiseTruth {
                n: 0.01,
                ..Default::default()
            },
        ),
        (
            "white + flicker",
            NoiseTruth {
                n: 0.01,
                b: 1e-3,
                ..Default::default()
            },
        ),
        (
            "white + random walk",
            NoiseTruth {
                n: 0.01,
                k: 1e-4,
                ..Default::default()
            },
        ),
    ];
    let n = trials(20, 200);
    let mut failed = Vec::new();
    for (name, truth) in mixes {
        for (gen_name, generate) in GENERATORS {
            let res = monte_carlo(72, n, |s| {
                rejects(&davar_of(&generate(&truth, 1.0, 1 << 15, s), "4096,1024"))
            });
            let alarms = res.iter().filter(|r| **r).count();
            eprintln!("davar {name} ({gen_name}): non-stationary in {alarms}/{n}");
            // The stated family-wise rate is 1 %; Bonferroni over τ and the
            // EDF's approximations leave room, not beyond 2 %.
            if alarms as f64 > at_most(n, 0.02) * n as f64 {
                failed.push(format!("{name} ({gen_name}): {alarms}/{n}"));
            }
        }
    }
    assert!(failed.is_empty(), "false alarms: {}", failed.join("; "));
}

/// White noise whose level steps by `ratio` half-way.
fn stepped(seed: u64, ratio: f64) -> Vec<f64> {
    let a = NoiseTruth {
        n: 0.01,
        ..Default::default()
    };
    let b = NoiseTruth {
        n: 0.01 * ratio,
        ..Default::default()
    };
    let mut y = rate_record(&a, 1.0, 1 << 14, trial_seed(seed, 0));
    y.extend(rate_record(&b, 1.0, 1 << 14, trial_seed(seed, 1)));
    y
}

#[test]
fn a_noise_that_steps_half_way_is_found() {
    let n = trials(20, 200);
    let res = monte_carlo(73, n, |s| rejects(&davar_of(&stepped(s, 1.5), "4096,1024")));
    let found = res.iter().filter(|r| **r).count();
    eprintln!("davar white x1.5 half-way: non-stationary in {found}/{n}");
    assert!(
        found as f64 >= at_least(n, 0.95) * n as f64,
        "found in {found}/{n}"
    );
    // The power against a smaller step, printed for the chapter.
    for ratio in [1.03, 1.05] {
        let res = monte_carlo(74, n, |s| {
            rejects(&davar_of(&stepped(s, ratio), "4096,1024"))
        });
        let found = res.iter().filter(|r| **r).count();
        eprintln!("davar white x{ratio} half-way: non-stationary in {found}/{n}");
    }
}

fn csv(y: &[f64]) -> String {
    let mut s = String::from("time_s,gx\n");
    for (i, v) in y.iter().enumerate() {
        s.push_str(&format!("{i},{v:e}\n"));
    }
    s
}

fn doc_of(y: &[f64], spec: &str) -> incal::Result<serde_json::Value> {
    let o = NoiseOptions {
        parallel: false,
        davar: DavarOptions {
            davar: Some(spec.into()),
        },
        ..Default::default()
    };
    let doc = reduce_source::<Noise, _>(
        "rec.csv",
        csv(y).as_bytes(),
        &incal_io::ReadOptions::default(),
        &o,
        &Silent,
    )?;
    Ok(serde_json::to_value(&doc).unwrap())
}

#[test]
fn the_document_holds_the_surface_the_table_and_the_warning() {
    let doc = doc_of(&stepped(5, 3.0), "4096,2048").unwrap();
    let d = &doc["channels"]["gx"]["davar"];
    assert_eq!(d["window_samples"], 4096);
    assert_eq!(d["step_samples"], 2048);
    let windows = d["windows"].as_u64().unwrap() as usize;
    assert_eq!(windows, (32768 - 4096) / 2048 + 1);
    let taus = d["taus_s"].as_array().unwrap().len();
    assert_eq!(taus, 11, "1 s to 1024 s by octaves: {}", d["taus_s"]);
    assert_eq!(d["adev"].as_array().unwrap().len(), windows);
    // The first window's ADEV at 1 s is the first level's, the last the
    // second's (three times as large).
    let first = d["adev"][0][0].as_f64().unwrap();
    let last = d["adev"][windows - 1][0].as_f64().unwrap();
    assert!((first / 0.01 - 1.0).abs() < 0.1, "{first}");
    assert!((last / 0.03 - 1.0).abs() < 0.1, "{last}");
    assert_eq!(d["test"]["non_stationary"], true);
    assert_eq!(d["test"]["windows_compared"], 8);
    let table = doc["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == "davar.gx")
        .expect("table davar.gx");
    assert_eq!(table["rows"].as_array().unwrap().len(), windows * taus);
    let w = doc["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .find(|w| w["code"] == "non-stationary")
        .expect("a non-stationary warning");
    let m = w["message"].as_str().unwrap();
    assert!(
        m.starts_with("gx: the noise changes along the record"),
        "{m}"
    );
    assert!(m.contains("davar.gx"), "{m}");
    // A stationary record: the test is there and says so, no warning.
    let calm = doc_of(&stepped(5, 1.0), "4096,2048").unwrap();
    assert_eq!(
        calm["channels"]["gx"]["davar"]["test"]["non_stationary"],
        false
    );
    assert!(!calm["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .any(|w| w["code"] == "non-stationary"));
}

#[test]
fn windows_the_record_cannot_hold_are_refused() {
    let y = stepped(6, 1.0);
    for (spec, says) in [
        ("40000,100", "longer than the record"),
        ("4,1", "at least 8 are needed"),
        ("1000,10", "at most 1000: take a longer step"),
        ("600", "WINDOW_S,STEP_S"),
        ("600,-1", "two positive numbers"),
        ("a,b", "WINDOW_S,STEP_S"),
    ] {
        let e = doc_of(&y, spec).unwrap_err().to_string();
        assert!(e.contains(says), "{spec}: {e}");
        assert!(e.contains("davar"), "{spec}: {e}");
    }
    // One window: the surface without a test, and why.
    let doc = doc_of(&y, "32768,1").unwrap();
    let d = &doc["channels"]["gx"]["davar"];
    assert_eq!(d["windows"], 1);
    assert!(d["test"].is_null());
    assert!(d["reason"]
        .as_str()
        .unwrap()
        .contains("fewer than two windows"));
}
