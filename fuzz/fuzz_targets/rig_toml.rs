#![no_main]
//! Fuzz target `rig_toml`: see `tests/fuzz/entries.rs` for what it reads and checks.

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = skinkit_fuzz::rig_toml(data);
});
