//! The fused all-lights kernel (AVX2 + FMA) for linear grey photos without an ambient frame.
//!
//! Per step of [`STEP`] pixels (two 8-lane vectors, so each light's broadcast coefficients serve
//! 16 pixels) it loads every light's samples, converts them (exactly) to f32, accumulates `g` and
//! `sum w^2` in registers, normalises, and writes interleaved normals, albedo and confidence: one
//! pass over the samples and one over the outputs, no scratch round trips. The arithmetic is the
//! scalar path's operation for operation (`mul_add` is `vfmadd`, `sqrt` and `/` are exactly
//! rounded, `max` keeps the non-NaN operand as `f32::max` does), so both give the same bits; the
//! unit tests compare them bitwise.
use std::arch::x86_64::*;

use glam::Vec3;

use super::sources::{Raw, as_f32, as_u8, as_u16};
use super::{MIN_ALBEDO, RESIDUAL_SCALE};

/// Pixels per step.
pub(super) const STEP: usize = 16;

/// A stored sample type the kernel loads eight at a time.
pub(super) trait Lanes: Copy + Sync {
    /// The samples of a photo of this type.
    fn of(raw: Raw<'_>) -> &[Self];
    /// The 8 samples at `p`, as f32 (exact for all three types).
    ///
    /// # Safety
    /// `p` must be valid for reading 8 samples, and the CPU must support AVX2.
    unsafe fn load8(p: *const Self) -> __m256;
}

impl Lanes for u8 {
    fn of(raw: Raw<'_>) -> &[Self] {
        as_u8(raw)
    }
    #[inline(always)]
    unsafe fn load8(p: *const Self) -> __m256 {
        // SAFETY: 8 readable bytes at `p` (unaligned load), AVX2 present (caller).
        unsafe { _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(p.cast()))) }
    }
}

impl Lanes for u16 {
    fn of(raw: Raw<'_>) -> &[Self] {
        as_u16(raw)
    }
    #[inline(always)]
    unsafe fn load8(p: *const Self) -> __m256 {
        // SAFETY: 16 readable bytes at `p` (unaligned load), AVX2 present (caller).
        unsafe { _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm_loadu_si128(p.cast()))) }
    }
}

impl Lanes for f32 {
    fn of(raw: Raw<'_>) -> &[Self] {
        as_f32(raw)
    }
    #[inline(always)]
    unsafe fn load8(p: *const Self) -> __m256 {
        // SAFETY: 32 readable bytes at `p` (unaligned load), AVX (caller).
        unsafe { _mm256_loadu_ps(p) }
    }
}

/// What the kernel applies, per light and per pixel.
pub(super) struct Kernel<'a> {
    /// Column of the pseudo-inverse per light (folded with the sample scale for least squares).
    pub coefs: &'a [[f32; 3]],
    /// `w_i = x_i * scales[i]` enters `sum w^2` (the readings, for least squares; ones, and
    /// not applied, for robust, whose `x_i` are the readings).
    pub scales: &'a [f32],
    /// Whether `scales` are all ones.
    pub unit_scales: bool,
    /// Least squares: `sum w^2` is multiplied by this at the end.
    pub rr_post: f32,
    /// Robust only: sample to reading scale per light (the readings are solved directly).
    pub gains: &'a [f32],
    /// `L^T L`: xx, xy, xz, yy, yz, zz.
    pub gram: [f32; 6],
    /// Robust only: stored values at or above this are saturated.
    pub saturated_at: f32,
    pub shadow_abs: f32,
    pub shadow_rel: f32,
    /// Robust only: whether a step whose pixels all drop readings, the same ones, is
    /// reported as [`Step::Subset`] (at most 9 lights, so the usable set fits in the lanes and
    /// the brightest reading is the shadow rule's reference).
    pub group_subsets: bool,
}

/// What [`step`] did with its pixels.
pub(super) enum Step {
    /// Solved from all lights and written; this many are invalid.
    Solved(u32),
    /// Not written: every pixel drops a reading and all have these usable lights.
    Subset(u32),
    /// Not written: some pixels drop readings, not all or not the same ones.
    Declined,
}

