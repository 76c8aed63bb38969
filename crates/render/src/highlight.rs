//! How much of a render's highlights the specular lobes make (issue 13): the same scene drawn
//! twice into linear radiance, once with the Lafortune lobes and once with `lobes = []`, compared
//! pixel by pixel. The difference is exactly the lobes' radiance, because the base pass adds the
//! lobes to the diffuse term before the (linear) sum over lights and nothing else depends on them.
//!
//! Highlight pixels are the brightest `HIGHLIGHT_FRACTION` of the pixels the surface covers
//! (luminance of the render with lobes, Rec. 709 weights; background pixels are 0 in both
//! renders and never count). For them [`SpecularShare`] gives the mean and median of
//! `(with - without) / with`, the share of each highlight pixel's luminance the lobes make, and
//! the lobes' local contrast there: the mean absolute difference between the lobes' luminance
//! and its `CONTRAST_BOX` x `CONTRAST_BOX` box average over the covered pixels of the box, over
//! the lobes' mean luminance. Smooth shading varies little over 9 pixels; fine-scale bumps that
//! break a sheen up raise it. The background is left out of the box: at a silhouette it would
//! pull the average toward 0 and count the outline as contrast, which smooth shading has too.

use serde::Serialize;

/// The brightest part of the covered pixels taken as the highlight: 5 % (issue 41's measure).
pub const HIGHLIGHT_FRACTION: f64 = 0.05;

/// Side of the box the local contrast compares each pixel with (odd).
pub const CONTRAST_BOX: usize = 9;

/// The lobes' part of a render's highlights.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpecularShare {
    /// Pixels the surface covers (luminance above 0 with the lobes).
    pub covered: usize,
    /// Highlight pixels measured (the brightest `HIGHLIGHT_FRACTION` of `covered`, at least 1).
    pub highlight: usize,
    /// Mean over the highlight pixels of the lobes' share of the pixel's luminance.
    pub mean: f64,
    /// Median of the same.
    pub median: f64,
    /// The lobes' share of all the covered pixels' summed luminance.
    pub overall: f64,
    /// Local contrast of the lobes' luminance on the highlight pixels (see the module docs).
    pub local_contrast: f64,
}

/// Errors from comparing two renders.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShareError {
    /// The renders differ in pixel count, are not RGB triples or not `width` wide.
    #[error("renders of {with} and {without} samples cannot be compared (same size, RGB, whole rows needed)")]
    Size {
        /// Samples of the render with lobes.
        with: usize,
        /// Samples of the render without.
        without: usize,
    },
    /// The render with lobes has no lit pixel.
    #[error("the render with lobes has no lit pixel")]
    Empty,
}

/// Linear luminance (Rec. 709 / sRGB primaries).
pub fn luminance(rgb: &[f32]) -> f64 {
    0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64
}

/// Compares `with` (lobes on) and `without` (lobes off): linear RGB samples, 3 per pixel, rows
/// `width` pixels long, the same scene, camera and size.
///
/// # Errors
/// When the sizes differ or no pixel of `with` is lit.
pub fn specular_share(with: &[f32], without: &[f32], width: usize) -> Result<SpecularShare, ShareError> {
    if with.len() != without.len() || width == 0 || !with.len().is_multiple_of(3 * width) {
        return Err(ShareError::Size { with: with.len(), without: without.len() });
    }
    let lum: Vec<f64> = with.chunks_exact(3).map(luminance).collect();
    let lobes: Vec<f64> = lum.iter().zip(without.chunks_exact(3)).map(|(a, b)| (a - luminance(b)).max(0.0)).collect();
    // Covered pixels, brightest first.
    let mut order: Vec<usize> = (0..lum.len()).filter(|&i| lum[i] > 0.0 && lum[i].is_finite()).collect();
    if order.is_empty() {
        return Err(ShareError::Empty);
    }
    let covered = order.len();
    let overall = order.iter().map(|&i| lobes[i]).sum::<f64>() / order.iter().map(|&i| lum[i]).sum::<f64>();
    let highlight = ((covered as f64 * HIGHLIGHT_FRACTION).round() as usize).max(1);
    order.sort_by(|&a, &b| lum[b].total_cmp(&lum[a]));
    let top = &order[..highlight];
    let mut shares: Vec<f64> = top.iter().map(|&i| lobes[i] / lum[i]).collect();
    shares.sort_by(f64::total_cmp);
    let mean = shares.iter().sum::<f64>() / highlight as f64;
    let covered_mask: Vec<bool> = lum.iter().map(|l| *l > 0.0 && l.is_finite()).collect();
    let boxed = box_mean(&lobes, &covered_mask, width, CONTRAST_BOX / 2);
    let lobes_mean = top.iter().map(|&i| lobes[i]).sum::<f64>() / highlight as f64;
    let deviation = top.iter().map(|&i| (lobes[i] - boxed[i]).abs()).sum::<f64>() / highlight as f64;
    let local_contrast = if lobes_mean > 0.0 { deviation / lobes_mean } else { 0.0 };
    Ok(SpecularShare { covered, highlight, mean, median: median(&shares), overall, local_contrast })
}

