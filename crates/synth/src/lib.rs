//! Wei-Levoy multiresolution texture synthesis of normal and colour maps (Haro et al. 2001,
//! section 4.1; Wei and Levoy 2000), for issue 3.
//!
//! * [`config`]: [`SynthConfig`] and [`Search`], validated against the exemplar (levels clamped
//!   with a warning, memory estimated before anything is allocated).
//! * [`neighbourhood`]: causal `N x N` + full coarser `M x M` neighbourhoods as feature vectors.
//! * [`exemplar`]: candidate texels of one exemplar level and the exact (exhaustive) search.
//! * [`search`]: PCA (nalgebra, f64) + kiddo kd-tree approximate search.
//! * [`synthesis`]: [`synthesize`], [`synthesize_normals`], [`replay`].
//! * [`metrics`]: quality measures.
//!
//! Texels are `Vec3` throughout: colour as linear RGB, normals as unnormalised vectors (pyramid
//! averages stay meaningful; the finest level copies unit exemplar texels, so no renormalisation
//! is needed on output). Pyramids come from `skinkit_maps::pyramid` (5-tap kernel, clamped
//! borders for the exemplar; output sides halve rounding up, addressed toroidally).
//!
//! # Status and next steps
//!
//! Done (tested in `tests/synthesis.rs`): exact search equal to an independent brute-force
//! single-level synthesis; approximate search with `rerank` covering every candidate equal to
//! exact (with and without coherence); same bits on 1 and 2 threads; every output texel equals
//! its coordinate's exemplar texel; constant, non-finite, too-small, non-square exemplars; 1x1
//! output; level clamping; memory refusal; replay. Approximate search scores Ashikhmin coherence
//! candidates first and searches the tree only within the best coherent distance (a lossless cut:
//! the projection is orthonormal, so projected distances bound full ones from below).
//!
//! Measured once (release, 2 cores, forehead heightfield normals, 3 levels, 5x5 + 3x3; "energy"
//! here is a crude proxy: mean smallest squared distance of each output texel's full 5x5 window
//! to an exemplar window, finest level only):
//!
//! | run | exact | PCA-4 rerank-8 | PCA-8 rerank-8 | PCA-8 rerank-8 + coherence |
//! | --- | --- | --- | --- | --- |
//! | 64x64 from 32x32 | 0.09 s, 0.108 | 0.010 s, 0.092 | 0.019 s, 0.095 | 0.022 s, 0.105 |
//! | 128x128 from 64x64 | 1.29 s, 0.071 | 0.046 s, 0.061 | 0.24 s, 0.067 | 0.20 s, 0.071 |
//! | 256x256 from 128x128 | - | 0.21 s | 1.4 s | 1.9 s |
//!
//! The kd-tree query is ~85 % of the time: in 8+ dimensions kiddo visits many leaves. Greedy
//! exact search is not the energy optimum: approximate modes can score lower than it.
//!
//! Next steps:
//! 1. Speed (issue target 512x512 from 128x128 < 1 s): accept the best coherence candidate
//!    without a tree query when its distance is below a threshold (e.g. a quantile of the
//!    exemplar's leave-one-out distances), or precompute k-coherence sets (Tong 2002) per
//!    exemplar texel; try kiddo's `approx_nearest_one` for the tree fallback; parallelise the
//!    texel loop by wavefront (a texel needs its row's left part and the rows above only).
//! 2. Quality: a correction pass (re-synthesise each level once with full, non-causal
//!    neighbourhoods), 7x7 option; measure each ingredient's energy against `Search::Exact`
//!    with [`metrics`] and produce the README table (D x N x levels, 256x256 from 128x128).
//! 3. Criterion bench in `crates/synth/benches/` (incl. the `texture-synthesis` peer), and the
//!    `skinkit synth` / `skinkit synth replay` commands (progress callback is per output row).
//! 4. Slopes instead of unnormalised vectors as the feature space (an option), and weighting
//!    (Gaussian kernel over the neighbourhood) if it helps energy.

pub mod config;
pub mod error;
pub mod exemplar;
pub mod metrics;
pub mod neighbourhood;
pub mod search;
pub mod synthesis;

pub use config::{Search, SynthConfig};
pub use error::{Error, Result};
pub use synthesis::{NormalSynthesis, Synthesis, replay, synthesize, synthesize_normals};