/// Solves the [`STEP`] pixels from `p` into the three output slices (each `STEP` long) and
/// returns how many are invalid; with `ROBUST`, writes nothing when any pixel has a shadowed
/// or saturated reading, and returns the pixels' usable lights when they all share them
/// (`usable_bits`: `r_i >= threshold` and not saturated) and all drop some reading.
#[inline]
#[target_feature(enable = "avx2,fma")]
pub(super) fn step<T: Lanes, const ROBUST: bool>(
    kernel: &Kernel,
    rows: &[&[T]],
    p: usize,
    normals: &mut [Vec3],
    albedo: &mut [f32],
    confidence: &mut [f32],
) -> Step {
    assert!(normals.len() == STEP && albedo.len() == STEP && confidence.len() == STEP);
    let mut sums = accumulate::<T, ROBUST>(kernel, rows, p);
    if !ROBUST {
        let post = _mm256_set1_ps(kernel.rr_post);
        sums.rr = sums.rr.map(|q| _mm256_mul_ps(q, post));
    }
    if ROBUST && let Some(step) = screen(kernel, rows, p, &sums) {
        return step;
    }
    let mut invalid = 0;
    for h in 0..2 {
        let out = Outputs { normals: &mut *normals, albedo: &mut *albedo, confidence: &mut *confidence };
        invalid += solve_half(kernel, &sums, h, out);
    }
    Step::Solved(invalid)
}

/// One step's sums per half (8 lanes each): `g` = sum of `c_i r_i`, `sum w^2`, and with `ROBUST`
/// the dimmest and brightest gained readings and the lanes with a saturated one.
struct Sums {
    gx: [__m256; 2],
    gy: [__m256; 2],
    gz: [__m256; 2],
    rr: [__m256; 2],
    lo: [__m256; 2],
    hi: [__m256; 2],
    saturated: [__m256; 2],
}

/// The three output slices of a step, each [`STEP`] long.
struct Outputs<'a> {
    normals: &'a mut [Vec3],
    albedo: &'a mut [f32],
    confidence: &'a mut [f32],
}

/// Loads every light's samples of the step at `p` and accumulates its [`Sums`] in registers.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn accumulate<T: Lanes, const ROBUST: bool>(kernel: &Kernel, rows: &[&[T]], p: usize) -> Sums {
    let zero = _mm256_setzero_ps();
    let (mut gx, mut gy, mut gz, mut rr) = ([zero; 2], [zero; 2], [zero; 2], [zero; 2]);
    let (mut lo, mut hi) = ([_mm256_set1_ps(f32::INFINITY); 2], [_mm256_set1_ps(f32::NEG_INFINITY); 2]);
    let mut saturated = [zero; 2];
    let saturated_at = _mm256_set1_ps(kernel.saturated_at);
    let lights = rows.iter().zip(kernel.coefs).zip(kernel.scales).enumerate();
    for (i, ((row, c), &scale)) in lights {
        let row = &row[p..p + STEP];
        let (cx, cy, cz) = (_mm256_set1_ps(c[0]), _mm256_set1_ps(c[1]), _mm256_set1_ps(c[2]));
        let scale = _mm256_set1_ps(scale);
        for h in 0..2 {
            // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
            let mut v = unsafe { T::load8(row.as_ptr().add(8 * h)) };
            if ROBUST {
                saturated[h] = _mm256_or_ps(saturated[h], _mm256_cmp_ps::<_CMP_GE_OQ>(v, saturated_at));
                v = _mm256_mul_ps(v, _mm256_set1_ps(kernel.gains[i]));
                // `min`/`max` return the second operand when one is NaN: NaN readings are
                // skipped, as `f32::max` skips them in the scalar path.
                lo[h] = _mm256_min_ps(v, lo[h]);
                hi[h] = _mm256_max_ps(v, hi[h]);
            }
            gx[h] = _mm256_fmadd_ps(cx, v, gx[h]);
            gy[h] = _mm256_fmadd_ps(cy, v, gy[h]);
            gz[h] = _mm256_fmadd_ps(cz, v, gz[h]);
            // Unit scales: `v * 1 == v` bit for bit, so the product is skipped.
            let w = if kernel.unit_scales { v } else { _mm256_mul_ps(v, scale) };
            rr[h] = _mm256_fmadd_ps(w, w, rr[h]);
        }
    }
    Sums { gx, gy, gz, rr, lo, hi, saturated }
}

