//! [`SynthConfig`]: the options of a synthesis run and their validation against an exemplar.

use crate::{Error, Result};

/// How the nearest exemplar neighbourhood is found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Search {
    /// Exhaustive L2 scan over every candidate: the reference every faster mode is measured against.
    Exact,
    /// PCA projection to `dims` dimensions (1..=32), a kd-tree query there, and the `rerank` best
    /// tree candidates re-scored in the full neighbourhood space.
    Approximate { dims: usize, rerank: usize },
    /// k-coherence (Tong et al. 2002): every exemplar candidate carries its `k` (1..=64) most
    /// similar candidates by full `N x N` (+ coarser `M x M`) neighbourhood, itself first. A texel's
    /// candidates are, for each synthesised causal neighbour, its source shifted back and that
    /// source's set; all are scored in the full causal feature space.
    ///
    /// `fallback`: when `Some(ratio)`, a texel whose best candidate's squared distance exceeds
    /// `ratio` times the level's typical squared distance (the median, over exemplar candidates,
    /// of the causal-feature distance to the most similar other candidate) is also searched with
    /// the PCA kd-tree of `dims` / `rerank` (as [`Search::Approximate`], bounded by the best
    /// distance so far; only at the levels that match in squared L2, see
    /// [`SynthConfig::robust_scale`]). `None` never queries a tree (a texel without any
    /// synthesised neighbour, i.e. the first of each level, is scanned exhaustively).
    KCoherence { k: usize, fallback: Option<f32>, dims: usize, rerank: usize },
}

impl Search {
    /// `k` of [`Search::K_COHERENCE`].
    pub const K_COHERENCE_K: usize = 4;
    /// k-coherence with `k` = 4 and no tree fallback (the default search of the scanline start).
    pub const K_COHERENCE: Search = Search::KCoherence { k: Self::K_COHERENCE_K, fallback: None, dims: 8, rerank: 8 };
}

/// How each output level gets its first state, before its correction passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Start {
    /// Wei-Levoy: the causal scanline pass (sequential), seeded with random exemplar copies.
    #[default]
    Scanline,
    /// Lefebvre and Hoppe 2005: the coarsest level is random exemplar copies, every finer level
    /// its coarser level's coordinates upsampled (child `2 p + (x mod 2, y mod 2)`), so whole
    /// exemplar patches are copied; the correction passes then do all the matching (parallel).
    Upsampled,
}

