//! Quality metrics of synthesised maps (issue 3, "Quality you can measure"): how close an output's
//! statistics are to its exemplar's, whether it tiles, and whether it is a patchwork of large
//! copied blocks.
//!
//! * Histogram distance: exact 1-D Wasserstein-1 distance between empirical distributions
//!   ([`wasserstein_1d`]) of normal slopes ([`slope_distance`]) or colour channels
//!   ([`channel_distance`]).
//! * Spectrum distance: radially averaged power spectra ([`radial_power_spectrum`]) compared in
//!   log10 ([`spectrum_distance`]); for normal maps on the slope fields ([`normal_spectrum`]).
//! * Tileability: [`seam_energy`] compares the squared differences across the wrap-around boundary
//!   with those between interior neighbours (Wei and Levoy 2000 note that boundaries can stay
//!   visible, so we measure them).
//! * Copying: [`copy_statistics`] finds the connected blocks of a source-coordinate map that copy
//!   the exemplar verbatim.
//! * The guards' figures (`guard`): the variation an output kept ([`variation_ratio`]) and how far
//!   its histograms drifted ([`histogram_mismatch`]), both against the exemplar's own spread.
//!
//! Every metric is deterministic (fixed summation order, no dependence on the thread count) and
//! returns finite values on constant or empty inputs; each function says what it returns there.

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use skinkit_maps::{ColorMap, Grid, NormalMap};

mod guard;
pub(crate) use guard::std_dev;
pub use guard::{
    COLLAPSE_RATIO, GuardMeter, HISTOGRAM_RATIO, channel_histogram_mismatch, histogram_mismatch,
    slope_histogram_mismatch, slope_variation_ratio, variation_ratio,
};

/// Normals with `z` at or below this are skipped by [`slopes`]: their slope (over 1000, a surface
/// tilted beyond 89.94 degrees) carries no usable statistics, and invalid `(0, 0, 0)` normals fall
/// here too.
pub const MIN_NZ: f32 = 1e-3;

/// Default number of radial bins for spectra.
pub const DEFAULT_SPECTRUM_BINS: usize = 32;

/// Power floor (relative to a total of 1) used by [`spectrum_distance`] only when one spectrum is
/// all zero and the other is not: each such bin then costs up to 12 decades.
pub const SPECTRUM_FLOOR: f64 = 1e-12;

/// Surface slopes of every usable texel of a normal map, in scan order: `sx = -nx / nz` and
/// `sy = -ny / nz` (the height gradient `dh/dx`, `dh/dy` in the map's frame, y up), for texels with
/// `nz > MIN_NZ` (so invalid texels are skipped). Both vectors have the same length.
pub fn slopes(n: &NormalMap) -> (Vec<f32>, Vec<f32>) {
    n.as_slice().iter().filter(|v| v.z > MIN_NZ).map(|v| (-v.x / v.z, -v.y / v.z)).unzip()
}

/// Exact 1-D Wasserstein-1 distance between the empirical distributions of `a` and `b` (sizes may
/// differ): the integral over quantiles `q` in (0, 1) of `|F_a^-1(q) - F_b^-1(q)|`, where
/// `F^-1` of `n` sorted samples is the step function equal to the `i`-th sample on
/// `[i/n, (i+1)/n)`. Computed by sorting both and merging the quantile steps in exact integer
/// units of `1 / (n m)`.
///
/// Non-finite values are ignored. Returns 0 when both are empty and `f64::INFINITY` when exactly
/// one is (there is no distribution to compare with).
pub fn wasserstein_1d(a: &[f32], b: &[f32]) -> f64 {
    let a = sorted_finite(a);
    let b = sorted_finite(b);
    match (a.is_empty(), b.is_empty()) {
        (true, true) => return 0.0,
        (true, false) | (false, true) => return f64::INFINITY,
        _ => {}
    }
    let (n, m) = (a.len() as u128, b.len() as u128);
    let (mut i, mut j, mut q, mut sum) = (0usize, 0usize, 0u128, 0.0f64);
    // Quantile breakpoints of a are (i+1) m and of b are (j+1) n, in units of 1/(n m).
    while i < a.len() && j < b.len() {
        let next_a = (i as u128 + 1) * m;
        let next_b = (j as u128 + 1) * n;
        let next = next_a.min(next_b);
        sum += (next - q) as f64 * (a[i] as f64 - b[j] as f64).abs();
        q = next;
        i += usize::from(next_a == next);
        j += usize::from(next_b == next);
    }
    sum / (n * m) as f64
}