/// The mean over each pixel's `(2 r + 1)^2` box of the values whose `mask` is set, clamped at
/// the image's edges (summed-area tables of the values and of the count, in f64); 0 where the
/// box holds no masked pixel.
fn box_mean(values: &[f64], mask: &[bool], width: usize, r: usize) -> Vec<f64> {
    let height = values.len() / width;
    let stride = width + 1;
    let (mut sum, mut count) = (vec![0.0; stride * (height + 1)], vec![0.0; stride * (height + 1)]);
    for y in 0..height {
        let (mut row, mut row_count) = (0.0, 0.0);
        for x in 0..width {
            let i = y * width + x;
            if mask[i] {
                row += values[i];
                row_count += 1.0;
            }
            sum[(y + 1) * stride + x + 1] = sum[y * stride + x + 1] + row;
            count[(y + 1) * stride + x + 1] = count[y * stride + x + 1] + row_count;
        }
    }
    let rect = |t: &[f64], x0: usize, y0: usize, x1: usize, y1: usize| {
        t[y1 * stride + x1] - t[y1 * stride + x0] - t[y0 * stride + x1] + t[y0 * stride + x0]
    };
    (0..values.len())
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let (x0, x1) = (x.saturating_sub(r), (x + r + 1).min(width));
            let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(height));
            let n = rect(&count, x0, y0, x1, y1);
            if n > 0.0 { rect(&sum, x0, y0, x1, y1) / n } else { 0.0 }
        })
        .collect()
}

/// Median of sorted values (the mean of the middle two for an even count).
fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    if n % 2 == 1 { sorted[n / 2] } else { 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(values: &[f32]) -> Vec<f32> {
        values.iter().flat_map(|&v| [v, v, v]).collect()
    }

    #[test]
    fn hand_computed_share() {
        // 40 covered pixels, 2 highlight pixels (5 %): 10 (half specular) and 8 (a quarter),
        // the rest 1 with no specular; 5 background pixels.
        let mut with = vec![0.0; 5];
        let mut without = vec![0.0; 5];
        with.extend([10.0, 8.0]);
        without.extend([5.0, 6.0]);
        with.extend([1.0; 38]);
        without.extend([1.0; 38]);
        let s = specular_share(&grey(&with), &grey(&without), 45).unwrap();
        assert_eq!((s.covered, s.highlight), (40, 2));
        assert!((s.mean - 0.375).abs() < 1e-12, "{s:?}");
        assert!((s.median - 0.375).abs() < 1e-12, "{s:?}");
        assert!((s.overall - 7.0 / 56.0).abs() < 1e-12, "{s:?}");
        // One row: the 9-box around pixel 5 (lobes 5) holds pixels 1-9, of which 5-9 are
        // covered, lobes 5 + 2 = 7, mean 7/5; around pixel 6 (lobes 2) pixels 2-10, covered 5-10,
        // mean 7/6. Deviations 18/5 and 5/6 over the lobes' mean 3.5.
        let expected = (18.0 / 5.0 + 5.0 / 6.0) / 2.0 / 3.5;
        assert!((s.local_contrast - expected).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn luminance_weights_the_channels() {
        let with = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let without = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let s = specular_share(&with, &without, 1).unwrap();
        // The green pixel is the brighter one (0.7152) and has no specular.
        assert_eq!((s.highlight, s.mean), (1, 0.0));
        assert!((s.overall - 0.2126 / (0.2126 + 0.7152)).abs() < 1e-9);
    }

    #[test]
    fn box_mean_against_a_direct_sum() {
        let (w, h, r) = (7, 5, 2);
        let values: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 11) as f64).collect();
        // A hole and a masked-out corner: only masked pixels count.
        let mask: Vec<bool> = (0..w * h).map(|i| i % 5 != 0 && i != 8).collect();
        let fast = box_mean(&values, &mask, w, r);
        for y in 0..h {
            for x in 0..w {
                let (mut sum, mut n) = (0.0, 0);
                for yy in y.saturating_sub(r)..(y + r + 1).min(h) {
                    for xx in x.saturating_sub(r)..(x + r + 1).min(w) {
                        if mask[yy * w + xx] {
                            sum += values[yy * w + xx];
                            n += 1;
                        }
                    }
                }
                let direct = if n > 0 { sum / n as f64 } else { 0.0 };
                assert!((fast[y * w + x] - direct).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn refuses_mismatched_or_dark_renders() {
        assert!(matches!(specular_share(&[1.0; 6], &[1.0; 3], 1), Err(ShareError::Size { .. })));
        assert!(matches!(specular_share(&[1.0; 6], &[1.0; 6], 4), Err(ShareError::Size { .. })));
        assert!(matches!(specular_share(&[0.0; 6], &[0.0; 6], 2), Err(ShareError::Empty)));
    }
}
