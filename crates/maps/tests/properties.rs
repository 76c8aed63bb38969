//! Property tests (proptest) of the Burt-Adelson pyramid (`skinkit_maps::pyramid`) on random
//! grids of any size from 1x1, both border rules:
//! - [`reduce`] against a naive 2-D sum of the 5x5 kernel at the kept texels;
//! - sizes (`ceil(w/2) x ceil(h/2)` down, the asked size up), finiteness;
//! - reduce and expand stay within the input's range (their weights are non-negative and sum
//!   to one) and keep a constant map constant;
//! - `collapse(laplacian(g)) == g` up to float rounding.
//!
//! `PROPTEST_CASES=N` runs N cases of each; `PROPTEST_RNG_SEED=S` other cases than the default seed.

use proptest::prelude::*;
use proptest::test_runner::Config;
use skinkit_maps::Grid;
use skinkit_maps::pyramid::{Border, KERNEL, collapse, expand, laplacian, max_levels, reduce};

/// `cases` cases from this suite's fixed seed (`PROPTEST_CASES`, `PROPTEST_RNG_SEED` override).
fn config(cases: u32) -> Config {
    skinkit_testkit::proptest_config(cases, 0x5eed_0a95)
}

fn grid() -> impl Strategy<Value = Grid<f32>> {
    (1usize..48, 1usize..48).prop_flat_map(|(w, h)| {
        prop::collection::vec(-1.0e3f32..1.0e3, w * h).prop_map(move |v| Grid::from_vec(w, h, v).unwrap())
    })
}

fn border() -> impl Strategy<Value = Border> {
    prop_oneof![Just(Border::Wrap), Just(Border::Clamp)]
}

fn index(border: Border, i: isize, n: usize) -> usize {
    match border {
        Border::Wrap => i.rem_euclid(n as isize) as usize,
        Border::Clamp => i.clamp(0, n as isize - 1) as usize,
    }
}

/// The naive reduce: `sum_ij w_i w_j g(2x + i - 2, 2y + j - 2)` in f64.
fn naive_reduce(g: &Grid<f32>, border: Border) -> Grid<f64> {
    let (w, h) = g.size();
    Grid::from_fn(w.div_ceil(2), h.div_ceil(2), |x, y| {
        let mut sum = 0.0f64;
        for (j, wy) in KERNEL.iter().enumerate() {
            for (i, wx) in KERNEL.iter().enumerate() {
                let sx = index(border, 2 * x as isize + i as isize - 2, w);
                let sy = index(border, 2 * y as isize + j as isize - 2, h);
                sum += f64::from(*wx) * f64::from(*wy) * f64::from(*g.get(sx, sy));
            }
        }
        sum
    })
}

fn range(g: &Grid<f32>) -> (f32, f32) {
    g.as_slice().iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
}

/// `v` within `[lo, hi]` up to float rounding of values of size `scale`.
fn within(v: f32, (lo, hi): (f32, f32), scale: f32) -> bool {
    let slack = 1e-5 * scale.max(1.0);
    v.is_finite() && v >= lo - slack && v <= hi + slack
}

proptest! {
    #![proptest_config(config(128))]

    #[test]
    fn reduce_is_the_naive_kernel_sum(g in grid(), border in border()) {
        let ours = reduce(&g, border);
        let naive = naive_reduce(&g, border);
        prop_assert_eq!(ours.size(), naive.size());
        for (i, (a, b)) in ours.as_slice().iter().zip(naive.as_slice()).enumerate() {
            prop_assert!((f64::from(*a) - b).abs() < 1e-3, "texel {}: {} vs {}", i, a, b);
        }
    }

    #[test]
    fn reduce_and_expand_keep_sizes_and_stay_in_range(g in grid(), border in border()) {
        let (w, h) = g.size();
        let r = range(&g);
        let scale = r.0.abs().max(r.1.abs());
        let small = reduce(&g, border);
        prop_assert_eq!(small.size(), (w.div_ceil(2), h.div_ceil(2)));
        prop_assert!(small.as_slice().iter().all(|&v| within(v, r, scale)), "reduce leaves [{}, {}]", r.0, r.1);
        let up = expand(&small, w, h, border);
        prop_assert_eq!(up.size(), (w, h));
        let rs = range(&small);
        prop_assert!(up.as_slice().iter().all(|&v| within(v, rs, scale)), "expand leaves [{}, {}]", rs.0, rs.1);
    }

    #[test]
    fn a_constant_map_stays_constant(
        (w, h) in (1usize..64, 1usize..64),
        c in -1.0e3f32..1.0e3,
        border in border(),
        up_w in 1usize..130,
        up_h in 1usize..130,
    ) {
        let g = Grid::filled(w, h, c);
        let tol = 1e-5 * c.abs().max(1.0);
        prop_assert!(reduce(&g, border).as_slice().iter().all(|v| (v - c).abs() <= tol));
        let up = expand(&g, up_w, up_h, border);
        prop_assert_eq!(up.size(), (up_w, up_h));
        prop_assert!(up.as_slice().iter().all(|v| (v - c).abs() <= tol));
    }

    #[test]
    fn collapse_inverts_laplacian(g in grid(), border in border(), levels in 1usize..8) {
        let bands = laplacian(&g, levels, border);
        prop_assert_eq!(bands.len(), levels.min(max_levels(g.width(), g.height(), 1).max(1)));
        let back = collapse(&bands, border);
        prop_assert_eq!(back.size(), g.size());
        for (a, b) in g.as_slice().iter().zip(back.as_slice()) {
            prop_assert!((a - b).abs() < 1e-3, "{} vs {}", a, b);
        }
    }
}
