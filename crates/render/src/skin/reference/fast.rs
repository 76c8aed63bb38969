//! The fast evaluation behind [`super::scatter`]: the same sums as [`super::scatter_exact`] (the
//! brute-force oracle), organised for speed. Measured on the sample head (2 shared cores): see
//! "Speed" in the parent module's docs.
//!
//! - Neighbours: source texels are packed once ([`Source`]) and sorted by grid cell (a quarter
//!   of the support), cells in `(z, y, x)` order, so the cells of one `(y, z)` row are one
//!   contiguous slice found by binary search. Each receiver cell gathers, once, the sources
//!   whose distance to the cell's box is within the support ([`Near`]); its receivers all read
//!   that one list (on the head about 2.2 times the support's disc: the surface folds).
//! - The wide pass: the three widest Gaussians (variances 0.567, 1.99 and 7.41 mm^2, reaching
//!   nearly the whole support and wider than any texel of a 256-or-finer head map) by the
//!   corrected midpoint rule, four sources at a time in SSE2 ([`simd`]), lanes outside the support
//!   or across opposed normals masked to zero, a group skipped when no lane is inside and a
//!   Gaussian when no lane is within its skip radius. Lanes evaluated beyond their own radius add
//!   less than `exp(-20)` of the Gaussian's peak, which the oracle drops.
//! - The narrow pass: the other Gaussians (and the wide ones of texels larger than their sigma)
//!   over a second per-cell list, the sources within their own skip radius of the cell, also
//!   four at a time ([`simd`]; each Gaussian skipped when no lane is within its radius): the
//!   oracle's separable form, each side by the corrected midpoint rule or a difference of erfc, in
//!   f32 with an inlined polynomial exponential ([`exp_neg`], relative error below 3e-7) and a
//!   Chebyshev `erfc` ([`erfc`], relative error 1.1e-6 for `|x| <= 3`, 2e-6 to 4) in place of
//!   libm's (two thirds of the oracle's time at 256 texels).
//! - Sums: f32 over lanes and per pass, f64 across them, receivers in a fixed order and sources
//!   in (cell, index) order: the same bits whatever the thread count. The result is within 1e-5
//!   relative of the oracle (a test: below 2e-6 on its spheres;
//!   5e-7 on the sample head at 256 texels, 1.1e-6 at 512).
//!
//! The SSE2 kernels are in [`simd`] (`fast/simd.rs`), each mirroring a scalar function here
//! (`exp_neg`, `erfc`, `correction`, the wide and narrow sums) operation for operation. They hold
//! the file pair's only unsafe code: four small blocks, each with its `SAFETY` comment.

use glam::Vec3;
use rayon::prelude::*;

use super::{MIDPOINT_RATIO, ReferenceBake, SKIP_EXPONENT, support_mm};
use crate::skin::profile::{Profile, WEIGHTS};

/// Number of Gaussians in the profile.
const GAUSSIANS: usize = WEIGHTS.len();

/// Grid cells per support radius: smaller cells gather fewer sources beyond the support but
/// share each gathered list among fewer receivers.
const CELLS_PER_SUPPORT: f32 = 4.0;

/// One covered source texel, packed for the inner loop.
#[derive(Clone, Copy, Default)]
pub(super) struct Source {
    pub(super) position: Vec3,
    pub(super) normal: Vec3,
    u_axis: Vec3,
    v_axis: Vec3,
    /// Footprint sides, mm.
    a: f32,
    b: f32,
    half_diagonal: f32,
    /// Gaussians from this index on are wider than the texel (midpoint rule).
    first_midpoint: u32,
    /// Beyond this squared distance the narrow pass has nothing to add (mm^2).
    narrow_reach2: f32,
    pub(super) irradiance: [f32; 3],
}

/// Per-Gaussian constants.
#[derive(Clone, Copy)]
struct Gaussian {
    sigma: f64,
    /// Normalisation relative to the 2-D one (the oracle's `scale`).
    scale32: f32,
    /// The 1-D density's peak, `1 / (sigma sqrt(2 pi))`.
    peak_1d: f32,
    inv_sigma: f32,
    neg_inv_2v: f32,
    /// `scale / (2 pi v)`: the 2-D density's peak.
    peak: f32,
    /// Skipped where the texel's nearest point is farther than this, squared (mm^2).
    reach2: f32,
    weights: [f32; 3],
}

pub(super) struct Kernel {
    gaussians: [Gaussian; GAUSSIANS],
}

