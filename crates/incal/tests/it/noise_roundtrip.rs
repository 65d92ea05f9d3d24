//! Round trip: simulate rate records with known IEEE 952 terms (white rate
//! N, Kasdin & Walter flicker B, rate random walk K), analyse, fit the terms,
//! and check the stated 95 % intervals cover the truth at least 90 % of the
//! time over many seeds (a term not identified counts as not covering).
//!
//! The model choice, measured (the `mix` tests): over 200 seeds per mix
//! - a term absent from the truth is reported in at most 5 % of records
//!   (false inclusion);
//! - a term that dominates a decade of τ is missed in at most 5 % (miss);
//! - each reported term's 95 % interval covers its truth in at least 90 %
//!   of the records that report it (the measured rates, printed, run to
//!   100 % for N and K in some mixes: conservative).
//!
//! The rates are printed (`cargo test --test noise_roundtrip -- --nocapture`)
//! and quoted in the noise chapter of the docs.

use incal::estimation::coverage_factor;
use incal::noise::{phase_from_rate, stability, terms, StabilityOptions};
use incal::sim::monte_carlo;
use incal::sim::noise::{rate_record, spectral_record, NoiseTruth};
use incal::sim::tier::{at_least, at_most, band, trials};

/// Records per coverage check: 150 in the statistical tier.
fn seeds() -> usize {
    trials(40, 150)
}

/// (reported value, U95) of each of the five terms.
type Found = [Option<(f64, f64)>; 5];

fn one(seed: u64, truth: &NoiseTruth, n: usize) -> Found {
    found_in(&rate_record(truth, 1.0, n, seed))
}

/// The terms fitted to the OADEV of rate samples `y` at τ0 = 1 s.
fn found_in(y: &[f64]) -> Found {
    let x = phase_from_rate(y, 1.0);
    let opts = StabilityOptions {
        parallel: false,
        ..Default::default()
    };
    let st = stability(&x, &opts).unwrap();
    let f = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, 1.0, x.len()).unwrap();
    f.terms
        .map(|t| t.map(|t| (t.value, coverage_factor(t.dof, 0.95) * t.u)))
}

#[test]
fn n_b_k_intervals_cover_the_truth() {
    // Each term dominates about a decade of τ in 2^17 samples at τ0 = 1 s.
    let truth = NoiseTruth {
        q: 0.0,
        n: 1.0,
        b: 0.1,
        k: 5e-3,
        r: 0.0,
    };
    let n_seeds = seeds();
    let res = monte_carlo(2026, n_seeds, |s| one(s, &truth, 1 << 17));
    let want = [truth.q, truth.n, truth.b, truth.k, truth.r];
    for j in [1usize, 2, 3] {
        let cover = res
            .iter()
            .filter(|r| r[j].is_some_and(|(v, u95)| (v - want[j]).abs() <= u95))
            .count();
        let rate = cover as f64 / n_seeds as f64;
        eprintln!(
            "{}: 95 % interval covers the truth in {cover}/{n_seeds}",
            terms::TERMS[j]
        );
        // At least 90 %; N runs to 149/150 (conservative: the Birge
        // ratio of the misfit at long τ scales every term).
        assert!(
            rate >= at_least(n_seeds, 0.90),
            "{}: coverage {rate}",
            terms::TERMS[j]
        );
    }
    // Q and R are zero: never reported as confident numbers most of the time.
    for j in [0usize, 4] {
        let found = res.iter().filter(|r| r[j].is_some()).count();
        assert!(
            found as f64 <= at_most(n_seeds, 0.1) * n_seeds as f64,
            "{} reported {found} times",
            terms::TERMS[j]
        );
    }
}

#[test]
fn a_short_white_record_reports_n_only() {
    let truth = NoiseTruth {
        n: 1.0,
        ..Default::default()
    };
    let y = rate_record(&truth, 0.01, 4000, 7);
    let x = phase_from_rate(&y, 0.01);
    let st = stability(
        &x,
        &StabilityOptions {
            tau0_s: 0.01,
            ..Default::default()
        },
    )
    .unwrap();
    let f = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, 0.01, x.len()).unwrap();
    let n = f.terms[1].expect("N identified");
    assert!((n.value - 1.0).abs() < 3.0 * n.u + 0.05, "{n:?}");
    assert!(
        f.terms[3].is_none() && f.terms[4].is_none(),
        "{:?}",
        f.terms
    );
    assert!(f
        .warnings
        .iter()
        .any(|w| w.code == incal::warning::WarningCode::NoiseTermNotIdentified));
}

