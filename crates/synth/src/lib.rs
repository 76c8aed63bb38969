//! Wei-Levoy multiresolution texture synthesis of normal and colour maps (Haro et al. 2001,
//! section 4.1; Wei and Levoy 2000), for issue 3.
//!
//! * [`config`]: [`SynthConfig`] and [`Search`], validated against the exemplar (levels clamped
//!   with a warning, memory estimated before anything is allocated).
//! * [`neighbourhood`]: causal `N x N` + full coarser `M x M` neighbourhoods as feature vectors.
//! * [`exemplar`]: candidate texels of one exemplar level and the exact (exhaustive) search.
//! * [`search`]: PCA (nalgebra, f64) + kiddo kd-tree approximate search; k-coherence sets.
//! * [`energy`]: the neighbourhood-matching energy the bench compares search modes with.
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
//! exact (with and without coherence); k-coherence with a zero fallback ratio and a full rerank
//! equal to exact; k-coherence sets equal to a brute-force nearest-window scan; the energy equal to
//! a brute-force scan; same bits on 1 and 2 threads (every mode); every output texel equals its
//! coordinate's exemplar texel; constant, non-finite, too-small, non-square exemplars; 1x1 output;
//! level clamping; memory refusal; replay.
//!
//! Search modes ([`Search`]): `Exact` (the reference); `Approximate` (PCA + kd-tree, Ashikhmin
//! coherence candidates scored first and bounding the tree search, a lossless cut since the
//! projection is orthonormal); `KCoherence` (Tong et al. 2002; sets of `k` similar exemplar
//! texels by full `N x N` + coarser window, built per level with a PCA kd-tree and a re-scored pool
//! of `max(2 k, 16)`; candidates scored with an early-exit distance; optional kd-tree fallback
//! above `ratio` x the level's typical distance).
//!
//! Measured (release, 2 cores shared with another build, forehead heightfield normals 128x128,
//! 3 levels, 5x5 + 3x3, seed 1; `cargo bench -p skinkit-synth --bench synth`). Energy:
//! [`energy::window_energy`], 5x5 windows, finest level, every other texel, relative to exact at
//! 256x256 (0.0493; greedy exact search is not the energy optimum, so faster modes can score
//! lower):
//!
//! | mode | 256x256 | 512x512 | energy 256 / 512 |
//! | --- | --- | --- | --- |
//! | exact | 18-28 s (one run) | - | 1.000 / - |
//! | PCA-8 rerank-8 + coherence | 1.61 s | 6.36 s | 0.880 / 0.881 |
//! | k-coherence k = 4 | 0.29 s | 0.56 s | 0.885 / 0.879 |
//! | k-coherence k = 4, fallback 2x typical | 0.44 s | 1.06 s | 0.934 / 0.903 |
//! | k-coherence k = 8 | 0.37 s | 0.92 s | 0.887 / 0.850 |
//! | k-coherence k = 4, 7x7 | 0.40 s | 0.94 s | 0.849 / 0.856 |
//!
//! (Criterion medians, 10 samples.) k-coherence meets the 512x512 < 1 s target at
//! PCA-8's energy (k = 4: 11x faster); k = 8 and a 7x7 window lower the energy a little for
//! about 1.7x the time (both still under 1 s); the tree fallback costs time and did not lower the
//! energy here. Of the 512x512 k = 4 time, ~0.18 s is building the finest level's sets. One
//! 4096x2048 run with k = 4 (`SYNTH_BENCH_LARGE=1`): 13.5 s, energy 0.0434 (every 16th texel),
//! under the 30 s. Before this change the fastest mode of equal energy was PCA-8 (above).
//!
//! Next steps:
//! 1. Speed: parallelise the texel loop by wavefront (a texel needs its row's left part and the
//!    rows above only) — the loop is single-threaded, so the second core idles; build the
//!    finest-level sets once per exemplar and cache them across runs (`skinkit synth`).
//! 2. Quality: a correction pass (re-synthesise each level once with full, non-causal
//!    neighbourhoods, which k-coherence makes cheap; the prototypes matched the peer with
//!    7x7 + one pass); measure each ingredient's energy against `Search::Exact` and produce the
//!    README table (D x N x levels, 256x256 from 128x128).
//! 3. The `texture-synthesis` peer in the bench, and the `skinkit synth` / `skinkit synth replay`
//!    commands (progress callback is per output row).
//! 4. Slopes instead of unnormalised vectors as the feature space (an option), and weighting
//!    (Gaussian kernel over the neighbourhood) if it helps energy.

pub mod config;
pub mod energy;
pub mod error;
pub mod exemplar;
pub mod metrics;
pub mod neighbourhood;
pub mod search;
pub mod synthesis;

pub use config::{Search, SynthConfig};
pub use error::{Error, Result};
pub use synthesis::{NormalSynthesis, Synthesis, replay, synthesize, synthesize_normals};
