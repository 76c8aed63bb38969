//! The Neumann solve by DCT ([`Neumann`]), and the whole integration of a map whose every normal
//! is usable fused into three passes over memory ([`integrate_valid`]), the default for
//! rectangular maps.
//!
//! The fused integration classifies each row's normals, forms its right-hand side and takes its
//! DCT-II while the row is in cache; solves every column's modes a strip of columns at a time;
//! and takes each row's DCT-III a band of rows at a time while measuring the heights. The
//! integrability residual comes from the spectrum, not from another pass: for the least-squares
//! solution `h` of `D h = g`, `|D h - g|^2 = |g|^2 - b . h` with `b = D^T g`, and by the DCT's
//! orthogonality `b . h = sum_k B_k^2 / (mu_k |phi_k|^2)` over the spectrum `B` of `b`.

use std::f64::consts::PI;

use rayon::prelude::*;
use skinkit_maps::NormalMap;

use crate::Moments;
use crate::dct::Dct;
use crate::poisson::eigenvalues;
use crate::slopes::{TexelCounts, classify_row};

/// Columns gathered by one task of the column pass (16 floats: one cache line of a row).
const STRIP: usize = 16;
/// Rows gathered by one task of the last row pass (one cache line of a transposed column).
const BAND: usize = 16;
/// Side of the tiles of [`transpose_strip`] (equal to [`STRIP`] and [`BAND`]).
const TILE: usize = 16;
/// Rows per task of the first row pass.
const ROWS_PER_TASK: usize = 16;
/// Running sums per accumulation (fixed, so sums have the same bits on any thread count).
const LANES: usize = 8;