#[test]
fn the_fit_spans_seven_decades_of_tau() {
    // A 10^8-sample record reaches τ = 2.5e7 s: the regressors then span
    // ~30 orders of magnitude, which must not read as a zero column.
    let taus: Vec<f64> = (0..25).map(|k| (1u64 << k) as f64).collect();
    let model = |t: f64| (1.0 / t + terms::FLICKER * 1e-4 + 1e-10 * t / 3.0).sqrt();
    let series = incal::noise::DevSeries {
        value: taus.iter().map(|&t| Some(model(t))).collect(),
        lo: vec![None; taus.len()],
        hi: vec![None; taus.len()],
        edf: taus.iter().map(|&t| Some(1e8 / t)).collect(),
        n: vec![1; taus.len()],
    };
    let f = terms::fit_terms(&taus, &series, &vec![Some(0); taus.len()], 1.0, 100_000_001).unwrap();
    let n = f.terms[1].expect("N");
    let b = f.terms[2].expect("B");
    let k = f.terms[3].expect("K");
    assert!(
        (n.value - 1.0).abs() < 1e-6
            && (b.value - 1e-2).abs() < 1e-6
            && (k.value - 1e-5).abs() < 1e-9,
        "{:?}",
        f.terms
    );
}

/// Seeds per mix of the model-choice tests.
/// Records per mix: 200 in the statistical tier.
fn selection_seeds() -> usize {
    trials(50, 200)
}
/// 2^16 samples at τ0 = 1 s: octaves from 4 s to 16 384 s in the fit.
const SAMPLES: usize = 1 << 16;
/// Three terms each dominating a decade need two more octaves.
const LONG: usize = 1 << 18;

/// A seeded record generator: truth, τ0 (s), samples, seed.
type Generator = fn(&NoiseTruth, f64, usize, u64) -> Vec<f64>;

/// The two independent generators the selection is measured on: incal's
/// own time-domain one and Timmer & König's frequency-domain one.
const GENERATORS: [(&str, Generator); 2] = [
    ("time-domain", rate_record),
    ("frequency-domain", spectral_record),
];

/// Run a mix on both generators; `present` are the terms in the truth
/// that must be found.
fn mix(name: &str, seed: u64, truth: NoiseTruth, samples: usize, present: &[usize]) {
    let mut failed = Vec::new();
    for (gen_name, generate) in GENERATORS {
        let n = selection_seeds();
        let res = monte_carlo(seed, n, |s| found_in(&generate(&truth, 1.0, samples, s)));
        failed.extend(
            rates(&format!("{name} ({gen_name})"), &truth, &res, present)
                .into_iter()
                .map(|f| format!("{gen_name}: {f}")),
        );
    }
    assert!(failed.is_empty(), "{name}: {}", failed.join("; "));
}

/// Print a mix's false-inclusion, miss and coverage rates over the
/// records `res`; the failed criteria.
fn rates(name: &str, truth: &NoiseTruth, res: &[Found], present: &[usize]) -> Vec<String> {
    rates_within(name, truth, res, present, (0.05, 0.05))
}

