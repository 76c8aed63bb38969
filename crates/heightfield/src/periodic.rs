//! [`periodic`]: a field of whole waves across the map, so that it tiles exactly (as a grown,
//! toroidal map does), with exact heights and normals: the wrapping case of normal integration.

use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{HeightSample, Heightfield, Result};

/// Waves summed: a few broad ones and many fine ones down to four texels, each a whole number of
/// periods across the map.
const WAVES: usize = 24;

/// A `width x height` field at `mm_per_texel` whose every wave has a whole number of periods
/// across the map (so it tiles), amplitudes falling with frequency (a rough, skin-like spectrum),
/// RMS slope about 0.15.
///
/// # Errors
/// When the size or pitch is invalid (as for [`crate::SkinParams::validate`]).
pub fn periodic(width: usize, height: usize, mm_per_texel: f64, seed: u64) -> Result<Heightfield> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (lx, ly) = (width as f64 * mm_per_texel, height as f64 * mm_per_texel);
    let max_kx = (width / 4).max(1) as i64;
    let max_ky = (height / 4).max(1) as i64;
    let waves: Vec<(f64, f64, f64, f64)> = (0..WAVES)
        .map(|i| {
            // The first third broad, the rest anywhere up to four texels a period.
            let (cx, cy) = if i < WAVES / 3 { (max_kx.min(4), max_ky.min(4)) } else { (max_kx, max_ky) };
            let kx = rng.random_range(-cx..=cx) as f64;
            let ky = rng.random_range(0..=cy) as f64;
            let (fx, fy) = (TAU * kx / lx, TAU * ky / ly);
            let f = (fx * fx + fy * fy).sqrt().max(TAU / lx.max(ly));
            (fx, fy, 0.012 / f, rng.random_range(0.0..TAU))
        })
        .collect();
    Heightfield::from_fn(width, height, mm_per_texel, move |x, y| {
        let mut s = HeightSample::default();
        for &(fx, fy, a, phase) in &waves {
            let arg = fx * x + fy * y + phase;
            s.height += a * arg.sin();
            s.gradient.x += a * fx * arg.cos();
            s.gradient.y += a * fy * arg.cos();
        }
        s
    })
}
