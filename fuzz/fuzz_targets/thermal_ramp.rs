#![no_main]
//! Fuzz target `thermal-ramp`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("thermal-ramp", data) {
        panic!("thermal-ramp: {e}");
    }
});
