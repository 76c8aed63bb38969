//! The fuzz targets' entry points: the same file the regression test `tests/fuzz_regressions.rs`
//! replays kept crash inputs through, so a fixed crash stays fixed.

#[path = "../../tests/fuzz/entries.rs"]
mod entries;

pub use entries::*;
