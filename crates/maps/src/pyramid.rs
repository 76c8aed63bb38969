//! Burt-Adelson Gaussian and Laplacian pyramids (Burt and Adelson 1983, "A multiresolution spline
//! with application to image mosaics"), used by synthesis (Wei and Levoy 2000 build a Gaussian
//! pyramid of the exemplar and of the output) and by stitching (the multiresolution spline).
//!
//! The generating kernel is the 5-tap `w = [0.05, 0.25, 0.4, 0.25, 0.05]` (a = 0.4), applied
//! separably. [`reduce`] blurs and keeps the even texels (`ceil(w/2) x ceil(h/2)`); [`expand`]
//! upsamples with the same kernel and the x4 gain of Burt-Adelson, which separably gives the
//! weights `[0.1, 0.8, 0.1]` at even texels and `[0.5, 0.5]` at odd ones, so constants stay
//! constant. [`laplacian`] stores `G_i - expand(G_{i+1})` and the coarsest Gaussian, so
//! [`collapse`] reverses it exactly up to float rounding, whatever the border rule.
//!
//! Borders: [`Border::Wrap`] treats the grid as a torus (synthesis outputs tile); [`Border::Clamp`]
//! replicates the edge texel (exemplars, stitching regions). Under `Wrap`, [`reduce`] commutes with
//! shifts by 2 texels only on even sides: an odd side has no toroidal half-size grid, so its last
//! coarse texel sits one texel from the first (still exact through [`collapse`]). Every pass runs rows in parallel; each
//! output texel is a fixed sum in a fixed order, so results do not depend on the thread count.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::Grid;

/// The Burt-Adelson generating kernel with a = 0.4; it sums to 1.
pub const KERNEL: [f32; 5] = [0.05, 0.25, 0.4, 0.25, 0.05];

/// Expand weights at an even fine texel `2i` (taps at coarse `i-1, i, i+1`): `2 * [w(-2), w(0), w(2)]`.
const EXPAND_EVEN: [f32; 3] = [0.1, 0.8, 0.1];
/// Expand weights at an odd fine texel `2i+1` (taps at coarse `i, i+1`): `2 * [w(-1), w(1)]`.
const EXPAND_ODD: [f32; 2] = [0.5, 0.5];

/// A value a pyramid can hold: a vector space over `f32` (scalars, colours, unnormalised normals,
/// slopes).
pub trait Texel:
    Copy
    + Send
    + Sync
    + Default
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<f32, Output = Self>
{
}
impl Texel for f32 {}
impl Texel for Vec3 {}
impl Texel for Vec2 {}

/// How filters read past the edge of a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Border {
    /// Toroidal: index `-1` is the last texel (synthesis outputs, which tile).
    Wrap,
    /// Replicate the edge texel (exemplars, stitching regions).
    Clamp,
}

impl Border {
    /// Maps a possibly out-of-range index into `0..n` (`n >= 1`).
    fn index(self, i: isize, n: usize) -> usize {
        match self {
            Border::Wrap => i.rem_euclid(n as isize) as usize,
            Border::Clamp => i.clamp(0, n as isize - 1) as usize,
        }
    }
}

/// The 5-tap kernel applied separably at every texel; same size as `g`.
pub fn blur<T: Texel>(g: &Grid<T>, border: Border) -> Grid<T> {
    vertical(&horizontal(g, border, 1), border, 1)
}

/// Blur then keep the even texels: a `ceil(w/2) x ceil(h/2)` grid (only the kept texels are
/// computed).
pub fn reduce<T: Texel>(g: &Grid<T>, border: Border) -> Grid<T> {
    vertical(&horizontal(g, border, 2), border, 2)
}

/// Upsamples `g` to `width x height` with the generating kernel and the x4 gain of Burt-Adelson:
/// fine texel `2i` is `0.1 g[i-1] + 0.8 g[i] + 0.1 g[i+1]`, fine texel `2i+1` is
/// `0.5 g[i] + 0.5 g[i+1]`, separably, coarse indices past the edge read through `border`.
/// The target is normally the size `g` was reduced from; an empty `g` gives a grid of defaults.
pub fn expand<T: Texel>(g: &Grid<T>, width: usize, height: usize, border: Border) -> Grid<T> {
    if g.is_empty() {
        return Grid::filled(width, height, T::default());
    }
    expand_vertical(&expand_horizontal(g, width, border), height, border)
}

