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

/// Floats summed between two checks of [`ExemplarLevel::robust_distance_below`].
const ROBUST_CHUNK: usize = 12;

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

    /// The robust (Cauchy) distance from `query` to candidate `i`: the sum over the floats of
    /// `scale ln(1 + d^2 / scale)`, `d` their difference (`scale` > 0; see
    /// [`crate::SynthConfig::robust_scale`]). Abandoned once the partial sum exceeds `bound` like
    /// [`Self::distance2_below`]: exact (same bits) when it is at most `bound`.
    pub fn robust_distance_below(&self, i: usize, query: &[f32], scale: f32, bound: f32) -> f32 {
        let mut sum = 0.0f32;
        for (a, b) in self.feature(i).chunks(ROBUST_CHUNK).zip(query.chunks(ROBUST_CHUNK)) {
            sum += a.iter().zip(b).map(|(p, q)| scale * ln_1p((p - q) * (p - q) / scale)).sum::<f32>();
            if sum > bound {
                return sum;
            }
        }
        sum
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

/// `ln(1 + x)` for `x >= 0` to about 1e-6 relative (plus the rounding of `1 + x`, about 6e-8
/// absolute), without a library call, so the robust distance's inner loop stays branch-free:
/// `1 + x = m 2^e` with `m` in [1, 2), and `ln m = 2 atanh(t)`, `t = (m - 1) / (m + 1)` in
/// [0, 1/3], by its series to `t^9` (the next term is under 1e-6).
#[inline]
fn ln_1p(x: f32) -> f32 {
    let bits = (1.0 + x).to_bits();
    let e = ((bits >> 23) & 0xff) as i32 - 127;
    let m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000);
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let series = 1.0 + t2 * (1.0 / 3.0 + t2 * (1.0 / 5.0 + t2 * (1.0 / 7.0 + t2 * (1.0 / 9.0))));
    e as f32 * std::f32::consts::LN_2 + 2.0 * t * series
}

/// The better of two scored candidates: smaller distance, then smaller index.
pub(crate) fn better(a: (f32, usize), b: (f32, usize)) -> (f32, usize) {
    if b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)).is_lt() { b } else { a }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The robust distance against a direct f64 sum, and its early exit: exact bits at or under
    /// the bound, some value over it otherwise.
    #[test]
    fn robust_distance_is_the_cauchy_sum_and_exits_early() {
        let texel =
            |x: usize, y: usize| Vec3::new((x * 7 % 5) as f32 * 0.3, (y * 3 % 4) as f32 * 0.2, (x + y) as f32 * 0.05);
        let level = ExemplarLevel::new(Grid::from_fn(9, 9, texel), None, &Neighbourhood::full(3, 1, false), 3, false);
        let query: Vec<f32> = (0..level.dim()).map(|j| (j as f32 * 0.37).sin()).collect();
        let scale = 0.2f32;
        for i in 0..level.len() {
            let exact: f64 = level
                .feature(i)
                .iter()
                .zip(&query)
                .map(|(&p, &q)| scale as f64 * ((p as f64 - q as f64).powi(2) / scale as f64).ln_1p())
                .sum();
            let got = level.robust_distance_below(i, &query, scale, f32::INFINITY);
            assert!((got as f64 - exact).abs() <= 1e-5 * exact, "candidate {i}: {got} against {exact}");
            assert_eq!(level.robust_distance_below(i, &query, scale, got).to_bits(), got.to_bits());
            assert!(level.robust_distance_below(i, &query, scale, 0.5 * got) > 0.5 * got);
        }
    }

    /// The fast `ln(1 + x)` against f64's over 13 decades, and at the exact powers of two.
    #[test]
    fn ln_1p_matches_the_library() {
        let mut x = 1e-7f64;
        while x < 1e6 {
            for v in [x, x * 1.37, x * 2.9, 1.0 / x] {
                let exact = v.ln_1p();
                let got = ln_1p(v as f32) as f64;
                assert!((got - exact).abs() <= 2e-6 * exact + 1.5e-7, "ln_1p({v}) = {got}, exact {exact}");
            }
            x *= 3.1;
        }
        assert_eq!(ln_1p(0.0), 0.0);
        assert!(ln_1p(f32::MAX).is_finite());
        for k in 0..20 {
            let v = (2.0f64).powi(k) - 1.0;
            assert!((ln_1p(v as f32) as f64 - v.ln_1p()).abs() < 1e-5, "2^{k} - 1");
        }
    }
}