/// The finite values of `v`, sorted ascending.
fn sorted_finite(v: &[f32]) -> Vec<f32> {
    let mut out: Vec<f32> = v.iter().copied().filter(|x| x.is_finite()).collect();
    out.par_sort_unstable_by(f32::total_cmp);
    out
}

/// Slope-histogram distance of two normal maps: the mean of the [`wasserstein_1d`] distances of
/// their `sx` and of their `sy` samples ([`slopes`]); in slope units (0.1 is about 6 degrees of
/// tilt near flat). Infinite when exactly one map has no usable texel.
pub fn slope_distance(a: &NormalMap, b: &NormalMap) -> f64 {
    let (ax, ay) = slopes(a);
    let (bx, by) = slopes(b);
    0.5 * (wasserstein_1d(&ax, &bx) + wasserstein_1d(&ay, &by))
}

/// Channel-histogram distance of two colour maps: the mean over r, g, b of the
/// [`wasserstein_1d`] distances of that channel's values (all texels). Infinite when exactly one
/// map is empty.
pub fn channel_distance(a: &ColorMap, b: &ColorMap) -> f64 {
    (0..3).map(|c| wasserstein_1d(&channel(a, c), &channel(b, c))).sum::<f64>() / 3.0
}

/// Channel `c` (0, 1, 2) of every texel.
fn channel(g: &Grid<Vec3>, c: usize) -> Vec<f32> {
    g.as_slice().iter().map(|v| v[c]).collect()
}

/// Radially averaged power spectrum of a scalar map, normalised to a total of 1 (its shape, not its
/// level), in `bins` rings of equal width in radial frequency from 0 to Nyquist.
///
/// Steps: subtract the mean; multiply by a separable Hann window `sin^2(pi (i + 0.5) / n)` per
/// axis (to keep the edges of a non-periodic map from adding a cross of spurious power; the
/// half-texel offset keeps every texel, so 1-texel axes work); 2-D FFT (rows, then columns);
/// `|F|^2` at frequency `(fx, fy)` in cycles per texel goes to ring
/// `floor(bins * sqrt(fx^2 + fy^2) / 0.5)`. Frequencies are in cycles per texel, so maps of
/// different sizes are comparable. The DC term and the corners beyond the Nyquist radius are left
/// out (a frequency exactly at Nyquist goes to the last ring). Each ring holds the mean power of its
/// samples; a ring with no sample (more rings than the map resolves) holds 0.
///
/// A constant (or empty) map has no power: every ring is 0.
pub fn radial_power_spectrum(values: &Grid<f32>, bins: usize) -> Vec<f64> {
    normalise(raw_radial_spectrum(values, bins))
}

/// [`spectrum_distance`] of the [`radial_power_spectrum`]s of two scalar maps.
pub fn scalar_spectrum_distance(a: &Grid<f32>, b: &Grid<f32>, bins: usize) -> f64 {
    spectrum_distance(&radial_power_spectrum(a, bins), &radial_power_spectrum(b, bins))
}

/// Spectrum of a normal map: the sum of the unnormalised radial spectra of its slope fields `sx` and
/// `sy` (see [`slopes`]; unusable texels take the field's mean, so they add no power), normalised to
/// a total of 1. A flat map gives all zeros.
pub fn normal_spectrum(n: &NormalMap, bins: usize) -> Vec<f64> {
    let (sx, sy) = slope_fields(n);
    let px = raw_radial_spectrum(&sx, bins);
    let py = raw_radial_spectrum(&sy, bins);
    normalise(px.iter().zip(&py).map(|(x, y)| x + y).collect())
}

/// [`spectrum_distance`] of the [`normal_spectrum`]s of two normal maps.
pub fn normal_spectrum_distance(a: &NormalMap, b: &NormalMap, bins: usize) -> f64 {
    spectrum_distance(&normal_spectrum(a, bins), &normal_spectrum(b, bins))
}

/// Spectrum of a colour map: the sum of the unnormalised radial spectra of its three channels,
/// normalised to a total of 1.
pub fn color_spectrum(c: &ColorMap, bins: usize) -> Vec<f64> {
    let mut total = vec![0.0; bins];
    for ch in 0..3 {
        let g = c.map(|v| v[ch]);
        for (t, p) in total.iter_mut().zip(raw_radial_spectrum(&g, bins)) {
            *t += p;
        }
    }
    normalise(total)
}