impl Kernel {
    pub(super) fn new(profile: &Profile) -> Self {
        let gaussians = std::array::from_fn(|k| {
            let v = profile.variance(k);
            let scale = profile.gaussian(k, 0.0) * 2.0 * std::f64::consts::PI * v;
            Gaussian {
                sigma: v.sqrt(),
                scale32: scale as f32,
                peak_1d: (1.0 / (2.0 * std::f64::consts::PI * v).sqrt()) as f32,
                inv_sigma: (1.0 / v.sqrt()) as f32,
                neg_inv_2v: (-0.5 / v) as f32,
                peak: (scale / (2.0 * std::f64::consts::PI * v)) as f32,
                reach2: (2.0 * v * SKIP_EXPONENT) as f32,
                weights: WEIGHTS[k].map(|w| w as f32),
            }
        });
        Self { gaussians }
    }

    /// The oracle's `texel_weight` for `offset` (receiver minus source) with `d2 = |offset|^2`.
    #[inline]
    fn weight(&self, s: &Source, offset: Vec3, d2: f32) -> [f32; 3] {
        let nearest = (d2.sqrt() - s.half_diagonal).max(0.0);
        let n2 = nearest * nearest;
        let dx = offset.dot(s.u_axis);
        let dy = offset.dot(s.v_axis);
        let mut w = [0.0f32; 3];
        for (k, g) in self.gaussians.iter().enumerate() {
            let wide = k >= FIRST_WIDE && k as u32 >= s.first_midpoint;
            if wide || n2 > g.reach2 {
                continue;
            }
            let value =
                if k as u32 >= s.first_midpoint { midpoint(g, s, dx, dy, d2) } else { self.narrow(k, s, dx, dy, d2) };
            for c in 0..3 {
                w[c] += g.weights[c] * value;
            }
        }
        w
    }

    /// The separable path of a Gaussian narrower than the texel: `exp(-dz^2 / 2v)` times the
    /// 1-D masses along both sides.
    #[inline]
    fn narrow(&self, k: usize, s: &Source, dx: f32, dy: f32, d2: f32) -> f32 {
        let g = &self.gaussians[k];
        // As the oracle: the out-of-plane part from the full offset, in f64 (cancellation).
        let (x, y) = (dx as f64, dy as f64);
        let dz2 = (d2 as f64 - x * x - y * y).max(0.0) as f32;
        let mass = box_mass(g, dx, s.a) * box_mass(g, dy, s.b);
        g.scale32 * exp_neg(dz2 * g.neg_inv_2v) * mass
    }
}

/// Gaussian `k` alone (no channel weights) integrated over source `s`'s footprint, seen from
/// `offset` (receiver minus source): one term of the oracle's `texel_weight`.
pub(super) fn texel_gaussian(kernel: &Kernel, k: usize, s: &Source, offset: Vec3) -> f32 {
    let g = &kernel.gaussians[k];
    let d2 = offset.length_squared();
    let nearest = (d2.sqrt() - s.half_diagonal).max(0.0);
    if nearest * nearest > g.reach2 {
        return 0.0;
    }
    let (dx, dy) = (offset.dot(s.u_axis), offset.dot(s.v_axis));
    if k as u32 >= s.first_midpoint { midpoint(g, s, dx, dy, d2) } else { kernel.narrow(k, s, dx, dy, d2) }
}

/// Mass of the 1-D Gaussian on `[x - a/2, x + a/2]`: the oracle's `box_mass` in f32 (the
/// corrected midpoint rule below `a = sigma`, differences of [`erfc`] above).
#[inline]
fn box_mass(g: &Gaussian, x: f32, a: f32) -> f32 {
    if (a as f64) < MIDPOINT_RATIO * g.sigma {
        let t = x * g.inv_sigma;
        return a * g.peak_1d * exp_neg(-0.5 * t * t) * correction(t, a * g.inv_sigma);
    }
    let x = x.abs();
    let s = g.inv_sigma * std::f32::consts::FRAC_1_SQRT_2;
    0.5 * (erfc((x - 0.5 * a) * s) - erfc((x + 0.5 * a) * s))
}