/// The robust solve's screen of a step: `None` when no pixel drops a reading (the step is solved
/// here), else the step declined or, when all pixels share their usable lights, that subset.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn screen<T: Lanes>(kernel: &Kernel, rows: &[&[T]], p: usize, sums: &Sums) -> Option<Step> {
    // Some reading is below `max(abs, rel * brightest)` iff the dimmest one is.
    let (abs, rel) = (_mm256_set1_ps(kernel.shadow_abs), _mm256_set1_ps(kernel.shadow_rel));
    // The brightest is the shadow rule's reference reading (`readings::Shadows`) only up to
    // 9 lights and without saturated readings (it excludes them); otherwise the threshold
    // from the brightest is at least the rule's, so "nothing dropped" still holds exactly,
    // and any other step is declined to the chunk path.
    let (mut dropped, mut clipped) = (0, 0);
    let mut threshold = [_mm256_setzero_ps(); 2];
    for h in 0..2 {
        threshold[h] = _mm256_max_ps(_mm256_mul_ps(rel, sums.hi[h]), abs);
        let shadowed = _mm256_cmp_ps::<_CMP_LT_OQ>(sums.lo[h], threshold[h]);
        dropped |= _mm256_movemask_ps(_mm256_or_ps(shadowed, sums.saturated[h])) << (8 * h);
        clipped |= _mm256_movemask_ps(sums.saturated[h]);
    }
    if dropped == 0xffff && clipped == 0 && kernel.group_subsets {
        return Some(common_usable(kernel, rows, p, threshold).map_or(Step::Declined, Step::Subset));
    }
    (dropped != 0).then_some(Step::Declined)
}

/// Normalises half `h` of the step's sums and writes its 8 normals, albedos and confidences into
/// `out`; returns how many of them are invalid.
#[inline]
#[target_feature(enable = "avx2,fma")]
fn solve_half(kernel: &Kernel, sums: &Sums, h: usize, out: Outputs) -> u32 {
    let zero = _mm256_setzero_ps();
    let m = kernel.gram.map(|v| _mm256_set1_ps(v));
    let one = _mm256_set1_ps(1.0);
    let excess_scale = _mm256_set1_ps(1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
    let (x, y, z, rr) = (sums.gx[h], sums.gy[h], sums.gz[h], sums.rr[h]);
    let mul = |a, b| _mm256_mul_ps(a, b);
    let add = |a, b| _mm256_add_ps(a, b);
    let len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
    let ok = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GT_OQ>(len, _mm256_set1_ps(MIN_ALBEDO)),
        _mm256_cmp_ps::<_CMP_LT_OQ>(len, _mm256_set1_ps(f32::INFINITY)),
    );
    let invalid = 8 - _mm256_movemask_ps(ok).count_ones();
    let inv = _mm256_div_ps(one, len);
    // `gram_form` and `residual_factor`, in the same order.
    let diagonal = add(add(mul(mul(m[0], x), x), mul(mul(m[3], y), y)), mul(mul(m[5], z), z));
    let cross = add(add(mul(mul(m[1], x), y), mul(mul(m[2], x), z)), mul(mul(m[4], y), z));
    let fitted = add(diagonal, mul(_mm256_set1_ps(2.0), cross));
    let excess = mul(_mm256_max_ps(_mm256_sub_ps(rr, fitted), zero), excess_scale);
    let factor = _mm256_blendv_ps(one, _mm256_div_ps(rr, add(rr, excess)), _mm256_cmp_ps::<_CMP_GT_OQ>(rr, zero));
    // Masks, not products with zero: a NaN must not leak into the outputs.
    let keep = |v| _mm256_and_ps(ok, v);
    let (nx, ny, nz) = (keep(mul(x, inv)), keep(mul(y, inv)), keep(mul(z, inv)));
    let [a, b, c] = interleave3(nx, ny, nz);
    assert!(out.normals.len() == STEP && out.albedo.len() == STEP && out.confidence.len() == STEP && h < 2);
    // SAFETY: each output slice holds STEP = 16 texels (asserted); half `h` writes texels
    // 8h..8h+8 (24 floats of `Vec3 { x, y, z }`, `repr(C)`) and floats 8h..8h+8.
    unsafe {
        let n = out.normals.as_mut_ptr().cast::<f32>().add(24 * h);
        _mm256_storeu_ps(n, a);
        _mm256_storeu_ps(n.add(8), b);
        _mm256_storeu_ps(n.add(16), c);
        _mm256_storeu_ps(out.albedo.as_mut_ptr().add(8 * h), keep(len));
        _mm256_storeu_ps(out.confidence.as_mut_ptr().add(8 * h), keep(factor));
    }
    invalid
}

