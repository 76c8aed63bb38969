//! Pictures of maps for people: 8-bit RGB images that the eye reads (a report page, a contact
//! sheet), as opposed to the maps themselves, whose encodings are for programs.
//!
//! * A normal map is drawn as the relief it describes, lit by a raking light ([`shade_normals`]):
//!   the usual blue-purple encoding hides pores and wrinkles that a low light shows at once.
//! * Scalar maps and photos are stretched between robust percentiles and given the sRGB curve
//!   ([`gray`]), so a dim linear photo is not drawn black.
//! * [`outline`] draws the boundaries of a label image (regions of a face map) over a picture.
//! * [`shrink`] box-filters a picture to fit a side, [`write_png`] writes it atomically.

use glam::Vec3;
use rayon::prelude::*;

use crate::io::{PngColour, PngLayout, write_png_rows};
use crate::{Grid, NormalMap, Result};

/// An 8-bit RGB picture.
pub type Picture = Grid<[u8; 3]>;

/// The light [`shade_normals`] uses by default: from the upper left, 30 degrees above the map's
/// plane (x right, y up, z out of the map), low enough that fine relief casts visible shading.
pub fn raking_light() -> Vec3 {
    let elevation = 30f32.to_radians();
    let (s, c) = elevation.sin_cos();
    Vec3::new(-c * std::f32::consts::FRAC_1_SQRT_2, c * std::f32::consts::FRAC_1_SQRT_2, s)
}

/// Colour of invalid texels (no normal, no value): a dark red that no shading produces.
pub const INVALID: [u8; 3] = [120, 0, 0];

/// Fraction of texels clipped at each end by the contrast stretch.
const CLIP: f64 = 0.005;

/// The relief of `map` under a directional `light` (a unit vector; the map's frame): `n . l` per
/// texel, stretched so that all but the darkest and brightest 0.5 % of valid texels span black to
/// white. Invalid texels are [`INVALID`]. A flat map (every `n . l` equal) is mid-grey.
pub fn shade_normals(map: &NormalMap, light: Vec3) -> Picture {
    let l = light.normalize_or(Vec3::Z);
    let lit = map.grid().map(|n| if *n == Vec3::ZERO { f32::NAN } else { n.dot(l) });
    stretch(&lit, 1.0)
}

/// A scalar map or a photo's linear luminance as grey: stretched like [`shade_normals`] between
/// robust percentiles, then given the sRGB curve. Non-finite values are [`INVALID`].
pub fn gray(values: &Grid<f32>) -> Picture {
    stretch(values, 1.0 / 2.4)
}

/// `values` mapped linearly from their robust range to [0, 1], raised to `gamma` (1: none; for
/// linear light, a plain power close to the sRGB curve), to 8 bits. NaN is [`INVALID`].
fn stretch(values: &Grid<f32>, gamma: f32) -> Picture {
    let (lo, hi) = robust_range(values.as_slice());
    let span = hi - lo;
    values.map(|&v| {
        if !v.is_finite() {
            return INVALID;
        }
        let t = if span > 0.0 { ((v - lo) / span).clamp(0.0, 1.0) } else { 0.5 };
        let g = (t.powf(gamma) * 255.0).round() as u8;
        [g, g, g]
    })
}

/// The values at the [`CLIP`] and `1 - CLIP` quantiles of the finite values (0, 0 when none).
fn robust_range(values: &[f32]) -> (f32, f32) {
    let mut finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return (0.0, 0.0);
    }
    let last = finite.len() - 1;
    let at = |q: f64| ((last as f64) * q).round() as usize;
    let (i_lo, i_hi) = (at(CLIP), at(1.0 - CLIP));
    let lo = *finite.select_nth_unstable_by(i_lo, f32::total_cmp).1;
    let hi = *finite.select_nth_unstable_by(i_hi, f32::total_cmp).1;
    (lo, hi)
}

