//! The causal scanline pass of the Wei-Levoy start ([`crate::Start::Scanline`]).
//!
//! Edges of the causal pass: an interior texel sees exactly its causal window synthesised. A texel
//! in the first or last `N / 2` rows or columns is scored instead with its full `N x N` window
//! (against full-window exemplar features) restricted to the neighbours already synthesised at
//! this level: wrapped neighbours not yet synthesised are left out (they used to be initial noise,
//! which put a seam at the wrap-around column), wrapped ones synthesised already (the first
//! columns and rows, seen from the last) are added. At the coarsest level the rows above the first
//! read the initial copies, the level's only source of variety.

use glam::Vec3;
use skinkit_maps::Grid;

use crate::config::SynthConfig;
use crate::exemplar::{ExemplarLevel, better};
use crate::level::{Fallback, LevelSearch, ModeSearch, random_copies, shape};
use crate::neighbourhood::Neighbourhood;
use crate::schedule::LevelPlan;
use crate::scoring::{Occurrence, Scorer, TreeQuery, coherence_candidates, tree_refine};

/// The causal scanline pass of one level: every texel, in scanline order, copies the exemplar
/// texel whose causal neighbourhood is nearest. Sequential: each texel's neighbourhood holds the
/// texels chosen just before it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn causal_pass(
    plan: &LevelPlan,
    (w, h): (usize, usize),
    coarser: Option<&Grid<Vec3>>,
    nb: &Neighbourhood,
    ex: &ExemplarLevel,
    search: &LevelSearch,
    config: &SynthConfig,
    report: &dyn Fn(usize),
) -> (Grid<Vec3>, Grid<[u32; 2]>) {
    let full = &search.full;
    let (mut out, mut coords) = random_copies(ex.texels(), ex.margin(), w, h, config.seed, plan.level);
    let coarsest = coarser.is_none();
    let full_nb = shape(config, true, !coarsest);
    let r = (config.neighbourhood / 2) as isize;
    let mut done = Grid::filled(w, h, false);
    let mut query = vec![0.0f32; nb.dim()];
    let mut full_query = vec![0.0f32; full_nb.dim()];
    let mut active = vec![true; full_nb.dim() / 3];
    let mut tree_active = vec![true; nb.dim() / 3];
    let mut candidates = Vec::new();
    let kcoherence = matches!(search.mode, ModeSearch::KCoherence { .. });
    let mut seen = vec![usize::MAX; if kcoherence { ex.len() } else { 0 }];
    let mut occurrence = Occurrence::new(ex.len(), w * h, plan.occurrence_penalty);
    let parent = |sx, sy| coarser.map_or(Vec3::ZERO, |c: &Grid<Vec3>| *c.get_wrapped(sx, sy));
    for y in 0..h {
        for x in 0..w {
            let (xi, yi) = (x as isize, y as isize);
            nb.gather(xi, yi, |sx, sy| *out.get_wrapped(sx, sy), parent, &mut query);
            let edge = x < r as usize || y < r as usize || x + r as usize >= w || y + r as usize >= h;
            let masked = edge && mask(&done, coarsest, &full_nb, nb, (xi, yi), &mut active, &mut tree_active);
            let (e, q, a, shape, tree) = if masked {
                full_nb.gather(xi, yi, |sx, sy| *out.get_wrapped(sx, sy), parent, &mut full_query);
                (full, &full_query[..], Some(&active[..]), &full_nb, Some(&tree_active[..]))
            } else {
                (ex, &query[..], None, nb, None)
            };
            let scorer =
                Scorer { ex: e, query: q, active: a, occurrence: &occurrence, own: None, forbidden: &[], robust: 0.0 };
            let texel = Texel {
                x: xi,
                y: yi,
                index: y * w + x,
                masked,
                shape,
                tree: TreeQuery { query: &query, active: tree },
            };
            let best =
                choose(search, ex, &scorer, &texel, (&coords, &done), config.coherence, &mut candidates, &mut seen);
            *out.get_mut(x, y) = ex.texel(best);
            *coords.get_mut(x, y) = ex.position(best);
            *done.get_mut(x, y) = true;
            occurrence.add(best);
        }
        report(y + 1);
    }
    (out, coords)
}

