//! Per-pixel photometric-stereo solves (Haro et al. 2001, section 3, equation 1).
//!
//! Each pixel seen under k >= 3 lights gives `albedo * E_i * (n . L_i) = I_i`. Writing
//! `g = albedo * n` and `r_i = I_i / E_i` (the reading divided by the light's intensity, after
//! ambient subtraction, as a fraction of full scale), the readings are linear in `g`: `L g = r`.
//!
//! * [`Method::LeastSquares`] is the paper's solve: one 3 x k pseudo-inverse `P = (L^T L)^-1 L^T`
//!   serves every pixel. It is computed once in f64 and applied in f32, with the per-light
//!   intensity division and the integer-to-linear scale folded into it
//!   (`P'_ji = P_ji / (full_scale E_i)`), so the kernel is a 3 x k matrix-vector product on the
//!   raw samples. Pixels are processed in bands of rows in parallel and, within a row, in chunks
//!   of [`CHUNK`] pixels laid out structure-of-arrays so the loops vectorise (compiled twice:
//!   portable and, chosen at run time, AVX2 + FMA; both use `mul_add`, so both give the same
//!   bits). 8-bit and 16-bit sRGB photos go through a lookup table instead of the folded scale.
//!   With AVX2 + FMA, linear grey photos without an ambient frame (the common case) take a fused
//!   kernel instead (`fused::step`): 16 pixels at a time from the samples to the interleaved
//!   output in registers, the same operations in the same order as the chunk path, so the bits
//!   still match the portable build. When all lights have the same intensity, the per-light
//!   scale is taken out of `sum r^2` (one multiplication per reading fewer, in both builds).
//! * [`Method::Robust`] (the default) drops readings exactly as [`Method::Threshold`] below and
//!   solves least squares on the rest, by the same paths (all lights when nothing is dropped;
//!   otherwise the cached subset pseudo-inverses, grouped and vectorised). That answer stands
//!   where its relative residual is within [`crate::robust::AGREEMENT`] (2 %), widened to what the
//!   image's own sensor noise leaves (measured on a sample of rows before solving, `plan/noise.rs`,
//!   reported as [`Solution::noise`]): the lit readings agree with one Lambertian normal. Only the other pixels are fitted by
//!   [`crate::robust::fit_pixel`] from their loaded readings (`plan/fit.rs`; the fused kernel hands
//!   such steps to the chunk path), so a cast shadow costs what it costs the threshold solve and
//!   only highlights, inter-reflections and the like pay for the per-pixel fit.
//! * [`Method::Threshold`] drops, per pixel, the readings that are shadowed or
//!   saturated and solves from the remaining lights with the pseudo-inverse of that subset.
//!   A reading is *shadowed* by the one rule of [`crate::readings::Shadows`]:
//!   `r_i < max(shadow_abs, shadow_rel * q90)`, `q90` the pixel's 90th-percentile usable reading
//!   (its brightest for up to 9 lights): below an absolute floor and also far below the pixel's
//!   own bright readings (a cast shadow on a bright pixel is far above the noise floor but far
//!   below its neighbours in the stack). A
//!   reading is *saturated* when its raw stored value is at or above `saturation * full_scale`
//!   (any channel, before ambient subtraction). Subset pseudo-inverses are cached per bitmask:
//!   a dense lazily filled table for k <= [`DENSE_MAX_LIGHTS`], a per-worker map capped at
//!   [`SolveConfig::cache_capacity`] entries (cleared when full) above that. Entries are pure
//!   functions of the bitmask, so results never depend on the cache or the thread count.
//!   Pixels with all readings usable take the vectorised least-squares result unchanged; in the
//!   fused kernel a step of 16 pixels is solved in registers unless one of its readings is
//!   dropped (a reading is below the threshold iff the pixel's dimmest one is). Shadows are
//!   spatially coherent, so a step whose 16 pixels all drop the same readings is solved in
//!   registers too, with that subset's columns (`fused::subset_step`; up to 9 lights, where the
//!   reference reading is the brightest); other such steps go
//!   through the chunk path. There, with k <= [`DENSE_MAX_LIGHTS`], the pixels that drop
//!   readings are grouped by subset and each group is solved with its subset's columns
//!   (`Plan::finish_subsets`); with more lights, one pixel at a time. All three subset paths
//!   use the same operations in the same order (`g = g + c_i r_i` over the used lights, no
//!   fused multiply-add; `n = g / |g|`), so they give the same bits.
//!
//! RGB photos: the normal comes from the luminance-weighted (Rec. 709) sum of the
//! intensity-divided channels; then each channel's albedo is the least-squares fit
//! `sum_i r_ci (n . L_i) / sum_i (n . L_i)^2` over the lights used. Grey photos give `|g|` as the
//! albedo, one value per texel ([`AlbedoMap::Gray`]; a grey photo is divided by the luminance of
//! each light's intensity).
//!
//! Confidence, in [0, 1], is 0 for invalid pixels and otherwise the product of
//! * the fraction of the rig's lights used,
//! * `min(1, cond(L_all) / cond(L_used))`, how much worse the used subset is conditioned, and
//! * `1 / (1 + (rho / 0.1)^2)` with `rho` the relative residual `|r - L g| / |r|` over the lights
//!   used (a Lambertian, noise-free pixel has `rho = 0`; 10% residual halves the confidence).
//!
//! With least squares the first two factors are 1.
//!
//! Every pixel is computed by the same arithmetic whatever the thread count or cache state, so
//! results are bitwise deterministic. Non-finite or all-black readings give invalid pixels
//! (`(0, 0, 0)` normal, zero albedo and confidence), never NaN. [`solve_into`] reuses the maps of
//! an earlier solution (large fresh maps cost a page fault per 4 KiB, which dominates the solve).

