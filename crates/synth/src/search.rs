//! Approximate nearest-neighbourhood search: PCA of an exemplar level's features to a few
//! dimensions (nalgebra `SymmetricEigen` of the covariance, in f64) and a kiddo kd-tree there.
//!
//! Raw neighbourhoods have about 60 dimensions, where an exact kd-tree is no faster than a linear
//! scan (REFERENCE.md, synthesis); the projected tree returns a few candidates which the caller
//! re-scores in the full space.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use nalgebra::{DMatrix, SymmetricEigen};
use rayon::prelude::*;

use crate::exemplar::ExemplarLevel;

/// Number of partial covariances (summed in order afterwards); their row ranges depend only on the
/// candidate count, so the bits never depend on the thread count, and memory stays bounded.
const COV_PARTS: usize = 32;

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
                        let found = t.nearest_n_within::<SquaredEuclidean>(&a, radius2, count, false);
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
        let mut q = [0.0f32; 32];
        let d = self.pca.dims().max(1);
        self.pca.project(query, &mut q[..self.pca.dims()]);
        self.tree.nearest(&q[..d], radius2, self.rerank, out);
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
}