/// [`rates`] with the largest miss and false-inclusion rates asserted.
fn rates_within(
    name: &str,
    truth: &NoiseTruth,
    res: &[Found],
    present: &[usize],
    (miss, invent): (f64, f64),
) -> Vec<String> {
    let n = res.len();
    let want = [truth.q, truth.n, truth.b, truth.k, truth.r];
    let mut line = format!("{name}:");
    let mut failed = Vec::new();
    for j in 0..5 {
        let term = terms::TERMS[j];
        let found = res.iter().filter(|r| r[j].is_some()).count();
        if want[j] == 0.0 {
            line += &format!(" {term} false {found}/{n};");
            if found as f64 > at_most(n, invent) * n as f64 {
                failed.push(format!("{term} (absent) reported in {found}/{n}"));
            }
            continue;
        }
        let cover = res
            .iter()
            .filter(|r| r[j].is_some_and(|(v, u95)| (v - want[j]).abs() <= u95))
            .count();
        line += &format!(" {term} found {found}/{n} covered {cover}/{found};");
        if present.contains(&j) && (found as f64) < at_least(n, 1.0 - miss) * n as f64 {
            failed.push(format!("{term} missed in {} of {n}", n - found));
        }
        // Never below 90 %. The target's upper end, 99 %, is not held by
        // N and K in every mix (up to 200/200): one Birge ratio scales
        // every term while the misfit sits at the longest τ (see the
        // noise chapter of the docs).
        if found >= n / 2 && (cover as f64 / found as f64) < at_least(found, 0.90) {
            failed.push(format!("{term} coverage {cover}/{found}"));
        }
    }
    // No reported term's U95 reaches its value.
    let weak = res
        .iter()
        .flatten()
        .filter(|t| t.is_some_and(|(v, u95)| u95 >= v))
        .count();
    line += &format!(" U95 >= value in {weak};");
    if weak > 0 {
        failed.push(format!("{weak} reported terms with U95 >= value"));
    }
    eprintln!("{line}");
    failed
}

#[test]
fn white_noise_only() {
    mix(
        "white",
        1,
        NoiseTruth {
            n: 1.0,
            ..Default::default()
        },
        SAMPLES,
        &[1],
    );
}

#[test]
fn white_and_rate_random_walk() {
    // K²τ/3 = N²/τ at τ = √3/K ≈ 1000 s: K dominates the top decade.
    mix(
        "white + RRW",
        2,
        NoiseTruth {
            n: 1.0,
            k: 1.7e-3,
            ..Default::default()
        },
        SAMPLES,
        &[1, 3],
    );
}

#[test]
fn white_and_flicker() {
    // (2 ln 2/π)B² = N²/τ at τ ≈ 900 s: B dominates the top decade.
    mix(
        "white + flicker",
        3,
        NoiseTruth {
            n: 1.0,
            b: 0.05,
            ..Default::default()
        },
        SAMPLES,
        &[1, 2],
    );
}

#[test]
fn white_flicker_and_rate_random_walk() {
    // B's floor from about 350 s, K above it from about 3700 s (to 65 536 s).
    mix(
        "white + flicker + RRW",
        4,
        NoiseTruth {
            n: 1.0,
            b: 0.08,
            k: 1.5e-3,
            ..Default::default()
        },
        LONG,
        &[1, 2, 3],
    );
}

#[test]
fn quantization_and_white() {
    // Angle data with a quantizer: 3Q²/τ² = N²/τ at τ = 3Q²/N² = 75 s.
    mix(
        "quantization + white",
        5,
        NoiseTruth {
            q: 5.0,
            n: 1.0,
            ..Default::default()
        },
        SAMPLES,
        &[0, 1],
    );
}

// ---- Gaps and time stamps (`incal noise` reads `time_s`) ----

use incal::procedures::noise::{Noise, NoiseOptions};
use incal::procedures::{reduce_source, Silent};

/// A CSV record `time_s,gx` at `rate_hz` from rate samples `y`: rows in
/// `cut` left out (a gap in the stamps), or, with `nan`, kept with an
/// empty cell.
fn csv(y: &[f64], rate_hz: f64, cut: std::ops::Range<usize>, nan: bool) -> String {
    let mut s = String::from("time_s,gx\n");
    for (i, v) in y.iter().enumerate() {
        let t = i as f64 / rate_hz;
        if cut.contains(&i) {
            if nan {
                s.push_str(&format!("{t:.4},NaN\n"));
            }
        } else {
            s.push_str(&format!("{t:.4},{v:e}\n"));
        }
    }
    s
}

fn noise_doc(csv: &str, rate_hz: Option<f64>) -> incal::Result<serde_json::Value> {
    let o = NoiseOptions {
        rate_hz,
        parallel: false,
        ..Default::default()
    };
    let doc = reduce_source::<Noise, _>(
        "rec.csv",
        csv.as_bytes(),
        &incal_io::ReadOptions::default(),
        &o,
        &Silent,
    )?;
    Ok(serde_json::to_value(&doc).unwrap())
}