/// Options of [`crate::synthesize`]. The per-level overrides (`finest_*`, `coarse_corrections`,
/// `correction_penalty`, `layout_penalty`, the finest-only `copy_cap` and `polish`, and the
/// coarse-only `robust_scale`) are resolved in one place, [`SynthConfig::schedule`], into one
/// [`crate::LevelPlan`] per level, which is what synthesis reads.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthConfig {
    /// Output width in texels.
    pub width: usize,
    /// Output height in texels.
    pub height: usize,
    /// Pyramid levels (1 = single resolution); clamped to what the exemplar allows.
    pub levels: usize,
    /// Side of the causal neighbourhood at the current level (odd, at least 3).
    pub neighbourhood: usize,
    /// Side of the full neighbourhood at the coarser level (odd).
    pub parent: usize,
    /// Nearest-neighbourhood search mode (default [`Search::K_COHERENCE`]: k = 4, no fallback).
    pub search: Search,
    /// Add Ashikhmin coherence candidates ([`Search::Approximate`] only; k-coherence always uses
    /// them).
    pub coherence: bool,
    /// Exemplar neighbourhoods wrap around the exemplar (otherwise only texels whose whole
    /// neighbourhood lies inside are candidates).
    pub exemplar_wrap: bool,
    /// How each level starts before its correction passes ([`Start::Scanline`] by default).
    pub start: Start,
    /// [`Start::Upsampled`] only: each upsampled coordinate moves by a seeded random offset of up
    /// to this many texels per axis (Lefebvre and Hoppe's jitter; 0 = none).
    pub jitter: usize,
    /// Correction passes per level (0..=16; Wei and Levoy 2000's multi-pass extension, Lefebvre and
    /// Hoppe 2005's correction): after the causal scanline pass, every texel is chosen again with
    /// its full (non-causal) `N x N` neighbourhood, centre included, in [`CORRECTION_STRIDE`]`^2`
    /// interleaved sub-passes (see [`crate::synthesis`]).
    pub corrections: usize,
    /// Occurrence (histogram) penalty `lambda` (Kopf et al. 2007, section 4.3; 0 = off): a
    /// candidate whose exemplar texel the level already copies more than its share (output texels
    /// over candidates) has its squared distance multiplied by `1 + lambda * (count - share)`.
    /// Greedy nearest-neighbour search otherwise keeps picking the most typical (flat) texels and
    /// loses sparse features such as pores and furrows. Counts grow in scanline order in the causal
    /// pass and are taken from the state at the start of each correction sub-pass.
    pub occurrence_penalty: f32,
    /// The occurrence penalty at the finest level, if it differs from
    /// [`SynthConfig::occurrence_penalty`] (coarse levels decide the structure the penalty
    /// protects; the finest level decides how coherent the copies are).
    pub finest_penalty: Option<f32>,
    /// The occurrence penalty of the correction passes, if it differs from the causal pass's.
    pub correction_penalty: Option<f32>,
    /// The occurrence penalty at the [`LAYOUT_LEVELS`] coarsest levels when it is higher than
    /// [`SynthConfig::occurrence_penalty`] (never the finest level; see
    /// [`SynthConfig::schedule`]). Those levels lay out which parts of the exemplar
    /// the output grows from, and every finer level inherits the layout through its coordinates.
    /// Unpenalised, they draw from the exemplar's middle (its candidates lie at least half a
    /// window from the border at each level) and from its most typical windows: the output's
    /// slope histogram drifts from the exemplar's.
    pub layout_penalty: f32,
    /// Correction passes at the coarser levels, if they differ from [`SynthConfig::corrections`].
    pub coarse_corrections: Option<usize>,
    /// The copy cap, a share of the exemplar's area (`None`: off): the finest level's last
    /// correction pass cuts every verbatim block larger than this (see
    /// `synthesis::cap_breaks`).
    pub copy_cap: Option<f32>,
    /// Coherence bias `kappa` of the correction passes ([`Search::KCoherence`] only; 0 = off): a
    /// candidate that continues no neighbour's block (from a k-coherence set, not a shifted
    /// source; the tree fallback's candidates are not biased) has its score multiplied by
    /// `1 + kappa`, so a texel leaves its block only for a
    /// clearly better match (Ashikhmin 2001; Hertzmann et al. 2001's `kappa`). At the coarser
    /// levels it keeps the patches the finest level inherits large.
    pub coherence_bias: f32,
    /// [`SynthConfig::coherence_bias`] at the finest level, if it differs (there the seams are
    /// placed, and a bias lets them cost more).
    pub finest_coherence_bias: Option<f32>,
    /// The k-coherence tree fallback's ratio at the finest level, if it differs from the
    /// search's (`Some(r)`, `r > 0`; see [`Search::KCoherence`]): fewer tree queries on the level
    /// that has the most texels.
    pub finest_fallback: Option<f32>,
    /// Seam-polishing passes at the finest level, after its correction passes and before the copy
    /// cap's last cuts (0..=16; needs at least one correction pass): each texel is chosen again
    /// among the sources that continue its neighbours' blocks, by the sum of the distances of all
    /// the `N x N` windows it lies in, each to the exemplar window its centre's source names. A
    /// correction pass looks only at the window centred on the texel; polishing moves the seams
    /// where every window across them matches best (the suite: 10-50 % lower energy).
    pub polish: usize,
    /// Scale of the robust (Cauchy) distance the correction passes of the coarser levels match
    /// with ([`Search::KCoherence`] only; 0 = squared L2 there too). A candidate's distance is
    /// `sum over the feature's floats of s ln(1 + d^2 / s)`, `d` a float's difference and `s` this
    /// scale times the level's typical squared distance per float (from its k-coherence sets):
    /// near `d^2` for small differences, growing only logarithmically for large ones. Squared L2
    /// regresses to candidates that are a little wrong everywhere, which are the smooth ones, and
    /// the output lost the exemplar's fine power; a robust distance prefers windows that match most
    /// of the query closely. The finest level stays L2 (the seams' energy is measured there).
    pub robust_scale: f32,
    /// Normal maps only: weight of the detail channel the coarser levels match in place of `z`
    /// (its deviation over the level's slope deviation; see [`crate::appearance`]; 0 = off).
    pub detail_weight: f32,
    /// Seed of the initial state (random exemplar positions, see [`crate::synthesis::random_copies`]).
    pub seed: u64,
    /// Runs whose [`SynthConfig::memory_estimate`] exceeds this many bytes are refused (default:
    /// the one budget of every stage, [`skinkit_maps::limits::default_memory_limit`]).
    pub memory_limit: u64,
    /// How the finest level leaves the growth (what [`SynthConfig::memory_estimate`] counts):
    /// set by [`crate::deliver`] for its streamed files.
    pub delivery: Delivery,
}

