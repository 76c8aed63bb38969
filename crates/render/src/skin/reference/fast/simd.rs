//! The SSE2 kernels of the fast evaluation ([`super`]): the wide pass ([`wide_lanes`]) and the
//! narrow pass ([`narrow_pass`]) four sources at a time, each lane by the same operations in the
//! same order as the scalar functions they mirror ([`super::wide_weight`], [`super::exp_neg`],
//! [`super::erfc`], [`super::correction`], `super::box_mass`), so a lane's value has the scalar
//! function's bits. Compiled for x86-64 only, where SSE2 is always present.
//!
//! The unsafe code is kept to four blocks: the kernels are safe functions that enable `sse2`,
//! in which the arithmetic intrinsics are safe to call; the two entry points ([`wide_lanes`],
//! [`narrow_pass`]) call them from code that does not name the feature, and [`load`] and
//! [`store`] are the intrinsics that go through raw pointers, behind bounds the slice types
//! check. There is no `unsafe fn`.

use std::arch::x86_64::*;

use super::{ERFC, FIRST_WIDE, Gaussian, Kernel, LANES, Near, Source};

/// Accumulates sources `start..end` into `acc` in groups of [`LANES`], the last one masked;
/// returns `end`.
pub(super) fn wide_lanes(
    near: &Near,
    kernel: &Kernel,
    r: &Source,
    start: usize,
    end: usize,
    acc: &mut [[f32; LANES]; 6],
) -> usize {
    // SAFETY: `lanes` needs SSE2 and nothing else (its loads are bounds-checked, see `load`);
    // every x86-64 CPU has SSE2, and this module is compiled for x86-64 only.
    unsafe { lanes(near, kernel, r, start, end, acc) }
}

/// Four floats of `col` from `j` on, unaligned; panics past the end. The columns of [`Near`]
/// are padded by [`LANES`] past their sources, so a last, partial group stays inside.
#[inline(always)]
fn load(col: &[f32], j: usize) -> __m128 {
    let four = &col[j..j + LANES];
    // SAFETY: `four` is `LANES` = 4 readable floats, what `_mm_loadu_ps` reads (unaligned is
    // allowed); its SSE2 is part of x86-64, which this module is compiled for.
    unsafe { _mm_loadu_ps(four.as_ptr()) }
}

/// The four lanes of `v` into `out`.
#[inline(always)]
fn store(out: &mut [f32; LANES], v: __m128) {
    // SAFETY: `out` is 4 writable floats, what `_mm_storeu_ps` writes (unaligned is allowed);
    // its SSE2 is part of x86-64, which this module is compiled for.
    unsafe { _mm_storeu_ps(out.as_mut_ptr(), v) }
}

