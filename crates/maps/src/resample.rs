//! Resampling a map to another size, so that a texture keeps its physical scale when its
//! millimetres per texel differ from the map it is placed in (a mold captured at 0.02 mm per
//! texel grown into a face map at 0.05 mm per texel is shrunk by 0.4 first).
//!
//! The filter is a separable tent (linear) kernel. Enlarging, it is bilinear interpolation;
//! shrinking by `s < 1`, its support widens by `1 / s`, so every input texel contributes and fine
//! detail averages out instead of aliasing. Weights are normalised per output sample, so a
//! constant map stays constant, and texels past the edge repeat the edge (clamp). Sample centres
//! are aligned: output texel `i` of `n` sits at input coordinate `(i + 0.5) * in / n - 0.5`.
//!
//! Normal maps are resampled as unnormalised vectors ([`resample_normals`]) and renormalised once.

use rayon::prelude::*;

use crate::normal::NormalMap;
use crate::pyramid::Texel;
use crate::{Error, Grid, Result};

/// The weights of one output sample along one axis: first input index and one weight per input.
struct Taps {
    first: Vec<usize>,
    weights: Vec<Vec<f32>>,
}

/// Tent-filter taps resampling `from` samples to `to` samples (both at least 1).
fn taps(from: usize, to: usize) -> Taps {
    let scale = to as f64 / from as f64;
    // Kernel half-width in input texels: 1 when enlarging, 1 / scale when shrinking.
    let support = (1.0 / scale).max(1.0);
    let mut first = Vec::with_capacity(to);
    let mut weights = Vec::with_capacity(to);
    for i in 0..to {
        let centre = (i as f64 + 0.5) / scale - 0.5;
        let lo = (centre - support).floor() as isize + 1;
        let hi = (centre + support).ceil() as isize - 1;
        let mut w: Vec<(usize, f64)> = Vec::new();
        for j in lo..=hi {
            let t = 1.0 - ((j as f64 - centre) / support).abs();
            if t > 0.0 {
                let clamped = j.clamp(0, from as isize - 1) as usize;
                w.push((clamped, t));
            }
        }
        if w.is_empty() {
            // Only when the centre falls exactly on a texel with support 1: that texel alone.
            w.push((centre.round().clamp(0.0, from as f64 - 1.0) as usize, 1.0));
        }
        let start = w.iter().map(|p| p.0).min().unwrap_or(0);
        let end = w.iter().map(|p| p.0).max().unwrap_or(0);
        let total: f64 = w.iter().map(|p| p.1).sum();
        let mut dense = vec![0.0f64; end - start + 1];
        for (j, t) in w {
            dense[j - start] += t / total;
        }
        first.push(start);
        weights.push(dense.into_iter().map(|v| v as f32).collect());
    }
    Taps { first, weights }
}

/// Resamples `map` to `width x height` with a tent filter (see the module docs).
///
/// # Errors
/// When the map or the requested size is empty.
pub fn resample<T: Texel>(map: &Grid<T>, width: usize, height: usize) -> Result<Grid<T>> {
    let (w, h) = map.size();
    if w == 0 || h == 0 || width == 0 || height == 0 {
        return Err(Error::InvalidParameter(format!(
            "cannot resample a {w}x{h} map to {width}x{height}: sizes must be positive"
        )));
    }
    if (w, h) == (width, height) {
        return Ok(map.clone());
    }
    let tx = taps(w, width);
    let ty = taps(h, height);
    // Horizontal pass into a width x h grid, then vertical into width x height.
    let mut rows = vec![T::default(); width * h];
    rows.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let src = map.row(y);
        for (x, o) in out.iter_mut().enumerate() {
            let start = tx.first[x];
            *o = tx.weights[x].iter().enumerate().fold(T::default(), |acc, (k, &wt)| acc + src[start + k] * wt);
        }
    });
    let mut data = vec![T::default(); width * height];
    data.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
        let start = ty.first[y];
        for (k, &wt) in ty.weights[y].iter().enumerate() {
            let src = &rows[(start + k) * width..(start + k + 1) * width];
            for (o, &s) in out.iter_mut().zip(src) {
                *o = *o + s * wt;
            }
        }
    });
    Grid::from_vec(width, height, data)
}

/// Resamples a normal map as unnormalised vectors and renormalises once. Invalid (zero) texels
/// take part as zero vectors, so they shorten their neighbours' averages but never flip them; an
/// output texel whose average is zero stays invalid.
///
/// # Errors
/// When the map or the requested size is empty.
pub fn resample_normals(map: &NormalMap, width: usize, height: usize) -> Result<NormalMap> {
    if map.size() == (width, height) {
        return Ok(map.clone());
    }
    Ok(NormalMap::from_grid(resample(map.grid(), width, height)?))
}