/// How a growth's finest level leaves it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Delivery {
    /// Collected into one grid ([`crate::synthesize`]): the whole output and its coordinates
    /// are held, and the quality figures measured on the whole of it.
    #[default]
    Whole,
    /// Handed band by band to the files' writers ([`crate::deliver`]): the map, and the
    /// coordinate map when `coords`.
    Streamed { coords: bool },
}

impl Default for SynthConfig {
    fn default() -> Self {
        SynthConfig {
            width: 256,
            height: 256,
            levels: DEFAULT_LEVELS,
            neighbourhood: 5,
            parent: 1,
            search: Search::KCoherence { k: 2, fallback: Some(DEFAULT_FALLBACK), dims: 8, rerank: 8 },
            coherence: true,
            exemplar_wrap: false,
            start: Start::Upsampled,
            jitter: 0,
            corrections: DEFAULT_CORRECTIONS,
            occurrence_penalty: 0.0,
            finest_penalty: None,
            correction_penalty: None,
            layout_penalty: DEFAULT_LAYOUT_PENALTY,
            coarse_corrections: Some(DEFAULT_COARSE_CORRECTIONS),
            copy_cap: Some(DEFAULT_COPY_CAP),
            coherence_bias: DEFAULT_COHERENCE_BIAS,
            finest_coherence_bias: Some(0.0),
            finest_fallback: Some(DEFAULT_FINEST_FALLBACK),
            polish: DEFAULT_POLISH,
            robust_scale: DEFAULT_ROBUST_SCALE,
            detail_weight: DEFAULT_DETAIL_WEIGHT,
            seed: 0,
            memory_limit: skinkit_maps::limits::default_memory_limit(),
            delivery: Delivery::Whole,
        }
    }
}

/// Pyramid levels of the default (before clamping to the exemplar).
pub const DEFAULT_LEVELS: usize = 5;

/// Correction passes at the finest level of the default (measured by the synthesis suite,
/// `benches/suite.rs`: with a seam-polishing pass after it, a second correction pass changed the
/// energy by under 2 % on every exemplar for 0.2 s more at 512x512).
pub const DEFAULT_CORRECTIONS: usize = 1;

/// Correction passes at the coarser levels of the default (the suite, with polishing: two passes
/// against one lowered the captured cheek's energy from 0.204 to 0.182 and its spectrum distance
/// from 0.109 to 0.083, and every exemplar's energy by 5-40 %; three against two lowered the energy
/// on 13 of 15 exemplars by up to 12 %, the captured cheek's spectrum distance from 0.092 to 0.076
/// and the forehead edges' from 0.348 to 0.285 and 0.109 to 0.076; five were mixed).
pub const DEFAULT_COARSE_CORRECTIONS: usize = 3;

/// Seam-polishing passes of the default at the finest level ([`SynthConfig::polish`]; the suite:
/// a second pass changed the energy by under 2 %).
pub const DEFAULT_POLISH: usize = 1;

/// Default of [`SynthConfig::copy_cap`]: 9 % of the exemplar's area (blocks of up to about 38 x 38
/// texels from a 128 x 128 exemplar). The suite's energy falls as the cap rises (a 6 % cap cost
/// 3-10 %), and the bound is 10 %.
pub const DEFAULT_COPY_CAP: f32 = 0.09;

/// The default's [`SynthConfig::robust_scale`] (the suite, 3 seeds, against squared L2: the
/// captured nose's spectrum distance 0.150 -> 0.091 (the peer's 0.095), the ink blots' 0.066 ->
/// 0.037, lower energy on every normal map (the captured cheek 0.186 -> 0.147); the brick photo's
/// energy rose from 0.31 to 0.57 (the peer's 1.62). Scales 0.25-1 and the finest level's
/// matching are compared in `docs/synthesis-notes.md`.)
pub const DEFAULT_ROBUST_SCALE: f32 = 0.5;