/// [`spectrum_distance`] of the [`color_spectrum`]s of two colour maps.
pub fn color_spectrum_distance(a: &ColorMap, b: &ColorMap, bins: usize) -> f64 {
    spectrum_distance(&color_spectrum(a, bins), &color_spectrum(b, bins))
}

/// Distance between two radial spectra (as from [`radial_power_spectrum`]): the mean of
/// `|log10 Pa - log10 Pb|` over the rings where both have power (> 0), i.e. the mean number of
/// decades between them; 0.1 is about 26% per ring.
///
/// When no ring has power in both: 0 if both spectra are all zero (two constant maps are alike);
/// if only one spectrum has power, its rings are compared with [`SPECTRUM_FLOOR`] (a constant map
/// against a textured one scores up to 12). Rings past the shorter spectrum are ignored.
pub fn spectrum_distance(a: &[f64], b: &[f64]) -> f64 {
    let both: Vec<f64> =
        a.iter().zip(b).filter(|(x, y)| **x > 0.0 && **y > 0.0).map(|(x, y)| (x.log10() - y.log10()).abs()).collect();
    if !both.is_empty() {
        return both.iter().sum::<f64>() / both.len() as f64;
    }
    let one: Vec<f64> = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x > 0.0 || **y > 0.0)
        .map(|(x, y)| (x.max(SPECTRUM_FLOOR).log10() - y.max(SPECTRUM_FLOOR).log10()).abs())
        .collect();
    if one.is_empty() { 0.0 } else { one.iter().sum::<f64>() / one.len() as f64 }
}

/// Divides by the total (unchanged when the total is 0).
fn normalise(mut p: Vec<f64>) -> Vec<f64> {
    let total: f64 = p.iter().sum();
    if total > 0.0 {
        p.iter_mut().for_each(|v| *v /= total);
    }
    p
}

/// The `sx` and `sy` slope fields as grids; unusable texels take the mean of the usable ones.
fn slope_fields(n: &NormalMap) -> (Grid<f32>, Grid<f32>) {
    let (sx, sy) = slopes(n);
    let mean =
        |v: &[f32]| if v.is_empty() { 0.0 } else { (v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64) as f32 };
    let (mx, my) = (mean(&sx), mean(&sy));
    let field = |f: fn(Vec3) -> f32, m: f32| n.grid().map(|v| if v.z > MIN_NZ { f(*v) } else { m });
    (field(|v| -v.x / v.z, mx), field(|v| -v.y / v.z, my))
}

/// Ring means of `|F|^2` of the mean-removed, Hann-windowed map (not normalised).
fn raw_radial_spectrum(values: &Grid<f32>, bins: usize) -> Vec<f64> {
    let (w, h) = values.size();
    if bins == 0 || values.is_empty() {
        return vec![0.0; bins];
    }
    let power = power_spectrum(values);
    let mut sums = vec![0.0f64; bins];
    let mut counts = vec![0usize; bins];
    for ky in 0..h {
        for kx in 0..w {
            if let Some(bin) = ring(kx, w, ky, h, bins) {
                sums[bin] += power[ky * w + kx];
                counts[bin] += 1;
            }
        }
    }
    sums.iter().zip(&counts).map(|(s, &c)| if c > 0 { s / c as f64 } else { 0.0 }).collect()
}

/// Signed frequency of FFT index `k` of `n`, in cycles per texel (in [-0.5, 0.5]).
fn frequency(k: usize, n: usize) -> f64 {
    let k = if k <= n / 2 { k as f64 } else { k as f64 - n as f64 };
    k / n as f64
}

/// The ring of FFT index `(kx, ky)`, or `None` for DC and beyond Nyquist.
fn ring(kx: usize, w: usize, ky: usize, h: usize, bins: usize) -> Option<usize> {
    if kx == 0 && ky == 0 {
        return None;
    }
    let r = frequency(kx, w).hypot(frequency(ky, h)) / 0.5;
    (r <= 1.0).then(|| ((r * bins as f64) as usize).min(bins - 1))
}

/// Hann window `sin^2(pi (i + 0.5) / n)`.
fn hann(n: usize) -> Vec<f64> {
    (0..n).map(|i| (std::f64::consts::PI * (i as f64 + 0.5) / n as f64).sin().powi(2)).collect()
}