/// Gaussian pyramid: `[0]` is a copy of `g`, each next level is [`reduce`] of the previous one.
/// Holds `levels` grids (at least one), fewer when the grid is already 1x1 (reducing it further
/// would not change its size; see [`max_levels`]).
pub fn gaussian<T: Texel>(g: &Grid<T>, levels: usize, border: Border) -> Vec<Grid<T>> {
    let count = levels.max(1).min(max_levels(g.width(), g.height(), 1).max(1));
    let mut out = Vec::with_capacity(count);
    out.push(g.clone());
    while out.len() < count {
        let next = reduce(out.last().expect("pyramid has a level"), border);
        out.push(next);
    }
    out
}

/// Laplacian pyramid: level `i` is `G_i - expand(G_{i+1})` (a band-pass image of `G_i`'s size), the
/// last level is the coarsest Gaussian level. Same level count as [`gaussian`].
pub fn laplacian<T: Texel>(g: &Grid<T>, levels: usize, border: Border) -> Vec<Grid<T>> {
    let gauss = gaussian(g, levels, border);
    let mut out: Vec<Grid<T>> = gauss
        .windows(2)
        .map(|pair| {
            let up = expand(&pair[1], pair[0].width(), pair[0].height(), border);
            zip_with(&pair[0], &up, |a, b| a - b)
        })
        .collect();
    out.push(gauss.last().expect("pyramid has a level").clone());
    out
}

/// Inverse of [`laplacian`] (same `border`): from the coarsest level up, `G_i = L_i + expand(G_{i+1})`.
/// Exact up to float rounding. An empty slice gives an empty grid.
pub fn collapse<T: Texel>(levels: &[Grid<T>], border: Border) -> Grid<T> {
    let Some((coarsest, finer)) = levels.split_last() else {
        return Grid::filled(0, 0, T::default());
    };
    finer.iter().rev().fold(coarsest.clone(), |acc, band| {
        let up = expand(&acc, band.width(), band.height(), border);
        zip_with(band, &up, |a, b| a + b)
    })
}

/// How many pyramid levels of a `width x height` grid keep both sides `>= min_side` (sides halve
/// rounding up; `min_side` 0 counts as 1). The count stops at the first 1x1 level, since reducing
/// 1x1 changes nothing. 0 when the grid itself is smaller than `min_side`.
pub fn max_levels(width: usize, height: usize, min_side: usize) -> usize {
    let min_side = min_side.max(1);
    let (mut w, mut h, mut levels) = (width, height, 0);
    while w >= min_side && h >= min_side {
        levels += 1;
        if w <= 1 && h <= 1 {
            break;
        }
        (w, h) = (w.div_ceil(2), h.div_ceil(2));
    }
    levels
}

/// Texel-wise `f(a, b)` of two grids of the same size.
fn zip_with<T: Texel>(a: &Grid<T>, b: &Grid<T>, f: impl Fn(T, T) -> T + Sync) -> Grid<T> {
    debug_assert_eq!(a.size(), b.size());
    let mut out = a.clone();
    out.as_mut_slice().par_iter_mut().zip(b.as_slice().par_iter()).for_each(|(x, &y)| *x = f(*x, y));
    out
}

/// For each output index `o` of `0..n.div_ceil(step)`, the five source indices around `o * step`.
fn kernel_taps(n: usize, step: usize, border: Border) -> Vec<[usize; 5]> {
    (0..n.div_ceil(step))
        .map(|o| {
            let c = (o * step) as isize;
            std::array::from_fn(|k| border.index(c + k as isize - 2, n))
        })
        .collect()
}