/// The body of [`wide_lanes`]: `start <= end <=` the wide list's length, so each group's four
/// lanes from `j < end` lie within the padded columns ([`load`]).
#[target_feature(enable = "sse2")]
fn lanes(near: &Near, kernel: &Kernel, r: &Source, start: usize, end: usize, acc: &mut [[f32; LANES]; 6]) -> usize {
    let c = &near.columns;
    let set = _mm_set1_ps;
    let (px, py, pz) = (set(r.position.x), set(r.position.y), set(r.position.z));
    let (nx, ny, nz) = (set(r.normal.x), set(r.normal.y), set(r.normal.z));
    let support2 = set(near.support * near.support);
    let mut sums = [_mm_setzero_ps(); 6];
    let mut j = start;
    while j < end {
        let lane = _mm_add_epi32(_mm_set1_epi32(j as i32), _mm_setr_epi32(0, 1, 2, 3));
        let live = _mm_castsi128_ps(_mm_cmplt_epi32(lane, _mm_set1_epi32(end as i32)));
        let d = [_mm_sub_ps(px, load(&c.p[0], j)), _mm_sub_ps(py, load(&c.p[1], j)), _mm_sub_ps(pz, load(&c.p[2], j))];
        let d2 = dot(d, d);
        let facing = dot([nx, ny, nz], [load(&c.n[0], j), load(&c.n[1], j), load(&c.n[2], j)]);
        let inside = _mm_and_ps(_mm_cmple_ps(d2, support2), _mm_cmpge_ps(facing, _mm_setzero_ps()));
        let inside = _mm_and_ps(inside, live);
        if _mm_movemask_ps(inside) == 0 {
            j += LANES;
            continue;
        }
        let nearest = _mm_max_ps(_mm_sub_ps(_mm_sqrt_ps(d2), load(&c.half_diagonal, j)), _mm_setzero_ps());
        let n2 = _mm_mul_ps(nearest, nearest);
        let dx = dot(d, [load(&c.u[0], j), load(&c.u[1], j), load(&c.u[2], j)]);
        let dy = dot(d, [load(&c.v[0], j), load(&c.v[1], j), load(&c.v[2], j)]);
        let (a, b) = (load(&c.a, j), load(&c.b, j));
        let mut w = [_mm_setzero_ps(); 3];
        for (m, g) in kernel.gaussians[FIRST_WIDE..].iter().enumerate() {
            // Skipped where no lane is within its radius (as the oracle skips it).
            if _mm_movemask_ps(_mm_cmple_ps(n2, set(g.reach2))) == 0 {
                continue;
            }
            let inv = set(g.inv_sigma);
            let cx = correction(_mm_mul_ps(dx, inv), _mm_mul_ps(a, inv));
            let cy = correction(_mm_mul_ps(dy, inv), _mm_mul_ps(b, inv));
            let mut value = _mm_mul_ps(load(&c.midpoint[m], j), set(g.peak));
            value = _mm_mul_ps(_mm_mul_ps(value, a), b);
            value = _mm_mul_ps(value, exp_neg(_mm_mul_ps(d2, set(g.neg_inv_2v))));
            value = _mm_and_ps(_mm_mul_ps(_mm_mul_ps(value, cx), cy), inside);
            for ch in 0..3 {
                if g.weights[ch] != 0.0 {
                    w[ch] = _mm_add_ps(w[ch], _mm_mul_ps(set(g.weights[ch]), value));
                }
            }
        }
        for ch in 0..3 {
            sums[ch] = _mm_add_ps(sums[ch], _mm_mul_ps(load(&c.e[ch], j), w[ch]));
            sums[3 + ch] = _mm_add_ps(sums[3 + ch], w[ch]);
        }
        j += LANES;
    }
    for (slot, v) in acc.iter_mut().zip(sums) {
        store(slot, v);
    }
    end.max(start)
}

/// The narrow pass over the cell's narrow list, four sources at a time: per Gaussian the
/// lanes that need it (within its skip radius, and narrower than the texel or below
/// [`FIRST_WIDE`]) take the oracle's separable form, each side by the midpoint rule or erfc.
pub(super) fn narrow_pass(near: &Near, kernel: &Kernel, r: &Source) -> ([f64; 3], [f64; 3]) {
    // SAFETY: as in `wide_lanes`: `narrow_lanes` needs SSE2 only, which x86-64 has.
    unsafe { narrow_lanes(near, kernel, r) }
}

