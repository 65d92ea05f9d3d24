//! The Allan family on real records against Stable32: a caesium clock
//! (556 990 phase points), a GPS receiver (241 218), a time-interval
//! counter's noise floor (55 688) and an OCXO (19 982 frequency points),
//! Stable32's results from allantools' tests (fixtures with the license
//! beside them). At every τ of every Stable32 run: the value to 1e-4, the
//! count of terms, the noise identified and the 68.3 % bounds to 3 %.

use std::io::Read;

use incal::noise::id::IdMethod;
use incal::noise::{phase_from_rate, stability_at, Deviation, Stability, StabilityOptions};

const FIX: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/fixtures/allantools-stable32/"
);

/// The numbers of a text: every line not starting with `#`, split on
/// white space.
fn numbers(text: &str) -> Vec<Vec<f64>> {
    text.lines()
        .filter(|l| !l.trim_start().starts_with('#') && !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|w| w.parse().unwrap()).collect())
        .collect()
}

/// The first column of a gzip-compressed fixture.
fn record(name: &str) -> Vec<f64> {
    let f = std::fs::File::open(format!("{FIX}{name}")).unwrap();
    let mut text = String::new();
    flate2::read::GzDecoder::new(f)
        .read_to_string(&mut text)
        .unwrap();
    numbers(&text).into_iter().map(|r| r[0]).collect()
}

/// One row of a Stable32 table: AF, tau, #, alpha, min sigma, sigma, max
/// sigma (the bounds 0 where Stable32 did not compute them).
struct Row {
    m: usize,
    n: usize,
    alpha: i32,
    lo: f64,
    value: f64,
    hi: f64,
}

