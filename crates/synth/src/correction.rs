//! Correction passes (see [`crate::synthesis`]): every texel of a level chosen again by its full
//! window, in interleaved sub-passes whose result does not depend on the thread count, and the
//! copy cap's cuts in the finest level's last pass.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::Grid;

use crate::band::Window;
use crate::config::{CORRECTION_STRIDE, Start, SynthConfig};
use crate::exemplar::{ExemplarLevel, better};
use crate::interleave::sub_pass;
use crate::level::{Fallback, LevelSearch, ModeSearch};
use crate::metrics;
use crate::neighbourhood::Neighbourhood;
use crate::schedule::LevelPlan;
use crate::scoring::{Occurrence, Scorer, TreeQuery, coherence_candidates, tree_refine};
use crate::search::KCoherenceSets;

/// What the correction passes of one level read.
pub(crate) struct CorrectionLevel<'a> {
    pub(crate) coarser: Option<&'a Grid<Vec3>>,
    /// The level's passes, penalty, bias, robust scale, copy cap (see [`cap_breaks`]) and
    /// seam-polishing passes ([`crate::polish`]).
    pub(crate) plan: &'a LevelPlan,
    /// The full `N x N` (+ coarser `M x M`) shape.
    pub(crate) nb: &'a Neighbourhood,
    pub(crate) search: &'a LevelSearch,
    pub(crate) config: &'a SynthConfig,
    /// Where the grid lies in its level and which of its rows may change ([`Window::whole`] for
    /// a whole level).
    pub(crate) window: &'a Window,
}

/// The most times the copy cap's cut is repeated after the last pass ([`CorrectionLevel::run`]).
const CAP_ROUNDS: usize = 4;

/// Per-thread buffers of a correction pass.
#[derive(Default)]
struct Scratch {
    query: Vec<f32>,
    sources: Vec<usize>,
    candidates: Vec<usize>,
    forbidden: Vec<usize>,
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
    /// Runs `plan.corrections` passes over the level in place. Each pass is split into
    /// `CORRECTION_STRIDE^2` sub-passes by `(x mod s, y mod s)`, in row-major order of the
    /// residues; a sub-pass chooses all its texels in parallel from the state the previous
    /// sub-passes left, then writes them, so the result does not depend on the thread count.
    ///
    /// With a copy cap, the last pass cuts the blocks that were too large when it began; blocks
    /// under the cap can still merge during that pass (the grass photo as height reached 10.8 %
    /// of its exemplar under a 6 % cap), so the cut is then repeated, re-choosing only the cut
    /// texels, until no block exceeds the cap or [`CAP_ROUNDS`] rounds have run.
    pub(crate) fn run(&self, out: &mut Grid<Vec3>, coords: &mut Grid<[u32; 2]>, report: &dyn Fn(usize)) {
        let (full, plan) = (&self.search.full, self.plan);
        let (s, h) = (CORRECTION_STRIDE, out.size().1);
        for pass in 0..plan.corrections {
            let last = pass + 1 == plan.corrections;
            let breaks =
                plan.copy_cap.filter(|_| last).map(|cap| cap_breaks(full, coords, cap, self.config.seed, self.window));
            let causal = if self.config.start == Start::Scanline { h } else { 0 };
            self.pass(out, coords, breaks.as_deref(), false, &|sub| {
                report(causal + h * pass + (sub + 1) * h / (s * s))
            });
        }
        if plan.polish > 0 {
            let active = &self.window.active;
            crate::polish::polish(full, self.config.neighbourhood, plan.copy_cap, (out, coords, active), plan.polish);
        }
        let Some(cap) = plan.copy_cap.filter(|_| plan.corrections > 0) else { return };
        for _ in 0..CAP_ROUNDS {
            let breaks = cap_breaks(full, coords, cap, self.config.seed, self.window);
            if !breaks.contains(&true) {
                break;
            }
            self.pass(out, coords, Some(&breaks), true, &|_| {});
        }
    }

