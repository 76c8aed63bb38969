//! Helpers the synthesis tests share.

use glam::Vec3;
use skinkit_maps::Grid;

/// A structured exemplar with no exactly repeated neighbourhoods: stripes plus a hash.
pub fn pattern(w: usize, h: usize) -> Grid<Vec3> {
    Grid::from_fn(w, h, |x, y| {
        let hash = ((x as u32).wrapping_mul(73_856_093) ^ (y as u32).wrapping_mul(19_349_663)) % 1000;
        let r = hash as f32 / 1000.0;
        Vec3::new((x as f32 * 0.9).sin() + 0.3 * r, (y as f32 * 0.7).cos(), r)
    })
}
