//! The round trip of integration: how far the normals of an integrated height are from the normal
//! map they came from, and where they part.
//!
//! A height's normals taken by central differences see each slope through a `[1 2 1] / 4` filter
//! (the mean of the two edge steps around a texel, each the mean of two slopes), so they are
//! compared with the map filtered the same way ([`as_central_differences`]): what is left is
//! the part of the map no surface has (noise, non-integrable texels, seams between stitched
//! regions), not the filter.

use serde::Serialize;
use skinkit_maps::normal::{AngularStats, angle_degrees};
use skinkit_maps::{Grid, NormalMap, Vec3};

use crate::Height;
use crate::compare::normals_of;
use crate::slopes::MAX_SLOPE;

/// Texels from a region boundary within which a texel counts as on a seam.
pub const SEAM_TEXELS: usize = 8;

/// The slopes of `normals` filtered by `[1 2 1] / 4` along their own axis (x slopes along rows, row
/// slopes along columns), clamped at the borders (wrapping with `wraps`), back as normals. Zero
/// (invalid) normals stay zero and count as flat for their neighbours.
pub fn as_central_differences(normals: &NormalMap, wraps: bool) -> NormalMap {
    let (w, h) = normals.size();
    let slope = |x: isize, y: isize| {
        let grid = normals.grid();
        let n = if wraps { *grid.get_wrapped(x, y) } else { *grid.get_clamped(x, y) };
        if n.z > 0.0 && n.is_finite() {
            ((-n.x / n.z).clamp(-MAX_SLOPE, MAX_SLOPE), (n.y / n.z).clamp(-MAX_SLOPE, MAX_SLOPE))
        } else {
            (0.0, 0.0)
        }
    };
    let grid = Grid::from_fn(w, h, |x, y| {
        if !normals.is_valid(x, y) {
            return Vec3::ZERO;
        }
        let (x, y) = (x as isize, y as isize);
        let p = 0.25 * (slope(x - 1, y).0 + 2.0 * slope(x, y).0 + slope(x + 1, y).0);
        let q = 0.25 * (slope(x, y - 1).1 + 2.0 * slope(x, y).1 + slope(x, y + 1).1);
        Vec3::new(-p, q, 1.0).normalize()
    });
    NormalMap::from_grid(grid)
}

/// Angles between two normal maps over the texels where both are valid.
#[derive(Clone, Debug, Serialize)]
pub struct Agreement {
    pub all: AngularStats,
    /// Split by distance to region boundaries, when the regions are known.
    pub seams: Option<SeamSplit>,
}

/// Where two normal maps part: on seams between regions or away from them.
#[derive(Clone, Debug, Serialize)]
pub struct SeamSplit {
    /// Texels within [`SEAM_TEXELS`] of a boundary, as a share of all compared texels.
    pub seam_share: f64,
    /// Of the texels at or above the overall 95th percentile angle, the share on seams.
    pub seam_share_of_worst: f64,
    pub on_seams: AngularStats,
    pub off_seams: AngularStats,
}

/// Compares `a` with `b` (same size), texel by texel; `labels` (same size) names each texel's
/// region.
pub fn agreement<L: PartialEq + Copy>(a: &NormalMap, b: &NormalMap, labels: Option<&Grid<L>>) -> Agreement {
    assert_eq!(a.size(), b.size(), "agreement: sizes");
    let (w, _) = a.size();
    let texels: Vec<(usize, f32)> = (0..a.as_slice().len())
        .filter(|&i| a.is_valid(i % w, i / w) && b.is_valid(i % w, i / w))
        .map(|i| (i, angle_degrees(a.as_slice()[i], b.as_slice()[i])))
        .collect();
    let all = AngularStats::from_degrees(texels.iter().map(|t| t.1).collect());
    let seams = labels.map(|labels| {
        let near = near_boundaries(labels, SEAM_TEXELS);
        let (on, off): (Vec<&(usize, f32)>, Vec<_>) = texels.iter().partition(|t| near[t.0]);
        let worst: Vec<bool> = texels.iter().filter(|t| t.1 >= all.p95).map(|t| near[t.0]).collect();
        SeamSplit {
            seam_share: on.len() as f64 / texels.len().max(1) as f64,
            seam_share_of_worst: worst.iter().filter(|&&n| n).count() as f64 / worst.len().max(1) as f64,
            on_seams: AngularStats::from_degrees(on.iter().map(|t| t.1).collect()),
            off_seams: AngularStats::from_degrees(off.iter().map(|t| t.1).collect()),
        }
    });
    Agreement { all, seams }
}

