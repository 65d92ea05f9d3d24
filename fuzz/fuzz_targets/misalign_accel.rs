#![no_main]
//! Fuzz target `misalign-accel`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("misalign-accel", data) {
        panic!("misalign-accel: {e}");
    }
});
