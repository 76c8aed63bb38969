//! The TSD blur's own variance: what one bilinear pass of the centred Poisson disc really adds,
//! checked against its kernel scattered texel by texel, and the table the blur inverts it with.

use skinkit_render::pass::setup::{POISSON, poisson_axis_variance, poisson_mean, poisson_second_moment};
use skinkit_render::skin::tsd::{pass_variance, radius_for_variance, radius_table};

/// The variance along `axis` of one pass's kernel built as the GPU applies it: each of the 13 taps
/// spreads its weight 1/13 over the two texels a bilinear fetch mixes, onto an integer grid.
fn brute_force_variance(radius: f32, axis: usize) -> f64 {
    let mean = poisson_mean()[axis];
    let mut weights = std::collections::BTreeMap::<i64, f64>::new();
    for p in std::iter::once(0.0).chain(POISSON.iter().map(|p| p[axis])) {
        let o = f64::from(radius) * f64::from(p - mean);
        let below = o.floor();
        let f = o - below;
        *weights.entry(below as i64).or_default() += (1.0 - f) / 13.0;
        *weights.entry(below as i64 + 1).or_default() += f / 13.0;
    }
    let m: f64 = weights.iter().map(|(x, w)| *x as f64 * w).sum();
    weights.iter().map(|(x, w)| (*x as f64 - m).powi(2) * w).sum()
}

#[test]
fn pass_variance_matches_the_scattered_kernel() {
    for axis in 0..2 {
        for i in 0..400 {
            let radius = i as f32 * 0.05;
            let (got, want) = (f64::from(pass_variance(radius, axis)), brute_force_variance(radius, axis));
            assert!((got - want).abs() < 1e-4 * want.max(1e-3), "axis {axis}, radius {radius}: {got} vs {want}");
        }
    }
}

#[test]
fn the_sampler_adds_variance_linear_in_a_sub_texel_radius_and_one_sixth_far_above() {
    let axis_variance = poisson_axis_variance();
    for axis in 0..2 {
        // Below a texel the disc's own share (radius^2) is small against the sampler's (radius).
        let small = pass_variance(0.1, axis);
        assert!(small > 5.0 * 0.01 * axis_variance[axis], "axis {axis}: {small}");
        // Far above, the sampler's share averages 1/6.
        let r = 40.0;
        let sampler = pass_variance(r, axis) - r * r * axis_variance[axis];
        assert!((sampler - 1.0 / 6.0).abs() < 0.03, "axis {axis}: sampler share {sampler}");
    }
    let mean = (axis_variance[0] + axis_variance[1]) / 2.0;
    assert!((mean - poisson_second_moment() / 2.0).abs() < 1e-6);
    assert!((axis_variance[0] / axis_variance[1] - 1.0).abs() > 0.1, "the disc is anisotropic: {axis_variance:?}");
}

#[test]
fn radius_table_gives_the_asked_variance_to_one_percent() {
    let table = radius_table();
    for axis in 0..2 {
        for i in 1..=600 {
            let variance = i as f32 * 0.05;
            let got = pass_variance(radius_for_variance(&table, variance, axis), axis);
            assert!((got / variance - 1.0).abs() < 0.01, "axis {axis}: asked {variance}, got {got}");
        }
        assert!(radius_for_variance(&table, 0.0, axis) < 1e-6);
    }
}