/// `erfc(x)` for any `x`: the Chebyshev fit of Press et al. (Numerical Recipes, `erfcc`,
/// fractional error below 1.2e-7) with [`exp_neg`]; in f32 1.1e-6 for `|x| <= 3`, 2e-6 (the
/// rounding of `z^2`) to `|x| = 4`.
#[inline]
fn erfc(x: f32) -> f32 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = ERFC.iter().rev().fold(0.0f32, |acc, &ck| acc * t + ck);
    let r = t * exp_neg(poly - z * z);
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The coefficients of [`erfc`]'s polynomial in `t`, constant term first.
const ERFC: [f32; 10] = [
    -1.265_512_2,
    1.000_023_7,
    0.374_091_96,
    0.096_784_18,
    -0.186_288_06,
    0.278_868_07,
    -1.135_204,
    1.488_515_9,
    -0.822_152_2,
    0.170_872_77,
];

/// One Gaussian over a texel smaller than its sigma: density at the offset times the area and
/// the corrected midpoint rule along both sides (the oracle's `midpoint_correction`).
#[inline]
fn midpoint(g: &Gaussian, s: &Source, dx: f32, dy: f32, d2: f32) -> f32 {
    let cx = correction(dx * g.inv_sigma, s.a * g.inv_sigma);
    let cy = correction(dy * g.inv_sigma, s.b * g.inv_sigma);
    g.peak * s.a * s.b * exp_neg(d2 * g.neg_inv_2v) * cx * cy
}

/// The oracle's `midpoint_correction` in f32.
#[inline]
fn correction(t: f32, r: f32) -> f32 {
    let (t2, r2) = (t * t, r * r);
    1.0 + r2 * (1.0 / 24.0) * (t2 - 1.0) + r2 * r2 * (1.0 / 1920.0) * (t2 * t2 - 6.0 * t2 + 3.0)
}

/// `exp(x)` for `x <= 0` (any finite value; below -87 gives about 0): `2^n exp(r)` with
/// `|r| <= ln 2 / 2` and the Taylor series to `r^7` (truncation below 1e-8 relative).
#[inline]
pub(super) fn exp_neg(x: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23: adding it rounds to an integer.
    let x = x.clamp(-87.0, 0.0);
    let n = (x * std::f32::consts::LOG2_E + MAGIC) - MAGIC;
    let r = x - n * 0.693_145_75 - n * 1.428_606_8e-6;
    let p = 1.0
        + r * (1.0
            + r * (0.5 + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r / 5040.0))))));
    f32::from_bits(((n as i32 + 127) << 23) as u32) * p
}

/// Covered texels sorted by grid cell, cells in `(z, y, x)` order, texels in index order.
struct Cells {
    cell: f32,
    support: f32,
    keys: Vec<[i32; 3]>,
    texels: Vec<u32>,
    sources: Vec<Source>,
}

impl Cells {
    fn new(bake: &ReferenceBake, kernel: &Kernel, support: f32) -> Self {
        let cell = support / CELLS_PER_SUPPORT;
        let mut entries: Vec<([i32; 3], u32)> = (0..bake.covered.len())
            .filter(|&i| bake.covered[i] && bake.position_mm[i].is_finite())
            .map(|i| (key(bake.position_mm[i], cell), i as u32))
            .collect();
        entries.sort_unstable();
        let sources: Vec<Source> = entries.iter().map(|&(_, i)| source(bake, kernel, i as usize)).collect();
        Self {
            cell,
            support,
            keys: entries.iter().map(|e| e.0).collect(),
            texels: entries.iter().map(|e| e.1).collect(),
            sources,
        }
    }

    /// Runs of equal keys: `(start, end)` into the sorted arrays.
    fn runs(&self) -> Vec<(usize, usize)> {
        let mut runs = Vec::new();
        let mut start = 0;
        for i in 1..=self.keys.len() {
            if i == self.keys.len() || self.keys[i] != self.keys[start] {
                runs.push((start, i));
                start = i;
            }
        }
        runs
    }

    /// The slices of sources that can lie within the support of any point in cell `k`.
    fn candidates(&self, k: [i32; 3]) -> Vec<(usize, usize)> {
        // A little slack so rounding in the keys never drops a texel at the support's edge.
        let reach = self.support * (1.0 + 1e-4) + 1e-4;
        let cells = (reach / self.cell).ceil() as i32;
        let gap = |d: i32| (d.abs() - 1).max(0) as f32 * self.cell;
        let mut out = Vec::new();
        for dz in -cells..=cells {
            for dy in -cells..=cells {
                let g2 = gap(dy).powi(2) + gap(dz).powi(2);
                if g2 > reach * reach {
                    continue;
                }
                let rx = (reach * reach - g2).sqrt();
                let lo = ((k[2] as f32 * self.cell - rx) / self.cell).floor() as i32;
                let hi = (((k[2] + 1) as f32 * self.cell + rx) / self.cell).floor() as i32;
                let (z, y) = (k[0] + dz, k[1] + dy);
                let start = self.keys.partition_point(|e| *e < [z, y, lo]);
                let end = self.keys.partition_point(|e| *e <= [z, y, hi]);
                if start < end {
                    out.push((start, end));
                }
            }
        }
        out
    }
}

