#![no_main]
//! Fuzz target `gfimu-geometry`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("gfimu-geometry", data) {
        panic!("gfimu-geometry: {e}");
    }
});
