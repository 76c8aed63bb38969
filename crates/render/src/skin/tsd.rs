//! Texture-space diffusion's blur plan on the CPU: which passes run, what each one blurs by and
//! adds, and which light map each reads and writes. The GPU side is `pass/blur/`.
//!
//! - [`TsdKernel::Single`] (Gosselin et al. 2004): `passes` Poisson blurs of one kernel, sized so
//!   their variances add up to the profile's luminance variance, ping-ponged between two maps.
//! - [`TsdKernel::Gaussians`] (d'Eon and Luebke 2007): the profile `R = sum_i w_i G(v_i)` applied
//!   per channel. The first pass dilates and blurs the irradiance `E` by `v_1 - v_0`; that map,
//!   `B`, is kept (map B). The others run Horner's scheme from the widest Gaussian down:
//!   `T_5 = w_5 B`, `T_(i-1) = K_i T_i + w_(i-1) B` with `K_i` the blur by `v_i - v_(i-1)` in
//!   `passes` Poisson passes, and the last adds `(w_0 + w_1) B`, so the result is
//!   `sum_i w_i G(v_i) E` (the narrowest Gaussian, 0.08 mm, taken at the next one's 0.22 mm:
//!   both below a texel of a face's light map). Gaussian convolutions commute, so the order of
//!   the blurs does not change the sum.

use super::options::TsdKernel;
use super::poisson::{centred_taps, poisson_axis_variance, poisson_second_moment};
use super::profile::{VARIANCES_MM2, WEIGHTS};

/// The radius the light map's alpha stores for [`TsdKernel::Gaussians`], mm: each pass scales it
/// by [`BlurStage::scale`] (with the single kernel, alpha stores that kernel's own radius).
/// Alpha holds it over [`super::poisson::MAX_KERNEL_TEXELS`] and is clamped below 1, so it must fit
/// in 64 texels of the finest light map: 0.1 mm does down to 1.6 micrometres a texel. At 1 mm it
/// clamped on the 6 mm sphere, whose texels are 0.01-0.02 mm at 2048, and the error doubled there.
pub const GAUSSIANS_KERNEL_MM: f32 = 0.1;

/// Names of the light maps, by index.
pub(crate) const LIGHT_MAP_NAMES: [&str; 3] = ["light map A", "light map B", "light map C"];

/// The Gaussians blurred by the Horner stages (the profile's six less the two the first pass
/// covers).
const HORNER_STAGES: u32 = VARIANCES_MM2.len() as u32 - 2;

/// One blur pass as the GPU runs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlurStage {
    /// Multiplies the per-texel radius `a k + b` of the light map's alpha.
    pub scale: f32,
    /// The pass dilates into unwritten texels (the first).
    pub dilate: bool,
    /// Scales the blurred source, per channel.
    pub source_scale: [f32; 3],
    /// Weight of the dilated irradiance (map B) added after the blur, per channel.
    pub irradiance_weight: [f32; 3],
}

/// The blur passes `kernel` runs with `passes` (per Gaussian for [`TsdKernel::Gaussians`]; 0
/// runs none, so the light map is drawn unblurred).
pub(crate) fn blur_count(kernel: TsdKernel, passes: u32) -> u32 {
    match (kernel, passes) {
        (_, 0) => 0,
        (TsdKernel::Single, n) => n,
        (TsdKernel::Gaussians, n) => 1 + HORNER_STAGES * n,
    }
}

/// How many light maps `kernel` needs: two to ping-pong, a third to keep map B.
pub(crate) fn map_count(kernel: TsdKernel) -> usize {
    match kernel {
        TsdKernel::Single => 2,
        TsdKernel::Gaussians => 3,
    }
}

/// The light maps blur `i` reads and writes (indices into [`LIGHT_MAP_NAMES`]). The light-map
/// pass writes map A; blur 0 writes map B; the single kernel then ping-pongs A and B, the
/// Gaussians A and C (B is kept).
pub(crate) fn blur_maps(kernel: TsdKernel, i: u32) -> (usize, usize) {
    match (kernel, i) {
        (_, 0) => (0, 1),
        (TsdKernel::Single, i) => ((i % 2) as usize, ((i + 1) % 2) as usize),
        (TsdKernel::Gaussians, 1) => (1, 2),
        (TsdKernel::Gaussians, i) if i % 2 == 0 => (2, 0),
        (TsdKernel::Gaussians, _) => (0, 2),
    }
}

/// The light map the base pass reads after `blurs` blurs.
pub(crate) fn final_map(kernel: TsdKernel, blurs: u32) -> usize {
    if blurs == 0 { 0 } else { blur_maps(kernel, blurs - 1).1 }
}

