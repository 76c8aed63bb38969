//! How a texel scores exemplar candidates, shared by the causal pass and the correction passes:
//! the distance over the active part of its feature, the occurrence penalty, kd-tree refinement
//! and coherence candidates.
//!
//! Occurrence penalty ([`crate::SynthConfig::occurrence_penalty`]; Kopf et al. 2007, "Solid texture
//! synthesis from 2D exemplars", section 4.3): greedy L2 search regresses to the most typical,
//! nearly flat texels (before it, a few were copied 250-390 times where 4 was the share, and the
//! outputs kept 35-65 % of the exemplar's rms slope). A candidate's squared distance is multiplied
//! by `1 + lambda * max(0, count - share)`, with `count` the copies of its texel at this level so
//! far (scanline order in the causal pass; the state at the start of each correction sub-pass,
//! not counting the texel itself, so the result stays independent of the thread count).

use skinkit_maps::Grid;

use crate::exemplar::{ExemplarLevel, better};
use crate::neighbourhood::Neighbourhood;
use crate::search::ApproximateIndex;

/// What a kd-tree is queried with: a causal feature, and which of its texel slots hold
/// synthesised texels (`None`: all).
pub(crate) struct TreeQuery<'a> {
    pub(crate) query: &'a [f32],
    pub(crate) active: Option<&'a [bool]>,
}

/// The occurrence (histogram) penalty of Kopf et al. 2007, section 4.3: a candidate whose
/// exemplar texel the level already copies more often than its share has its squared distance
/// multiplied by `1 + lambda * max(0, count - expected)`.
pub(crate) struct Occurrence {
    counts: Vec<u32>,
    /// Copies per candidate if every candidate were used equally: output texels / candidates.
    expected: f32,
    lambda: f32,
}

impl Occurrence {
    /// Zero counts over `candidates`, for a level of `texels` output texels.
    pub(crate) fn new(candidates: usize, texels: usize, lambda: f32) -> Self {
        let counts = vec![0; if lambda > 0.0 { candidates } else { 0 }];
        Occurrence { counts, expected: texels as f32 / candidates.max(1) as f32, lambda }
    }

    /// The counts of the sources in `coords` (positions that are not candidates are not counted).
    pub(crate) fn of(full: &ExemplarLevel, coords: &Grid<[u32; 2]>, lambda: f32) -> Self {
        let mut o = Occurrence::new(full.len(), coords.len(), lambda);
        if lambda > 0.0 {
            for &[x, y] in coords.as_slice() {
                if let Some(i) = full.index_of(x as isize, y as isize) {
                    o.counts[i] += 1;
                }
            }
        }
        o
    }

    /// Counts one more copy of candidate `i`.
    pub(crate) fn add(&mut self, i: usize) {
        if let Some(c) = self.counts.get_mut(i) {
            *c += 1;
        }
    }

    /// The factor on candidate `i`'s squared distance; `own` (a texel's current source in a
    /// correction pass) is counted without the texel itself.
    pub(crate) fn factor(&self, i: usize, own: Option<usize>) -> f32 {
        if self.lambda <= 0.0 {
            return 1.0;
        }
        let count = self.counts[i] - u32::from(own == Some(i));
        1.0 + self.lambda * (count as f32 - self.expected).max(0.0)
    }
}

/// How one texel scores candidates: squared distance over the active part of its feature (all of
/// it unless `active` says otherwise), times the occurrence factor.
pub(crate) struct Scorer<'a> {
    pub(crate) ex: &'a ExemplarLevel,
    pub(crate) query: &'a [f32],
    /// Per texel slot of the feature, whether it counts (`None`: every slot).
    pub(crate) active: Option<&'a [bool]>,
    pub(crate) occurrence: &'a Occurrence,
    pub(crate) own: Option<usize>,
    /// Candidates the texel may not take (where the copy cap cuts: its current source and every
    /// source that would continue a neighbour's block, see `correction::cut_forbidden`).
    pub(crate) forbidden: &'a [usize],
    /// The robust distance's scale per float ([`ExemplarLevel::robust_distance_below`]); 0:
    /// squared L2. Unmasked queries only.
    pub(crate) robust: f32,
}