/// Whether texel `(x, y)` near an edge is scored with its full window masked (and, if so, which
/// slots of the full and the causal shape are known, in `active` and `tree_active`). Interior
/// texels see exactly their causal window synthesised. Near the edges the wrapped window differs:
/// causal neighbours not synthesised yet are left out, and neighbours past the end of the row or
/// column that are synthesised already (wrapped to the first ones) are added. At the coarsest level
/// the rows above the first wrap to the initial state, which is read (the level's only source of
/// variety).
fn mask(
    done: &Grid<bool>,
    coarsest: bool,
    full_nb: &Neighbourhood,
    nb: &Neighbourhood,
    (x, y): (isize, isize),
    active: &mut [bool],
    tree_active: &mut [bool],
) -> bool {
    let known = |&[dx, dy]: &[isize; 2]| *done.get_wrapped(x + dx, y + dy) || (coarsest && y + dy < 0);
    active.iter_mut().zip(full_nb.causal()).for_each(|(slot, o)| *slot = known(o));
    tree_active.iter_mut().zip(nb.causal()).for_each(|(slot, o)| *slot = known(o));
    let causal = |&[dx, dy]: &[isize; 2]| dy < 0 || (dy == 0 && dx < 0);
    full_nb.causal().iter().zip(&*active).any(|(o, &on)| on != causal(o))
}

/// The texel a causal choice is for: its position and index, whether its window is masked, the
/// shape its candidates are gathered with, and its kd-tree query.
struct Texel<'a> {
    x: isize,
    y: isize,
    index: usize,
    masked: bool,
    shape: &'a Neighbourhood,
    tree: TreeQuery<'a>,
}

/// The candidate a causal texel copies, by the level's search mode.
#[allow(clippy::too_many_arguments)]
fn choose(
    search: &LevelSearch,
    ex: &ExemplarLevel,
    scorer: &Scorer,
    t: &Texel,
    (coords, done): (&Grid<[u32; 2]>, &Grid<bool>),
    coherence: bool,
    candidates: &mut Vec<usize>,
    seen: &mut [usize],
) -> usize {
    let score = |&i: &usize| (scorer.score(i), i);
    candidates.clear();
    match &search.mode {
        ModeSearch::KCoherence { sets, causal, .. } => {
            coherence_candidates(ex, t.shape, coords, Some(done), t.x, t.y, candidates);
            // Each candidate is scored once per texel (`seen` holds the last texel that scored
            // it); the result does not depend on the order, only the work does.
            let mut best = (f32::INFINITY, usize::MAX);
            for &source in candidates.iter() {
                for &j in sets.set(source) {
                    let j = j as usize;
                    if std::mem::replace(&mut seen[j], t.index) != t.index {
                        best = better(best, (scorer.score_below(j, best.0), j));
                    }
                }
            }
            let typical = if t.masked { sets.typical_full() } else { sets.typical() };
            match causal {
                _ if best.1 == usize::MAX => scorer.nearest_exact(),
                Some(Fallback { index, ratio }) if best.0 > ratio * typical => {
                    tree_refine(index, &t.tree, best, &score, candidates)
                }
                _ => best.1,
            }
        }
        ModeSearch::Exact => scorer.nearest_exact(),
        ModeSearch::Approximate { index, .. } => {
            if coherence {
                coherence_candidates(ex, t.shape, coords, Some(done), t.x, t.y, candidates);
            }
            let coherent = candidates.iter().map(score).fold((f32::INFINITY, usize::MAX), better);
            tree_refine(index, &t.tree, coherent, &score, candidates)
        }
    }
}
