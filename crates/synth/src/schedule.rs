//! [`LevelPlan`]: what one pyramid level of a run does, resolved once from [`SynthConfig`].

use crate::config::{LAYOUT_LEVELS, Search, Start, SynthConfig};

/// The upsampled start jitters only the levels from this one up (the finest two keep their
/// coarser level's coordinates exactly; see [`SynthConfig::jitter`]).
pub const JITTER_MIN_LEVEL: usize = 2;

/// The options one pyramid level runs with, resolved from a [`SynthConfig`] by
/// [`SynthConfig::schedule`] (level 0 is the finest). Synthesis builds the schedule once per run
/// and every per-level step (the start, the causal pass, the correction passes, seam polishing,
/// the copy cap) reads its level's plan; no other code resolves a per-level override.
///
/// Which value applies where, and why:
///
/// | field | finest level (0) | layout levels (the [`LAYOUT_LEVELS`] coarsest, not 0) | other coarser levels |
/// |---|---|---|---|
/// | `occurrence_penalty` | `finest_penalty`, else `occurrence_penalty` | max(`occurrence_penalty`, `layout_penalty`) | `occurrence_penalty` |
/// | `correction_penalty` | `correction_penalty`, else this level's `occurrence_penalty` | same | same |
/// | `corrections` | `corrections` | `coarse_corrections`, else `corrections` | same |
/// | `search`'s k-coherence fallback | `finest_fallback`, else the search's | the search's | the search's |
/// | `coherence_bias` | `finest_coherence_bias`, else `coherence_bias` | `coherence_bias` | `coherence_bias` |
/// | `robust_scale` | 0 (squared L2: the seams' energy is measured there) | `robust_scale` | `robust_scale` |
/// | `copy_cap` | `copy_cap` times the exemplar's area (at least 4 texels) | none | none |
/// | `polish` | `polish` | 0 | 0 |
/// | `jitter` | 0 | `jitter` from level [`JITTER_MIN_LEVEL`] up | same |
///
/// The coarse levels lay out which parts of the exemplar the output grows from (hence the layout
/// penalty, more correction passes, the coherence bias that keeps their patches large and the
/// robust distance); the finest level places the seams and holds the most texels (hence its
/// own penalty, a looser fallback ratio, no bias, L2, and the copy cap and polishing).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelPlan {
    /// Pyramid level, 0 the finest.
    pub level: usize,
    /// Whether this is level 0.
    pub is_finest: bool,
    /// Whether this is one of the [`LAYOUT_LEVELS`] coarsest levels (never the finest), where
    /// [`SynthConfig::layout_penalty`] applies.
    pub is_layout_level: bool,
    /// The level's search: [`SynthConfig::search`], with [`SynthConfig::finest_fallback`] as the
    /// k-coherence fallback ratio at the finest level.
    pub search: Search,
    /// The occurrence penalty of the causal pass (and of the correction passes unless
    /// [`SynthConfig::correction_penalty`] is set).
    pub occurrence_penalty: f32,
    /// The occurrence penalty of the correction passes.
    pub correction_penalty: f32,
    /// Correction passes.
    pub corrections: usize,
    /// The k-coherence tree fallback ratio of the causal pass: `search`'s, with the scanline
    /// start only (`None`: no causal tree).
    pub causal_fallback: Option<f32>,
    /// The k-coherence tree fallback ratio of the correction passes: `search`'s, at the levels
    /// that match in squared L2 (`robust_scale` 0) and have correction passes (`None`: no tree).
    pub correction_fallback: Option<f32>,
    /// The coherence bias `kappa` of the correction passes (k-coherence only).
    pub coherence_bias: f32,
    /// The robust distance's scale of the correction passes (0: squared L2).
    pub robust_scale: f32,
    /// The copy cap in texels (the finest level only).
    pub copy_cap: Option<usize>,
    /// Seam-polishing passes (the finest level only; run after the correction passes, so none
    /// without one).
    pub polish: usize,
    /// The upsampled start's jitter in texels ([`Start::Upsampled`] only).
    pub jitter: usize,
}

impl SynthConfig {
    /// The plan of every level of a run from an `ew x eh` exemplar, `[0]` the finest (levels
    /// clamped to [`SynthConfig::max_levels`], as [`SynthConfig::validate`] clamps them).
    pub fn schedule(&self, ew: usize, eh: usize) -> Vec<LevelPlan> {
        let levels = self.levels.min(self.max_levels(ew, eh)).max(1);
        (0..levels).map(|level| self.plan(level, levels, (ew, eh))).collect()
    }