fn stable32(name: &str) -> Vec<Row> {
    let text = std::fs::read_to_string(format!("{FIX}{name}")).unwrap();
    numbers(&text)
        .into_iter()
        .map(|r| Row {
            m: r[0] as usize,
            n: r[2] as usize,
            alpha: r[3] as i32,
            lo: r[4],
            value: r[5],
            hi: r[6],
        })
        .collect()
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// What one record's comparison found, for the summary line.
#[derive(Default)]
struct Tally {
    rows: usize,
    bounds: usize,
    worst_value: f64,
    worst_bound: f64,
    by_method: [usize; 3],
    lag1_differs: Vec<String>,
    fallback_differs: Vec<String>,
}

impl Tally {
    /// Share of the rows identified by lag-1 (`true`) or by B1 and R(n)
    /// where α is Stable32's.
    fn agreement(&self, lag1: bool) -> f64 {
        let (rows, differ) = if lag1 {
            (self.by_method[0], self.lag1_differs.len())
        } else {
            (
                self.by_method[1] + self.by_method[2],
                self.fallback_differs.len(),
            )
        };
        if rows == 0 {
            1.0
        } else {
            1.0 - differ as f64 / rows as f64
        }
    }
}

/// Compare the deviations of `x` at the factors of each Stable32 file;
/// `alpha_too` says whether Stable32 identified the noise in that file
/// (runs made with a fixed noise type are compared on values only).
fn compare(x: &[f64], files: &[(Deviation, &str, bool)], t: &mut Tally) {
    for &(d, file, alpha_too) in files {
        let rows = stable32(file);
        let ms: Vec<usize> = rows.iter().map(|r| r.m).collect();
        let st: Stability = stability_at(
            x,
            &ms,
            &StabilityOptions {
                tau0_s: 1.0,
                confidence: 0.683,
                ..Default::default()
            },
        )
        .unwrap();
        let s = st.series(d);
        for (k, r) in rows.iter().enumerate() {
            let tag = format!("{file} m={}", r.m);
            let v = s.value[k].unwrap_or_else(|| panic!("{tag}: no value"));
            let e = rel(v, r.value);
            assert!(e < 1e-4, "{tag}: {v} vs Stable32 {}", r.value);
            t.worst_value = t.worst_value.max(e);
            if d != Deviation::Totdev {
                assert_eq!(s.n[k], r.n, "{tag}: terms");
            }
            t.rows += 1;
            if !alpha_too {
                continue;
            }
            let how = st.id_method[k].unwrap();
            t.by_method[how as usize] += 1;
            if st.alpha[k] != Some(r.alpha) {
                let line = format!(
                    "{tag}: alpha {:?} ({how:?}) vs Stable32 {}",
                    st.alpha[k], r.alpha
                );
                // The lag-1 method is Stable32's to the bit; B1 and R(n)
                // on a handful of averages sit near their boundaries (and
                // Stable32's TOTDEV identifies its longest τ otherwise
                // than its own OADEV there, by a rule not published).
                if how == IdMethod::Lag1 {
                    t.lag1_differs.push(line);
                } else {
                    t.fallback_differs.push(line);
                }
                // Where Stable32 states bounds for the Allan family, they
                // must be met whatever the method (checked below).
                if d == Deviation::Totdev || r.lo == 0.0 {
                    continue;
                }
            }
            if r.lo > 0.0 {
                let (lo, hi) = (s.lo[k].unwrap(), s.hi[k].unwrap());
                let e = rel(lo, r.lo).max(rel(hi, r.hi));
                assert!(
                    e < 0.03,
                    "{tag} ({how:?}): bounds [{lo}, {hi}] vs Stable32 [{}, {}]",
                    r.lo,
                    r.hi
                );
                t.worst_bound = t.worst_bound.max(e);
                t.bounds += 1;
            }
        }
    }
}

fn five(prefix: &str, suffix: &str) -> Vec<(Deviation, String)> {
    Deviation::ALL
        .iter()
        .map(|&d| (d, format!("{prefix}{}{suffix}", d.as_str())))
        .collect()
}

fn run(x: &[f64], prefix: &str, suffixes: &[&str], fixed_alpha: &[&str]) -> Tally {
    let mut t = Tally::default();
    for suffix in suffixes {
        let files = five(prefix, suffix);
        let files: Vec<(Deviation, &str, bool)> = files
            .iter()
            .map(|(d, f)| (*d, f.as_str(), !fixed_alpha.contains(&f.as_str())))
            .collect();
        compare(x, &files, &mut t);
    }
    println!(
        "{prefix}: {} rows, values to {:.1e}; {} bounds to {:.2} %; α as Stable32 at {}/{} lag-1 rows and {}/{} B1/R(n) rows",
        t.rows,
        t.worst_value,
        t.bounds,
        100.0 * t.worst_bound,
        t.by_method[0] - t.lag1_differs.len(),
        t.by_method[0],
        t.by_method[1] + t.by_method[2] - t.fallback_differs.len(),
        t.by_method[1] + t.by_method[2],
    );
    for l in t.lag1_differs.iter().chain(&t.fallback_differs) {
        println!("  {l}");
    }
    t
}

#[test]
fn caesium_clock_at_every_stable32_tau() {
    let x = record("cs5071a_phase.txt.gz");
    assert_eq!(x.len(), 556_990);
    let t = run(
        &x,
        "cs5071a_",
        &["_decade.txt", "_all.txt"],
        // Stable32's TOTDEV runs of this record were made with α fixed at
        // 0 (α = 0 at τ = 1 s, where every other run says 2).
        &["cs5071a_totdev_decade.txt", "cs5071a_totdev_all.txt"],
    );
    // The long τ where the record holds fewer than 30 averages: the B1
    // ratio, not a carried value (Stable32's white FM there, ±8 %).
    assert!(t.by_method[IdMethod::B1 as usize] + t.by_method[IdMethod::Rn as usize] > 200);
    assert!(t.bounds >= 64);
    // Measured: 1024/1024 and 288/296 (the misses at N = 4 averages).
    assert_eq!(t.agreement(true), 1.0);
    assert!(t.agreement(false) >= 0.95);
}

#[test]
fn gps_receiver_at_every_stable32_tau() {
    let x = record("gps_phase.txt.gz");
    assert_eq!(x.len(), 241_218);
    let t = run(&x, "gps_", &["_octave.txt"], &[]);
    assert!(t.bounds >= 80);
    // Measured: 70/70 and 10/11 (TOTDEV at 32 768 s).
    assert_eq!(t.agreement(true), 1.0);
    assert!(t.agreement(false) >= 0.9);
}

#[test]
fn counter_noise_floor_at_every_stable32_tau() {
    let x = record("tic_phase.txt.gz");
    assert_eq!(x.len(), 55_688);
    let t = run(&x, "tic_", &[".txt"], &[]);
    assert!(t.bounds >= 69);
    // Measured: 55/55 and 14/16 (TOTDEV at 8192 and 16 384 s).
    assert_eq!(t.agreement(true), 1.0);
    assert!(t.agreement(false) >= 0.85);
}

#[test]
fn ocxo_frequency_at_every_stable32_tau() {
    // Frequency in Hz to fractional frequency, then to phase (Stable32
    // does the same with frequency data).
    let y: Vec<f64> = record("ocxo_frequency.txt.gz")
        .iter()
        .map(|f| (f - 1.0e7) / 1.0e7)
        .collect();
    assert_eq!(y.len(), 19_982);
    let x = phase_from_rate(&y, 1.0);
    // Stable32's TOTDEV run of this record has α fixed at 0.
    let t = run(&x, "ocxo_", &["_alltau.txt"], &["ocxo_totdev_alltau.txt"]);
    assert!(t.rows >= 1400);
    // Measured: 660/676 (ρ within a few thousandths of a boundary) and
    // 331/416 (Stable32's B1 on this drifting oscillator differs by one
    // noise type at 85 τ; no bounds were published for this run).
    assert!(t.agreement(true) >= 0.97);
    assert!(t.agreement(false) >= 0.75);
}

/// The non-overlapping ADEV and HDEV of every record at every τ of every
/// Stable32 run of them: value to 1e-4, terms exact, and, where Stable32
/// states bounds and identifies the same noise, the bounds to 3 %
/// (Greenhall's EDF for the non-overlapping estimators).
#[test]
fn adev_and_hdev_of_every_record_at_every_stable32_tau() {
    use incal::noise::{statistic, Statistic};
    let ocxo: Vec<f64> = record("ocxo_frequency.txt.gz")
        .iter()
        .map(|f| (f - 1.0e7) / 1.0e7)
        .collect();
    let records = [
        (
            record("cs5071a_phase.txt.gz"),
            vec![
                "cs5071a_adev_decade.txt",
                "cs5071a_hdev_decade.txt",
                "cs5071a_adev_all.txt",
                "cs5071a_hdev_all.txt",
            ],
        ),
        (
            record("gps_phase.txt.gz"),
            vec!["gps_adev_decade.txt", "gps_hdev_octave.txt"],
        ),
        (
            record("tic_phase.txt.gz"),
            vec!["tic_adev.txt", "tic_hdev.txt"],
        ),
        (
            phase_from_rate(&ocxo, 1.0),
            vec!["ocxo_adev_alltau.txt", "ocxo_hdev_alltau.txt"],
        ),
    ];
    let (mut rows, mut bounds, mut published, mut worst) = (0, 0, 0, 0.0f64);
    for (x, files) in &records {
        for file in files {
            let s = if file.contains("adev") {
                Statistic::Adev
            } else {
                Statistic::Hdev
            };
            let want = stable32(file);
            let ms: Vec<usize> = want.iter().map(|r| r.m).collect();
            let opts = StabilityOptions {
                tau0_s: 1.0,
                confidence: 0.683,
                ..Default::default()
            };
            let st = stability_at(x, &ms, &opts).unwrap();
            let got = statistic(x, s, &st, &opts).unwrap();
            for (k, r) in want.iter().enumerate() {
                let tag = format!("{file} m={}", r.m);
                let v = got.dev.value[k].unwrap_or_else(|| panic!("{tag}: no value"));
                assert!(rel(v, r.value) < 1e-4, "{tag}: {v} vs Stable32 {}", r.value);
                assert_eq!(got.dev.n[k], r.n, "{tag}: terms");
                rows += 1;
                let alpha = if s == Statistic::Adev {
                    st.alpha[k]
                } else {
                    st.alpha_hadamard[k]
                };
                if r.lo > 0.0 && alpha == Some(r.alpha) {
                    let (lo, hi) = (got.dev.lo[k].unwrap(), got.dev.hi[k].unwrap());
                    let e = rel(lo, r.lo).max(rel(hi, r.hi));
                    assert!(
                        e < 0.03,
                        "{tag}: bounds [{lo}, {hi}] vs Stable32 [{}, {}]",
                        r.lo,
                        r.hi
                    );
                    worst = worst.max(e);
                    bounds += 1;
                }
                published += usize::from(r.lo > 0.0);
            }
        }
    }
    println!(
        "ADEV/HDEV: {rows} rows; {bounds} of {published} published bounds (those where α is Stable32's) to {:.2} %",
        100.0 * worst
    );
    // Measured: 1471 rows, 70 bounds to 0.05 %.
    assert!(rows >= 1400 && bounds >= 70, "{rows} rows, {bounds} bounds");
}