/// Every blur pass of `kernel` with `passes`, in order.
pub fn stages(kernel: TsdKernel, passes: u32) -> Vec<BlurStage> {
    let plain = |dilate| BlurStage { scale: 1.0, dilate, source_scale: [1.0; 3], irradiance_weight: [0.0; 3] };
    match kernel {
        TsdKernel::Single => (0..passes).map(|i| plain(i == 0)).collect(),
        TsdKernel::Gaussians if passes == 0 => Vec::new(),
        TsdKernel::Gaussians => {
            let radius = |variance_mm2: f64| {
                (variance_mm2 as f32 / (poisson_second_moment() / 2.0)).sqrt() / GAUSSIANS_KERNEL_MM
            };
            let weight = |i: usize| WEIGHTS[i].map(|w| w as f32);
            let mut out = vec![BlurStage { scale: radius(VARIANCES_MM2[1] - VARIANCES_MM2[0]), ..plain(true) }];
            let last = VARIANCES_MM2.len() - 1;
            for g in (2..=last).rev() {
                let scale = radius((VARIANCES_MM2[g] - VARIANCES_MM2[g - 1]) / f64::from(passes));
                for p in 0..passes {
                    let mut stage = BlurStage { scale, ..plain(false) };
                    if g == last && p == 0 {
                        stage.source_scale = weight(last);
                    }
                    if p == passes - 1 {
                        stage.irradiance_weight = match g {
                            2 => std::array::from_fn(|c| weight(0)[c] + weight(1)[c]),
                            _ => weight(g - 1),
                        };
                    }
                    out.push(stage);
                }
            }
            out
        }
    }
}

/// Entries of [`radius_table`], for variances evenly spaced over `[0, RADIUS_TABLE_MAX_VARIANCE]`.
pub const RADIUS_TABLE_LEN: usize = 64;

/// The largest per-axis variance, texels^2, that [`radius_table`] covers; above it the sampler's
/// share is its mean, 1/6, to 0.6 % ([`radius_for_variance`]).
pub const RADIUS_TABLE_MAX_VARIANCE: f32 = 4.0;

/// The variance along `axis` (0: u, 1: v), in texels^2, that one bilinear blur pass of the 13
/// centred taps adds when its disc's radius along that axis is `radius` texels.
///
/// A tap at offset `o` texels from the texel centre it is drawn for mixes the texels `floor(o)`
/// and `floor(o) + 1` with weights `1 - f` and `f` (`f` the fraction of `o`): its mean is `o` and
/// its second moment `o^2 + f (1 - f)`. The taps' mean is 0, so the pass's variance is the taps'
/// mean of that. Below a texel the sampler's share `f (1 - f)`, linear in the radius, is most of
/// it; far above, it averages 1/6.
pub fn pass_variance(radius: f32, axis: usize) -> f32 {
    let sum: f64 = centred_taps(axis)
        .map(|p| f64::from(radius * p))
        .map(|o| {
            let f = o - o.floor();
            o * o + f * (1.0 - f)
        })
        .sum();
    (sum / 13.0) as f32
}

/// The radius along `axis`, texels, at which a bilinear pass adds `variance` texels^2 along it:
/// [`pass_variance`] inverted by bisection (it rises with the radius).
fn exact_radius(variance: f32, axis: usize) -> f32 {
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    while pass_variance(hi, axis) < variance {
        hi *= 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if pass_variance(mid, axis) < variance { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// The bilinear pass's radius for a variance, per axis: entry `i` holds the radii along u and v for
/// the variance `i / (RADIUS_TABLE_LEN - 1) * RADIUS_TABLE_MAX_VARIANCE`, two entries per `vec4`
/// as the blur's uniforms carry them. Linear interpolation in it is within 0.9 % of the variance.
pub fn radius_table() -> [[f32; 4]; RADIUS_TABLE_LEN / 2] {
    let entry = |i: usize, axis| exact_radius(table_variance(i), axis);
    std::array::from_fn(|j| [entry(2 * j, 0), entry(2 * j, 1), entry(2 * j + 1, 0), entry(2 * j + 1, 1)])
}

fn table_variance(i: usize) -> f32 {
    i as f32 / (RADIUS_TABLE_LEN - 1) as f32 * RADIUS_TABLE_MAX_VARIANCE
}

/// The radius along `axis` a bilinear pass is given for `variance` texels^2, as the blur shader
/// computes it: interpolated in `table` ([`radius_table`]) up to its end, above it the disc's
/// own variance plus the sampler's mean share of 1/6.
pub fn radius_for_variance(table: &[[f32; 4]; RADIUS_TABLE_LEN / 2], variance: f32, axis: usize) -> f32 {
    if variance >= RADIUS_TABLE_MAX_VARIANCE {
        return ((variance - 1.0 / 6.0) / poisson_axis_variance()[axis]).sqrt();
    }
    let x = variance.max(0.0) / RADIUS_TABLE_MAX_VARIANCE * (RADIUS_TABLE_LEN - 1) as f32;
    let i = (x as usize).min(RADIUS_TABLE_LEN - 2);
    let at = |i: usize| table[i / 2][(i % 2) * 2 + axis];
    let t = x - i as f32;
    at(i) + (at(i + 1) - at(i)) * t
}