/// `L^-1` for the Neumann Laplacian of a `w x h` grid, planned once (the masked solve applies it
/// every iteration). Three passes over memory: DCT-II along rows in place; columns gathered a
/// strip at a time into a transposed scratch, each column's DCT-II, division by the eigenvalues
/// and DCT-III done while it sits in cache; rows gathered back a band at a time, each row's
/// DCT-III. The transposes ride inside the passes that need them.
pub struct Neumann {
    w: usize,
    h: usize,
    rows: Dct,
    columns: Dct,
    mu_x: Vec<f64>,
    mu_y: Vec<f64>,
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
        let (mu_x, mu_y) = (eigenvalues(w, PI), eigenvalues(h, PI));
        Neumann { w, h, rows: Dct::new(w), columns: Dct::new(h), mu_x, mu_y }
    }

    /// `b <- L^-1 b` with the constant mode set to zero; `scratch` (of the grid's size) is
    /// overwritten.
    pub fn solve_in_place(&self, b: &mut [f32], scratch: &mut [f32]) {
        let (w, h) = (self.w, self.h);
        assert_eq!(b.len(), w * h, "Neumann solve: right-hand side size");
        assert_eq!(scratch.len(), w * h, "Neumann solve: scratch size");
        let rows = &self.rows;
        b.par_chunks_mut(w * ROWS_PER_TASK)
            .for_each_init(|| rows.scratch(), |s, chunk| chunk.chunks_exact_mut(w).for_each(|row| rows.dct2(row, s)));
        self.columns_pass(b, scratch, 1.0);
        self.rows_back(scratch, b);
    }

    /// Transposes `b` into `t` a strip of columns at a time, solving each column's modes (and
    /// multiplying by `scale`); returns `sum_k B_k^2 / (mu_k |phi_k|^2)`, which is `b . h`.
    fn columns_pass(&self, b: &[f32], t: &mut [f32], scale: f64) -> f64 {
        let (w, h, columns) = (self.w, self.h, &self.columns);
        // DCT-III after DCT-II scales by n/2 per axis.
        let norm = (4.0 / (w as f64 * h as f64) * scale) as f32;
        let mu_y: Vec<f32> = self.mu_y.iter().map(|&m| m as f32).collect();
        // For kx = 0 the constant mode's eigenvalue (0) is replaced by 1 and the mode zeroed first.
        let mut mu_y0 = mu_y.clone();
        mu_y0[0] = 1.0;
        let strips: Vec<f64> = t
            .par_chunks_mut(h * STRIP)
            .enumerate()
            .map_init(
                || columns.scratch(),
                |s, (strip, out)| {
                    let x0 = strip * STRIP;
                    transpose_strip(&b[x0..], w, out, h);
                    let mut energy = 0.0;
                    for (c, column) in out.chunks_exact_mut(h).enumerate() {
                        let kx = x0 + c;
                        columns.dct2(column, s);
                        if kx == 0 {
                            column[0] = 0.0;
                        }
                        let first = column[0];
                        let mu_y = if kx == 0 { &mu_y0 } else { &mu_y };
                        let sum = divide_column(column, mu_y, self.mu_x[kx] as f32, norm);
                        // B^2 / mu = B (B norm / mu) / norm, over |phi|^2 = w h / 4 (halved
                        // weight for kx = 0 and ky = 0, whose basis vectors are twice as long).
                        let sum = sum - 0.5 * f64::from(first) * f64::from(column[0]);
                        energy += sum * if kx == 0 { 0.5 } else { 1.0 };
                        columns.dct3(column, s);
                    }
                    energy
                },
            )
            .collect();
        let scale = 4.0 / (w as f64 * h as f64) / f64::from(norm);
        strips.iter().sum::<f64>() * scale
    }

    /// Transposes `t` back into `b` a band of rows at a time, each row's DCT-III; returns the
    /// moments of the result.
    fn rows_back(&self, t: &[f32], b: &mut [f32]) -> Moments {
        let (w, h, rows) = (self.w, self.h, &self.rows);
        let bands: Vec<Moments> = b
            .par_chunks_mut(w * BAND)
            .enumerate()
            .map_init(
                || rows.scratch(),
                |s, (band, out)| {
                    transpose_strip(&t[band * BAND..], h, out, w);
                    out.chunks_exact_mut(w).for_each(|row| rows.dct3(row, s));
                    Moments::of(out)
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
    let mut b = vec![0f32; w * h];
    let first = rhs_and_rows(normals, &solver.rows, &mut b);
    if first.counts.invalid() > 0 {
        return None;
    }
    let mut t = vec![0f32; w * h];
    let bh = solver.columns_pass(&b, &mut t, texel);
    let moments = solver.rows_back(&t, &mut b);
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

/// One task's rows of slopes and steps in the first pass.
struct RowBuffers {
    px: Vec<f32>,
    py: Vec<f32>,
    px_next: Vec<f32>,
    py_next: Vec<f32>,
    v_above: Vec<f32>,
    v_below: Vec<f32>,
    /// Horizontal steps, the last one (no edge) 0.
    steps: Vec<f32>,
    ok: Vec<bool>,
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
            ok: vec![false; w],
        }
    }

    /// Classifies `normals` (a row) into the `next` slopes.
    fn load_next(&mut self, normals: &[skinkit_maps::Vec3]) -> TexelCounts {
        classify_row(normals, &mut self.px_next, &mut self.py_next, &mut self.ok)
    }

    /// The next row becomes the current one.
    fn advance(&mut self) {
        std::mem::swap(&mut self.px, &mut self.px_next);
        std::mem::swap(&mut self.py, &mut self.py_next);
    }
}

/// Writes into `b` each row's right-hand side `D^T g` (no edge across the borders, invalid texels
/// flat) and then its DCT-II, block of rows by block of rows.
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
                let mut steps = 0.0;
                let mut counts = TexelCounts::default();
                if y0 > 0 {
                    r.load_next(row_of(y0 - 1));
                    r.advance();
                }
                counts = counts + r.load_next(row_of(y0));
                for x in 0..w {
                    r.v_above[x] = if y0 > 0 { 0.5 * (r.py[x] + r.py_next[x]) } else { 0.0 };
                }
                r.advance();
                for (y, out) in (y0..y1).zip(rows.chunks_exact_mut(w)) {
                    // Per texel: the steps of the edges arriving minus those leaving.
                    for x in 0..w - 1 {
                        r.steps[x] = 0.5 * (r.px[x] + r.px[x + 1]);
                    }
                    steps += sum_squares(&r.steps[..w - 1]);
                    out[0] = -r.steps[0];
                    for x in 1..w {
                        out[x] = r.steps[x - 1] - r.steps[x];
                    }
                    if y + 1 < h {
                        let c = r.load_next(row_of(y + 1));
                        if y + 1 < y1 {
                            counts = counts + c;
                        }
                        for x in 0..w {
                            r.v_below[x] = 0.5 * (r.py[x] + r.py_next[x]);
                        }
                        steps += sum_squares(&r.v_below);
                    } else {
                        r.v_below.iter_mut().for_each(|v| *v = 0.0);
                    }
                    for x in 0..w {
                        out[x] += r.v_above[x] - r.v_below[x];
                    }
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

/// Multiplies each of `column`'s modes by `norm / (mu_x + mu_y)` and returns the sum of the
/// products of each mode before and after (in eight f64 running sums, added in order).
fn divide_column(column: &mut [f32], mu_y: &[f32], mu_x: f32, norm: f32) -> f64 {
    let mut lanes = [0f64; LANES];
    let step = |v: &mut f32, mu_y: f32, lane: &mut f64| {
        let after = *v * (norm / (mu_x + mu_y));
        *lane += f64::from(*v * after);
        *v = after;
    };
    let mut chunks = column.chunks_exact_mut(LANES);
    let mut mus = mu_y.chunks_exact(LANES);
    for (vs, ms) in chunks.by_ref().zip(mus.by_ref()) {
        for ((v, &m), lane) in vs.iter_mut().zip(ms).zip(lanes.iter_mut()) {
            step(v, m, lane);
        }
    }
    for ((v, &m), lane) in chunks.into_remainder().iter_mut().zip(mus.remainder()).zip(lanes.iter_mut()) {
        step(v, m, lane);
    }
    lanes.iter().sum()
}

/// The sum of the squares of `v` in f64 (eight running sums, added in order).
fn sum_squares(v: &[f32]) -> f64 {
    let mut lanes = [0f64; LANES];
    let mut chunks = v.chunks_exact(LANES);
    for c in chunks.by_ref() {
        for (lane, &x) in lanes.iter_mut().zip(c) {
            *lane += f64::from(x) * f64::from(x);
        }
    }
    for (lane, &x) in lanes.iter_mut().zip(chunks.remainder()) {
        *lane += f64::from(x) * f64::from(x);
    }
    lanes.iter().sum()
}

/// Writes the transpose of a strip of `src` into `dst`: `dst` holds `k` rows of `n` (`k` at most
/// [`TILE`]), and row `j` of it receives column `j` of the first `n` rows of `src` (rows `stride`
/// apart). Square tiles go through a small buffer so that each destination cache line is written
/// once: writing the `k` destination rows a value at a time would touch `k` lines a power-of-two
/// stride apart, which share a cache set and evict each other.
fn transpose_strip(src: &[f32], stride: usize, dst: &mut [f32], n: usize) {
    let k = dst.len() / n;
    let mut tile = [0f32; TILE * TILE];
    for i0 in (0..n).step_by(TILE) {
        let m = TILE.min(n - i0);
        for i in 0..m {
            let row = &src[(i0 + i) * stride..][..k];
            for (j, &v) in row.iter().enumerate() {
                tile[j * TILE + i] = v;
            }
        }
        for j in 0..k {
            dst[j * n + i0..][..m].copy_from_slice(&tile[j * TILE..][..m]);
        }
    }
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