/// Kernel sum of five source values in a fixed order.
fn weigh<T: Texel>(taps: &[usize; 5], value: impl Fn(usize) -> T) -> T {
    taps.iter().zip(KERNEL).fold(T::default(), |acc, (&i, w)| acc + value(i) * w)
}

/// Horizontal 5-tap pass, keeping every `step`-th column.
fn horizontal<T: Texel>(g: &Grid<T>, border: Border, step: usize) -> Grid<T> {
    let (w, h) = g.size();
    if g.is_empty() {
        return Grid::filled(w.div_ceil(step), h, T::default());
    }
    let taps = kernel_taps(w, step, border);
    let mut out = Grid::filled(taps.len(), h, T::default());
    out.par_rows_mut().for_each(|(y, row)| {
        let src = g.row(y);
        for (o, t) in row.iter_mut().zip(&taps) {
            *o = weigh(t, |i| src[i]);
        }
    });
    out
}

/// Vertical 5-tap pass, keeping every `step`-th row.
fn vertical<T: Texel>(g: &Grid<T>, border: Border, step: usize) -> Grid<T> {
    let (w, h) = g.size();
    if g.is_empty() {
        return Grid::filled(w, h.div_ceil(step), T::default());
    }
    let taps = kernel_taps(h, step, border);
    let mut out = Grid::filled(w, taps.len(), T::default());
    out.par_rows_mut().for_each(|(y, row)| {
        let rows: [&[T]; 5] = std::array::from_fn(|k| g.row(taps[y][k]));
        for (x, o) in row.iter_mut().enumerate() {
            *o = rows.iter().zip(KERNEL).fold(T::default(), |acc, (r, wt)| acc + r[x] * wt);
        }
    });
    out
}

/// For each fine index in `0..fine`, up to three coarse indices (of `0..coarse`) and weights.
fn expand_taps(fine: usize, coarse: usize, border: Border) -> Vec<[(usize, f32); 3]> {
    (0..fine)
        .map(|x| {
            let i = (x / 2) as isize;
            let at = |d: isize| border.index(i + d, coarse);
            if x % 2 == 0 {
                [(at(-1), EXPAND_EVEN[0]), (at(0), EXPAND_EVEN[1]), (at(1), EXPAND_EVEN[2])]
            } else {
                [(at(0), EXPAND_ODD[0]), (at(1), EXPAND_ODD[1]), (at(0), 0.0)]
            }
        })
        .collect()
}

/// Weighted sum of up to three values in a fixed order.
fn weigh3<T: Texel>(taps: &[(usize, f32); 3], value: impl Fn(usize) -> T) -> T {
    taps.iter().fold(T::default(), |acc, &(i, w)| acc + value(i) * w)
}

/// Horizontal expansion of every row to `width` columns.
fn expand_horizontal<T: Texel>(g: &Grid<T>, width: usize, border: Border) -> Grid<T> {
    let taps = expand_taps(width, g.width(), border);
    let mut out = Grid::filled(width, g.height(), T::default());
    out.par_rows_mut().for_each(|(y, row)| {
        let src = g.row(y);
        for (o, t) in row.iter_mut().zip(&taps) {
            *o = weigh3(t, |i| src[i]);
        }
    });
    out
}