impl Scorer<'_> {
    /// The score of candidate `i`.
    pub(crate) fn score(&self, i: usize) -> f32 {
        if self.forbidden.contains(&i) {
            return f32::INFINITY;
        }
        let d = match self.active {
            Some(active) => self.ex.distance2_masked(i, self.query, active),
            None if self.robust > 0.0 => self.ex.robust_distance_below(i, self.query, self.robust, f32::INFINITY),
            None => self.ex.distance2(i, self.query),
        };
        d * self.occurrence.factor(i, self.own)
    }

    /// The score of candidate `i` when it is at most `best`, `f32::INFINITY` otherwise (the
    /// distance is abandoned early once it cannot win).
    pub(crate) fn score_below(&self, i: usize, best: f32) -> f32 {
        if self.forbidden.contains(&i) {
            return f32::INFINITY;
        }
        let f = self.occurrence.factor(i, self.own);
        let bound = best / f;
        let d = match self.active {
            Some(active) => self.ex.distance2_masked(i, self.query, active),
            None if self.robust > 0.0 => self.ex.robust_distance_below(i, self.query, self.robust, bound),
            None => self.ex.distance2_below(i, self.query, bound),
        };
        if d > bound { f32::INFINITY } else { d * f }
    }

    /// The best candidate of the level by exhaustive scan.
    pub(crate) fn nearest_exact(&self) -> usize {
        self.ex.nearest_by(|i| self.score(i))
    }
}

/// The best of `best` and the tree's candidates for the scorer's query. Tree candidates farther
/// than `best` (in projected distance, a lower bound of the full one, which the occurrence factor
/// only raises) cannot win, so the tree is searched only within that radius; the margin covers
/// the rounding of the f32 projection. A masked query has its left-out slots set to the
/// projection's mean and no radius (the projected distance no longer bounds the masked one).
pub(crate) fn tree_refine(
    index: &ApproximateIndex,
    tree_query: &TreeQuery,
    best: (f32, usize),
    score: &dyn Fn(&usize) -> (f32, usize),
    candidates: &mut Vec<usize>,
) -> usize {
    let first = candidates.len();
    match tree_query.active {
        None => index.candidates(tree_query.query, best.0 * (1.0 + 1e-4) + 1e-6, candidates),
        Some(active) => {
            let mut query = tree_query.query.to_vec();
            let mean = index.pca().mean();
            for ((slot, m), &on) in query.chunks_exact_mut(3).zip(mean.chunks_exact(3)).zip(active) {
                if !on {
                    slot.copy_from_slice(m);
                }
            }
            index.candidates(&query, f32::INFINITY, candidates);
        }
    }
    candidates[first..].iter().map(score).fold(best, better).1
}

/// Ashikhmin (2001) candidates: for each already synthesised neighbour at offset `(dx, dy)` in `nb`
/// (every neighbour when `done` is `None`), the exemplar texel at its source shifted back by
/// `(dx, dy)`.
pub(crate) fn coherence_candidates(
    ex: &ExemplarLevel,
    nb: &Neighbourhood,
    coords: &Grid<[u32; 2]>,
    done: Option<&Grid<bool>>,
    x: isize,
    y: isize,
    out: &mut Vec<usize>,
) {
    for &[dx, dy] in nb.causal() {
        if done.is_some_and(|d| !*d.get_wrapped(x + dx, y + dy)) {
            continue;
        }
        let [sx, sy] = *coords.get_wrapped(x + dx, y + dy);
        if let Some(i) = ex.index_of(sx as isize - dx, sy as isize - dy) {
            out.push(i);
        }
    }
}