/// How the normals of `height` (integrated from `normals`, wrapping with `wraps`) agree with
/// `normals` seen through the same central differences; `labels` name the map's regions.
pub fn height_agreement<L: PartialEq + Copy>(
    normals: &NormalMap,
    height: &Height,
    wraps: bool,
    labels: Option<&Grid<L>>,
) -> Agreement {
    let texel = height.report.mm_per_texel.unwrap_or(1.0) as f32;
    let mut from_height = normals_of(&height.map, texel, wraps).into_grid();
    // Texels the integration did not use as data (holes it filled) are not compared.
    from_height.as_mut_slice().iter_mut().zip(&height.valid).filter(|(_, ok)| !**ok).for_each(|(n, _)| *n = Vec3::ZERO);
    agreement(&as_central_differences(normals, wraps), &NormalMap::from_grid(from_height), labels)
}

/// Per texel: a texel whose label differs from its right or lower neighbour's lies within
/// `radius` texels (in both axes) of it.
fn near_boundaries<L: PartialEq + Copy>(labels: &Grid<L>, radius: usize) -> Vec<bool> {
    let (w, h) = labels.size();
    let mut edge = vec![0u32; w * h];
    for y in 0..h {
        for x in 0..w {
            let l = *labels.get(x, y);
            let differs = (x + 1 < w && *labels.get(x + 1, y) != l) || (y + 1 < h && *labels.get(x, y + 1) != l);
            edge[y * w + x] = u32::from(differs);
        }
    }
    // A box of side 2 radius + 1 around each texel holds an edge texel: rows, then columns.
    let rows = box_sums(&edge, h, w, radius, w, 1);
    let both = box_sums(&rows, w, h, radius, 1, w);
    both.into_iter().map(|n| n > 0).collect()
}

