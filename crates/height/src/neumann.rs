//! The Neumann solve ([`Neumann`]): a DCT along rows, a tridiagonal solve down each column of
//! the rows' spectra ([`crate::tridiagonal`]), the inverse DCT along rows; and the whole
//! integration of a map whose every normal is usable fused into three passes over memory
//! ([`integrate_valid`]), the default for rectangular maps.
//!
//! The fused integration classifies each row's normals, forms its right-hand side and takes its
//! DCT-II while the row is in cache; solves the columns a strip at a time, sweeping down and up
//! the rows; and takes each row's DCT-III while measuring the heights. No pass transposes the
//! map. The integrability residual comes from the solve, not from another pass: for the
//! least-squares solution `h` of `D h = g`, `|D h - g|^2 = |g|^2 - b . h` with `b = D^T g`, and
//! the column solve returns `b . h`.

use std::f64::consts::PI;

use rayon::prelude::*;
use skinkit_maps::NormalMap;

use crate::Moments;
use crate::dct::Dct;
use crate::poisson::eigenvalues;
use crate::slopes::{TexelCounts, usable_row};
use crate::tridiagonal::Columns;

/// Rows per task of the row passes.
const ROWS_PER_TASK: usize = 16;
/// Running sums per accumulation (fixed, so sums have the same bits on any thread count).
const LANES: usize = 8;

/// `L^-1` for the Neumann Laplacian of a `w x h` grid, planned once (the masked solve applies it
/// every iteration): DCT-II along rows, the columns' tridiagonal systems, DCT-III along rows.
pub struct Neumann {
    w: usize,
    rows: Dct,
    columns: Columns,
}

/// What the fused integration measured besides the heights.
pub struct Measured {
    pub counts: TexelCounts,
    /// RMS residual and the same against the RMS step (see [`crate::HeightReport`]).
    pub residual: (f64, f64),
    /// Moments of the heights, in the output's unit.
    pub moments: Moments,
}

impl Neumann {
    pub fn new(w: usize, h: usize) -> Neumann {
        Neumann { w, rows: Dct::new(w), columns: Columns::new(&eigenvalues(w, PI), h) }
    }

    /// `b <- L^-1 b` with the constant mode set to zero.
    pub fn solve_in_place(&self, b: &mut [f32]) {
        let (w, rows) = (self.w, &self.rows);
        b.par_chunks_mut(w * ROWS_PER_TASK)
            .for_each_init(|| rows.scratch(), |s, chunk| chunk.chunks_exact_mut(w).for_each(|row| rows.dct2(row, s)));
        self.columns.solve(b, 2.0 / w as f64);
        self.rows_back(b);
    }

    /// Each row's DCT-III in place; returns the moments of the result.
    fn rows_back(&self, b: &mut [f32]) -> Moments {
        let (w, rows) = (self.w, &self.rows);
        let bands: Vec<Moments> = b
            .par_chunks_mut(w * ROWS_PER_TASK)
            .map_init(
                || rows.scratch(),
                |s, band| {
                    band.chunks_exact_mut(w).for_each(|row| rows.dct3(row, s));
                    Moments::of(band)
                },
            )
            .collect();
        bands.iter().fold(Moments::EMPTY, |a, m| a.add(*m))
    }
}

/// Integrates `normals` with Neumann boundaries in three passes, heights multiplied by `texel`,
/// if every normal is usable; `None` (having classified the map) otherwise, for the caller to
/// take the general path.
pub fn integrate_valid(normals: &NormalMap, texel: f64) -> Option<(Vec<f32>, Measured)> {
    let (w, h) = normals.size();
    let solver = Neumann::new(w, h);
    let mut b = crate::buffer::zeroed(w * h);
    let first = rhs_and_rows(normals, &solver.rows, &mut b);
    if first.counts.invalid() > 0 {
        return None;
    }
    // DCT-III after DCT-II multiplies by w / 2; b . h in texel units is 2 / w times the sum.
    let bh = solver.columns.solve(&mut b, 2.0 / w as f64 * texel) * 2.0 / w as f64;
    let moments = solver.rows_back(&mut b);
    let edges = (h * w.saturating_sub(1) + w * h.saturating_sub(1)) as f64;
    let residual = if edges > 0.0 && first.steps > 0.0 {
        let rms = ((first.steps - bh).max(0.0) / edges).sqrt();
        (rms, rms / (first.steps / edges).sqrt())
    } else {
        (0.0, 0.0)
    };
    Some((b, Measured { counts: first.counts, residual, moments }))
}

