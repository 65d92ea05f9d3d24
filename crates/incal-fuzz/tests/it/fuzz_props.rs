//! The fuzz targets ([`incal_fuzz`]) as a quick property-based pass, in
//! process: each target's valid seed input, then mutations of it (bytes
//! flipped, cut, duplicated, or replaced by the tokens that break readers:
//! NaN, inf, 1e308, empty fields, separators, a BOM, text), must never
//! panic and must be accepted with valid output or refused with one short
//! line. The long runs are `cargo fuzz` (docs/src/development.md).

use incal_fuzz::{check, run, seed, target_names, Outcome};
use proptest::prelude::*;

const TOKENS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e-320",
    "",
    ",",
    "\n",
    "\r\n",
    "\u{feff}",
    "abc",
    "0",
    "-0",
    "99999999999999999999",
    "\"",
    "#",
    " ",
    "x_p",
    "x_rot",
    "[",
    "]",
    "{",
    "}",
    "=",
    "1e15",
    "-1",
    "0.0",
    "9.81",
];

#[derive(Debug, Clone)]
enum Mutation {
    Flip(usize, u8),
    Cut(usize),
    Token(usize, usize, usize),
    Duplicate(usize, usize),
}

fn apply(base: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut v = base.to_vec();
    for m in muts {
        let n = v.len().max(1);
        match *m {
            Mutation::Flip(at, b) => {
                if !v.is_empty() {
                    v[at % n] ^= b;
                }
            }
            Mutation::Cut(at) => v.truncate(at % (n + 1)),
            Mutation::Token(at, len, t) => {
                let s = (at % n).min(v.len());
                let e = (s + len % 8).min(v.len());
                v.splice(s..e, TOKENS[t % TOKENS.len()].bytes());
            }
            Mutation::Duplicate(at, len) => {
                let s = (at % n).min(v.len());
                let e = (s + len % 200).min(v.len());
                let piece = v[s..e].to_vec();
                v.splice(s..s, piece);
            }
        }
    }
    v
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 1u8..=255).prop_map(|(a, b)| Mutation::Flip(a, b)),
        any::<usize>().prop_map(Mutation::Cut),
        (any::<usize>(), any::<usize>(), any::<usize>())
            .prop_map(|(a, l, t)| Mutation::Token(a, l, t)),
        (any::<usize>(), any::<usize>()).prop_map(|(a, l)| Mutation::Duplicate(a, l)),
    ]
}

#[test]
fn every_seed_is_valid_and_accepted() {
    for t in target_names() {
        let s = seed(t);
        assert!(!s.is_empty(), "{t}: empty seed");
        match run(t, s) {
            Outcome::Accepted(_) => {}
            Outcome::Refused(m) => panic!("{t}: the valid seed is refused: {m}"),
        }
        check(t, s).unwrap_or_else(|e| panic!("{t}: {e}"));
        // The empty input is refused, not a panic.
        assert!(matches!(run(t, b""), Outcome::Refused(_)), "{t}");
        check(t, b"").unwrap_or_else(|e| panic!("{t}: {e}"));
    }
}

/// The property tests' seed: fixed, so CI runs the same inputs every time
/// (a random one once failed a run on an input no other run had drawn);
/// `PROPTEST_RNG_SEED=N` explores others (a longer campaign is the fuzz
/// targets' job).
fn rng_seed() -> proptest::test_runner::RngSeed {
    let seed = std::env::var("PROPTEST_RNG_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_261_130);
    proptest::test_runner::RngSeed::Fixed(seed)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, failure_persistence: None, rng_seed: rng_seed(), ..ProptestConfig::default() })]

    #[test]
    fn mutated_inputs_never_panic(target in 0..target_names().len(), muts in prop::collection::vec(mutation(), 1..6)) {
        let t = target_names()[target];
        let data = apply(seed(t), &muts);
        let r = std::panic::catch_unwind(|| check(t, &data));
        match r {
            Ok(Ok(())) => {}
            Ok(Err(e)) => prop_assert!(false, "{t}: {e}"),
            Err(_) => prop_assert!(false, "{t}: panicked"),
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(target in 0..target_names().len(), data in prop::collection::vec(any::<u8>(), 0..400)) {
        let t = target_names()[target];
        let r = std::panic::catch_unwind(|| check(t, &data));
        prop_assert!(matches!(r, Ok(Ok(()))), "{t}: {r:?}");
    }
}

/// The fixed campaign CI runs: [`incal_fuzz::ci_executions`] mutations of
/// every target's seed from one stream, each checked against the contract
/// (the same inputs on every run; a longer campaign is recorded in the
/// README).
#[test]
fn every_target_runs_its_fixed_executions() {
    for t in target_names() {
        let n = incal_fuzz::ci_executions(t);
        let c = incal_fuzz::campaign(t, n, 0x5EED_0027).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(c.executions, n);
    }
}

/// Inputs the long campaign (`examples/rate.rs`, stream
/// 0x9E3779B97F4A7C15) found breaking the contract, rebuilt from the
/// stream and checked: each is now refused in one short line.
#[test]
fn inputs_the_long_campaign_found_keep_the_contract() {
    // warmup, chunk 0, execution 8040 (2026-11-29): "no warm-up curve
    // fits" listed every curve's failure, 567 characters.
    let base = incal_fuzz::seed("warmup");
    let mut r = incal_fuzz::Rng(0x9E37_79B9_7F4A_7C15 | 1);
    let mut data = Vec::new();
    for _ in 0..=8040 {
        data = incal_fuzz::mutate(base, &mut r);
    }
    assert_eq!(data.len(), 5846, "the stream no longer rebuilds the input");
    incal_fuzz::check("warmup", &data).unwrap();
}