/// `|F|^2` of the mean-removed, windowed map, row-major with `F[ky * w + kx]`.
fn power_spectrum(values: &Grid<f32>) -> Vec<f64> {
    let (w, h) = values.size();
    let mean = values.as_slice().iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
    let (wx, wy) = (hann(w), hann(h));
    let mut rows: Vec<Complex<f64>> =
        (0..w * h).map(|i| Complex::new((values.as_slice()[i] as f64 - mean) * wx[i % w] * wy[i / w], 0.0)).collect();
    let mut planner = FftPlanner::<f64>::new();
    fft_rows(&mut rows, w, planner.plan_fft_forward(w));
    let mut cols = transpose(&rows, w, h);
    fft_rows(&mut cols, h, planner.plan_fft_forward(h));
    // cols[kx * h + ky]; return in row-major (ky, kx) order.
    (0..w * h).map(|i| cols[(i % w) * h + i / w].norm_sqr()).collect()
}

/// In-place FFT of every `len`-long row, rows in parallel (each row's transform is independent).
fn fft_rows(data: &mut [Complex<f64>], len: usize, fft: Arc<dyn Fft<f64>>) {
    data.par_chunks_mut(len).for_each_init(
        || vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()],
        |scratch, row| fft.process_with_scratch(row, scratch),
    );
}

/// Transpose of a row-major `w x h` array into a row-major `h x w` one.
fn transpose(data: &[Complex<f64>], w: usize, h: usize) -> Vec<Complex<f64>> {
    (0..w * h).map(|i| data[(i % h) * w + i / h]).collect()
}

/// Squared differences across a map's wrap-around boundary against those between interior
/// neighbours (see [`seam_energy`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeamEnergy {
    /// Mean `|a - b|^2` over the wrap pairs: (last column, first column) of every row and (last row,
    /// first row) of every column.
    pub across_seam: f64,
    /// Mean `|a - b|^2` over all horizontally and vertically adjacent pairs inside the map.
    pub interior: f64,
    /// `across_seam / interior`: about 1 when the map tiles, large when the seam shows. 1 when both
    /// are 0 (a constant map tiles); when only the interior is 0, `across_seam / f64::MIN_POSITIVE`.
    pub ratio: f64,
}

/// Seam energy of a vector map (colour, or unnormalised normals): the mean squared difference
/// between texels paired across the wrap-around boundary (last column with first column, last row
/// with first row) versus the mean over all interior adjacent pairs. A side of length 1 adds no
/// pairs; a map with no pair at all gives zeros and ratio 1.
pub fn seam_energy(map: &Grid<Vec3>) -> SeamEnergy {
    seam_energy_where(map, |_| true)
}

/// [`seam_energy`] of a normal map, skipping every pair that involves an invalid `(0, 0, 0)` texel.
pub fn normal_seam_energy(n: &NormalMap) -> SeamEnergy {
    seam_energy_where(n.grid(), |v| v != Vec3::ZERO)
}

/// [`seam_energy`] of a scalar map.
pub fn scalar_seam_energy(map: &Grid<f32>) -> SeamEnergy {
    seam_energy_where(&map.map(|&v| Vec3::new(v, 0.0, 0.0)), |_| true)
}

/// Running sum and count of squared differences.
#[derive(Default)]
struct PairSum {
    sum: f64,
    count: usize,
}

impl PairSum {
    fn add(&mut self, a: Vec3, b: Vec3, valid: &impl Fn(Vec3) -> bool) {
        if valid(a) && valid(b) {
            self.sum += (a.as_dvec3() - b.as_dvec3()).length_squared();
            self.count += 1;
        }
    }
    fn mean(&self) -> f64 {
        if self.count == 0 { 0.0 } else { self.sum / self.count as f64 }
    }
}

/// Seam energy over the pairs whose texels both satisfy `valid`.
fn seam_energy_where(map: &Grid<Vec3>, valid: impl Fn(Vec3) -> bool) -> SeamEnergy {
    let mut meter = SeamMeter::new(map.size(), valid);
    meter.add(map.as_slice());
    meter.finish()
}

