//! The exemplar pyramid the search matches in, for normal maps: at the coarser levels, `(x, y)` of
//! the averaged normals and, in place of `z`, a detail channel that survives averaging.
//!
//! Averaging normals cancels a small bump (its slopes point every way), so at the coarser levels a
//! pore looks like flat skin: the matching there cannot see where the exemplar's fine detail is,
//! and the output grows from its smoother parts (on the suite's heightfield nose, the sources the
//! output copied carried half of the exemplar's fine detail, and whole areas lost their pores).
//! The detail channel is the local rms high-pass of the finest normals (each texel's squared
//! difference from its 4-neighbours' mean, averaged down the pyramid like any channel, so it does
//! not cancel, then square-rooted): each texel carries what its neighbourhood looks like, in the
//! spirit of Lefebvre and Hoppe 2006's appearance space. The `z` it replaces holds no information
//! of its own for unit normals facing the viewer (`z` of an average only falls, at second order,
//! where the normals vary).
//!
//! The finest levels (below [`DETAIL_MIN_LEVEL`]) stay plain: there the pores are resolved, and
//! the finest level copies its texels to the output, which must be the exemplar's normals.

use crate::metrics::std_dev;
use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_maps::pyramid::{Border, gaussian};

/// The finest pyramid level that carries the detail channel (levels 0 and 1 resolve pores of a few
/// texels well enough; the suite measured the channel at level 1 too, which raised energy).
pub const DETAIL_MIN_LEVEL: usize = 2;

/// The matching pyramid of a normal exemplar: the [`gaussian`] pyramid (clamped borders), with
/// every level from [`DETAIL_MIN_LEVEL`] up holding `(x, y, d)`, `d` the detail channel scaled so
/// that its standard deviation over the level is `weight` times the mean of the `x` and `y`
/// channels' (its share of a distance stays the same at every level). `weight` 0 gives the plain
/// pyramid. A level without detail variation (a constant exemplar) gets `d` = 0.
pub fn normal_pyramid(exemplar: &Grid<Vec3>, levels: usize, weight: f32) -> Vec<Grid<Vec3>> {
    let mut pyramid = gaussian(exemplar, levels, Border::Clamp);
    if weight <= 0.0 || pyramid.len() <= DETAIL_MIN_LEVEL {
        return pyramid;
    }
    let detail = gaussian(&high_pass(exemplar), pyramid.len(), Border::Clamp);
    for (level, d) in pyramid.iter_mut().zip(&detail).skip(DETAIL_MIN_LEVEL) {
        let rms = d.map(|v| v.max(0.0).sqrt());
        let spread =
            0.5 * (std_dev(level.as_slice().iter().map(|t| t.x)) + std_dev(level.as_slice().iter().map(|t| t.y)));
        let own = std_dev(rms.as_slice().iter().copied());
        let scale = if own > 1e-12 { (weight as f64 * spread / own) as f32 } else { 0.0 };
        for (t, r) in level.as_mut_slice().iter_mut().zip(rms.as_slice()) {
            t.z = scale * r;
        }
    }
    pyramid
}

/// Each texel's squared distance from the mean of its 4-neighbours (clamped at the border).
fn high_pass(g: &Grid<Vec3>) -> Grid<f32> {
    Grid::from_fn(g.width(), g.height(), |x, y| {
        let (x, y) = (x as isize, y as isize);
        let around =
            *g.get_clamped(x - 1, y) + *g.get_clamped(x + 1, y) + *g.get_clamped(x, y - 1) + *g.get_clamped(x, y + 1);
        (*g.get_clamped(x, y) - 0.25 * around).length_squared()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit normals of `h(x, y)` by central differences (clamped), unit texel spacing.
    fn normals_of(side: usize, h: impl Fn(f32, f32) -> f32 + Sync) -> Grid<Vec3> {
        Grid::from_fn(side, side, |x, y| {
            let (xf, yf) = (x as f32, y as f32);
            let dx = 0.5 * (h(xf + 1.0, yf) - h(xf - 1.0, yf));
            let dy = 0.5 * (h(xf, yf + 1.0) - h(xf, yf - 1.0));
            Vec3::new(-dx, -dy, 1.0).normalize()
        })
    }

    /// A 64x64 map: bumps of radius 2 on a 6-texel grid in the left half, flat on the right.
    fn half_bumpy() -> Grid<Vec3> {
        normals_of(64, |x, y| {
            let (cx, cy) = ((x / 6.0).round() * 6.0, (y / 6.0).round() * 6.0);
            let r2 = (x - cx).powi(2) + (y - cy).powi(2);
            if x < 30.0 { 0.5 * (-r2 / 2.0).exp() } else { 0.0 }
        })
    }

    #[test]
    fn weight_zero_and_finest_levels_are_the_plain_pyramid() {
        let ex = half_bumpy();
        let plain = gaussian(&ex, 5, Border::Clamp);
        assert_eq!(normal_pyramid(&ex, 5, 0.0), plain);
        let detailed = normal_pyramid(&ex, 5, 1.5);
        assert_eq!(detailed.len(), plain.len());
        assert_eq!(detailed[..DETAIL_MIN_LEVEL], plain[..DETAIL_MIN_LEVEL]);
        for (d, p) in detailed.iter().zip(&plain).skip(DETAIL_MIN_LEVEL) {
            for (a, b) in d.as_slice().iter().zip(p.as_slice()) {
                assert_eq!((a.x, a.y), (b.x, b.y));
            }
        }
    }

    /// The channel tells bumpy from flat where the averaged normals no longer do, and its
    /// deviation is `weight` times the slope channels' mean deviation.
    #[test]
    fn detail_survives_averaging_at_the_weighted_scale() {
        let ex = half_bumpy();
        let pyramid = normal_pyramid(&ex, 5, 2.0);
        let level = &pyramid[3]; // 8x8: a texel covers 8x8 finest texels, more than a bump period
        let (w, h) = level.size();
        let side_mean = |xs: std::ops::Range<usize>, c: usize| {
            let v: Vec<f32> =
                (0..h).flat_map(|y| xs.clone().map(move |x| (x, y))).map(|(x, y)| level.get(x, y)[c]).collect();
            v.iter().sum::<f32>() / v.len() as f32
        };
        // Slopes average out on both sides; the detail channel does not.
        let (left, right) = (0..w / 2 - 1, w / 2 + 1..w);
        assert!(side_mean(left.clone(), 0).abs() < 0.05 && side_mean(right.clone(), 0).abs() < 0.05);
        assert!(side_mean(left, 2) > 5.0 * side_mean(right, 2).abs().max(1e-6));
        let spread =
            0.5 * (std_dev(level.as_slice().iter().map(|t| t.x)) + std_dev(level.as_slice().iter().map(|t| t.y)));
        let own = std_dev(level.as_slice().iter().map(|t| t.z));
        assert!((own - 2.0 * spread).abs() < 1e-4 * spread.max(1e-9), "{own} against {spread}");
    }

    /// A constant exemplar (no slope, no detail) stays finite: the channel is 0.
    #[test]
    fn constant_exemplar_gets_a_zero_channel() {
        let ex = Grid::filled(32, 32, Vec3::Z);
        for level in normal_pyramid(&ex, 4, 1.5).iter().skip(DETAIL_MIN_LEVEL) {
            assert!(level.as_slice().iter().all(|t| t.is_finite() && t.z == 0.0));
        }
    }
}