/// Grid key `[z, y, x]` of a position.
fn key(p: Vec3, cell: f32) -> [i32; 3] {
    let f = |x: f32| (x / cell).floor() as i32;
    [f(p.z), f(p.y), f(p.x)]
}

pub(super) fn source(bake: &ReferenceBake, kernel: &Kernel, i: usize) -> Source {
    let f = bake.footprint[i];
    let (a, b) = (f.u_mm as f64, f.v_mm as f64);
    let first_midpoint = kernel.gaussians.iter().position(|g| a.max(b) < MIDPOINT_RATIO * g.sigma).unwrap_or(GAUSSIANS);
    let half_diagonal = 0.5 * a.hypot(b);
    // The widest Gaussian the narrow pass takes for this source.
    let widest = first_midpoint.clamp(FIRST_WIDE, GAUSSIANS) - 1;
    let reach = (kernel.gaussians[widest].reach2 as f64).sqrt() + half_diagonal;
    Source {
        position: bake.position_mm[i],
        normal: bake.normal[i],
        u_axis: f.u_axis,
        v_axis: f.v_axis,
        a: f.u_mm,
        b: f.v_mm,
        half_diagonal: half_diagonal as f32,
        first_midpoint: first_midpoint as u32,
        narrow_reach2: (reach * reach * (1.0 + 1e-4)) as f32,
        irradiance: bake.irradiance[i],
    }
}

/// [`super::scatter`]: scattered irradiance per texel.
pub(super) fn scatter(bake: &ReferenceBake, profile: &Profile) -> Vec<[f32; 3]> {
    let support = support_mm(profile) as f32;
    let kernel = Kernel::new(profile);
    let cells = Cells::new(bake, &kernel, support);
    // Covered texels without a finite position see no source: they keep their irradiance.
    let mut out: Vec<[f32; 3]> = (0..bake.covered.len())
        .map(|i| if bake.covered[i] { normalised([0.0; 3], [0.0; 3], bake.irradiance[i]) } else { [0.0; 3] })
        .collect();
    let results: Vec<Vec<(u32, [f32; 3])>> =
        cells.runs().into_par_iter().map(|run| scatter_cell(&cells, &kernel, run)).collect();
    for (i, m) in results.into_iter().flatten() {
        out[i as usize] = m;
    }
    out
}

/// The receivers of one grid cell.
fn scatter_cell(cells: &Cells, kernel: &Kernel, (start, end): (usize, usize)) -> Vec<(u32, [f32; 3])> {
    let near = Near::new(cells, cells.keys[start]);
    (start..end).map(|r| (cells.texels[r], receive(&near, kernel, &cells.sources[r]))).collect()
}

/// The sources within the support of some point of one grid cell, gathered in (cell, index)
/// order: every receiver of the cell reads one contiguous list.
struct Near {
    support: f32,
    sources: Vec<Source>,
    columns: Columns,
    /// The sources within their own narrow-pass reach of the cell.
    narrow: Vec<Source>,
    narrow_columns: Columns,
}

impl Near {
    fn new(cells: &Cells, k: [i32; 3]) -> Self {
        let lo = Vec3::new(k[2] as f32, k[1] as f32, k[0] as f32) * cells.cell;
        let hi = lo + Vec3::splat(cells.cell);
        let reach = cells.support * (1.0 + 1e-4) + 1e-4;
        let sources: Vec<Source> = cells
            .candidates(k)
            .into_iter()
            .flat_map(|(start, end)| &cells.sources[start..end])
            .filter(|s| {
                let gap = (lo - s.position).max(s.position - hi).max(Vec3::ZERO);
                gap.length_squared() <= reach * reach
            })
            .copied()
            .collect();
        let columns = Columns::new(&sources);
        let narrow: Vec<Source> = sources
            .iter()
            .filter(|s| {
                let gap = (lo - s.position).max(s.position - hi).max(Vec3::ZERO);
                gap.length_squared() <= s.narrow_reach2 * (1.0 + 1e-4) + 1e-4
            })
            .copied()
            .collect();
        let narrow_columns = Columns::new(&narrow);
        Self { support: cells.support, sources, columns, narrow, narrow_columns }
    }
}

