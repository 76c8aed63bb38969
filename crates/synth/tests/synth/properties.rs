//! Property tests (proptest) of the synthesis search against linear scans on random exemplars:
//! - the kd-tree of [`ApproximateIndex`] returns exactly the nearest candidates in the projected
//!   space (distances equal to a linear scan's, ranked), and honours the radius;
//! - [`ExemplarLevel::nearest_exact`] finds a candidate at the linear scan's smallest distance;
//! - [`KCoherenceSets`]: each set is its candidate followed by the `k - 1` nearest others by full
//!   distance, as a linear scan ranks them (PCA to the full dimension, so the tree is exact).
//!
//! `PROPTEST_CASES=N` runs N cases of each; `PROPTEST_RNG_SEED=S` other cases than the default seed.

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::Config;
use skinkit_maps::Grid;
use skinkit_synth::exemplar::ExemplarLevel;
use skinkit_synth::neighbourhood::Neighbourhood;
use skinkit_synth::search::{ApproximateIndex, KCoherenceSets};

/// `cases` cases from this suite's fixed seed (`PROPTEST_CASES`, `PROPTEST_RNG_SEED` override).
fn config(cases: u32) -> Config {
    skinkit_testkit::proptest_config(cases, 0x5eed_5e7c)
}

/// A random exemplar of 3..=20 texels a side, values on a coarse lattice sometimes (ties) and
/// continuous otherwise.
fn exemplar() -> impl Strategy<Value = Grid<Vec3>> {
    (3usize..=20, 3usize..=20, any::<bool>()).prop_flat_map(|(w, h, lattice)| {
        let value = (0.0f32..1.0).prop_map(move |v| if lattice { (v * 4.0).floor() / 4.0 } else { v });
        prop::collection::vec((value.clone(), value.clone(), value), w * h).prop_map(move |v| {
            Grid::from_vec(w, h, v.into_iter().map(|(x, y, z)| Vec3::new(x, y, z)).collect()).unwrap()
        })
    })
}

/// A level over `g` with the `n x n` full window (`n` = 3 or 5), wrapped or not.
fn level(g: &Grid<Vec3>, n: usize, wrap: bool, full: bool) -> ExemplarLevel {
    let nb = if full { Neighbourhood::full(n, 3, false) } else { Neighbourhood::new(n, 3, false) };
    ExemplarLevel::new(g.clone(), None, &nb, n, wrap)
}

fn distance2(a: &[f32], b: &[f32]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (f64::from(*x) - f64::from(*y)).powi(2)).sum()
}

/// Sorted distances `x[..count]` against `y[..count]`, relative tolerance.
fn same_ranks(x: &[f64], y: &[f64], tol: f64) -> Result<(), String> {
    for (r, (a, b)) in x.iter().zip(y).enumerate() {
        if (a - b).abs() > tol * (1.0 + b.abs()) {
            return Err(format!("rank {r}: {a} vs linear scan {b}"));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn kd_tree_returns_the_projected_nearest(
        g in exemplar(),
        wrap in any::<bool>(),
        dims in 1usize..=12,
        rerank in 1usize..24,
        query_seed in any::<u64>(),
    ) {
        let level = level(&g, 3, wrap, false);
        prop_assume!(!level.is_empty());
        let index = ApproximateIndex::new(&level, dims, rerank);
        let d = index.pca().dims();
        let project = |f: &[f32]| {
            let mut p = vec![0.0f32; d];
            index.pca().project(f, &mut p);
            p
        };
        let projected: Vec<Vec<f32>> = (0..level.len()).map(|i| project(level.feature(i))).collect();
        // Queries: a candidate's own feature, and a blend of two.
        let (a, b) = ((query_seed % level.len() as u64) as usize, (query_seed / 7 % level.len() as u64) as usize);
        let blend: Vec<f32> = level.feature(a).iter().zip(level.feature(b)).map(|(x, y)| 0.3 * x + 0.7 * y).collect();
        for query in [level.feature(a).to_vec(), blend] {
            let q = project(&query);
            let mut scan: Vec<f64> = projected.iter().map(|p| distance2(p, &q)).collect();
            scan.sort_by(f64::total_cmp);
            let mut found = Vec::new();
            index.candidates(&query, f32::INFINITY, &mut found);
            prop_assert_eq!(found.len(), rerank.min(level.len()));
            let mut got: Vec<f64> = found.iter().map(|&i| distance2(&projected[i], &q)).collect();
            got.sort_by(f64::total_cmp);
            same_ranks(&got, &scan, 1e-4).map_err(TestCaseError::fail)?;
            // A radius: every candidate inside it, and as many as the scan finds clearly inside.
            let radius2 = scan[scan.len() / 2] as f32;
            found.clear();
            index.candidates(&query, radius2, &mut found);
            let inside = scan.iter().filter(|&&s| s < f64::from(radius2) * (1.0 - 1e-4) - 1e-6).count();
            prop_assert!(found.len() >= rerank.min(inside), "{} found, {} inside", found.len(), inside);
            for &i in &found {
                prop_assert!(distance2(&projected[i], &q) <= f64::from(radius2) * (1.0 + 1e-4) + 1e-6);
            }
        }
    }

    #[test]
    fn nearest_exact_is_the_linear_scan_minimum(g in exemplar(), wrap in any::<bool>(), t in 0.0f32..1.0) {
        let level = level(&g, 5, wrap, false);
        prop_assume!(!level.is_empty());
        let query: Vec<f32> = (0..level.dim()).map(|k| (t * (k as f32 + 1.0)).fract()).collect();
        let best = level.nearest_exact(&query);
        let scan = (0..level.len()).map(|i| distance2(level.feature(i), &query)).fold(f64::INFINITY, f64::min);
        let got = distance2(level.feature(best), &query);
        prop_assert!((got - scan).abs() <= 1e-5 * (1.0 + scan), "{} vs {}", got, scan);
    }

    #[test]
    fn k_coherence_sets_are_the_nearest_by_full_distance(g in exemplar(), wrap in any::<bool>(), k in 1usize..8) {
        let full = level(&g, 3, wrap, true);
        let causal = level(&g, 3, wrap, false);
        prop_assume!(!full.is_empty());
        // 3x3 full windows have 27 floats: PCA to 27 dimensions is a rotation, the tree is exact.
        let sets = KCoherenceSets::new(&full, &causal, k, full.dim());
        for i in 0..full.len() {
            let set = sets.set(i);
            prop_assert_eq!(set.len(), k);
            prop_assert_eq!(set[0] as usize, i);
            let mut scan: Vec<f64> =
                (0..full.len()).filter(|&j| j != i).map(|j| distance2(full.feature(j), full.feature(i))).collect();
            scan.sort_by(f64::total_cmp);
            let others = (k - 1).min(full.len() - 1);
            let got: Vec<f64> = set[1..=others].iter().map(|&j| distance2(full.feature(j as usize), full.feature(i))).collect();
            prop_assert!(set[1..=others].iter().all(|&j| j as usize != i), "candidate {} lists itself", i);
            same_ranks(&got, &scan, 1e-3).map_err(|e| TestCaseError::fail(format!("candidate {i}: {e}")))?;
        }
    }
}
