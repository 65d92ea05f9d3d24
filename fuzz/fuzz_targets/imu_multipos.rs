#![no_main]
//! Fuzz target `imu-multipos`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("imu-multipos", data) {
        panic!("imu-multipos: {e}");
    }
});
