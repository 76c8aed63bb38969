//! One module per subcommand: its `Args` and its `run`.

pub mod accuracy;
pub mod batch;
pub mod capture;
pub mod demo;
pub mod export;
pub mod height;
pub mod lut;
pub mod render;
pub mod rig;
pub mod samples;
pub mod stitch;
pub mod synth;
