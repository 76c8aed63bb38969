#![no_main]
//! Fuzz target `coverage_mask`: see `tests/fuzz/entries.rs` for what it reads and checks.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = skinkit_fuzz::coverage_mask(data);
});