/// The body of [`narrow_pass`]: each group loads four lanes from below the narrow list's
/// length, within the padding [`Near`] builds ([`load`]).
#[target_feature(enable = "sse2")]
fn narrow_lanes(near: &Near, kernel: &Kernel, r: &Source) -> ([f64; 3], [f64; 3]) {
    let c = &near.narrow_columns;
    let end = near.narrow.len();
    let set = _mm_set1_ps;
    let zero = _mm_setzero_ps();
    let (px, py, pz) = (set(r.position.x), set(r.position.y), set(r.position.z));
    let (nx, ny, nz) = (set(r.normal.x), set(r.normal.y), set(r.normal.z));
    let support2 = set(near.support * near.support);
    let mut sums = [zero; 6];
    let mut j = 0;
    while j < end {
        let lane = _mm_add_epi32(_mm_set1_epi32(j as i32), _mm_setr_epi32(0, 1, 2, 3));
        let live = _mm_castsi128_ps(_mm_cmplt_epi32(lane, _mm_set1_epi32(end as i32)));
        let d = [_mm_sub_ps(px, load(&c.p[0], j)), _mm_sub_ps(py, load(&c.p[1], j)), _mm_sub_ps(pz, load(&c.p[2], j))];
        let d2 = dot(d, d);
        let facing = dot([nx, ny, nz], [load(&c.n[0], j), load(&c.n[1], j), load(&c.n[2], j)]);
        let inside = _mm_and_ps(_mm_cmple_ps(d2, support2), _mm_cmpge_ps(facing, zero));
        let inside = _mm_and_ps(inside, live);
        let nearest = _mm_max_ps(_mm_sub_ps(_mm_sqrt_ps(d2), load(&c.half_diagonal, j)), zero);
        let n2 = _mm_mul_ps(nearest, nearest);
        let dx = dot(d, [load(&c.u[0], j), load(&c.u[1], j), load(&c.u[2], j)]);
        let dy = dot(d, [load(&c.v[0], j), load(&c.v[1], j), load(&c.v[2], j)]);
        let dz2 = _mm_max_ps(_mm_sub_ps(_mm_sub_ps(d2, _mm_mul_ps(dx, dx)), _mm_mul_ps(dy, dy)), zero);
        let (a, b) = (load(&c.a, j), load(&c.b, j));
        let first_midpoint = load(&c.first_midpoint, j);
        let mut w = [zero; 3];
        for (k, g) in kernel.gaussians.iter().enumerate() {
            let mut need = _mm_and_ps(inside, _mm_cmple_ps(n2, set(g.reach2)));
            if k >= FIRST_WIDE {
                need = _mm_and_ps(need, _mm_cmpgt_ps(first_midpoint, set(k as f32)));
            }
            if _mm_movemask_ps(need) == 0 {
                continue;
            }
            let mass = _mm_mul_ps(side_mass(g, dx, a), side_mass(g, dy, b));
            let value = _mm_mul_ps(_mm_mul_ps(set(g.scale32), exp_neg(_mm_mul_ps(dz2, set(g.neg_inv_2v)))), mass);
            let value = _mm_and_ps(value, need);
            for ch in 0..3 {
                if g.weights[ch] != 0.0 {
                    w[ch] = _mm_add_ps(w[ch], _mm_mul_ps(set(g.weights[ch]), value));
                }
            }
        }
        for ch in 0..3 {
            sums[ch] = _mm_add_ps(sums[ch], _mm_mul_ps(load(&c.e[ch], j), w[ch]));
            sums[3 + ch] = _mm_add_ps(sums[3 + ch], w[ch]);
        }
        j += LANES;
    }
    let mut lanes = [[0.0f32; LANES]; 6];
    for (slot, v) in lanes.iter_mut().zip(sums) {
        store(slot, v);
    }
    let sum = |x: &[f32; LANES]| x.iter().map(|&v| v as f64).sum::<f64>();
    (std::array::from_fn(|ch| sum(&lanes[ch])), std::array::from_fn(|ch| sum(&lanes[3 + ch])))
}

/// The dot products of four pairs of vectors.
#[target_feature(enable = "sse2")]
#[inline]
fn dot(a: [__m128; 3], b: [__m128; 3]) -> __m128 {
    _mm_add_ps(_mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1])), _mm_mul_ps(a[2], b[2]))
}

