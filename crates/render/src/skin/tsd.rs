//! Texture-space diffusion's blur plan on the CPU: which passes run, what each one blurs by and
//! adds, and which light map each reads and writes. The GPU side is `pass/blur.rs`.
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
use super::profile::{VARIANCES_MM2, WEIGHTS};
use crate::passes::poisson_second_moment;

/// The radius the light map's alpha stores for [`TsdKernel::Gaussians`], mm: each pass scales it
/// by [`BlurStage::scale`] (with the single kernel, alpha stores that kernel's own radius).
pub const GAUSSIANS_KERNEL_MM: f32 = 1.0;

/// Names of the light maps, by index.
pub const LIGHT_MAP_NAMES: [&str; 3] = ["light map A", "light map B", "light map C"];

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
pub fn blur_count(kernel: TsdKernel, passes: u32) -> u32 {
    match (kernel, passes) {
        (_, 0) => 0,
        (TsdKernel::Single, n) => n,
        (TsdKernel::Gaussians, n) => 1 + HORNER_STAGES * n,
    }
}

/// How many light maps `kernel` needs: two to ping-pong, a third to keep map B.
pub fn map_count(kernel: TsdKernel) -> usize {
    match kernel {
        TsdKernel::Single => 2,
        TsdKernel::Gaussians => 3,
    }
}

/// The light maps blur `i` reads and writes (indices into [`LIGHT_MAP_NAMES`]). The light-map
/// pass writes map A; blur 0 writes map B; the single kernel then ping-pongs A and B, the
/// Gaussians A and C (B is kept).
pub fn blur_maps(kernel: TsdKernel, i: u32) -> (usize, usize) {
    match (kernel, i) {
        (_, 0) => (0, 1),
        (TsdKernel::Single, i) => ((i % 2) as usize, ((i + 1) % 2) as usize),
        (TsdKernel::Gaussians, 1) => (1, 2),
        (TsdKernel::Gaussians, i) if i % 2 == 0 => (2, 0),
        (TsdKernel::Gaussians, _) => (0, 2),
    }
}

/// The light map the base pass reads after `blurs` blurs.
pub fn final_map(kernel: TsdKernel, blurs: u32) -> usize {
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
