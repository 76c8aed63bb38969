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

use crate::config::{Search, SynthConfig};
use crate::exemplar::{ExemplarLevel, better};
use crate::neighbourhood::Neighbourhood;
use crate::scoring::{Occurrence, Scorer, TreeQuery, coherence_candidates, tree_refine};
use crate::synthesis::{LevelSearch, random_copies, shape};

/// The causal scanline pass of one level: every texel, in scanline order, copies the exemplar
/// texel whose causal neighbourhood is nearest. Sequential: each texel's neighbourhood holds the
/// texels chosen just before it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn causal_pass(
    level: usize,
    (w, h): (usize, usize),
    coarser: Option<&Grid<Vec3>>,
    nb: &Neighbourhood,
    ex: &ExemplarLevel,
    search: &LevelSearch,
    config: &SynthConfig,
    report: &dyn Fn(usize),
) -> (Grid<Vec3>, Grid<[u32; 2]>) {
    let full = search.full.as_ref().expect("always built");
    let (mut out, mut coords) = random_copies(ex.texels(), ex.margin(), w, h, config.seed, level);
    let coarsest = coarser.is_none();
    let full_nb = shape(config, true, !coarsest);
    let r = (config.neighbourhood / 2) as isize;
    let mut done = Grid::filled(w, h, false);
    let mut query = vec![0.0f32; nb.dim()];
    let mut full_query = vec![0.0f32; full_nb.dim()];
    let mut active = vec![true; full_nb.dim() / 3];
    let mut tree_active = vec![true; nb.dim() / 3];
    let mut candidates = Vec::new();
    let mut seen = vec![usize::MAX; if search.sets.is_some() { ex.len() } else { 0 }];
    let mut occurrence = Occurrence::new(ex.len(), w * h, config.occurrence_penalty);
    let parent = |sx, sy| coarser.map_or(Vec3::ZERO, |c: &Grid<Vec3>| *c.get_wrapped(sx, sy));
    for y in 0..h {
        for x in 0..w {
            let (xi, yi) = (x as isize, y as isize);
            nb.gather(xi, yi, |sx, sy| *out.get_wrapped(sx, sy), parent, &mut query);
            // Interior texels see exactly their causal window synthesised. Near the edges the
            // wrapped window differs: causal neighbours not synthesised yet are left out, and
            // neighbours past the end of the row or column that are synthesised already (wrapped
            // to the first ones) are added, so the texel is scored with the full window masked
            // by what exists. At the coarsest level the rows above the first wrap to the initial
            // state, which is read (the level's only source of variety).
            let edge = x < r as usize || y < r as usize || x + r as usize >= w || y + r as usize >= h;
            let masked = edge && {
                let known = |&[dx, dy]: &[isize; 2]| *done.get_wrapped(xi + dx, yi + dy) || (coarsest && yi + dy < 0);
                active.iter_mut().zip(full_nb.causal()).for_each(|(slot, o)| *slot = known(o));
                tree_active.iter_mut().zip(nb.causal()).for_each(|(slot, o)| *slot = known(o));
                let causal = |&[dx, dy]: &[isize; 2]| dy < 0 || (dy == 0 && dx < 0);
                full_nb.causal().iter().zip(&active).any(|(o, &on)| on != causal(o))
            };
            let (scorer, shape, tree_query) = if masked {
                full_nb.gather(xi, yi, |sx, sy| *out.get_wrapped(sx, sy), parent, &mut full_query);
                let scorer = Scorer {
                    ex: full,
                    query: &full_query,
                    active: Some(&active[..]),
                    occurrence: &occurrence,
                    own: None,
                    forbidden: &[],
                    robust: 0.0,
                };
                (scorer, &full_nb, TreeQuery { query: &query, active: Some(&tree_active[..]) })
            } else {
                let scorer = Scorer {
                    ex,
                    query: &query,
                    active: None,
                    occurrence: &occurrence,
                    own: None,
                    forbidden: &[],
                    robust: 0.0,
                };
                (scorer, nb, TreeQuery { query: &query, active: None })
            };
            let score = |&i: &usize| (scorer.score(i), i);
            candidates.clear();
            let best = match (&search.index, &search.sets) {
                (_, Some(sets)) => {
                    coherence_candidates(ex, shape, &coords, Some(&done), xi, yi, &mut candidates);
                    // Each candidate is scored once per texel (`seen` holds the last texel that
                    // scored it); the result does not depend on the order, only the work does.
                    let texel = y * w + x;
                    let mut best = (f32::INFINITY, usize::MAX);
                    for &source in &candidates {
                        for &j in sets.set(source) {
                            let j = j as usize;
                            if std::mem::replace(&mut seen[j], texel) != texel {
                                best = better(best, (scorer.score_below(j, best.0), j));
                            }
                        }
                    }
                    let Search::KCoherence { fallback, .. } = config.search else { unreachable!() };
                    let typical = if masked { sets.typical_full() } else { sets.typical() };
                    match (&search.index, fallback) {
                        _ if best.1 == usize::MAX => scorer.nearest_exact(),
                        (Some(index), Some(ratio)) if best.0 > ratio * typical => {
                            tree_refine(index, &tree_query, best, &score, &mut candidates)
                        }
                        _ => best.1,
                    }
                }
                (None, None) => scorer.nearest_exact(),
                (Some(index), None) => {
                    if config.coherence {
                        coherence_candidates(ex, shape, &coords, Some(&done), xi, yi, &mut candidates);
                    }
                    let coherent = candidates.iter().map(score).fold((f32::INFINITY, usize::MAX), better);
                    tree_refine(index, &tree_query, coherent, &score, &mut candidates)
                }
            };
            *out.get_mut(x, y) = ex.texel(best);
            *coords.get_mut(x, y) = ex.position(best);
            *done.get_mut(x, y) = true;
            occurrence.add(best);
        }
        report(y + 1);
    }
    (out, coords)
}