fn series(doc: &serde_json::Value, name: &str, what: &str) -> Vec<Option<f64>> {
    doc["channels"]["gx"][name][what]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64())
        .collect()
}

fn gyro_rate(seed: u64, n: usize) -> Vec<f64> {
    let truth = NoiseTruth {
        n: 1.0,
        k: 0.01,
        ..Default::default()
    };
    rate_record(&truth, 1.0, n, seed)
}

#[test]
fn a_gap_leaves_the_deviations_within_their_bounds() {
    // 2^16 samples at 100 Hz, 6000 of them (a minute) cut out a third of the
    // way in: at every τ the gap-aware deviations' bounds hold the
    // deviations of the whole record, and the terms that straddled the gap
    // are counted out (n).
    let y = gyro_rate(11, 1 << 16);
    let whole = noise_doc(&csv(&y, 100.0, 0..0, false), Some(100.0)).unwrap();
    let gapped = noise_doc(&csv(&y, 100.0, 20_000..26_000, false), None).unwrap();
    assert_eq!(
        gapped["options"]["rate_hz"]
            .as_f64()
            .map(|r| (r * 1e6).round()),
        Some(1e8)
    );
    let w = gapped["warnings"].to_string();
    assert!(w.contains("time-gaps") && w.contains("spans a gap"), "{w}");
    for d in ["oadev", "mdev", "ohdev", "tdev"] {
        let (v, lo, hi) = (
            series(&whole, d, "value"),
            series(&gapped, d, "lo"),
            series(&gapped, d, "hi"),
        );
        let g = series(&gapped, d, "value");
        let mut compared = 0;
        for k in 0..g.len() {
            let (Some(v), Some(lo), Some(hi)) = (v[k], lo[k], hi[k]) else {
                continue;
            };
            // The bounds are 68.3 % intervals of an estimate that shares
            // 90 % of its data with the whole record's: a miss is a defect.
            assert!(
                lo <= v && v <= hi,
                "{d} at k={k}: whole {v} outside [{lo}, {hi}]"
            );
            compared += 1;
        }
        assert!(compared >= 10, "{d}: {compared} taus compared");
    }
    let n_whole = whole["channels"]["gx"]["oadev"]["n"][0].as_u64().unwrap();
    let n_gap = gapped["channels"]["gx"]["oadev"]["n"][0].as_u64().unwrap();
    // τ0: the whole record has N − 1 first differences of phase... the
    // gapped one loses the 6000 cut and the one across the gap.
    assert_eq!(n_whole - n_gap, 6000 + 1, "terms at tau0");
    // TOTDEV reflects the whole record: not reported across a gap.
    assert!(series(&gapped, "totdev", "value")
        .iter()
        .all(Option::is_none));
}

#[test]
fn missing_cells_and_missing_stamps_give_the_same_numbers() {
    let y = gyro_rate(12, 20_000);
    let stamps = noise_doc(&csv(&y, 100.0, 5000..5400, false), Some(100.0)).unwrap();
    let cells = noise_doc(&csv(&y, 100.0, 5000..5400, true), Some(100.0)).unwrap();
    for d in ["oadev", "mdev", "ohdev", "tdev"] {
        assert_eq!(
            series(&stamps, d, "value"),
            series(&cells, d, "value"),
            "{d}"
        );
        assert_eq!(series(&stamps, d, "hi"), series(&cells, d, "hi"), "{d}");
    }
    let w = cells["warnings"].to_string();
    assert!(w.contains("400 missing samples"), "{w}");
}

#[test]
fn logger_repeats_are_dropped_and_counted() {
    let y = gyro_rate(13, 20_000);
    let clean = csv(&y, 100.0, 0..0, false);
    let mut lines: Vec<&str> = clean.lines().collect();
    // A logger writes 100 rows twice, scattered over the record.
    let mut with = Vec::new();
    for (i, l) in lines.drain(..).enumerate() {
        with.push(l);
        if i > 0 && i % 150 == 0 && i <= 15_000 {
            with.push(l);
        }
    }
    let repeated = with.join("\n") + "\n";
    let a = noise_doc(&clean, Some(100.0)).unwrap();
    let b = noise_doc(&repeated, Some(100.0)).unwrap();
    assert_eq!(series(&a, "oadev", "value"), series(&b, "oadev", "value"));
    let w = b["warnings"].to_string();
    assert!(w.contains("100 rows equal to the row before"), "{w}");
}

