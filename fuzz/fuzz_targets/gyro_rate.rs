#![no_main]
//! Fuzz target `gyro-rate`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("gyro-rate", data) {
        panic!("gyro-rate: {e}");
    }
});
