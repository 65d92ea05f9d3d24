#![no_main]
//! Fuzz target `misalign-gyro`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("misalign-gyro", data) {
        panic!("misalign-gyro: {e}");
    }
});