/// The default's [`SynthConfig::layout_penalty`] (the suite, 3 seeds, against none: the slope
/// distribution distance fell on 12 of 15 exemplars (the heightfield nose 0.0127 -> 0.0069, the
/// captured forehead 0.0051 -> 0.0028), the energy on 14 (the ink blots 0.113 -> 0.082; the brick
/// photo's rose 0.57 -> 0.65, the peer's 1.64); `tests/synth/quality.rs`' captured forehead went from
/// 2.1 to 1.1 times the slope distance of two halves of its mold. 0.1 and 0.2 raised the
/// heightfield cheek's spectrum distance over the peer's, and so did 0.05 at the three coarsest
/// levels or at every level.)
pub const DEFAULT_LAYOUT_PENALTY: f32 = 0.05;

/// How many of the coarsest levels [`SynthConfig::layout_penalty`] applies to.
pub const LAYOUT_LEVELS: usize = 2;

/// The default's coarser-level [`SynthConfig::coherence_bias`] (measured by the synthesis suite:
/// 0.25 and 1 scored higher energy on the captured maps than 0.5; none at the finest level).
pub const DEFAULT_COHERENCE_BIAS: f32 = 0.5;

/// The default's [`SynthConfig::detail_weight`] (the suite, 3 seeds, against none: the heightfield
/// nose kept its pores, slope variation 0.68 -> 0.99 and spectrum distance 0.225 -> 0.155; the
/// captured cheek's distribution 0.0054 -> 0.0035; the captured nose's spectrum rose from 0.101 to
/// 0.150. Weights 1 and 2 lost more scores to the peer.)
pub const DEFAULT_DETAIL_WEIGHT: f32 = 1.5;

/// The default's k-coherence fallback ratio at the coarser levels (the suite: 1.5 and 2 cost
/// more time for no lower energy, 4 and 6 raised it on the captured cheek). With the default's
/// robust distance there ([`SynthConfig::robust_scale`]) the tree is not searched: it only
/// applies when the coarser levels match in squared L2.
pub const DEFAULT_FALLBACK: f32 = 3.0;

/// The default's fallback ratio at the finest level: most of the energy of 3 at about half its
/// time (3 there took 4096x2048 from 14 to 24 s).
pub const DEFAULT_FINEST_FALLBACK: f32 = 6.0;

/// The occurrence penalty of [`SynthConfig::scanline`] (the scanline start regresses to flat
/// texels without it; measured in `tests/synth/quality.rs`).
pub const SCANLINE_OCCURRENCE_PENALTY: f32 = 4.0;

/// The occurrence penalty of [`SynthConfig::collapse_retry`], at the coarser levels.
pub const COLLAPSE_RETRY_PENALTY: f32 = 2.0;

/// The occurrence penalty of [`SynthConfig::histogram_retry`], at every level (the suite's
/// heightfield nose: slope-histogram distance 0.0306 -> 0.0096 over 6 seeds, energy 0.209 ->
/// 0.257, still under the peer's 0.317; 1 gave 0.0125).
pub const HISTOGRAM_RETRY_PENALTY: f32 = 0.5;

/// Largest [`SynthConfig::jitter`] accepted, texels.
pub const MAX_JITTER: usize = 16;

/// Most correction passes [`SynthConfig::validate`] accepts.
pub const MAX_CORRECTIONS: usize = 16;

/// Most levels a configuration may ask for (an exemplar within the image limit, 16384 a side,
/// halves at most 12 times before a neighbourhood no longer fits; [`SynthConfig::validate`]
/// clamps to the exemplar's own number with a warning).
pub const MAX_LEVELS: usize = 32;

/// Most tree candidates re-scored per texel ([`Search`]'s `rerank`).
pub const MAX_RERANK: usize = 1024;

/// Largest penalty, weight or robust scale [`SynthConfig::validate`] accepts. They are ratios to
/// a level's typical squared distance, whose useful values are under 10; far above this the
/// weighted distances of a 16-bit exemplar overflow f32.
pub const MAX_WEIGHT: f32 = 1000.0;

/// Side of the interleaving of a correction pass: texels with equal `(x mod s, y mod s)` form
/// one sub-pass, chosen together from the state the previous sub-passes left.
pub const CORRECTION_STRIDE: usize = 3;

