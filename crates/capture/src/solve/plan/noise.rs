//! The image's own noise floor, for [`Method::Robust`](crate::solve::Method::Robust) (issue 39).
//!
//! The robust solve keeps a pixel's least-squares answer when its relative residual
//! `rho = |r - L g| / |r|` is small enough that there is nothing to reject. A fixed gate
//! ([`crate::robust::AGREEMENT`], 2 %) sits under the residual that sensor noise alone leaves
//! from about 1 % noise on: every pixel then falls to the rank-trimmed fit, which throws away
//! good readings and loses to least squares. So before solving, the noise is measured on a
//! sample of rows (deterministic: evenly spaced rows, in order) in two independent ways:
//!
//! * **Residuals.** With `nu = k - 3` degrees of freedom, a Lambertian pixel under Gaussian noise
//!   has `|r - L g|^2 ~ sigma^2 chi^2(nu)`. The median over the sampled all-lights pixels, divided
//!   by the chi-square median, estimates `sigma^2`; any model error (highlights, inter-reflection)
//!   only raises it.
//! * **Second differences.** Along a row, `r[x-1] - 2 r[x] + r[x+1]` of independent noise has
//!   variance `6 sigma^2`; its median absolute value over pixels and lights, divided by
//!   `0.6745 sqrt(6)` (MAD to sigma), estimates `sigma`; fine texture only raises it.
//!
//! Both over-estimate, in different situations (non-Lambertian objects and textured ones), so
//! the smaller is taken. The gate becomes `max(AGREEMENT, sigma_rel sqrt(chi^2_0.995(nu)))`,
//! with `sigma_rel` the noise relative to a pixel's `|r|` (median over the sample): 99.5 % of
//! Lambertian pixels pass at that noise (99.9 % cost DiLiGenT cat 0.06 degrees more at 8 lights
//! and gained under 0.01 on the noise sweep; 99 % left 4 lights at 1.027x least squares). The
//! absolute `sigma` floors the robust fit's residual
//! scale ([`RobustConfig::noise_floor`](crate::robust::RobustConfig::noise_floor)), so its inlier
//! test never rejects a reading for noise alone. Chi-square quantiles by Wilson and Hilferty
//! (1931): `nu (1 - 2/(9 nu) + z sqrt(2/(9 nu)))^3`.

use super::Plan;
use crate::solve::chunk::Scratch;
use crate::solve::{CHUNK, NoiseFloor, RESIDUAL_SCALE};

/// Rows sampled for the estimate (evenly spaced), at most.
const SAMPLE_ROWS: usize = 64;
/// Most sampled pixels (every few pixels of the sampled rows), so the estimate's memory is a
/// few hundred KiB whatever the image size.
const MAX_SAMPLES: usize = 16384;
/// Fewest sampled pixels for an estimate; fewer keep the fixed gate.
const MIN_SAMPLES: usize = 64;
/// Normal quantile of the gate: 99.5 % of noise-only pixels pass.
const GATE_Z: f64 = 2.576;
/// Median absolute deviation of a standard normal.
const MAD_NORMAL: f64 = 0.6745;

/// Wilson-Hilferty quantile of chi-square with `nu` degrees of freedom at normal quantile `z`.
pub(crate) fn chi2_quantile(nu: f64, z: f64) -> f64 {
    let a = 2.0 / (9.0 * nu);
    nu * (1.0 - a + z * a.sqrt()).powi(3).max(0.0)
}

/// The gate for relative noise `relative` with `nu` degrees of freedom, at least `agreement`.
pub(crate) fn gate_for(relative: f64, nu: f64, agreement: f32) -> f32 {
    ((relative * chi2_quantile(nu, GATE_Z).sqrt()) as f32).max(agreement)
}

/// Median of `v` (reordered), `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    if v.is_empty() {
        return None;
    }
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// Samples gathered over the rows: per all-lights pixel its residual `|r - L g|^2` and `|r|^2`,
/// per interior pixel one light's absolute second difference, and the same over the pixel's `|r|`.
#[derive(Default)]
struct Samples {
    residual: Vec<f64>,
    rr: Vec<f64>,
    curvature: Vec<f64>,
    curvature_rel: Vec<f64>,
}

