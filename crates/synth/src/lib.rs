//! Wei-Levoy multiresolution texture synthesis of normal and colour maps (Haro et al. 2001,
//! section 4.1; Wei and Levoy 2000), for issue 3.
//!
//! * [`config`]: [`SynthConfig`] and [`Search`], validated against the exemplar (levels clamped
//!   with a warning, memory estimated before anything is allocated).
//! * [`appearance`]: the pyramid normal maps are matched in (a detail channel in place of `z` at
//!   the coarser levels, so pores are not averaged away).
//! * [`neighbourhood`]: causal `N x N` + full coarser `M x M` neighbourhoods as feature vectors.
//! * [`exemplar`]: candidate texels of one exemplar level and the exact (exhaustive) search.
//! * [`search`]: PCA (nalgebra, f64) + kiddo kd-tree approximate search; k-coherence sets.
//! * [`energy`]: the neighbourhood-matching energy the bench compares search modes with.
//! * [`synthesis`]: [`synthesize`], [`synthesize_normals`], [`replay`].
//! * `causal`, `correction` and `polish` (private): the scanline pass, the correction passes with
//!   the copy cap, and seam polishing of the finest level by every window a texel lies in;
//!   `scoring` (private) how all of them score a candidate (occurrence penalty, tree refinement),
//!   `level` (private) what they share of one level (its search structures and initial copies)
//!   and `interleave` (private) the interleaved sub-passes the correction and polishing run in.
//! * [`metrics`]: quality measures.
//!
//! Texels are `Vec3` throughout: colour as linear RGB, normals as unnormalised vectors (pyramid
//! averages stay meaningful; the finest level copies unit exemplar texels, so no renormalisation
//! is needed on output). Pyramids come from `skinkit_maps::pyramid` (5-tap kernel, clamped
//! borders for the exemplar; output sides halve rounding up, addressed toroidally).
//!
//! # Defaults and where they were measured
//!
//! [`SynthConfig::default`] is the upsampled start (Lefebvre and Hoppe 2005) with k-coherence
//! correction passes (a robust distance at the coarser levels, [`SynthConfig::robust_scale`]),
//! seam polishing, a copy cap and a collapse guard; [`SynthConfig::scanline`] the Wei-Levoy
//! causal start. Both are scored against the `texture-synthesis` peer on a fixed set of
//! exemplars by `benches/suite.rs` (its table is in the book); `benches/table.rs` gives
//! accuracy against time per search mode, and `docs/synthesis-notes.md` keeps what was measured
//! on the way (the occurrence penalty, correction passes, seams, search modes).

pub mod appearance;
pub mod band;
mod causal;
pub mod config;
pub mod coords;
mod correction;
pub mod deliver;
pub mod energy;
pub mod error;
pub mod exemplar;
mod interleave;
mod level;
pub mod map;
pub mod memory;
pub mod metrics;
pub mod neighbourhood;
mod polish;
pub mod report;
pub mod schedule;
mod scoring;
pub mod search;
pub mod synthesis;

pub use config::{Delivery, Search, Start, SynthConfig};
pub use error::{Error, Result};
pub use map::{Grown, Map};
pub use report::{OptionsReport, QualityReport};
pub use schedule::LevelPlan;
pub use synthesis::{
    BandSink, Guards, NormalSynthesis, Streamed, Synthesis, replay, synthesize, synthesize_normals,
    synthesize_normals_streamed, synthesize_streamed,
};