/// The side of the next coarser pyramid level.
pub(crate) fn half(side: usize) -> usize {
    side.div_ceil(2)
}

impl SynthConfig {
    /// The default options for a `width x height` output.
    pub fn new(width: usize, height: usize) -> Self {
        SynthConfig { width, height, ..Default::default() }
    }

    /// What the collapse guard grows again with when an output kept less than half of the
    /// exemplar's variation: occurrence penalty [`COLLAPSE_RETRY_PENALTY`] at the coarser levels
    /// (the finest keeps its own). `None` when the coarser levels are penalised that much already.
    pub fn collapse_retry(&self) -> Option<SynthConfig> {
        (self.occurrence_penalty < COLLAPSE_RETRY_PENALTY).then(|| SynthConfig {
            occurrence_penalty: COLLAPSE_RETRY_PENALTY,
            finest_penalty: Some(self.finest_penalty.unwrap_or(self.occurrence_penalty)),
            ..self.clone()
        })
    }

    /// What the histogram guard grows again with when an output's value histogram drifted more than
    /// [`crate::metrics::HISTOGRAM_RATIO`] from the exemplar's: occurrence penalty
    /// [`HISTOGRAM_RETRY_PENALTY`] at every level (Kopf et al. 2007's weighting of texels by their
    /// use, which keeps the output's histogram near the exemplar's). `None` when every level is
    /// penalised at least that much already.
    pub fn histogram_retry(&self) -> Option<SynthConfig> {
        let finest = self.finest_penalty.unwrap_or(self.occurrence_penalty);
        (self.occurrence_penalty.min(finest) < HISTOGRAM_RETRY_PENALTY).then(|| SynthConfig {
            occurrence_penalty: self.occurrence_penalty.max(HISTOGRAM_RETRY_PENALTY),
            finest_penalty: Some(finest.max(HISTOGRAM_RETRY_PENALTY)),
            ..self.clone()
        })
    }

    /// The Wei-Levoy scanline start of earlier versions: 3 levels, the causal pass with k-coherence
    /// (k = 4), one correction pass and occurrence penalty [`SCANLINE_OCCURRENCE_PENALTY`], no
    /// copy cap. Sequential and slower than the default; its copied blocks are small without a cap.
    pub fn scanline(width: usize, height: usize) -> Self {
        SynthConfig {
            width,
            height,
            start: Start::Scanline,
            levels: 3,
            search: Search::K_COHERENCE,
            corrections: 1,
            coarse_corrections: None,
            occurrence_penalty: SCANLINE_OCCURRENCE_PENALTY,
            copy_cap: None,
            parent: 3,
            coherence_bias: 0.0,
            finest_coherence_bias: None,
            finest_fallback: None,
            polish: 0,
            robust_scale: 0.0,
            detail_weight: 0.0,
            layout_penalty: 0.0,
            ..Default::default()
        }
    }

    /// The most pyramid levels an `ew x eh` exemplar allows: its coarsest level must still hold a
    /// full `neighbourhood x neighbourhood` window.
    pub fn max_levels(&self, ew: usize, eh: usize) -> usize {
        skinkit_maps::pyramid::max_levels(ew, eh, self.neighbourhood).max(1)
    }

    /// Checks the options against an `ew x eh` exemplar; returns the options to run with (levels
    /// clamped) and warnings about what was changed.
    ///
    /// # Errors
    /// On an empty output, an even or too small neighbourhood, zero levels, search parameters out
    /// of range, or an exemplar smaller than the neighbourhood.
    pub fn validate(&self, ew: usize, eh: usize) -> Result<(SynthConfig, Vec<String>)> {
        self.check_shape()?;
        self.check_weights()?;
        self.check_search()?;
        if ew < self.neighbourhood || eh < self.neighbourhood || ew > u32::MAX as usize || eh > u32::MAX as usize {
            return Err(Error::ExemplarTooSmall { width: ew, height: eh, n: self.neighbourhood });
        }
        let mut config = self.clone();
        let mut warnings = Vec::new();
        let max = self.max_levels(ew, eh);
        if self.levels > max {
            warnings.push(format!(
                "levels {} clamped to {max}: the {ew}x{eh} exemplar's coarsest level must hold a {n}x{n} neighbourhood",
                self.levels,
                n = self.neighbourhood
            ));
            config.levels = max;
        }
        let estimate = config.memory_estimate(ew, eh);
        if estimate > config.memory_limit {
            return Err(Error::TooLarge {
                width: config.width,
                height: config.height,
                estimate_mib: estimate.div_ceil(1 << 20),
                limit_mib: config.memory_limit >> 20,
            });
        }
        Ok((config, warnings))
    }

