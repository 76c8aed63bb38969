//! The chunk kernels: structure-of-arrays accumulation over the lights, and output helpers.

use glam::Vec3;
use skinkit_maps::Grid;

use super::plan::{Out, Scratch};
use super::solution::AlbedoTexel;
use super::sources::Sample;
use super::{CHUNK, RESIDUAL_SCALE};

/// The texels of `grid` when it is `w x h` (to be overwritten), else a fresh zeroed vector.
pub(super) fn take_sized<T: AlbedoTexel>(grid: Grid<T>, w: usize, h: usize) -> Vec<T> {
    if grid.size() == (w, h) { grid.into_vec() } else { T::fresh(w * h) }
}

/// `n` zeros from the allocator's zeroed allocation. Large sizes come straight from the OS as
/// untouched zero pages, so the only touch of each page is the solve's write to it, made by the
/// worker that owns the band (no separate fill pass).
///
/// Transparent huge pages were tried (`madvise(MADV_HUGEPAGE)`): they made the solve faster on
/// average but the whole 4096x4096 capture slower and erratic (0.13 to 0.44 s detrends, from
/// synchronous compaction), so the plain 4 KiB pages stay.
pub(crate) fn fresh_zeroed(n: usize) -> Vec<f32> {
    vec![0.0f32; n]
}

/// [`fresh_zeroed`] for `Vec3` texels.
pub(crate) fn fresh_zeroed_vec3(n: usize) -> Vec<Vec3> {
    const { assert!(size_of::<Vec3>() == 3 * size_of::<f32>() && align_of::<Vec3>() == align_of::<f32>()) };
    let mut floats = std::mem::ManuallyDrop::new(fresh_zeroed(3 * n));
    let (ptr, len, cap) = (floats.as_mut_ptr(), floats.len(), floats.capacity());
    // SAFETY: `Vec3` is `#[repr(C)] { x, y, z: f32 }` (size and alignment checked above), so the
    // allocation of `cap` zeroed floats, with `len == cap == 3 n` (`vec!` allocates exactly), has
    // the layout of `n` zero `Vec3`s, and the old vector is never dropped.
    debug_assert!(len == cap && len % 3 == 0);
    unsafe { Vec::from_raw_parts(ptr.cast::<Vec3>(), len / 3, cap / 3) }
}

/// Copies the chunk's all-lights results (grey albedo) to the output.
#[inline(always)]
pub(super) fn write_all_lights<A: AlbedoTexel>(n: usize, s: &Scratch, out: Out<A>) {
    let (normals, albedo) = (&mut out.normals[..n], &mut out.albedo[..n]);
    for j in 0..n {
        normals[j].x = s.gx[j];
        normals[j].y = s.gy[j];
        normals[j].z = s.gz[j];
        albedo[j] = A::gray(s.len[j]);
    }
    out.confidence.copy_from_slice(&s.conf[..n]);
}

