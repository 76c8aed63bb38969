//! Approximate nearest-neighbourhood search: PCA of an exemplar level's features to a few
//! dimensions (nalgebra `SymmetricEigen` of the covariance, in f64) and a kiddo kd-tree there.
//!
//! Raw neighbourhoods have about 60 dimensions, where an exact kd-tree is no faster than a linear
//! scan (docs/references.md, synthesis); the projected tree returns a few candidates which the caller
//! re-scores in the full space.
//!
//! [`KCoherenceSets`] (Tong et al. 2002, "Synthesis of bidirectional texture functions on arbitrary
//! surfaces") precompute, per exemplar candidate, the candidates with the most similar full
//! neighbourhoods, so synthesis can draw its candidates from coherent sources alone.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

use crate::exemplar::ExemplarLevel;

/// Number of partial covariances (summed in order afterwards); their row ranges depend only on the
/// candidate count, so the bits never depend on the thread count, and memory stays bounded.
const COV_PARTS: usize = 32;

/// The fewest kd-tree candidates re-scored per k-coherence set (the pool is `max(2 k, SET_POOL)`).
/// The synthesis suite measured 4 against 16 with the default's `k` = 2: the same energy within
/// 1-5 % either way on its 15 exemplars, and the finest level's sets of a 128x128 exemplar built in
/// 0.13 s instead of 0.28 s (the kd-tree search is most of it).
const SET_POOL: usize = 4;

/// A linear projection onto the leading principal axes.
#[derive(Clone, Debug)]
pub struct Pca {
    mean: Vec<f32>,
    /// `dims` rows of length `dim`, by decreasing eigenvalue.
    axes: Vec<f32>,
    dim: usize,
    dims: usize,
    /// Eigenvalues (variances) of the kept axes.
    pub variances: Vec<f64>,
}

impl Pca {
    /// Fits `dims` axes (at most the feature length) to the candidate-major `features`.
    pub fn fit(features: &[f32], dim: usize, dims: usize) -> Self {
        let n = features.len() / dim.max(1);
        let dims = dims.min(dim);
        let rows_per_part = n.div_ceil(COV_PARTS).max(1);
        let chunks: Vec<&[f32]> = features.chunks(rows_per_part * dim.max(1)).collect();
        let sums: Vec<Vec<f64>> = chunks
            .par_iter()
            .map(|c| {
                let mut s = vec![0.0f64; dim];
                for row in c.chunks_exact(dim) {
                    s.iter_mut().zip(row).for_each(|(a, &v)| *a += v as f64);
                }
                s
            })
            .collect();
        let mut mean = vec![0.0f64; dim];
        for s in &sums {
            mean.iter_mut().zip(s).for_each(|(m, v)| *m += v);
        }
        mean.iter_mut().for_each(|m| *m /= n.max(1) as f64);
        let partials: Vec<DMatrix<f64>> = chunks
            .par_iter()
            .map(|c| {
                let rows = c.len() / dim;
                let x = DMatrix::from_fn(rows, dim, |r, k| c[r * dim + k] as f64 - mean[k]);
                x.transpose() * x
            })
            .collect();
        let mut cov = DMatrix::<f64>::zeros(dim, dim);
        for p in &partials {
            cov += p;
        }
        cov /= n.max(1) as f64;
        let eig = SymmetricEigen::new(cov);
        let mut order: Vec<usize> = (0..dim).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]).then(a.cmp(&b)));
        let mut axes = Vec::with_capacity(dims * dim);
        let mut variances = Vec::with_capacity(dims);
        for &k in &order[..dims] {
            let col = eig.eigenvectors.column(k);
            // Fix the sign (largest component positive) so the axes do not depend on the solver's.
            let big = col.iter().copied().fold(0.0f64, |a, v| if v.abs() > a.abs() { v } else { a });
            let sign = if big < 0.0 { -1.0 } else { 1.0 };
            axes.extend(col.iter().map(|&v| (sign * v) as f32));
            variances.push(eig.eigenvalues[k].max(0.0));
        }
        Pca { mean: mean.iter().map(|&m| m as f32).collect(), axes, dim, dims, variances }
    }

    /// The mean feature the projection is centred on.
    pub fn mean(&self) -> &[f32] {
        &self.mean
    }

    /// Number of output dimensions.
    pub fn dims(&self) -> usize {
        self.dims
    }

    /// Projects the feature `v` into `out` (length [`Self::dims`]).
    pub fn project(&self, v: &[f32], out: &mut [f32]) {
        for (o, axis) in out.iter_mut().zip(self.axes.chunks_exact(self.dim)) {
            *o = v.iter().zip(&self.mean).zip(axis).map(|((x, m), a)| (x - m) * a).sum();
        }
    }
}

