//! What a growth holds at its peak (issue 43): [`SynthConfig::memory_estimate`], the one estimate
//! `synth`, `face`, `stitch` and `batch` plan and refuse jobs by.
//!
//! A growth runs its levels coarsest first; while level `k` grows it holds the finished level
//! `k + 1` (its parent, texels and coordinates), the grid being corrected (the whole level, or a
//! band's window: [`crate::band`]), and what the level's rows go to: the next level's collected
//! grid, or at the finest level the whole output ([`Delivery::Whole`]) or the bands queued for
//! the files' writers and the quality crop ([`Delivery::Streamed`]). After the finest level the
//! quality figures are measured on the crop (or the whole output). The peak is the largest of
//! these phases, plus the exemplar's pyramid, features, sets and trees, and the program itself.
//!
//! The per-texel constants are the buffers' sizes (texels 12 bytes, coordinates 8) and, for the
//! transients of a correction pass and of the quality figures, calibrated against the peak
//! resident memory of `skinkit synth` (the test `the_memory_estimate_tracks_the_measured_peak` in the CLI's
//! tests and the benchmark `memory` check them).

use crate::band::{BAND_HALO, bands};
use crate::config::{Delivery, Search, Start, SynthConfig, half};
use crate::deliver::QUALITY_SIDE;

/// The program's own resident memory before any map: code, libraries, the thread pools' stacks
/// and the allocator's arenas (10 MiB measured at the first level's start).
const PROGRAM_BYTES: u64 = 10 << 20;

/// A texel and its coordinates, as every level and band holds them.
const TEXEL_BYTES: u64 = 12 + 8;

/// What a correction pass holds per texel of its grid beyond the texels and coordinates: a
/// sub-pass's choices, the copy cap's union-find and flags, the polishing pass's scratch
/// (measured: 17 bytes a texel of a 4096 x 1056 window).
const CORRECTION_BYTES: u64 = 17;

/// What the correction passes leave allocated per texel of their grid while its band is handed
/// on (the allocator keeps part of their scratch; measured: 7-10 bytes a texel of 4096- and
/// 8192-wide windows).
const RETAINED_BYTES: u64 = 9;

/// What the quality figures hold per texel measured beyond the texels and coordinates: spectra,
/// histograms, copied blocks (measured: 44-49 bytes a texel of 1024x1024 and 2048x2048 crops,
/// the colour figures' the fewer).
const QUALITY_BYTES: u64 = 44;

/// A level's sizes, and how it grows: whole, or in bands (the tallest band's rows, and its
/// window's rows with the context above and below).
struct LevelShape {
    width: u64,
    height: u64,
    band_rows: u64,
    window_rows: u64,
}

impl LevelShape {
    fn texels(&self) -> u64 {
        self.width.saturating_mul(self.height)
    }
    fn band(&self) -> u64 {
        self.width.saturating_mul(self.band_rows)
    }
    fn window(&self) -> u64 {
        self.width.saturating_mul(self.window_rows)
    }
    fn banded(&self) -> bool {
        self.band_rows < self.height
    }
}

impl SynthConfig {
    /// Bytes a run from an `ew x eh` exemplar holds at its peak, delivered as
    /// [`SynthConfig::delivery`] says (see the module's docs for what is counted).
    pub fn memory_estimate(&self, ew: usize, eh: usize) -> u64 {
        let shapes = self.level_shapes();
        let mut peak = 0u64;
        for (k, level) in shapes.iter().enumerate() {
            let parent = shapes.get(k + 1).map_or(0, |p| p.texels().saturating_mul(TEXEL_BYTES));
            peak = peak.max(parent.saturating_add(self.level_bytes(k, level)));
        }
        let quality = match self.delivery {
            Delivery::Whole => shapes[0].texels().saturating_mul(TEXEL_BYTES + QUALITY_BYTES),
            Delivery::Streamed { .. } => self.crop_texels().saturating_mul(TEXEL_BYTES + QUALITY_BYTES),
        };
        PROGRAM_BYTES.saturating_add(self.exemplar_bytes(ew, eh)).saturating_add(peak.max(quality))
    }

