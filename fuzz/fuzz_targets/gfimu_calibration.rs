#![no_main]
//! Fuzz target `gfimu-calibration`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("gfimu-calibration", data) {
        panic!("gfimu-calibration: {e}");
    }
});