/// Paints `colour` on every texel of `picture` whose label differs from its right or lower
/// neighbour's, so each boundary between regions is a line one texel wide.
///
/// # Panics
/// When `labels` and `picture` differ in size (a caller's bug).
pub fn outline<L: PartialEq + Sync>(picture: &mut Picture, labels: &Grid<L>, colour: [u8; 3]) {
    assert_eq!(picture.size(), labels.size(), "outline: labels and picture differ in size");
    let (w, h) = labels.size();
    picture.par_rows_mut().for_each(|(y, row)| {
        for (x, texel) in row.iter_mut().enumerate() {
            let here = labels.get(x, y);
            let right = x + 1 < w && labels.get(x + 1, y) != here;
            let below = y + 1 < h && labels.get(x, y + 1) != here;
            if right || below {
                *texel = colour;
            }
        }
    });
}

/// `picture` box-filtered by the smallest whole factor that brings its longer side to at most
/// `max_side` (unchanged when it already fits). Edge boxes average the texels they cover.
pub fn shrink(picture: &Picture, max_side: usize) -> Picture {
    let (w, h) = picture.size();
    let factor = w.max(h).div_ceil(max_side.max(1));
    if factor <= 1 {
        return picture.clone();
    }
    let (sw, sh) = (w.div_ceil(factor), h.div_ceil(factor));
    Grid::from_fn(sw, sh, |x, y| {
        let mut sum = [0u32; 3];
        let mut count = 0;
        for yy in y * factor..((y + 1) * factor).min(h) {
            for xx in x * factor..((x + 1) * factor).min(w) {
                let t = picture.get(xx, yy);
                (0..3).for_each(|c| sum[c] += u32::from(t[c]));
                count += 1;
            }
        }
        sum.map(|s| ((s + count / 2) / count) as u8)
    })
}

/// Writes `picture` as an 8-bit RGB PNG, atomically.
///
/// # Errors
/// When writing fails.
pub fn write_png(path: &std::path::Path, picture: &Picture) -> Result<()> {
    let (w, h) = picture.size();
    write_png_rows(path, w, h, PngLayout::Rgb8, PngColour::Srgb, |y, row| {
        for (out, texel) in row.chunks_exact_mut(3).zip(picture.row(y)) {
            (0..3).for_each(|c| out[c] = u16::from(texel[c]));
        }
    })
}

/// Stops of the height colour ramp, low to high: deep blue, teal, green, yellow (a ramp whose
/// lightness rises steadily, so the picture also reads in grey).
const RAMP: [[f32; 3]; 5] =
    [[40.0, 20.0, 90.0], [35.0, 95.0, 140.0], [35.0, 150.0, 130.0], [120.0, 200.0, 80.0], [250.0, 230.0, 60.0]];

/// Values in `[lo, hi]` as colours of the height ramp (clamped; non-finite values [`INVALID`]).
pub fn false_colour(values: &Grid<f32>, lo: f32, hi: f32) -> Picture {
    let span = hi - lo;
    values.map(|&v| if v.is_finite() { ramp(if span > 0.0 { (v - lo) / span } else { 0.5 }) } else { INVALID })
}

/// The ramp's colour at `t` in `[0, 1]` (clamped).
pub fn ramp(t: f32) -> [u8; 3] {
    let x = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f32;
    let i = (x.floor() as usize).min(RAMP.len() - 2);
    let f = x - i as f32;
    std::array::from_fn(|c| (RAMP[i][c] * (1.0 - f) + RAMP[i + 1][c] * f).round() as u8)
}

