#![no_main]
//! Fuzz target `tumble`: see `incal_fuzz`.
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Err(e) = incal_fuzz::check("tumble", data) {
        panic!("tumble: {e}");
    }
});