macro_rules! trees {
    ($($variant:ident => $k:literal),*) => {
        /// A kd-tree over projected features, its dimension rounded up to a supported constant
        /// (the padding coordinates are zero and do not change distances).
        enum Tree { $($variant(Box<ImmutableKdTree<f32, $k>>)),* }

        impl Tree {
            fn build(points: &[f32], dims: usize) -> Tree {
                $(if dims <= $k {
                    let padded: Vec<[f32; $k]> = points
                        .chunks_exact(dims)
                        .map(|p| {
                            let mut a = [0.0f32; $k];
                            a[..dims].copy_from_slice(p);
                            a
                        })
                        .collect();
                    return Tree::$variant(Box::new(ImmutableKdTree::new_from_slice(&padded)));
                })*
                panic!("projection to {dims} dimensions exceeds the supported 32")
            }

            fn nearest(&self, q: &[f32], radius2: f32, count: NonZero<usize>, out: &mut Vec<usize>) {
                match self {
                    $(Tree::$variant(t) => {
                        let mut a = [0.0f32; $k];
                        a[..q.len()].copy_from_slice(q);
                        let found = t.nearest_n_within::<SquaredEuclidean>(&a, radius2, count, true);
                        out.extend(found.iter().map(|nn| nn.item as usize));
                    })*
                }
            }
        }
    };
}

trees!(D4 => 4, D8 => 8, D16 => 16, D32 => 32);

/// PCA projection and kd-tree over one exemplar level's candidates.
pub struct ApproximateIndex {
    pca: Pca,
    tree: Tree,
    rerank: NonZero<usize>,
}

impl ApproximateIndex {
    /// Builds the index of `level` with `dims` projected dimensions (1..=32), returning `rerank`
    /// candidates per query.
    pub fn new(level: &ExemplarLevel, dims: usize, rerank: usize) -> Self {
        let pca = Pca::fit(level.features(), level.dim(), dims);
        let d = pca.dims().max(1);
        let mut points = vec![0.0f32; level.len() * d];
        points.par_chunks_mut(d).enumerate().for_each(|(i, p)| pca.project(level.feature(i), p));
        let tree = Tree::build(&points, d);
        ApproximateIndex { pca, tree, rerank: NonZero::new(rerank.max(1)).expect("at least one") }
    }

    /// The projection in use.
    pub fn pca(&self) -> &Pca {
        &self.pca
    }

    /// Appends to `out` (in no particular order) the up to `rerank` candidates nearest to `query` (a
    /// full feature) in the projected space among those within squared distance `radius2` there.
    ///
    /// The projection is orthonormal, so a projected distance never exceeds the full one: a
    /// candidate whose full squared distance is below `radius2` is never cut by the radius.
    pub fn candidates(&self, query: &[f32], radius2: f32, out: &mut Vec<usize>) {
        self.nearest(query, radius2, self.rerank, out);
    }

    /// [`Self::candidates`] with `count` candidates instead of the index's `rerank`.
    pub fn nearest(&self, query: &[f32], radius2: f32, count: NonZero<usize>, out: &mut Vec<usize>) {
        let mut q = [0.0f32; 32];
        let d = self.pca.dims().max(1);
        self.pca.project(query, &mut q[..self.pca.dims()]);
        self.tree.nearest(&q[..d], radius2, count, out);
    }
}

/// Rounds of [`propagate`] after the kd-tree's sets.
const PROPAGATION_ROUNDS: usize = 4;

/// PCA dimensions of the kd-tree the k-coherence sets start from. With `PROPAGATION_ROUNDS`
/// rounds of propagation, 4 dimensions find neighbours as near as 8 dimensions without
/// propagation did (median squared distance to the nearest other candidate of a 128x128 skin
/// exemplar: 0.0697 against 0.0700) in a quarter of the time (0.04 against 0.12 s on 2 cores;
/// 8 dimensions and 2 rounds reach 0.0625 in 0.085 s).
pub const SET_DIMS: usize = 4;

