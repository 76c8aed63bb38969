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
//! level clamping; memory refusal; replay. Correction passes: exact search with two passes equal
//! to an independent brute-force full-window oracle; same bits on 1 and 2 threads in every mode;
//! one pass lowers the energy (by a measured margin) and a second does not raise it by more
//! than 5 %.
//!
//! Search modes ([`Search`]): `Exact` (the reference); `Approximate` (PCA + kd-tree, Ashikhmin
//! coherence candidates scored first and bounding the tree search, a lossless cut since the
//! projection is orthonormal); `KCoherence` (Tong et al. 2002; sets of `k` similar exemplar
//! texels by full `N x N` + coarser window, built per level with a PCA kd-tree and a re-scored pool
//! of `max(2 k, 16)`; candidates scored with an early-exit distance; optional kd-tree fallback
//! above `ratio` x the level's typical distance).
//!
//! Measured before correction passes existed (i.e. `corrections: 0`; release, 2 cores shared with another build, forehead heightfield normals 128x128,
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
//! Correction passes (`SynthConfig::corrections`, see [`synthesis`]): k = 4, same exemplar and
//! seed, energy as above (absolute, 5x5 windows, every other texel; deterministic) and the run's
//! CPU seconds on one rayon thread (best of 3; the machine was shared with other builds, load
//! 4-6 on 2 cores, so wall times were not measurable cleanly). Relative energies are to the
//! uncorrected 5x5 run of the same size.
//!
//! | N | corrections | 256: energy | 256: CPU s | 512: energy | 512: CPU s |
//! | --- | --- | --- | --- | --- | --- |
//! | 5 | 0 | 0.04367 (1.000) | 0.44 | 0.04337 (1.000) | 0.76 |
//! | 5 | 1 | 0.03179 (0.728) | 0.67 | 0.03215 (0.741) | 1.50 |
//! | 5 | 2 | 0.03008 (0.689) | 0.87 | 0.02887 (0.666) | 2.36 |
//! | 7 | 0 | 0.04188 (0.959) | 0.61 | 0.04225 (0.974) | 1.08 |
//! | 7 | 1 | 0.02871 (0.657) | 1.00 | 0.02839 (0.655) | 2.78 |
//! | 7 | 2 | 0.02605 (0.597) | 1.36 | 0.02616 (0.603) | 4.08 |
//!
//! One pass removes about a quarter of the energy, more than a 7x7 window (4 %) or k = 8 did; a
//! second pass adds less (4-10 %) for as much time again. The passes run in parallel, so on 2
//! free cores one 5x5 pass should add about half its CPU time, (1.50 - 0.76) / 2 = 0.37 s, to the
//! 0.56 s measured before at 512x512: about 0.93 s, inside the 1 s target. Default:
//! **1 correction pass** (`config::DEFAULT_CORRECTIONS`), 5x5. Interleaving stride
//! (`config::CORRECTION_STRIDE`) at 256x256, 5x5, one pass: 1 (Jacobi) 0.03323, 2: 0.03384,
//! 3: 0.03179, 5 (sub-passes fully independent): 0.03339; 3 is used. Drawing the k-coherence
//! candidates from the inner 3x3 neighbours' sources only (instead of all `N x N`) cut the pass's
//! CPU time by about 40 % for energy 0.03336 instead of 0.03215 at 512x512; not adopted.
//!
//! Next steps:
//! 1. Speed: the causal pass is sequential, ~0.45 s of 512x512's CPU time. A wavefront cannot
//!    reproduce it (texel `(0, y)` reads row `y - 1`'s last columns through the toroidal wrap). A
//!    deterministic pipeline is possible if wrapped causal reads take the level's initial noise
//!    instead (row `y` at column `x` then waits only for row `y - 1` up to `x + N / 2`; rows
//!    round-robin on threads with atomic progress counters); it changes the results (the exact
//!    oracle in the tests would change with it) and gains at most ~0.2 s at 512x512 on 2 cores.
//!    Not done yet (time). Also: build the finest-level sets once per exemplar and cache them
//!    across runs (`skinkit synth`).
//! 2. Quality: measure each ingredient's energy against `Search::Exact` and the peer, and produce
//!    the README table (D x N x levels, 256x256 from 128x128), now with correction passes.
//! 3. The `texture-synthesis` peer in the bench, and the `skinkit synth` / `skinkit synth replay`
//!    commands (progress callback is per output row, and per correction sub-pass).
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