/// `M_i` for one receiver from its cell's sources: the wide Gaussians over lanes
/// ([`wide_pass`]), the rest pair by pair ([`narrow_pass`]).
fn receive(near: &Near, kernel: &Kernel, receiver: &Source) -> [f32; 3] {
    let (l, t) = wide_pass(near, kernel, receiver, 0, near.sources.len());
    #[cfg(target_arch = "x86_64")]
    let (nl, nt) = simd::narrow_pass(near, kernel, receiver);
    #[cfg(not(target_arch = "x86_64"))]
    let (nl, nt) = narrow_pass(near, kernel, receiver);
    let light = std::array::from_fn(|c| l[c] as f64 + nl[c]);
    let total = std::array::from_fn(|c| t[c] as f64 + nt[c]);
    normalised(light, total, receiver.irradiance)
}

/// Lanes of the wide pass (one SSE vector).
const LANES: usize = 4;

/// Gaussians from this index on are taken in the wide pass for every source wider-than-texel.
const FIRST_WIDE: usize = 3;

/// The source columns the wide pass reads, one entry per sorted source.
struct Columns {
    p: [Vec<f32>; 3],
    n: [Vec<f32>; 3],
    u: [Vec<f32>; 3],
    v: [Vec<f32>; 3],
    a: Vec<f32>,
    b: Vec<f32>,
    half_diagonal: Vec<f32>,
    first_midpoint: Vec<f32>,
    e: [Vec<f32>; 3],
    /// Per wide Gaussian: 1 where the source takes it by the midpoint rule, else 0.
    midpoint: [Vec<f32>; GAUSSIANS - FIRST_WIDE],
}

impl Columns {
    fn new(sources: &[Source]) -> Self {
        let len = sources.len() + LANES;
        let column = || Vec::with_capacity(len);
        let mut c = Self {
            p: std::array::from_fn(|_| column()),
            n: std::array::from_fn(|_| column()),
            u: std::array::from_fn(|_| column()),
            v: std::array::from_fn(|_| column()),
            a: column(),
            b: column(),
            half_diagonal: column(),
            first_midpoint: column(),
            e: std::array::from_fn(|_| column()),
            midpoint: std::array::from_fn(|_| column()),
        };
        for s in sources {
            c.push(s);
        }
        // A vector's worth of zeros so the last group's loads stay in bounds.
        for _ in 0..LANES {
            c.push(&Source::default());
        }
        c
    }

    fn push(&mut self, s: &Source) {
        for i in 0..3 {
            self.p[i].push(s.position[i]);
            self.n[i].push(s.normal[i]);
            self.u[i].push(s.u_axis[i]);
            self.v[i].push(s.v_axis[i]);
            self.e[i].push(s.irradiance[i]);
        }
        self.a.push(s.a);
        self.b.push(s.b);
        self.half_diagonal.push(s.half_diagonal);
        self.first_midpoint.push(s.first_midpoint as f32);
        for (k, m) in self.midpoint.iter_mut().enumerate() {
            m.push(if (k + FIRST_WIDE) as u32 >= s.first_midpoint { 1.0 } else { 0.0 });
        }
    }
}

/// The wide Gaussians' (index [`FIRST_WIDE`] on) midpoint-rule weights of sources
/// `start..end`, everywhere in the support (beyond their skip radius they add less than
/// `exp(-20)` of their peak), in [`LANES`] independent f32 sums: `(light, total)` per channel.
fn wide_pass(near: &Near, kernel: &Kernel, r: &Source, start: usize, end: usize) -> ([f32; 3], [f32; 3]) {
    let mut acc = [[0.0f32; LANES]; 6];
    #[cfg(target_arch = "x86_64")]
    let mut j = simd::wide_lanes(near, kernel, r, start, end, &mut acc);
    #[cfg(not(target_arch = "x86_64"))]
    let mut j = start;
    while j < end {
        for l in 0..LANES.min(end - j) {
            let w = wide_weight(near, kernel, r, j + l);
            lane_add(&mut acc, l, w, near, j + l);
        }
        j += LANES;
    }
    let sum = |x: &[f32; LANES]| x.iter().sum::<f32>();
    (std::array::from_fn(|c| sum(&acc[c])), std::array::from_fn(|c| sum(&acc[3 + c])))
}

#[inline(always)]
fn lane_add(acc: &mut [[f32; LANES]; 6], l: usize, w: [f32; 3], near: &Near, j: usize) {
    for c in 0..3 {
        acc[c][l] += near.columns.e[c][j] * w[c];
        acc[3 + c][l] += w[c];
    }
}