//!
//! The module's files follow its seams, each depending only on those listed before it (no module
//! circles, issue 38): [`PhotoStack`] (`stack.rs`), the parameters (`config.rs`), subset
//! pseudo-inverses (`subsets.rs`), stored samples to readings (`sources.rs`), the results and the
//! fresh maps they are written into (`solution.rs`), the chunk kernels and their scratch buffers
//! (`chunk.rs`), the fused AVX2 kernel (`fused.rs`), the per-solve plan and its all-lights chunk
//! path (`plan.rs`) with the parts that extend it: the robust fit (`plan/fit.rs`), its noise
//! floor (`plan/noise.rs`) and the paths of pixels that drop readings (`plan/finish.rs`); and the
//! unit tests (`tests.rs`).

mod chunk;
mod config;
#[cfg(target_arch = "x86_64")]
mod fused;
mod plan;
mod solution;
mod sources;
mod stack;
mod subsets;
#[cfg(test)]
mod tests;

use glam::Vec3;
use skinkit_maps::{Grid, NormalMap, Transfer};

pub use crate::readings::SolveStats;
use crate::readings::{LUMA, MIN_ALBEDO};
pub use config::{Method, NoProgress, Progress, SolveConfig};
use plan::Plan;
pub(crate) use solution::fresh_zeroed_vec3;
pub use solution::{AlbedoMap, NoiseFloor, Solution};
pub use stack::PhotoStack;

use crate::{Error, Result, Rig};

/// Pixels per structure-of-arrays chunk in the kernels.
pub const CHUNK: usize = 64;
/// Most lights a rig may have (subsets are `u128` bitmasks).
pub const MAX_LIGHTS: usize = skinkit_maps::limits::MAX_LIGHTS;
/// Rigs with at most this many lights cache every subset in a dense `2^k` table.
pub const DENSE_MAX_LIGHTS: usize = 12;
/// Rows per parallel work item.
pub(super) const BAND_ROWS: usize = 8;
/// Relative residual at which the residual factor of the confidence is 1/2.
pub(super) const RESIDUAL_SCALE: f32 = 0.1;

/// Solves for normals, albedo and confidence from `stack` lit by `rig`.
///
/// # Errors
/// [`Error::InvalidInput`] when the photo count differs from the rig's light count, the rig has
/// more than [`MAX_LIGHTS`] lights, or `config` is out of range; [`Error::BadRig`] when the rig's
/// condition number exceeds `config.max_condition`.
pub fn solve(stack: &PhotoStack, rig: &Rig, config: &SolveConfig, progress: &dyn Progress) -> Result<Solution> {
    // Empty maps: `solve_into` allocates fresh ones of the right size and kind, untouched until
    // the parallel bands write them.
    let mut solution = Solution {
        normals: NormalMap::flat(0, 0),
        albedo: AlbedoMap::Gray(Grid::filled(0, 0, 0.0)),
        confidence: Grid::filled(0, 0, 0.0),
        stats: SolveStats::default(),
        noise: None,
    };
    solve_into(stack, rig, config, progress, &mut solution)?;
    Ok(solution)
}

