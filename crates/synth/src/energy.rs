//! A neighbourhood-matching energy of a synthesised map (in the spirit of Kwatra et al. 2005's
//! texture energy): the mean, over output texels, of the smallest squared L2 distance between the
//! texel's full `n x n` window (toroidal in the output) and any `n x n` window lying inside the
//! exemplar. Lower is better; 0 means every output window occurs verbatim in the exemplar.
//!
//! It is measured on one level only (the finest, in the benches), so it ignores the coarser-level
//! part of the synthesis neighbourhoods; it is a relative measure to compare search modes with.

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::Grid;

/// The energy of `output` against `exemplar` with `n x n` windows (`n` odd), evaluated on the
/// output texels whose coordinates are multiples of `stride` (1 = every texel). Exhaustive (with
/// a per-row early exit, which does not change the minimum), parallel over output texels, and
/// summed in texel order, so the value does not depend on the thread count. Returns 0 when the
/// exemplar holds no whole window.
pub fn window_energy(output: &Grid<Vec3>, exemplar: &Grid<Vec3>, n: usize, stride: usize) -> f64 {
    let mins = window_minima(output, exemplar, n, stride);
    if mins.is_empty() { 0.0 } else { mins.iter().map(|&m| m as f64).sum::<f64>() / mins.len() as f64 }
}

/// The smallest squared distance of [`window_energy`] for each sampled output texel, row-major
/// (empty when the exemplar holds no whole window): where the energy sits (seams, interiors).
pub fn window_minima(output: &Grid<Vec3>, exemplar: &Grid<Vec3>, n: usize, stride: usize) -> Vec<f32> {
    let r = n / 2;
    let (ew, eh) = exemplar.size();
    if ew < n || eh < n || output.is_empty() {
        return Vec::new();
    }
    let row = 3 * n;
    let windows: Vec<f32> = (r..eh - r)
        .flat_map(|y| (r..ew - r).map(move |x| (x, y)))
        .flat_map(|(x, y)| window(|dx, dy| *exemplar.get_wrapped(x as isize + dx, y as isize + dy), r))
        .collect();
    let stride = stride.max(1);
    let samples: Vec<(usize, usize)> = (0..output.height())
        .step_by(stride)
        .flat_map(|y| (0..output.width()).step_by(stride).map(move |x| (x, y)))
        .collect();
    samples
        .par_iter()
        .map(|&(x, y)| {
            let q = window(|dx, dy| *output.get_wrapped(x as isize + dx, y as isize + dy), r);
            let mut best = f32::INFINITY;
            for w in windows.chunks_exact(row * n) {
                let mut d = 0.0f32;
                for (a, b) in w.chunks_exact(row).zip(q.chunks_exact(row)) {
                    d += a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum::<f32>();
                    if d >= best {
                        break;
                    }
                }
                best = best.min(d);
            }
            best
        })
        .collect()
}

/// The `(2r + 1)^2` texels around a centre, row-major, flattened to floats.
fn window(texel: impl Fn(isize, isize) -> Vec3, r: usize) -> Vec<f32> {
    let r = r as isize;
    (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| (dx, dy))).flat_map(|(dx, dy)| texel(dx, dy).to_array()).collect()
}

/// The exemplar's own figure of [`window_energy`]: the mean, over the exemplar's whole `n x n`
/// windows (centres on multiples of `stride`), of the smallest squared distance to another whole
/// window that does not overlap it (centres at least `n` apart on some axis). It is what a map
/// made of the exemplar's own texture scores away from verbatim copies, so `window_energy / self`
/// compares exemplars of different contrast. Returns 0 when no window has a non-overlapping
/// partner.
pub fn self_energy(exemplar: &Grid<Vec3>, n: usize, stride: usize) -> f64 {
    let r = n / 2;
    let (ew, eh) = exemplar.size();
    if ew < n || eh < n {
        return 0.0;
    }
    let centres: Vec<(usize, usize)> = (r..eh - r).flat_map(|y| (r..ew - r).map(move |x| (x, y))).collect();
    let windows: Vec<Vec<f32>> = centres
        .iter()
        .map(|&(x, y)| window(|dx, dy| *exemplar.get_wrapped(x as isize + dx, y as isize + dy), r))
        .collect();
    let stride = stride.max(1);
    let samples: Vec<usize> = (0..centres.len())
        .filter(|&i| centres[i].0.is_multiple_of(stride) && centres[i].1.is_multiple_of(stride))
        .collect();
    let mins: Vec<f32> = samples
        .par_iter()
        .map(|&i| {
            let (x, y) = centres[i];
            let mut best = f32::INFINITY;
            for (j, w) in windows.iter().enumerate() {
                let (u, v) = centres[j];
                if u.abs_diff(x) < n && v.abs_diff(y) < n {
                    continue;
                }
                let mut d = 0.0f32;
                for (a, b) in w.iter().zip(&windows[i]) {
                    d += (a - b) * (a - b);
                }
                best = best.min(d);
            }
            best
        })
        .filter(|m| m.is_finite())
        .collect();
    if mins.is_empty() { 0.0 } else { mins.iter().map(|&m| m as f64).sum::<f64>() / mins.len() as f64 }
}