/// The size a `width x height` map of `from_mm` millimetres per texel takes at `to_mm` per texel,
/// so features keep their physical size (each side at least 1).
pub fn scaled_size(width: usize, height: usize, from_mm: f64, to_mm: f64) -> (usize, usize) {
    let s = from_mm / to_mm;
    let side = |n: usize| ((n as f64 * s).round() as usize).max(1);
    (side(width), side(height))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn ramp(w: usize, h: usize) -> Grid<f32> {
        Grid::from_fn(w, h, |x, y| 0.3 * x as f32 - 0.7 * y as f32 + 2.0)
    }

    #[test]
    fn weights_sum_to_one_and_constants_stay_constant() {
        for (from, to) in [(7, 3), (3, 7), (128, 51), (51, 128), (1, 5), (5, 1), (64, 64)] {
            let t = taps(from, to);
            for w in &t.weights {
                let s: f32 = w.iter().sum();
                assert!((s - 1.0).abs() < 1e-5, "{from}->{to}: {s}");
            }
        }
        let c = Grid::filled(37, 23, 0.625f32);
        let r = resample(&c, 91, 11).unwrap();
        assert!(r.as_slice().iter().all(|&v| (v - 0.625).abs() < 1e-6));
    }

    #[test]
    fn enlarging_is_bilinear_interpolation() {
        // Doubling: output texel 1 sits at input 0.25, texel 2 at 0.75 (centres aligned).
        let g = Grid::from_vec(2, 1, vec![0.0f32, 4.0]).unwrap();
        let r = resample(&g, 4, 1).unwrap();
        assert_eq!(r.as_slice(), &[0.0, 1.0, 3.0, 4.0]);
    }

    #[test]
    fn linear_ramps_survive_away_from_the_edges() {
        // Enlarging, the tent is linear interpolation and reproduces a ramp exactly wherever its
        // support stays inside the map (independent check: the analytic ramp at the output
        // sample's input coordinate). Shrinking, the widened tent sampled at integer texels has
        // its centroid slightly off the centre: the ramp comes back within 0.03 texel of shift.
        let g = ramp(64, 48);
        for (w, h, tolerance) in [(25, 19, 0.03 * 0.77), (150, 100, 1e-4)] {
            let r = resample(&g, w, h).unwrap();
            let (sx, sy) = (64.0 / w as f64, 48.0 / h as f64);
            for y in 0..h {
                for x in 0..w {
                    let (cx, cy) = ((x as f64 + 0.5) * sx - 0.5, (y as f64 + 0.5) * sy - 0.5);
                    let margin_x = sx.max(1.0) + 1.0;
                    let margin_y = sy.max(1.0) + 1.0;
                    if cx < margin_x || cx > 63.0 - margin_x || cy < margin_y || cy > 47.0 - margin_y {
                        continue;
                    }
                    let expected = 0.3 * cx - 0.7 * cy + 2.0;
                    let got = *r.get(x, y) as f64;
                    assert!((got - expected).abs() < tolerance, "({x},{y}) {w}x{h}: {got} vs {expected}");
                }
            }
        }
    }

    #[test]
    fn shrinking_averages_instead_of_aliasing() {
        // A one-texel checkerboard halved: point sampling would give all 0 or all 1; the tent
        // filter over its widened support gives the mean everywhere inside.
        let g = Grid::from_fn(64, 64, |x, y| ((x + y) % 2) as f32);
        let r = resample(&g, 32, 32).unwrap();
        for y in 1..31 {
            for x in 1..31 {
                assert!((r.get(x, y) - 0.5).abs() < 1e-6, "({x},{y}) = {}", r.get(x, y));
            }
        }
    }

    #[test]
    fn normals_are_unit_and_invalid_regions_stay_invalid() {
        let n =
            NormalMap::from_grid(Grid::from_fn(
                40,
                40,
                |x, _| {
                    if x < 20 { Vec3::ZERO } else { Vec3::new(0.3, -0.2, 1.0) }
                },
            ));
        let r = resample_normals(&n, 17, 17).unwrap();
        for (i, v) in r.grid().as_slice().iter().enumerate() {
            let x = i % 17;
            if x < 7 {
                assert_eq!(*v, Vec3::ZERO);
            } else if x > 9 {
                assert!((v.length() - 1.0).abs() < 1e-5);
                assert!((*v - Vec3::new(0.3, -0.2, 1.0).normalize()).length() < 1e-5);
            }
        }
    }

    #[test]
    fn empty_sizes_are_errors_and_scaled_sizes_round() {
        assert!(resample(&Grid::filled(4, 4, 0.0f32), 0, 3).is_err());
        assert_eq!(scaled_size(256, 128, 0.02, 0.05), (102, 51));
        assert_eq!(scaled_size(3, 3, 0.01, 1.0), (1, 1));
    }
}