/// The usable lights (bit `i` for light `i`) of the [`STEP`] pixels at `p` given their shadow
/// thresholds, when all pixels have the same ones.
// Kept out of line: inlined into `step`, its constants would crowd the main loop's registers.
#[inline(never)]
#[target_feature(enable = "avx2,fma")]
pub(super) fn common_usable<T: Lanes>(kernel: &Kernel, rows: &[&[T]], p: usize, threshold: [__m256; 2]) -> Option<u32> {
    let saturated_at = _mm256_set1_ps(kernel.saturated_at);
    let mut bits = [_mm256_setzero_si256(); 2];
    for (i, row) in rows.iter().enumerate() {
        let row = &row[p..p + STEP];
        let bit = _mm256_set1_epi32(1 << i);
        for h in 0..2 {
            // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
            let raw = unsafe { T::load8(row.as_ptr().add(8 * h)) };
            let saturated = _mm256_cmp_ps::<_CMP_GE_OQ>(raw, saturated_at);
            let v = _mm256_mul_ps(raw, _mm256_set1_ps(kernel.gains[i]));
            let ok = _mm256_andnot_ps(saturated, _mm256_cmp_ps::<_CMP_GE_OQ>(v, threshold[h]));
            bits[h] = _mm256_or_si256(bits[h], _mm256_and_si256(_mm256_castps_si256(ok), bit));
        }
    }
    let first = _mm256_cvtsi256_si32(bits[0]);
    let all = _mm256_set1_epi32(first);
    let same = _mm256_and_si256(_mm256_cmpeq_epi32(bits[0], all), _mm256_cmpeq_epi32(bits[1], all));
    (_mm256_movemask_epi8(same) == -1).then_some(first as u32)
}

/// What [`subset_step`] applies: one subset's pseudo-inverse and confidence terms.
pub(super) struct SubsetKernel<'a> {
    /// The subset's usable lights, bit `i` for light `i`.
    pub bits: u32,
    /// Column of the subset's pseudo-inverse per usable light, in light order.
    pub cols: &'a [[f32; 3]],
    /// Sample to reading scale per light.
    pub gains: &'a [f32],
    /// The subset's `L^T L`: xx, xy, xz, yy, yz, zz.
    pub gram: [f32; 6],
    /// Lights-used and conditioning factors of the confidence.
    pub weight: f32,
    /// Residual factor below which a pixel's fit does not agree (robust; see `Fit::agrees`).
    pub gate: f32,
}

