//! The chunk kernels: structure-of-arrays accumulation over the lights into a worker's
//! [`Scratch`], and the output helpers that write a chunk's [`Out`] slices.

use std::collections::HashMap;

use glam::Vec3;
use skinkit_maps::Grid;

use super::solution::AlbedoTexel;
use super::sources::Sample;
use super::subsets::SubsetSolve;
use super::{CHUNK, RESIDUAL_SCALE};

/// The texels of `grid` when it is `w x h` (to be overwritten), else a fresh zeroed vector.
pub(super) fn take_sized<T: AlbedoTexel>(grid: Grid<T>, w: usize, h: usize) -> Vec<T> {
    if grid.size() == (w, h) { grid.into_vec() } else { T::fresh(w * h) }
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

/// Per-worker scratch buffers, structure-of-arrays over one chunk.
pub(super) struct Scratch {
    pub(super) r: Vec<f32>,
    pub(super) rgb: Vec<[f32; 3]>,
    pub(super) sat: Vec<u8>,
    pub(super) gx: [f32; CHUNK],
    pub(super) gy: [f32; CHUNK],
    pub(super) gz: [f32; CHUNK],
    pub(super) rr: [f32; CHUNK],
    pub(super) top: [f32; CHUNK],
    pub(super) len: [f32; CHUNK],
    pub(super) conf: [f32; CHUNK],
    pub(super) dropped: [u32; CHUNK],
    /// Batched subsets: usable lights per pixel (bit `i` for light `i`).
    pub(super) bits: [u32; CHUNK],
    /// Batched subsets: pixels still to solve, and those of the current group.
    pub(super) pending: [u8; CHUNK],
    pub(super) group: [u8; CHUNK],
    /// Batched subsets: `g` and `sum r^2` of the current group.
    pub(super) bx: [f32; CHUNK],
    pub(super) by: [f32; CHUNK],
    pub(super) bz: [f32; CHUNK],
    pub(super) brr: [f32; CHUNK],
    /// Batched subsets, robust: pixels whose subset fit does not agree, to be fitted.
    pub(super) refit: [u8; CHUNK],
    pub(super) refits: usize,
    pub(super) cache: HashMap<u128, SubsetSolve>,
}

impl Scratch {
    pub(super) fn new(k: usize, rgb: bool) -> Self {
        Scratch {
            r: vec![0.0; k * CHUNK],
            rgb: if rgb { vec![[0.0; 3]; k * CHUNK] } else { Vec::new() },
            sat: vec![0; k * CHUNK],
            gx: [0.0; CHUNK],
            gy: [0.0; CHUNK],
            gz: [0.0; CHUNK],
            rr: [0.0; CHUNK],
            top: [0.0; CHUNK],
            len: [0.0; CHUNK],
            conf: [0.0; CHUNK],
            dropped: [0; CHUNK],
            bits: [0; CHUNK],
            pending: [0; CHUNK],
            group: [0; CHUNK],
            bx: [0.0; CHUNK],
            by: [0.0; CHUNK],
            bz: [0.0; CHUNK],
            brr: [0.0; CHUNK],
            refit: [0; CHUNK],
            refits: 0,
            cache: HashMap::new(),
        }
    }
}

/// Output slices of one chunk.
pub(super) struct Out<'o, A> {
    pub(super) normals: &'o mut [Vec3],
    pub(super) albedo: &'o mut [A],
    pub(super) confidence: &'o mut [f32],
}
