//! Correction passes (see [`crate::synthesis`]): every texel of a level chosen again by its full
//! window, in interleaved sub-passes whose result does not depend on the thread count, and the
//! copy cap's cuts in the finest level's last pass.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::config::{CORRECTION_STRIDE, Search, Start, SynthConfig};
use crate::exemplar::{ExemplarLevel, better};
use crate::metrics;
use crate::neighbourhood::Neighbourhood;
use crate::synthesis::{LevelSearch, Occurrence, Scorer, TreeQuery, coherence_candidates, tree_refine};

/// What the correction passes of one level read.
pub(crate) struct CorrectionLevel<'a> {
    pub(crate) coarser: Option<&'a Grid<Vec3>>,
    /// The copy cap of this level in texels (the finest level only; see [`cap_breaks`]).
    pub(crate) copy_cap: Option<usize>,
    /// The full `N x N` (+ coarser `M x M`) shape.
    pub(crate) nb: &'a Neighbourhood,
    pub(crate) search: &'a LevelSearch,
    pub(crate) config: &'a SynthConfig,
}

/// Per-thread buffers of a correction pass.
#[derive(Default)]
struct Scratch {
    query: Vec<f32>,
    sources: Vec<usize>,
    candidates: Vec<usize>,
    seen: Seen,
}

/// Marks of the candidates already scored for the current texel.
#[derive(Default)]
struct Seen {
    marks: Vec<u32>,
    stamp: u32,
}

impl Seen {
    /// A fresh stamp for the next texel, over `len` candidates.
    fn next(&mut self, len: usize) -> u32 {
        if self.marks.len() != len || self.stamp == u32::MAX {
            self.marks.clear();
            self.marks.resize(len, 0);
            self.stamp = 0;
        }
        self.stamp += 1;
        self.stamp
    }
}

