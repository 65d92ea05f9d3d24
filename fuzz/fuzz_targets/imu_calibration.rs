#![no_main]
//! Fuzz target `imu-calibration`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("imu-calibration", data) {
        panic!("imu-calibration: {e}");
    }
});
