//! The masked solve: the weighted Poisson system `D^T W D h = D^T W g`, where an edge with an
//! invalid end has weight [`HOLE_WEIGHT`] and a flat target, by conjugate gradients preconditioned
//! with the unweighted Neumann solve (a DCT pair per iteration). Dot products are summed per fixed
//! block and then in order, so the result is the same bits at any thread count.

use rayon::prelude::*;

use crate::HOLE_WEIGHT;
use crate::neumann::Neumann;
use crate::slopes::{Slopes, neighbours};

/// Elements per block of a deterministic dot product.
const DOT_BLOCK: usize = 1 << 14;

/// Solves for the heights (texel units) and returns them with the iterations taken. Stops when
/// the residual falls under `tolerance` times the right-hand side's norm, or after
/// `max_iterations`.
pub fn solve(slopes: &Slopes, tolerance: f64, max_iterations: usize) -> (Vec<f32>, usize) {
    let (w, h) = (slopes.width(), slopes.height());
    let mut r = slopes.rhs(false, true);
    let norm_b = dot(&r, &r).sqrt();
    let mut x = vec![0f32; w * h];
    if norm_b == 0.0 {
        return (x, 0);
    }
    let mut q = vec![0f32; w * h];
    let preconditioner = Neumann::new(w, h);
    let mut z = r.clone();
    preconditioner.solve_in_place(&mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    for iteration in 1..=max_iterations {
        apply(slopes, &p, &mut q);
        let pq = dot(&p, &q);
        if !(pq > 0.0) {
            return (x, iteration);
        }
        let alpha = (rz / pq) as f32;
        axpy(&mut x, alpha, &p);
        axpy(&mut r, -alpha, &q);
        if dot(&r, &r).sqrt() <= tolerance * norm_b {
            return (x, iteration);
        }
        z.copy_from_slice(&r);
        preconditioner.solve_in_place(&mut z);
        let rz_next = dot(&r, &z);
        let beta = (rz_next / rz) as f32;
        rz = rz_next;
        p.par_iter_mut().zip(z.par_iter()).for_each(|(p, z)| *p = z + beta * *p);
    }
    (x, max_iterations)
}

/// `out = A p`: per texel, the weighted differences to its neighbours.
fn apply(slopes: &Slopes, p: &[f32], out: &mut [f32]) {
    let (w, h) = (slopes.width(), slopes.height());
    let valid = &slopes.valid;
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, o) in row.iter_mut().enumerate() {
            let i = y * w + x;
            let mut sum = 0.0;
            for (a, b, _) in neighbours(x, y, w, h, false) {
                let weight = if valid[a] && valid[b] { 1.0 } else { HOLE_WEIGHT };
                let other = if a == i { b } else { a };
                sum += weight * (p[i] - p[other]);
            }
            *o = sum;
        }
    });
}

/// `y += a x`.
fn axpy(y: &mut [f32], a: f32, x: &[f32]) {
    y.par_iter_mut().zip(x.par_iter()).for_each(|(y, x)| *y += a * x);
}

/// The dot product in f64, summed per block of [`DOT_BLOCK`] and then in block order.
fn dot(a: &[f32], b: &[f32]) -> f64 {
    let blocks: Vec<f64> = a
        .par_chunks(DOT_BLOCK)
        .zip(b.par_chunks(DOT_BLOCK))
        .map(|(a, b)| a.iter().zip(b).map(|(x, y)| *x as f64 * *y as f64).sum())
        .collect();
    blocks.iter().sum()
}
