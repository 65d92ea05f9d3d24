#![no_main]
//! The one `cargo fuzz` binary: it runs the target named by the
//! environment variable `INCAL_FUZZ_TARGET` (`incal_fuzz::targets`: every
//! registry procedure's input and the documents beside them), e.g.
//! `INCAL_FUZZ_TARGET=tumble cargo +nightly fuzz run target corpus/tumble`.
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;

fn target() -> &'static str {
    static NAME: OnceLock<&'static str> = OnceLock::new();
    NAME.get_or_init(|| {
        let name = std::env::var("INCAL_FUZZ_TARGET").unwrap_or_default();
        let names = incal_fuzz::target_names();
        match names.iter().find(|t| **t == name) {
            Some(t) => t,
            None => panic!(
                "set INCAL_FUZZ_TARGET to one of: {} (got {name:?})",
                names.join(", ")
            ),
        }
    })
}

fuzz_target!(|data: &[u8]| {
    let t = target();
    if let Err(e) = incal_fuzz::check(t, data) {
        panic!("{t}: {e}");
    }
});
