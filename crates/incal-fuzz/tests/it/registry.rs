//! Every procedure of the registry is fuzzed: each target its entry names
//! ([`incal::procedures::registry::Entry::fuzz`]) is one of
//! [`incal_fuzz::targets`], is reduced through the entry's typed reduction
//! with its example options (or, for an entry that reduces result
//! documents, by its own target), and has a seed (written by
//! `make-seeds.sh`) that it accepts; the one `cargo fuzz` binary runs
//! every target. Each gap is named ("procedure thermal-ramp: fuzz target
//! thermal-ramp has no seed").

use std::path::Path;

use incal::procedures::registry::{InputKind, REGISTRY};
use incal_fuzz::{run, seed, target_names, Outcome};

#[test]
fn every_registry_procedure_has_its_fuzz_targets_and_seeds() {
    let names = target_names();
    let mut gaps = Vec::new();
    for e in REGISTRY {
        if e.fuzz.is_empty() {
            gaps.push(format!("procedure {}: no fuzz target", e.id));
        }
        if e.input == InputKind::Recording && e.reduction.and_then(|t| t.example).is_none() {
            gaps.push(format!(
                "procedure {}: no typed reduction with example options to fuzz",
                e.id
            ));
        }
        for t in e.fuzz {
            if !names.contains(t) {
                gaps.push(format!("procedure {}: no fuzz target {t}", e.id));
            } else if seed(t).is_empty() {
                gaps.push(format!(
                    "procedure {}: fuzz target {t} has no seed (crates/incal-fuzz/seeds/{t}, make-seeds.sh)",
                    e.id
                ));
            } else if let Outcome::Refused(m) = run(t, seed(t)) {
                gaps.push(format!(
                    "procedure {}: fuzz target {t} refuses its own seed: {m}",
                    e.id
                ));
            }
        }
    }
    assert!(gaps.is_empty(), "{}", gaps.join("\n"));
}

#[test]
fn the_cargo_fuzz_binary_runs_every_target_by_name() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cargo = std::fs::read_to_string(root.join("fuzz/Cargo.toml")).unwrap();
    let bin = std::fs::read_to_string(root.join("fuzz/fuzz_targets/target.rs")).unwrap();
    assert!(
        cargo.contains("name = \"target\""),
        "fuzz/Cargo.toml: no [[bin]] target"
    );
    assert!(
        bin.contains("INCAL_FUZZ_TARGET") && bin.contains("incal_fuzz::check"),
        "fuzz/fuzz_targets/target.rs: the target is not chosen by INCAL_FUZZ_TARGET"
    );
}

#[test]
fn every_target_has_a_seed_and_no_seed_is_orphaned() {
    let names = target_names();
    let mut seen = std::collections::BTreeSet::new();
    for t in &names {
        assert!(seen.insert(*t), "fuzz target {t} listed twice");
        assert!(!seed(t).is_empty(), "fuzz target {t}: no seed");
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds");
    for f in std::fs::read_dir(dir).unwrap().flatten() {
        let name = f.file_name().to_string_lossy().into_owned();
        assert!(
            names.contains(&name.as_str()),
            "seeds/{name}: no fuzz target of that name"
        );
    }
}