/// Writes candidate `i`'s set from `scored` (other candidates with their squared full distances):
/// `i` first, then the nearest, ties to the lower index, duplicates once; when fewer than `k - 1`
/// remain (tiny levels), `i` repeats.
fn fill_set(i: usize, mut scored: Vec<(f32, usize)>, set: &mut [u32]) {
    scored.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    scored.dedup_by_key(|c| c.1);
    set[0] = i as u32;
    for (s, slot) in set[1..].iter_mut().enumerate() {
        *slot = scored.get(s).map_or(i, |c| c.1) as u32;
    }
}

/// The sets from the kd-tree alone: each candidate's `max(2 k, SET_POOL)` nearest in the projected
/// space, re-scored in the full space.
fn tree_sets(full: &ExemplarLevel, k: usize, index: &ApproximateIndex) -> Vec<u32> {
    let pool = NonZero::new((2 * k).max(SET_POOL)).expect("at least SET_POOL");
    let mut sets = vec![0u32; full.len() * k];
    sets.par_chunks_mut(k).enumerate().for_each_init(Vec::new, |found, (i, set)| {
        found.clear();
        index.nearest(full.feature(i), f32::INFINITY, pool, found);
        let scored = found.iter().filter(|&&j| j != i).map(|&j| (full.distance2(j, full.feature(i)), j)).collect();
        fill_set(i, scored, set);
    });
    sets
}

/// One round of coherent propagation (as in PatchMatch, Barnes et al. 2009, run as a Jacobi
/// sweep so every candidate reads the previous round and the result does not depend on the thread
/// count): candidate `i` also considers, for each 4-neighbour `n` (candidate `i` shifted by
/// `(dx, dy)`), the members of `n`'s set shifted back by `(dx, dy)`. Windows that are alike
/// usually stay alike one texel over, so this finds near neighbours the projected kd-tree missed.
fn propagate(full: &ExemplarLevel, k: usize, prev: &[u32]) -> Vec<u32> {
    let mut sets = vec![0u32; prev.len()];
    sets.par_chunks_mut(k).enumerate().for_each(|(i, set)| {
        let query = full.feature(i);
        let mut scored: Vec<(f32, usize)> = Vec::with_capacity(5 * k);
        let own = prev[i * k + 1..(i + 1) * k].iter().map(|&j| j as usize);
        scored.extend(own.filter(|&j| j != i).map(|j| (full.distance2(j, query), j)));
        let [x, y] = full.position(i);
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let Some(n) = full.index_of(x as isize + dx, y as isize + dy) else { continue };
            for &m in &prev[n * k + 1..(n + 1) * k] {
                let [mx, my] = full.position(m as usize);
                match full.index_of(mx as isize - dx, my as isize - dy) {
                    Some(c) if c != i && !scored.iter().any(|s| s.1 == c) => {
                        scored.push((full.distance2(c, query), c));
                    }
                    _ => {}
                }
            }
        }
        fill_set(i, scored, set);
    });
    sets
}

/// k-coherence sets (Tong et al. 2002) of one exemplar level: for every candidate, itself and the
/// `k - 1` other candidates whose full neighbourhoods are nearest.
pub struct KCoherenceSets {
    k: usize,
    sets: Vec<u32>,
    typical: f32,
    typical_full: f32,
}

impl KCoherenceSets {
    /// Builds the sets from `full` (the level's candidates with full-window features) and measures
    /// the typical causal distance on `causal` (the same candidates, causal features).
    ///
    /// The similar candidates come from a PCA-`dims` kd-tree over `full` whose `max(2 k, SET_POOL)`
    /// nearest are re-scored in the full space (exact when the level has no more candidates than
    /// that), then `PROPAGATION_ROUNDS` rounds of `propagate`; ties go to the lower index.
    /// Each round reads only the previous one, so the result does not depend on the thread count.
    pub fn new(full: &ExemplarLevel, causal: &ExemplarLevel, k: usize, dims: usize) -> Self {
        debug_assert_eq!(full.len(), causal.len());
        let k = k.max(1);
        let mut sets = tree_sets(full, k, &ApproximateIndex::new(full, dims, 1));
        for _ in 0..PROPAGATION_ROUNDS {
            sets = propagate(full, k, &sets);
        }
        let median = |level: &ExemplarLevel| {
            let mut nearest: Vec<f32> = (0..level.len())
                .filter(|&i| k > 1 && sets[i * k + 1] as usize != i)
                .map(|i| level.distance2(sets[i * k + 1] as usize, level.feature(i)))
                .collect();
            nearest.sort_by(f32::total_cmp);
            nearest.get(nearest.len() / 2).copied().unwrap_or(0.0)
        };
        let (typical, typical_full) = (median(causal), median(full));
        KCoherenceSets { k, sets, typical, typical_full }
    }

