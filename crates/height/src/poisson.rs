//! The two direct Poisson solves: `L h = b` with `L` the grid's 5-point graph Laplacian
//! (positive semi-definite, `2 - 2 cos` eigenvalues per axis), periodic by FFT and Neumann by DCT.
//! Both set the constant mode to zero, so `h` has mean zero.

use std::f64::consts::PI;

use rayon::prelude::*;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex32;

use crate::dct::Dct;
use crate::slopes::Slopes;
use crate::transform::{fft_rows, transpose};

/// Integrates `slopes` with edges wrapping around both borders.
pub fn solve_periodic(slopes: &Slopes) -> Vec<f32> {
    let (w, h) = (slopes.width(), slopes.height());
    let b = slopes.rhs(true, false);
    solve_periodic_rhs(b, w, h)
}

/// Integrates `slopes` with no edge across the borders (every texel's slope used as data).
pub fn solve_neumann(slopes: &Slopes) -> Vec<f32> {
    let (w, h) = (slopes.width(), slopes.height());
    let solver = Neumann::new(w, h);
    let mut b = slopes.rhs(false, false);
    let mut scratch = vec![0f32; w * h];
    solver.solve_in_place(&mut b, &mut scratch);
    b
}

/// Columns gathered by one task of the column pass (16 floats: one cache line of a row).
const STRIP: usize = 16;
/// Rows gathered by one task of the last row pass (one cache line of a transposed column).
const BAND: usize = 16;
/// Side of the tiles of [`transpose_strip`] (equal to [`STRIP`] and [`BAND`]).
const TILE: usize = 16;
/// Rows per task of the first row pass.
const ROWS_PER_TASK: usize = 16;

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
        self.columns_pass(b, scratch);
        self.rows_back(scratch, b);
    }

    /// Transposes `b` into `t` a strip of columns at a time, solving each column's modes.
    fn columns_pass(&self, b: &[f32], t: &mut [f32]) {
        let (w, h, columns) = (self.w, self.h, &self.columns);
        // DCT-III after DCT-II scales by n/2 per axis.
        let norm = (4.0 / (w as f64 * h as f64)) as f32;
        let mu_y: Vec<f32> = self.mu_y.iter().map(|&m| m as f32).collect();
        t.par_chunks_mut(h * STRIP).enumerate().for_each_init(
            || columns.scratch(),
            |s, (strip, out)| {
                let x0 = strip * STRIP;
                transpose_strip(&b[x0..], w, out, h);
                for (c, column) in out.chunks_exact_mut(h).enumerate() {
                    let kx = x0 + c;
                    columns.dct2(column, s);
                    let mu_x = self.mu_x[kx] as f32;
                    for (v, &mu_y) in column.iter_mut().zip(&mu_y) {
                        *v *= norm / (mu_x + mu_y);
                    }
                    if kx == 0 {
                        // The constant mode (mu = 0: its quotient above is not finite) is zero.
                        column[0] = 0.0;
                    }
                    columns.dct3(column, s);
                }
            },
        );
    }

    /// Transposes `t` back into `b` a band of rows at a time, each row's DCT-III.
    fn rows_back(&self, t: &[f32], b: &mut [f32]) {
        let (w, h, rows) = (self.w, self.h, &self.rows);
        b.par_chunks_mut(w * BAND).enumerate().for_each_init(
            || rows.scratch(),
            |s, (band, out)| {
                transpose_strip(&t[band * BAND..], h, out, w);
                out.chunks_exact_mut(w).for_each(|row| rows.dct3(row, s));
            },
        );
    }
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

fn solve_periodic_rhs(b: Vec<f32>, w: usize, h: usize) -> Vec<f32> {
    let mut planner = FftPlanner::new();
    let (fw, fh) = (planner.plan_fft_forward(w), planner.plan_fft_forward(h));
    let (iw, ih) = (planner.plan_fft_inverse(w), planner.plan_fft_inverse(h));
    let mut data: Vec<Complex32> = b.into_iter().map(|v| Complex32::new(v, 0.0)).collect();
    fft_rows(&mut data, &fw);
    let mut t = vec![Complex32::default(); w * h];
    transpose(&data, w, h, &mut t);
    fft_rows(&mut t, &fh);
    let (mu_x, mu_y) = (eigenvalues(w, 2.0 * PI), eigenvalues(h, 2.0 * PI));
    divide(&mut t, h, &mu_x, &mu_y, 1.0 / (w as f64 * h as f64), |v, s| *v *= s);
    fft_rows(&mut t, &ih);
    transpose(&t, h, w, &mut data);
    drop(t);
    fft_rows(&mut data, &iw);
    data.into_iter().map(|c| c.re).collect()
}

/// `2 - 2 cos(step k / n)` for `k` in `0..n`: the 1-D Laplacian's eigenvalues in the DCT-II
/// (`step = pi`) or DFT (`step = 2 pi`) basis.
fn eigenvalues(n: usize, step: f64) -> Vec<f64> {
    (0..n).map(|k| 2.0 - 2.0 * (step * k as f64 / n as f64).cos()).collect()
}

/// Scales each coefficient of the transposed spectrum (row `kx`, column `ky`) by
/// `norm / (mu_x + mu_y)`, and the constant mode to zero.
fn divide<T: Send>(t: &mut [T], h: usize, mu_x: &[f64], mu_y: &[f64], norm: f64, scale: impl Fn(&mut T, f32) + Sync) {
    t.par_chunks_mut(h).enumerate().for_each(|(kx, row)| {
        for (ky, v) in row.iter_mut().enumerate() {
            let mu = mu_x[kx] + mu_y[ky];
            scale(v, if mu > 0.0 { (norm / mu) as f32 } else { 0.0 });
        }
    });
}