/// [`seam_energy`] of a map measured as its rows come, top to bottom: the same sums in the same
/// order (a row is counted once the row below it has come; the last row against the first at the
/// end), so the same bits as on the whole map, holding two rows.
pub struct SeamMeter<F> {
    size: (usize, usize),
    valid: F,
    first: Vec<Vec3>,
    last: Vec<Vec3>,
    rows: usize,
    seam: PairSum,
    inner: PairSum,
}

impl<F: Fn(Vec3) -> bool> SeamMeter<F> {
    /// A meter of a `size` map over the pairs whose texels both satisfy `valid`
    /// (`|v| v != Vec3::ZERO` for normal maps, as [`normal_seam_energy`]).
    pub fn new(size: (usize, usize), valid: F) -> Self {
        SeamMeter {
            size,
            valid,
            first: Vec::new(),
            last: Vec::new(),
            rows: 0,
            seam: PairSum::default(),
            inner: PairSum::default(),
        }
    }

    /// Counts the next whole rows.
    pub fn add(&mut self, rows: &[Vec3]) {
        for row in rows.chunks_exact(self.size.0.max(1)) {
            if self.rows == 0 {
                self.first = row.to_vec();
            } else {
                let above = std::mem::take(&mut self.last);
                self.count_row(self.rows - 1, &above, row);
            }
            self.last = row.to_vec();
            self.rows += 1;
        }
    }

    /// The pairs of row `y`: each texel with its right neighbour, then with the one below.
    fn count_row(&mut self, y: usize, row: &[Vec3], below: &[Vec3]) {
        let (w, h) = self.size;
        for x in 0..w {
            let right = if x + 1 < w { &mut self.inner } else { &mut self.seam };
            if w > 1 {
                right.add(row[x], row[(x + 1) % w], &self.valid);
            }
            let down = if y + 1 < h { &mut self.inner } else { &mut self.seam };
            if h > 1 {
                down.add(row[x], below[x], &self.valid);
            }
        }
    }

    /// The energy, once every row has come.
    pub fn finish(mut self) -> SeamEnergy {
        if self.rows > 0 {
            let (last, first) = (std::mem::take(&mut self.last), std::mem::take(&mut self.first));
            self.count_row(self.rows - 1, &last, &first);
        }
        let (across_seam, interior) = (self.seam.mean(), self.inner.mean());
        let ratio = if interior > 0.0 {
            across_seam / interior
        } else if across_seam > 0.0 {
            across_seam / f64::MIN_POSITIVE
        } else {
            1.0
        };
        SeamEnergy { across_seam, interior, ratio }
    }
}

/// Copied blocks of a source-coordinate map (see [`copy_statistics`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CopyStats {
    /// Texels of the largest connected verbatim copy.
    pub largest_block: usize,
    /// Mean block size: texels / blocks (1 when no neighbours copy neighbours).
    pub mean_block: f64,
    /// Number of distinct offsets `src - dst` (modulo the exemplar size when it wraps).
    pub distinct_offsets: usize,
}

/// Copy statistics of a source-coordinate map: `coords` holds, per output texel `(x, y)`, the
/// exemplar texel `[sx, sy]` it copies. Two 4-adjacent output texels belong to the same block when
/// they copy adjacent exemplar texels in the same arrangement, i.e. their offsets `src - dst` are
/// equal (modulo `exemplar_size` on each axis when `wrap`, the exemplar being a torus then).
/// The output is toroidal, as synthesis outputs are: the last column is adjacent to the first
/// (and the last row to the first row), and a pair there is in one block when the source of the
/// first-column texel is one step right of the source of the last-column texel (same for rows).
/// Blocks are the connected components (union-find); an empty map gives zeros.
pub fn copy_statistics(coords: &Grid<[u32; 2]>, exemplar_size: (usize, usize), wrap: bool) -> CopyStats {
    if coords.is_empty() {
        return CopyStats { largest_block: 0, mean_block: 0.0, distinct_offsets: 0 };
    }
    let blocks = copy_blocks(coords, exemplar_size, wrap);
    let largest_block = blocks.block_sizes().max().unwrap_or(0);
    let mean_block = coords.len() as f64 / blocks.block_sizes().count() as f64;
    let modulus = (exemplar_size.0.max(1) as i64, exemplar_size.1.max(1) as i64);
    CopyStats { largest_block, mean_block, distinct_offsets: distinct_offsets(coords, modulus, wrap) }
}

