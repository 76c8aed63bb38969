//! What the passes of one output level share (see [`crate::synthesis`]): its neighbourhood
//! shapes, its initial state of random exemplar copies, and the search structures its search
//! mode builds. The causal pass, the correction passes and the level loop of
//! [`crate::synthesis`] all read these; they live here so that each of those depends on this
//! module and none on another (issue 38).

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::Grid;

use crate::config::{Search, SynthConfig};
use crate::exemplar::ExemplarLevel;
use crate::neighbourhood::Neighbourhood;
use crate::schedule::LevelPlan;
use crate::search::{ApproximateIndex, KCoherenceSets, SET_DIMS};

/// The causal (or, `full`, the full) neighbourhood shape of a level.
pub(crate) fn shape(config: &SynthConfig, full: bool, has_parent: bool) -> Neighbourhood {
    let (n, m) = (config.neighbourhood, config.parent);
    if full { Neighbourhood::full(n, m, has_parent) } else { Neighbourhood::new(n, m, has_parent) }
}

/// The initial state of an output level: texels copied from seeded random candidate positions of
/// an exemplar level (`texels`; candidates are the positions at least `margin` from its border),
/// one ChaCha stream per level, and those positions. Its texels are real exemplar texels, pores
/// and furrows included, rather than independent per-channel noise; the causal pass reads them
/// only at the coarsest level, through the rows above the first.
pub fn random_copies(
    texels: &Grid<Vec3>,
    margin: usize,
    width: usize,
    height: usize,
    seed: u64,
    level: usize,
) -> (Grid<Vec3>, Grid<[u32; 2]>) {
    let (ew, eh) = texels.size();
    let (cols, rows) = (ew.saturating_sub(2 * margin).max(1), eh.saturating_sub(2 * margin).max(1));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(level as u64);
    let picks: Vec<[u32; 2]> = (0..width * height)
        .map(|_| {
            let i = rng.random_range(0..cols * rows);
            [(margin + i % cols).min(ew - 1) as u32, (margin + i / cols).min(eh - 1) as u32]
        })
        .collect();
    let copies = picks.iter().map(|&[x, y]| *texels.get(x as usize, y as usize)).collect();
    let grid = Grid::from_vec(width, height, copies).expect("length is width * height");
    (grid, Grid::from_vec(width, height, picks).expect("length is width * height"))
}

/// The search structures of one level: the candidates with full-window features, which every
/// mode needs (the causal pass's texels next to already synthesised wrapped neighbours, the
/// upsampled start's clamping and the correction passes), and what the level's search mode built.
pub(crate) struct LevelSearch {
    pub(crate) full: ExemplarLevel,
    pub(crate) mode: ModeSearch,
}

/// What one search mode builds for a level ([`LevelPlan::search`]).
pub(crate) enum ModeSearch {
    /// [`Search::Exact`]: nothing; every texel scans all candidates.
    Exact,
    /// [`Search::Approximate`]: a PCA kd-tree over causal features and, when the level has
    /// correction passes, one over full features.
    Approximate { index: ApproximateIndex, full_index: Option<ApproximateIndex> },
    /// [`Search::KCoherence`]: the sets, and the tree fallbacks the plan asks for
    /// ([`LevelPlan::causal_fallback`] over causal features, [`LevelPlan::correction_fallback`]
    /// over full features).
    KCoherence { sets: KCoherenceSets, causal: Option<Fallback>, correction: Option<Fallback> },
}

/// A k-coherence tree fallback: a texel whose best candidate's squared distance exceeds `ratio`
/// times the level's typical one also searches `index`.
pub(crate) struct Fallback {
    pub(crate) index: ApproximateIndex,
    pub(crate) ratio: f32,
}

/// The search structures a level needs: the full-window candidates, and what `plan.search`
/// builds (the PCA kd-trees, the k-coherence sets).
pub(crate) fn build_search(
    pyramid: &[Grid<Vec3>],
    plan: &LevelPlan,
    has_parent: bool,
    ex: &ExemplarLevel,
    config: &SynthConfig,
) -> LevelSearch {
    let full = ExemplarLevel::new(
        pyramid[plan.level].clone(),
        pyramid.get(plan.level + 1).filter(|_| has_parent),
        &shape(config, true, has_parent),
        config.neighbourhood,
        config.exemplar_wrap,
    );
    let mode = match plan.search {
        Search::Exact => ModeSearch::Exact,
        Search::Approximate { dims, rerank } => ModeSearch::Approximate {
            index: ApproximateIndex::new(ex, dims, rerank),
            full_index: (plan.corrections > 0).then(|| ApproximateIndex::new(&full, dims, rerank)),
        },
        Search::KCoherence { k, dims, rerank, .. } => {
            // The sets start from a coarser projection of their own (see `search::SET_DIMS`).
            let sets = KCoherenceSets::new(&full, ex, k, SET_DIMS.min(dims));
            let tree = |ex: &ExemplarLevel, ratio| Fallback { index: ApproximateIndex::new(ex, dims, rerank), ratio };
            let causal = plan.causal_fallback.map(|ratio| tree(ex, ratio));
            let correction = plan.correction_fallback.map(|ratio| tree(&full, ratio));
            ModeSearch::KCoherence { sets, causal, correction }
        }
    };
    LevelSearch { full, mode }
}