    /// The set of candidate `i`: `i` itself first, then its most similar candidates.
    pub fn set(&self, i: usize) -> &[u32] {
        &self.sets[i * self.k..(i + 1) * self.k]
    }

    /// The level's typical squared causal distance: the median, over candidates, of the distance
    /// between a candidate's causal feature and that of its most similar other candidate (0 when
    /// `k` = 1 or the level has a single candidate).
    pub fn typical(&self) -> f32 {
        self.typical
    }

    /// [`Self::typical`] for the full-window features (the correction passes' fallback threshold).
    pub fn typical_full(&self) -> f32 {
        self.typical_full
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pca_finds_the_dominant_axis() {
        // Points along (3, 4) / 5 with a small orthogonal wobble.
        let mut f = Vec::new();
        for i in 0..200 {
            let t = i as f32 - 100.0;
            let w = if i % 2 == 0 { 0.1 } else { -0.1 };
            f.extend([0.6 * t - 0.8 * w + 1.0, 0.8 * t + 0.6 * w - 2.0]);
        }
        let pca = Pca::fit(&f, 2, 1);
        let mut p = [0.0];
        pca.project(&[1.0 + 0.6, -2.0 + 0.8], &mut p);
        // The mean sits at t = -0.5, so the query lies 1.5 along the axis from it.
        assert!((p[0] - 1.5).abs() < 1e-3, "{p:?}");
        assert!(pca.variances[0] > 3000.0);
    }

    /// A 40x40 level of a texture with structure at several scales (so windows have near but not
    /// equal neighbours), full 5x5 features.
    fn level() -> ExemplarLevel {
        use glam::Vec3;
        let texel = |x: usize, y: usize| {
            let (fx, fy) = (x as f32, y as f32);
            let hash = ((x * 73 + y * 151) % 97) as f32 / 97.0;
            Vec3::new((0.7 * fx).sin() + 0.3 * hash, (0.4 * fy + 0.2 * fx).cos(), (0.15 * (fx + fy)).sin() * hash)
        };
        let texels = skinkit_maps::Grid::from_fn(40, 40, texel);
        let nb = crate::neighbourhood::Neighbourhood::full(5, 1, false);
        ExemplarLevel::new(texels, None, &nb, 5, false)
    }

    /// Squared full distance from candidate `i` to its set's second member.
    fn nearest_of(full: &ExemplarLevel, sets: &[u32], k: usize, i: usize) -> f32 {
        full.distance2(sets[i * k + 1] as usize, full.feature(i))
    }

    #[test]
    fn propagation_never_loses_a_neighbour_and_finds_the_exact_ones_a_poor_tree_misses() {
        let full = level();
        let k = 2;
        // A 1-D projection: the tree alone often misses the nearest window.
        let tree = tree_sets(&full, k, &ApproximateIndex::new(&full, 1, 1));
        let mut sets = tree.clone();
        for _ in 0..PROPAGATION_ROUNDS {
            let next = propagate(&full, k, &sets);
            for i in 0..full.len() {
                assert!(nearest_of(&full, &next, k, i) <= nearest_of(&full, &sets, k, i), "candidate {i}");
                assert_eq!(next[i * k], i as u32);
            }
            sets = next;
        }
        // Against brute force over every other candidate.
        let exact = |s: &[u32]| {
            (0..full.len())
                .filter(|&i| {
                    let best = (0..full.len()).filter(|&j| j != i).map(|j| full.distance2(j, full.feature(i)));
                    nearest_of(&full, s, k, i) <= best.fold(f32::INFINITY, f32::min)
                })
                .count()
        };
        let (before, after) = (exact(&tree), exact(&sets));
        assert!(after >= 10 * before.max(1), "exact nearest: {before} from the tree, {after} after propagation");
        let mean = |s: &[u32]| (0..full.len()).map(|i| nearest_of(&full, s, k, i)).sum::<f32>() / full.len() as f32;
        let (before, after) = (mean(&tree), mean(&sets));
        assert!(after < 0.6 * before, "mean squared distance to the nearest: {before} from the tree, {after} after");
    }

    #[test]
    fn sets_do_not_depend_on_the_thread_count() {
        let full = level();
        let build = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
            pool.install(|| KCoherenceSets::new(&full, &full, 3, SET_DIMS).sets)
        };
        assert_eq!(build(1), build(2));
    }
}