/// [`solve`] into an existing solution, reusing its maps when they have the stack's size (for
/// repeated solves of large stacks: fresh maps cost a page fault per 4 KiB written).
///
/// # Errors
/// As [`solve`]; `out` is unchanged on error.
pub fn solve_into(
    stack: &PhotoStack,
    rig: &Rig,
    config: &SolveConfig,
    progress: &dyn Progress,
    out: &mut Solution,
) -> Result<()> {
    config.validate()?;
    let lights = check_rig(stack, rig)?;
    let table = srgb_table(stack);
    let mut plan = Plan::new(stack, rig, config, lights, table.as_deref())?;
    let noise = plan.adapt_to_noise(stack.height());
    plan.run(stack, progress, out);
    out.noise = noise;
    Ok(())
}

/// Unit light directions of `rig`, after checking it against the stack (a [`Rig`] is valid by
/// construction, so only the photo count and the solver's own light limit are left to check).
fn check_rig(stack: &PhotoStack, rig: &Rig) -> Result<Vec<Vec3>> {
    rig.expect_readings(stack.len())?;
    check_light_count(rig.light_count())?;
    Ok(solver_directions(rig))
}

/// Refuses more than [`MAX_LIGHTS`] lights.
///
/// # Errors
/// [`Error::InvalidInput`] with the count and the limit.
pub fn check_light_count(k: usize) -> Result<()> {
    if k > MAX_LIGHTS {
        return Err(Error::InvalidInput(format!("rig has {k} lights; at most {MAX_LIGHTS} are supported")));
    }
    Ok(())
}

/// The rig's unit directions as the solver holds them: `normalize` of the stored unit directions
/// (not a check: `Light::new` made them unit) keeps the f32 directions, and so every output bit,
/// the solver has always used.
fn solver_directions(rig: &Rig) -> Vec<Vec3> {
    rig.directions().into_iter().map(Vec3::normalize).collect()
}

/// The bit set of all `k` lights (`k <= MAX_LIGHTS`).
fn all_lights(k: usize) -> u128 {
    if k == 128 { u128::MAX } else { (1u128 << k) - 1 }
}

/// Refuses a rig of at most [`MAX_LIGHTS`] lights whose condition number, computed as the
/// distant-light solve computes it, exceeds `config.max_condition`: the one check `capture`
/// (before decoding anything) and `rig check` share with the solver.
///
/// # Errors
/// [`Error::InvalidInput`] for too many lights; [`Error::BadRig`] with the condition number and
/// the limit.
pub fn check_conditioning(rig: &Rig, config: &SolveConfig) -> Result<()> {
    check_light_count(rig.light_count())?;
    let lights = solver_directions(rig);
    let full = subsets::SubsetSolve::new(&lights, all_lights(lights.len()), config.max_condition);
    refuse_ill_conditioned(lights.len(), full.condition, full.usable, config.max_condition)
}

/// The refusal of a rig whose full light set is not usable (condition above the limit).
fn refuse_ill_conditioned(k: usize, condition: f64, usable: bool, max_condition: f64) -> Result<()> {
    if !usable {
        return Err(Error::BadRig(format!(
            "the rig's {k} lights cannot determine a normal (coplanar or nearly so): condition number {condition:.4} exceeds max_condition {max_condition} (--max-condition)"
        )));
    }
    Ok(())
}

/// A stored-value to linear table for 8- and 16-bit sRGB photos.
fn srgb_table(stack: &PhotoStack) -> Option<Vec<f32>> {
    let first = &stack.photos()[0];
    if first.transfer() != Transfer::Srgb || first.bit_depth() == 32 {
        return None;
    }
    let full = first.samples().full_scale();
    Some((0..=full as usize).map(|v| skinkit_maps::encoding::srgb_to_linear(v as f32 / full)).collect())
}