#[test]
fn a_rate_the_stamps_contradict_is_refused_and_none_needs_stamps() {
    let y = gyro_rate(14, 5000);
    let e = noise_doc(&csv(&y, 100.0, 0..0, false), Some(200.0))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("rec.csv") && e.contains("200") && e.contains("100.0"),
        "{e}"
    );
    let no_stamps: String = std::iter::once("gx".to_string())
        .chain(y.iter().map(|v| format!("{v:e}")))
        .collect::<Vec<_>>()
        .join("\n");
    let e = noise_doc(&no_stamps, None).unwrap_err().to_string();
    assert!(e.contains("rec.csv") && e.contains("`rate_hz`"), "{e}");
}

// ---- The statistics beyond the default five, and the three-cornered hat ----

fn doc_with(csv: &str, o: &NoiseOptions) -> incal::Result<serde_json::Value> {
    let doc = reduce_source::<Noise, _>(
        "rec.csv",
        csv.as_bytes(),
        &incal_io::ReadOptions::default(),
        o,
        &Silent,
    )?;
    Ok(serde_json::to_value(&doc).unwrap())
}

#[test]
fn every_statistic_sits_in_the_document_on_its_own_grid() {
    let y = gyro_rate(21, 4000);
    let text = csv(&y, 10.0, 0..0, false);
    let o = NoiseOptions {
        deviations: "all".into(),
        parallel: false,
        ..Default::default()
    };
    let d = doc_with(&text, &o).unwrap();
    let c = &d["channels"]["gx"];
    for k in [
        "oadev", "mdev", "ohdev", "tdev", "totdev", "adev", "hdev", "mtotdev", "htotdev", "theo1",
        "theoh",
    ] {
        let s = &c[k];
        let n = s["taus_s"].as_array().unwrap().len();
        assert!(n > 3, "{k}: {n} taus");
        for f in ["value", "lo", "hi", "edf", "n"] {
            assert_eq!(s[f].as_array().unwrap().len(), n, "{k}.{f}");
        }
    }
    // Rate data: no time-interval errors in `all`.
    assert!(c.get("mtie").is_none() && c.get("tierms").is_none());
    // Theo1 at τ = 0.75·m·τ0 for even m, to m = N − 1 (τ0 = 0.1 s).
    let th: Vec<f64> = c["theo1"]["taus_s"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!((th[0] - 0.75 * 2.0 * 0.1).abs() < 1e-12, "{th:?}");
    assert!(*th.last().unwrap() > 0.75 * 2000.0 * 0.1, "{th:?}");
    assert_eq!(d["options"]["deviations"], "all");
    // ADEV at τ0 equals OADEV there (one term per sample either way).
    let (a, b) = (
        c["adev"]["value"][0].as_f64().unwrap(),
        c["oadev"]["value"][0].as_f64().unwrap(),
    );
    assert!(((a - b) / b).abs() < 1e-12, "{a} vs {b}");
    // TheoH is OADEV below a tenth of the record, TheoBR (with bounds) from
    // there on, on Theo1's τ.
    let (h, o) = (&c["theoh"], &c["oadev"]);
    let n_pts = y.len() + 1;
    let mut theobr = 0;
    for (k, t) in h["taus_s"].as_array().unwrap().iter().enumerate() {
        let t = t.as_f64().unwrap();
        if t / 0.1 < (n_pts / 10) as f64 - 1e-9 {
            assert_eq!(h["value"][k], o["value"][k], "τ = {t}");
            assert_eq!(h["hi"][k], o["hi"][k], "τ = {t}");
        } else {
            theobr += 1;
            assert!(h["hi"][k].as_f64().unwrap() > h["value"][k].as_f64().unwrap());
        }
    }
    assert!(theobr >= 2, "{theobr} TheoBR points");
    // A list selects: only what it names.
    let o = NoiseOptions {
        deviations: "oadev,theo1".into(),
        parallel: false,
        ..Default::default()
    };
    let d = doc_with(&text, &o).unwrap();
    let c = &d["channels"]["gx"];
    assert!(c.get("oadev").is_some() && c.get("theo1").is_some());
    assert!(c.get("mdev").is_none() && c.get("adev").is_none());
    // Angle data: MTIE and TIE rms in `all`.
    let o = NoiseOptions {
        deviations: "all".into(),
        data: incal::procedures::noise::DataKind::Angle,
        parallel: false,
        ..Default::default()
    };
    let d = doc_with(&text, &o).unwrap();
    assert!(d["channels"]["gx"]["mtie"]["value"][0].as_f64().unwrap() > 0.0);
    // A name that is no statistic, and a statistic across a gap: refused.
    let e = doc_with(
        &text,
        &NoiseOptions {
            deviations: "oadev,allan".into(),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("allan") && e.contains("deviations"), "{e}");
    let gapped = csv(&y, 10.0, 1000..1100, false);
    let e = doc_with(
        &gapped,
        &NoiseOptions {
            deviations: "oadev,theo1".into(),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("theo1") && e.contains("gaps"), "{e}");
}

#[test]
fn the_three_cornered_hat_separates_three_instruments() {
    use incal::noise::{three_cornered_hat, StabilityOptions};
    // Three white-rate instruments of σ 1, 2 and 3 read one common
    // disturbance of σ 10 (which the differences cancel). At τ0 each
    // one's 68.3 % interval covers its σ in 61–76 % of 300 seeds (±3
    // standard errors; measured 62–69 %).
    let sigma = [1.0, 2.0, 3.0];
    let n = 4096;
    let covered = monte_carlo(31, 300, |seed| {
        let common = rate_record(
            &NoiseTruth {
                n: 10.0,
                ..Default::default()
            },
            1.0,
            n,
            seed,
        );
        let x: Vec<Vec<f64>> = sigma
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let own = rate_record(
                    &NoiseTruth {
                        n: *s,
                        ..Default::default()
                    },
                    1.0,
                    n,
                    seed.wrapping_mul(7).wrapping_add(k as u64 + 1),
                );
                let y: Vec<f64> = (0..n).map(|i| common[i] + own[i]).collect();
                phase_from_rate(&y, 1.0)
            })
            .collect();
        let opts = StabilityOptions {
            parallel: false,
            ..Default::default()
        };
        let h = three_cornered_hat([&x[0], &x[1], &x[2]], &opts).unwrap();
        let mut hit = [false; 3];
        for k in 0..3 {
            let (lo, hi) = (h[k].dev.lo[0].unwrap(), h[k].dev.hi[0].unwrap());
            hit[k] = lo <= sigma[k] && sigma[k] <= hi;
        }
        hit
    });
    let mut rates = Vec::new();
    for k in 0..3 {
        let rate = covered.iter().filter(|h| h[k]).count() as f64 / covered.len() as f64;
        println!(
            "three-cornered hat, instrument {k}: 68.3 % interval covers σ in {:.0} %",
            100.0 * rate
        );
        rates.push(rate);
    }
    for (k, r) in rates.iter().enumerate() {
        assert!((0.61..=0.76).contains(r), "instrument {k}: {r}");
    }
    // Through the procedure: exactly three channels, the document's shape.
    let y = gyro_rate(22, 3000);
    let z = gyro_rate(23, 3000);
    let w = gyro_rate(24, 3000);
    let mut text = String::from("a,b,c\n");
    for i in 0..3000 {
        text.push_str(&format!("{:e},{:e},{:e}\n", y[i], z[i], w[i]));
    }
    let o = NoiseOptions {
        rate_hz: Some(1.0),
        three_cornered_hat: true,
        parallel: false,
        ..Default::default()
    };
    let d = doc_with(&text, &o).unwrap();
    for k in ["a", "b", "c"] {
        let s = &d["three_cornered_hat"][k];
        assert_eq!(
            s["taus_s"].as_array().unwrap().len(),
            s["value"].as_array().unwrap().len()
        );
        assert!(s["lo"][0].as_f64().is_some(), "{k}");
    }
    let two = "a,b\n1,2\n2,3\n3,1\n4,4\n5,2\n6,1\n";
    let e = doc_with(two, &o).unwrap_err().to_string();
    assert!(e.contains("exactly three channels"), "{e}");
}

#[test]
fn theo1_bounds_cover_and_theobr_removes_the_theo1_bias() {
    use incal::noise::{more, statistic, Statistic};
    // White rate (white FM) of σ 1 at τ0 = 1 s, 1000 samples: at τ = 0.75·m
    // Theo1 estimates σ²/τ. Its 68.3 % interval (Howe & Peppler EDF, α
    // identified nearest in τ) covers the truth at 60–77 % of 300 seeds
    // at m = 8, 32 and 128.
    let n = 1000;
    let ms = [8usize, 32, 128];
    let opts = StabilityOptions {
        parallel: false,
        ..Default::default()
    };
    let runs = monte_carlo(41, trials(60, 300), |seed| {
        let y = rate_record(
            &NoiseTruth {
                n: 1.0,
                ..Default::default()
            },
            1.0,
            n,
            seed,
        );
        let x = phase_from_rate(&y, 1.0);
        let st = stability(&x, &opts).unwrap();
        let th = statistic(&x, Statistic::Theo1, &st, &opts).unwrap();
        let hit = ms.map(|m| {
            let tau = 0.75 * m as f64;
            let k = th
                .taus_s
                .iter()
                .position(|t| (t - tau).abs() < 1e-9)
                .unwrap();
            let truth = (1.0 / tau).sqrt();
            th.dev.lo[k].unwrap() <= truth && truth <= th.dev.hi[k].unwrap()
        });
        (hit, more::theobr_bias(&x, 1, false).unwrap())
    });
    for (j, m) in ms.iter().enumerate() {
        let rate = runs.iter().filter(|r| r.0[j]).count() as f64 / runs.len() as f64;
        println!("theo1 coverage at m = {m}: {rate:.3}");
        let (lo, hi) = band(runs.len(), 0.60, 0.77);
        assert!((lo..=hi).contains(&rate), "m = {m}: {rate}");
    }
    // The TheoBR factor is about 1 for white FM (Theo1 unbiased there) …
    let wfm = runs.iter().map(|r| r.1).sum::<f64>() / runs.len() as f64;
    println!("TheoBR factor, white FM: {wfm:.3}");
    assert!((0.95..=1.05).contains(&wfm), "{wfm}");
    // … and removes Theo1's bias for random-walk FM: TheoBR agrees with
    // OADEV at the same τ on average (Theo1 alone reads low there).
    let runs = monte_carlo(43, 60, |seed| {
        let y = rate_record(
            &NoiseTruth {
                k: 1.0,
                ..Default::default()
            },
            1.0,
            4000,
            seed,
        );
        let x = phase_from_rate(&y, 1.0);
        let exact = more::theobr_bias(&x, 1, false).unwrap();
        let fast = more::theobr_bias(&x, 4, false).unwrap();
        // OAVAR(m = 300) against Theo1(m = 400), τ = 300 s.
        let a = incal::noise::dev::oavar(&x, 300, 1.0, false).unwrap().var;
        let t = more::theo1var(&x, 400, 1.0, false).unwrap().var;
        (exact, fast, a / t, a / (exact * t))
    });
    let mean =
        |k: usize| runs.iter().map(|r| [r.0, r.1, r.2, r.3][k]).sum::<f64>() / runs.len() as f64;
    let (exact, raw, br) = (mean(0), mean(2), mean(3));
    println!("RWFM: factor {exact:.3}, OAVAR/Theo1 {raw:.3}, OAVAR/TheoBR {br:.3}");
    assert!(exact > 1.5 && raw > 1.5, "{exact} {raw}");
    assert!((0.85..=1.15).contains(&br), "{br}");
    // Fast TheoBR (averaged in blocks of 4) agrees with the exact factor.
    let worst = runs
        .iter()
        .map(|r| ((r.1 - r.0) / r.0).abs())
        .fold(0.0, f64::max);
    println!("fast vs exact TheoBR factor: worst {worst:.4}");
    assert!(worst < 0.05, "{worst}");
}

/// Where the record cannot tell bias instability from a rate random walk
/// (white noise with a floor at the top octaves of a short record), the
/// document reports neither, names the alias and gives the Allan
/// deviation's floor; across the records no reported term has U95 at or
/// above its value.
#[test]
fn b_and_k_that_alias_are_neither_reported_and_the_floor_is() {
    let truth = NoiseTruth {
        n: 1.0,
        b: 0.05,
        k: 2e-4,
        ..Default::default()
    };
    let mut aliased = 0;
    for seed in 0..trials(30, 100) as u64 {
        let y = rate_record(&truth, 1.0, 1 << 13, seed);
        let doc = noise_doc(&csv(&y, 1.0, 0..0, false), Some(1.0)).unwrap();
        let coef = doc["coefficients"].as_object().unwrap();
        for (name, c) in coef {
            let (v, u95) = (c["value"].as_f64().unwrap(), c["U95"].as_f64().unwrap());
            assert!(u95 < v.abs(), "seed {seed}: {name} = {v} with U95 {u95}");
        }
        let alias = doc["warnings"].as_array().unwrap().iter().any(|w| {
            let m = w["message"].as_str().unwrap();
            w["code"] == "noise-terms-not-separated"
                && m.contains("alias")
                && m.contains('B')
                && m.contains('K')
        });
        if alias {
            aliased += 1;
            assert!(
                !coef.contains_key("gx.B") && !coef.contains_key("gx.K"),
                "seed {seed}: {:?}",
                coef.keys().collect::<Vec<_>>()
            );
            // The floor, unless the curve still falls at its last τ.
            let oadev: Vec<f64> = doc["channels"]["gx"]["oadev"]["value"]
                .as_array()
                .unwrap()
                .iter()
                .filter_map(|v| v.as_f64())
                .collect();
            let last_is_least = oadev.last().is_some_and(|l| oadev.iter().all(|v| v >= l));
            assert!(
                coef.contains_key("gx.adev_min") != last_is_least,
                "seed {seed}: adev_min {} with the curve {oadev:?}",
                coef.contains_key("gx.adev_min")
            );
        }
    }
    eprintln!("B/K aliased in {aliased} records");
    assert!(aliased > 0, "no record aliased B and K");
}

/// A MEMS gyro's white noise and bias instability (B = 1 °/h, N = 0.15
/// °/√h, 2 h at 100 Hz, in °/s) from both generators. The record is too
/// short for the 5 % targets: the flicker floor starts at 180 s and the
/// fit's longest τ is 1311 s, so B dominates 0.85 of a decade, three
/// octaves whose estimates have 24, 11 and 5 EDF. Measured over 100
/// seeds: B found in 79 % (time domain) and 84 % (frequency domain), K
/// invented in 10 % and 12 %, the rest named as a B/K alias with neither
/// reported; asserted: B found in at least 70 %, K invented in at most
/// 15 %, and (as everywhere) no reported term with U95 at its value.
#[test]
fn mems_white_and_flicker_at_100_hz() {
    let truth = NoiseTruth {
        n: 0.15 / 60.0,
        b: 1.0 / 3600.0,
        ..Default::default()
    };
    let n = trials(6, 50);
    let mut failed = Vec::new();
    for (gen_name, generate) in GENERATORS {
        let res = monte_carlo(48, n, |s| {
            let y = generate(&truth, 0.01, 720_000, s);
            let x = phase_from_rate(&y, 0.01);
            let st = stability(
                &x,
                &StabilityOptions {
                    tau0_s: 0.01,
                    parallel: false,
                    ..Default::default()
                },
            )
            .unwrap();
            let f = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, 0.01, x.len()).unwrap();
            f.terms
                .map(|t| t.map(|t| (t.value, coverage_factor(t.dof, 0.95) * t.u)))
        });
        failed.extend(
            rates_within(
                &format!("MEMS white + flicker ({gen_name})"),
                &truth,
                &res,
                &[1, 2],
                (0.30, 0.15),
            )
            .into_iter()
            .map(|f| format!("{gen_name}: {f}")),
        );
    }
    assert!(failed.is_empty(), "{}", failed.join("; "));
}