/// The range that [`shade_normals`] and [`gray`] stretch over: the values' robust extremes.
pub fn value_range(values: &[f32]) -> (f32, f32) {
    robust_range(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The height ramp runs from its first stop to its last, its lightness rising all the way
    /// (so a grey print still reads low to high), and clamps outside [0, 1].
    #[test]
    fn the_height_ramp_rises_in_lightness() {
        let luma = |c: [u8; 3]| 0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32;
        assert_eq!((ramp(0.0), ramp(1.0)), ([40, 20, 90], [250, 230, 60]));
        assert_eq!((ramp(-3.0), ramp(7.0)), (ramp(0.0), ramp(1.0)));
        let steps: Vec<f32> = (0..=100).map(|i| luma(ramp(i as f32 / 100.0))).collect();
        assert!(steps.windows(2).all(|p| p[1] >= p[0]), "{steps:?}");
        let picture = false_colour(&Grid::from_vec(3, 1, vec![0.0, f32::NAN, 2.0]).unwrap(), 0.0, 2.0);
        assert_eq!(picture.as_slice(), &[ramp(0.0), INVALID, ramp(1.0)]);
    }

    #[test]
    fn a_bump_is_bright_where_it_faces_the_light_and_dark_where_it_faces_away() {
        // A cone: normals tilted 20 degrees outward from the centre.
        let tilt = 20f32.to_radians();
        let map = NormalMap::from_grid(Grid::from_fn(33, 33, |x, y| {
            let (dx, dy) = (x as f32 - 16.0, 16.0 - y as f32);
            let r = (dx * dx + dy * dy).sqrt().max(1e-3);
            Vec3::new(dx / r * tilt.sin(), dy / r * tilt.sin(), tilt.cos())
        }));
        let picture = shade_normals(&map, raking_light());
        // The light comes from the upper left: the upper-left flank is lit, the lower-right not.
        assert!(picture.get(8, 8)[0] > 200, "{:?}", picture.get(8, 8));
        assert!(picture.get(24, 24)[0] < 55, "{:?}", picture.get(24, 24));
    }

    #[test]
    fn flat_invalid_and_empty_maps_stay_sensible() {
        let mut grid = Grid::filled(4, 4, Vec3::Z);
        *grid.get_mut(1, 2) = Vec3::ZERO;
        let picture = shade_normals(&NormalMap::from_grid(grid), raking_light());
        assert_eq!(*picture.get(0, 0), [128, 128, 128]);
        assert_eq!(*picture.get(1, 2), INVALID);
        let nothing = gray(&Grid::filled(3, 2, f32::NAN));
        assert!(nothing.as_slice().iter().all(|t| *t == INVALID));
    }

    #[test]
    fn gray_stretches_the_robust_range_with_a_gamma() {
        // 0..=999 ramp: 0.5 % clipped at each end, so 5 -> 0 and 994 -> 255; the middle value is
        // ((499.5 - 5) / 989)^(1/2.4) of white.
        let ramp = Grid::from_fn(1000, 1, |x, _| x as f32);
        let picture = gray(&ramp);
        assert_eq!(picture.get(2, 0)[0], 0);
        assert_eq!(picture.get(999, 0)[0], 255);
        let expected = ((500.0f32 - 5.0) / 989.0).powf(1.0 / 2.4) * 255.0;
        assert!((f32::from(picture.get(500, 0)[0]) - expected).abs() <= 1.0);
    }

    #[test]
    fn outline_marks_each_boundary_once() {
        let labels = Grid::from_fn(6, 4, |x, _| u8::from(x >= 3));
        let mut picture = Grid::filled(6, 4, [0u8; 3]);
        outline(&mut picture, &labels, [255, 0, 0]);
        for y in 0..4 {
            let marked: Vec<usize> = (0..6).filter(|&x| picture.get(x, y)[0] == 255).collect();
            assert_eq!(marked, vec![2], "row {y}");
        }
    }

    #[test]
    fn shrink_averages_whole_boxes_and_partial_edge_boxes() {
        let picture = Grid::from_fn(5, 2, |x, _| [if x < 4 { 10 * x as u8 } else { 200 }; 3]);
        let small = shrink(&picture, 3);
        assert_eq!(small.size(), (3, 1));
        assert_eq!(small.get(0, 0)[0], 5); // (0 + 10) / 2, both rows
        assert_eq!(small.get(1, 0)[0], 25);
        assert_eq!(small.get(2, 0)[0], 200); // the edge box covers one column
        assert_eq!(shrink(&picture, 8), picture);
    }
}
