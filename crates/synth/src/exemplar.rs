//! [`ExemplarLevel`]: the candidate texels of one exemplar pyramid level with their feature
//! vectors, and the exhaustive (exact) nearest-neighbourhood search over them.
//!
//! Candidates form a rectangle: the whole level when the exemplar wraps, otherwise the texels
//! whose full `N x N` window lies inside the level (Wei and Levoy 2000). The coarser-level part of
//! a neighbourhood then uses clamped addressing (or wrapped, when the exemplar wraps), so every
//! candidate of a level that passed [`crate::SynthConfig::validate`] has a complete feature.

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::neighbourhood::{LANES, Lanes, Neighbourhood, distance2};
use crate::{Error, Result};

/// Floats summed between two checks of [`ExemplarLevel::distance2_below`] (whole lanes). Each check
/// adds the lanes up, which costs about as much as summing 16 floats: 32 took 512x512 from 0.80 to
/// 0.72 s of processor time against 16 (24 and 48 were slower than 32). The result does not depend
/// on it (partial sums only grow).
const EXIT_CHUNK: usize = 4 * LANES;

/// Candidates per rayon task in the exhaustive scan.
const SCAN_CHUNK: usize = 256;

/// Checks a normal-map exemplar before any work (issue 15, D13): refuses one without a single
/// valid texel, and warns, with the count, when some texels are the invalid marker (they are
/// copied into the output like any other texel).
///
/// # Errors
/// [`Error::NoValidNormals`] when every texel is invalid.
pub(crate) fn check_normal_exemplar(exemplar: &skinkit_maps::NormalMap) -> Result<Option<String>> {
    let (width, height) = exemplar.size();
    let total = width * height;
    let invalid = total - exemplar.valid_count();
    if invalid == total {
        return Err(Error::NoValidNormals { width, height });
    }
    Ok((invalid > 0).then(|| {
        let percent = 100.0 * invalid as f64 / total as f64;
        format!(
            "exemplar: {invalid} of {total} texels ({percent:.1}%) are invalid (zero or non-finite normals); the output copies them as invalid texels"
        )
    }))
}

/// One exemplar level ready for searching.
#[derive(Clone, Debug)]
pub struct ExemplarLevel {
    texels: Grid<Vec3>,
    x0: usize,
    y0: usize,
    cols: usize,
    rows: usize,
    wrap: bool,
    dim: usize,
    features: Vec<f32>,
}

impl ExemplarLevel {
    /// Builds the candidates of `texels` (with `coarser` the next pyramid level, if any) for an
    /// `n x n` neighbourhood shape `nb`; features are computed in parallel.
    pub fn new(texels: Grid<Vec3>, coarser: Option<&Grid<Vec3>>, nb: &Neighbourhood, n: usize, wrap: bool) -> Self {
        let (w, h) = texels.size();
        let r = if wrap { 0 } else { n / 2 };
        let (cols, rows) = (w.saturating_sub(2 * r), h.saturating_sub(2 * r));
        let dim = nb.dim();
        let mut features = vec![0.0f32; cols * rows * dim];
        let fine = |x: isize, y: isize| {
            if wrap { *texels.get_wrapped(x, y) } else { *texels.get_clamped(x, y) }
        };
        let coarse = |x: isize, y: isize| match coarser {
            Some(c) if wrap => *c.get_wrapped(x, y),
            Some(c) => *c.get_clamped(x, y),
            None => Vec3::ZERO,
        };
        features.par_chunks_mut(dim.max(1)).enumerate().for_each(|(i, out)| {
            let (x, y) = (r + i % cols, r + i / cols);
            nb.gather(x as isize, y as isize, fine, coarse, out);
        });
        ExemplarLevel { texels, x0: r, y0: r, cols, rows, wrap, dim, features }
    }

    /// Whether the exemplar wraps (its neighbourhoods read across its border).
    pub fn wraps(&self) -> bool {
        self.wrap
    }

    /// Distance of the candidate rectangle from the level's border (0 when the exemplar wraps).
    pub fn margin(&self) -> usize {
        self.x0
    }

    /// Number of candidates.
    pub fn len(&self) -> usize {
        self.cols * self.rows
    }