    /// The plan of `level` of a run with `levels` levels from an `ew x eh` exemplar.
    fn plan(&self, level: usize, levels: usize, (ew, eh): (usize, usize)) -> LevelPlan {
        let is_finest = level == 0;
        let is_layout_level = !is_finest && level + LAYOUT_LEVELS >= levels;
        let occurrence_penalty = match (is_finest, is_layout_level) {
            (true, _) => self.finest_penalty.unwrap_or(self.occurrence_penalty),
            (false, true) => self.occurrence_penalty.max(self.layout_penalty),
            (false, false) => self.occurrence_penalty,
        };
        let search = match (self.search, self.finest_fallback) {
            (Search::KCoherence { k, dims, rerank, .. }, Some(ratio)) if is_finest => {
                Search::KCoherence { k, fallback: Some(ratio), dims, rerank }
            }
            (search, _) => search,
        };
        let corrections = if is_finest { None } else { self.coarse_corrections }.unwrap_or(self.corrections);
        let robust_scale = if is_finest { 0.0 } else { self.robust_scale };
        let fallback = match search {
            Search::KCoherence { fallback, .. } => fallback,
            _ => None,
        };
        let copy_cap =
            self.copy_cap.filter(|_| is_finest).map(|share| ((share as f64 * (ew * eh) as f64) as usize).max(4));
        LevelPlan {
            level,
            is_finest,
            is_layout_level,
            search,
            occurrence_penalty,
            correction_penalty: self.correction_penalty.unwrap_or(occurrence_penalty),
            corrections,
            causal_fallback: fallback.filter(|_| self.start == Start::Scanline),
            correction_fallback: fallback.filter(|_| robust_scale == 0.0 && corrections > 0),
            coherence_bias: if is_finest { self.finest_coherence_bias } else { None }.unwrap_or(self.coherence_bias),
            robust_scale,
            copy_cap,
            polish: if is_finest { self.polish } else { 0 },
            jitter: if level >= JITTER_MIN_LEVEL { self.jitter } else { 0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::SCANLINE_OCCURRENCE_PENALTY;

    /// An exemplar large enough for every level asked for.
    const EX: usize = 1024;

    /// The layout penalty reaches the two coarsest levels only, never the finest, and a retry's
    /// higher general penalty wins over it.
    #[test]
    fn each_level_gets_its_occurrence_penalty() {
        let c = SynthConfig { levels: 5, occurrence_penalty: 0.01, layout_penalty: 0.05, ..SynthConfig::default() };
        let at = |c: &SynthConfig| c.schedule(EX, EX).iter().map(|p| p.occurrence_penalty).collect::<Vec<_>>();
        assert_eq!(at(&c), [0.01, 0.01, 0.01, 0.05, 0.05]);
        assert_eq!(at(&SynthConfig { finest_penalty: Some(0.3), ..c.clone() }), [0.3, 0.01, 0.01, 0.05, 0.05]);
        assert_eq!(at(&SynthConfig { levels: 2, ..c.clone() }), [0.01, 0.05]);
        assert_eq!(at(&SynthConfig { levels: 1, ..c.clone() }), [0.01]);
        let retry = c.collapse_retry().expect("the coarser levels are penalised less than the retry");
        assert_eq!(at(&retry), [0.01, 2.0, 2.0, 2.0, 2.0]);
        assert_eq!(at(&SynthConfig::scanline(8, 8)), [SCANLINE_OCCURRENCE_PENALTY; 3]);
        let layout: Vec<bool> = c.schedule(EX, EX).iter().map(|p| p.is_layout_level).collect();
        assert_eq!(layout, [false, false, false, true, true]);
        // Levels are clamped as validation clamps them: a 32x32 exemplar holds three.
        assert_eq!(c.schedule(32, 32).len(), 3);
    }

    /// The default's finest level: its own fallback ratio, no bias, L2, the cap and polishing; the
    /// coarser ones: more corrections, the bias, the robust distance and so no correction tree.
    #[test]
    fn the_default_schedule_splits_finest_and_coarse() {
        let c = SynthConfig::default();
        let plans = c.schedule(128, 128);
        let finest = &plans[0];
        assert!(finest.is_finest && !finest.is_layout_level);
        let Search::KCoherence { fallback, .. } = finest.search else { panic!("k-coherence") };
        assert_eq!(fallback, c.finest_fallback);
        assert_eq!(finest.correction_fallback, c.finest_fallback);
        assert_eq!(finest.causal_fallback, None, "the upsampled start has no causal pass");
        assert_eq!((finest.coherence_bias, finest.robust_scale, finest.polish), (0.0, 0.0, c.polish));
        assert_eq!(finest.copy_cap, Some((0.09f64 * 128.0 * 128.0) as usize));
        for p in &plans[1..] {
            assert_eq!((p.corrections, p.polish, p.copy_cap), (3, 0, None));
            assert_eq!((p.coherence_bias, p.robust_scale, p.correction_fallback), (0.5, 0.5, None));
        }
        let jitter = SynthConfig { jitter: 3, ..c.clone() };
        let jitters: Vec<usize> = jitter.schedule(128, 128).iter().map(|p| p.jitter).collect();
        assert_eq!(jitters, [0, 0, 3, 3, 3]);
    }
}