    /// The output levels, finest first, as the growth runs them ([`crate::band`]: the levels
    /// of more than a band's rows that start from their coarser level grow in bands).
    fn level_shapes(&self) -> Vec<LevelShape> {
        let levels = self.levels.max(1);
        let (mut w, mut h) = (self.width, self.height);
        let mut shapes = Vec::with_capacity(levels);
        for k in 0..levels {
            let bands = bands(h);
            let banded = self.start == Start::Upsampled && k + 1 < levels && bands.len() > 1;
            let tallest = bands.iter().map(|b| b.len()).max().unwrap_or(0);
            let (band_rows, window_rows) = if banded { (tallest, (tallest + 2 * BAND_HALO).min(h)) } else { (h, h) };
            shapes.push(LevelShape {
                width: w as u64,
                height: h as u64,
                band_rows: band_rows as u64,
                window_rows: window_rows as u64,
            });
            (w, h) = (half(w), half(h));
        }
        shapes
    }

    /// What level `k` holds at its peak besides its parent: its grid (or band window) while it
    /// is corrected, then when a band is handed on, with what its rows go to: the next level's
    /// collected grid (or the whole output), or at a streamed finest level the band the writer
    /// still holds and the quality crop.
    fn level_bytes(&self, k: usize, level: &LevelShape) -> u64 {
        let window = level.window().saturating_mul(TEXEL_BYTES);
        let correcting = level.window().saturating_mul(CORRECTION_BYTES);
        // A band's own rows are copied out of its window when it is handed on; a whole level
        // is handed on as it is.
        let copied = if level.banded() { level.band().saturating_mul(TEXEL_BYTES) } else { 0 };
        let handed_on = copied.saturating_add(level.window().saturating_mul(RETAINED_BYTES));
        let rows_to = match (k, self.delivery) {
            (0, Delivery::Streamed { coords }) => {
                let queued =
                    if level.banded() { level.band().saturating_mul(if coords { TEXEL_BYTES } else { 12 }) } else { 0 };
                queued.saturating_add(self.crop_texels().saturating_mul(TEXEL_BYTES))
            }
            _ if level.banded() => level.texels().saturating_mul(TEXEL_BYTES),
            _ => 0,
        };
        window.saturating_add(rows_to).saturating_add(correcting.max(handed_on))
    }

    /// The texels the quality figures are measured on: the whole output, or for a streamed one
    /// its central crop ([`QUALITY_SIDE`] a side at most).
    fn crop_texels(&self) -> u64 {
        let (w, h) = match self.delivery {
            Delivery::Whole => (self.width, self.height),
            Delivery::Streamed { .. } => (self.width.min(QUALITY_SIDE), self.height.min(QUALITY_SIDE)),
        };
        (w as u64).saturating_mul(h as u64)
    }

    /// The exemplar's pyramid and, per candidate of its finest level, the features, projected
    /// points and trees of the search (the coarser levels', a quarter each, are freed before).
    fn exemplar_bytes(&self, ew: usize, eh: usize) -> u64 {
        let texels = (ew as u64).saturating_mul(eh as u64);
        let tree = |dims: usize| 4 * dims as u64 + 4 * dims.next_power_of_two().max(4) as u64 + 8;
        let n2 = (self.neighbourhood * self.neighbourhood) as u64;
        let m2 = (self.parent * self.parent) as u64;
        let causal = 3 * (n2 / 2 + m2);
        let full = 3 * (n2 + m2);
        let search = match self.search {
            Search::Exact => 4 * causal + 4 * full,
            Search::Approximate { dims, .. } if self.corrections == 0 => 4 * causal + tree(dims) + 4 * full,
            Search::Approximate { dims, .. } => 4 * causal + 4 * full + 2 * tree(dims),
            Search::KCoherence { k, fallback, dims, .. } => {
                // Causal and full features, the sets, one tree at a time, and the fallback's.
                let fallback = fallback.map_or(0, |_| tree(dims));
                4 * causal + 4 * full + 8 * k as u64 + tree(dims) + fallback
            }
        };
        texels.saturating_mul(12 * 4 / 3 + search)
    }
}