    /// The output size, neighbourhood, levels and pass counts.
    fn check_shape(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            let size = format!("{}x{}", self.width, self.height);
            return Err(Error::config("size", size, "the output must be at least 1x1"));
        }
        if self.width > u32::MAX as usize || self.height > u32::MAX as usize {
            let size = format!("{}x{}", self.width, self.height);
            return Err(Error::config("size", size, "sides must fit in 32 bits"));
        }
        if self.neighbourhood < 3 || self.neighbourhood.is_multiple_of(2) {
            return Err(Error::config("neighbourhood", self.neighbourhood, "must be odd and at least 3"));
        }
        if self.parent.is_multiple_of(2) {
            return Err(Error::config("parent", self.parent, "must be odd"));
        }
        if self.levels == 0 {
            return Err(Error::config("levels", 0, "at least one level is needed"));
        }
        if self.corrections > MAX_CORRECTIONS {
            return Err(Error::config("corrections", self.corrections, format!("at most {MAX_CORRECTIONS} passes")));
        }
        Ok(())
    }

    /// The penalties, biases, ratios, the copy cap, the jitter and the pass counts of polish and
    /// the coarse levels.
    fn check_weights(&self) -> Result<()> {
        for (field, weight) in [
            ("occurrence_penalty", self.occurrence_penalty),
            ("layout_penalty", self.layout_penalty),
            ("robust_scale", self.robust_scale),
            ("detail_weight", self.detail_weight),
        ] {
            if !(weight.is_finite() && (0.0..=MAX_WEIGHT).contains(&weight)) {
                return Err(Error::config(field, weight, format!("must be finite, from 0 to {MAX_WEIGHT}")));
            }
        }
        if let Some(p) = self.finest_penalty.filter(|p| !(p.is_finite() && *p >= 0.0)) {
            return Err(Error::config("finest_penalty", p, "must be finite and >= 0"));
        }
        if let Some(p) = self.correction_penalty.filter(|p| !(p.is_finite() && *p >= 0.0)) {
            return Err(Error::config("correction_penalty", p, "must be finite and >= 0"));
        }
        for (field, bias) in
            [("coherence_bias", Some(self.coherence_bias)), ("finest_coherence_bias", self.finest_coherence_bias)]
        {
            if let Some(b) = bias.filter(|b| !(b.is_finite() && *b >= 0.0)) {
                return Err(Error::config(field, b, "must be finite and >= 0"));
            }
        }
        if let Some(r) = self.finest_fallback.filter(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(Error::config("finest_fallback", r, "must be a finite ratio > 0"));
        }
        if let Some(c) = self.copy_cap.filter(|c| !(c.is_finite() && *c > 0.0 && *c <= 1.0)) {
            return Err(Error::config("copy_cap", c, "must be a share of the exemplar's area in (0, 1]"));
        }
        if self.copy_cap.is_some() && (self.width as u64).saturating_mul(self.height as u64) > u32::MAX as u64 {
            let size = format!("{}x{}", self.width, self.height);
            return Err(Error::config("size", size, "with a copy cap, the output must hold under 2^32 texels"));
        }
        if self.jitter > MAX_JITTER {
            return Err(Error::config("jitter", self.jitter, format!("at most {MAX_JITTER} texels")));
        }
        if self.polish > MAX_CORRECTIONS {
            return Err(Error::config("polish", self.polish, format!("at most {MAX_CORRECTIONS} passes")));
        }
        if let Some(c) = self.coarse_corrections.filter(|&c| c > MAX_CORRECTIONS) {
            return Err(Error::config("coarse_corrections", c, format!("at most {MAX_CORRECTIONS} passes")));
        }
        Ok(())
    }

    /// The search mode's parameters.
    fn check_search(&self) -> Result<()> {
        if let Search::KCoherence { k, fallback, .. } = self.search {
            if !(1..=64).contains(&k) {
                return Err(Error::config("k", k, "must be between 1 and 64"));
            }
            if let Some(ratio) = fallback.filter(|r| !(r.is_finite() && *r >= 0.0)) {
                return Err(Error::config("fallback", ratio, "must be a finite ratio >= 0"));
            }
        }
        if let Search::Approximate { dims, rerank } | Search::KCoherence { dims, rerank, .. } = self.search {
            if !(1..=32).contains(&dims) {
                return Err(Error::config("dims", dims, "must be between 1 and 32"));
            }
            if !(1..=MAX_RERANK).contains(&rerank) {
                return Err(Error::config("rerank", rerank, format!("must be between 1 and {MAX_RERANK} candidates")));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_levels_keeps_a_neighbourhood_at_the_top() {
        let c = SynthConfig::default();
        // 32 -> 16 -> 8 -> 4: 4 < 5, so three levels.
        assert_eq!(c.max_levels(32, 32), 3);
        assert_eq!(c.max_levels(5, 100), 1);
        assert_eq!(c.max_levels(9, 9), 2);
        assert_eq!(c.max_levels(10, 10), 2);
    }

    #[test]
    fn validate_rejects_bad_options() {
        let bad = |f: fn(&mut SynthConfig)| {
            let mut c = SynthConfig::new(8, 8);
            f(&mut c);
            c.validate(32, 32).unwrap_err().to_string()
        };
        assert!(bad(|c| c.neighbourhood = 4).contains("neighbourhood = 4"));
        assert!(bad(|c| c.width = 0).contains("0x8"));
        assert!(bad(|c| c.search = Search::Approximate { dims: 33, rerank: 1 }).contains("dims = 33"));
        assert!(bad(|c| c.levels = 0).contains("levels"));
        let kc = |k, fallback| Search::KCoherence { k, fallback, dims: 8, rerank: 8 };
        let mut c = SynthConfig { search: kc(0, None), ..SynthConfig::new(8, 8) };
        assert!(c.validate(32, 32).unwrap_err().to_string().contains("k = 0"));
        c.search = kc(4, Some(f32::NAN));
        assert!(c.validate(32, 32).unwrap_err().to_string().contains("fallback = NaN"));
        c.search = kc(4, Some(2.0));
        assert!(c.validate(32, 32).is_ok());
        assert!(bad(|c| c.corrections = 17).contains("corrections = 17"));
        assert!(bad(|c| c.coarse_corrections = Some(17)).contains("coarse_corrections = 17"));
        assert!(bad(|c| c.layout_penalty = -0.1).contains("layout_penalty = -0.1"));
        assert!(bad(|c| c.layout_penalty = f32::INFINITY).contains("layout_penalty = inf"));
        assert!(bad(|c| c.robust_scale = -1.0).contains("robust_scale"));
        assert!(bad(|c| c.robust_scale = f32::NAN).contains("robust_scale"));
        assert!(bad(|c| c.detail_weight = 1e30).contains("detail_weight"));
        assert!(bad(|c| c.occurrence_penalty = MAX_WEIGHT * 1.01).contains("occurrence_penalty"));
        assert!(bad(|c| c.search = Search::Approximate { dims: 8, rerank: MAX_RERANK + 1 }).contains("rerank"));
        assert!(bad(|c| c.finest_penalty = Some(-1.0)).contains("finest_penalty = -1"));
        assert!(bad(|c| c.coherence_bias = f32::INFINITY).contains("coherence_bias = inf"));
        assert!(bad(|c| c.detail_weight = f32::NAN).contains("detail_weight = NaN"));
        assert!(bad(|c| c.detail_weight = -1.0).contains("detail_weight = -1"));
        assert!(bad(|c| c.finest_coherence_bias = Some(-0.5)).contains("finest_coherence_bias = -0.5"));
        assert!(bad(|c| c.finest_fallback = Some(0.0)).contains("finest_fallback = 0"));
        assert!(bad(|c| c.jitter = 17).contains("jitter = 17"));
        assert!(bad(|c| c.correction_penalty = Some(f32::NAN)).contains("correction_penalty = NaN"));
        for cap in [0.0, -0.1, 1.5, f32::NAN, f32::INFINITY] {
            let c = SynthConfig { copy_cap: Some(cap), ..SynthConfig::new(8, 8) };
            assert!(c.validate(32, 32).unwrap_err().to_string().contains("copy_cap"), "{cap}");
        }
    }
}
