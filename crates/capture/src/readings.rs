//! The rules both solvers, distant ([`crate::solve`]) and near ([`crate::near`]), apply to a
//! pixel's readings, kept in one place: which readings are dropped (shadowed, by the one rule
//! of [`Shadows`], or saturated), how RGB readings combine into the one the normal comes from
//! ([`LUMA`]), which `|g|` still defines a normal ([`MIN_ALBEDO`]), how the condition number of
//! a set of lights is measured (`condition_of`) and how per-band counts are merged
//! ([`SolveStats`]).
//!
//! The distant solver's vectorised kernels (`solve/fused.rs`) apply the same rules with the
//! same operations, lane by lane; its unit tests compare them bitwise with the scalar paths
//! that call these functions.

use nalgebra::Matrix3;

/// Rec. 709 luminance weights: how RGB readings combine into the one used for the normal (and
/// how a grey photo is divided by an RGB light intensity).
pub const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Smallest `|g|` (albedo as a fraction of full scale per unit light) that still defines a normal.
pub const MIN_ALBEDO: f32 = 1e-6;

/// Whether a solved `|g|` defines a normal: above [`MIN_ALBEDO`] and finite (NaN does not).
#[inline(always)]
pub(crate) fn defines_normal<F: Into<f64>>(len: F) -> bool {
    let len = len.into();
    len > MIN_ALBEDO as f64 && len < f64::INFINITY
}

/// Default absolute shadow floor ([`Shadows::abs`]).
pub const SHADOW_ABS: f32 = 0.005;
/// Default relative shadow threshold ([`Shadows::rel`]).
pub const SHADOW_REL: f32 = 0.1;

/// The one shadow rule of every solver (least squares aside): a reading `r_i` is shadowed when
/// `r_i < max(abs, rel * q90)`, below an absolute floor and also far below the pixel's own
/// reference reading `q90`, the 90th percentile of its usable (finite, unsaturated) readings
/// (`shadow_reference`). The 90th percentile rather than the brightest, so that a few
/// highlights do not raise the threshold; with up to 9 usable readings the two are the same.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shadows {
    /// Absolute floor, as a fraction of full scale after ambient subtraction and division by the
    /// light's intensity.
    pub abs: f32,
    /// Fraction of the pixel's reference reading.
    pub rel: f32,
}

impl Default for Shadows {
    fn default() -> Self {
        Shadows { abs: SHADOW_ABS, rel: SHADOW_REL }
    }
}

/// 0-based ascending rank, among `usable` readings, of the reference reading of the relative
/// shadow threshold (the 90th percentile, rounded up: the brightest for up to 9 readings).
#[inline(always)]
pub(crate) fn reference_rank(usable: usize) -> usize {
    (usable * 9).div_ceil(10).saturating_sub(1)
}

/// Whether the reference reading of up to `k` usable readings is always the brightest.
#[inline(always)]
pub(crate) fn reference_is_brightest(k: usize) -> bool {
    (1..=k).all(|m| reference_rank(m) == m - 1)
}

/// The reference reading of a pixel whose usable readings are `values` (reordered in place):
/// the one at [`reference_rank`]; negative infinity when there are none.
pub(crate) fn shadow_reference(values: &mut [f32]) -> f32 {
    if values.is_empty() {
        return f32::NEG_INFINITY;
    }
    let rank = reference_rank(values.len());
    *values.select_nth_unstable_by(rank, f32::total_cmp).1
}

/// The shadow threshold of a pixel whose reference reading is `reference`:
/// `max(abs, rel * reference)`. In f64; for f32 readings the result cast back to f32 is bit for
/// bit `abs.max(rel * reference)` in f32 (the product of two f32 values is exact in f64, so it is
/// rounded once either way), and a NaN or negative infinite `reference` gives `abs`.
#[inline(always)]
pub(crate) fn shadow_floor(shadows: Shadows, reference: f64) -> f64 {
    (shadows.abs as f64).max(shadows.rel as f64 * reference)
}

/// The raw stored value at or above which a reading is saturated, for samples of `full_scale`
/// and a solve's `saturation` fraction ([`crate::solve::SolveConfig::saturation`]; any channel,
/// before ambient subtraction).
#[inline(always)]
pub(crate) fn saturation_level(saturation: f32, full_scale: f32) -> f32 {
    saturation * full_scale
}

/// `sigma_max / sigma_min` of a direction matrix `L` from its Gram matrix `L^T L` (infinite when
/// singular): the condition number [`crate::solve::SolveConfig::max_condition`] bounds, for a subset of a rig's
/// lights (distant) or a pixel's own light directions (near).
pub(crate) fn condition_of(gram: &Matrix3<f64>) -> f64 {
    let eig = gram.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if lo > hi * 1e-15 && lo > 0.0 { (hi / lo).sqrt() } else { f64::INFINITY }
}

/// Counts gathered during a solve.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Texels in the map.
    pub pixels: usize,
    /// Texels with no normal (masked out, too few lights, ill-conditioned, black).
    pub invalid_count: usize,
    /// Texels outside the mask.
    pub masked_count: usize,
    /// `lights_used[m]`: unmasked texels with `m` usable readings (`len = k + 1`).
    pub lights_used: Vec<usize>,
}

impl SolveStats {
    /// No texels yet, for a rig of `k` lights.
    pub(crate) fn empty(k: usize) -> Self {
        SolveStats { lights_used: vec![0; k + 1], ..SolveStats::default() }
    }

    /// The counts of two disjoint sets of texels together.
    pub(crate) fn merge(mut self, other: SolveStats) -> Self {
        self.pixels += other.pixels;
        self.invalid_count += other.invalid_count;
        self.masked_count += other.masked_count;
        for (a, b) in self.lights_used.iter_mut().zip(other.lights_used) {
            *a += b;
        }
        self
    }
}