/// `super::box_mass` on four lanes: the midpoint rule where `a < sigma`, erfc elsewhere
/// (each computed only when some lane takes it).
#[target_feature(enable = "sse2")]
#[inline]
fn side_mass(g: &Gaussian, x: __m128, a: __m128) -> __m128 {
    let set = _mm_set1_ps;
    let small = _mm_cmplt_ps(a, set(g.sigma as f32));
    let mask = _mm_movemask_ps(small);
    let mut out = _mm_setzero_ps();
    if mask != 0 {
        let t = _mm_mul_ps(x, set(g.inv_sigma));
        let density = exp_neg(_mm_mul_ps(set(-0.5), _mm_mul_ps(t, t)));
        let mid = _mm_mul_ps(
            _mm_mul_ps(_mm_mul_ps(a, set(g.peak_1d)), density),
            correction(t, _mm_mul_ps(a, set(g.inv_sigma))),
        );
        out = _mm_and_ps(mid, small);
    }
    if mask != 0xf {
        let ax = _mm_andnot_ps(set(-0.0), x);
        let half = _mm_mul_ps(set(0.5), a);
        let s = set(g.inv_sigma * std::f32::consts::FRAC_1_SQRT_2);
        let lo = erfc(_mm_mul_ps(_mm_sub_ps(ax, half), s));
        let hi = erfc(_mm_mul_ps(_mm_add_ps(ax, half), s));
        let big = _mm_mul_ps(set(0.5), _mm_sub_ps(lo, hi));
        out = _mm_or_ps(out, _mm_andnot_ps(small, big));
    }
    out
}

/// `super::erfc` on four lanes.
#[target_feature(enable = "sse2")]
#[inline]
fn erfc(x: __m128) -> __m128 {
    let set = _mm_set1_ps;
    let z = _mm_andnot_ps(set(-0.0), x);
    let t = _mm_div_ps(set(1.0), _mm_add_ps(set(1.0), _mm_mul_ps(set(0.5), z)));
    let mut poly = _mm_setzero_ps();
    for ck in ERFC.iter().rev() {
        poly = _mm_add_ps(_mm_mul_ps(poly, t), set(*ck));
    }
    let r = _mm_mul_ps(t, exp_neg(_mm_sub_ps(poly, _mm_mul_ps(z, z))));
    let negative = _mm_cmplt_ps(x, _mm_setzero_ps());
    _mm_or_ps(_mm_andnot_ps(negative, r), _mm_and_ps(negative, _mm_sub_ps(set(2.0), r)))
}

/// `super::correction` on four lanes.
#[target_feature(enable = "sse2")]
#[inline]
fn correction(t: __m128, r: __m128) -> __m128 {
    let set = _mm_set1_ps;
    let (t2, r2) = (_mm_mul_ps(t, t), _mm_mul_ps(r, r));
    let second = _mm_mul_ps(_mm_mul_ps(r2, set(1.0 / 24.0)), _mm_sub_ps(t2, set(1.0)));
    let quartic = _mm_add_ps(_mm_sub_ps(_mm_mul_ps(t2, t2), _mm_mul_ps(set(6.0), t2)), set(3.0));
    let fourth = _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(r2, r2), set(1.0 / 1920.0)), quartic);
    _mm_add_ps(_mm_add_ps(set(1.0), second), fourth)
}

/// `super::exp_neg` on four lanes (finite inputs).
#[target_feature(enable = "sse2")]
#[inline]
fn exp_neg(x: __m128) -> __m128 {
    let set = _mm_set1_ps;
    let magic = set(12_582_912.0);
    let x = _mm_max_ps(_mm_min_ps(x, _mm_setzero_ps()), set(-87.0));
    let n = _mm_sub_ps(_mm_add_ps(_mm_mul_ps(x, set(std::f32::consts::LOG2_E)), magic), magic);
    let r = _mm_sub_ps(_mm_sub_ps(x, _mm_mul_ps(n, set(0.693_145_75))), _mm_mul_ps(n, set(1.428_606_8e-6)));
    let mut p = set(1.0 / 5040.0);
    for k in [1.0 / 720.0, 1.0 / 120.0, 1.0 / 24.0, 1.0 / 6.0, 0.5, 1.0, 1.0] {
        p = _mm_add_ps(set(k), _mm_mul_ps(r, p));
    }
    let scale = _mm_castsi128_ps(_mm_slli_epi32(_mm_add_epi32(_mm_cvtps_epi32(n), _mm_set1_epi32(127)), 23));
    _mm_mul_ps(scale, p)
}