/// The verbatim blocks of a source-coordinate map (as [`copy_statistics`] defines them): per
/// texel (row-major) its block's label, the index of one texel of the block; and per texel index
/// the size of the block it labels (0 for texels that label none).
#[derive(Clone, Debug, PartialEq)]
pub struct CopyBlocks {
    pub labels: Vec<u32>,
    pub sizes: Vec<u32>,
}

impl CopyBlocks {
    /// The size of the block texel `i` belongs to.
    pub fn size_at(&self, i: usize) -> u32 {
        self.sizes[self.labels[i] as usize]
    }
    /// The sizes of all blocks.
    pub fn block_sizes(&self) -> impl Iterator<Item = usize> + '_ {
        self.sizes.iter().filter(|&&s| s > 0).map(|&s| s as usize)
    }
}

/// The connected blocks of `coords` (see [`copy_statistics`]). Maps of `2^32` texels or more are
/// not supported (the union-find uses `u32` indices).
pub fn copy_blocks(coords: &Grid<[u32; 2]>, exemplar_size: (usize, usize), wrap: bool) -> CopyBlocks {
    let (w, h) = coords.size();
    let modulus = (exemplar_size.0.max(1) as i64, exemplar_size.1.max(1) as i64);
    let follows = |a: [u32; 2], b: [u32; 2], dx: i64, dy: i64| {
        let (ex, ey) = (b[0] as i64 - a[0] as i64 - dx, b[1] as i64 - a[1] as i64 - dy);
        if wrap { ex.rem_euclid(modulus.0) == 0 && ey.rem_euclid(modulus.1) == 0 } else { ex == 0 && ey == 0 }
    };
    let mut sets = DisjointSets::new(w * h);
    for y in 0..h {
        for x in 0..w {
            let p = *coords.get(x, y);
            if w > 1 && follows(p, *coords.get((x + 1) % w, y), 1, 0) {
                sets.union(y * w + x, y * w + (x + 1) % w);
            }
            if h > 1 && follows(p, *coords.get(x, (y + 1) % h), 0, 1) {
                sets.union(y * w + x, ((y + 1) % h) * w + x);
            }
        }
    }
    // Every texel points at its root after this; the parents become the labels and the sizes of
    // the roots the block sizes (no second map of the same size is allocated).
    for i in 0..w * h {
        let root = sets.find(i);
        sets.parent[i] = root as u32;
    }
    let DisjointSets { parent: labels, size } = sets;
    let sizes = size.iter().enumerate().map(|(i, &s)| if labels[i] as usize == i { s } else { 0 }).collect();
    CopyBlocks { labels, sizes }
}

/// Number of distinct `src - dst` offsets (reduced modulo the exemplar size when `wrap`).
fn distinct_offsets(coords: &Grid<[u32; 2]>, modulus: (i64, i64), wrap: bool) -> usize {
    let w = coords.width();
    let mut offsets: Vec<(i64, i64)> = coords
        .as_slice()
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (ox, oy) = (s[0] as i64 - (i % w) as i64, s[1] as i64 - (i / w) as i64);
            if wrap { (ox.rem_euclid(modulus.0), oy.rem_euclid(modulus.1)) } else { (ox, oy) }
        })
        .collect();
    offsets.sort_unstable();
    offsets.dedup();
    offsets.len()
}

/// Union-find with path halving and union by size.
struct DisjointSets {
    /// `u32` indices: half the memory of `usize` on the largest maps (8192^2 texels: 512 MiB for
    /// both vectors), which the copy cap builds at the finest level.
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl DisjointSets {
    /// Sets over `n < 2^32` elements.
    fn new(n: usize) -> Self {
        assert!(u32::try_from(n).is_ok(), "{n} elements do not fit u32 indices");
        DisjointSets { parent: (0..n as u32).collect(), size: vec![1; n] }
    }
    fn find(&mut self, i: usize) -> usize {
        let mut i = i as u32;
        while self.parent[i as usize] != i {
            self.parent[i as usize] = self.parent[self.parent[i as usize] as usize];
            i = self.parent[i as usize];
        }
        i as usize
    }
    fn union(&mut self, a: usize, b: usize) {
        let (mut ra, mut rb) = (self.find(a), self.find(b));
        if ra == rb {
            return;
        }
        if self.size[ra] < self.size[rb] {
            std::mem::swap(&mut ra, &mut rb);
        }
        self.parent[rb] = ra as u32;
        self.size[ra] += self.size[rb];
    }
}
