//! Detrend: block size against what it leaves and what it takes. A synthetic nose mold (pores,
//! furrows) is given a broad bulge and a planar tilt, the low-frequency shape a mold that was not
//! flat carries; its truth is the same field without them. Each block size detrends the curved
//! map and is scored by
//!
//! * the mean angular error against the flat truth (the plotted error),
//! * [`residual_tilt`]: the tilt left in coarse tiles (the low frequencies it failed to remove),
//! * `detail_lost`: the share of fine-scale slope it flattened along with them.

use glam::{DVec3, Vec3};
use skinkit_capture::detrend::detrend;
use skinkit_heightfield::{Bulge, SkinParams};
use skinkit_maps::NormalMap;

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::timing::median_of;
use crate::{Config, Result};

/// Tiles per side of the residual-tilt measure.
pub const TILT_TILES: usize = 8;
/// Side of the tiles the fine-scale detail is measured in, texels.
pub const DETAIL_TILE: usize = 8;
/// Planar tilt of the curved mold, slopes `(dh/dx, dh/dy)`.
const TILT: [f64; 2] = [0.08, -0.05];

fn blocks(config: &Config) -> (usize, Vec<usize>) {
    if config.quick { (256, vec![0, 8, 25, 50, 100]) } else { (1024, vec![0, 4, 8, 16, 25, 50, 100, 200, 400]) }
}

/// Measures every block size.
///
/// # Errors
/// When the molds cannot be generated.
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let (side, blocks) = blocks(config);
    let flat = SkinParams { bulge: None, tilt: [0.0, 0.0], ..SkinParams::nose(side, side, config.seed) };
    let sigma = 0.3 * flat.extent_mm().0;
    let curved =
        SkinParams { bulge: Some(Bulge { height_mm: 0.25 * sigma, radius_mm: sigma }), tilt: TILT, ..flat.clone() };
    let truth = flat.generate()?.normals;
    let input = curved.generate()?.normals;
    let setup = format!(
        "{side}x{side} synthetic nose mold (seed {}) with a bulge and a planar tilt ({}, {}), against \
         the same mold without them; residual tilt: RMS angle from +Z of the mean normals of \
         {TILT_TILES}x{TILT_TILES} tiles; detail lost: the share of the truth's slope spread within \
         {DETAIL_TILE}x{DETAIL_TILE}-texel tiles that is gone; block 0 is no detrend",
        config.seed, TILT[0], TILT[1]
    );
    let mut report = StageReport::new(Stage::Detrend, setup, "mean angular error (deg)", "seconds");
    let tally = crate::Tally::start(progress, Stage::Detrend, blocks.len());
    let truth_detail = detail(&truth);
    for (i, &block) in blocks.iter().enumerate() {
        let (out, seconds) = median_of(config.runs(), || {
            let mut map = input.clone();
            detrend(&mut map, block);
            map
        });
        let error = out.angular_error(&truth, None)?.mean as f64;
        let lost = if truth_detail > 0.0 { 100.0 * (1.0 - detail(&out) / truth_detail) } else { 0.0 };
        let label = if block == 0 { "off".to_owned() } else { block.to_string() };
        report.choices.push(Choice::timed(
            "block size",
            &label,
            knobs(&[("block", block.to_string())]),
            metrics(&[
                ("mean angular error (deg)", error),
                ("residual tilt (deg)", residual_tilt(&out, TILT_TILES)),
                ("detail lost (%)", lost),
            ]),
            seconds,
            config.runs(),
        ));
        tally.done(i + 1);
    }
    Ok(report)
}

/// The tilt a map still carries: the RMS over `tiles x tiles` tiles of the angle (degrees) between
/// each tile's mean valid normal and +Z. A map tilted by a constant angle gives that angle; a map
/// of invalid texels, or tiles whose normals cancel, count 0.
pub fn residual_tilt(map: &NormalMap, tiles: usize) -> f64 {
    let means = tile_means(map, tiles.max(1), tiles.max(1));
    if means.is_empty() {
        return 0.0;
    }
    let sum: f64 = means.iter().map(|m| angle_from_z(*m).powi(2)).sum();
    (sum / means.len() as f64).sqrt()
}