/// `1 / (1 + (rho / RESIDUAL_SCALE)^2)` with `rho^2 = (|r|^2 - |L g|^2) / |r|^2`, the relative
/// residual of a least-squares fit (the fitted readings are orthogonal to the residual).
#[inline(always)]
pub(super) fn residual_factor(rr: f32, fitted: f32) -> f32 {
    // 1 / (1 + rho^2 / s^2) = rr / (rr + (rr - fitted) / s^2): one division.
    let excess = (rr - fitted).max(0.0) * (1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
    if rr > 0.0 { rr / (rr + excess) } else { 1.0 }
}

/// Stored values minus the ambient frame's, as f32.
#[inline(always)]
pub(super) fn raw_values<T: Sample>(v: &[T], ambient: Option<&[T]>, out: &mut [f32]) {
    match ambient {
        None => out.iter_mut().zip(v).for_each(|(o, x)| *o = x.value()),
        Some(a) => out.iter_mut().zip(v.iter().zip(a)).for_each(|(o, (x, y))| *o = x.value() - y.value()),
    }
}

/// `g += coefs_i * x_i` and `rr += (x_i * scales_i)^2` over all lights, `x_i` the rows of `s.r`.
#[inline(always)]
pub(super) fn accumulate_all(n: usize, s: &mut Scratch, coefs: &[[f32; 3]], scales: &[f32]) {
    let Scratch { r, gx, gy, gz, rr, .. } = s;
    accumulate_rows(n, |i| &r[i * CHUNK..i * CHUNK + n], (gx, gy, gz, rr), coefs, scales);
}

/// `g += coefs_i * x_i` and `rr += (x_i * scales_i)^2` over all lights, `x_i = row(i)` (the `n`
/// values of light `i`, stored samples or readings), four lights per pass over the accumulators
/// (the sums are still formed light by light, so the grouping does not change a bit).
#[inline(always)]
pub(super) fn accumulate_rows<'r, T: Sample + 'r>(
    n: usize,
    row: impl Fn(usize) -> &'r [T],
    sums: (&mut [f32; CHUNK], &mut [f32; CHUNK], &mut [f32; CHUNK], &mut [f32; CHUNK]),
    coefs: &[[f32; 3]],
    scales: &[f32],
) {
    let (gx, gy, gz, rr) = sums;
    for (g, (c, sc)) in coefs.chunks(4).zip(scales.chunks(4)).enumerate() {
        let sums = (&mut gx[..n], &mut gy[..n], &mut gz[..n], &mut rr[..n]);
        let rows = |t: usize| row(4 * g + t);
        match (c.len(), g == 0) {
            (4, true) => accumulate::<T, 4, true>(std::array::from_fn(rows), n, c, sc, sums),
            (4, false) => accumulate::<T, 4, false>(std::array::from_fn(rows), n, c, sc, sums),
            (3, true) => accumulate::<T, 3, true>(std::array::from_fn(rows), n, c, sc, sums),
            (3, false) => accumulate::<T, 3, false>(std::array::from_fn(rows), n, c, sc, sums),
            (2, _) => accumulate::<T, 2, false>(std::array::from_fn(rows), n, c, sc, sums),
            _ => accumulate::<T, 1, false>(std::array::from_fn(rows), n, c, sc, sums),
        }
    }
}

/// The kernel of [`accumulate_rows`] for `N` lights' values `xs`; `FIRST` starts the sums from
/// zero instead of reading them (no separate clearing pass).
#[inline(always)]
pub(super) fn accumulate<T: Sample, const N: usize, const FIRST: bool>(
    xs: [&[T]; N],
    n: usize,
    coefs: &[[f32; 3]],
    scales: &[f32],
    sums: (&mut [f32], &mut [f32], &mut [f32], &mut [f32]),
) {
    let (gx, gy, gz, rr) = sums;
    let xs: [&[T]; N] = std::array::from_fn(|t| &xs[t][..n]);
    let c: [[f32; 3]; N] = std::array::from_fn(|t| coefs[t]);
    let sc: [f32; N] = std::array::from_fn(|t| scales[t]);
    let (gx, gy, gz, rr) = (&mut gx[..n], &mut gy[..n], &mut gz[..n], &mut rr[..n]);
    for j in 0..n {
        let (mut x, mut y, mut z, mut q) = if FIRST { (0.0, 0.0, 0.0, 0.0) } else { (gx[j], gy[j], gz[j], rr[j]) };
        for t in 0..N {
            let v = xs[t][j].value();
            // Fused multiply-adds: one rounding each, the same bits with or without FMA hardware.
            x = c[t][0].mul_add(v, x);
            y = c[t][1].mul_add(v, y);
            z = c[t][2].mul_add(v, z);
            let w = v * sc[t];
            q = w.mul_add(w, q);
        }
        (gx[j], gy[j], gz[j], rr[j]) = (x, y, z, q);
    }
}
