//! skinkit-synth's integration tests, one binary: each file a module, the shared helpers in
//! `support`.

mod bands;
mod brute_force;
mod guards;
mod metrics;
mod properties;
mod quality;
mod support;
mod synthesis;