/// Solves the [`STEP`] pixels from `p` with one subset of lights (what `finish_subset` does
/// per pixel, in the same operations: `g = g + c * r` light by light without fusing,
/// `n = g / |g|`, confidence `weight * residual_factor`), writes them and returns how many
/// are invalid and the pixels (bit `t` for pixel `t`) that are invalid or whose residual factor
/// is below `kernel.gate`.
#[inline(never)]
#[target_feature(enable = "avx2,fma")]
pub(super) fn subset_step<T: Lanes>(
    kernel: &SubsetKernel,
    rows: &[&[T]],
    p: usize,
    normals: &mut [Vec3],
    albedo: &mut [f32],
    confidence: &mut [f32],
) -> (u32, u32) {
    assert!(normals.len() == STEP && albedo.len() == STEP && confidence.len() == STEP);
    let zero = _mm256_setzero_ps();
    let (mut gx, mut gy, mut gz, mut rr) = ([zero; 2], [zero; 2], [zero; 2], [zero; 2]);
    let used = rows.iter().enumerate().filter(|(i, _)| kernel.bits >> i & 1 == 1);
    for ((i, row), c) in used.zip(kernel.cols) {
        let row = &row[p..p + STEP];
        let (cx, cy, cz) = (_mm256_set1_ps(c[0]), _mm256_set1_ps(c[1]), _mm256_set1_ps(c[2]));
        let gain = _mm256_set1_ps(kernel.gains[i]);
        for h in 0..2 {
            // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
            let v = _mm256_mul_ps(unsafe { T::load8(row.as_ptr().add(8 * h)) }, gain);
            gx[h] = _mm256_add_ps(gx[h], _mm256_mul_ps(cx, v));
            gy[h] = _mm256_add_ps(gy[h], _mm256_mul_ps(cy, v));
            gz[h] = _mm256_add_ps(gz[h], _mm256_mul_ps(cz, v));
            rr[h] = _mm256_add_ps(rr[h], _mm256_mul_ps(v, v));
        }
    }
    let m = kernel.gram.map(|v| _mm256_set1_ps(v));
    let one = _mm256_set1_ps(1.0);
    let excess_scale = _mm256_set1_ps(1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
    let weight = _mm256_set1_ps(kernel.weight);
    let gate = _mm256_set1_ps(kernel.gate);
    let (mut invalid, mut disagree) = (0, 0);
    for h in 0..2 {
        let (x, y, z, rr) = (gx[h], gy[h], gz[h], rr[h]);
        let mul = |a, b| _mm256_mul_ps(a, b);
        let add = |a, b| _mm256_add_ps(a, b);
        // `Vec3::length`: `sqrt((x x + y y) + z z)`.
        let len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
        let ok = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(len, _mm256_set1_ps(MIN_ALBEDO)),
            _mm256_cmp_ps::<_CMP_LT_OQ>(len, _mm256_set1_ps(f32::INFINITY)),
        );
        invalid += 8 - _mm256_movemask_ps(ok).count_ones();
        // `gram_form` and `residual_factor`, in the same order.
        let diagonal = add(add(mul(mul(m[0], x), x), mul(mul(m[3], y), y)), mul(mul(m[5], z), z));
        let cross = add(add(mul(mul(m[1], x), y), mul(mul(m[2], x), z)), mul(mul(m[4], y), z));
        let fitted = add(diagonal, mul(_mm256_set1_ps(2.0), cross));
        let excess = mul(_mm256_max_ps(_mm256_sub_ps(rr, fitted), zero), excess_scale);
        let factor = _mm256_blendv_ps(one, _mm256_div_ps(rr, add(rr, excess)), _mm256_cmp_ps::<_CMP_GT_OQ>(rr, zero));
        let agrees = _mm256_and_ps(ok, _mm256_cmp_ps::<_CMP_GE_OQ>(factor, gate));
        disagree |= ((!_mm256_movemask_ps(agrees)) as u32 & 0xff) << (8 * h);
        let keep = |v| _mm256_and_ps(ok, v);
        let div = |a| _mm256_div_ps(a, len);
        let (nx, ny, nz) = (keep(div(x)), keep(div(y)), keep(div(z)));
        let [a, b, c] = interleave3(nx, ny, nz);
        // SAFETY: as in `step`: half `h` writes texels 8h..8h+8 of slices of STEP texels.
        unsafe {
            let n = normals.as_mut_ptr().cast::<f32>().add(24 * h);
            _mm256_storeu_ps(n, a);
            _mm256_storeu_ps(n.add(8), b);
            _mm256_storeu_ps(n.add(16), c);
            _mm256_storeu_ps(albedo.as_mut_ptr().add(8 * h), keep(len));
            _mm256_storeu_ps(confidence.as_mut_ptr().add(8 * h), keep(mul(weight, factor)));
        }
    }
    (invalid, disagree)
}

/// `x0 y0 z0 x1 y1 z1 ... x7 y7 z7` from the three vectors, as three vectors.
#[inline]
#[target_feature(enable = "avx2,fma")]
pub(super) fn interleave3(x: __m256, y: __m256, z: __m256) -> [__m256; 3] {
    // Per 128-bit lane (lane 1 likewise with 4..7):
    let xy = _mm256_shuffle_ps::<0b10_00_10_00>(x, y); // x0 x2 y0 y2
    let yz = _mm256_shuffle_ps::<0b11_01_11_01>(y, z); // y1 y3 z1 z3
    let zx = _mm256_shuffle_ps::<0b11_01_10_00>(z, x); // z0 z2 x1 x3
    let a = _mm256_shuffle_ps::<0b10_00_10_00>(xy, zx); // x0 y0 z0 x1
    let b = _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy); // y1 z1 x2 y2
    let c = _mm256_shuffle_ps::<0b11_01_11_01>(zx, yz); // z2 x3 y3 z3
    [
        _mm256_permute2f128_ps::<0x20>(a, b), // x0 y0 z0 x1 y1 z1 x2 y2
        _mm256_permute2f128_ps::<0x30>(c, a), // z2 x3 y3 z3 x4 y4 z4 x5
        _mm256_permute2f128_ps::<0x31>(b, c), // y5 z5 x6 y6 z6 x7 y7 z7
    ]
}
