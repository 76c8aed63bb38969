#![no_main]
//! Fuzz target `scene`: see `tests/fuzz/entries.rs` for what it reads and checks.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = skinkit_fuzz::scene(data);
});