/// What the first pass returns: the texel counts and `|g|^2`, the sum of the squared steps.
#[derive(Clone, Copy, Default)]
struct FirstPass {
    counts: TexelCounts,
    steps: f64,
}

/// One task's rows of slopes in the first pass: the current row's and the next one's, and the
/// vertical steps between the current row and the one above.
struct RowBuffers {
    px: Vec<f32>,
    py: Vec<f32>,
    px_next: Vec<f32>,
    py_next: Vec<f32>,
    v_above: Vec<f32>,
    v_below: Vec<f32>,
    steps: Vec<f32>,
}

impl RowBuffers {
    fn new(w: usize) -> RowBuffers {
        let z = vec![0f32; w];
        RowBuffers {
            px: z.clone(),
            py: z.clone(),
            px_next: z.clone(),
            py_next: z.clone(),
            v_above: z.clone(),
            v_below: z.clone(),
            steps: z,
        }
    }

    /// Reads `normals` (a row) into the `next` slopes; returns its counts.
    fn load_next(&mut self, normals: &[skinkit_maps::Vec3]) -> TexelCounts {
        usable_row(normals, &mut self.px_next, &mut self.py_next)
    }

    /// The next row becomes the current one.
    fn advance(&mut self) {
        std::mem::swap(&mut self.px, &mut self.px_next);
        std::mem::swap(&mut self.py, &mut self.py_next);
    }
}

/// Writes into `b` each row's right-hand side `D^T g` (no edge across the borders) and then its
/// DCT-II, block of rows by block of rows. Counts are exact only when every normal is usable
/// (otherwise the caller takes the general path, which classifies every texel).
fn rhs_and_rows(normals: &NormalMap, dct: &Dct, b: &mut [f32]) -> FirstPass {
    let (w, h) = normals.size();
    let row_of = |y: usize| &normals.as_slice()[y * w..][..w];
    let blocks: Vec<FirstPass> = b
        .par_chunks_mut(w * ROWS_PER_TASK)
        .enumerate()
        .map_init(
            || (dct.scratch(), RowBuffers::new(w)),
            |(s, r), (block, rows)| {
                let (y0, y1) = (block * ROWS_PER_TASK, block * ROWS_PER_TASK + rows.len() / w);
                let mut counts = TexelCounts::default();
                r.v_above.iter_mut().for_each(|v| *v = 0.0);
                if y0 > 0 {
                    r.load_next(row_of(y0 - 1));
                    r.advance();
                }
                counts = counts + r.load_next(row_of(y0));
                if y0 > 0 {
                    vertical(&r.py, Some(&r.py_next), &[], &mut r.v_above, None);
                }
                r.advance();
                let mut steps = 0.0;
                for (y, out) in (y0..y1).zip(rows.chunks_exact_mut(w)) {
                    steps += horizontal(&r.px, &mut r.steps, out);
                    let next = (y + 1 < h).then(|| r.load_next(row_of(y + 1)));
                    if y + 1 < y1 {
                        // A row loaded past the block belongs to the next block's counts.
                        counts = counts + next.unwrap_or_default();
                    }
                    let next = next.map(|_| r.py_next.as_slice());
                    steps += vertical(&r.py, next, &r.v_above, &mut r.v_below, Some(out));
                    std::mem::swap(&mut r.v_above, &mut r.v_below);
                    r.advance();
                    dct.dct2(out, s);
                }
                FirstPass { counts, steps }
            },
        )
        .collect();
    blocks.iter().fold(FirstPass::default(), |a, p| FirstPass { counts: a.counts + p.counts, steps: a.steps + p.steps })
}