    /// True when no texel can be a candidate.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Feature length in floats.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// All features, candidate-major.
    pub fn features(&self) -> &[f32] {
        &self.features
    }

    /// The feature of candidate `i`.
    pub fn feature(&self, i: usize) -> &[f32] {
        &self.features[i * self.dim..(i + 1) * self.dim]
    }

    /// The texels of this level.
    pub fn texels(&self) -> &Grid<Vec3> {
        &self.texels
    }

    /// Exemplar position `[x, y]` of candidate `i`.
    pub fn position(&self, i: usize) -> [u32; 2] {
        [(self.x0 + i % self.cols) as u32, (self.y0 + i / self.cols) as u32]
    }

    /// The texel candidate `i` copies.
    pub fn texel(&self, i: usize) -> Vec3 {
        let [x, y] = self.position(i);
        *self.texels.get(x as usize, y as usize)
    }

    /// The candidate nearest exemplar position `(x, y)` (clamped into the candidate rectangle).
    pub fn nearest_candidate(&self, x: isize, y: isize) -> usize {
        let cx = (x - self.x0 as isize).clamp(0, self.cols as isize - 1) as usize;
        let cy = (y - self.y0 as isize).clamp(0, self.rows as isize - 1) as usize;
        cy * self.cols + cx
    }

    /// The candidate at exemplar position `(x, y)`, wrapped when the exemplar wraps; `None` when the
    /// position is not a candidate.
    pub fn index_of(&self, x: isize, y: isize) -> Option<usize> {
        let (x, y) = if self.wrap {
            (x.rem_euclid(self.cols as isize), y.rem_euclid(self.rows as isize))
        } else {
            (x - self.x0 as isize, y - self.y0 as isize)
        };
        let inside = (0..self.cols as isize).contains(&x) && (0..self.rows as isize).contains(&y);
        inside.then(|| y as usize * self.cols + x as usize)
    }

    /// Squared L2 distance from `query` to candidate `i`'s feature.
    pub fn distance2(&self, i: usize, query: &[f32]) -> f32 {
        distance2(self.feature(i), query)
    }

    /// [`Self::distance2`], abandoned once the partial sum exceeds `bound`: the result is the exact
    /// distance (same bits) when it is at most `bound`, and some value above `bound` otherwise.
    pub fn distance2_below(&self, i: usize, query: &[f32], bound: f32) -> f32 {
        let mut lanes = Lanes::default();
        for (a, b) in self.feature(i).chunks(EXIT_CHUNK).zip(query.chunks(EXIT_CHUNK)) {
            lanes.add(a, b);
            let d = lanes.total();
            if d > bound {
                return d;
            }
        }
        lanes.total()
    }

    /// [`Self::distance2`] over the texel slots of the feature whose `active` entry is true (one
    /// entry per texel, 3 floats each); the others are left out of the sum.
    pub fn distance2_masked(&self, i: usize, query: &[f32], active: &[bool]) -> f32 {
        // The same lanes as `distance2`, so with every slot active the bits are the same.
        let mut lanes = Lanes::default();
        let floats = self.feature(i).iter().zip(query).enumerate();
        for (j, (&p, &q)) in floats.filter(|(j, _)| active[j / 3]) {
            lanes.add_one(j, p, q);
        }
        lanes.total()
    }

    /// The candidate nearest to `query` by exhaustive scan (parallel over candidates; ties go to
    /// the lowest index, so the answer does not depend on the thread count).
    pub fn nearest_exact(&self, query: &[f32]) -> usize {
        self.nearest_by(|i| self.distance2(i, query))
    }

    /// The candidate of smallest `score` by exhaustive scan (parallel; ties go to the lowest
    /// index, so the answer does not depend on the thread count).
    pub fn nearest_by(&self, score: impl Fn(usize) -> f32 + Sync) -> usize {
        (0..self.len())
            .into_par_iter()
            .with_min_len(SCAN_CHUNK)
            .map(|i| (score(i), i))
            .reduce(|| (f32::INFINITY, usize::MAX), better)
            .1
    }
}

/// The better of two scored candidates: smaller distance, then smaller index.
pub(crate) fn better(a: (f32, usize), b: (f32, usize)) -> (f32, usize) {
    if b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)).is_lt() { b } else { a }
}