/// Vertical expansion of every column to `height` rows.
fn expand_vertical<T: Texel>(g: &Grid<T>, height: usize, border: Border) -> Grid<T> {
    let taps = expand_taps(height, g.height(), border);
    let mut out = Grid::filled(g.width(), height, T::default());
    if g.width() == 0 {
        return out;
    }
    out.par_rows_mut().for_each(|(y, row)| {
        let rows: [(&[T], f32); 3] = std::array::from_fn(|k| (g.row(taps[y][k].0), taps[y][k].1));
        for (x, o) in row.iter_mut().enumerate() {
            *o = rows.iter().fold(T::default(), |acc, (r, wt)| acc + r[x] * *wt);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const BORDERS: [Border; 2] = [Border::Wrap, Border::Clamp];

    /// Deterministic pseudo-random values in [-1, 1) (a 64-bit LCG; the crate has no rand dependency).
    fn noise(width: usize, height: usize, seed: u64) -> Grid<f32> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let data = (0..width * height)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
            })
            .collect();
        Grid::from_vec(width, height, data).unwrap()
    }

    fn max_diff(a: &Grid<f32>, b: &Grid<f32>) -> f32 {
        assert_eq!(a.size(), b.size());
        a.as_slice().iter().zip(b.as_slice()).map(|(x, y)| (x - y).abs()).fold(0.0, f32::max)
    }

    /// Direct 2-D convolution with the outer product of the kernel, reading through `border`.
    fn blur_oracle(g: &Grid<f32>, border: Border) -> Grid<f32> {
        let (w, h) = g.size();
        Grid::from_fn(w, h, |x, y| {
            let mut sum = 0.0f64;
            for (dy, ky) in KERNEL.iter().enumerate() {
                for (dx, kx) in KERNEL.iter().enumerate() {
                    let sx = border.index(x as isize + dx as isize - 2, w);
                    let sy = border.index(y as isize + dy as isize - 2, h);
                    sum += (*kx as f64) * (*ky as f64) * (*g.get(sx, sy) as f64);
                }
            }
            sum as f32
        })
    }

    #[test]
    fn kernel_sums_to_one_and_expand_weights_are_twice_the_kernel() {
        assert!((KERNEL.iter().sum::<f32>() - 1.0).abs() < 1e-7);
        assert!((EXPAND_EVEN.iter().sum::<f32>() - 1.0).abs() < 1e-7);
        assert!((EXPAND_ODD.iter().sum::<f32>() - 1.0).abs() < 1e-7);
        assert_eq!(EXPAND_EVEN, [2.0 * KERNEL[0], 2.0 * KERNEL[2], 2.0 * KERNEL[4]]);
        assert_eq!(EXPAND_ODD, [2.0 * KERNEL[1], 2.0 * KERNEL[3]]);
    }

    #[test]
    fn constants_stay_constant() {
        for border in BORDERS {
            for (w, h) in [(7, 5), (8, 8), (1, 9), (1, 1), (2, 3)] {
                let g = Grid::filled(w, h, 0.3f32);
                let c = Grid::filled(w, h, 0.3f32);
                assert!(max_diff(&blur(&g, border), &c) < 1e-6, "{border:?} {w}x{h}");
                let r = reduce(&g, border);
                assert!(max_diff(&r, &Grid::filled(r.width(), r.height(), 0.3)) < 1e-6);
                assert!(max_diff(&expand(&r, w, h, border), &c) < 1e-6);
                let v = Grid::filled(w, h, Vec3::new(1.0, -2.0, 0.5));
                let e = expand(&reduce(&v, border), w, h, border);
                assert!(e.as_slice().iter().all(|p| (*p - Vec3::new(1.0, -2.0, 0.5)).abs().max_element() < 1e-6));
            }
        }
    }

    #[test]
    fn blur_matches_direct_convolution() {
        for border in BORDERS {
            for (w, h, seed) in [(13, 9, 1), (4, 4, 2), (1, 6, 3), (3, 1, 4), (2, 2, 5)] {
                let g = noise(w, h, seed);
                let d = max_diff(&blur(&g, border), &blur_oracle(&g, border));
                assert!(d < 1e-6, "{border:?} {w}x{h}: {d}");
            }
        }
    }

    #[test]
    fn reduce_keeps_even_texels_of_the_blur() {
        for border in BORDERS {
            let g = noise(11, 6, 7);
            let b = blur(&g, border);
            let r = reduce(&g, border);
            assert_eq!(r.size(), (6, 3));
            for (x, y) in [(0, 0), (5, 2), (3, 1)] {
                assert!((r.get(x, y) - b.get(2 * x, 2 * y)).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn reduce_sizes_round_up() {
        let sizes: Vec<_> = [(1, 1), (1, 7), (5, 3), (8, 9), (2, 2)]
            .iter()
            .map(|&(w, h)| reduce(&Grid::filled(w, h, 0.0f32), Border::Clamp).size())
            .collect();
        assert_eq!(sizes, vec![(1, 1), (1, 4), (3, 2), (4, 5), (1, 1)]);
    }

    #[test]
    fn wrapped_reduce_commutes_with_shifts() {
        let g = noise(16, 12, 11);
        let shifted = Grid::from_fn(16, 12, |x, y| *g.get_wrapped(x as isize - 2, y as isize - 4));
        let r = reduce(&g, Border::Wrap);
        let rs = reduce(&shifted, Border::Wrap);
        let expect = Grid::from_fn(8, 6, |x, y| *r.get_wrapped(x as isize - 1, y as isize - 2));
        assert!(max_diff(&rs, &expect) < 1e-6);
        // Clamp does not commute with shifts: the test above is not vacuous.
        let rc = reduce(&shifted, Border::Clamp);
        assert!(max_diff(&rc, &expect) > 1e-3);
    }

    #[test]
    fn expand_interpolates_linear_ramps_inside() {
        // The expand weights reproduce linear functions away from the border: coarse i sits at 2i.
        let coarse = Grid::from_fn(6, 1, |x, _| x as f32 * 2.0);
        let fine = expand(&coarse, 11, 1, Border::Clamp);
        for x in 1..10 {
            assert!((fine.get(x, 0) - x as f32).abs() < 1e-5, "{x}: {}", fine.get(x, 0));
        }
    }

    #[test]
    fn collapse_inverts_laplacian() {
        for border in BORDERS {
            for (w, h, levels) in [(33, 20, 5), (16, 16, 4), (1, 1, 3), (1, 13, 4), (9, 1, 6), (7, 7, 10)] {
                let g = noise(w, h, (w * 31 + h) as u64);
                let lap = laplacian(&g, levels, border);
                assert_eq!(lap[0].size(), (w, h));
                let back = collapse(&lap, border);
                assert!(max_diff(&back, &g) < 1e-5, "{border:?} {w}x{h}");
            }
        }
        let v = Grid::from_fn(10, 6, |x, y| Vec3::new(x as f32, y as f32, (x * y) as f32 * 0.1));
        let back = collapse(&laplacian(&v, 3, Border::Wrap), Border::Wrap);
        assert!(v.as_slice().iter().zip(back.as_slice()).all(|(a, b)| (*a - *b).abs().max_element() < 1e-5));
    }

    #[test]
    fn gaussian_levels_and_max_levels_agree() {
        let g = noise(20, 9, 3);
        let pyr = gaussian(&g, 10, Border::Clamp);
        let sizes: Vec<_> = pyr.iter().map(Grid::size).collect();
        assert_eq!(sizes, vec![(20, 9), (10, 5), (5, 3), (3, 2), (2, 1), (1, 1)]);
        assert_eq!(max_levels(20, 9, 1), 6);
        assert_eq!(max_levels(20, 9, 3), 3);
        assert_eq!(max_levels(2, 9, 3), 0);
        assert_eq!(max_levels(1, 1, 0), 1);
        assert_eq!(max_levels(128, 128, 1), 8);
        assert_eq!(gaussian(&g, 0, Border::Wrap).len(), 1);
        assert_eq!(pyr[0], g);
        assert!(max_diff(&pyr[1], &reduce(&g, Border::Clamp)) == 0.0);
    }

    #[test]
    fn empty_grids_do_not_panic() {
        let e = Grid::filled(0, 0, 0.0f32);
        assert!(blur(&e, Border::Wrap).is_empty());
        assert!(reduce(&e, Border::Clamp).is_empty());
        assert_eq!(collapse(&laplacian(&e, 3, Border::Wrap), Border::Wrap).size(), (0, 0));
        assert!(collapse::<f32>(&[], Border::Clamp).is_empty());
    }

    #[test]
    fn results_do_not_depend_on_thread_count() {
        let g = noise(64, 48, 9);
        let many = laplacian(&g, 4, Border::Wrap);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let one = pool.install(|| laplacian(&g, 4, Border::Wrap));
        assert_eq!(many, one);
    }
}