/// Writes into `out` each texel's horizontal steps arriving minus those leaving (the step of an
/// edge is the mean of its ends' slopes `px`, kept in `steps`); returns the sum of their squares.
fn horizontal(px: &[f32], steps: &mut [f32], out: &mut [f32]) -> f64 {
    let w = px.len();
    let steps = &mut steps[..w - 1];
    for ((s, &l), &r) in steps.iter_mut().zip(px).zip(&px[1..]) {
        *s = 0.5 * (l + r);
    }
    out[0] = 0.0;
    out[1..].copy_from_slice(steps);
    for (o, &s) in out.iter_mut().zip(steps.iter()) {
        *o -= s;
    }
    sum_squares(steps)
}

/// The vertical steps below the current row (the mean of `py` and the next row's, none on the
/// last row) into `v_below`; added to `out` (when given) with those from above (`v_above`);
/// returns the sum of their squares.
fn vertical(py: &[f32], next: Option<&[f32]>, v_above: &[f32], v_below: &mut [f32], out: Option<&mut [f32]>) -> f64 {
    match next {
        Some(next) => v_below.iter_mut().zip(py).zip(next).for_each(|((v, &a), &b)| *v = 0.5 * (a + b)),
        None => v_below.iter_mut().for_each(|v| *v = 0.0),
    }
    if let Some(out) = out {
        for ((o, &a), &b) in out.iter_mut().zip(v_above).zip(v_below.iter()) {
            *o += a - b;
        }
    }
    sum_squares(v_below)
}

/// The sum of the squares of `v`: eight f32 running sums, added in f64 in order.
fn sum_squares(v: &[f32]) -> f64 {
    let mut lanes = [0f32; LANES];
    let mut chunks = v.chunks_exact(LANES);
    for c in chunks.by_ref() {
        for (lane, &x) in lanes.iter_mut().zip(c) {
            *lane += x * x;
        }
    }
    let rest: f32 = chunks.remainder().iter().map(|x| x * x).sum();
    lanes.iter().map(|&l| f64::from(l)).sum::<f64>() + f64::from(rest)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::slopes::Slopes;
    use skinkit_maps::{Grid, Vec3};

    /// A map that no surface has (a curl field plus a slope): the spectral residual and moments
    /// of the fused path against the residual measured edge by edge and the moments of the
    /// heights, and the heights against the general path's solve.
    #[test]
    fn the_fused_path_measures_what_the_general_path_does() {
        let (w, h) = (70, 45);
        let normals = NormalMap::from_grid(Grid::from_fn(w, h, |x, y| {
            let (u, v) = (x as f32 * 0.2, y as f32 * 0.3);
            Vec3::new(0.3 * v.sin() + 0.1, -0.3 * u.cos(), 1.0)
        }));
        let (heights, m) = integrate_valid(&normals, 0.5).expect("every normal is usable");
        let slopes = Slopes::from_normals(&normals);
        let direct = slopes.residual(&heights, 0.5, false);
        assert!(m.residual.1 > 0.1, "{:?}", m.residual);
        assert!((m.residual.0 - direct.0).abs() < 1e-4 * direct.0, "{:?} against {direct:?}", m.residual);
        assert!((m.residual.1 - direct.1).abs() < 1e-4 * direct.1);
        let general = crate::poisson::solve_neumann(&slopes);
        let mean = general.iter().map(|&v| f64::from(v)).sum::<f64>() / general.len() as f64;
        for (a, b) in heights.iter().zip(&general) {
            assert!((f64::from(*a) - 0.5 * (f64::from(*b) - mean)).abs() < 1e-4, "{a} against {b}");
        }
        let exact = Moments::of(&heights);
        assert_eq!((m.moments.lo, m.moments.hi, m.moments.n), (exact.lo, exact.hi, exact.n));
        assert!((m.moments.squares - exact.squares).abs() < 1e-9 * exact.squares);
        assert_eq!(m.counts.valid, w * h);
    }

    /// A map with one unusable normal is left to the general path.
    #[test]
    fn an_unusable_normal_declines_the_fused_path() {
        let mut grid = Grid::from_fn(20, 10, |_, _| Vec3::Z);
        *grid.get_mut(3, 4) = Vec3::ZERO;
        assert!(integrate_valid(&NormalMap::from_grid(grid), 1.0).is_none());
    }
}