/// Sums of `v` over a window of `radius` elements either side, along `lines` lines of `len`
/// elements: line `l`, element `k` is `v[l * line_stride + k * step]`.
fn box_sums(v: &[u32], lines: usize, len: usize, radius: usize, line_stride: usize, step: usize) -> Vec<u32> {
    let mut out = vec![0u32; v.len()];
    let mut prefix = vec![0u32; len + 1];
    for line in 0..lines {
        let at = |k: usize| line * line_stride + k * step;
        for k in 0..len {
            prefix[k + 1] = prefix[k] + v[at(k)];
        }
        for k in 0..len {
            let (lo, hi) = (k.saturating_sub(radius), (k + radius + 1).min(len));
            out[at(k)] = prefix[hi] - prefix[lo];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A texel next to a boundary is near it, one `radius + 1` away is not.
    #[test]
    fn boundaries_reach_their_radius() {
        let labels = Grid::from_fn(40, 30, |x, _| u8::from(x >= 20));
        let near = near_boundaries(&labels, 3);
        for x in 0..40 {
            // The boundary texels are x = 19 (differs from its right neighbour).
            assert_eq!(near[10 * 40 + x], (16..=22).contains(&x), "x {x}");
        }
        let rows = Grid::from_fn(30, 40, |_, y| u8::from(y >= 20));
        let near = near_boundaries(&rows, 3);
        assert!(near[22 * 30 + 5] && !near[23 * 30 + 5] && !near[15 * 30 + 5] && near[16 * 30 + 5]);
    }

    /// A map against itself agrees to 0; a 10-degree tilt along the seam only is measured there.
    #[test]
    fn agreement_measures_angles_and_where() {
        let flat = NormalMap::from_grid(Grid::from_fn(64, 64, |_, _| Vec3::Z));
        let labels = Grid::from_fn(64, 64, |x, _| u8::from(x >= 32));
        let same = agreement(&flat, &flat, Some(&labels));
        assert!(same.all.max < 1e-3 && same.all.count == 64 * 64);
        let tilt = Vec3::new(10f32.to_radians().sin(), 0.0, 10f32.to_radians().cos());
        let seam =
            NormalMap::from_grid(Grid::from_fn(64, 64, |x, _| if (30..34).contains(&x) { tilt } else { Vec3::Z }));
        let a = agreement(&flat, &seam, Some(&labels));
        assert!((a.all.max - 10.0).abs() < 1e-3, "{a:?}");
        let split = a.seams.unwrap();
        assert!((split.seam_share - 17.0 / 64.0).abs() < 1e-9, "{split:?}");
        assert!(split.on_seams.max > 9.9 && split.off_seams.max < 1e-3 && split.seam_share_of_worst == 1.0);
    }

    /// An integrable map's height comes back through the round trip within a hundredth of a
    /// degree; noise added to the slopes (not integrable) shows up as disagreement.
    #[test]
    fn an_integrable_map_round_trips() {
        let h = |x: f32, y: f32| 3.0 * (x * 0.11).sin() * (y * 0.07).cos();
        let map = |noise: f32| {
            NormalMap::from_grid(Grid::from_fn(96, 80, |x, y| {
                let (xf, yf) = (x as f32, y as f32);
                let p = (h(xf + 0.5, yf) - h(xf - 0.5, yf)) + noise * (((x * 7 + y * 13) % 5) as f32 - 2.0);
                let q = h(xf, yf + 0.5) - h(xf, yf - 0.5);
                Vec3::new(-p, q, 1.0)
            }))
        };
        let options = crate::HeightOptions::default();
        let clean = map(0.0);
        let height = crate::integrate(&clean, &options).unwrap();
        let a = height_agreement::<u8>(&clean, &height, false, None);
        assert!(a.all.p95 < 0.05, "{a:?}");
        let noisy = map(0.05);
        let height = crate::integrate(&noisy, &options).unwrap();
        let b = height_agreement::<u8>(&noisy, &height, false, None);
        assert!(b.all.median > 10.0 * a.all.median.max(0.01), "{b:?} against {a:?}");
    }

    /// On a quadratic height, `[1 2 1] / 4` of its slopes is its central difference, exactly.
    #[test]
    fn the_filter_matches_central_differences_on_quadratics() {
        let h = |x: f32, y: f32| 0.01 * x * x - 0.02 * y * y + 0.005 * x * y;
        let normals = NormalMap::from_grid(Grid::from_fn(16, 12, |x, y| {
            let (x, y) = (x as f32, y as f32);
            // dh/dcol = -nx/nz, dh/drow = ny/nz.
            Vec3::new(-(0.02 * x + 0.005 * y), -0.04 * y + 0.005 * x, 1.0).normalize()
        }));
        let filtered = as_central_differences(&normals, false);
        for y in 1..11 {
            for x in 1..15 {
                let (xf, yf) = (x as f32, y as f32);
                let p = (h(xf + 1.0, yf) - h(xf - 1.0, yf)) / 2.0;
                let q = (h(xf, yf + 1.0) - h(xf, yf - 1.0)) / 2.0;
                let want = Vec3::new(-p, q, 1.0).normalize();
                assert!((filtered.get(x, y) - want).length() < 1e-5, "({x}, {y})");
            }
        }
    }
}