    /// One correction pass in its sub-passes; with `only_cut`, only the texels `breaks` marks are
    /// chosen again (each away from its current source), the others keep theirs.
    fn pass(
        &self,
        out: &mut Grid<Vec3>,
        coords: &mut Grid<[u32; 2]>,
        breaks: Option<&[bool]>,
        only_cut: bool,
        report: &dyn Fn(usize),
    ) {
        let full = &self.search.full;
        let w = out.width();
        let s = CORRECTION_STRIDE;
        let lambda = self.plan.correction_penalty;
        for sub in 0..s * s {
            let occurrence = Occurrence::of(full, coords, lambda);
            sub_pass(
                full,
                out,
                coords,
                (sub, &self.window.active),
                |x, y, read_out, read_coords, scratch: &mut Scratch| {
                    let forbid = breaks.is_some_and(|b| b[y * w + x]);
                    (forbid || !only_cut).then(|| {
                        self.choose(x as isize, y as isize, read_out, read_coords, &occurrence, forbid, scratch)
                    })
                },
            );
            report(sub);
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
        let full = &self.search.full;
        let Scratch { query, sources, candidates, forbidden, seen } = scratch;
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
        forbidden.clear();
        if forbid_own {
            cut_forbidden(full, coords, x, y, forbidden);
        }
        let robust = self.robust_per_float();
        let scorer = Scorer { ex: full, query, active: None, occurrence, own, forbidden, robust };
        let score = |&i: &usize| (scorer.score(i), i);
        candidates.clear();
        match &self.search.mode {
            ModeSearch::KCoherence { sets, correction, .. } => {
                let best = self.coherent_best(x, y, coords, sets, &scorer, forbid_own, sources, seen);
                match correction {
                    _ if best.1 == usize::MAX => scorer.nearest_exact(),
                    // The tree searches within an L2 radius, which a robust score does not give
                    // (the plan builds no tree where the level matches robustly).
                    Some(Fallback { index, ratio }) if robust == 0.0 && best.0 > ratio * sets.typical_full() => {
                        tree_refine(index, &TreeQuery { query, active: None }, best, &score, candidates)
                    }
                    _ => best.1,
                }
            }
            // The full-feature tree is built for every level with correction passes.
            ModeSearch::Approximate { full_index: Some(index), .. } => {
                if self.config.coherence {
                    coherence_candidates(full, self.nb, coords, None, x, y, candidates);
                }
                let coherent = candidates.iter().map(score).fold((f32::INFINITY, usize::MAX), better);
                tree_refine(index, &TreeQuery { query, active: None }, coherent, &score, candidates)
            }
            ModeSearch::Approximate { full_index: None, .. } | ModeSearch::Exact => scorer.nearest_exact(),
        }
    }

    /// The robust distance's scale per float: the level's typical squared distance per float,
    /// times the plan's scale. A level whose typical distance is 0 (most windows have an exact
    /// twin, as in a mostly flat exemplar) has no scale to measure and matches in L2 (0).
    fn robust_per_float(&self) -> f32 {
        match &self.search.mode {
            ModeSearch::KCoherence { sets, .. } if self.plan.robust_scale > 0.0 && sets.typical_full() > 0.0 => {
                self.plan.robust_scale * sets.typical_full() / self.search.full.dim() as f32
            }
            _ => 0.0,
        }
    }

    /// The best k-coherence candidate of texel `(x, y)` and its score: its own source (unless the
    /// copy cap cuts it), the sources its neighbours' blocks continue, then the rest of their
    /// sets, biased by the plan's coherence bias; `(INFINITY, usize::MAX)` when there is none.
    #[allow(clippy::too_many_arguments)]
    fn coherent_best(
        &self,
        x: isize,
        y: isize,
        coords: &Grid<[u32; 2]>,
        sets: &KCoherenceSets,
        scorer: &Scorer,
        forbid_own: bool,
        sources: &mut Vec<usize>,
        seen: &mut Seen,
    ) -> (f32, usize) {
        let (full, own) = (&self.search.full, scorer.own);
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
        // Shifted sources first (they continue a neighbour's block), then the rest of
        // their sets, biased: a candidate counts as coherent if any neighbour makes it so.
        for &j in sources.iter() {
            if std::mem::replace(&mut seen.marks[j], stamp) != stamp {
                best = better(best, (scorer.score_below(j, best.0), j));
            }
        }
        let bias = 1.0 + self.plan.coherence_bias;
        for &source in sources.iter() {
            for &j in &sets.set(source)[1..] {
                let j = j as usize;
                if std::mem::replace(&mut seen.marks[j], stamp) != stamp {
                    best = better(best, (scorer.score_below(j, best.0 / bias) * bias, j));
                }
            }
        }
        best
    }
}

/// The sources a texel the copy cap cuts may not take: its own, and each one that would continue
/// a 4-neighbour's block (the neighbour's source less their offset). The cut texel then starts a
/// block of its own, so no block crosses a cut line (otherwise a cut texel between two blocks of
/// one offset could join them again).
fn cut_forbidden(full: &ExemplarLevel, coords: &Grid<[u32; 2]>, x: isize, y: isize, out: &mut Vec<usize>) {
    let [cx, cy] = *coords.get_wrapped(x, y);
    out.extend(full.index_of(cx as isize, cy as isize));
    for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
        let [nx, ny] = *coords.get_wrapped(x + dx, y + dy);
        out.extend(full.index_of(nx as isize - dx, ny as isize - dy));
    }
}

/// The texels the copy cap re-chooses away from their current source: those of verbatim blocks
/// larger than `cap` texels ([`metrics::copy_blocks`]) that lie on a grid of lines `p` apart
/// (`(p - 1)^2 <= cap`, phase drawn from `seed`, plus row and column 0). Choosing another source
/// there cuts every such block into pieces of at most `(p - 1)^2` texels; the new source is the
/// best match of the cut texel's whole neighbourhood, so the cut follows the texture as a seam
/// would. The lines are drawn in the level's rows (`window`), so a band's lie where the whole
/// level's would.
fn cap_breaks(full: &ExemplarLevel, coords: &Grid<[u32; 2]>, cap: usize, seed: u64, window: &Window) -> Vec<bool> {
    let (w, h) = coords.size();
    let blocks = metrics::copy_blocks(coords, full.texels().size(), full.wraps());
    let p = ((cap as f64).sqrt() as usize + 1).max(2);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(2 << 32);
    let (px, py) = (rng.random_range(0..p), rng.random_range(0..p));
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, window.level_row(i / w));
            // Row and column 0 are lines too: the output wraps, and where its side is not a
            // multiple of p the cell across the wrap would be up to 2 p - 2 texels wide (a 3 %
            // cap let a 201-texel block through there).
            let on_line = (x + px) % p == 0 || (y + py) % p == 0 || x == 0 || y == 0;
            on_line && blocks.size_at(i) as usize > cap
        })
        .collect()
}
