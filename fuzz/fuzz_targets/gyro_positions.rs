#![no_main]
//! Fuzz target `gyro-positions`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("gyro-positions", data) {
        panic!("gyro-positions: {e}");
    }
});
