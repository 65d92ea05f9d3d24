//! The noise-term model choice, measured: records simulated from known IEEE
//! 952 terms (seeded), analysed, the terms chosen and fitted
//! (`terms::fit_terms`). Over 200 seeds per mix:
//! - a term absent from the truth is reported in at most 5 % of records
//!   (false inclusion);
//! - a term that dominates a decade of τ is missed in at most 5 % (miss);
//! - each reported term's 95 % interval covers its truth in at least 90 %
//!   of the records that report it (the measured rates, printed, run to
//!   100 % for N and K in some mixes: conservative).
//!
//! The rates are printed (`cargo test --test noise_selection -- --nocapture`)
//! and quoted in the noise chapter of the docs.

use incal::estimation::coverage_factor;
use incal::noise::{phase_from_rate, stability, terms, StabilityOptions};
use incal::sim::monte_carlo;
use incal::sim::noise::{rate_record, NoiseTruth};

const SEEDS: usize = 200;
/// 2^16 samples at τ0 = 1 s: octaves from 4 s to 16 384 s in the fit.
const SAMPLES: usize = 1 << 16;
/// Three terms each dominating a decade need two more octaves.
const LONG: usize = 1 << 18;

/// (reported value, U95) of each of the five terms.
type Found = [Option<(f64, f64)>; 5];

fn one(seed: u64, truth: &NoiseTruth, samples: usize) -> Found {
    let y = rate_record(truth, 1.0, samples, seed);
    let x = phase_from_rate(&y, 1.0);
    let opts = StabilityOptions {
        parallel: false,
        ..Default::default()
    };
    let st = stability(&x, &opts).unwrap();
    let f = terms::fit_terms(&st.taus_s, &st.oadev, &st.alpha, 1.0, x.len()).unwrap();
    f.terms
        .map(|t| t.map(|t| (t.value, coverage_factor(t.dof, 0.95) * t.u)))
}

/// Run a mix; `present` are the terms in the truth that must be found.
fn mix(name: &str, seed: u64, truth: NoiseTruth, samples: usize, present: &[usize]) {
    let res = monte_carlo(seed, SEEDS, |s| one(s, &truth, samples));
    let want = [truth.q, truth.n, truth.b, truth.k, truth.r];
    let mut line = format!("{name}:");
    let mut failed = Vec::new();
    for j in 0..5 {
        let term = terms::TERMS[j];
        let found = res.iter().filter(|r| r[j].is_some()).count();
        if want[j] == 0.0 {
            line += &format!(" {term} false {found}/{SEEDS};");
            if found as f64 > 0.05 * SEEDS as f64 {
                failed.push(format!("{term} (absent) reported in {found}/{SEEDS}"));
            }
            continue;
        }
        let cover = res
            .iter()
            .filter(|r| r[j].is_some_and(|(v, u95)| (v - want[j]).abs() <= u95))
            .count();
        line += &format!(" {term} found {found}/{SEEDS} covered {cover}/{found};");
        if present.contains(&j) && (found as f64) < 0.95 * SEEDS as f64 {
            failed.push(format!("{term} missed in {} of {SEEDS}", SEEDS - found));
        }
        // Never below 90 %. The target's upper end, 99 %, is not held by
        // N and K in every mix (up to 200/200): one Birge ratio scales
        // every term while the misfit sits at the longest τ (see the
        // noise chapter of the docs).
        if found >= SEEDS / 2 && (cover as f64 / found as f64) < 0.90 {
            failed.push(format!("{term} coverage {cover}/{found}"));
        }
    }
    eprintln!("{line}");
    assert!(failed.is_empty(), "{name}: {}", failed.join("; "));
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
