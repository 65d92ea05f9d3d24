#![no_main]
//! Fuzz target `gfimu-solve`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("gfimu-solve", data) {
        panic!("gfimu-solve: {e}");
    }
});
