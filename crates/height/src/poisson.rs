//! The two direct Poisson solves: `L h = b` with `L` the grid's 5-point graph Laplacian
//! (positive semi-definite, `2 - 2 cos` eigenvalues per axis), periodic by FFT and Neumann by DCT.
//! Both set the constant mode to zero, so `h` has mean zero.

use std::f64::consts::PI;

use rayon::prelude::*;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex32;

use crate::neumann::Neumann;
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
    solver.solve_in_place(&mut b);
    b
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
pub(crate) fn eigenvalues(n: usize, step: f64) -> Vec<f64> {
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