/// One source's wide-Gaussian weights, branch-free (0 outside the support or across opposed
/// normals).
#[inline(always)]
fn wide_weight(near: &Near, kernel: &Kernel, r: &Source, j: usize) -> [f32; 3] {
    let c = &near.columns;
    let d = [r.position.x - c.p[0][j], r.position.y - c.p[1][j], r.position.z - c.p[2][j]];
    let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    let facing = r.normal.x * c.n[0][j] + r.normal.y * c.n[1][j] + r.normal.z * c.n[2][j];
    let inside = if d2 <= near.support * near.support && facing >= 0.0 { 1.0 } else { 0.0 };
    let dx = d[0] * c.u[0][j] + d[1] * c.u[1][j] + d[2] * c.u[2][j];
    let dy = d[0] * c.v[0][j] + d[1] * c.v[1][j] + d[2] * c.v[2][j];
    let (a, b) = (c.a[j], c.b[j]);
    let mut w = [0.0f32; 3];
    for (m, g) in kernel.gaussians[FIRST_WIDE..].iter().enumerate() {
        let cx = correction(dx * g.inv_sigma, a * g.inv_sigma);
        let cy = correction(dy * g.inv_sigma, b * g.inv_sigma);
        let value = inside * c.midpoint[m][j] * g.peak * a * b * exp_neg(d2 * g.neg_inv_2v) * cx * cy;
        for ch in 0..3 {
            w[ch] += g.weights[ch] * value;
        }
    }
    w
}

/// The Gaussians the wide pass leaves out (narrow ones, and wide ones of sources larger than
/// their sigma), pair by pair within their skip radius, in f64 sums: the narrow pass where
/// there is no SSE2 path.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn narrow_pass(near: &Near, kernel: &Kernel, r: &Source) -> ([f64; 3], [f64; 3]) {
    let (mut light, mut total) = ([0.0f64; 3], [0.0f64; 3]);
    for s in &near.narrow {
        let d = r.position - s.position;
        let d2 = d.length_squared();
        if d2 > s.narrow_reach2 || d2 > near.support * near.support || r.normal.dot(s.normal) < 0.0 {
            continue;
        }
        let w = kernel.weight(s, d, d2);
        for c in 0..3 {
            light[c] += (s.irradiance[c] * w[c]) as f64;
            total[c] += w[c] as f64;
        }
    }
    (light, total)
}

/// `light / total`, the receiver's own irradiance where nothing weighs, 0 where not finite.
fn normalised(light: [f64; 3], total: [f64; 3], e: [f32; 3]) -> [f32; 3] {
    std::array::from_fn(|c| {
        let m = if total[c] > 0.0 { (light[c] / total[c]) as f32 } else { e[c] };
        if m.is_finite() { m } else { 0.0 }
    })
}

/// The wide and narrow passes four sources at a time in SSE2 (always present on x86-64), by the
/// same operations in the same order as [`wide_weight`], [`exp_neg`], [`erfc`] and [`correction`].
#[cfg(target_arch = "x86_64")]
mod simd;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_matches_f64_exp() {
        let mut worst = 0.0f64;
        for k in 0..=200_000 {
            let x = -30.0 * k as f32 / 200_000.0;
            let exact = (x as f64).exp();
            worst = worst.max((exp_neg(x) as f64 - exact).abs() / exact);
        }
        assert!(worst < 3e-7, "{worst}");
        assert_eq!(exp_neg(0.0), 1.0);
        assert!(exp_neg(-1e30) < 1e-37 && exp_neg(f32::NEG_INFINITY) < 1e-37);
    }

    #[test]
    fn erfc_matches_libm() {
        let (mut worst, mut core) = (0.0f64, 0.0f64);
        for k in 0..=100_000 {
            let x = -4.0 + 10.0 * k as f32 / 100_000.0;
            let exact = libm::erfc(x as f64);
            // Relative where erfc is above 1e-8 (|x| < 4), absolute beyond.
            worst = worst.max((erfc(x) as f64 - exact).abs() / exact.max(1e-8));
            if (-3.0..=3.0).contains(&x) {
                core = core.max((erfc(x) as f64 - exact).abs() / exact);
            }
        }
        // The f32 rounding of `z^2` in the exponent grows toward |x| = 4.
        assert!(worst < 3e-6 && core < 1.5e-6, "{worst} {core}");
    }
}
