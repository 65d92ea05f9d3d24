//! Every procedure of the registry is fuzzed: each of its fuzz targets is
//! in [`incal_fuzz::TARGETS`], has a seed (written by `make-seeds.sh`) that
//! the target accepts, and a `cargo fuzz` binary in `fuzz/`. Each gap is
//! named ("procedure thermal-ramp: no fuzz target").

use std::path::Path;

use incal::procedures::registry::REGISTRY;
use incal_fuzz::{run, seed, Outcome, TARGETS};

#[test]
fn every_registry_procedure_has_its_fuzz_targets_seeds_and_binaries() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cargo = std::fs::read_to_string(root.join("fuzz/Cargo.toml")).unwrap();
    let seeds = std::fs::read_to_string(root.join("crates/incal-fuzz/make-seeds.sh")).unwrap();
    let mut gaps = Vec::new();
    for e in REGISTRY {
        for t in e.fuzz {
            let bin = t.replace('-', "_");
            if !TARGETS.iter().any(|(name, _)| name == t) {
                gaps.push(format!(
                    "procedure {}: no fuzz target {t} in incal_fuzz::TARGETS",
                    e.id
                ));
                continue;
            }
            if seed(t).is_empty() {
                gaps.push(format!("procedure {}: fuzz target {t} has no seed", e.id));
            } else if let Outcome::Refused(m) = run(t, seed(t)) {
                gaps.push(format!(
                    "procedure {}: fuzz target {t} refuses its own seed: {m}",
                    e.id
                ));
            }
            if !seeds.contains(&format!("\"$D/{t}\"")) {
                gaps.push(format!(
                    "procedure {}: make-seeds.sh does not write the seed of {t}",
                    e.id
                ));
            }
            if !root.join(format!("fuzz/fuzz_targets/{bin}.rs")).exists() {
                gaps.push(format!("procedure {}: no fuzz/fuzz_targets/{bin}.rs", e.id));
            }
            if !cargo.contains(&format!("name = \"{bin}\"")) {
                gaps.push(format!(
                    "procedure {}: fuzz/Cargo.toml has no [[bin]] {bin}",
                    e.id
                ));
            }
        }
    }
    assert!(gaps.is_empty(), "{}", gaps.join("\n"));
}