impl Plan<'_> {
    /// Measures the noise floor of the stack on up to [`SAMPLE_ROWS`] rows; `None` with 3 lights
    /// (no residual) or too few usable pixels.
    pub(in crate::solve) fn noise_floor(&self, height: usize, agreement: f32) -> Option<NoiseFloor> {
        if self.k < 4 || height == 0 {
            return None;
        }
        let mut s = Scratch::new(self.k, self.rgb);
        let mut samples = Samples::default();
        let rows = SAMPLE_ROWS.min(height);
        let stride = (rows * self.width).div_ceil(MAX_SAMPLES);
        for t in 0..rows {
            let y = (2 * t + 1) * height / (2 * rows);
            let mut x = 0;
            while x < self.width {
                let n = CHUNK.min(self.width - x);
                self.sample_chunk(y * self.width + x, n, stride, &mut s, &mut samples);
                x += n;
            }
        }
        self.floor_of(samples, agreement)
    }

    /// Adds every `stride`-th pixel of the chunk of `n` pixels from `p` to `samples`: its
    /// residual, and the second difference of one light's readings (lights in turn).
    fn sample_chunk(&self, p: usize, n: usize, stride: usize, s: &mut Scratch, samples: &mut Samples) {
        self.load_readings(p, n, s);
        self.accumulate_readings(n, s);
        self.count_dropped(n, s);
        self.normalise_all(n, s);
        let inside = |j: usize| self.mask.is_none_or(|m| m[p + j]);
        for j in 0..n {
            if !(p + j).is_multiple_of(stride) || !inside(j) || s.dropped[j] > 0 || s.conf[j] <= 0.0 || s.rr[j] <= 0.0 {
                continue;
            }
            let rho2 = (RESIDUAL_SCALE * RESIDUAL_SCALE) as f64 * (1.0 / s.conf[j] as f64 - 1.0);
            samples.residual.push(rho2 * s.rr[j] as f64);
            samples.rr.push(s.rr[j] as f64);
            if j == 0 || j + 1 >= n || !inside(j - 1) || !inside(j + 1) {
                continue;
            }
            let norm = (s.rr[j] as f64).sqrt();
            let r = &s.r[((p + j) / stride % self.k) * CHUNK..];
            let d = (r[j - 1] - 2.0 * r[j] + r[j + 1]).abs() as f64;
            if d.is_finite() {
                samples.curvature.push(d);
                samples.curvature_rel.push(d / norm);
            }
        }
    }

    /// The noise floor of the gathered samples.
    fn floor_of(&self, mut samples: Samples, agreement: f32) -> Option<NoiseFloor> {
        if samples.residual.len() < MIN_SAMPLES {
            return None;
        }
        let nu = (self.k - 3) as f64;
        let chi_median = chi2_quantile(nu, 0.0);
        let mut relative: Vec<f64> = samples.residual.iter().zip(&samples.rr).map(|(e, r)| e / r).collect();
        let from_residual = (median(&mut samples.residual)? / chi_median).sqrt();
        let relative_residual = (median(&mut relative)? / chi_median).sqrt();
        let spread = MAD_NORMAL * 6f64.sqrt();
        let (sigma, rel) = match (median(&mut samples.curvature), median(&mut samples.curvature_rel)) {
            (Some(c), Some(cr)) => (from_residual.min(c / spread), relative_residual.min(cr / spread)),
            _ => (from_residual, relative_residual),
        };
        Some(NoiseFloor { sigma: sigma as f32, relative: rel as f32, gate: gate_for(rel, nu, agreement) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wilson-Hilferty against tabulated chi-square quantiles (Abramowitz and Stegun, table 26.8).
    #[test]
    fn chi_square_quantiles_match_the_tables() {
        for (nu, z, table) in
            [(1.0, 2.326, 6.635), (5.0, 2.326, 15.086), (13.0, 2.326, 27.688), (5.0, 2.576, 16.750), (5.0, 0.0, 4.351)]
        {
            let q = chi2_quantile(nu, z);
            assert!((q - table).abs() / table < 0.02, "nu {nu} z {z}: {q} against {table}");
        }
    }

    #[test]
    fn the_gate_never_drops_under_the_agreement() {
        assert_eq!(gate_for(0.0, 5.0, 0.02), 0.02);
        let g = gate_for(0.02, 5.0, 0.02);
        // chi-square(5) at 0.995 is 16.750 (tables).
        assert!((g as f64 - 0.02 * 16.750f64.sqrt()).abs() < 2e-3, "{g}");
    }

    #[test]
    fn the_median_is_the_middle_value() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(&mut []), None);
    }
}
