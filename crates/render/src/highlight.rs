//! How much of a render's highlights the specular lobes make (issue 13): the same scene drawn
//! twice into linear radiance, once with the Lafortune lobes and once with `lobes = []`, compared
//! pixel by pixel. The difference is exactly the lobes' radiance, because the base pass adds the
//! lobes to the diffuse term before the (linear) sum over lights and nothing else depends on them.
//!
//! Highlight pixels are the brightest [`HIGHLIGHT_FRACTION`] of the pixels the surface covers
//! (luminance of the render with lobes, Rec. 709 weights; background pixels are 0 in both
//! renders and never count). For them [`SpecularShare`] gives the mean and median of
//! `(with - without) / with`, the share of each highlight pixel's luminance the lobes make, and
//! the relative spread of the lobes' radiance there (standard deviation over mean), which is what
//! the fine-scale bumps raise when they break a sheen up.

use serde::Serialize;

/// The brightest part of the covered pixels taken as the highlight: 2 %.
pub const HIGHLIGHT_FRACTION: f64 = 0.02;

/// The lobes' part of a render's highlights.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SpecularShare {
    /// Pixels the surface covers (luminance above 0 with the lobes).
    pub covered: usize,
    /// Highlight pixels measured (the brightest [`HIGHLIGHT_FRACTION`] of `covered`, at least 1).
    pub highlight: usize,
    /// Mean over the highlight pixels of the lobes' share of the pixel's luminance.
    pub mean: f64,
    /// Median of the same.
    pub median: f64,
    /// The lobes' share of all the covered pixels' summed luminance.
    pub overall: f64,
    /// Standard deviation over mean of the lobes' luminance on the highlight pixels.
    pub specular_spread: f64,
}

/// Errors from comparing two renders.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ShareError {
    /// The renders differ in pixel count or are not RGB triples.
    #[error("renders of {with} and {without} samples cannot be compared (same size, RGB, needed)")]
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

/// Compares `with` (lobes on) and `without` (lobes off): linear RGB samples, 3 per pixel, the
/// same scene, camera and size.
///
/// # Errors
/// When the sizes differ or no pixel of `with` is lit.
pub fn specular_share(with: &[f32], without: &[f32]) -> Result<SpecularShare, ShareError> {
    if with.len() != without.len() || with.len() % 3 != 0 {
        return Err(ShareError::Size { with: with.len(), without: without.len() });
    }
    // (luminance with, luminance of the lobes) per covered pixel.
    let mut pixels: Vec<(f64, f64)> = with
        .chunks_exact(3)
        .zip(without.chunks_exact(3))
        .map(|(a, b)| (luminance(a), luminance(b)))
        .filter(|&(a, _)| a > 0.0 && a.is_finite())
        .map(|(a, b)| (a, (a - b).max(0.0)))
        .collect();
    if pixels.is_empty() {
        return Err(ShareError::Empty);
    }
    let covered = pixels.len();
    let overall = pixels.iter().map(|p| p.1).sum::<f64>() / pixels.iter().map(|p| p.0).sum::<f64>();
    let highlight = ((covered as f64 * HIGHLIGHT_FRACTION).round() as usize).max(1);
    pixels.sort_by(|a, b| b.0.total_cmp(&a.0));
    let top = &pixels[..highlight];
    let mut shares: Vec<f64> = top.iter().map(|&(a, s)| s / a).collect();
    shares.sort_by(f64::total_cmp);
    let mean = shares.iter().sum::<f64>() / highlight as f64;
    let specular_mean = top.iter().map(|p| p.1).sum::<f64>() / highlight as f64;
    let variance = top.iter().map(|p| (p.1 - specular_mean).powi(2)).sum::<f64>() / highlight as f64;
    let specular_spread = if specular_mean > 0.0 { variance.sqrt() / specular_mean } else { 0.0 };
    Ok(SpecularShare { covered, highlight, mean, median: median(&shares), overall, specular_spread })
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
        // 100 covered pixels, 2 highlight pixels: 10 (half specular) and 8 (a quarter), the
        // rest 1 with no specular; 5 background pixels.
        let mut with = vec![0.0; 5];
        let mut without = vec![0.0; 5];
        with.extend([10.0, 8.0]);
        without.extend([5.0, 6.0]);
        with.extend([1.0; 98]);
        without.extend([1.0; 98]);
        let s = specular_share(&grey(&with), &grey(&without)).unwrap();
        assert_eq!((s.covered, s.highlight), (100, 2));
        assert!((s.mean - 0.375).abs() < 1e-12, "{s:?}");
        assert!((s.median - 0.375).abs() < 1e-12, "{s:?}");
        assert!((s.overall - 7.0 / 116.0).abs() < 1e-12, "{s:?}");
        // Lobes 5 and 2: mean 3.5, standard deviation 1.5.
        assert!((s.specular_spread - 1.5 / 3.5).abs() < 1e-12, "{s:?}");
    }

    #[test]
    fn luminance_weights_the_channels() {
        let with = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let without = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let s = specular_share(&with, &without).unwrap();
        // The green pixel is the brighter one (0.7152) and has no specular.
        assert_eq!((s.highlight, s.mean), (1, 0.0));
        assert!((s.overall - 0.2126 / (0.2126 + 0.7152)).abs() < 1e-9);
    }

    #[test]
    fn refuses_mismatched_or_dark_renders() {
        assert!(matches!(specular_share(&[1.0; 6], &[1.0; 3]), Err(ShareError::Size { .. })));
        assert!(matches!(specular_share(&[0.0; 6], &[0.0; 6]), Err(ShareError::Empty)));
    }
}