/// Fine-scale detail: the RMS angle (degrees) between each valid normal and the mean of its
/// [`DETAIL_TILE`]-texel tile. 0 for a constant map.
pub fn detail(map: &NormalMap) -> f64 {
    let (w, h) = map.size();
    let (tx, ty) = (w.div_ceil(DETAIL_TILE).max(1), h.div_ceil(DETAIL_TILE).max(1));
    let means = tile_grid(map, tx, ty);
    let (mut sum, mut count) = (0.0, 0usize);
    for y in 0..h {
        for x in 0..w {
            let n = map.get(x, y);
            let m = means[(y * ty / h) * tx + x * tx / w];
            if n != Vec3::ZERO && m != DVec3::ZERO {
                let a = n.as_dvec3().cross(m).length().atan2(n.as_dvec3().dot(m)).to_degrees();
                sum += a * a;
                count += 1;
            }
        }
    }
    if count == 0 { 0.0 } else { (sum / count as f64).sqrt() }
}

/// Unit mean normals of a `tx x ty` tiling, row-major, zero where a tile has none.
fn tile_grid(map: &NormalMap, tx: usize, ty: usize) -> Vec<DVec3> {
    let (w, h) = map.size();
    let mut sums = vec![DVec3::ZERO; tx * ty];
    for y in 0..h {
        for x in 0..w {
            sums[(y * ty / h) * tx + x * tx / w] += map.get(x, y).as_dvec3();
        }
    }
    sums.into_iter().map(|s| s.try_normalize().unwrap_or(DVec3::ZERO)).collect()
}

/// The non-zero tile means of [`tile_grid`].
fn tile_means(map: &NormalMap, tx: usize, ty: usize) -> Vec<DVec3> {
    if map.width() == 0 || map.height() == 0 {
        return Vec::new();
    }
    tile_grid(map, tx, ty).into_iter().filter(|m| *m != DVec3::ZERO).collect()
}

/// Angle of a unit vector from +Z, degrees (atan2: exact near 0).
fn angle_from_z(n: DVec3) -> f64 {
    n.truncate().length().atan2(n.z).to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;
    use skinkit_maps::Grid;

    #[test]
    fn residual_tilt_of_a_constant_tilt_is_its_angle() {
        for degrees in [0.0f32, 0.5, 7.0, 30.0] {
            let t = degrees.to_radians();
            let n = Vec3::new(t.sin() * 0.6, t.sin() * 0.8, t.cos());
            let map = NormalMap::from_grid(Grid::filled(40, 24, n));
            assert!((residual_tilt(&map, 8) - degrees as f64).abs() < 1e-4, "{degrees}");
            assert!(detail(&map) < 1e-3);
        }
    }

    #[test]
    fn residual_tilt_of_a_plane_ramp_matches_the_closed_form() {
        // Normals of a cylinder bending about y: angle theta(x) = a * (x - c). Tile means of a
        // symmetric ramp of small angles are close to the mean angle of the tile.
        let (w, a) = (64usize, 0.004f32);
        let map = NormalMap::from_grid(Grid::from_fn(w, 8, |x, _| {
            let t = a * (x as f32 + 0.5 - w as f32 / 2.0);
            Vec3::new(t.sin(), 0.0, t.cos())
        }));
        // Tiles of 8 columns: tile i's mean angle is a * (8 i + 4 - 32); RMS over the tiles.
        let closed: f64 =
            ((0..8).map(|i| (a as f64 * (8.0 * i as f64 + 4.0 - 32.0)).powi(2)).sum::<f64>() / 8.0).sqrt();
        assert!((residual_tilt(&map, 8) - closed.to_degrees()).abs() < 1e-3);
    }

    #[test]
    fn degenerate_maps_give_zero_not_nan() {
        let empty = NormalMap::flat(0, 0);
        assert_eq!(residual_tilt(&empty, 8), 0.0);
        assert_eq!(detail(&empty), 0.0);
        let invalid = NormalMap::from_grid(Grid::filled(16, 16, Vec3::ZERO));
        assert_eq!(residual_tilt(&invalid, 4), 0.0);
        assert_eq!(detail(&invalid), 0.0);
    }

    #[test]
    fn detrending_removes_the_tilt_of_a_tilted_mold() {
        let config = Config { quick: true, seed: 3, samples: std::path::PathBuf::new() };
        let report = measure(&config, &skinkit_maps::progress::NoProgress).unwrap();
        let off = &report.choices[0];
        let on = report.choices.iter().find(|c| c.label == "50").unwrap();
        assert!(on.metric("residual tilt (deg)").unwrap() < 0.5 * off.metric("residual tilt (deg)").unwrap());
        assert!(on.error() < off.error());
    }
}