impl CorrectionLevel<'_> {
    /// Runs `config.corrections` passes over the level in place. Each pass is split into
    /// `CORRECTION_STRIDE^2` sub-passes by `(x mod s, y mod s)`, in row-major order of the
    /// residues; a sub-pass chooses all its texels in parallel from the state the previous
    /// sub-passes left, then writes them, so the result does not depend on the thread count.
    pub(crate) fn run(&self, out: &mut Grid<Vec3>, coords: &mut Grid<[u32; 2]>, report: &dyn Fn(usize)) {
        let full = self.search.full.as_ref().expect("built for corrections");
        let (w, h) = out.size();
        let s = CORRECTION_STRIDE;
        for pass in 0..self.config.corrections {
            let last = pass + 1 == self.config.corrections;
            let breaks = self.copy_cap.filter(|_| last).map(|cap| cap_breaks(full, coords, cap, self.config.seed));
            for sub in 0..s * s {
                let (ox, oy) = (sub % s, sub / s);
                let rows: Vec<usize> = (oy..h).step_by(s).collect();
                let (read_out, read_coords) = (&*out, &*coords);
                let lambda = self.config.correction_penalty.unwrap_or(self.config.occurrence_penalty);
                let occurrence = Occurrence::of(full, read_coords, lambda);
                let chosen: Vec<Vec<usize>> = rows
                    .par_iter()
                    .map_init(Scratch::default, |scratch, &y| {
                        (ox..w)
                            .step_by(s)
                            .map(|x| {
                                let forbid = breaks.as_ref().is_some_and(|b| b[y * w + x]);
                                self.choose(x as isize, y as isize, read_out, read_coords, &occurrence, forbid, scratch)
                            })
                            .collect()
                    })
                    .collect();
                for (&y, row) in rows.iter().zip(&chosen) {
                    for (x, &best) in (ox..w).step_by(s).zip(row) {
                        *out.get_mut(x, y) = full.texel(best);
                        *coords.get_mut(x, y) = full.position(best);
                    }
                }
                let causal = if self.config.start == Start::Scanline { h } else { 0 };
                report(causal + h * pass + (sub + 1) * h / (s * s));
            }
        }
    }

    /// The candidate texel `(x, y)` copies, chosen by its full neighbourhood in `out`.
    #[allow(clippy::too_many_arguments)]
    fn choose(
        &self,
        x: isize,
        y: isize,
        out: &Grid<Vec3>,
        coords: &Grid<[u32; 2]>,
        occurrence: &Occurrence,
        forbid_own: bool,
        scratch: &mut Scratch,
    ) -> usize {
        let full = self.search.full.as_ref().expect("built for corrections");
        let Scratch { query, sources, candidates, seen } = scratch;
        query.resize(self.nb.dim(), 0.0);
        self.nb.gather(
            x,
            y,
            |sx, sy| *out.get_wrapped(sx, sy),
            |sx, sy| self.coarser.map_or(Vec3::ZERO, |c| *c.get_wrapped(sx, sy)),
            query,
        );
        let [cx, cy] = *coords.get_wrapped(x, y);
        let own = full.index_of(cx as isize, cy as isize);
        let forbidden = own.filter(|_| forbid_own);
        let scorer = Scorer { ex: full, query, active: None, occurrence, own, forbidden };
        let score = |&i: &usize| (scorer.score(i), i);
        candidates.clear();
        match (self.config.search, &self.search.sets) {
            (Search::KCoherence { fallback, .. }, Some(sets)) => {
                sources.clear();
                coherence_candidates(full, self.nb, coords, None, x, y, sources);
                // The texel's current source is usually close to the best: scoring it first makes
                // the early exit cut the others sooner. Each candidate is scored once (`seen`);
                // the minimum does not depend on the order.
                let stamp = seen.next(full.len());
                let mut best = match own {
                    Some(i) if forbid_own => {
                        seen.marks[i] = stamp;
                        (f32::INFINITY, usize::MAX)
                    }
                    Some(i) => {
                        seen.marks[i] = stamp;
                        (scorer.score(i), i)
                    }
                    None => (f32::INFINITY, usize::MAX),
                };
                for &source in sources.iter() {
                    for &j in sets.set(source) {
                        let j = j as usize;
                        if std::mem::replace(&mut seen.marks[j], stamp) != stamp {
                            best = better(best, (scorer.score_below(j, best.0), j));
                        }
                    }
                }
                match (&self.search.full_index, fallback) {
                    _ if best.1 == usize::MAX => scorer.nearest_exact(),
                    (Some(index), Some(ratio)) if best.0 > ratio * sets.typical_full() => {
                        tree_refine(index, &TreeQuery { query, active: None }, best, &score, candidates)
                    }
                    _ => best.1,
                }
            }
            (Search::Approximate { .. }, _) => {
                if self.config.coherence {
                    coherence_candidates(full, self.nb, coords, None, x, y, candidates);
                }
                let coherent = candidates.iter().map(score).fold((f32::INFINITY, usize::MAX), better);
                let index = self.search.full_index.as_ref().expect("built for corrections");
                tree_refine(index, &TreeQuery { query, active: None }, coherent, &score, candidates)
            }
            _ => scorer.nearest_exact(),
        }
    }
}

/// The texels the copy cap re-chooses away from their current source: those of verbatim blocks
/// larger than `cap` texels ([`metrics::copy_blocks`]) that lie on a grid of lines `p` apart
/// (`(p - 1)^2 <= cap`, phase drawn from `seed`). Choosing another source there cuts every such
/// block into pieces of at most `(p - 1)^2` texels; the new source is the best match of the cut
/// texel's whole neighbourhood, so the cut follows the texture as a seam would.
fn cap_breaks(full: &ExemplarLevel, coords: &Grid<[u32; 2]>, cap: usize, seed: u64) -> Vec<bool> {
    let (w, h) = coords.size();
    let blocks = metrics::copy_blocks(coords, full.texels().size(), full.wraps());
    let p = ((cap as f64).sqrt() as usize + 1).max(2);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(2 << 32);
    let (px, py) = (rng.random_range(0..p), rng.random_range(0..p));
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let on_line = (x + px) % p == 0 || (y + py) % p == 0;
            on_line && blocks.size_at(i) as usize > cap
        })
        .collect()
}
