//! What a synthesis reports about itself: the options it ran with and the quality of its output
//! against the exemplar. Both serialise as the `options` and `quality` blocks of
//! `skinkit synth --report`.

use serde::Serialize;
use skinkit_maps::Grid;

use crate::map::Map;
use crate::metrics::{self, DEFAULT_SPECTRUM_BINS};
use crate::{Guards, Search, SynthConfig};

/// The options as run (after validation adapted them to the exemplar).
#[derive(Clone, Debug, Serialize)]
pub struct OptionsReport {
    pub kind: String,
    pub levels_requested: usize,
    /// `scanline` (Wei-Levoy causal pass) or `upsampled` (Lefebvre-Hoppe coordinates).
    pub start: String,
    pub occurrence_penalty: f32,
    /// Occurrence penalty of the two coarsest levels (the larger of it and the general one).
    pub layout_penalty: f32,
    /// Largest verbatim copy allowed, share of the exemplar's area (`null`: no cap).
    pub copy_cap: Option<f32>,
    pub levels: usize,
    pub neighborhood: usize,
    pub parent: usize,
    pub corrections: usize,
    /// Correction passes at the coarser levels.
    pub coarse_corrections: usize,
    /// Seam-polishing passes at the finest level.
    pub polish: usize,
    /// Normal maps: weight of the coarser levels' detail channel (`null` for colour maps).
    pub detail_weight: Option<f32>,
    /// Scale of the coarser levels' robust distance (0: squared L2).
    pub robust_scale: f32,
    /// `exact`, `approximate` (PCA kd-tree) or `k-coherence (k = K)`.
    pub search: String,
    /// k-coherence: the tree fallback's ratio at the coarser levels and at the finest (`null`: no
    /// fallback).
    pub fallback: Option<f32>,
    pub finest_fallback: Option<f32>,
    /// k-coherence: the coherence bias at the coarser levels and at the finest.
    pub coherence_bias: f32,
    pub finest_coherence_bias: f32,
    pub dims: Option<usize>,
    pub rerank: Option<usize>,
    pub coherence: bool,
    pub exemplar_wrap: bool,
    pub seed: u64,
}

impl OptionsReport {
    /// The report of `run` (a validated configuration) growing a map of kind `kind` (`normal` or
    /// `color`), `levels_requested` being the level count asked for before validation.
    pub fn new(run: &SynthConfig, kind: &str, levels_requested: usize) -> Self {
        let fallback = match run.search {
            Search::KCoherence { fallback, .. } => fallback,
            _ => None,
        };
        let (search, dims, rerank) = match run.search {
            Search::Exact => ("exact".to_owned(), None, None),
            Search::Approximate { dims, rerank } => ("approximate".to_owned(), Some(dims), Some(rerank)),
            Search::KCoherence { k, dims, rerank, .. } => (format!("k-coherence (k = {k})"), Some(dims), Some(rerank)),
        };
        OptionsReport {
            kind: kind.to_owned(),
            levels_requested,
            start: format!("{:?}", run.start).to_lowercase(),
            occurrence_penalty: run.occurrence_penalty,
            layout_penalty: run.layout_penalty,
            copy_cap: run.copy_cap,
            levels: run.levels,
            neighborhood: run.neighbourhood,
            parent: run.parent,
            corrections: run.corrections,
            coarse_corrections: run.coarse_corrections.unwrap_or(run.corrections),
            polish: run.polish,
            detail_weight: (kind != "color").then_some(run.detail_weight),
            robust_scale: run.robust_scale,
            search,
            fallback,
            finest_fallback: run.finest_fallback.or(fallback),
            coherence_bias: run.coherence_bias,
            finest_coherence_bias: run.finest_coherence_bias.unwrap_or(run.coherence_bias),
            dims,
            rerank,
            coherence: run.coherence,
            exemplar_wrap: run.exemplar_wrap,
            seed: run.seed,
        }
    }
}

/// Quality of an output against its exemplar (see [`crate::metrics`]).
#[derive(Clone, Debug, Serialize)]
pub struct QualityReport {
    /// Normal maps: mean Wasserstein-1 distance of the slope histograms (slope units).
    pub slope_distance: Option<f64>,
    /// Colour maps: mean Wasserstein-1 distance of the channel histograms.
    pub channel_distance: Option<f64>,
    /// Mean decades between the radial power spectra.
    pub spectrum_distance: f64,
    /// Squared differences across the output's wrap-around seam over interior ones (~1 tiles).
    pub seam_energy_ratio: f64,
    /// The same for the exemplar, for comparison.
    pub exemplar_seam_energy_ratio: f64,
    /// The collapse guard: the output's slope (normals) or channel (colour) standard deviation
    /// over the exemplar's, the smallest over axes or channels; under 0.5 a warning says the output
    /// may be nearly blank.
    pub variation: f64,
    /// The histogram guard: how far the output's slope or channel histograms are from the
    /// exemplar's, in the exemplar's deviations (Wasserstein-1 distance over deviation, mean over
    /// axes or channels); above 0.15, on outputs of at least 64x64 texels that have not collapsed,
    /// the output was grown again with an occurrence penalty.
    pub histogram_mismatch: f64,
    /// Whether the output is the histogram guard's second growth (kept because it came nearer).
    pub histogram_retry: bool,
    /// Texels of the largest verbatim copied block.
    pub largest_block: usize,
    /// Mean copied block size in texels.
    pub mean_block: f64,
    /// Distinct copy offsets.
    pub distinct_offsets: usize,
}

impl QualityReport {
    /// The measures of `output` (grown by `coords` from `exemplar`, `wrap` if the exemplar was
    /// read as tiling) with the synthesis's own guard figures. `None` if the two maps are of
    /// different kinds.
    pub fn new(exemplar: &Map, output: &Map, coords: &Grid<[u32; 2]>, wrap: bool, guards: Guards) -> Option<Self> {
        let bins = DEFAULT_SPECTRUM_BINS;
        let copies = metrics::copy_statistics(coords, exemplar.size(), wrap);
        let (slope, channel, spectrum, seam, exemplar_seam) = match (exemplar, output) {
            (Map::Normal(e), Map::Normal(o)) => (
                Some(metrics::slope_distance(o, e)),
                None,
                metrics::normal_spectrum_distance(o, e, bins),
                metrics::normal_seam_energy(o).ratio,
                metrics::normal_seam_energy(e).ratio,
            ),
            (Map::Color(e), Map::Color(o)) => (
                None,
                Some(metrics::channel_distance(o, e)),
                metrics::color_spectrum_distance(o, e, bins),
                metrics::seam_energy(o).ratio,
                metrics::seam_energy(e).ratio,
            ),
            _ => return None,
        };
        Some(QualityReport {
            slope_distance: slope,
            channel_distance: channel,
            spectrum_distance: spectrum,
            seam_energy_ratio: seam,
            exemplar_seam_energy_ratio: exemplar_seam,
            variation: guards.variation,
            histogram_mismatch: guards.histogram,
            histogram_retry: guards.histogram_retry,
            largest_block: copies.largest_block,
            mean_block: copies.mean_block,
            distinct_offsets: copies.distinct_offsets,
        })
    }
}
