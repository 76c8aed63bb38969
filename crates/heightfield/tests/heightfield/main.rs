//! The heightfield crate's integration tests, one binary: each file a module.

mod render;
mod skin;
